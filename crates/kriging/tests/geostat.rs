//! The geostatistics front end ([`kriging::Krige`]): leave-one-out against refits, anisotropy,
//! conditioning, determinism, serde, degenerate input, and the variogram additions.

use kriging::faer::Mat;
use kriging::{
    Anisotropy, Binning, Drift, EmpiricalVariogram, FitOptions, FitWeights, Krige, KrigeModel,
    Kriging, KrigingConfig, KrigingError, MaxLag, Method, ModelChoice, Neighbourhood,
    NestedVariogram, ScalingChoice, Variogram, VariogramModel, fit_variogram,
};

/// Deterministic scattered points (Halton 2, 3) scaled to `[0, w] x [0, h]` plus `origin`.
fn halton(n: usize, w: f64, h: f64, origin: [f64; 2]) -> Vec<[f64; 2]> {
    let radical = |mut i: usize, b: usize| {
        let (mut f, mut r) = (1.0, 0.0);
        while i > 0 {
            f /= b as f64;
            r += f * (i % b) as f64;
            i /= b;
        }
        r
    };
    (1..=n)
        .map(|i| [origin[0] + w * radical(i, 2), origin[1] + h * radical(i, 3)])
        .collect()
}

fn field(p: [f64; 2]) -> f64 {
    (p[0] / 300.0).sin() + 0.5 * (p[1] / 170.0).cos() + 0.001 * p[0]
}

fn mat(pts: &[[f64; 2]]) -> Mat<f64> {
    Mat::from_fn(pts.len(), 2, |i, k| pts[i][k])
}

fn sph(nugget: f64, sill: f64, range: f64) -> NestedVariogram {
    NestedVariogram::single(VariogramModel::Spherical, nugget, sill, range).unwrap()
}

fn fit_without(
    krige: &Krige,
    pts: &[[f64; 2]],
    z: &[f64],
    ext: Option<&[f64]>,
    k: usize,
) -> KrigeModel {
    let p: Vec<[f64; 2]> = pts
        .iter()
        .enumerate()
        .filter(|(i, _)| *i != k)
        .map(|(_, p)| *p)
        .collect();
    let zz: Vec<f64> = z
        .iter()
        .enumerate()
        .filter(|(i, _)| *i != k)
        .map(|(_, v)| *v)
        .collect();
    match ext {
        None => krige.fit(mat(&p).as_ref(), &zz).unwrap(),
        Some(e) => {
            let ee: Vec<f64> = e
                .iter()
                .enumerate()
                .filter(|(i, _)| *i != k)
                .map(|(_, v)| *v)
                .collect();
            let em = Mat::from_fn(ee.len(), 1, |i, _| ee[i]);
            krige
                .fit_with_external(mat(&p).as_ref(), &zz, em.as_ref())
                .unwrap()
        }
    }
}

#[test]
fn closed_form_leave_one_out_matches_refits() {
    let pts = halton(40, 1000.0, 800.0, [0.0, 0.0]);
    let z: Vec<f64> = pts.iter().map(|p| field(*p)).collect();
    let ext: Vec<f64> = pts.iter().map(|p| (p[0] * p[1]).sqrt() / 100.0).collect();
    for (drift, with_ext) in [
        (Drift::Constant, false),
        (Drift::Linear, false),
        (Drift::Quadratic, false),
        (Drift::Constant, true),
    ] {
        let krige = Krige::new().drift(drift).variogram(sph(0.02, 0.6, 450.0));
        let model = if with_ext {
            let em = Mat::from_fn(pts.len(), 1, |i, _| ext[i]);
            krige
                .fit_with_external(mat(&pts).as_ref(), &z, em.as_ref())
                .unwrap()
        } else {
            krige.fit(mat(&pts).as_ref(), &z).unwrap()
        };
        let loo = model.leave_one_out().unwrap();
        for k in [0, 7, 22, 39] {
            let refit = fit_without(&krige, &pts, &z, with_ext.then_some(&ext[..]), k);
            let p = if with_ext {
                refit.predict_external(&pts[k], &[ext[k]]).unwrap()
            } else {
                refit.predict(&pts[k]).unwrap()
            };
            let e = z[k] - p.value;
            assert!(
                (loo.errors[k] - e).abs() < 1e-9,
                "{drift:?} {with_ext} sample {k}: {} vs {e}",
                loo.errors[k]
            );
            assert!(
                (loo.variances[k] - p.variance).abs() < 1e-9,
                "{drift:?} sample {k}: variance {} vs {}",
                loo.variances[k],
                p.variance
            );
            assert!((loo.standardised[k] - e / p.variance.sqrt()).abs() < 1e-7);
        }
        let rmse = (loo.errors.iter().map(|e| e * e).sum::<f64>() / 40.0).sqrt();
        assert!((loo.rmse - rmse).abs() < 1e-15);
        // The neighbourhood path (every sample a neighbour) gives the same numbers.
        let local = krige
            .clone()
            .neighbourhood(Neighbourhood::Nearest { k: 39 });
        let local = if with_ext {
            let em = Mat::from_fn(pts.len(), 1, |i, _| ext[i]);
            local
                .fit_with_external(mat(&pts).as_ref(), &z, em.as_ref())
                .unwrap()
        } else {
            local.fit(mat(&pts).as_ref(), &z).unwrap()
        };
        let lloo = local.leave_one_out().unwrap();
        for k in 0..40 {
            assert!((lloo.errors[k] - loo.errors[k]).abs() < 1e-9);
            assert!((lloo.variances[k] - loo.variances[k]).abs() < 1e-9);
        }
    }
}

#[test]
fn variance_is_zero_at_samples_and_grows_away_from_them() {
    let pts = halton(30, 1000.0, 1000.0, [0.0, 0.0]);
    let z: Vec<f64> = pts.iter().map(|p| field(*p)).collect();
    let model = Krige::new()
        .drift(Drift::Linear)
        .variogram(sph(0.05, 0.5, 400.0))
        .fit(mat(&pts).as_ref(), &z)
        .unwrap();
    for (k, p) in pts.iter().enumerate() {
        let q = model.predict(p).unwrap();
        assert!((q.value - z[k]).abs() < 1e-9 && q.variance < 1e-9);
    }
    // Far outside the data the variance exceeds the sill (extrapolated drift adds to it).
    let far = model.predict(&[5000.0, 5000.0]).unwrap();
    assert!(far.variance > 0.55, "{}", far.variance);
    // Just off a sample the nugget shows.
    let near = model.predict(&[pts[3][0] + 1e-3, pts[3][1]]).unwrap();
    assert!(
        near.variance >= 0.05 - 1e-6 && near.variance < 0.2,
        "{}",
        near.variance
    );
}

#[test]
fn results_do_not_depend_on_units_or_offsets() {
    // Raw map coordinates (offset 1.8e5, 3.3e5) and the same geometry at the origin: the centring
    // inside keeps the drift system conditioned, so the answers agree.
    let base = halton(60, 3000.0, 4000.0, [0.0, 0.0]);
    let far: Vec<[f64; 2]> = base.iter().map(|p| [p[0] + 1.8e5, p[1] + 3.3e5]).collect();
    let z: Vec<f64> = base.iter().map(|p| field(*p)).collect();
    for drift in [Drift::Linear, Drift::Quadratic] {
        let krige = Krige::new().drift(drift).variogram(sph(0.01, 0.5, 900.0));
        let a = krige.fit(mat(&base).as_ref(), &z).unwrap();
        let b = krige.fit(mat(&far).as_ref(), &z).unwrap();
        assert!(b.warnings().is_empty(), "{:?}", b.warnings());
        for q in [[100.0, 200.0], [1500.0, 2500.0], [2900.0, 100.0]] {
            let pa = a.predict(&q).unwrap();
            let pb = b.predict(&[q[0] + 1.8e5, q[1] + 3.3e5]).unwrap();
            assert!((pa.value - pb.value).abs() < 1e-8, "{drift:?}");
            assert!((pa.variance - pb.variance).abs() < 1e-8, "{drift:?}");
        }
    }
}

#[test]
fn regression_kriging_on_raw_map_coordinates_keeps_every_trend_direction() {
    // The issue: with raw coordinates ~1.8e5 and no scaling, the trend's Gram matrix lost a
    // direction. Now the coordinates are centred for the trend (no distance changes).
    let base = halton(50, 2000.0, 3000.0, [0.0, 0.0]);
    let far: Vec<[f64; 2]> = base.iter().map(|p| [p[0] + 1.8e5, p[1] + 3.3e5]).collect();
    let values = Mat::from_fn(50, 1, |i, _| field(base[i]) + 0.002 * base[i][1]);
    let v = Variogram::new(VariogramModel::Exponential, 0.01, 0.4, 800.0, 1.0).unwrap();
    let config = KrigingConfig {
        method: Method::Regression,
        model: ModelChoice::Given(v),
        scaling: ScalingChoice::None,
        ..KrigingConfig::default()
    };
    let a = Kriging::fit(mat(&base).as_ref(), values.as_ref(), &config).unwrap();
    let b = Kriging::fit(mat(&far).as_ref(), values.as_ref(), &config).unwrap();
    assert_eq!(a.trend_rank(), Some(3));
    assert_eq!(b.trend_rank(), Some(3));
    let (mut oa, mut ob) = ([0.0], [0.0]);
    for q in [[10.0, 20.0], [1000.0, 1500.0], [2500.0, 3500.0]] {
        a.predict(&q, &mut oa).unwrap();
        b.predict(&[q[0] + 1.8e5, q[1] + 3.3e5], &mut ob).unwrap();
        assert!((oa[0] - ob[0]).abs() < 1e-8, "{} vs {}", oa[0], ob[0]);
    }
}

#[test]
fn anisotropy_follows_the_rotation_of_the_data() {
    let pts = halton(50, 1000.0, 1000.0, [0.0, 0.0]);
    let z: Vec<f64> = pts.iter().map(|p| field(*p)).collect();
    let rot = |p: [f64; 2], deg: f64| {
        let (s, c) = deg.to_radians().sin_cos();
        [c * p[0] - s * p[1], s * p[0] + c * p[1]]
    };
    let base = Krige::new()
        .drift(Drift::Linear)
        .variogram(sph(0.01, 0.5, 600.0));
    let a = base
        .clone()
        .anisotropy(Anisotropy::TwoD {
            angle: 20.0,
            ratio: 0.4,
        })
        .fit(mat(&pts).as_ref(), &z)
        .unwrap();
    let turned: Vec<[f64; 2]> = pts.iter().map(|p| rot(*p, 35.0)).collect();
    let b = base
        .clone()
        .anisotropy(Anisotropy::TwoD {
            angle: 55.0,
            ratio: 0.4,
        })
        .fit(mat(&turned).as_ref(), &z)
        .unwrap();
    let iso = base.clone().fit(mat(&pts).as_ref(), &z).unwrap();
    let unit = base
        .clone()
        .anisotropy(Anisotropy::TwoD {
            angle: 73.0,
            ratio: 1.0,
        })
        .fit(mat(&pts).as_ref(), &z)
        .unwrap();
    let mut differs = false;
    for q in [[100.0, 700.0], [500.0, 500.0], [900.0, 50.0]] {
        let pa = a.predict(&q).unwrap();
        let pb = b.predict(&rot(q, 35.0)).unwrap();
        assert!((pa.value - pb.value).abs() < 1e-9 && (pa.variance - pb.variance).abs() < 1e-9);
        let pi = iso.predict(&q).unwrap();
        let pu = unit.predict(&q).unwrap();
        assert!((pi.value - pu.value).abs() < 1e-9 && (pi.variance - pu.variance).abs() < 1e-9);
        differs |= (pa.value - pi.value).abs() > 1e-4;
    }
    assert!(differs, "anisotropy changed nothing");
    // 3-D: a rotation about z by the azimuth, and a ratio of one on the third axis reduces to 2-D.
    let p3 = Mat::from_fn(50, 3, |i, k| if k < 2 { pts[i][k] } else { 0.0 });
    let a3 = base
        .clone()
        .anisotropy(Anisotropy::ThreeD {
            angles: [20.0, 0.0, 0.0],
            ratios: [0.4, 1.0],
        })
        .fit(p3.as_ref(), &z);
    // All z = 0: the samples are coplanar; a linear drift in 3-D is then singular.
    assert!(
        matches!(a3, Err(KrigingError::IllConditionedDrift { .. })),
        "{a3:?}"
    );
    let a3 = Krige::new()
        .variogram(sph(0.01, 0.5, 600.0))
        .anisotropy(Anisotropy::ThreeD {
            angles: [20.0, 0.0, 0.0],
            ratios: [0.4, 1.0],
        })
        .fit(p3.as_ref(), &z)
        .unwrap();
    let a2 = Krige::new()
        .variogram(sph(0.01, 0.5, 600.0))
        .anisotropy(Anisotropy::TwoD {
            angle: 20.0,
            ratio: 0.4,
        })
        .fit(mat(&pts).as_ref(), &z)
        .unwrap();
    for q in [[100.0, 700.0], [500.0, 500.0]] {
        let x = a3.predict(&[q[0], q[1], 0.0]).unwrap();
        let y = a2.predict(&q).unwrap();
        assert!((x.value - y.value).abs() < 1e-9 && (x.variance - y.variance).abs() < 1e-9);
    }
}

#[test]
fn batch_predictions_are_identical_for_any_thread_count_and_after_serde() {
    let pts = halton(300, 1000.0, 1000.0, [5e5, 5e5]);
    let z: Vec<f64> = pts.iter().map(|p| field(*p)).collect();
    let q = Mat::from_fn(1000, 2, |i, k| {
        5e5 + [(i % 40) as f64 * 25.0, (i / 40) as f64 * 40.0][k]
    });
    for nb in [Neighbourhood::Global, Neighbourhood::Nearest { k: 30 }] {
        let model = Krige::new()
            .drift(Drift::Linear)
            .fit_model(VariogramModel::Exponential)
            .neighbourhood(nb)
            .fit(mat(&pts).as_ref(), &z)
            .unwrap();
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| model.predict_many(q.as_ref()).unwrap())
        };
        let one = run(1);
        let two = run(2);
        let five = run(5);
        let bits = |p: &kriging::Predictions| {
            p.values
                .iter()
                .chain(&p.variances)
                .map(|v| v.to_bits())
                .collect::<Vec<_>>()
        };
        assert_eq!(bits(&one), bits(&two));
        assert_eq!(bits(&one), bits(&five));
        let cfg = bincode::config::standard();
        let bytes = bincode::serde::encode_to_vec(&model, cfg).unwrap();
        let (back, _): (KrigeModel, usize) =
            bincode::serde::decode_from_slice(&bytes, cfg).unwrap();
        assert_eq!(bits(&one), bits(&back.predict_many(q.as_ref()).unwrap()));
        // JSON too: with serde_json's `float_roundtrip` feature (a dev-dependency feature of this
        // crate) every f64 reads back exactly, so the reloaded model gives the same bits.
        let json = serde_json::to_string(&model).unwrap();
        let back_json: KrigeModel = serde_json::from_str(&json).unwrap();
        assert_eq!(
            bits(&one),
            bits(&back_json.predict_many(q.as_ref()).unwrap())
        );
        // ... also on a grid (the case a user found off by up to 7e-15 without the feature).
        let xs: Vec<f64> = (0..40).map(|i| 5e5 + 25.0 * i as f64).collect();
        let ys: Vec<f64> = (0..40).map(|j| 5e5 + 25.0 * j as f64).collect();
        let g = model.predict_grid(&xs, &ys).unwrap();
        let gj = back_json.predict_grid(&xs, &ys).unwrap();
        assert_eq!(bits(&g), bits(&gj));
        assert_eq!(back.variogram(), model.variogram());
        assert!(back.fit_report().is_some());
        // Without variances: the same predictions.
        let nv = model.predict_many_with(q.as_ref(), None, false).unwrap();
        assert!(nv.variances.is_empty());
        assert_eq!(
            nv.values.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            one.values.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        );
    }
}

#[test]
fn grid_layout_is_x_fastest() {
    let pts = halton(40, 100.0, 100.0, [0.0, 0.0]);
    let z: Vec<f64> = pts.iter().map(|p| field(*p)).collect();
    let model = Krige::new()
        .variogram(sph(0.0, 1.0, 60.0))
        .fit(mat(&pts).as_ref(), &z)
        .unwrap();
    let xs = [1.0, 30.0, 77.0];
    let ys = [5.0, 95.0];
    let g = model.predict_grid(&xs, &ys).unwrap();
    for (j, y) in ys.iter().enumerate() {
        for (i, x) in xs.iter().enumerate() {
            let p = model.predict(&[*x, *y]).unwrap();
            assert!((g.values[j * 3 + i] - p.value).abs() < 1e-12);
            assert!((g.variances[j * 3 + i] - p.variance).abs() < 1e-12);
        }
    }
}

#[test]
fn degenerate_input_gives_clear_errors() {
    let pts = halton(20, 10.0, 10.0, [0.0, 0.0]);
    let z: Vec<f64> = pts.iter().map(|p| field(*p)).collect();
    let k = Krige::new().variogram(sph(0.0, 1.0, 5.0));
    // NaN coordinate: row and column.
    let mut bad = mat(&pts);
    bad[(4, 1)] = f64::NAN;
    assert_eq!(
        k.fit(bad.as_ref(), &z).unwrap_err(),
        KrigingError::NonFinite {
            what: "coordinates",
            row: 4,
            col: 1
        }
    );
    let mut zb = z.clone();
    zb[9] = f64::INFINITY;
    assert!(matches!(
        k.fit(mat(&pts).as_ref(), &zb),
        Err(KrigingError::NonFinite {
            what: "values",
            row: 9,
            ..
        })
    ));
    // Duplicates without nugget name both samples; a nugget makes them legal.
    let mut dup = pts.clone();
    dup[12] = dup[3];
    assert_eq!(
        k.fit(mat(&dup).as_ref(), &z).unwrap_err(),
        KrigingError::DuplicateParams {
            what: "kriging",
            first: 3,
            second: 12
        }
    );
    let nug = Krige::new().variogram(sph(0.1, 1.0, 5.0));
    let m = nug.fit(mat(&dup).as_ref(), &z).unwrap();
    assert!(m.predict(&[5.0, 5.0]).unwrap().value.is_finite());
    // Too few samples for the drift.
    let q = Krige::new()
        .drift(Drift::Quadratic)
        .variogram(sph(0.0, 1.0, 5.0));
    assert!(matches!(
        q.fit(mat(&pts[..5]).as_ref(), &z[..5]),
        Err(KrigingError::TooFewSamples {
            needed: 7,
            got: 5,
            ..
        })
    ));
    // Collinear samples and a linear drift: an ill-conditioned drift system.
    let line: Vec<[f64; 2]> = (0..10).map(|i| [i as f64, 2.0 * i as f64]).collect();
    let lz: Vec<f64> = (0..10).map(|i| (i as f64).sin()).collect();
    let lin = Krige::new()
        .drift(Drift::Linear)
        .variogram(sph(0.0, 1.0, 5.0));
    assert!(matches!(
        lin.fit(mat(&line).as_ref(), &lz),
        Err(KrigingError::IllConditionedDrift { terms: 3, .. })
    ));
    // Radius neighbourhood with nothing in reach: the query is named.
    let r = Krige::new()
        .variogram(sph(0.0, 1.0, 5.0))
        .neighbourhood(Neighbourhood::Radius {
            radius: 2.0,
            max: 10,
        })
        .fit(mat(&pts).as_ref(), &z)
        .unwrap();
    let qs = Mat::from_fn(3, 2, |i, _| if i == 2 { 100.0 } else { 5.0 });
    assert!(matches!(
        r.predict_many(qs.as_ref()),
        Err(KrigingError::QueryNeighbourhood {
            point: 2,
            got: 0,
            ..
        })
    ));
    // Shapes.
    assert!(matches!(
        k.fit(mat(&pts).as_ref(), &z[..19]),
        Err(KrigingError::ShapeMismatch { .. })
    ));
    let good = k.fit(mat(&pts).as_ref(), &z).unwrap();
    assert!(matches!(
        good.predict(&[1.0]),
        Err(KrigingError::ShapeMismatch { .. })
    ));
    assert!(matches!(
        good.predict(&[1.0, f64::NAN]),
        Err(KrigingError::NonFinite { col: 1, .. })
    ));
    // Anisotropy for the wrong dimension, bad ratio.
    let a = Krige::new()
        .variogram(sph(0.0, 1.0, 5.0))
        .anisotropy(Anisotropy::TwoD {
            angle: 10.0,
            ratio: 0.0,
        });
    assert!(matches!(
        a.fit(mat(&pts).as_ref(), &z),
        Err(KrigingError::InvalidConfig(_))
    ));
}

#[test]
fn fitted_variograms_recover_the_model_in_the_input_units() {
    // Empirical variograms built from known models (no noise): the fit returns the parameters.
    let truths = [
        Variogram::new(VariogramModel::Matern, 0.1, 2.0, 300.0, 1.5).unwrap(),
        Variogram::new(VariogramModel::Matern, 0.0, 1.0, 150.0, 0.5).unwrap(),
        Variogram::new(VariogramModel::CardinalSine, 0.05, 1.0, 120.0, 1.0).unwrap(),
        Variogram::new(VariogramModel::Spherical, 0.2, 1.0, 900.0, 1.0).unwrap(),
    ];
    for t in truths {
        let bins = 30;
        let dh = 3000.0 / bins as f64;
        let centers: Vec<f64> = (0..bins).map(|u| dh * (u as f64 + 0.5)).collect();
        let emp = EmpiricalVariogram {
            bin_width: dh,
            gamma: centers.iter().map(|&h| t.eval(h)).collect(),
            counts: vec![100; bins],
            centers,
        };
        for w in [FitWeights::PairCounts, FitWeights::Cressie] {
            let f = fit_variogram(
                &emp,
                t.model,
                &FitOptions {
                    nugget: true,
                    weights: w,
                },
            )
            .unwrap();
            let v = f.variogram;
            assert!(
                (v.sill - t.sill).abs() < 1e-3 * t.sill,
                "{t:?} {w:?}: {v:?}"
            );
            assert!((v.range - t.range).abs() < 1e-3 * t.range, "{t:?}: {v:?}");
            assert!((v.nugget - t.nugget).abs() < 1e-3, "{t:?}: {v:?}");
            // Matérn's nu is a continuous parameter of the fit (issue 37): recovered, not exact.
            assert!(
                (v.exponent - t.exponent).abs() < 1e-6 * t.exponent,
                "{t:?}: {v:?}"
            );
            assert!(!f.bounds.any(), "{t:?}: {f:?}");
        }
    }
}

#[test]
fn maximum_lag_leaves_out_far_pairs_and_the_map_fit_reports_map_units() {
    let pts = halton(200, 4000.0, 2000.0, [1.8e5, 3.3e5]);
    let z: Vec<f64> = pts
        .iter()
        .map(|p| field([p[0] - 1.8e5, p[1] - 3.3e5]))
        .collect();
    let zm = Mat::from_fn(200, 1, |i, _| z[i]);
    let all = EmpiricalVariogram::compute_binned(
        mat(&pts).as_ref(),
        zm.as_ref(),
        &Binning {
            bins: 10,
            max_lag: MaxLag::Largest,
        },
    )
    .unwrap();
    let cut = EmpiricalVariogram::compute_binned(
        mat(&pts).as_ref(),
        zm.as_ref(),
        &Binning {
            bins: 10,
            max_lag: MaxLag::Distance(1000.0),
        },
    )
    .unwrap();
    assert_eq!(all.counts.iter().sum::<usize>(), 200 * 199 / 2);
    let within = (0..200)
        .flat_map(|i| (i + 1..200).map(move |j| (i, j)))
        .filter(|&(i, j)| {
            let (a, b) = (pts[i], pts[j]);
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt() <= 1000.0
        })
        .count();
    assert_eq!(cut.counts.iter().sum::<usize>(), within);
    assert!((cut.bin_width - 100.0).abs() < 1e-12);
    // The default map fit: ranges in metres, comparable to the field's scales (hundreds of metres),
    // not in rescaled units.
    let m = Krige::new()
        .drift(Drift::Linear)
        .fit(mat(&pts).as_ref(), &z)
        .unwrap();
    let s = &m.variogram().structures[0];
    assert!(s.range > 100.0 && s.range < 5000.0, "{:?}", m.variogram());
    let rep = m.fit_report().unwrap();
    assert_eq!(rep.candidates.len(), 3);
    let diag = (4000.0f64.powi(2) + 2000.0f64.powi(2)).sqrt();
    assert!(rep.empirical.bin_width * 15.0 <= diag / 3.0 * 1.01);
}

#[test]
fn nested_variograms_add_their_structures() {
    let v = NestedVariogram::single(VariogramModel::Spherical, 0.1, 0.5, 100.0)
        .unwrap()
        .with(VariogramModel::Exponential, 0.3, 1000.0, 1.0);
    v.validate().unwrap();
    let a = Variogram::new(VariogramModel::Spherical, 0.1, 0.5, 100.0, 1.0).unwrap();
    let b = Variogram::new(VariogramModel::Exponential, 0.0, 0.3, 1000.0, 1.0).unwrap();
    for h in [0.0, 1.0, 50.0, 100.0, 700.0, 5000.0] {
        assert!((v.eval(h) - (a.eval(h) + b.eval(h))).abs() < 1e-15);
    }
    assert!((v.total_sill() - 0.9).abs() < 1e-15);
    // Kriging with a nested variogram interpolates and gives sensible variances.
    let pts = halton(50, 1000.0, 1000.0, [0.0, 0.0]);
    let z: Vec<f64> = pts.iter().map(|p| field(*p)).collect();
    let m = Krige::new()
        .variogram(v)
        .fit(mat(&pts).as_ref(), &z)
        .unwrap();
    let p = m.predict(&pts[10]).unwrap();
    assert!((p.value - z[10]).abs() < 1e-9);
    let far = m.predict(&[1e5, 1e5]).unwrap();
    assert!(far.variance > 0.9 && far.variance < 1.0, "{}", far.variance);
    // Unbounded models work through a covariance shift.
    let lin = NestedVariogram::single(VariogramModel::Linear, 0.0, 0.001, 0.0).unwrap();
    let ml = Krige::new()
        .variogram(lin)
        .fit(mat(&pts).as_ref(), &z)
        .unwrap();
    let pl = ml.predict(&pts[3]).unwrap();
    assert!((pl.value - z[3]).abs() < 1e-8 && pl.variance.abs() < 1e-8);
    assert!(ml.predict(&[500.0, 500.0]).unwrap().variance > 0.0);
}

#[test]
fn cardinal_sine_keeps_its_old_hole_effect_names() {
    // The variant was called `HoleEffect`: files and code with that name still work.
    let old: VariogramModel = serde_json::from_str("\"HoleEffect\"").unwrap();
    assert_eq!(old, VariogramModel::CardinalSine);
    assert_eq!(
        serde_json::to_string(&VariogramModel::CardinalSine).unwrap(),
        "\"CardinalSine\""
    );
    // Binary formats store the variant index, which did not change (the seventh model).
    let cfg = bincode::config::standard();
    let bytes = bincode::serde::encode_to_vec(VariogramModel::CardinalSine, cfg).unwrap();
    assert_eq!(bytes, [6]);
    assert_eq!(VariogramModel::HoleEffect, VariogramModel::CardinalSine);
    assert_eq!(
        VariogramModel::from_name("Hole-Effect"),
        Some(VariogramModel::CardinalSine)
    );
    assert_eq!(VariogramModel::CardinalSine.name(), "cardinal-sine");
}
