//! `select_dims_by_folds`: every varying dimension stays unless dropping it lowers the error of a
//! cross-validation over the given folds; a dimension that only adds noise goes.

use faer::Mat;

use crate::common;
use kriging::{DimDecision, KrigingConfig, select_dims_by_folds};

const MARGIN: f64 = 0.01;

/// [`common::selection_data`] with `b_weight`, and its 60 samples in 20 groups of 3 (group
/// `g = i / 3`), the groups dealt round-robin to 5 folds (the folds deal whole groups).
fn data(b_weight: f64) -> (Mat<f64>, Mat<f64>, Vec<usize>) {
    let (params, values) = common::selection_data(11, b_weight);
    let fold = (0..params.nrows()).map(|i| (i / 3) % 5).collect();
    (params, values, fold)
}

fn select(b_weight: f64) -> kriging::DimSelection {
    let (params, values, fold) = data(b_weight);
    select_dims_by_folds(
        params.as_ref(),
        values.as_ref(),
        &KrigingConfig::default(),
        MARGIN,
        &fold,
        None,
    )
    .unwrap()
}

#[test]
fn a_dimension_whose_dropping_does_not_lower_the_error_stays() {
    // A real effect of `b`, weaker than `a`'s: dropping it does not lower the held-out error, so it stays.
    let sel = select(0.3);
    for k in [0, 1] {
        match sel.decisions[k] {
            DimDecision::KeptByFolds {
                cv_with,
                cv_without,
                folds,
            } => {
                assert_eq!(folds, 5);
                assert!(
                    cv_with.is_finite() && cv_with <= (1.0 + MARGIN) * cv_without,
                    "dimension {k}: {cv_with} with, {cv_without} without"
                );
            }
            d => panic!("dimension {k}: {d:?}"),
        }
    }
    assert_eq!(sel.decisions[2], DimDecision::Constant);
    assert!(
        sel.kriging.dropped_dims() == [2],
        "{:?}",
        sel.kriging.dropped_dims()
    );
    assert!(sel.rmse.is_finite() && sel.rmse > 0.0);
}

#[test]
fn a_dimension_that_only_adds_noise_is_dropped() {
    let sel = select(0.0);
    assert!(
        matches!(sel.decisions[0], DimDecision::KeptByFolds { .. }),
        "{:?}",
        sel.decisions
    );
    match sel.decisions[1] {
        DimDecision::DroppedByFolds {
            cv_with,
            cv_without,
            folds,
        } => {
            assert_eq!(folds, 5);
            assert!(
                cv_with > (1.0 + MARGIN) * cv_without,
                "{cv_with} vs {cv_without}"
            );
            assert!((sel.rmse - cv_without).abs() < 1e-12);
        }
        d => panic!("noise dimension: {d:?}"),
    }
    // The only dimension left cannot be dropped: its `without` is infinite.
    assert!(matches!(
        sel.decisions[0],
        DimDecision::KeptByFolds { cv_without, .. } if cv_without.is_infinite()
    ));
    assert_eq!(sel.kriging.dropped_dims(), [1, 2]);
}

#[test]
fn the_selection_is_deterministic_over_thread_counts() {
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| select(0.3));
    let many = select(0.3);
    assert_eq!(one.decisions, many.decisions);
    assert_eq!(one.rmse.to_bits(), many.rmse.to_bits());
}

#[test]
fn bad_folds_and_margins_are_errors() {
    let (params, values, fold) = data(0.0);
    let cfg = KrigingConfig::default();
    let run = |margin: f64, fold: &[usize], scored: Option<&[bool]>| {
        select_dims_by_folds(params.as_ref(), values.as_ref(), &cfg, margin, fold, scored)
    };
    assert!(run(-0.1, &fold, None).is_err());
    assert!(run(f64::NAN, &fold, None).is_err());
    assert!(run(MARGIN, &fold[1..], None).is_err(), "wrong length");
    assert!(run(MARGIN, &vec![0; 60], None).is_err(), "one fold");
    let gap: Vec<usize> = fold.iter().map(|&f| if f == 1 { 2 } else { f }).collect();
    assert!(run(MARGIN, &gap, None).is_err(), "an empty fold");
    assert!(
        run(MARGIN, &fold, Some(&[false; 4])).is_err(),
        "scores nothing"
    );
    assert!(
        run(MARGIN, &fold, Some(&[true; 3])).is_err(),
        "wrong mask length"
    );
}
