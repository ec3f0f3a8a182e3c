//! Hand-checked cases and agreement with the naive reference in `common` (to 1e-10).

// Reference loops are index-style on purpose (they mirror the formulas).
#![allow(clippy::needless_range_loop)]

use crate::common;

use common::*;
use faer::Mat;
use kriging::*;

fn cfg(method: Method, model: ModelChoice) -> KrigingConfig {
    KrigingConfig {
        method,
        model,
        scaling: ScalingChoice::None,
        ..KrigingConfig::default()
    }
}

fn linear() -> Variogram {
    Variogram::new(VariogramModel::Linear, 0.0, 1.0, 0.0, 1.0).unwrap()
}

#[test]
fn hand_1d_two_points_linear_variogram_is_linear_interpolation() {
    let p = Mat::from_fn(2, 1, |i, _| i as f64);
    let x = Mat::from_fn(2, 1, |i, _| [2.0, 6.0][i]);
    let k = Kriging::fit(
        p.as_ref(),
        x.as_ref(),
        &cfg(Method::Ordinary, ModelChoice::Given(linear())),
    )
    .unwrap();
    let mut b = [0.0; 2];
    k.weights(&[0.25], &mut b).unwrap();
    assert!(
        (b[0] - 0.75).abs() < 1e-12 && (b[1] - 0.25).abs() < 1e-12,
        "{b:?}"
    );
    let mut y = [0.0];
    k.predict(&[0.25], &mut y).unwrap();
    assert!((y[0] - 3.0).abs() < 1e-12);
}

#[test]
fn hand_1d_three_points_linear_variogram_uses_neighbours_only() {
    // In 1-D, ordinary kriging with gamma(h) = h interpolates piecewise linearly between neighbours.
    let p = Mat::from_fn(3, 1, |i, _| [0.0, 1.0, 3.0][i]);
    let x = Mat::from_fn(3, 1, |i, _| [1.0, -1.0, 5.0][i]);
    let k = Kriging::fit(
        p.as_ref(),
        x.as_ref(),
        &cfg(Method::Ordinary, ModelChoice::Given(linear())),
    )
    .unwrap();
    let mut b = [0.0; 3];
    k.weights(&[2.0], &mut b).unwrap();
    for (got, want) in b.iter().zip([0.0, 0.5, 0.5]) {
        assert!((got - want).abs() < 1e-12, "{b:?}");
    }
    k.weights(&[0.5], &mut b).unwrap();
    for (got, want) in b.iter().zip([0.5, 0.5, 0.0]) {
        assert!((got - want).abs() < 1e-12, "{b:?}");
    }
}

#[test]
fn hand_2d_square_centre_gets_equal_weights() {
    let c = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]];
    let p = Mat::from_fn(4, 2, |i, k| c[i][k]);
    let x = Mat::from_fn(4, 1, |i, _| i as f64);
    for model in VariogramModel::ALL {
        let k = Kriging::fit(
            p.as_ref(),
            x.as_ref(),
            &cfg(Method::Ordinary, ModelChoice::Given(var(model, 0.1))),
        )
        .unwrap();
        let mut b = [0.0; 4];
        k.weights(&[0.5, 0.5], &mut b).unwrap();
        for w in b {
            assert!((w - 0.25).abs() < 1e-12, "{model:?} {b:?}");
        }
    }
}

#[test]
fn weights_and_predictions_match_naive_for_every_model() {
    let (p, x) = data(9, 2, 7);
    let (pm, xm) = (to_mat(&p), to_mat(&x));
    let queries = [[0.3, 0.8], [0.55, 0.1], [-0.2, 1.3], [0.5, 0.5]];
    for model in VariogramModel::ALL {
        for nugget in [0.0, 0.2] {
            let v = var(model, nugget);
            for (method, regression) in [(Method::Ordinary, false), (Method::Regression, true)] {
                let k = Kriging::fit(
                    pm.as_ref(),
                    xm.as_ref(),
                    &cfg(method, ModelChoice::Given(v)),
                )
                .unwrap();
                for q in &queries {
                    let mut b = vec![0.0; 9];
                    k.weights(q, &mut b).unwrap();
                    // Regression kriging: the ordinary weights of the residuals (same system).
                    let nb = ok_weights(&p, &v, q);
                    for (a, e) in b.iter().zip(&nb) {
                        assert!((a - e).abs() < 1e-10, "{model:?} {method:?} {a} vs {e}");
                    }
                    let mut y = vec![0.0; 3];
                    k.predict(q, &mut y).unwrap();
                    let ny = predict(&p, &x, &v, regression, q);
                    for (a, e) in y.iter().zip(&ny) {
                        assert!(
                            (a - e).abs() < 1e-10,
                            "{model:?} {method:?} predict {a} vs {e}"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn trend_matches_naive_normal_equations() {
    let (p, x) = data(10, 3, 11);
    let k = Kriging::fit(
        to_mat(&p).as_ref(),
        to_mat(&x).as_ref(),
        &cfg(Method::Regression, ModelChoice::Given(linear())),
    )
    .unwrap();
    let f = k.trend().unwrap();
    let nf = trend(&p, &x);
    assert_eq!(f.shape(), (3, 4));
    for j in 0..3 {
        for l in 0..4 {
            assert!((f[(j, l)] - nf[j][l]).abs() < 1e-10);
        }
    }
    let c = k.augmented_params();
    assert_eq!(c.shape(), (4, 10));
    assert_eq!(c[(3, 5)], 1.0);
    assert_eq!(c[(1, 5)], p[5][1]);
}

#[test]
fn empirical_variogram_matches_naive() {
    let (p, x) = data(15, 3, 3);
    let e = EmpiricalVariogram::compute(to_mat(&p).as_ref(), to_mat(&x).as_ref(), 6).unwrap();
    let (c, g, n) = empirical(&p, &x, 6);
    assert_eq!(e.counts, n);
    assert_eq!(e.counts.iter().sum::<usize>(), 15 * 14 / 2);
    for u in 0..6 {
        assert!((e.centers[u] - c[u]).abs() < 1e-12);
        assert!((e.gamma[u] - g[u]).abs() < 1e-10 * (1.0 + g[u]));
    }
}

#[test]
fn closed_form_loo_matches_refitting_s_times() {
    let (p, x) = data(11, 2, 5);
    let (pm, xm) = (to_mat(&p), to_mat(&x));
    for model in [
        VariogramModel::Linear,
        VariogramModel::Exponential,
        VariogramModel::Spherical,
    ] {
        for nugget in [0.0, 0.3] {
            let v = var(model, nugget);
            for (method, regression) in [(Method::Ordinary, false), (Method::Regression, true)] {
                let k = Kriging::fit(
                    pm.as_ref(),
                    xm.as_ref(),
                    &cfg(method, ModelChoice::Given(v)),
                )
                .unwrap();
                let e = k.loo_errors().unwrap();
                let ne = loo(&p, &x, &v, regression);
                for i in 0..11 {
                    for j in 0..3 {
                        assert!(
                            (e[(i, j)] - ne[i][j]).abs() < 1e-10,
                            "{model:?} {method:?} {i} {j}: {} vs {}",
                            e[(i, j)],
                            ne[i][j]
                        );
                    }
                }
                let r = k.leave_one_out().unwrap();
                let want = (ne
                    .iter()
                    .map(|e| e.iter().map(|v| v * v).sum::<f64>())
                    .sum::<f64>()
                    / 11.0)
                    .sqrt();
                assert!((r.rmse - want).abs() < 1e-10);
            }
        }
    }
}

#[test]
fn rbf_loo_matches_refitting_s_times() {
    let (p, x) = data(10, 2, 9);
    let cfg = RbfConfig {
        kernel: RbfKernel::Cubic,
        scaling: ScalingChoice::None,
        smoothing: RbfSmoothing::None,
    };
    let r = Rbf::fit(to_mat(&p).as_ref(), to_mat(&x).as_ref(), &cfg).unwrap();
    let e = r.loo_errors().unwrap();
    for k in 0..10 {
        let (pk, xk) = (without(&p, k), without(&x, k));
        let rk = Rbf::fit(to_mat(&pk).as_ref(), to_mat(&xk).as_ref(), &cfg).unwrap();
        let mut y = vec![0.0; 3];
        rk.predict(&p[k], &mut y).unwrap();
        for j in 0..3 {
            assert!((e[(k, j)] - (x[k][j] - y[j])).abs() < 1e-9, "{k} {j}");
        }
    }
}

#[test]
fn rbf_matches_naive_augmented_system() {
    // Independent: solve [Phi P; P^t 0] [w; a] = [x; 0] with P = [c 1] directly.
    let (p, x) = data(8, 2, 21);
    let r = Rbf::fit(
        to_mat(&p).as_ref(),
        to_mat(&x).as_ref(),
        &RbfConfig {
            kernel: RbfKernel::Cubic,
            scaling: ScalingChoice::None,
            smoothing: RbfSmoothing::None,
        },
    )
    .unwrap();
    let n = 8 + 3;
    let mut a = vec![vec![0.0; n]; n];
    for i in 0..8 {
        for j in 0..8 {
            a[i][j] = dist(&p[i], &p[j]).powi(3);
        }
        for k in 0..3 {
            let z = if k < 2 { p[i][k] } else { 1.0 };
            a[i][8 + k] = z;
            a[8 + k][i] = z;
        }
    }
    let q = [0.37, 0.61];
    for j in 0..3 {
        let mut rhs: Vec<f64> = x.iter().map(|xi| xi[j]).collect();
        rhs.extend([0.0; 3]);
        let coef = solve(a.clone(), rhs);
        let want: f64 = (0..8)
            .map(|i| coef[i] * dist(&q, &p[i]).powi(3))
            .sum::<f64>()
            + coef[8] * q[0]
            + coef[9] * q[1]
            + coef[10];
        let mut y = vec![0.0; 3];
        r.predict(&q, &mut y).unwrap();
        assert!((y[j] - want).abs() < 1e-10, "{} vs {want}", y[j]);
        let mut b = vec![0.0; 8];
        r.weights(&q, &mut b).unwrap();
        let viaw: f64 = b.iter().zip(&x).map(|(bi, xi)| bi * xi[j]).sum();
        assert!((viaw - want).abs() < 1e-10);
    }
}
