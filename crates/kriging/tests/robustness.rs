//! Inputs at the edges of double precision and of memory: the public API answers with an error
//! (or a finite result), never NaN, a hang, a panic deep inside or an allocation abort.

use faer::Mat;
use kriging::*;

fn line(n: usize) -> Mat<f64> {
    Mat::from_fn(n, 1, |i, _| i as f64)
}

fn vals(n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| (i as f64 * 0.7).sin() + 0.1 * i as f64)
        .collect()
}

fn vcol(n: usize) -> Mat<f64> {
    let v = vals(n);
    Mat::from_fn(n, 1, |i, _| v[i])
}

fn matern(nu: f64) -> NestedVariogram {
    let mut v = NestedVariogram::single(VariogramModel::Exponential, 0.0, 1.0, 1.0).unwrap();
    v.structures[0].model = VariogramModel::Matern;
    v.structures[0].exponent = nu;
    v
}

fn given(v: Variogram, method: Method) -> KrigingConfig {
    KrigingConfig {
        method,
        model: ModelChoice::Given(v),
        scaling: ScalingChoice::None,
        bins: 4,
        ..KrigingConfig::default()
    }
}

fn is_overflow<T: std::fmt::Debug>(r: &Result<T, KrigingError>) -> bool {
    matches!(r, Err(KrigingError::Overflow { .. }))
}

fn is_invalid_config<T: std::fmt::Debug>(r: &Result<T, KrigingError>) -> bool {
    matches!(r, Err(KrigingError::InvalidConfig(_)))
}

// --- 1. Matérn (and cardinal sine) at extreme lags --------------------------------------------

#[test]
fn matern_is_finite_at_tiny_and_huge_lags() {
    for nu in [0.05, 0.2, 0.5, 1.5, 2.5, 5.0, 20.0, 30.0, 49.9, 50.0] {
        let v = Variogram::new(VariogramModel::Matern, 0.0, 1.0, 1.0, nu).unwrap();
        for h in [
            1e-300, 1e-100, 1e-20, 1e-10, 1e-5, 1e-3, 1.0, 700.0, 1e5, 1e155, 1e300,
        ] {
            let g = v.eval(h);
            assert!((0.0..=1.0).contains(&g), "nu {nu} h {h}: {g}");
        }
        assert_eq!(v.eval(1e300), 1.0, "nu {nu}");
        assert_eq!(v.eval(f64::INFINITY), 1.0, "nu {nu}");
    }
    // The audit's case: NaN before.
    let v = Variogram::new(VariogramModel::Matern, 0.0, 1.0, 1.0, 30.0).unwrap();
    assert_eq!(v.eval(1e-10), 0.0);
    // A tiny range: the lag over the range is infinite.
    for nu in [1.5, 2.5, 7.0] {
        let v = Variogram::new(VariogramModel::Matern, 0.0, 1.0, 1e-300, nu).unwrap();
        assert_eq!(v.eval(1e300), 1.0, "nu {nu}");
    }
    let v = Variogram::new(VariogramModel::CardinalSine, 0.0, 1.0, 1e-300, 1.0).unwrap();
    assert_eq!(v.eval(1e300), 1.0);
    assert_eq!(v.eval(f64::INFINITY), 1.0);
}

#[test]
fn matern_predictions_far_away_are_finite() {
    let k = Krige::new()
        .variogram(matern(2.5))
        .fit(line(6).as_ref(), &vals(6))
        .unwrap();
    let p = k.predict(&[1e300]).unwrap();
    assert!(p.value.is_finite() && p.variance.is_finite(), "{p:?}");
    let many = k
        .predict_many(Mat::from_fn(3, 1, |i, _| [1e300, 2.5, -1e300][i]).as_ref())
        .unwrap();
    assert!(
        many.values
            .iter()
            .chain(&many.variances)
            .all(|v| v.is_finite())
    );

    let cfg = given(
        Variogram::new(VariogramModel::Matern, 0.0, 1.0, 1.0, 2.5).unwrap(),
        Method::Ordinary,
    );
    let k = Kriging::fit(line(6).as_ref(), vcol(6).as_ref(), &cfg).unwrap();
    let mut x = [0.0];
    k.predict(&[1e300], &mut x).unwrap();
    assert!(x[0].is_finite());
}

#[test]
fn matern_samples_close_together_fit_and_predict() {
    // With nu = 30 two samples 1e-7 apart gave a NaN covariance ("singular", residual NaN).
    let c = Mat::from_fn(4, 1, |i, _| [0.0, 1e-7, 1.0, 2.0][i]);
    let mut v = matern(30.0);
    v.nugget = 0.01;
    let k = Krige::new()
        .variogram(v)
        .fit(c.as_ref(), &[0.0, 0.1, 0.5, 1.0])
        .unwrap();
    let p = k.predict(&[0.5]).unwrap();
    assert!(p.value.is_finite() && p.variance.is_finite());
}

#[test]
fn predictions_are_never_ok_nan() {
    // An unbounded variogram at queries near the end of the doubles: the variogram values
    // overflow; the answer is a finite prediction or an overflow error, never Ok(NaN).
    let cfg = given(
        Variogram::new(VariogramModel::Linear, 0.0, 1.0, 0.0, 1.0).unwrap(),
        Method::Regression,
    );
    let k = Kriging::fit(line(6).as_ref(), vcol(6).as_ref(), &cfg).unwrap();
    let mut overflowed = 0;
    for q in [1e300, 1e307, f64::MAX, -f64::MAX] {
        let mut x = [0.0];
        match k.predict(&[q], &mut x) {
            Ok(()) => assert!(x[0].is_finite(), "{q}: {x:?}"),
            Err(KrigingError::Overflow { .. }) => overflowed += 1,
            Err(e) => panic!("{q}: {e}"),
        }
        let mut b = [0.0; 6];
        match k.weights(&[q], &mut b) {
            Ok(()) => assert!(b.iter().all(|w| w.is_finite()), "{q}: {b:?}"),
            Err(KrigingError::Overflow { .. }) => {}
            Err(e) => panic!("{q}: {e}"),
        }
        match k.predict_rows(Mat::from_fn(1, 1, |_, _| q).as_ref()) {
            Ok(m) => assert!(m[(0, 0)].is_finite()),
            Err(KrigingError::Overflow { .. }) => {}
            Err(e) => panic!("{q}: {e}"),
        }
    }
    assert!(overflowed > 0);
    let v = NestedVariogram::single(VariogramModel::Linear, 0.0, 1.0, 0.0).unwrap();
    let k = Krige::new()
        .drift(Drift::Linear)
        .variogram(v)
        .fit(line(6).as_ref(), &vals(6))
        .unwrap();
    let mut overflowed = 0;
    for q in [1e300, f64::MAX, -f64::MAX] {
        match k.predict(&[q]) {
            Ok(p) => assert!(p.value.is_finite() && p.variance.is_finite(), "{q}: {p:?}"),
            Err(KrigingError::Overflow { .. }) => overflowed += 1,
            Err(e) => panic!("{q}: {e}"),
        }
    }
    assert!(overflowed > 0);
    let r = k.predict_many(Mat::from_fn(3, 1, |i, _| [0.5, f64::MAX, 2.0][i]).as_ref());
    match r {
        Ok(p) => assert!(p.values.iter().chain(&p.variances).all(|v| v.is_finite())),
        Err(KrigingError::Overflow { what, .. }) => assert!(what.contains("point 1"), "{what}"),
        Err(e) => panic!("{e}"),
    }
}

#[test]
fn projected_queries_are_never_ok_nan() {
    // The runtime's hot path (`L b(c)` without the weights): the same overflow as `weights`.
    let cfg = given(
        Variogram::new(VariogramModel::Linear, 0.0, 1.0, 0.0, 1.0).unwrap(),
        Method::Regression,
    );
    let k = Kriging::fit(line(6).as_ref(), vcol(6).as_ref(), &cfg).unwrap();
    let l = Mat::from_fn(2, 6, |r, i| if r == 0 { 1.0 } else { i as f64 });
    let pq = ProjectedQuery::new(&k, l.as_ref()).unwrap();
    let (mut scratch, mut out) = (vec![0.0; 7], [0.0; 2]);
    let mut overflowed = 0;
    for q in [1e300, 1e307, f64::MAX, -f64::MAX] {
        match pq.query(&[q], &mut scratch, &mut out) {
            Ok(()) => assert!(out.iter().all(|v| v.is_finite()), "{q}: {out:?}"),
            Err(KrigingError::Overflow { what, .. }) => {
                assert!(what.contains("projected weights"), "{what}");
                overflowed += 1;
            }
            Err(e) => panic!("{q}: {e}"),
        }
    }
    assert!(overflowed > 0);
    // An ordinary query: L b(c), as the weights give it.
    pq.query(&[2.5], &mut scratch, &mut out).unwrap();
    let mut b = [0.0; 6];
    k.weights(&[2.5], &mut b).unwrap();
    assert!((out[0] - 1.0).abs() < 1e-12, "{out:?}");
    let lb: f64 = (0..6).map(|i| i as f64 * b[i]).sum();
    assert!((out[1] - lb).abs() < 1e-9, "{out:?} against {lb}");
}

// --- 2. Size parameters ------------------------------------------------------------------------

#[test]
fn huge_bin_counts_are_config_errors() {
    let (p, v) = (line(6), vcol(6));
    for bins in [MAX_BINS + 1, 1 << 40, usize::MAX] {
        assert!(is_invalid_config(&EmpiricalVariogram::compute(
            p.as_ref(),
            v.as_ref(),
            bins
        )));
        let binning = Binning {
            bins,
            max_lag: MaxLag::Largest,
        };
        assert!(is_invalid_config(&EmpiricalVariogram::compute_binned(
            p.as_ref(),
            v.as_ref(),
            &binning
        )));
        assert!(is_invalid_config(&EmpiricalVariogram::estimate(
            p.as_ref(),
            &vals(6),
            &binning,
            &EstimateOptions::default()
        )));
        for model in [
            ModelChoice::Fixed(VariogramModel::Exponential),
            ModelChoice::default(),
        ] {
            let cfg = KrigingConfig {
                bins,
                model,
                ..KrigingConfig::default()
            };
            let r = Kriging::fit(p.as_ref(), v.as_ref(), &cfg);
            assert!(is_invalid_config(&r), "{:?}", r.err());
        }
        assert!(is_invalid_config(
            &Krige::new()
                .binning(binning)
                .fit(p.as_ref(), &vals(6))
                .map(|_| ())
        ));
    }
    // The cap itself is allowed (and costs no more memory than a row of intervals at a time).
    let e = EmpiricalVariogram::compute(p.as_ref(), v.as_ref(), MAX_BINS).unwrap();
    assert_eq!(e.counts.iter().sum::<usize>(), 15);
}

#[test]
fn many_rows_with_many_bins_give_the_same_bits_as_one_pass() {
    // 600 samples x 10_000 bins: the rows are binned in blocks; the sums keep the row order.
    let n = 600;
    let p = Mat::from_fn(n, 2, |i, k| {
        ((i * 7 + k * 13) % 97) as f64 + 0.01 * i as f64
    });
    let z = Mat::from_fn(n, 1, |i, _| (i as f64 * 0.37).sin());
    let bins = 10_000;
    let e = EmpiricalVariogram::compute(p.as_ref(), z.as_ref(), bins).unwrap();
    // Reference: every pair into its interval, rows in order.
    let mut dmax = 0.0f64;
    let dist = |i: usize, j: usize| {
        ((p[(i, 0)] - p[(j, 0)]).powi(2) + (p[(i, 1)] - p[(j, 1)]).powi(2)).sqrt()
    };
    for i in 0..n {
        for j in i + 1..n {
            dmax = dmax.max(dist(i, j));
        }
    }
    let dh = dmax / bins as f64;
    let mut sums = vec![0.0; bins];
    let mut counts = vec![0usize; bins];
    for i in 0..n {
        let mut rs = vec![0.0; bins];
        for j in i + 1..n {
            let u = ((dist(i, j) / dh) as usize).min(bins - 1);
            rs[u] += 0.5 * (z[(i, 0)] - z[(j, 0)]).powi(2);
            counts[u] += 1;
        }
        for u in 0..bins {
            sums[u] += rs[u];
        }
    }
    assert_eq!(e.counts, counts);
    for u in 0..bins {
        let g = if counts[u] > 0 {
            sums[u] / counts[u] as f64
        } else {
            0.0
        };
        assert_eq!(e.gamma[u].to_bits(), g.to_bits(), "interval {u}");
    }
}

#[test]
fn huge_simulations_are_config_errors() {
    let v = NestedVariogram::single(VariogramModel::Exponential, 0.0, 1.0, 3.0).unwrap();
    for r in [1 << 40, MAX_SIMULATED_VALUES / 10 + 1, usize::MAX] {
        let res = Sgs::new(v.clone())
            .simple(0.0)
            .realisations(r)
            .simulate_unconditional(line(10).as_ref());
        assert!(is_invalid_config(&res.map(|_| ())), "{r}");
    }
}

#[test]
fn huge_anisotropy_dimensions_are_config_errors() {
    for d in [Anisotropy::MAX_DIMS + 1, 1 << 40, usize::MAX] {
        assert!(is_invalid_config(&Anisotropy::Isotropic.matrix(d)), "{d}");
    }
    assert_eq!(Anisotropy::Isotropic.matrix(3).unwrap().len(), 9);
}

// --- 3. Hand-built empirical variograms ----------------------------------------------------------

fn emp(centers: Vec<f64>, gamma: Vec<f64>, counts: Vec<usize>) -> EmpiricalVariogram {
    EmpiricalVariogram {
        bin_width: 1.0,
        centers,
        gamma,
        counts,
    }
}

fn is_fit_error<T: std::fmt::Debug>(r: &Result<T, KrigingError>) -> bool {
    matches!(r, Err(KrigingError::VariogramFit { .. }))
}

#[test]
fn malformed_empirical_variograms_are_fit_errors() {
    let start = std::time::Instant::now();
    let g = vec![0.3, 0.4, 0.5];
    let bad = [
        emp(vec![0.0, 1.0, 2.0], g.clone(), vec![3, 3, 3]),
        emp(vec![-1.0, 1.0, 2.0], g.clone(), vec![3, 3, 3]),
        emp(vec![0.5, 1.5, 2.5], vec![0.3, 0.4], vec![3, 3, 3]),
        emp(vec![0.5, 1.5], g.clone(), vec![3, 3, 3]),
        emp(vec![0.5, 1.5, 2.5], g.clone(), vec![3, 3]),
        EmpiricalVariogram {
            bin_width: 0.0,
            ..emp(vec![0.5, 1.5, 2.5], g.clone(), vec![3, 3, 3])
        },
        EmpiricalVariogram {
            bin_width: f64::NAN,
            ..emp(vec![0.5, 1.5, 2.5], g.clone(), vec![3, 3, 3])
        },
    ];
    for e in &bad {
        for model in VariogramModel::EVERY {
            let r = fit_variogram(e, model, &FitOptions::default());
            assert!(is_fit_error(&r), "{model:?} {e:?}: {r:?}");
        }
        let r = fit_nested(e, &[VariogramModel::Spherical], &FitOptions::default());
        assert!(is_fit_error(&r), "{e:?}: {r:?}");
    }
    // An empty interval may have any centre; the well-formed rest still fits.
    let ok = emp(vec![0.0, 1.5, 2.5], g, vec![0, 3, 3]);
    fit_variogram(&ok, VariogramModel::Matern, &FitOptions::default()).unwrap();
    // The Matérn fit on a zero centre ran for minutes.
    assert!(start.elapsed().as_secs() < 60);
}

// --- 4. Overflow reported as overflow ------------------------------------------------------------

#[test]
fn huge_values_are_overflow_not_constant() {
    let big = Mat::from_fn(6, 1, |i, _| 1e300 * (i as f64 - 2.5));
    for cfg in [
        KrigingConfig::default(),
        KrigingConfig {
            model: ModelChoice::Fixed(VariogramModel::Linear),
            method: Method::Ordinary,
            ..KrigingConfig::default()
        },
    ] {
        let r = Kriging::fit(line(6).as_ref(), big.as_ref(), &cfg);
        match r {
            Err(KrigingError::Overflow { what, .. }) => {
                assert!(what.contains("column 0"), "{what}")
            }
            other => panic!("{:?}", other.err()),
        }
    }
    let r = EmpiricalVariogram::compute(line(6).as_ref(), big.as_ref(), 3);
    assert!(is_overflow(&r), "{r:?}");
    let col: Vec<f64> = (0..6).map(|i| big[(i, 0)]).collect();
    let binning = Binning {
        bins: 3,
        max_lag: MaxLag::Largest,
    };
    let r = EmpiricalVariogram::compute_binned(line(6).as_ref(), big.as_ref(), &binning);
    assert!(is_overflow(&r), "{r:?}");
    let r = EmpiricalVariogram::estimate(
        line(6).as_ref(),
        &col,
        &binning,
        &EstimateOptions::default(),
    );
    assert!(is_overflow(&r), "{r:?}");
}

#[test]
fn far_apart_or_nearly_equal_coordinates_are_overflow_not_duplicates() {
    let z = vals(6);
    let v = NestedVariogram::single(VariogramModel::Exponential, 0.0, 1.0, 3.0).unwrap();
    let cases = [
        Mat::from_fn(6, 1, |i, _| 1e300 * (i as f64 - 2.5)),
        Mat::from_fn(6, 1, |i, _| 1e-300 * i as f64),
        Mat::from_fn(6, 2, |i, k| 1e200 * [(i % 3) as f64, (i / 3) as f64][k]),
    ];
    for c in &cases {
        let r = Krige::new().variogram(v.clone()).fit(c.as_ref(), &z);
        assert!(is_overflow(&r), "{:?}", r.err());
    }
    let c = Mat::from_fn(6, 2, |i, k| [(i % 3) as f64, (i / 3) as f64][k]);
    let r = Krige::new()
        .variogram(v)
        .anisotropy(Anisotropy::TwoD {
            angle: 0.0,
            ratio: 1e-300,
        })
        .fit(c.as_ref(), &z);
    assert!(is_overflow(&r), "{:?}", r.err());
    // The motion front end without scaling: distances overflow.
    let cfg = KrigingConfig {
        model: ModelChoice::Fixed(VariogramModel::Exponential),
        scaling: ScalingChoice::None,
        ..KrigingConfig::default()
    };
    let r = Kriging::fit(cases[0].as_ref(), vcol(6).as_ref(), &cfg);
    assert!(is_overflow(&r), "{:?}", r.err());
    let r = EmpiricalVariogram::compute(cases[0].as_ref(), vcol(6).as_ref(), 3);
    assert!(is_overflow(&r), "{r:?}");
}

#[test]
fn standardising_huge_columns_is_overflow_not_constant() {
    let p = Mat::from_fn(
        4,
        2,
        |i, k| if k == 0 { i as f64 } else { 1e300 * i as f64 },
    );
    match ParamScaling::standardise(p.as_ref()) {
        Err(KrigingError::Overflow { what, .. }) => assert!(what.contains("column 1"), "{what}"),
        other => panic!("{other:?}"),
    }
    let r = Kriging::fit(p.as_ref(), vcol(4).as_ref(), &KrigingConfig::default());
    assert!(is_overflow(&r), "{:?}", r.err());
}

#[test]
fn subnormal_anisotropy_ratio_is_overflow() {
    let r = Anisotropy::TwoD {
        angle: 0.0,
        ratio: 1e-320,
    }
    .matrix(2);
    assert!(is_overflow(&r), "{r:?}");
    let r = Anisotropy::ThreeD {
        angles: [10.0, 20.0, 30.0],
        ratios: [0.5, 1e-320],
    }
    .matrix(3);
    assert!(is_overflow(&r), "{r:?}");
    assert!(
        Anisotropy::TwoD {
            angle: 0.0,
            ratio: 1e-300
        }
        .matrix(2)
        .is_ok()
    );
}

// --- 5. Public helpers: errors or documented panics ----------------------------------------------

#[test]
#[should_panic(expected = "variogram_column")]
fn variogram_column_with_a_long_output_panics_with_a_message() {
    let v = Variogram::new(VariogramModel::Linear, 0.0, 1.0, 0.0, 1.0).unwrap();
    let mut out = vec![0.0; 20];
    variogram_column(&v, &ParamScaling::none(2), &[0.0; 4], &[0.1, 0.2], &mut out);
}

#[test]
#[should_panic(expected = "held_out_squared_error")]
fn held_out_squared_error_with_mismatched_rows_panics_with_a_message() {
    let pred = Mat::<f64>::zeros(1, 1);
    let values = Mat::<f64>::zeros(3, 1);
    held_out_squared_error(pred.as_ref(), values.as_ref(), &[0, 1], None);
}

#[test]
#[should_panic(expected = "held_out_squared_error")]
fn held_out_squared_error_with_a_short_mask_panics_with_a_message() {
    let pred = Mat::<f64>::zeros(1, 2);
    let values = Mat::<f64>::zeros(3, 2);
    held_out_squared_error(pred.as_ref(), values.as_ref(), &[0], Some(&[true]));
}

#[test]
#[should_panic(expected = "ParamScaling::apply_rows")]
fn apply_rows_with_extra_columns_panics_with_a_message() {
    ParamScaling::none(1).apply_rows(Mat::<f64>::zeros(2, 3).as_ref());
}

#[test]
#[should_panic(expected = "sym_pinv needs a square matrix")]
fn sym_pinv_of_a_non_square_matrix_panics_with_a_message() {
    sym_pinv(Mat::<f64>::zeros(2, 3).as_ref());
}

#[test]
fn compress_columns_checks_the_energy_fraction() {
    for bad in [f64::NAN, -1.0, 2.0] {
        let r = std::panic::catch_unwind(|| compress_columns(vcol(5).as_ref(), bad));
        let msg = r.expect_err("a panic");
        let msg = msg.downcast_ref::<String>().expect("a formatted message");
        assert!(msg.contains("rel_energy"), "{msg}");
    }
    assert_eq!(compress_columns(vcol(5).as_ref(), 1e-6).ncols(), 1);
}

#[test]
fn drift_term_counts_saturate() {
    assert_eq!(Drift::Quadratic.n_terms(2), 6);
    assert_eq!(Drift::Quadratic.n_terms(3), 10);
    assert_eq!(Drift::Linear.n_terms(3), 4);
    assert_eq!(Drift::Quadratic.n_terms(usize::MAX), usize::MAX);
    assert_eq!(Drift::Linear.n_terms(usize::MAX), usize::MAX);
    let d: usize = 1 << 31;
    assert_eq!(Drift::Quadratic.n_terms(d), 1 + d + d / 2 * (d + 1));
    if usize::BITS == 64 {
        // d (d + 1) / 2 is about 2^65: it wrapped to 12884901889 before.
        assert_eq!(Drift::Quadratic.n_terms(1 << 33), usize::MAX);
    }
}

#[test]
fn fold_labels_beyond_the_samples_are_config_errors() {
    let p = Mat::from_fn(12, 2, |i, k| {
        if k == 0 {
            (i % 4) as f64
        } else {
            (i / 4) as f64 + 0.37 * (i % 3) as f64
        }
    });
    for big in [12, 1 << 40, usize::MAX] {
        let mut fold = vec![0, 1, 0, 1, 0, 1, 0, 1, 0, 1, 0, 1];
        fold[11] = big;
        let r = select_dims_by_folds(
            p.as_ref(),
            vcol(12).as_ref(),
            &KrigingConfig::default(),
            0.01,
            &fold,
            None,
        );
        match r {
            Err(KrigingError::InvalidConfig(m)) => assert!(m.contains(&big.to_string()), "{m}"),
            other => panic!("{:?}", other.err()),
        }
    }
}
