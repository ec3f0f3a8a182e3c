//! Variogram analysis on Meuse (log zinc) against GSTools 1.7.0 (issue 37, item 4): directional
//! and robust empirical variograms, and the Matérn fit with a continuous smoothness. Numbers from
//! `crates/kriging/scripts/variogram_analysis_reference.py` in `tests/data/meuse_variogram_reference.json`
//! (data licence in `tests/data/MEUSE_SOURCE.md`).

use kriging::faer::Mat;
use kriging::{
    Binning, Direction, EmpiricalVariogram, EstimateOptions, Estimator, FitOptions, MaxLag,
    NestedVariogram, VariogramModel, fit_nested, fit_variogram,
};

fn data_dir() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data")
}

fn meuse() -> (Mat<f64>, Vec<f64>) {
    let text = std::fs::read_to_string(data_dir().join("meuse.csv")).expect("meuse.csv");
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 155);
    let coords = Mat::from_fn(rows.len(), 2, |i, k| rows[i][k]);
    let z = rows.iter().map(|r| r[2].ln()).collect();
    (coords, z)
}

fn reference() -> serde_json::Value {
    let text = std::fs::read_to_string(data_dir().join("meuse_variogram_reference.json"))
        .expect("reference json");
    serde_json::from_str(&text).unwrap()
}

fn floats(v: &serde_json::Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn counts(v: &serde_json::Value) -> Vec<usize> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_u64().unwrap() as usize)
        .collect()
}

fn binning(r: &serde_json::Value) -> Binning {
    Binning {
        bins: r["bins"].as_u64().unwrap() as usize,
        max_lag: MaxLag::Distance(r["max_lag"].as_f64().unwrap()),
    }
}

/// Omnidirectional and directional (4 directions, tolerance 22.5 degrees, two with a bandwidth)
/// Matheron and Cressie-Hawkins variograms against GSTools' `vario_estimate`, Dowd against numpy
/// over the same pairs: same counts, values within 1e-10 relative (measured: 6.3e-15).
#[test]
fn directional_and_robust_estimators_match_gstools() {
    let (coords, z) = meuse();
    let r = reference();
    let b = binning(&r);
    let mut worst = 0.0f64;
    let cases = r["cases"].as_array().unwrap();
    assert_eq!(cases.len(), 7);
    for case in cases {
        let direction = case["angle"].as_f64().map(|a| {
            let d = Direction::planar(a, case["tolerance"].as_f64().unwrap());
            match case["bandwidth"].as_f64() {
                Some(bw) => d.with_bandwidth(bw),
                None => d,
            }
        });
        for (key, estimator) in [
            ("matheron", Estimator::Matheron),
            ("cressie", Estimator::CressieHawkins),
            ("dowd", Estimator::Dowd),
        ] {
            let opts = EstimateOptions {
                estimator,
                direction: direction.clone(),
                great_circle: None,
            };
            let e = EmpiricalVariogram::estimate(coords.as_ref(), &z, &b, &opts).unwrap();
            assert_eq!(
                e.counts,
                counts(&case[format!("{key}_counts")]),
                "{case} {key}"
            );
            let want = floats(&case[key]);
            for (u, (&g, &w)) in e.gamma.iter().zip(&want).enumerate() {
                let rel = (g - w).abs() / w.abs().max(1e-300);
                worst = worst.max(rel);
                assert!(rel < 1e-10, "{key} bin {u}: {g} vs {w} ({case})");
            }
            for (&c, &w) in e.centers.iter().zip(&floats(&case["centers"])) {
                assert!((c - w).abs() < 1e-9 * w, "centre {c} vs {w}");
            }
        }
    }
    eprintln!("largest relative difference to GSTools / numpy: {worst:.2e}");
}

/// The Matheron estimator without a direction is `compute_binned`'s variogram.
#[test]
fn omnidirectional_matheron_is_compute_binned() {
    let (coords, z) = meuse();
    let b = binning(&reference());
    let e =
        EmpiricalVariogram::estimate(coords.as_ref(), &z, &b, &EstimateOptions::default()).unwrap();
    let zm = Mat::from_fn(z.len(), 1, |i, _| z[i]);
    let c = EmpiricalVariogram::compute_binned(coords.as_ref(), zm.as_ref(), &b).unwrap();
    assert_eq!(e.counts, c.counts);
    for (a, b) in e.gamma.iter().zip(&c.gamma) {
        assert!((a - b).abs() < 1e-14 * b);
    }
}

/// Matérn with a continuous smoothness on Meuse: GSTools 1.7.0 (`Matern.fit_variogram`, weights
/// sqrt(counts), nu in [0.2, 30]) and the crate minimise the same pair-count-weighted squared error
/// over the same bounds. The data want a gaussian shape: the crate's `nu` ends at the upper bound
/// 30 and says so (`bounds.exponent_at_bound`), with a smaller error than GSTools' (6.915 against
/// 6.947 in the crate's objective), whose optimiser stops at nu = 28.3. Parameters within 5 %
/// (measured: nugget 4.1 %, sill 1.0 %, scale 4.0 %) and nu within 10 % (6.0 %); the error is flat
/// in nu there. (Before, nu was chosen from a fixed set and ended silently at 5.)
#[test]
fn matern_smoothness_fit_matches_gstools() {
    let (coords, z) = meuse();
    let r = reference();
    let b = binning(&r);
    let e =
        EmpiricalVariogram::estimate(coords.as_ref(), &z, &b, &EstimateOptions::default()).unwrap();
    let fit = fit_variogram(&e, VariogramModel::Matern, &FitOptions::default()).unwrap();
    let v = fit.variogram;
    let g = &r["matern"];
    let (gn, gs, gnu, ga) = (
        g["nugget"].as_f64().unwrap(),
        g["sill"].as_f64().unwrap(),
        g["nu"].as_f64().unwrap(),
        g["scale"].as_f64().unwrap(),
    );
    let theirs = kriging::Variogram::new(VariogramModel::Matern, gn, gs, ga, gnu).unwrap();
    let wsse_theirs: f64 = (0..e.gamma.len())
        .filter(|&u| e.counts[u] > 0)
        .map(|u| e.counts[u] as f64 * (theirs.eval(e.centers[u]) - e.gamma[u]).powi(2))
        .sum();
    let rel = |a: f64, b: f64| (a - b).abs() / b.abs();
    eprintln!(
        "matern: crate nugget {:.6} sill {:.6} scale {:.4} nu {:.4} wsse {:.8e}; GSTools {gn:.6} \
         {gs:.6} {ga:.4} {gnu:.4} wsse {wsse_theirs:.8e}; bounds {:?}",
        v.nugget, v.sill, v.range, v.exponent, fit.wsse, fit.bounds
    );
    assert!(fit.wsse <= wsse_theirs * (1.0 + 1e-9));
    assert!(fit.bounds.exponent_at_bound && fit.bounds.any() && !fit.bounds.range_at_bound);
    assert!((v.exponent - kriging::MATERN_NU_BOUNDS.1).abs() < 1e-12);
    assert!(rel(v.nugget, gn) < 0.05 && rel(v.sill, gs) < 0.05 && rel(v.range, ga) < 0.05);
    assert!(rel(v.exponent, gnu) < 0.10);
    // The map front end (with the same pair-count weights; its default is Cressie's) reports
    // the same flag in its fit report.
    let model = kriging::Krige::new()
        .fit_model(VariogramModel::Matern)
        .fit_weights(kriging::FitWeights::PairCounts)
        .binning(b)
        .fit(coords.as_ref(), &z)
        .unwrap();
    let rep = &model.fit_report().unwrap().candidates[0];
    assert_eq!(rep.bounds, Some(fit.bounds));
}

/// Spherical + exponential on Meuse: the data carry one structure. GSTools 1.7.0's SumModel fit
/// ends with a negligible exponential structure (sill 3e-5, range 0.5 m); the crate's fit says so
/// as an error (a structure with zero sill) or flags the range at its bound, never silently.
#[test]
fn nested_fit_on_meuse_reports_a_degenerate_structure() {
    let (coords, z) = meuse();
    let b = binning(&reference());
    let e =
        EmpiricalVariogram::estimate(coords.as_ref(), &z, &b, &EstimateOptions::default()).unwrap();
    let models = [VariogramModel::Spherical, VariogramModel::Exponential];
    match fit_nested(&e, &models, &FitOptions::default()) {
        Err(err) => assert!(err.to_string().contains("zero sill"), "{err}"),
        Ok(f) => {
            let v: &NestedVariogram = &f.variogram;
            assert!(f.range_at_bound.contains(&true), "{v:?}");
        }
    }
}
