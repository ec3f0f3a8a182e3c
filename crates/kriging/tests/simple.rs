//! Simple kriging (known mean, [`kriging::Krige::simple`]): hand-checked weights and variances,
//! its relation to ordinary kriging, neighbourhoods, anisotropy, leave-one-out, determinism,
//! GSTools reference numbers and the errors.

use crate::common;

use common::gstools_points::{XS, YS, Z};
use kriging::faer::Mat;
use kriging::{
    Anisotropy, Drift, Krige, KrigeModel, KrigingError, Neighbourhood, NestedVariogram,
    VariogramModel,
};

fn close(a: f64, b: f64, tol: f64, what: &str) {
    assert!(
        (a - b).abs() <= tol,
        "{what}: {a} vs {b} (diff {:e})",
        (a - b).abs()
    );
}

fn expo(nugget: f64, sill: f64, range: f64) -> NestedVariogram {
    NestedVariogram::single(VariogramModel::Exponential, nugget, sill, range).unwrap()
}

fn col(x: &[f64]) -> Mat<f64> {
    Mat::from_fn(x.len(), 1, |i, _| x[i])
}

/// Two samples in 1-D, exponential variogram without nugget: the 2 x 2 system by hand.
#[test]
fn two_points_by_hand() {
    let (x, z, m) = ([0.0, 1.0], [3.0, 1.0], 2.5);
    let (sill, range) = (2.0, 3.0);
    // C(h) = sill exp(-3 h / range) (no nugget: C(0) = sill).
    let cov = |h: f64| sill * (-3.0 * h / range).exp();
    let model = Krige::new()
        .simple(m)
        .variogram(expo(0.0, sill, range))
        .fit(col(&x).as_ref(), &z)
        .unwrap();
    for x0 in [0.4, -0.7, 2.0, 1.0] {
        let (a, b) = (sill, cov(1.0)); // [[a, b], [b, a]]
        let (c1, c2) = (cov((x0 - x[0]).abs()), cov((x0 - x[1]).abs()));
        let det = a * a - b * b;
        let w1 = (a * c1 - b * c2) / det;
        let w2 = (a * c2 - b * c1) / det;
        let value = m + w1 * (z[0] - m) + w2 * (z[1] - m);
        let variance = sill - (w1 * c1 + w2 * c2);
        let p = model.predict(&[x0]).unwrap();
        close(p.value, value, 1e-12, "value");
        close(p.variance, variance, 1e-12, "variance");
    }
    // Leave-one-out: each sample predicted from the other alone, w = C(1) / C(0).
    let loo = model.leave_one_out().unwrap();
    let w = cov(1.0) / sill;
    for (k, other) in [(0, 1), (1, 0)] {
        close(
            loo.errors[k],
            z[k] - (m + w * (z[other] - m)),
            1e-12,
            "loo error",
        );
        close(loo.variances[k], sill - w * cov(1.0), 1e-12, "loo variance");
    }
}

/// Three samples in 1-D with a nugget: the 3 x 3 system by Cramer's rule.
#[test]
fn three_points_by_hand() {
    let (x, z, m) = ([0.0, 1.0, 2.5], [0.4, 1.3, -0.2], 0.5);
    let (nugget, sill, range) = (0.2, 1.0, 2.0);
    let model = Krige::new()
        .simple(m)
        .variogram(expo(nugget, sill, range))
        .fit(col(&x).as_ref(), &z)
        .unwrap();
    // Between distinct points C(h) = sill exp(-3 h / range); C(0) = nugget + sill.
    let cov = |h: f64| sill * (-3.0 * h / range).exp();
    let k0 = nugget + sill;
    let a = [
        [k0, cov(1.0), cov(2.5)],
        [cov(1.0), k0, cov(1.5)],
        [cov(2.5), cov(1.5), k0],
    ];
    let det3 = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det3(a);
    for x0 in [1.7, 0.3, -1.0, 6.0] {
        let c: Vec<f64> = x.iter().map(|xi| cov((x0 - xi).abs())).collect();
        let w: Vec<f64> = (0..3)
            .map(|j| {
                let mut aj = a;
                for (i, row) in aj.iter_mut().enumerate() {
                    row[j] = c[i];
                }
                det3(aj) / d
            })
            .collect();
        let value = m + (0..3).map(|i| w[i] * (z[i] - m)).sum::<f64>();
        let variance = k0 - (0..3).map(|i| w[i] * c[i]).sum::<f64>();
        let p = model.predict(&[x0]).unwrap();
        close(p.value, value, 1e-12, "value");
        close(p.variance, variance, 1e-12, "variance");
        // The variance is at least the nugget away from the samples.
        assert!(p.variance >= nugget);
    }
    // At a sample: exact, variance 0 (the nugget is micro-scale variation, as in ordinary kriging).
    let p = model.predict(&[1.0]).unwrap();
    close(p.value, 1.3, 1e-12, "value at a sample");
    close(p.variance, 0.0, 1e-12, "variance at a sample");
}

/// Scattered 2-D samples with a trend-free field.
fn data2d() -> (Mat<f64>, Vec<f64>) {
    let n = 30;
    let coords = Mat::from_fn(n, 2, |i, k| {
        let step = [0.618_033_988_749_895, 0.754_877_666_246_693][k];
        100.0 * ((i as f64 + 0.5) * step).fract()
    });
    let z = (0..n)
        .map(|i| 2.0 + (coords[(i, 0)] / 17.0).sin() * (coords[(i, 1)] / 23.0).cos())
        .collect();
    (coords, z)
}

/// With the mean that ordinary kriging estimates (its generalised least-squares mean), simple
/// kriging predicts what ordinary kriging predicts, with a variance smaller by the mean's
/// uncertainty term; exact at the samples; the mean and the total sill beyond the range.
#[test]
fn with_the_ordinary_kriging_mean() {
    let (coords, z) = data2d();
    let v = expo(0.0, 0.6, 40.0);
    let aniso = Anisotropy::TwoD {
        angle: 0.5,
        ratio: 0.6,
    };
    let ok = Krige::new()
        .variogram(v.clone())
        .anisotropy(aniso)
        .fit(coords.as_ref(), &z)
        .unwrap();
    let mean = ok.drift_coefficients().unwrap()[0];
    let sk = Krige::new()
        .simple(mean)
        .variogram(v)
        .anisotropy(aniso)
        .fit(coords.as_ref(), &z)
        .unwrap();
    assert_eq!(sk.drift_coefficients(), Some(&[][..]));
    for q in [[10.0, 20.0], [55.5, 47.0], [90.0, 3.0], [-20.0, 110.0]] {
        let (a, b) = (ok.predict(&q).unwrap(), sk.predict(&q).unwrap());
        close(b.value, a.value, 1e-10, "SK(GLS mean) = OK");
        assert!(b.variance <= a.variance + 1e-12);
        assert!(b.variance > 0.0);
    }
    for i in [0, 7, 29] {
        let p = sk.predict(&[coords[(i, 0)], coords[(i, 1)]]).unwrap();
        close(p.value, z[i], 1e-10, "exact at a sample");
        close(p.variance, 0.0, 1e-10, "variance at a sample");
    }
    // Far beyond the (major) range of 40: exp(-3 * 1e4 / 40) underflows to 0.
    let far = sk.predict(&[1e4, -1e4]).unwrap();
    assert_eq!(far.value, mean);
    close(far.variance, 0.6, 1e-14, "total sill far away");
    // With a nugget the far variance is nugget + partial sill.
    let sk_nug = Krige::new()
        .simple(mean)
        .variogram(expo(0.15, 0.6, 40.0))
        .fit(coords.as_ref(), &z)
        .unwrap();
    let far = sk_nug.predict(&[1e4, -1e4]).unwrap();
    assert_eq!(far.value, mean);
    close(far.variance, 0.75, 1e-14, "total sill far away (nugget)");
}

fn refit_without(krige: &Krige, coords: &Mat<f64>, z: &[f64], k: usize) -> KrigeModel {
    let rest: Vec<usize> = (0..z.len()).filter(|&i| i != k).collect();
    let c = Mat::from_fn(rest.len(), coords.ncols(), |i, j| coords[(rest[i], j)]);
    let zr: Vec<f64> = rest.iter().map(|&i| z[i]).collect();
    krige.fit(c.as_ref(), &zr).unwrap()
}

/// Closed-form (global) and per-point (moving neighbourhood) leave-one-out against refits.
#[test]
fn leave_one_out_matches_refits() {
    let (coords, z) = data2d();
    let global = Krige::new().simple(1.8).variogram(expo(0.05, 0.6, 35.0));
    let local = global
        .clone()
        .neighbourhood(Neighbourhood::Nearest { k: 8 });
    for krige in [&global, &local] {
        let loo = krige
            .fit(coords.as_ref(), &z)
            .unwrap()
            .leave_one_out()
            .unwrap();
        for k in [0, 11, 29] {
            let p = refit_without(krige, &coords, &z, k)
                .predict(&[coords[(k, 0)], coords[(k, 1)]])
                .unwrap();
            close(loo.errors[k], z[k] - p.value, 1e-10, "loo error");
            close(loo.variances[k], p.variance, 1e-10, "loo variance");
        }
    }
}

/// Local simple kriging keeps the global mean: k = n is the global system; a few neighbours stay
/// exact at the samples and close to the global answer inside the data.
#[test]
fn neighbourhoods() {
    let (coords, z) = data2d();
    let n = z.len();
    let krige = Krige::new().simple(2.0).variogram(expo(0.0, 0.6, 30.0));
    let global = krige.fit(coords.as_ref(), &z).unwrap();
    let all = krige
        .clone()
        .neighbourhood(Neighbourhood::Nearest { k: n })
        .fit(coords.as_ref(), &z)
        .unwrap();
    let local = krige
        .clone()
        .neighbourhood(Neighbourhood::Nearest { k: 10 })
        .fit(coords.as_ref(), &z)
        .unwrap();
    for q in [[12.0, 34.0], [50.0, 50.0], [80.0, 91.0]] {
        let (a, b, c) = (
            global.predict(&q).unwrap(),
            all.predict(&q).unwrap(),
            local.predict(&q).unwrap(),
        );
        close(a.value, b.value, 1e-10, "k = n value");
        close(a.variance, b.variance, 1e-10, "k = n variance");
        close(a.value, c.value, 0.05, "local value");
        assert!(c.variance >= a.variance - 1e-12);
    }
    let p = local.predict(&[coords[(3, 0)], coords[(3, 1)]]).unwrap();
    close(p.value, z[3], 1e-12, "local exact");
    // One neighbour is enough for simple kriging; none in the radius is an error naming the query.
    let radius = krige
        .neighbourhood(Neighbourhood::Radius {
            radius: 5.0,
            max: 4,
        })
        .fit(coords.as_ref(), &z)
        .unwrap();
    let q = Mat::from_fn(2, 2, |i, k| if i == 0 { coords[(0, k)] } else { 500.0 });
    match radius.predict_many(q.as_ref()) {
        Err(KrigingError::QueryNeighbourhood { point, needed, got }) => {
            assert_eq!((point, needed, got), (1, 1, 0));
        }
        other => panic!("expected QueryNeighbourhood, got {other:?}"),
    }
}

/// Same bits for any thread count, and after a serde round trip.
#[test]
fn deterministic_and_serialisable() {
    let (coords, z) = data2d();
    let q = Mat::from_fn(300, 2, |i, k| 0.37 * i as f64 * [1.0, 0.29][k]);
    for nb in [Neighbourhood::Global, Neighbourhood::Nearest { k: 7 }] {
        let model = Krige::new()
            .simple(1.9)
            .variogram(expo(0.02, 0.6, 30.0))
            .neighbourhood(nb)
            .fit(coords.as_ref(), &z)
            .unwrap();
        let bits = |m: &KrigeModel, threads: usize| -> Vec<u64> {
            let p = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| m.predict_many(q.as_ref()).unwrap());
            p.values
                .iter()
                .chain(&p.variances)
                .map(|x| x.to_bits())
                .collect()
        };
        let one = bits(&model, 1);
        assert_eq!(one, bits(&model, 3));
        let json = serde_json::to_string(&model).unwrap();
        let back: KrigeModel = serde_json::from_str(&json).unwrap();
        assert_eq!(back.known_mean(), Some(1.9));
        assert_eq!(one, bits(&back, 2));
    }
    // The builder serialises too, and settings saved before simple kriging existed still load.
    let krige = Krige::new().simple(0.5);
    let json = serde_json::to_string(&krige).unwrap();
    assert_eq!(serde_json::from_str::<Krige>(&json).unwrap(), krige);
    let mut old: serde_json::Value = serde_json::to_value(Krige::new()).unwrap();
    old.as_object_mut().unwrap().remove("known_mean");
    assert_eq!(serde_json::from_value::<Krige>(old).unwrap(), Krige::new());
}

// Reference numbers printed by crates/kriging/scripts/simple_reference.py (GSTools 1.7.0,
// gstools.krige.Simple with exact=True, pseudo_inv=False).
const QX: [f64; 8] = [10.0, 33.3, 50.0, 71.2, 90.0, 37.5, 45.0, 400.0];
const QY: [f64; 8] = [10.0, 60.0, 40.0, 25.5, 75.0, 17.77777777777778, 5.0, -300.0];
// exponential: nugget 0.1, sill 1.0, range 60.0, mean 2.0
const EXPONENTIAL_VALUES: [f64; 8] = [
    1.38682595392887,
    0.948657631606385,
    1.3567772284209743,
    1.5706117312638204,
    1.5024963544841468,
    1.6391221448170588,
    1.8411647363304644,
    1.9999999999162623,
];
const EXPONENTIAL_VARIANCES: [f64; 8] = [
    0.7169957035339944,
    0.754330967189019,
    0.7804417404397963,
    0.8228753003617011,
    0.9721786054227816,
    0.0,
    0.6986445274334367,
    1.1,
];
// spherical: nugget 0.0, sill 0.8, range 50.0, mean 1.5
const SPHERICAL_VALUES: [f64; 8] = [
    1.1822122555486434,
    0.8497459723716508,
    1.335411178118934,
    1.476780825913362,
    1.2136320717002838,
    1.639122144817059,
    1.8593914554948223,
    1.5,
];
const SPHERICAL_VARIANCES: [f64; 8] = [
    0.3542307602991205,
    0.38535705334840886,
    0.40482555314319446,
    0.45130850116296584,
    0.6572432704401967,
    0.0,
    0.3278305203709466,
    0.8,
];

#[test]
fn simple_kriging_matches_gstools() {
    let coords = Mat::from_fn(12, 2, |i, k| [XS[i], YS[i]][k]);
    let q = Mat::from_fn(8, 2, |i, k| [QX[i], QY[i]][k]);
    let cases = [
        (
            VariogramModel::Exponential,
            0.1,
            1.0,
            60.0,
            2.0,
            &EXPONENTIAL_VALUES,
            &EXPONENTIAL_VARIANCES,
        ),
        (
            VariogramModel::Spherical,
            0.0,
            0.8,
            50.0,
            1.5,
            &SPHERICAL_VALUES,
            &SPHERICAL_VARIANCES,
        ),
    ];
    let mut worst = 0.0f64;
    for (model, nugget, sill, range, mean, values, variances) in cases {
        let v = NestedVariogram::single(model, nugget, sill, range).unwrap();
        let sk = Krige::new()
            .simple(mean)
            .variogram(v)
            .fit(coords.as_ref(), &Z)
            .unwrap();
        let p = sk.predict_many(q.as_ref()).unwrap();
        for i in 0..8 {
            close(p.values[i], values[i], 1e-9, "GSTools value");
            close(p.variances[i], variances[i], 1e-9, "GSTools variance");
            worst = worst
                .max((p.values[i] - values[i]).abs())
                .max((p.variances[i] - variances[i]).abs());
        }
    }
    eprintln!("largest difference from GSTools: {worst:e}");
}

#[test]
fn errors() {
    let x = col(&[0.0, 1.0, 2.0, 4.0]);
    let z = [1.0, 2.0, 1.5, 0.5];
    // Unbounded models are refused, naming the model, given or fitted, alone or nested.
    for model in [VariogramModel::Power, VariogramModel::Linear] {
        let v = NestedVariogram::single(model, 0.0, 1.0, 1.0).unwrap();
        let err = Krige::new()
            .simple(1.0)
            .variogram(v)
            .fit(x.as_ref(), &z)
            .unwrap_err();
        assert!(
            matches!(err, KrigingError::InvalidVariogram { model: m, .. } if m == model),
            "{err:?}"
        );
        assert!(err.to_string().contains(model.name()), "{err}");
        assert!(err.to_string().contains("bounded"), "{err}");
    }
    let nested = expo(0.0, 1.0, 2.0).with(VariogramModel::Power, 0.1, 0.0, 1.5);
    let err = Krige::new()
        .simple(1.0)
        .variogram(nested)
        .fit(x.as_ref(), &z)
        .unwrap_err();
    assert!(matches!(
        err,
        KrigingError::InvalidVariogram {
            model: VariogramModel::Power,
            ..
        }
    ));
    let err = Krige::new()
        .simple(1.0)
        .fit_model(VariogramModel::Linear)
        .fit(x.as_ref(), &z)
        .unwrap_err();
    assert!(matches!(
        err,
        KrigingError::InvalidVariogram {
            model: VariogramModel::Linear,
            ..
        }
    ));
    // Non-finite means.
    for m in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let err = Krige::new()
            .simple(m)
            .variogram(expo(0.0, 1.0, 2.0))
            .fit(x.as_ref(), &z);
        match err {
            Err(KrigingError::InvalidConfig(msg)) => assert!(msg.contains("mean"), "{msg}"),
            other => panic!("expected InvalidConfig, got {other:?}"),
        }
    }
    // Too few samples: one (and none).
    for n in [0, 1] {
        let err = Krige::new()
            .simple(1.0)
            .variogram(expo(0.0, 1.0, 2.0))
            .fit(col(&[0.0, 1.0][..n]).as_ref(), &z[..n])
            .unwrap_err();
        assert!(
            matches!(err, KrigingError::TooFewSamples { needed: 2, got, .. } if got == n),
            "{err:?}"
        );
    }
    // A drift to estimate contradicts a known mean.
    let err = Krige::new()
        .simple(1.0)
        .drift(Drift::Linear)
        .variogram(expo(0.0, 1.0, 2.0))
        .fit(x.as_ref(), &z)
        .unwrap_err();
    assert!(matches!(err, KrigingError::InvalidConfig(_)), "{err:?}");
    let err = Krige::new()
        .simple(1.0)
        .variogram(expo(0.0, 1.0, 2.0))
        .fit_with_external(x.as_ref(), &z, col(&[1.0, 2.0, 0.0, 3.0]).as_ref())
        .unwrap_err();
    assert!(matches!(err, KrigingError::InvalidConfig(_)), "{err:?}");
}
