//! Properties: weights sum to one, exact interpolation, sample-order invariance, determinism,
//! the projected query, variogram fitting, RBF linear reproduction, serde.

// Reference loops are index-style on purpose (they mirror the formulas).
#![allow(clippy::needless_range_loop)]

use crate::common;

use common::*;
use faer::Mat;
use kriging::*;
use proptest::prelude::*;

fn auto(method: Method, sel: Selection) -> KrigingConfig {
    KrigingConfig {
        method,
        model: ModelChoice::Auto(sel),
        bins: 8,
        ..KrigingConfig::default()
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn weights_sum_to_one_and_predict_is_weighted_sum(seed in 1u64..10_000, q0 in -0.5f64..1.5, q1 in -0.5f64..1.5) {
        let (p, x) = data(12, 2, seed);
        let v = var(VariogramModel::Exponential, 0.05);
        for method in [Method::Ordinary, Method::Regression] {
            let cfg = KrigingConfig { method, model: ModelChoice::Given(v), ..KrigingConfig::default() };
            let k = Kriging::fit(to_mat(&p).as_ref(), to_mat(&x).as_ref(), &cfg).unwrap();
            let mut b = vec![0.0; 12];
            k.weights(&[q0, q1], &mut b).unwrap();
            prop_assert!((b.iter().sum::<f64>() - 1.0).abs() < 1e-10);
            // Ordinary: the prediction is the weighted sum of the values.
            if method == Method::Ordinary {
                let mut y = vec![0.0; 3];
                k.predict(&[q0, q1], &mut y).unwrap();
                for j in 0..3 {
                    let s: f64 = b.iter().zip(&x).map(|(bi, xi)| bi * xi[j]).sum();
                    prop_assert!((s - y[j]).abs() < 1e-10);
                }
            }
        }
        let r = Rbf::fit(to_mat(&p).as_ref(), to_mat(&x).as_ref(), &RbfConfig::default()).unwrap();
        let mut b = vec![0.0; 12];
        r.weights(&[q0, q1], &mut b).unwrap();
        // Relative to the weights' own size: an ill-conditioned draw (seed 5298) has weights of
        // +-16 that summed to 1 - 3.7e-9, an absolute 1e-9 failing one run in many.
        let l1: f64 = b.iter().map(|w| w.abs()).sum();
        prop_assert!((b.iter().sum::<f64>() - 1.0).abs() < 1e-10 * l1.max(1.0) * 12.0);
    }
}

#[test]
fn fitted_models_interpolate_exactly_at_the_samples() {
    let (p, x) = data(20, 3, 42);
    for method in [Method::Ordinary, Method::Regression] {
        for sel in [Selection::BestFit, Selection::BestLoo] {
            for nugget in [false, true] {
                let cfg = KrigingConfig {
                    nugget,
                    ..auto(method, sel)
                };
                let k = Kriging::fit(to_mat(&p).as_ref(), to_mat(&x).as_ref(), &cfg).unwrap();
                assert_eq!(k.candidates().len(), 5);
                let mut b = vec![0.0; 20];
                let mut y = vec![0.0; 3];
                for (i, c) in p.iter().enumerate() {
                    k.weights(c, &mut b).unwrap();
                    for (j, w) in b.iter().enumerate() {
                        let want = if i == j { 1.0 } else { 0.0 };
                        assert!(
                            (w - want).abs() < 1e-8,
                            "{method:?} {sel:?} sample {i} weight {j} = {w}"
                        );
                    }
                    k.predict(c, &mut y).unwrap();
                    for j in 0..3 {
                        assert!((y[j] - x[i][j]).abs() < 1e-8);
                    }
                }
                if !nugget {
                    assert_eq!(k.variogram().nugget, 0.0);
                }
            }
        }
    }
}

#[test]
fn best_loo_selection_picks_the_smallest_loo_error() {
    let (p, x) = data(25, 2, 77);
    let k = Kriging::fit(
        to_mat(&p).as_ref(),
        to_mat(&x).as_ref(),
        &auto(Method::Regression, Selection::BestLoo),
    )
    .unwrap();
    let best = k
        .candidates()
        .iter()
        .filter(|c| c.error.is_none())
        .min_by(|a, b| a.loo_rmse.unwrap().total_cmp(&b.loo_rmse.unwrap()))
        .unwrap();
    assert_eq!(best.variogram.as_ref(), Some(k.variogram()));
    assert!((k.leave_one_out().unwrap().rmse - best.loo_rmse.unwrap()).abs() < 1e-12);
    let kf = Kriging::fit(
        to_mat(&p).as_ref(),
        to_mat(&x).as_ref(),
        &auto(Method::Regression, Selection::BestFit),
    )
    .unwrap();
    let bestfit = kf
        .candidates()
        .iter()
        .filter(|c| c.error.is_none())
        .min_by(|a, b| a.wsse.unwrap().total_cmp(&b.wsse.unwrap()))
        .unwrap();
    assert_eq!(bestfit.variogram.as_ref(), Some(kf.variogram()));
}

#[test]
fn invariant_to_sample_order() {
    let (p, x) = data(15, 2, 5);
    let perm: Vec<usize> = (0..15).map(|i| (i * 7 + 3) % 15).collect();
    let pp: Vec<Vec<f64>> = perm.iter().map(|&i| p[i].clone()).collect();
    let xp: Vec<Vec<f64>> = perm.iter().map(|&i| x[i].clone()).collect();
    for cfg in [
        auto(Method::Regression, Selection::BestLoo),
        auto(Method::Ordinary, Selection::BestFit),
    ] {
        let a = Kriging::fit(to_mat(&p).as_ref(), to_mat(&x).as_ref(), &cfg).unwrap();
        let b = Kriging::fit(to_mat(&pp).as_ref(), to_mat(&xp).as_ref(), &cfg).unwrap();
        assert_eq!(a.variogram().model, b.variogram().model);
        let (va, vb) = (a.variogram(), b.variogram());
        assert!(
            (va.sill - vb.sill).abs() < 1e-8 * va.sill
                && (va.range - vb.range).abs() < 1e-8 * (1.0 + va.range)
        );
        let q = [0.33, 0.71];
        let (mut wa, mut wb) = (vec![0.0; 15], vec![0.0; 15]);
        a.weights(&q, &mut wa).unwrap();
        b.weights(&q, &mut wb).unwrap();
        for (k, &i) in perm.iter().enumerate() {
            assert!((wb[k] - wa[i]).abs() < 1e-8);
        }
        let (mut ya, mut yb) = (vec![0.0; 3], vec![0.0; 3]);
        a.predict(&q, &mut ya).unwrap();
        b.predict(&q, &mut yb).unwrap();
        for j in 0..3 {
            assert!((ya[j] - yb[j]).abs() < 1e-8);
        }
    }
}

#[test]
fn bit_identical_across_runs_and_thread_counts() {
    let (p, x3) = data(40, 3, 9);
    // D = 300 > 128 exercises the column-blocked parallel products.
    let x: Vec<Vec<f64>> = x3
        .iter()
        .map(|r| {
            (0..300)
                .map(|j| r[j % 3] * (1.0 + j as f64 * 0.01))
                .collect()
        })
        .collect();
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let k = Kriging::fit(
                    to_mat(&p).as_ref(),
                    to_mat(&x).as_ref(),
                    &auto(Method::Regression, Selection::BestLoo),
                )
                .unwrap();
                let mut b = vec![0.0; 40];
                k.weights(&[0.2, 0.4, 0.6], &mut b).unwrap();
                let l = k.leave_one_out().unwrap();
                let mut y = vec![0.0; 300];
                k.predict(&[0.2, 0.4, 0.6], &mut y).unwrap();
                let r = Rbf::fit(
                    to_mat(&p).as_ref(),
                    to_mat(&x).as_ref(),
                    &RbfConfig::default(),
                )
                .unwrap();
                let mut yr = vec![0.0; 300];
                r.predict(&[0.2, 0.4, 0.6], &mut yr).unwrap();
                b.extend(y);
                b.extend(yr);
                (*k.variogram(), b, l.rmse)
            })
    };
    let one = run(1);
    let two = run(2);
    let again = run(2);
    assert_eq!(one.0, two.0);
    assert_eq!(
        one.1.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
        two.1.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
    );
    assert_eq!(one.2.to_bits(), two.2.to_bits());
    assert_eq!(two.1, again.1);
}

#[test]
fn projected_query_equals_l_times_weights() {
    let (p, x) = data(30, 3, 13);
    let k = Kriging::fit(
        to_mat(&p).as_ref(),
        to_mat(&x).as_ref(),
        &auto(Method::Regression, Selection::BestLoo),
    )
    .unwrap();
    let mut r = Rng(99);
    let l = Mat::from_fn(5, 30, |_, _| r.next() - 0.5);
    let c = k.augmented_params();
    // The motion model's L = [U^t ; C].
    let lc = Mat::from_fn(
        5 + 4,
        30,
        |i, j| if i < 5 { l[(i, j)] } else { c[(i - 5, j)] },
    );
    let pq = ProjectedQuery::new(&k, lc.as_ref()).unwrap();
    assert_eq!(pq.matrix().len(), 9 * 31);
    assert_eq!(pq.scaled_params().len(), 30 * 3);
    let mut g = vec![0.0; 31];
    let mut out = vec![0.0; 9];
    let mut b = vec![0.0; 30];
    for q in [
        [0.1, 0.5, 0.9],
        [0.7, 0.2, 0.3],
        p[4].clone().try_into().unwrap(),
    ] {
        pq.query(&q, &mut g, &mut out).unwrap();
        k.weights(&q, &mut b).unwrap();
        for i in 0..9 {
            let want: f64 = (0..30).map(|j| lc[(i, j)] * b[j]).sum();
            assert!((out[i] - want).abs() < 1e-10, "{i}: {} vs {want}", out[i]);
        }
        // The last row of C b is sum b = 1.
        assert!((out[8] - 1.0).abs() < 1e-10);
    }
    assert!(pq.query(&[0.1, 0.5], &mut g, &mut out).is_err());
    assert!(pq.query(&[0.1, 0.5, 0.3], &mut g[..30], &mut out).is_err());
    assert!(ProjectedQuery::new(&k, Mat::<f64>::zeros(2, 29).as_ref()).is_err());
}

#[test]
fn fit_recovers_known_variogram_parameters() {
    let truth = [
        Variogram::new(VariogramModel::Spherical, 0.2, 1.5, 2.0, 1.0).unwrap(),
        Variogram::new(VariogramModel::Exponential, 0.1, 2.0, 1.5, 1.0).unwrap(),
        Variogram::new(VariogramModel::Gaussian, 0.3, 1.0, 1.2, 1.0).unwrap(),
        Variogram::new(VariogramModel::Power, 0.05, 0.7, 0.0, 1.5).unwrap(),
        Variogram::new(VariogramModel::Linear, 0.4, 0.9, 0.0, 1.0).unwrap(),
    ];
    for t in truth {
        let centers: Vec<f64> = (0..20).map(|u| 0.2 * (u as f64 + 0.5)).collect();
        let emp = EmpiricalVariogram {
            bin_width: 0.2,
            gamma: centers.iter().map(|&h| t.eval(h)).collect(),
            counts: (0..20).map(|u| 10 + u).collect(),
            centers,
        };
        let f = fit_variogram(&emp, t.model, &FitOptions::default()).unwrap();
        let v = f.variogram;
        assert!(f.wsse < 1e-12, "{t:?} -> {v:?} wsse {}", f.wsse);
        assert!(
            (v.nugget - t.nugget).abs() < 1e-5 && (v.sill - t.sill).abs() < 1e-5,
            "{t:?} -> {v:?}"
        );
        assert!(
            (v.range - t.range).abs() < 1e-4 && (v.exponent - t.exponent).abs() < 1e-4,
            "{t:?} -> {v:?}"
        );
        let fc = fit_variogram(
            &emp,
            t.model,
            &FitOptions {
                nugget: true,
                weights: FitWeights::Cressie,
            },
        )
        .unwrap();
        assert!((fc.variogram.sill - t.sill).abs() < 1e-4);
        let f0 = fit_variogram(
            &emp,
            t.model,
            &FitOptions {
                nugget: false,
                weights: FitWeights::PairCounts,
            },
        )
        .unwrap();
        assert_eq!(f0.variogram.nugget, 0.0);
    }
}

#[test]
fn variogram_eval_conventions() {
    let v = Variogram::new(VariogramModel::Spherical, 0.5, 2.0, 3.0, 7.0).unwrap();
    assert_eq!(v.eval(0.0), 0.0);
    assert_eq!(v.eval(10.0), 2.5);
    assert!((v.eval(1.5) - (0.5 + 2.0 * (0.75 - 0.0625))).abs() < 1e-15);
    assert_eq!(v.between_samples(0.0), 0.5);
    assert_eq!(v.exponent, 1.0);
    let l = Variogram::new(VariogramModel::Linear, 0.0, 2.0, 5.0, 1.0).unwrap();
    assert_eq!(l.range, 0.0);
    assert_eq!(l.eval(3.0), 6.0);
    for m in VariogramModel::ALL {
        assert_eq!(VariogramModel::from_name(m.name()), Some(m));
    }
}

#[test]
fn rbf_reproduces_linear_functions_and_interpolates() {
    let (p, _) = data(14, 3, 31);
    let x: Vec<Vec<f64>> = p
        .iter()
        .map(|c| vec![1.0 + 2.0 * c[0] - c[1] + 0.5 * c[2], c[1]])
        .collect();
    for kernel in [
        RbfKernel::Linear,
        RbfKernel::Cubic,
        RbfKernel::ThinPlate,
        RbfKernel::Gaussian { width: 1.0 },
    ] {
        let r = Rbf::fit(
            to_mat(&p).as_ref(),
            to_mat(&x).as_ref(),
            &RbfConfig {
                kernel,
                scaling: ScalingChoice::Standardise,
                smoothing: RbfSmoothing::None,
            },
        )
        .unwrap();
        let mut y = vec![0.0; 2];
        let q = [0.3, -0.4, 1.2];
        r.predict(&q, &mut y).unwrap();
        assert!(
            (y[0] - (1.0 + 0.6 + 0.4 + 0.6)).abs() < 1e-9,
            "{kernel:?} {y:?}"
        );
        assert!((y[1] + 0.4).abs() < 1e-9);
        let mut b = vec![0.0; 14];
        r.weights(&p[6], &mut b).unwrap();
        for (j, w) in b.iter().enumerate() {
            assert!(
                (w - if j == 6 { 1.0 } else { 0.0 }).abs() < 1e-8,
                "{kernel:?}"
            );
        }
        assert!(r.leave_one_out().unwrap().rmse < 1e-8);
    }
    assert!(
        Rbf::fit(
            to_mat(&p).as_ref(),
            to_mat(&x).as_ref(),
            &RbfConfig {
                kernel: RbfKernel::Gaussian { width: 0.0 },
                scaling: ScalingChoice::None,
                smoothing: RbfSmoothing::None,
            }
        )
        .is_err()
    );
}

#[test]
fn scaling_constructors() {
    let p = Mat::from_fn(4, 3, |i, k| [i as f64, 2.0 * i as f64 + 1.0, 5.0][k]);
    let s = ParamScaling::standardise(p.as_ref()).unwrap();
    assert_eq!(s.dropped(), vec![2]);
    assert!((s.offset[0] - 1.5).abs() < 1e-15 && (s.scale[0] - 1.0 / 1.25f64.sqrt()).abs() < 1e-15);
    let mut out = [0.0; 3];
    s.apply(&[1.5, 4.0, 9.0], &mut out);
    assert_eq!(out, [0.0, 0.0, 0.0]);
    let g = ParamScaling::given(vec![1.0, 0.0], vec![2.0, 0.5]).unwrap();
    let mut o2 = [0.0; 2];
    g.apply(&[2.0, 4.0], &mut o2);
    assert_eq!(o2, [2.0, 2.0]);
    assert_eq!(ParamScaling::none(2).scale, vec![1.0, 1.0]);
    let cfg = KrigingConfig {
        scaling: ScalingChoice::Given(g),
        ..KrigingConfig::default()
    };
    assert!(matches!(
        Kriging::fit(p.as_ref(), p.as_ref(), &cfg),
        Err(KrigingError::ShapeMismatch { .. })
    ));
}

#[test]
fn serde_round_trips() {
    let v = Variogram::new(VariogramModel::Power, 0.1, 0.3, 0.0, 1.3).unwrap();
    let s = serde_json::to_string(&v).unwrap();
    assert_eq!(serde_json::from_str::<Variogram>(&s).unwrap(), v);
    let (p, x) = data(10, 2, 3);
    let k = Kriging::fit(
        to_mat(&p).as_ref(),
        to_mat(&x).as_ref(),
        &KrigingConfig::default(),
    )
    .unwrap();
    let pq = ProjectedQuery::new(&k, Mat::<f64>::identity(10, 10).as_ref()).unwrap();
    let back: ProjectedQuery = serde_json::from_str(&serde_json::to_string(&pq).unwrap()).unwrap();
    // serde_json's default float parsing may be off by one ulp: compare to 1e-15 relative.
    let close = |a: &[f64], b: &[f64]| {
        a.len() == b.len()
            && a.iter()
                .zip(b)
                .all(|(x, y)| (x - y).abs() <= 1e-15 * x.abs().max(1.0))
    };
    assert!(close(back.matrix(), pq.matrix()) && close(back.scaled_params(), pq.scaled_params()));
    assert_eq!((back.rows(), back.n_samples()), (pq.rows(), pq.n_samples()));
    assert_eq!(back.variogram().model, pq.variogram().model);
    let cfg: KrigingConfig =
        serde_json::from_str(&serde_json::to_string(&KrigingConfig::default()).unwrap()).unwrap();
    assert_eq!(cfg, KrigingConfig::default());
}
