//! DTW against a brute-force search, constraints, and known warps.

use crate::common;

use proptest::prelude::*;
use timewarp::{DtwConfig, DtwWorkspace, FrameSeq, TimewarpError, dtw, dtw_cost_with, dtw_with};

fn d2(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum()
}

/// Independent statement of the band rule: normalised time difference within
/// `max(band, 0.5 / (min(n, m) - 1))`, no band when a sequence has one frame.
fn in_band(n: usize, m: usize, band: f64, i: usize, j: usize) -> bool {
    let short = n.min(m);
    if short <= 1 {
        return true;
    }
    let w = band.max(0.5 / (short - 1) as f64);
    (i as f64 / (n - 1) as f64 - j as f64 / (m - 1) as f64).abs() <= w + 1e-12
}

/// Checks start, end, steps, band and slope of a path; returns its cost.
fn check_path(a: &FrameSeq, b: &FrameSeq, cfg: &DtwConfig, pairs: &[(usize, usize)]) -> f64 {
    let (n, m) = (a.len(), b.len());
    assert_eq!(pairs.first(), Some(&(0, 0)));
    assert_eq!(pairs.last(), Some(&(n - 1, m - 1)));
    let (mut run_a, mut run_b) = (0, 0);
    for w in pairs.windows(2) {
        let (di, dj) = (w[1].0 - w[0].0, w[1].1 - w[0].1);
        match (di, dj) {
            (1, 1) => {
                run_a = 0;
                run_b = 0;
            }
            (1, 0) => {
                run_a += 1;
                run_b = 0;
            }
            (0, 1) => {
                run_b += 1;
                run_a = 0;
            }
            _ => panic!("illegal step {:?} -> {:?}", w[0], w[1]),
        }
        assert!(
            run_a <= cfg.max_slope && run_b <= cfg.max_slope,
            "slope broken at {:?}",
            w[1]
        );
    }
    for &(i, j) in pairs {
        assert!(in_band(n, m, cfg.band, i, j), "({i}, {j}) outside the band");
    }
    pairs.iter().map(|&(i, j)| d2(a.frame(i), b.frame(j))).sum()
}

/// Minimum cost over every admissible path, by exhaustive search.
fn brute_force(a: &FrameSeq, b: &FrameSeq, cfg: &DtwConfig) -> Option<f64> {
    #[allow(clippy::too_many_arguments)]
    fn go(
        a: &FrameSeq,
        b: &FrameSeq,
        cfg: &DtwConfig,
        i: usize,
        j: usize,
        run_a: usize,
        run_b: usize,
        acc: f64,
        best: &mut Option<f64>,
    ) {
        let (n, m) = (a.len(), b.len());
        if !in_band(n, m, cfg.band, i, j) || run_a > cfg.max_slope || run_b > cfg.max_slope {
            return;
        }
        let acc = acc + d2(a.frame(i), b.frame(j));
        if i == n - 1 && j == m - 1 {
            if best.is_none_or(|b| acc < b) {
                *best = Some(acc);
            }
            return;
        }
        if i + 1 < n && j + 1 < m {
            go(a, b, cfg, i + 1, j + 1, 0, 0, acc, best);
        }
        if i + 1 < n {
            go(a, b, cfg, i + 1, j, run_a + 1, 0, acc, best);
        }
        if j + 1 < m {
            go(a, b, cfg, i, j + 1, 0, run_b + 1, acc, best);
        }
    }
    let mut best = None;
    go(a, b, cfg, 0, 0, 0, 0, 0.0, &mut best);
    best
}

fn seq_strategy(max_len: usize, dim: usize) -> impl Strategy<Value = FrameSeq> {
    prop::collection::vec(-2.0f64..2.0, dim..=max_len * dim).prop_map(move |mut v| {
        v.truncate(v.len() / dim * dim);
        FrameSeq::new(dim, v).unwrap()
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn dtw_matches_brute_force(
        a in seq_strategy(7, 2),
        b in seq_strategy(7, 2),
        band in prop_oneof![Just(0.0), 0.0f64..0.6, Just(1.0)],
        max_slope in 0usize..8,
    ) {
        let cfg = DtwConfig { band, max_slope };
        let expected = brute_force(&a, &b, &cfg);
        match (dtw(&a, &b, &cfg), expected) {
            (Ok(path), Some(best)) => {
                let recomputed = check_path(&a, &b, &cfg, &path.pairs);
                prop_assert!((recomputed - path.cost).abs() <= 1e-9 * (1.0 + best));
                prop_assert!((path.cost - best).abs() <= 1e-9 * (1.0 + best),
                    "dtw {} brute force {}", path.cost, best);
                let mut ws = DtwWorkspace::new();
                let c = dtw_cost_with(&a, &b, &cfg, &mut ws).unwrap();
                prop_assert_eq!(c, path.cost);
            }
            (Err(TimewarpError::NoPath { .. }), None) => {}
            (got, want) => prop_assert!(false, "dtw {:?} vs brute force {:?}", got, want),
        }
    }
}

#[test]
fn identical_sequences_warp_to_the_diagonal() {
    let a = common::warped(30, 5, |s| s);
    for cfg in [
        DtwConfig::default(),
        DtwConfig {
            band: 1.0,
            max_slope: usize::MAX,
        },
        DtwConfig {
            band: 0.0,
            max_slope: 0,
        },
    ] {
        let path = dtw(&a, &a, &cfg).unwrap();
        let diagonal: Vec<(usize, usize)> = (0..30).map(|i| (i, i)).collect();
        assert_eq!(path.pairs, diagonal);
        assert_eq!(path.cost, 0.0);
    }
}

#[test]
fn known_monotone_warp_is_recovered() {
    // b_j = curve(w(j / (m - 1))): the matched reference frame should be close to (n - 1) w(s_j).
    let (n, m) = (40, 50);
    let warp = common::bump(0.6);
    let a = common::warped(n, 6, |s| s);
    let b = common::warped(m, 6, &warp);
    let cfg = DtwConfig {
        band: 0.25,
        max_slope: 3,
    };
    let path = dtw(&a, &b, &cfg).unwrap();
    check_path(&a, &b, &cfg, &path.pairs);
    let mut worst: f64 = 0.0;
    for &(i, j) in &path.pairs {
        let expected = (n - 1) as f64 * warp(j as f64 / (m - 1) as f64);
        worst = worst.max((i as f64 - expected).abs());
    }
    assert!(
        worst <= 1.5,
        "largest deviation from the true warp: {worst} frames"
    );
}

#[test]
fn band_and_slope_are_respected_on_longer_inputs() {
    let a = common::warped(45, 4, |s| s * s);
    let b = common::warped(33, 4, |s| s.sqrt());
    for cfg in [
        DtwConfig {
            band: 0.05,
            max_slope: 2,
        },
        DtwConfig {
            band: 0.3,
            max_slope: 1,
        },
        DtwConfig {
            band: 1.0,
            max_slope: 5,
        },
    ] {
        let mut ws = DtwWorkspace::new();
        let path = dtw_with(&a, &b, &cfg, &mut ws).unwrap();
        let c = check_path(&a, &b, &cfg, &path.pairs);
        assert!((c - path.cost).abs() < 1e-9 * (1.0 + c));
    }
    // A wider band can only lower the cost.
    let narrow = dtw(
        &a,
        &b,
        &DtwConfig {
            band: 0.05,
            max_slope: 2,
        },
    )
    .unwrap()
    .cost;
    let wide = dtw(
        &a,
        &b,
        &DtwConfig {
            band: 0.5,
            max_slope: 2,
        },
    )
    .unwrap()
    .cost;
    assert!(wide <= narrow);
}

#[test]
fn impossible_slope_is_reported() {
    let a = common::warped(4, 2, |s| s);
    let b = common::warped(20, 2, |s| s);
    let err = dtw(
        &a,
        &b,
        &DtwConfig {
            band: 1.0,
            max_slope: 1,
        },
    )
    .unwrap_err();
    assert!(
        matches!(
            err,
            TimewarpError::NoPath {
                len_a: 4,
                len_b: 20,
                ..
            }
        ),
        "{err}"
    );
    let err = dtw(
        &a,
        &b,
        &DtwConfig {
            band: 1.0,
            max_slope: 0,
        },
    )
    .unwrap_err();
    assert!(matches!(err, TimewarpError::NoPath { .. }));
}

#[test]
fn bad_inputs_are_errors() {
    let a = common::warped(10, 3, |s| s);
    let cfg = DtwConfig::default();
    let empty = FrameSeq::new(3, vec![]).unwrap();
    assert!(matches!(
        dtw(&a, &empty, &cfg),
        Err(TimewarpError::TooShort {
            index: 1,
            frames: 0,
            ..
        })
    ));
    let mut nan = a.clone();
    nan.frame_mut(4)[2] = f64::NAN;
    assert!(matches!(
        dtw(&nan, &a, &cfg),
        Err(TimewarpError::NonFinite {
            index: 0,
            frame: 4,
            column: 2,
            ..
        })
    ));
    let other = common::warped(10, 2, |s| s);
    assert!(matches!(
        dtw(&a, &other, &cfg),
        Err(TimewarpError::DimMismatch {
            index: 1,
            expected: 3,
            found: 2
        })
    ));
    let ragged = FrameSeq {
        dim: 3,
        frames: vec![0.0; 7],
    };
    assert!(matches!(
        dtw(&ragged, &a, &cfg),
        Err(TimewarpError::RaggedFrames { index: 0, .. })
    ));
    assert!(FrameSeq::new(0, vec![]).is_err());
    for band in [f64::NAN, -0.1, f64::INFINITY] {
        assert!(matches!(
            dtw(&a, &a, &DtwConfig { band, max_slope: 2 }),
            Err(TimewarpError::InvalidConfig { what: "band", .. })
        ));
    }
}

/// One-column sequence from its values.
fn column(values: &[f64]) -> FrameSeq {
    FrameSeq::new(1, values.to_vec()).unwrap()
}

/// Finite features whose squared distances (or their sum along the path) overflow give a
/// non-finite cost, reported as such and not as "no path" (the band and slope admit a path).
#[test]
fn overflowing_costs_are_not_reported_as_no_path() {
    let cfg = DtwConfig::default();
    let mut ws = DtwWorkspace::new();
    for big in [1e155, 1e200] {
        let a = column(&[big, -big, big]);
        let b = column(&[-big, big, -big]);
        let err = dtw(&a, &b, &cfg).unwrap_err();
        assert_eq!(
            err,
            TimewarpError::NonFiniteCost { len_a: 3, len_b: 3 },
            "{err}"
        );
        assert!(err.to_string().contains("too large"), "{err}");
        assert_eq!(dtw_cost_with(&a, &b, &cfg, &mut ws).unwrap_err(), err);
    }
    // Each squared distance (1.44e308) is finite, their sum along the path is not.
    let a = column(&[0.0, 0.0]);
    let b = column(&[1.2e154, 1.2e154]);
    assert_eq!(
        dtw(&a, &b, &cfg).unwrap_err(),
        TimewarpError::NonFiniteCost { len_a: 2, len_b: 2 }
    );
    // Constraints that admit no path are still reported as such, even with large values.
    let a = column(&[1e200, 0.0]);
    let b = column(&[-1e200, 0.0, 1.0, 2.0, 3.0]);
    let none = DtwConfig {
        band: 1.0,
        max_slope: 0,
    };
    assert!(matches!(
        dtw(&a, &b, &none),
        Err(TimewarpError::NoPath { .. })
    ));
}

/// A binding slope limit on long sequences would need a table of `n m (2 max_slope + 2)` values
/// (144 GB here): refused before any allocation.
#[test]
fn oversized_tables_are_refused() {
    let a = common::warped(3000, 1, |s| s);
    let b = common::warped(3000, 1, common::bump(0.1));
    let cfg = DtwConfig {
        band: 1.0,
        max_slope: 1000,
    };
    let err = dtw(&a, &b, &cfg).unwrap_err();
    assert!(
        matches!(
            &err,
            TimewarpError::TooLarge {
                limit: timewarp::MAX_BUFFER_VALUES,
                ..
            }
        ),
        "{err}"
    );
    assert!(err.to_string().contains("18018000000"), "{err}");
    assert_eq!(
        dtw_cost_with(&a, &b, &cfg, &mut DtwWorkspace::new()).unwrap_err(),
        err
    );
    let err = timewarp::medoid(&[a.clone(), b.clone()], &cfg).unwrap_err();
    assert!(
        matches!(&err, TimewarpError::Pair { source, .. }
            if matches!(**source, TimewarpError::TooLarge { .. })),
        "{err}"
    );
}
