//! The time table and playback of aligned sequences.

use crate::common;

use lod_policy::TimeTable;
use timewarp::{
    AlignConfig, AlignMethod, DtwConfig, FrameSeq, MIN_INCREMENT, TimewarpError, align, fill_times,
    phase_at, playback, playback_into,
};

/// The offline playback times and the runtime's clip time table are the same rule: the same bits
/// for the same increments (bad ones included), at every playback time.
#[test]
fn offline_playback_times_match_the_runtime_time_table_bit_for_bit() {
    assert_eq!(MIN_INCREMENT, lod_policy::MIN_INCREMENT);
    let sets: [&[f64]; 4] = [
        &[0.1, 0.2, 0.3, 0.0],
        &[0.1, -0.5, f64::NAN, f64::INFINITY, 0.2, 9.0],
        &[0.033; 40],
        &[0.5],
    ];
    let mut times = Vec::new();
    for incs in sets {
        let table = TimeTable::from_increments(incs);
        fill_times(&mut times, incs.iter().copied());
        assert_eq!(times, table.times());
        for k in -5..=200 {
            let t = k as f64 * 0.0137;
            assert_eq!(phase_at(&times, t).to_bits(), table.phase_at(t).to_bits());
        }
        assert_eq!(phase_at(&times, f64::NAN), table.phase_at(f64::NAN));
    }
}

#[test]
fn time_table_accumulates_and_inverts() {
    let incs = [0.1, 0.2, 0.3, 0.0];
    let table = TimeTable::from_increments(&incs);
    assert_eq!(table.len(), 4);
    let expect = [0.0, 0.1, 0.30000000000000004, 0.6000000000000001];
    for (a, b) in table.times().iter().zip(expect) {
        assert!((a - b).abs() < 1e-15);
    }
    assert!((table.duration() - 0.6).abs() < 1e-15);
    assert_eq!(table.phase_at(0.0), 0.0);
    assert!((table.phase_at(0.05) - 0.5).abs() < 1e-12);
    assert!((table.phase_at(0.2) - 1.5).abs() < 1e-12);
    assert!((table.phase_at(0.6) - 3.0).abs() < 1e-12);
    assert_eq!(table.phase_at(-1.0), 0.0);
    assert_eq!(table.phase_at(10.0), 3.0);
    assert_eq!(table.phase_at(f64::NAN), 0.0);
    for k in 0..=30 {
        let phase = k as f64 * 0.1;
        assert!((table.phase_at(table.time_at(phase)) - phase).abs() < 1e-9);
    }
    assert_eq!(TimeTable::new().phase_at(1.0), 0.0);
    assert_eq!(TimeTable::new().duration(), 0.0);
}

#[test]
fn bad_synthesized_increments_are_clamped() {
    let table = TimeTable::from_increments(&[0.1, -0.5, f64::NAN, f64::INFINITY, 0.2, 9.0]);
    let t = table.times();
    assert!(t.windows(2).all(|w| w[1] > w[0]));
    let d = [0.1, MIN_INCREMENT, MIN_INCREMENT, MIN_INCREMENT, 0.2];
    assert!((table.duration() - d.iter().sum::<f64>()).abs() < 1e-12);
    // Phases stay in range and increase with time.
    let mut last = -1.0;
    for k in 0..=100 {
        let p = table.phase_at(k as f64 * 0.004);
        assert!((0.0..=5.0).contains(&p) && p >= last);
        last = p;
    }
}

#[test]
fn fill_from_reuses_the_buffer() {
    let mut table = TimeTable::with_capacity(64);
    let incs: Vec<f64> = (0..64).map(|k| 0.01 + 0.001 * k as f64).collect();
    table.fill_from(&incs);
    let ptr = table.times().as_ptr();
    table.fill_from(&incs[..40]);
    assert_eq!(table.len(), 40);
    table.fill_from(&incs);
    assert_eq!(table.times().as_ptr(), ptr);
    let sum: f64 = incs[..63].iter().sum();
    assert!((table.duration() - sum).abs() < 1e-12);
}

#[test]
fn playback_at_the_source_rate_reproduces_the_source() {
    let n = 31;
    let src = common::warped(n, 4, common::bump(0.5));
    let ft = 1.0 / 30.0;
    // Uniform alignment with T - 1 a multiple of n - 1: aligned frames contain every source frame.
    for frames in [n, 2 * n - 1] {
        let al = align(
            std::slice::from_ref(&src),
            std::slice::from_ref(&src),
            &[ft],
            &AlignConfig::new(frames, AlignMethod::Uniform),
        )
        .unwrap();
        let back = playback(&al.aligned[0], al.increment_col, 30.0).unwrap();
        assert_eq!(back.len(), n);
        assert_eq!(back.dim, 4);
        for (x, y) in back.frames.iter().zip(&src.frames) {
            assert!((x - y).abs() < 1e-9, "{x} vs {y}");
        }
    }
}

#[test]
fn playback_of_dtw_aligned_cycles_is_close_to_the_source() {
    let seqs: Vec<FrameSeq> = [(90, 0.6), (108, -0.5), (99, 0.0)]
        .iter()
        .map(|&(n, a)| common::warped(n, 5, common::bump(a)))
        .collect();
    let cfg = AlignConfig::new(200, AlignMethod::Dtw(DtwConfig::default()));
    let al = align(&seqs, &seqs, &[1.0 / 30.0; 3], &cfg).unwrap();
    for (s, src) in seqs.iter().enumerate() {
        let back = playback(&al.aligned[s], al.increment_col, 30.0).unwrap();
        assert_eq!(back.len(), src.len());
        let worst = back
            .frames
            .iter()
            .zip(&src.frames)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        // Two linear interpolations of a curve sampled ~25 times per period (each one alone errs
        // by up to (2 pi / 25)^2 / 8 ~ 0.008 of the amplitude).
        assert!(worst < 0.02, "sequence {s}: {worst}");
        // At 120 fps: four times as many intervals over the same duration.
        let fast = playback(&al.aligned[s], al.increment_col, 120.0).unwrap();
        assert_eq!(fast.len(), 4 * (src.len() - 1) + 1);
    }
}

#[test]
fn playback_into_reuses_buffers_and_rejects_bad_input() {
    let mut aligned = FrameSeq::zeros(3, 5);
    for k in 0..5 {
        let f = aligned.frame_mut(k);
        f[0] = k as f64;
        f[1] = if k < 4 { 0.25 } else { 0.0 };
        f[2] = -(k as f64);
    }
    let mut times = Vec::with_capacity(5);
    let mut out = FrameSeq::zeros(2, 9);
    playback_into(&aligned, 1, 8.0, &mut times, &mut out).unwrap();
    assert_eq!(out.len(), 9);
    for m in 0..9 {
        let phase = m as f64 * 0.5;
        assert!((out.frame(m)[0] - phase).abs() < 1e-12);
        assert!((out.frame(m)[1] + phase).abs() < 1e-12);
    }
    assert!(matches!(
        playback(&aligned, 3, 30.0),
        Err(TimewarpError::InvalidConfig {
            what: "increment_col",
            ..
        })
    ));
    for fps in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(
            playback(&aligned, 1, fps),
            Err(TimewarpError::InvalidConfig { what: "fps", .. })
        ));
    }
    assert!(playback(&FrameSeq::zeros(3, 0), 1, 30.0).is_err());
    assert!(playback(&FrameSeq::zeros(1, 4), 0, 30.0).is_err());
    aligned.frame_mut(2)[0] = f64::NAN;
    assert!(matches!(
        playback(&aligned, 1, 30.0),
        Err(TimewarpError::NonFinite {
            frame: 2,
            column: 0,
            ..
        })
    ));
}

/// Two-column aligned sequence (value = frame index) with the increments in column 1.
fn with_increments(incs: &[f64]) -> FrameSeq {
    let frames = incs
        .iter()
        .enumerate()
        .flat_map(|(i, &d)| [i as f64, d])
        .collect();
    FrameSeq::new(2, frames).unwrap()
}

/// Frame counts beyond the limit (or beyond `usize`) are errors, not 0 frames, an overflow
/// panic or an aborted allocation.
#[test]
fn absurd_frame_counts_are_refused() {
    let cases: [(&[f64], f64); 3] = [
        (&[0.1, 0.1, 0.0], 1e300),
        (&[1e300, 1e300, 0.0], 1e10),
        // 1e7 s at 1e6 fps: 1e13 frames (80 TB).
        (&[1e7, 0.0], 1e6),
    ];
    for (incs, fps) in cases {
        let err = playback(&with_increments(incs), 1, fps).unwrap_err();
        assert!(
            matches!(
                err,
                TimewarpError::TooLarge {
                    limit: timewarp::MAX_PLAYBACK_FRAMES,
                    ..
                }
            ),
            "{incs:?} at {fps}: {err}"
        );
    }
    // One frame over the limit; the limit itself is a count, not a duration.
    let over = timewarp::MAX_PLAYBACK_FRAMES as f64 / 1000.0;
    assert!(matches!(
        playback(&with_increments(&[over, 0.0]), 1, 1000.0),
        Err(TimewarpError::TooLarge { .. })
    ));
    // Ordinary counts are unchanged: 2 s at 30 fps.
    assert_eq!(
        playback(&with_increments(&[1.0, 1.0, 0.0]), 1, 30.0)
            .unwrap()
            .len(),
        61
    );
}

/// Increments whose cumulative times overflow or stop increasing are refused by playback
/// (`fill_times` and `phase_at` keep the runtime's rule).
#[test]
fn overflowing_or_absorbed_times_are_refused() {
    // f64::MAX twice: the duration is infinite.
    let err = playback(&with_increments(&[f64::MAX, f64::MAX, 0.0]), 1, 1.0).unwrap_err();
    assert!(
        matches!(err, TimewarpError::PlaybackTimes { frame: 2, time } if time.is_infinite()),
        "{err}"
    );
    // 1e300 absorbs the next increments: times [0, 1e300, 1e300, 1e300].
    let err = playback(&with_increments(&[1e300, 1e-3, 1e-3, 0.0]), 1, 1e-300).unwrap_err();
    assert!(
        matches!(err, TimewarpError::PlaybackTimes { frame: 2, .. }),
        "{err}"
    );
    let mut out = FrameSeq::zeros(1, 3);
    let before = out.clone();
    assert!(
        playback_into(
            &with_increments(&[f64::MAX, f64::MAX, 0.0]),
            1,
            1.0,
            &mut Vec::new(),
            &mut out
        )
        .is_err()
    );
    assert_eq!(out, before);
}
