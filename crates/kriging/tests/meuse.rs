//! Ordinary, universal and external-drift kriging on the Meuse data (log zinc) against PyKrige 1.7.3
//! and GSTools 1.7.0 (numbers from `crates/kriging/scripts/meuse_reference.py`, data licence in
//! `tests/data/MEUSE_SOURCE.md`): predictions and kriging variances within 1e-8.

use kriging::faer::Mat;
use kriging::{Drift, Krige, KrigeModel, Neighbourhood, NestedVariogram, VariogramModel};

const TOL: f64 = 1e-8;

struct Meuse {
    x: Vec<f64>,
    y: Vec<f64>,
    log_zinc: Vec<f64>,
}

fn data_dir() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data")
}

fn meuse() -> Meuse {
    let text = std::fs::read_to_string(data_dir().join("meuse.csv")).expect("meuse.csv");
    let mut m = Meuse {
        x: Vec::new(),
        y: Vec::new(),
        log_zinc: Vec::new(),
    };
    for line in text.lines().skip(1) {
        let f: Vec<f64> = line.split(',').map(|v| v.parse().unwrap()).collect();
        m.x.push(f[0]);
        m.y.push(f[1]);
        m.log_zinc.push(f[2].ln());
    }
    assert_eq!(m.x.len(), 155);
    m
}

fn reference() -> serde_json::Value {
    let text =
        std::fs::read_to_string(data_dir().join("meuse_reference.json")).expect("reference json");
    serde_json::from_str(&text).unwrap()
}

fn floats(v: &serde_json::Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

/// The script's external drift variable.
fn ext(x: f64, y: f64) -> f64 {
    ((x - 179000.0).powi(2) + (y - 331000.0).powi(2)).sqrt() / 1000.0
}

fn fit_case(m: &Meuse, case: &serde_json::Value, neighbourhood: Neighbourhood) -> KrigeModel {
    let model = VariogramModel::from_name(case["model"].as_str().unwrap()).unwrap();
    let v = NestedVariogram::single(
        model,
        case["nugget"].as_f64().unwrap(),
        case["sill"].as_f64().unwrap(),
        case["range"].as_f64().unwrap(),
    )
    .unwrap();
    let n = m.x.len();
    let coords = Mat::from_fn(n, 2, |i, k| if k == 0 { m.x[i] } else { m.y[i] });
    let drift = match case["drift"].as_str().unwrap() {
        "none" | "external" => Drift::Constant,
        "linear" => Drift::Linear,
        "quadratic" => Drift::Quadratic,
        other => panic!("unknown drift {other}"),
    };
    let krige = Krige::new()
        .drift(drift)
        .variogram(v)
        .neighbourhood(neighbourhood);
    if case["drift"] == "external" {
        let e = Mat::from_fn(n, 1, |i, _| ext(m.x[i], m.y[i]));
        krige
            .fit_with_external(coords.as_ref(), &m.log_zinc, e.as_ref())
            .unwrap()
    } else {
        krige.fit(coords.as_ref(), &m.log_zinc).unwrap()
    }
}

fn predict_case(
    model: &KrigeModel,
    case: &serde_json::Value,
    qx: &[f64],
    qy: &[f64],
) -> (Vec<f64>, Vec<f64>) {
    let q = Mat::from_fn(qx.len(), 2, |i, k| if k == 0 { qx[i] } else { qy[i] });
    let p = if case["drift"] == "external" {
        let e = Mat::from_fn(qx.len(), 1, |i, _| ext(qx[i], qy[i]));
        model
            .predict_many_with(q.as_ref(), Some(e.as_ref()), true)
            .unwrap()
    } else {
        model.predict_many(q.as_ref()).unwrap()
    };
    (p.values, p.variances)
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

#[test]
fn ordinary_universal_and_external_drift_match_pykrige_and_gstools() {
    let m = meuse();
    let r = reference();
    let qx = floats(&r["query_x"]);
    let qy = floats(&r["query_y"]);
    let cases = r["cases"].as_array().unwrap();
    assert_eq!(cases.len(), 5);
    let mut seen = std::collections::BTreeSet::new();
    for case in cases {
        let name = case["name"].as_str().unwrap();
        seen.insert(case["drift"].as_str().unwrap().to_string());
        let model = fit_case(&m, case, Neighbourhood::Global);
        assert!(
            model.warnings().is_empty(),
            "{name}: {:?}",
            model.warnings()
        );
        let (val, var) = predict_case(&model, case, &qx, &qy);
        for lib in ["pykrige", "gstools"] {
            let pz = floats(&case[format!("{lib}_prediction")]);
            let pv = floats(&case[format!("{lib}_variance")]);
            let dz = max_diff(&val, &pz);
            let dv = max_diff(&var, &pv);
            eprintln!("{name:28} vs {lib:8}: prediction {dz:.1e}, variance {dv:.1e}");
            assert!(dz < TOL, "{name} vs {lib}: predictions differ by {dz:e}");
            assert!(dv < TOL, "{name} vs {lib}: variances differ by {dv:e}");
        }
        // Single-point queries agree with the batch.
        for i in [0, 17, qx.len() - 1] {
            if case["drift"] == "external" {
                let p = model
                    .predict_external(&[qx[i], qy[i]], &[ext(qx[i], qy[i])])
                    .unwrap();
                assert!((p.value - val[i]).abs() < 1e-12 && (p.variance - var[i]).abs() < 1e-12);
            } else {
                let p = model.predict(&[qx[i], qy[i]]).unwrap();
                assert!((p.value - val[i]).abs() < 1e-12 && (p.variance - var[i]).abs() < 1e-12);
            }
        }
    }
    assert_eq!(
        seen.into_iter().collect::<Vec<_>>(),
        ["external", "linear", "none", "quadratic"]
    );
}

#[test]
fn a_neighbourhood_holding_every_sample_gives_the_global_answer() {
    let m = meuse();
    let r = reference();
    let qx = floats(&r["query_x"]);
    let qy = floats(&r["query_y"]);
    for case in r["cases"].as_array().unwrap() {
        let model = fit_case(&m, case, Neighbourhood::Nearest { k: 155 });
        let (val, var) = predict_case(&model, case, &qx, &qy);
        let pz = floats(&case["pykrige_prediction"]);
        let pv = floats(&case["pykrige_variance"]);
        assert!(max_diff(&val, &pz) < TOL, "{}", case["name"]);
        assert!(max_diff(&var, &pv) < TOL, "{}", case["name"]);
    }
}

#[test]
fn textbook_universal_kriging_differs_from_regression_kriging() {
    // The finding: the paper's regression kriging (OLS trend + OK of residuals) is not the
    // BLUP of universal kriging. Both from the crate, same variogram and drift.
    use kriging::{Kriging, KrigingConfig, Method, ModelChoice, ScalingChoice, Variogram};
    let m = meuse();
    let n = m.x.len();
    let coords = Mat::from_fn(n, 2, |i, k| if k == 0 { m.x[i] } else { m.y[i] });
    let values = Mat::from_fn(n, 1, |i, _| m.log_zinc[i]);
    let v = Variogram::new(VariogramModel::Spherical, 0.05, 0.5, 800.0, 1.0).unwrap();
    let rk = Kriging::fit(
        coords.as_ref(),
        values.as_ref(),
        &KrigingConfig {
            method: Method::Regression,
            model: ModelChoice::Given(v),
            scaling: ScalingChoice::None,
            ..KrigingConfig::default()
        },
    )
    .unwrap();
    let uk = Krige::new()
        .drift(Drift::Linear)
        .variogram(v)
        .fit(coords.as_ref(), &m.log_zinc)
        .unwrap();
    let mut largest: f64 = 0.0;
    let mut out = [0.0];
    for i in 0..20 {
        for j in 0..20 {
            let x = 178600.0 + 2700.0 * i as f64 / 19.0;
            let y = 329700.0 + 3900.0 * j as f64 / 19.0;
            rk.predict(&[x, y], &mut out).unwrap();
            largest = largest.max((out[0] - uk.predict(&[x, y]).unwrap().value).abs());
        }
    }
    // Both interpolate the data; away from it they differ by a visible amount.
    assert!(largest > 1e-3, "largest difference {largest}");
}
