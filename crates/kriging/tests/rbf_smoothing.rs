//! The smoothing term of the RBF baseline: `[Phi + lambda I, Q; Q^t, 0]`, fixed or chosen by
//! leave-one-out error.
#![allow(clippy::needless_range_loop)]

use crate::common;

use common::*;
use faer::Mat;
use kriging::*;

fn cfg(kernel: RbfKernel, smoothing: RbfSmoothing) -> RbfConfig {
    RbfConfig {
        kernel,
        scaling: ScalingChoice::None,
        smoothing,
    }
}

fn fit(p: &[Vec<f64>], x: &[Vec<f64>], config: &RbfConfig) -> Result<Rbf, KrigingError> {
    Rbf::fit(to_mat(p).as_ref(), to_mat(x).as_ref(), config)
}

/// Takes with `cycles` near-duplicate controls each (jitter `jitter`) and noisy field values.
fn near_duplicates(
    takes: usize,
    cycles: usize,
    jitter: f64,
    noise: f64,
) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let mut r = Rng(0x5eed_1234_abcd);
    let mut p = Vec::new();
    let mut x = Vec::new();
    for _ in 0..takes {
        let base = [r.next(), r.next()];
        for _ in 0..cycles {
            let c = vec![
                base[0] + jitter * (r.next() - 0.5),
                base[1] + jitter * (r.next() - 0.5),
            ];
            let mut v = field(&c);
            for vj in v.iter_mut() {
                *vj += noise * (r.next() - 0.5);
            }
            p.push(c);
            x.push(v);
        }
    }
    (p, x)
}

#[test]
fn fixed_zero_equals_none() {
    let (p, x) = data(12, 2, 5);
    for kernel in [
        RbfKernel::Cubic,
        RbfKernel::ThinPlate,
        RbfKernel::Gaussian { width: 0.7 },
    ] {
        let a = fit(&p, &x, &cfg(kernel, RbfSmoothing::None)).unwrap();
        let b = fit(&p, &x, &cfg(kernel, RbfSmoothing::Fixed(0.0))).unwrap();
        assert_eq!((a.smoothing(), b.smoothing()), (0.0, 0.0));
        assert!(a.smoothing_candidates().is_empty() && b.smoothing_candidates().is_empty());
        let q = [0.31, 0.77];
        let (mut ya, mut yb) = (vec![0.0; 3], vec![0.0; 3]);
        a.predict(&q, &mut ya).unwrap();
        b.predict(&q, &mut yb).unwrap();
        let (mut wa, mut wb) = (vec![0.0; 12], vec![0.0; 12]);
        a.weights(&q, &mut wa).unwrap();
        b.weights(&q, &mut wb).unwrap();
        for j in 0..3 {
            assert!((ya[j] - yb[j]).abs() < 1e-10);
        }
        for i in 0..12 {
            assert!((wa[i] - wb[i]).abs() < 1e-10);
        }
        let (ea, eb) = (a.loo_errors().unwrap(), b.loo_errors().unwrap());
        for k in 0..12 {
            for j in 0..3 {
                assert!((ea[(k, j)] - eb[(k, j)]).abs() < 1e-10);
            }
        }
    }
}

#[test]
fn fixed_lambda_loo_matches_brute_force_refit() {
    // Independent reference: [Phi + lambda I, P; P^t, 0] with P = [c 1] solved by Gaussian
    // elimination on the 11 remaining samples, evaluated at the left-out control.
    let (p, x) = data(12, 2, 77);
    let lambda = 0.05;
    let r = fit(&p, &x, &cfg(RbfKernel::Cubic, RbfSmoothing::Fixed(lambda))).unwrap();
    assert_eq!(r.smoothing(), lambda);
    let e = r.loo_errors().unwrap();
    let w = r.loo_weights().unwrap();
    for k in 0..12 {
        let (pk, xk) = (without(&p, k), without(&x, k));
        let s = pk.len();
        let n = s + 3;
        let mut a = vec![vec![0.0; n]; n];
        for i in 0..s {
            for j in 0..s {
                a[i][j] = dist(&pk[i], &pk[j]).powi(3) + if i == j { lambda } else { 0.0 };
            }
            for l in 0..3 {
                let z = if l < 2 { pk[i][l] } else { 1.0 };
                a[i][s + l] = z;
                a[s + l][i] = z;
            }
        }
        for j in 0..3 {
            let mut rhs: Vec<f64> = xk.iter().map(|xi| xi[j]).collect();
            rhs.extend([0.0; 3]);
            let coef = solve(a.clone(), rhs);
            let pred: f64 = (0..s)
                .map(|i| coef[i] * dist(&p[k], &pk[i]).powi(3))
                .sum::<f64>()
                + coef[s] * p[k][0]
                + coef[s + 1] * p[k][1]
                + coef[s + 2];
            let want = x[k][j] - pred;
            assert!(
                (e[(k, j)] - want).abs() < 1e-8,
                "{k} {j}: {} vs {want}",
                e[(k, j)]
            );
            // The leave-one-out weights give the same prediction.
            let via_w: f64 = (0..12).map(|i| w[(k, i)] * x[i][j]).sum();
            assert!((via_w - pred).abs() < 1e-8, "{k} {j}");
        }
        assert_eq!(w[(k, k)], 0.0);
        assert!(((0..12).map(|i| w[(k, i)]).sum::<f64>() - 1.0).abs() < 1e-9);
    }
    // The library's own refit agrees too.
    for k in [0, 5, 11] {
        let rk = fit(
            &without(&p, k),
            &without(&x, k),
            &cfg(RbfKernel::Cubic, RbfSmoothing::Fixed(lambda)),
        )
        .unwrap();
        let mut y = vec![0.0; 3];
        rk.predict(&p[k], &mut y).unwrap();
        for j in 0..3 {
            assert!((e[(k, j)] - (x[k][j] - y[j])).abs() < 1e-8);
        }
    }
}

#[test]
fn loo_choice_beats_none_and_a_much_larger_lambda_on_near_duplicates() {
    let (p, x) = near_duplicates(8, 4, 1e-3, 0.05);
    let none = fit(&p, &x, &cfg(RbfKernel::Cubic, RbfSmoothing::None)).unwrap();
    let chosen = fit(&p, &x, &cfg(RbfKernel::Cubic, RbfSmoothing::Loo)).unwrap();
    let cands = chosen.smoothing_candidates();
    assert_eq!(cands.len(), RBF_SMOOTHING_GRID.len());
    assert_eq!(cands[0].lambda, 0.0);
    let lambda = chosen.smoothing();
    assert!(lambda > 0.0, "{cands:?}");
    // The chosen lambda is the grid's smallest-error candidate and its error is the reported one.
    let best = cands
        .iter()
        .filter_map(|c| c.loo_rmse.map(|r| (c.lambda, r)))
        .fold(
            (f64::NAN, f64::INFINITY),
            |b, c| if c.1 < b.1 { c } else { b },
        );
    assert_eq!(best.0, lambda);
    let rmse = chosen.leave_one_out().unwrap().rmse;
    assert!((rmse - best.1).abs() <= 1e-12 * best.1.max(1.0));
    let rmse_none = none.leave_one_out().unwrap().rmse;
    assert!(rmse < rmse_none, "{rmse} vs none {rmse_none}");
    let big = 1e3 * cands.last().unwrap().lambda;
    let rmse_big = fit(&p, &x, &cfg(RbfKernel::Cubic, RbfSmoothing::Fixed(big)))
        .unwrap()
        .leave_one_out()
        .unwrap()
        .rmse;
    assert!(rmse < rmse_big, "{rmse} vs lambda {big}: {rmse_big}");
    // Deterministic: the same input gives the same bytes.
    let again = fit(&p, &x, &cfg(RbfKernel::Cubic, RbfSmoothing::Loo)).unwrap();
    assert_eq!(again.smoothing().to_bits(), lambda.to_bits());
    let (mut y1, mut y2) = (vec![0.0; 3], vec![0.0; 3]);
    chosen.predict(&[0.4, 0.6], &mut y1).unwrap();
    again.predict(&[0.4, 0.6], &mut y2).unwrap();
    assert_eq!(y1, y2);
}

#[test]
fn smoothed_weights_sum_to_one_and_reproduce_linear_functions() {
    let (p, _) = data(14, 3, 31);
    let lin = |c: &[f64]| vec![1.0 + 2.0 * c[0] - c[1] + 0.5 * c[2], c[1]];
    let x: Vec<Vec<f64>> = p.iter().map(|c| lin(c)).collect();
    for kernel in [
        RbfKernel::Linear,
        RbfKernel::Cubic,
        RbfKernel::ThinPlate,
        RbfKernel::Gaussian { width: 1.0 },
    ] {
        for smoothing in [RbfSmoothing::Fixed(0.3), RbfSmoothing::Loo] {
            let r = Rbf::fit(
                to_mat(&p).as_ref(),
                to_mat(&x).as_ref(),
                &RbfConfig {
                    kernel,
                    scaling: ScalingChoice::Standardise,
                    smoothing,
                },
            )
            .unwrap();
            for q in [
                [0.3, -0.4, 1.2],
                [0.5, 0.5, 0.5],
                p[3].clone().try_into().unwrap(),
            ] {
                let mut y = vec![0.0; 2];
                r.predict(&q, &mut y).unwrap();
                let want = lin(&q);
                let mut b = vec![0.0; 14];
                r.weights(&q, &mut b).unwrap();
                assert!(
                    (b.iter().sum::<f64>() - 1.0).abs() < 1e-9,
                    "{kernel:?} {smoothing:?}"
                );
                for j in 0..2 {
                    assert!(
                        (y[j] - want[j]).abs() < 1e-9,
                        "{kernel:?} {smoothing:?} {y:?}"
                    );
                    let via_b: f64 = b.iter().zip(&x).map(|(bi, xi)| bi * xi[j]).sum();
                    assert!((via_b - want[j]).abs() < 1e-9);
                }
            }
            assert!(r.leave_one_out().unwrap().rmse < 1e-8);
        }
    }
}

#[test]
fn smoothing_no_longer_interpolates_but_fixed_lambda_is_reported() {
    let (p, x) = data(10, 2, 3);
    let r = fit(&p, &x, &cfg(RbfKernel::Cubic, RbfSmoothing::Fixed(0.5))).unwrap();
    assert_eq!(r.smoothing(), 0.5);
    let mut y = vec![0.0; 3];
    r.predict(&p[2], &mut y).unwrap();
    let off: f64 = (0..3).map(|j| (y[j] - x[2][j]).abs()).sum();
    assert!(
        off > 1e-6,
        "a smoothing spline does not pass through the samples: {off}"
    );
}

#[test]
fn invalid_fixed_smoothing_is_an_error() {
    let (p, x) = data(8, 2, 9);
    for bad in [f64::NAN, -1.0, f64::INFINITY] {
        match fit(&p, &x, &cfg(RbfKernel::Cubic, RbfSmoothing::Fixed(bad))) {
            Err(KrigingError::InvalidConfig(msg)) => {
                assert!(msg.contains(&format!("{bad}")), "{msg}")
            }
            other => panic!("{bad}: {other:?}"),
        }
    }
}

#[test]
fn duplicate_controls_need_smoothing() {
    let (mut p, x) = data(9, 2, 13);
    p[6] = p[2].clone();
    for smoothing in [RbfSmoothing::None, RbfSmoothing::Fixed(0.0)] {
        let e = fit(&p, &x, &cfg(RbfKernel::Cubic, smoothing)).unwrap_err();
        assert_eq!(
            e,
            KrigingError::DuplicateParams {
                what: "rbf",
                first: 2,
                second: 6
            }
        );
    }
    for smoothing in [RbfSmoothing::Fixed(0.01), RbfSmoothing::Loo] {
        let r = fit(&p, &x, &cfg(RbfKernel::Cubic, smoothing)).unwrap();
        assert!(r.smoothing() > 0.0);
        let l = r.leave_one_out().unwrap();
        assert!(l.rmse.is_finite() && l.per_sample.iter().all(|e| e.is_finite()));
        let mut b = vec![0.0; 9];
        r.weights(&p[2], &mut b).unwrap();
        assert!((b.iter().sum::<f64>() - 1.0).abs() < 1e-9);
        // The two copies are interchangeable: they get the same weight.
        assert!((b[2] - b[6]).abs() < 1e-9, "{b:?}");
    }
    let r = fit(&p, &x, &cfg(RbfKernel::Cubic, RbfSmoothing::Loo)).unwrap();
    assert_eq!(r.smoothing_candidates()[0].loo_rmse, None);
}

#[test]
fn loo_weights_match_loo_errors_of_identity_values() {
    // The route other crates use: W = I - E(I), with E the leave-one-out errors of identity values.
    let (p, x) = near_duplicates(4, 3, 1e-2, 0.05);
    let s = p.len();
    let chosen = fit(&p, &x, &cfg(RbfKernel::Cubic, RbfSmoothing::Loo)).unwrap();
    let fixed = cfg(RbfKernel::Cubic, RbfSmoothing::Fixed(chosen.smoothing()));
    let identity = Mat::<f64>::identity(s, s);
    let r = Rbf::fit(to_mat(&p).as_ref(), identity.as_ref(), &fixed).unwrap();
    let e = r.loo_errors().unwrap();
    let w = chosen.loo_weights().unwrap();
    for k in 0..s {
        for j in 0..s {
            let want = if k == j { 0.0 } else { -e[(k, j)] };
            assert!((w[(k, j)] - want).abs() < 1e-9, "{k} {j}");
        }
    }
}
