//! `select_dims`: dimensions that carry signal stay, noise dimensions and constants go.

use faer::Mat;

use crate::common;
use kriging::{DimDecision, KrigingConfig, SelectRule, select_dims};

const RULE: SelectRule = SelectRule {
    margin: 0.01,
    min_t: 2.0,
};

/// [`common::selection_data`]: `b` carries signal when `b_matters`.
fn data(b_matters: bool) -> (Mat<f64>, Mat<f64>) {
    common::selection_data(7, if b_matters { 1.0 } else { 0.0 })
}

#[test]
fn a_noise_dimension_is_dropped_and_a_constant_reported() {
    let (params, values) = data(false);
    let sel = select_dims(
        params.as_ref(),
        values.as_ref(),
        &KrigingConfig::default(),
        RULE,
        None,
    )
    .unwrap();
    assert!(
        matches!(sel.decisions[0], DimDecision::Kept { .. }),
        "{:?}",
        sel.decisions
    );
    assert!(
        matches!(sel.decisions[1], DimDecision::NoSignal { .. }),
        "{:?}",
        sel.decisions
    );
    assert_eq!(sel.decisions[2], DimDecision::Constant);
    assert_eq!(sel.kriging.dropped_dims(), &[1, 2]);
    assert!(sel.decisions[1].dropped() && !sel.decisions[0].dropped());
    // Predictions do not move with the dropped dimension.
    let (mut x, mut y) = (vec![0.0; 4], vec![0.0; 4]);
    sel.kriging.predict(&[0.2, -0.9, 2.5], &mut x).unwrap();
    sel.kriging.predict(&[0.2, 0.9, 2.5], &mut y).unwrap();
    assert_eq!(x, y);
}

#[test]
fn dimensions_with_signal_stay() {
    let (params, values) = data(true);
    let sel = select_dims(
        params.as_ref(),
        values.as_ref(),
        &KrigingConfig::default(),
        RULE,
        None,
    )
    .unwrap();
    for k in [0, 1] {
        match sel.decisions[k] {
            DimDecision::Kept {
                loo_with,
                loo_without,
                t,
            } => assert!(loo_with < loo_without && t >= 2.0, "{:?}", sel.decisions),
            other => panic!("dimension {k}: {other:?}"),
        }
    }
    assert_eq!(sel.kriging.dropped_dims(), &[2]);
}

#[test]
fn scored_columns_decide_and_bad_rules_are_refused() {
    let (params, values) = data(true);
    // Column 0 replaced by a function of a alone and scored alone: b's effect on the other columns
    // does not count, so b is dropped.
    let only_a = Mat::from_fn(values.nrows(), values.ncols(), |i, j| {
        if j == 0 {
            (1.5 * params[(i, 0)]).sin()
        } else {
            values[(i, j)]
        }
    });
    let mask = [true, false, false, false];
    let sel = select_dims(
        params.as_ref(),
        only_a.as_ref(),
        &KrigingConfig::default(),
        RULE,
        Some(&mask),
    )
    .unwrap();
    assert!(
        matches!(sel.decisions[1], DimDecision::NoSignal { .. }),
        "{:?}",
        sel.decisions
    );
    let cfg = KrigingConfig::default();
    for rule in [
        SelectRule {
            margin: -0.1,
            min_t: 2.0,
        },
        SelectRule {
            margin: 0.01,
            min_t: f64::NAN,
        },
    ] {
        assert!(select_dims(params.as_ref(), values.as_ref(), &cfg, rule, None).is_err());
    }
    assert!(
        select_dims(
            params.as_ref(),
            values.as_ref(),
            &cfg,
            RULE,
            Some(&[true, false])
        )
        .is_err()
    );
    assert!(
        select_dims(
            params.as_ref(),
            values.as_ref(),
            &cfg,
            RULE,
            Some(&[false; 4])
        )
        .is_err()
    );
}
