//! Alignment to a reference, the time-increment channel, and the medoid.

use crate::common;

use timewarp::{
    AlignConfig, AlignMethod, DtwConfig, DtwWorkspace, FrameSeq, TimewarpError, align,
    dtw_cost_with, median_length, medoid, medoid_with_candidates, uniform_medoid,
};

/// Cycles of one shape with different lengths and timings (index 0 is unwarped).
fn cycles(dim: usize) -> Vec<FrameSeq> {
    let specs: [(usize, f64); 7] = [
        (34, 0.0),
        (30, 0.7),
        (38, -0.7),
        (33, 0.5),
        (41, -0.4),
        (27, 0.3),
        (35, -0.6),
    ];
    specs
        .iter()
        .map(|&(n, a)| common::warped(n, dim, common::bump(a)))
        .collect()
}

/// Mean squared distance between aligned frames of two sequences, increment column excluded.
fn mean_distance(x: &FrameSeq, y: &FrameSeq, skip: usize) -> f64 {
    let mut sum = 0.0;
    for k in 0..x.len() {
        for c in (0..x.dim).filter(|&c| c != skip) {
            let d = x.frame(k)[c] - y.frame(k)[c];
            sum += d * d;
        }
    }
    sum / x.len() as f64
}

#[test]
fn dtw_alignment_beats_uniform_resampling() {
    let seqs = cycles(6);
    let ft = vec![1.0 / 30.0; seqs.len()];
    let method = AlignMethod::Dtw(DtwConfig {
        band: 0.25,
        max_slope: 2,
    });
    let mut cfg = AlignConfig::new(34, method);
    cfg.reference = Some(0);
    let warped = align(&seqs, &seqs, &ft, &cfg).unwrap();
    cfg.method = AlignMethod::Uniform;
    let uniform = align(&seqs, &seqs, &ft, &cfg).unwrap();
    let r = warped.reference;
    for s in 1..seqs.len() {
        let dw = mean_distance(&warped.aligned[s], &warped.aligned[r], warped.increment_col);
        let du = mean_distance(
            &uniform.aligned[s],
            &uniform.aligned[r],
            uniform.increment_col,
        );
        assert!(dw < 0.5 * du, "sequence {s}: warped {dw} vs uniform {du}");
    }
}

#[test]
fn increments_integrate_to_durations() {
    let seqs = cycles(4);
    let ft: Vec<f64> = (0..seqs.len())
        .map(|s| 1.0 / (30.0 + 30.0 * (s % 2) as f64))
        .collect();
    for method in [AlignMethod::Dtw(DtwConfig::default()), AlignMethod::Uniform] {
        for frames in [2, 17, 34, 100] {
            let al = align(&seqs, &seqs, &ft, &AlignConfig::new(frames, method)).unwrap();
            for (s, seq) in al.aligned.iter().enumerate() {
                assert_eq!(seq.len(), frames);
                assert_eq!(seq.dim, 5);
                let incs: Vec<f64> = (0..frames)
                    .map(|k| seq.frame(k)[al.increment_col])
                    .collect();
                let total: f64 = incs.iter().sum();
                let duration = (seqs[s].len() - 1) as f64 * ft[s];
                assert!(
                    (total - duration).abs() < 1e-12,
                    "{s}: {total} vs {duration}"
                );
                assert!(incs[..frames - 1].iter().all(|&d| d > 0.0));
                assert_eq!(incs[frames - 1], 0.0);
                // The time map is strictly increasing from the first to the last source frame.
                let u = &al.source_frames[s];
                assert_eq!(u[0], 0.0);
                assert_eq!(u[frames - 1], (seqs[s].len() - 1) as f64);
                assert!(u.windows(2).all(|w| w[0] < w[1]));
                // First and last aligned values are the source's first and last frames.
                let skip = al.increment_col;
                let strip = |f: &[f64]| -> Vec<f64> {
                    f.iter()
                        .enumerate()
                        .filter(|&(c, _)| c != skip)
                        .map(|(_, &x)| x)
                        .collect()
                };
                assert_eq!(strip(seq.frame(0)), seqs[s].frame(0));
                assert_eq!(
                    strip(seq.frame(frames - 1)),
                    seqs[s].frame(seqs[s].len() - 1)
                );
            }
        }
    }
}

#[test]
fn increment_row_inserts_the_column() {
    let seqs = cycles(8);
    let ft = vec![0.1; seqs.len()];
    let mut cfg = AlignConfig::new(20, AlignMethod::Uniform);
    let appended = align(&seqs, &seqs, &ft, &cfg).unwrap();
    assert_eq!(appended.increment_col, 8);
    cfg.increment_row = Some(6);
    let inserted = align(&seqs, &seqs, &ft, &cfg).unwrap();
    assert_eq!(inserted.increment_col, 6);
    for (x, y) in appended.aligned.iter().zip(&inserted.aligned) {
        for k in 0..20 {
            let (fx, fy) = (x.frame(k), y.frame(k));
            assert_eq!(&fx[..6], &fy[..6]);
            assert_eq!(fx[8], fy[6]);
            assert_eq!(&fx[6..8], &fy[7..9]);
        }
    }
    cfg.increment_row = Some(9);
    assert!(matches!(
        align(&seqs, &seqs, &ft, &cfg),
        Err(TimewarpError::InvalidConfig {
            what: "increment_row",
            ..
        })
    ));
}

#[test]
fn values_follow_the_feature_warp() {
    // Values differ from features (here: a scaled copy plus a constant column); the warp found on
    // the features is applied to the values.
    let feats = cycles(3);
    let vals: Vec<FrameSeq> = feats
        .iter()
        .map(|f| {
            let mut v = FrameSeq::zeros(2, f.len());
            for k in 0..f.len() {
                v.frame_mut(k)[0] = 2.0 * f.frame(k)[0];
                v.frame_mut(k)[1] = 7.0;
            }
            v
        })
        .collect();
    let mut cfg = AlignConfig::new(30, AlignMethod::Dtw(DtwConfig::default()));
    cfg.reference = Some(2);
    let al = align(&feats, &vals, &vec![1.0 / 30.0; feats.len()], &cfg).unwrap();
    assert_eq!(al.reference, 2);
    for (s, seq) in al.aligned.iter().enumerate() {
        for k in 0..30 {
            let u = al.source_frames[s][k];
            let mut f = [0.0; 3];
            feats[s].sample_at(u, &mut f);
            assert!((seq.frame(k)[0] - 2.0 * f[0]).abs() < 1e-12);
            assert!((seq.frame(k)[1] - 7.0).abs() < 1e-12);
        }
    }
}

#[test]
fn medoid_is_exact_for_small_sets_and_robust_for_large_ones() {
    let seqs = cycles(5);
    let cfg = DtwConfig::default();
    let mut ws = DtwWorkspace::new();
    let sums: Vec<f64> = (0..seqs.len())
        .map(|r| {
            (0..seqs.len())
                .filter(|&s| s != r)
                .map(|s| dtw_cost_with(&seqs[r], &seqs[s], &cfg, &mut ws).unwrap())
                .sum()
        })
        .collect();
    let best = (0..sums.len())
        .min_by(|&a, &b| sums[a].total_cmp(&sums[b]))
        .unwrap();
    assert_eq!(medoid(&seqs, &cfg).unwrap(), best);
    assert_eq!(
        medoid_with_candidates(&seqs, &cfg, seqs.len()).unwrap(),
        best
    );
    // With preselection the choice is one of the sequences and depends only on the data.
    let pre = medoid_with_candidates(&seqs, &cfg, 2).unwrap();
    assert!(pre < seqs.len());
    assert_eq!(pre, medoid_with_candidates(&seqs, &cfg, 2).unwrap());
    // An outlier far from the others is never the medoid.
    let mut with_outlier = seqs.clone();
    for v in &mut with_outlier[3].frames {
        *v += 10.0;
    }
    assert_ne!(medoid(&with_outlier, &cfg).unwrap(), 3);
    assert_ne!(uniform_medoid(&with_outlier).unwrap(), 3);
    assert_eq!(median_length(&seqs), 34);
    assert_eq!(median_length(&[]), 0);
}

#[test]
fn large_set_medoid_and_alignment_are_deterministic() {
    // 200 cycles of different length and timing; same result twice and on a 1-thread pool.
    let seqs: Vec<FrameSeq> = (0..200)
        .map(|s| {
            let n = 24 + (s * 7) % 17;
            let a = ((s * 13) % 11) as f64 / 10.0 - 0.5;
            common::warped(n, 12, common::bump(a))
        })
        .collect();
    let ft = vec![1.0 / 30.0; seqs.len()];
    let cfg = AlignConfig::for_data(&seqs, AlignMethod::Dtw(DtwConfig::default()));
    assert_eq!(cfg.frames, median_length(&seqs));
    let a = align(&seqs, &seqs, &ft, &cfg).unwrap();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let b = pool.install(|| align(&seqs, &seqs, &ft, &cfg).unwrap());
    assert_eq!(a, b);
}

#[test]
fn bad_inputs_are_errors() {
    let seqs = cycles(3);
    let ft = vec![1.0 / 30.0; seqs.len()];
    let cfg = AlignConfig::new(20, AlignMethod::Dtw(DtwConfig::default()));
    assert!(matches!(
        align(&[], &[], &[], &cfg),
        Err(TimewarpError::NoSequences)
    ));
    assert!(matches!(
        align(&seqs, &seqs[..3], &ft, &cfg),
        Err(TimewarpError::CountMismatch {
            features: 7,
            values: 3
        })
    ));
    assert!(matches!(
        align(&seqs, &seqs, &ft[..2], &cfg),
        Err(TimewarpError::CountMismatch {
            features: 7,
            values: 2
        })
    ));
    let mut bad_ft = ft.clone();
    bad_ft[4] = 0.0;
    assert!(matches!(
        align(&seqs, &seqs, &bad_ft, &cfg),
        Err(TimewarpError::BadFrameTime { index: 4, .. })
    ));
    let mut nan = seqs.clone();
    nan[5].frames[3] = f64::INFINITY;
    assert!(matches!(
        align(&nan, &seqs, &ft, &cfg),
        Err(TimewarpError::NonFinite {
            index: 5,
            frame: 1,
            column: 0,
            ..
        })
    ));
    let mut mixed = seqs.clone();
    mixed[2] = common::warped(30, 4, |s| s);
    assert!(matches!(
        align(&mixed, &seqs, &ft, &cfg),
        Err(TimewarpError::DimMismatch {
            index: 2,
            expected: 3,
            found: 4
        })
    ));
    let mut short_vals = seqs.clone();
    short_vals[1] = common::warped(12, 3, |s| s);
    assert!(matches!(
        align(&seqs, &short_vals, &ft, &cfg),
        Err(TimewarpError::FrameCountMismatch {
            index: 1,
            features: 30,
            values: 12
        })
    ));
    let mut one_frame = seqs.clone();
    one_frame[6] = common::warped(2, 3, |s| s);
    one_frame[6].frames.truncate(3);
    assert!(matches!(
        align(&one_frame, &one_frame, &ft, &cfg),
        Err(TimewarpError::TooShort {
            index: 6,
            frames: 1,
            needed: 2
        })
    ));
    let mut c = cfg;
    c.frames = 1;
    assert!(matches!(
        align(&seqs, &seqs, &ft, &c),
        Err(TimewarpError::InvalidConfig { .. })
    ));
    c = cfg;
    c.reference = Some(7);
    assert!(matches!(
        align(&seqs, &seqs, &ft, &c),
        Err(TimewarpError::ReferenceOutOfRange {
            reference: 7,
            count: 7
        })
    ));
    c = cfg;
    c.method = AlignMethod::Dtw(DtwConfig {
        band: 1.0,
        max_slope: 0,
    });
    c.reference = Some(0);
    assert!(matches!(
        align(&seqs, &seqs, &ft, &c),
        Err(TimewarpError::Pair { reference: 0, .. })
    ));
}

/// The medoid reports overflowing DTW costs as such (inside [`TimewarpError::Pair`]).
#[test]
fn medoid_reports_overflowing_costs() {
    let seq = |v: &[f64]| FrameSeq::new(1, v.to_vec()).unwrap();
    let set = [
        seq(&[1e200, 0.0, 1.0]),
        seq(&[-1e200, 0.0, 1.0]),
        seq(&[0.0, 1.0, 1e200]),
    ];
    let err = medoid(&set, &DtwConfig::default()).unwrap_err();
    assert!(
        matches!(&err, TimewarpError::Pair { source, .. }
            if matches!(**source, TimewarpError::NonFiniteCost { .. })),
        "{err}"
    );
}

/// Absurd aligned frame counts, outputs and durations are refused instead of aborting on the
/// allocation or returning infinite increments.
#[test]
fn absurd_sizes_and_durations_are_refused() {
    let seqs = cycles(2);
    let ft = vec![1.0 / 30.0; seqs.len()];
    for frames in [1 << 40, timewarp::MAX_ALIGN_FRAMES + 1] {
        assert!(matches!(
            align(
                &seqs,
                &seqs,
                &ft,
                &AlignConfig::new(frames, AlignMethod::Uniform)
            ),
            Err(TimewarpError::InvalidConfig { what: "frames", .. })
        ));
    }
    // 7 sequences x 1e6 frames x 201 columns: over the buffer limit.
    let wide: Vec<FrameSeq> = seqs.iter().map(|s| FrameSeq::zeros(200, s.len())).collect();
    let cfg = AlignConfig::new(timewarp::MAX_ALIGN_FRAMES, AlignMethod::Uniform);
    assert!(matches!(
        align(&seqs, &wide, &ft, &cfg),
        Err(TimewarpError::TooLarge { .. })
    ));
    // A frame time whose duration overflows gives no infinite increments.
    let mut huge = ft.clone();
    huge[3] = f64::MAX;
    assert!(matches!(
        align(
            &seqs,
            &seqs,
            &huge,
            &AlignConfig::new(5, AlignMethod::Uniform)
        ),
        Err(TimewarpError::DurationOverflow {
            index: 3,
            frames: 33,
            ..
        })
    ));
    // Large but finite durations stay fine.
    let al = align(
        &seqs,
        &seqs,
        &[1e300; 7],
        &AlignConfig::new(5, AlignMethod::Uniform),
    )
    .unwrap();
    assert!(
        al.aligned
            .iter()
            .all(|a| a.frames.iter().all(|v| v.is_finite()))
    );
}
