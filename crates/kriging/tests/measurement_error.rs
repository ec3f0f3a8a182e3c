//! Measurement error (non-exact kriging, [`kriging::Krige::measurement_error`]): GSTools reference
//! numbers (ordinary and simple kriging, a duplicated site, a pure nugget), smoothing at the
//! samples, leave-one-out against explicit refits, neighbourhoods, serde, and the option off.

use crate::common;

use common::gstools_points::{XS, YS, Z};
use kriging::faer::Mat;
use kriging::{
    Drift, Krige, KrigeModel, KrigingError, Neighbourhood, NestedVariogram, VariogramModel,
};

fn close(a: f64, b: f64, tol: f64, what: &str) {
    assert!(
        (a - b).abs() <= tol,
        "{what}: {a} vs {b} (diff {:e})",
        (a - b).abs()
    );
}

fn col(x: &[f64]) -> Mat<f64> {
    Mat::from_fn(x.len(), 1, |i, _| x[i])
}

// Reference numbers: crates/kriging/scripts/measurement_error_reference.py (GSTools 1.7.0,
// krige.Ordinary / krige.Simple with exact=False, cond_err="nugget", pseudo_inv=False).
const QX: [f64; 8] = [10.0, 33.3, 50.0, 71.2, 50.0, 37.5, 18.75, 400.0];
const QY: [f64; 8] = [
    10.0,
    60.0,
    40.0,
    25.5,
    26.666666666666664,
    17.77777777777778,
    11.851851851851851,
    -300.0,
];
// exponential: nugget 0.2, sill 1.0, range 60.0; simple: mean 0.5
const EXPONENTIAL_OK_VALUES: [f64; 8] = [
    1.0440886477261964,
    0.7194916790811334,
    1.1925771693611724,
    1.3626504860743422,
    1.5587609338249155,
    1.57497172104128,
    1.1704737575148423,
    0.9735390162443283,
];
const EXPONENTIAL_OK_VARIANCES: [f64; 8] = [
    0.874857906562562,
    0.8935842444666078,
    0.9049498023775716,
    0.9486925618463276,
    0.3575817693371326,
    0.3525477411152712,
    0.36264764142548644,
    1.424353214595007,
];
const EXPONENTIAL_SK_VALUES: [f64; 8] = [
    0.8723622566546706,
    0.594649021576605,
    1.1105024239926253,
    1.2607653959635572,
    1.5388724714283908,
    1.5571680665742675,
    1.1276601072797638,
    0.500000000255795,
];
const EXPONENTIAL_SK_VARIANCES: [f64; 8] = [
    0.8453529589381671,
    0.8779906307546894,
    0.8982101134815796,
    0.9383067122341869,
    0.3571860172818605,
    0.35223060983871535,
    0.36081370078161534,
    1.2,
];
// spherical: nugget 0.05, sill 0.8, range 50.0; simple: mean 1.5
const SPHERICAL_OK_VALUES: [f64; 8] = [
    1.0176859904320608,
    0.7208983074119567,
    1.2377079684708931,
    1.4255057585691266,
    1.604481259166665,
    1.6206219910038504,
    1.17812985639173,
    0.97447389530674,
];
const SPHERICAL_OK_VARIANCES: [f64; 8] = [
    0.44841188707168067,
    0.4709938705517847,
    0.4815074271823208,
    0.5222426843632479,
    0.09544930892155301,
    0.09393759336883223,
    0.09625913012431941,
    0.9954899252020604,
];
const SPHERICAL_SK_VALUES: [f64; 8] = [
    1.1969303796501283,
    0.8578753125082283,
    1.3377521064284954,
    1.4834850200405967,
    1.6152653998160036,
    1.6245753177329323,
    1.1986313229277512,
    1.5,
];
const SPHERICAL_SK_VARIANCES: [f64; 8] = [
    0.4314866222283072,
    0.4611097128518033,
    0.47623479318203743,
    0.5204718020876953,
    0.09538804350089447,
    0.09392936014825892,
    0.09603771147851392,
    0.8500000000000001,
];
// duplicated site: exponential nugget 0.5, sill 1, range 6; simple mean 3
const DUP_OK_VALUES: [f64; 3] = [3.4901859507077875, 3.1943967154127937, 3.5159069811721917];
const DUP_OK_VARIANCES: [f64; 3] = [0.7152913127957736, 0.8631859304432705, 1.490725050677617];
const DUP_SK_VALUES: [f64; 3] = [3.3986566181646465, 3.060347961631652, 3.2351303661273723];
const DUP_SK_VARIANCES: [f64; 3] = [0.698633255014411, 0.8274562332969666, 1.3339685206130916];
// pure nugget 0.3 (GSTools: var = 0); simple mean 0.5
const PURE_OK_VALUES: [f64; 8] = [
    1.0671067908832794,
    1.0671067908832794,
    1.0671067908832794,
    1.0671067908832794,
    1.0671067908832794,
    1.0671067908832794,
    1.0671067908832794,
    1.0671067908832794,
];
const PURE_OK_VARIANCES: [f64; 8] = [
    0.3250000000000001,
    0.3250000000000001,
    0.3250000000000001,
    0.3250000000000001,
    0.3250000000000001,
    0.3250000000000001,
    0.3250000000000001,
    0.3250000000000001,
];
const PURE_SK_VALUES: [f64; 8] = [0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5];
const PURE_SK_VARIANCES: [f64; 8] = [0.3, 0.3, 0.3, 0.3, 0.3, 0.3, 0.3, 0.3];

fn sample_coords() -> Mat<f64> {
    Mat::from_fn(12, 2, |i, k| [XS[i], YS[i]][k])
}

fn queries() -> Mat<f64> {
    Mat::from_fn(8, 2, |i, k| [QX[i], QY[i]][k])
}

/// Compares a model's predictions with reference literals; returns the largest difference.
fn compare(model: &KrigeModel, q: &Mat<f64>, values: &[f64], variances: &[f64], what: &str) -> f64 {
    let p = model.predict_many(q.as_ref()).unwrap();
    let mut worst = 0.0f64;
    for i in 0..values.len() {
        close(p.values[i], values[i], 1e-9, &format!("{what} value {i}"));
        close(
            p.variances[i],
            variances[i],
            1e-9,
            &format!("{what} variance {i}"),
        );
        worst = worst
            .max((p.values[i] - values[i]).abs())
            .max((p.variances[i] - variances[i]).abs());
    }
    worst
}

type Case = (
    VariogramModel,
    f64,
    f64,
    f64,
    f64,
    &'static [f64; 8],
    &'static [f64; 8],
    &'static [f64; 8],
    &'static [f64; 8],
);

const CASES: [Case; 2] = [
    (
        VariogramModel::Exponential,
        0.2,
        1.0,
        60.0,
        0.5,
        &EXPONENTIAL_OK_VALUES,
        &EXPONENTIAL_OK_VARIANCES,
        &EXPONENTIAL_SK_VALUES,
        &EXPONENTIAL_SK_VARIANCES,
    ),
    (
        VariogramModel::Spherical,
        0.05,
        0.8,
        50.0,
        1.5,
        &SPHERICAL_OK_VALUES,
        &SPHERICAL_OK_VARIANCES,
        &SPHERICAL_SK_VALUES,
        &SPHERICAL_SK_VARIANCES,
    ),
];

#[test]
fn ordinary_matches_gstools() {
    let (coords, q) = (sample_coords(), queries());
    let mut worst = 0.0f64;
    for (model, nugget, sill, range, _, ok_val, ok_var, _, _) in CASES {
        let v = NestedVariogram::single(model, nugget, sill, range).unwrap();
        let ok = Krige::new()
            .measurement_error(true)
            .variogram(v)
            .fit(coords.as_ref(), &Z)
            .unwrap();
        assert!(ok.measurement_error());
        worst = worst.max(compare(&ok, &q, ok_val, ok_var, model.name()));
    }
    eprintln!("ordinary kriging, measurement error: max |diff| vs GSTools {worst:e}");
}

#[test]
fn simple_matches_gstools() {
    let (coords, q) = (sample_coords(), queries());
    let mut worst = 0.0f64;
    for (model, nugget, sill, range, mean, _, _, sk_val, sk_var) in CASES {
        let v = NestedVariogram::single(model, nugget, sill, range).unwrap();
        let sk = Krige::new()
            .simple(mean)
            .measurement_error(true)
            .variogram(v)
            .fit(coords.as_ref(), &Z)
            .unwrap();
        worst = worst.max(compare(&sk, &q, sk_val, sk_var, model.name()));
    }
    eprintln!("simple kriging, measurement error: max |diff| vs GSTools {worst:e}");
}

/// At the samples (queries 4, 5 and 6 are samples 0, 5 and 11) the predictions are smoothed and
/// the variance is above the nugget; the exact form interpolates there with variance 0.
#[test]
fn smoothed_at_the_samples() {
    let (coords, q) = (sample_coords(), queries());
    for (model, nugget, sill, range, ..) in CASES {
        let v = NestedVariogram::single(model, nugget, sill, range).unwrap();
        let me = Krige::new()
            .measurement_error(true)
            .variogram(v.clone())
            .fit(coords.as_ref(), &Z)
            .unwrap();
        let exact = Krige::new().variogram(v).fit(coords.as_ref(), &Z).unwrap();
        let (pm, pe) = (
            me.predict_many(q.as_ref()).unwrap(),
            exact.predict_many(q.as_ref()).unwrap(),
        );
        for (qi, si) in [(4, 0), (5, 5), (6, 11)] {
            close(pe.values[qi], Z[si], 1e-12, "exact value at a sample");
            close(pe.variances[qi], 0.0, 1e-12, "exact variance at a sample");
            assert!(
                (pm.values[qi] - Z[si]).abs() > 1e-3,
                "smoothed at sample {si}"
            );
            assert!(
                pm.variances[qi] > nugget,
                "variance at sample {si} above the nugget"
            );
        }
        // Away from the samples only the right-hand side at h = 0 differs: the same numbers.
        for qi in [0, 1, 2, 3, 7] {
            close(pm.values[qi], pe.values[qi], 1e-12, "value off the samples");
            close(
                pm.variances[qi],
                pe.variances[qi],
                1e-12,
                "variance off the samples",
            );
        }
    }
}

/// A site measured twice (2 and 5): accepted with a nugget, the prediction there lies between the
/// two and its variance is positive, as in GSTools.
#[test]
fn duplicated_site_matches_gstools() {
    let coords = col(&[0.0, 0.0, 3.0, 7.0]);
    let z = [2.0, 5.0, 3.0, 4.0];
    let q = col(&[0.0, 3.0, 5.0]);
    let v = NestedVariogram::single(VariogramModel::Exponential, 0.5, 1.0, 6.0).unwrap();
    let mut worst = 0.0f64;
    for (krige, values, variances) in [
        (Krige::new(), &DUP_OK_VALUES, &DUP_OK_VARIANCES),
        (Krige::new().simple(3.0), &DUP_SK_VALUES, &DUP_SK_VARIANCES),
    ] {
        let model = krige
            .measurement_error(true)
            .variogram(v.clone())
            .fit(coords.as_ref(), &z)
            .unwrap();
        worst = worst.max(compare(&model, &q, values, variances, "duplicated site"));
        let at = model.predict(&[0.0]).unwrap();
        assert!(at.value > 2.0 && at.value < 5.0, "{}", at.value);
        assert!(at.variance > 0.5, "{}", at.variance);
    }
    eprintln!("duplicated site: max |diff| vs GSTools {worst:e}");
    // Without a nugget coinciding samples stay an error, with or without the option.
    let v0 = NestedVariogram::single(VariogramModel::Exponential, 0.0, 1.0, 6.0).unwrap();
    let err = Krige::new()
        .measurement_error(true)
        .variogram(v0)
        .fit(coords.as_ref(), &z)
        .unwrap_err();
    assert!(matches!(
        err,
        KrigingError::DuplicateParams {
            first: 0,
            second: 1,
            ..
        }
    ));
}

/// A pure nugget: no structure, only noise. Ordinary kriging predicts the sample mean everywhere
/// (variance `c0 (1 + 1/n)`), simple kriging the known mean (variance `c0`), as in GSTools (which
/// writes the pure nugget as a zero-variance model). Without the option it is refused.
#[test]
fn pure_nugget_matches_gstools() {
    let (coords, q) = (sample_coords(), queries());
    let noise = NestedVariogram {
        nugget: 0.3,
        structures: Vec::new(),
    };
    let ok = Krige::new()
        .measurement_error(true)
        .variogram(noise.clone())
        .fit(coords.as_ref(), &Z)
        .unwrap();
    let sk = Krige::new()
        .simple(0.5)
        .measurement_error(true)
        .variogram(noise.clone())
        .fit(coords.as_ref(), &Z)
        .unwrap();
    let mut worst = compare(
        &ok,
        &q,
        &PURE_OK_VALUES,
        &PURE_OK_VARIANCES,
        "pure nugget OK",
    );
    worst = worst.max(compare(
        &sk,
        &q,
        &PURE_SK_VALUES,
        &PURE_SK_VARIANCES,
        "pure nugget SK",
    ));
    eprintln!("pure nugget: max |diff| vs GSTools {worst:e}");
    let mean = Z.iter().sum::<f64>() / 12.0;
    close(
        ok.predict(&[1e4, -3.0]).unwrap().value,
        mean,
        1e-12,
        "OK mean",
    );
    close(
        ok.predict(&[XS[3], YS[3]]).unwrap().variance,
        0.3 * (1.0 + 1.0 / 12.0),
        1e-12,
        "OK variance",
    );
    // A linear drift: the least-squares plane everywhere (reproduced on a plane's samples).
    let plane: Vec<f64> = (0..12).map(|i| 1.0 + 0.02 * XS[i] - 0.01 * YS[i]).collect();
    let uk = Krige::new()
        .drift(Drift::Linear)
        .measurement_error(true)
        .variogram(noise.clone())
        .fit(coords.as_ref(), &plane)
        .unwrap();
    close(
        uk.predict(&[300.0, 40.0]).unwrap().value,
        1.0 + 6.0 - 0.4,
        1e-9,
        "pure nugget drift",
    );
    // Refused without the option, and with a zero nugget.
    assert!(
        Krige::new()
            .variogram(noise)
            .fit(coords.as_ref(), &Z)
            .is_err()
    );
    let zero = NestedVariogram {
        nugget: 0.0,
        structures: Vec::new(),
    };
    assert!(matches!(
        Krige::new()
            .measurement_error(true)
            .variogram(zero)
            .fit(coords.as_ref(), &Z),
        Err(KrigingError::InvalidConfig(_))
    ));
}

/// Leave-one-out (closed form, global) equals refitting without each sample and predicting it
/// with the measurement-error model: ordinary, universal and simple kriging, with a duplicated
/// site among the samples; a moving neighbourhood covering every sample gives the same numbers.
#[test]
fn leave_one_out_matches_refits() {
    let mut xy: Vec<[f64; 2]> = (0..12).map(|i| [XS[i], YS[i]]).collect();
    let mut z = Z.to_vec();
    xy.push([XS[4], YS[4]]); // sample 4 measured twice
    z.push(Z[4] + 0.7);
    let n = xy.len();
    let coords = Mat::from_fn(n, 2, |i, k| xy[i][k]);
    let v = NestedVariogram::single(VariogramModel::Exponential, 0.2, 1.0, 60.0).unwrap();
    for krige in [
        Krige::new(),
        Krige::new().drift(Drift::Linear),
        Krige::new().simple(0.5),
    ] {
        let krige = krige.measurement_error(true).variogram(v.clone());
        let loo = krige
            .fit(coords.as_ref(), &z)
            .unwrap()
            .leave_one_out()
            .unwrap();
        let local = krige
            .clone()
            .neighbourhood(Neighbourhood::Nearest { k: n - 1 })
            .fit(coords.as_ref(), &z)
            .unwrap()
            .leave_one_out()
            .unwrap();
        for k in 0..n {
            let rest: Vec<usize> = (0..n).filter(|&i| i != k).collect();
            let without = Mat::from_fn(n - 1, 2, |i, c| xy[rest[i]][c]);
            let z_without: Vec<f64> = rest.iter().map(|&i| z[i]).collect();
            let p = krige
                .fit(without.as_ref(), &z_without)
                .unwrap()
                .predict(&xy[k])
                .unwrap();
            close(loo.errors[k], z[k] - p.value, 1e-10, "loo error");
            close(loo.variances[k], p.variance, 1e-10, "loo variance");
            close(local.errors[k], loo.errors[k], 1e-10, "moving loo error");
            close(
                local.variances[k],
                loo.variances[k],
                1e-10,
                "moving loo variance",
            );
        }
    }
}

/// A moving neighbourhood holding every sample is the global system, also at the samples.
#[test]
fn neighbourhood_all_equals_global() {
    let (coords, q) = (sample_coords(), queries());
    let v = NestedVariogram::single(VariogramModel::Spherical, 0.05, 0.8, 50.0).unwrap();
    let krige = Krige::new().measurement_error(true).variogram(v);
    let g = krige.fit(coords.as_ref(), &Z).unwrap();
    let l = krige
        .neighbourhood(Neighbourhood::Nearest { k: 12 })
        .fit(coords.as_ref(), &Z)
        .unwrap();
    let (a, b) = (
        g.predict_many(q.as_ref()).unwrap(),
        l.predict_many(q.as_ref()).unwrap(),
    );
    for i in 0..8 {
        close(a.values[i], b.values[i], 1e-10, "value");
        close(a.variances[i], b.variances[i], 1e-10, "variance");
    }
}

/// The option is saved with the model; a model saved before it existed reads back as exact.
#[test]
fn serde_keeps_the_option() {
    let (coords, q) = (sample_coords(), queries());
    let v = NestedVariogram::single(VariogramModel::Exponential, 0.2, 1.0, 60.0).unwrap();
    let me = Krige::new()
        .measurement_error(true)
        .variogram(v)
        .fit(coords.as_ref(), &Z)
        .unwrap();
    let json = serde_json::to_string(&me).unwrap();
    let back: KrigeModel = serde_json::from_str(&json).unwrap();
    assert!(back.measurement_error());
    assert_eq!(
        back.predict_many(q.as_ref()).unwrap(),
        me.predict_many(q.as_ref()).unwrap()
    );
    let mut value: serde_json::Value = serde_json::from_str(&json).unwrap();
    value
        .as_object_mut()
        .unwrap()
        .remove("measurement_error")
        .unwrap();
    let old: KrigeModel = serde_json::from_value(value).unwrap();
    assert!(!old.measurement_error());
    let at = old.predict(&[XS[0], YS[0]]).unwrap();
    close(at.value, Z[0], 1e-12, "old model is exact");
    // The builder too: settings saved before the option read back without it.
    let mut kv = serde_json::to_value(Krige::new()).unwrap();
    kv.as_object_mut().unwrap().remove("measurement_error");
    let k: Krige = serde_json::from_value(kv).unwrap();
    assert!(!k.measurement_error);
}

/// The option off (the default, or `measurement_error(false)`) is the exact form, bit for bit;
/// without a nugget the option changes nothing.
#[test]
fn option_off_unchanged() {
    let (coords, q) = (sample_coords(), queries());
    assert!(!Krige::new().measurement_error);
    let bits = |m: &KrigeModel| -> Vec<u64> {
        let p = m.predict_many(q.as_ref()).unwrap();
        let l = m.leave_one_out().unwrap();
        p.values
            .iter()
            .chain(&p.variances)
            .chain(&l.errors)
            .chain(&l.variances)
            .map(|x| x.to_bits())
            .collect()
    };
    let v = NestedVariogram::single(VariogramModel::Exponential, 0.2, 1.0, 60.0).unwrap();
    for krige in [
        Krige::new().variogram(v.clone()),
        Krige::new().simple(0.5).variogram(v.clone()),
        Krige::new().drift(Drift::Linear).variogram(v.clone()),
    ] {
        let default = krige.fit(coords.as_ref(), &Z).unwrap();
        let off = krige
            .clone()
            .measurement_error(false)
            .fit(coords.as_ref(), &Z)
            .unwrap();
        assert!(!default.measurement_error());
        assert_eq!(bits(&default), bits(&off));
        let at = default.predict(&[XS[5], YS[5]]).unwrap();
        close(at.value, Z[5], 1e-12, "exact at a sample");
        close(at.variance, 0.0, 1e-12, "variance 0 at a sample");
    }
    let v0 = NestedVariogram::single(VariogramModel::Exponential, 0.0, 1.0, 60.0).unwrap();
    let exact = Krige::new()
        .variogram(v0.clone())
        .fit(coords.as_ref(), &Z)
        .unwrap();
    let me = Krige::new()
        .measurement_error(true)
        .variogram(v0)
        .fit(coords.as_ref(), &Z)
        .unwrap();
    let (a, b) = (
        exact.predict_many(q.as_ref()).unwrap(),
        me.predict_many(q.as_ref()).unwrap(),
    );
    for i in 0..8 {
        close(a.values[i], b.values[i], 1e-12, "no nugget: value");
        close(a.variances[i], b.variances[i], 1e-12, "no nugget: variance");
    }
}

/// Two samples in 1-D by hand: `c(x) = sill exp(-3 h / a)` at every distance, the matrix with
/// `nugget + sill` on its diagonal, and the semivariogram form of the ordinary kriging variance
/// with `gamma_me(h) = nugget + gamma_s(h)`.
#[test]
fn two_points_by_hand() {
    let (x, z) = ([0.0, 2.0], [1.0, 3.0]);
    let (c0, sill, range) = (0.4, 1.0, 3.0);
    let cov = |h: f64| sill * (-3.0 * h / range).exp();
    let v = NestedVariogram::single(VariogramModel::Exponential, c0, sill, range).unwrap();
    let ok = Krige::new()
        .measurement_error(true)
        .variogram(v)
        .fit(col(&x).as_ref(), &z)
        .unwrap();
    for x0 in [0.0, 0.5, 2.0, 5.0] {
        let (c1, c2) = (cov((x0 - x[0]).abs()), cov((x0 - x[1]).abs()));
        // [[a, b, 1], [b, a, 1], [1, 1, 0]]: by symmetry lambda_1 = 1/2 + (c1 - c2) / (2 (a - b)).
        let (a, b) = (c0 + sill, cov(2.0));
        let l1 = 0.5 + (c1 - c2) / (2.0 * (a - b));
        let l2 = 1.0 - l1;
        let mu = c1 - a * l1 - b * l2; // covariance form: C lambda + mu 1 = c
        let value = l1 * z[0] + l2 * z[1];
        let variance = (c0 + sill) - (l1 * c1 + l2 * c2) - mu;
        let p = ok.predict(&[x0]).unwrap();
        close(p.value, value, 1e-12, "value");
        close(p.variance, variance, 1e-12, "variance");
        // Semivariogram form: sum lambda_i gamma_me(x - x_i) - mu (mu of the covariance form).
        let gme = |h: f64| c0 + sill - cov(h);
        let semi = l1 * gme((x0 - x[0]).abs()) + l2 * gme((x0 - x[1]).abs()) - mu;
        close(p.variance, semi, 1e-12, "semivariogram form");
    }
}
