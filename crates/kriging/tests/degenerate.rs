//! Degenerate input gives a clear error or a documented regularisation, never NaN or a panic.

// Reference loops are index-style on purpose (they mirror the formulas).
#![allow(clippy::needless_range_loop)]

use crate::common;

use common::*;
use faer::Mat;
use kriging::*;

fn given(v: Variogram, method: Method) -> KrigingConfig {
    KrigingConfig {
        method,
        model: ModelChoice::Given(v),
        scaling: ScalingChoice::None,
        ..KrigingConfig::default()
    }
}

fn all_finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

#[test]
fn duplicate_points_without_nugget_name_both_samples() {
    let (mut p, x) = data(8, 2, 1);
    p[5] = p[2].clone();
    let v = var(VariogramModel::Exponential, 0.0);
    for method in [Method::Ordinary, Method::Regression] {
        let e =
            Kriging::fit(to_mat(&p).as_ref(), to_mat(&x).as_ref(), &given(v, method)).unwrap_err();
        assert_eq!(
            e,
            KrigingError::DuplicateParams {
                what: "kriging",
                first: 2,
                second: 5
            }
        );
        assert!(e.to_string().contains("samples 2 and 5"));
    }
    let e = Rbf::fit(
        to_mat(&p).as_ref(),
        to_mat(&x).as_ref(),
        &RbfConfig {
            smoothing: RbfSmoothing::None,
            ..RbfConfig::default()
        },
    )
    .unwrap_err();
    assert!(matches!(
        e,
        KrigingError::DuplicateParams {
            first: 2,
            second: 5,
            ..
        }
    ));
}

#[test]
fn duplicate_points_with_nugget_are_regularised() {
    let (mut p, mut x) = data(8, 2, 1);
    p[5] = p[2].clone();
    x[5] = x[2].iter().map(|v| v + 0.1).collect();
    let v = var(VariogramModel::Exponential, 0.2);
    let k = Kriging::fit(
        to_mat(&p).as_ref(),
        to_mat(&x).as_ref(),
        &given(v, Method::Ordinary),
    )
    .unwrap();
    let mut b = vec![0.0; 8];
    k.weights(&p[2], &mut b).unwrap();
    assert!(all_finite(&b));
    assert!((b.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    // Both duplicates share the weight (symmetry), the others get none.
    assert!((b[2] - b[5]).abs() < 1e-10 && b[2] > 0.3, "{b:?}");
    assert!(all_finite(k.leave_one_out().unwrap().per_sample.as_slice()));
}

#[test]
fn automatic_fit_with_duplicates_uses_a_nugget_model_or_errors_cleanly() {
    let (mut p, x) = data(12, 2, 4);
    p[7] = p[3].clone();
    let cfg = KrigingConfig {
        method: Method::Ordinary,
        ..KrigingConfig::default()
    };
    match Kriging::fit(to_mat(&p).as_ref(), to_mat(&x).as_ref(), &cfg) {
        Ok(k) => {
            assert!(k.variogram().nugget > 0.0);
            let mut b = vec![0.0; 12];
            k.weights(&[0.5, 0.5], &mut b).unwrap();
            assert!(all_finite(&b));
        }
        Err(e) => assert!(matches!(e, KrigingError::NoModel(_)), "{e}"),
    }
}

#[test]
fn too_few_samples_for_the_trend() {
    let (p, x) = data(4, 3, 2);
    let e = Kriging::fit(
        to_mat(&p).as_ref(),
        to_mat(&x).as_ref(),
        &given(var(VariogramModel::Linear, 0.0), Method::Regression),
    )
    .unwrap_err();
    assert_eq!(
        e,
        KrigingError::TooFewSamples {
            what: "regression kriging (trend over [c; 1] plus residuals)",
            needed: 5,
            got: 4
        }
    );
    let (p1, x1) = data(1, 2, 2);
    assert!(matches!(
        Kriging::fit(
            to_mat(&p1).as_ref(),
            to_mat(&x1).as_ref(),
            &given(var(VariogramModel::Linear, 0.0), Method::Ordinary)
        ),
        Err(KrigingError::TooFewSamples {
            needed: 2,
            got: 1,
            ..
        })
    ));
}

#[test]
fn collinear_parameters_use_the_pseudo_inverse() {
    // Points on the line y = 2x in 2-D: C is rank 2, the trend is taken along the line only.
    let p: Vec<Vec<f64>> = (0..7)
        .map(|i| vec![i as f64 * 0.15, i as f64 * 0.3])
        .collect();
    let x: Vec<Vec<f64>> = p.iter().map(|c| field(c)).collect();
    let v = var(VariogramModel::Exponential, 0.0);
    let k = Kriging::fit(
        to_mat(&p).as_ref(),
        to_mat(&x).as_ref(),
        &given(v, Method::Regression),
    )
    .unwrap();
    let f = k.trend().unwrap();
    assert!((0..3).all(|j| (0..3).all(|l| f[(j, l)].is_finite())));
    let mut y = vec![0.0; 3];
    for (i, c) in p.iter().enumerate() {
        k.predict(c, &mut y).unwrap();
        for j in 0..3 {
            assert!((y[j] - x[i][j]).abs() < 1e-9);
        }
    }
    assert!(all_finite(&k.leave_one_out().unwrap().per_sample));
    // Standardised: both dimensions stay (neither is constant), the RBF drops one polynomial term.
    let r = Rbf::fit(
        to_mat(&p).as_ref(),
        to_mat(&x).as_ref(),
        &RbfConfig::default(),
    )
    .unwrap();
    assert_eq!(r.poly_terms(), 2);
    let mut b = vec![0.0; 7];
    r.weights(&[0.4, 0.8], &mut b).unwrap();
    assert!(all_finite(&b) && (b.iter().sum::<f64>() - 1.0).abs() < 1e-10);
}

#[test]
fn constant_dimension_is_dropped_and_reported() {
    let (mut p, x) = data(10, 3, 8);
    for row in p.iter_mut() {
        row[2] = 1.75; // performer height, constant
    }
    let cfg = KrigingConfig {
        method: Method::Ordinary,
        model: ModelChoice::Fixed(VariogramModel::Exponential),
        ..KrigingConfig::default()
    };
    let k = Kriging::fit(to_mat(&p).as_ref(), to_mat(&x).as_ref(), &cfg).unwrap();
    assert_eq!(k.dropped_dims(), &[2]);
    assert_eq!(k.scaling().scale[2], 0.0);
    assert!((0..10).all(|i| k.scaled_params()[(i, 2)] == 0.0));
    let mut b = vec![0.0; 10];
    // A query with another height is the same query once the dimension is dropped.
    let mut b2 = vec![0.0; 10];
    k.weights(&[0.3, 0.4, 1.75], &mut b).unwrap();
    k.weights(&[0.3, 0.4, 1.90], &mut b2).unwrap();
    assert_eq!(b, b2);
    assert!(all_finite(&b));
}

#[test]
fn nan_and_infinity_are_rejected_with_their_position() {
    let (mut p, mut x) = data(6, 2, 3);
    let cfg = given(var(VariogramModel::Linear, 0.0), Method::Ordinary);
    p[4][1] = f64::NAN;
    assert_eq!(
        Kriging::fit(to_mat(&p).as_ref(), to_mat(&x).as_ref(), &cfg).unwrap_err(),
        KrigingError::NonFinite {
            what: "params",
            row: 4,
            col: 1
        }
    );
    p[4][1] = 0.5;
    x[3][2] = f64::INFINITY;
    assert_eq!(
        Kriging::fit(to_mat(&p).as_ref(), to_mat(&x).as_ref(), &cfg).unwrap_err(),
        KrigingError::NonFinite {
            what: "values",
            row: 3,
            col: 2
        }
    );
    x[3][2] = 0.0;
    let k = Kriging::fit(to_mat(&p).as_ref(), to_mat(&x).as_ref(), &cfg).unwrap();
    let mut b = vec![0.0; 6];
    assert!(matches!(
        k.weights(&[f64::NAN, 0.0], &mut b),
        Err(KrigingError::NonFinite { col: 0, .. })
    ));
    assert!(matches!(
        k.weights(&[0.0], &mut b),
        Err(KrigingError::ShapeMismatch { .. })
    ));
    assert!(matches!(
        k.predict(&[0.0, 0.0], &mut b),
        Err(KrigingError::ShapeMismatch {
            expected: 3,
            got: 6,
            ..
        })
    ));
    assert!(Variogram::new(VariogramModel::Exponential, f64::NAN, 1.0, 1.0, 1.0).is_err());
    assert!(Variogram::new(VariogramModel::Power, 0.0, 1.0, 0.0, 2.0).is_err());
    assert!(ParamScaling::given(vec![0.0], vec![-1.0]).is_err());
    assert!(ParamScaling::given(vec![0.0, 1.0], vec![1.0]).is_err());
}

#[test]
fn unfittable_variogram_is_a_clear_error() {
    // Values exactly linear in c: regression-kriging residuals are zero, nothing to fit.
    let (p, _) = data(8, 2, 6);
    let x: Vec<Vec<f64>> = p.iter().map(|c| vec![2.0 * c[0] - c[1] + 0.5]).collect();
    let cfg = KrigingConfig {
        model: ModelChoice::Fixed(VariogramModel::Spherical),
        ..KrigingConfig::default()
    };
    let e = Kriging::fit(to_mat(&p).as_ref(), to_mat(&x).as_ref(), &cfg).unwrap_err();
    assert!(
        matches!(e, KrigingError::VariogramFit { model: None, .. }),
        "{e}"
    );
    let e = Kriging::fit(
        to_mat(&p).as_ref(),
        to_mat(&x).as_ref(),
        &KrigingConfig::default(),
    )
    .unwrap_err();
    assert!(matches!(e, KrigingError::VariogramFit { .. }), "{e}");
    // A given variogram still yields weights; the prediction is the trend.
    let v = var(VariogramModel::Linear, 0.0);
    let k = Kriging::fit(
        to_mat(&p).as_ref(),
        to_mat(&x).as_ref(),
        &KrigingConfig {
            model: ModelChoice::Given(v),
            ..KrigingConfig::default()
        },
    )
    .unwrap();
    let mut y = [0.0];
    k.predict(&[0.3, 0.9], &mut y).unwrap();
    assert!((y[0] - (0.6 - 0.9 + 0.5)).abs() < 1e-12);
    // A decreasing empirical variogram has no non-negative fit other than a pure nugget.
    let emp = EmpiricalVariogram {
        bin_width: 1.0,
        centers: vec![0.5, 1.5, 2.5],
        gamma: vec![3.0, 2.0, 1.0],
        counts: vec![4, 4, 4],
    };
    let e = fit_variogram(&emp, VariogramModel::Exponential, &FitOptions::default()).unwrap_err();
    assert!(
        matches!(
            e,
            KrigingError::VariogramFit {
                model: Some(VariogramModel::Exponential),
                ..
            }
        ),
        "{e}"
    );
    // Constant values under ordinary kriging: same.
    let xc = vec![vec![3.0]; 8];
    let cfg = KrigingConfig {
        method: Method::Ordinary,
        ..KrigingConfig::default()
    };
    assert!(Kriging::fit(to_mat(&p).as_ref(), to_mat(&xc).as_ref(), &cfg).is_err());
    // All parameters equal.
    let pc = vec![vec![1.0, 1.0]; 5];
    let e = Kriging::fit(to_mat(&pc).as_ref(), to_mat(&xc[..5]).as_ref(), &cfg).unwrap_err();
    assert!(
        matches!(
            e,
            KrigingError::NoSpread { samples: 5 } | KrigingError::TooFewSamples { .. }
        ),
        "{e}"
    );
}

#[test]
fn ill_conditioned_gaussian_without_nugget_is_rejected_or_finite() {
    // Close points and a long-range gaussian make Gamma nearly singular.
    let p: Vec<Vec<f64>> = (0..30).map(|i| vec![i as f64 * 1e-3]).collect();
    let x: Vec<Vec<f64>> = p.iter().map(|c| vec![c[0].sin()]).collect();
    let v = Variogram::new(VariogramModel::Gaussian, 0.0, 1.0, 10.0, 1.0).unwrap();
    match Kriging::fit(
        to_mat(&p).as_ref(),
        to_mat(&x).as_ref(),
        &given(v, Method::Ordinary),
    ) {
        Err(e) => assert!(
            matches!(
                e,
                KrigingError::Singular {
                    what: "kriging",
                    ..
                }
            ),
            "{e}"
        ),
        Ok(k) => {
            let mut b = vec![0.0; 30];
            k.weights(&[0.0105], &mut b).unwrap();
            assert!(all_finite(&b));
        }
    }
}

#[test]
fn shape_mismatches_are_errors() {
    let p = Mat::<f64>::zeros(5, 2);
    let x = Mat::<f64>::zeros(4, 3);
    assert!(matches!(
        Kriging::fit(p.as_ref(), x.as_ref(), &KrigingConfig::default()),
        Err(KrigingError::ShapeMismatch { .. })
    ));
    let p0 = Mat::<f64>::zeros(0, 2);
    let x0 = Mat::<f64>::zeros(0, 3);
    assert!(Kriging::fit(p0.as_ref(), x0.as_ref(), &KrigingConfig::default()).is_err());
    assert!(Rbf::fit(p0.as_ref(), x0.as_ref(), &RbfConfig::default()).is_err());
    let cfg = KrigingConfig {
        bins: 0,
        ..KrigingConfig::default()
    };
    let (pp, xx) = data(8, 2, 1);
    assert!(matches!(
        Kriging::fit(to_mat(&pp).as_ref(), to_mat(&xx).as_ref(), &cfg),
        Err(KrigingError::InvalidConfig(_))
    ));
}
