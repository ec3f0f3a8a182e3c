//! Kriging and empirical variograms on the sphere (issue 37, item 5) against GSTools 1.7.0 with
//! `latlon=True, geo_scale=EARTH_RADIUS`: ordinary and simple kriging on `latlon_to_xyz`
//! coordinates (chordal distances, GSTools' convention) within 1e-9 (measured: printed), and the
//! great-circle empirical variogram within 1e-12 relative. Reference numbers from
//! `crates/kriging/scripts/sphere_reference.py` (20 generated points, 6 queries, one at sample 4),
//! pasted below.

use kriging::faer::Mat;
use kriging::{
    Binning, EmpiricalVariogram, EstimateOptions, Krige, KrigingError, MaxLag, NestedVariogram,
    VariogramModel, chord_distance, great_circle_distance, latlon_to_xyz,
};

// Output of scripts/sphere_reference.py: gstools 1.7.0, EARTH_RADIUS = 6371.0
const LAT: [f64; 20] = [
    50.0, 42.5, 57.5, 38.75, 53.75, 46.25, 61.25, 36.875, 51.875, 44.375, 59.375, 40.625, 55.625,
    48.125, 63.125, 35.9375, 50.9375, 43.4375, 58.4375, 39.6875,
];
const LON: [f64; 20] = [
    1.6666666666666643,
    18.33333333333333,
    -9.444444444444445,
    7.222222222222221,
    23.888888888888886,
    -3.8888888888888893,
    12.777777777777779,
    29.444444444444443,
    -13.148148148148149,
    3.518518518518519,
    20.185185185185183,
    -7.5925925925925934,
    9.074074074074073,
    25.740740740740733,
    -2.037037037037038,
    14.629629629629626,
    31.29629629629629,
    -11.296296296296298,
    5.37037037037037,
    22.037037037037038,
];
const Z: [f64; 20] = [
    0.17274387238687075,
    0.6437697291757867,
    -0.42038819197336674,
    0.9595142460763328,
    -0.17741516938635032,
    0.36362567924622885,
    -0.3863221767990844,
    0.846286412162824,
    -0.20710960501348064,
    0.5703434449619513,
    -0.39574988993334825,
    0.6857865638453067,
    -0.14022995660686632,
    0.15155292765274853,
    -0.4769286620555881,
    1.0979487278637359,
    -0.12369463339197867,
    0.410964127124641,
    -0.2723782217054187,
    0.785290549670409,
];
const QLAT: [f64; 6] = [50.0, 40.0, 62.5, 53.75, 55.0, 30.0];
const QLON: [f64; 6] = [10.0, 0.0, 25.0, 23.888888888888886, -20.0, 40.0];
const OK_VALUE: [f64; 6] = [
    0.19522458247303678,
    0.5512415002411454,
    -0.07824777891730562,
    -0.17741516938635032,
    0.009804189099380786,
    0.2864356692728657,
];
const OK_VAR: [f64; 6] = [
    0.7231380328281112,
    0.7043186701904266,
    0.7273028311792686,
    0.0,
    0.7814421258321689,
    0.9229096674462526,
];
const SK_VALUE: [f64; 6] = [
    0.4107038874149791,
    0.8004438298271945,
    0.29828190706026725,
    -0.17741516938635016,
    0.4414781975884269,
    0.9830277989190067,
];
const SK_VAR: [f64; 6] = [
    0.7156524146662645,
    0.6943066726579761,
    0.7044460546420556,
    0.0,
    0.7514001606482663,
    0.8446796071767918,
];
const VARIO: [f64; 8] = [
    0.0,
    0.01507336031518304,
    0.036739352935152396,
    0.07646451161092596,
    0.15556212538066388,
    0.1873705362292582,
    0.29992505068666764,
    0.3712472648687586,
];
const VARIO_COUNTS: [usize; 8] = [0, 8, 21, 15, 28, 20, 26, 24];

const R: f64 = 6371.0;

fn xyz(lat: &[f64], lon: &[f64]) -> Mat<f64> {
    let ll = Mat::from_fn(lat.len(), 2, |i, k| if k == 0 { lat[i] } else { lon[i] });
    latlon_to_xyz(ll.as_ref(), R).unwrap()
}

/// Exponential, partial sill 0.8, practical range 1500 km (GSTools len_scale 500), nugget 0.05.
fn variogram() -> NestedVariogram {
    NestedVariogram::single(VariogramModel::Exponential, 0.05, 0.8, 1500.0).unwrap()
}

#[test]
fn latlon_kriging_matches_gstools() {
    let data = xyz(&LAT, &LON);
    let queries = xyz(&QLAT, &QLON);
    let mut worst = 0.0f64;
    for (krige, values, vars) in [
        (Krige::new(), OK_VALUE, OK_VAR),
        (Krige::new().simple(1.0), SK_VALUE, SK_VAR),
    ] {
        let model = krige.variogram(variogram()).fit(data.as_ref(), &Z).unwrap();
        let p = model.predict_many(queries.as_ref()).unwrap();
        for q in 0..6 {
            let (dv, ds) = (
                (p.values[q] - values[q]).abs(),
                (p.variances[q] - vars[q]).abs(),
            );
            worst = worst.max(dv).max(ds);
            assert!(
                dv < 1e-9 && ds < 1e-9,
                "query {q}: {} {} vs {} {}",
                p.values[q],
                p.variances[q],
                values[q],
                vars[q]
            );
        }
    }
    eprintln!("largest difference to GSTools: {worst:.2e}");
}

#[test]
fn great_circle_variogram_matches_gstools() {
    let ll = Mat::from_fn(20, 2, |i, k| if k == 0 { LAT[i] } else { LON[i] });
    let b = Binning {
        bins: 8,
        max_lag: MaxLag::Distance(2400.0),
    };
    let o = EstimateOptions {
        great_circle: Some(R),
        ..EstimateOptions::default()
    };
    let e = EmpiricalVariogram::estimate(ll.as_ref(), &Z, &b, &o).unwrap();
    assert_eq!(e.counts, VARIO_COUNTS);
    for (g, w) in e.gamma.iter().zip(VARIO) {
        assert!((g - w).abs() <= 1e-12 * w, "{g} vs {w}");
    }
}

#[test]
fn distances_on_the_sphere() {
    // A quarter of a great circle: arc pi R / 2, chord sqrt(2) R.
    let (p, q) = ([0.0, 0.0], [0.0, 90.0]);
    assert!((great_circle_distance(p, q, R) - std::f64::consts::FRAC_PI_2 * R).abs() < 1e-9);
    assert!((chord_distance(p, q, R) - 2f64.sqrt() * R).abs() < 1e-9);
    // Antipodes, poles, the date line.
    assert!(
        (great_circle_distance([90.0, 0.0], [-90.0, 0.0], 1.0) - std::f64::consts::PI).abs()
            < 1e-12
    );
    assert!(great_circle_distance([10.0, 179.5], [10.0, -179.5], R) < 120.0);
    // Chord between converted points equals chord_distance.
    let x = xyz(&LAT[..2], &LON[..2]);
    let c: f64 = (0..3)
        .map(|k| (x[(0, k)] - x[(1, k)]).powi(2))
        .sum::<f64>()
        .sqrt();
    assert!((c - chord_distance([LAT[0], LON[0]], [LAT[1], LON[1]], R)).abs() < 1e-9);
}

#[test]
fn bad_latlon_input_gives_errors() {
    let bad =
        |lat: f64, lon: f64| latlon_to_xyz(Mat::from_fn(1, 2, |_, k| [lat, lon][k]).as_ref(), R);
    assert!(matches!(
        bad(91.0, 0.0),
        Err(KrigingError::InvalidConfig(_))
    ));
    assert!(matches!(
        bad(f64::NAN, 0.0),
        Err(KrigingError::NonFinite { col: 0, .. })
    ));
    assert!(matches!(
        bad(0.0, f64::INFINITY),
        Err(KrigingError::NonFinite { col: 1, .. })
    ));
    let ok = Mat::from_fn(1, 2, |_, _| 0.0);
    for r in [0.0, -1.0, f64::NAN] {
        assert!(matches!(
            latlon_to_xyz(ok.as_ref(), r),
            Err(KrigingError::InvalidConfig(_))
        ));
    }
    let three = Mat::from_fn(2, 3, |_, _| 0.0);
    assert!(matches!(
        latlon_to_xyz(three.as_ref(), R),
        Err(KrigingError::ShapeMismatch { .. })
    ));
    // Empirical variogram: no direction, no diagonal fraction, latitudes checked.
    let ll = Mat::from_fn(20, 2, |i, k| if k == 0 { LAT[i] } else { LON[i] });
    let o = EstimateOptions {
        great_circle: Some(R),
        direction: Some(kriging::Direction::planar(0.0, 20.0)),
        ..EstimateOptions::default()
    };
    let b = Binning::default();
    assert!(matches!(
        EmpiricalVariogram::estimate(ll.as_ref(), &Z, &b, &o),
        Err(KrigingError::InvalidConfig(_))
    ));
    let o = EstimateOptions {
        great_circle: Some(R),
        ..EstimateOptions::default()
    };
    assert!(matches!(
        EmpiricalVariogram::estimate(ll.as_ref(), &Z, &b, &o),
        Err(KrigingError::InvalidConfig(_))
    ));
    let swapped = Mat::from_fn(20, 2, |i, k| if k == 0 { LON[i] + 100.0 } else { LAT[i] });
    let b = Binning {
        bins: 4,
        max_lag: MaxLag::Largest,
    };
    assert!(matches!(
        EmpiricalVariogram::estimate(swapped.as_ref(), &Z, &b, &o),
        Err(KrigingError::InvalidConfig(_))
    ));
    let o = EstimateOptions {
        great_circle: Some(-1.0),
        ..EstimateOptions::default()
    };
    assert!(matches!(
        EmpiricalVariogram::estimate(ll.as_ref(), &Z, &b, &o),
        Err(KrigingError::InvalidConfig(_))
    ));
}
