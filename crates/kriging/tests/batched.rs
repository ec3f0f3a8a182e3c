//! The batched paths a cross-validation over many samples and value columns takes: predictions of
//! many queries as matrix products (`Kriging::predict_rows`), held-out squared errors read column
//! by column (`held_out_squared_error`), value columns compressed to their leading directions
//! (`compress_columns`), and an empirical variogram over a subsample of a large set.

use kriging::faer::Mat;
use kriging::{
    Kriging, KrigingConfig, ModelChoice, Variogram, VariogramModel, compress_columns,
    held_out_squared_error,
};

/// `n` samples over 2 controls (a Halton-like spread) and `dv` values: smooth functions of the
/// controls plus a little per-sample wobble, in a subspace of `rank` directions.
fn data(n: usize, dv: usize, rank: usize) -> (Mat<f64>, Mat<f64>) {
    let h = |i: usize, b: usize| {
        let (mut f, mut r, mut k) = (1.0, 0.0, i + 1);
        while k > 0 {
            f /= b as f64;
            r += f * (k % b) as f64;
            k /= b;
        }
        r
    };
    let params = Mat::from_fn(n, 2, |i, k| h(i, [2, 3][k]));
    let basis = Mat::from_fn(rank, dv, |r, j| ((r + 1) as f64 * 0.37 * j as f64).sin());
    let latent = Mat::from_fn(n, rank, |i, r| {
        let (x, y) = (params[(i, 0)], params[(i, 1)]);
        ((r + 1) as f64 * x).sin() + (r as f64 * y).cos() * 0.5 + 0.05 * h(i, 5)
    });
    (params, &latent * &basis)
}

fn given() -> KrigingConfig {
    KrigingConfig {
        model: ModelChoice::Given(
            Variogram::new(VariogramModel::Gaussian, 0.01, 1.0, 1.5, 1.0).unwrap(),
        ),
        ..KrigingConfig::default()
    }
}

#[test]
fn predict_rows_agrees_with_predict_row_by_row() {
    let (params, values) = data(60, 300, 5);
    let k = Kriging::fit(params.as_ref(), values.as_ref(), &given()).unwrap();
    let queries = Mat::from_fn(17, 2, |i, c| 0.05 * i as f64 + 0.3 * c as f64);
    let batch = k.predict_rows(queries.as_ref()).unwrap();
    assert_eq!(batch.shape(), (17, 300));
    let mut one = vec![0.0; 300];
    let mut worst = 0.0f64;
    for i in 0..17 {
        k.predict(&[queries[(i, 0)], queries[(i, 1)]], &mut one)
            .unwrap();
        for j in 0..300 {
            worst = worst.max((one[j] - batch[(i, j)]).abs() / (1.0 + one[j].abs()));
        }
    }
    assert!(
        worst < 1e-12,
        "batched and single predictions differ by {worst:e}"
    );
}

#[test]
fn predict_rows_names_a_bad_query() {
    let (params, values) = data(20, 4, 2);
    let k = Kriging::fit(params.as_ref(), values.as_ref(), &given()).unwrap();
    let wrong = Mat::from_fn(3, 3, |_, _| 0.5);
    let err = k.predict_rows(wrong.as_ref()).unwrap_err().to_string();
    assert!(err.contains("query parameter length"), "{err}");
    let nan = Mat::from_fn(3, 2, |i, _| if i == 2 { f64::NAN } else { 0.5 });
    let err = k.predict_rows(nan.as_ref()).unwrap_err().to_string();
    assert!(err.contains("queries") && err.contains('2'), "{err}");
}

#[test]
fn held_out_squared_error_sums_the_scored_columns_of_the_held_out_rows() {
    let values = Mat::from_fn(5, 3, |i, j| (i * 3 + j) as f64);
    let test = [1, 4];
    let pred = Mat::from_fn(2, 3, |t, j| values[(test[t], j)] + (j + 1) as f64);
    // Errors 1, 2, 3 per column on both rows; column 1 not scored.
    let all = held_out_squared_error(pred.as_ref(), values.as_ref(), &test, None);
    assert_eq!(all, 2.0 * (1.0 + 4.0 + 9.0));
    let some = held_out_squared_error(
        pred.as_ref(),
        values.as_ref(),
        &test,
        Some(&[true, false, true]),
    );
    assert_eq!(some, 2.0 * (1.0 + 9.0));
}

/// Squared distances between rows and leave-one-out squared errors of compressed values agree
/// with the full values', on both sides of the Gram choice (more samples than columns and fewer).
#[test]
fn compressed_columns_keep_distances_and_cross_validated_errors() {
    for (n, dv) in [(40, 200), (120, 30)] {
        let (params, values) = data(n, dv, 6);
        let c = compress_columns(values.as_ref(), 1e-12);
        assert!(
            c.ncols() <= 6,
            "{n} x {dv}: kept {} columns of a rank-6 set",
            c.ncols()
        );
        let sq = |m: &Mat<f64>, a: usize, b: usize| {
            (0..m.ncols())
                .map(|j| (m[(a, j)] - m[(b, j)]).powi(2))
                .sum::<f64>()
        };
        for (a, b) in [(0, 1), (3, n - 1), (7, 20)] {
            let (full, small) = (sq(&values, a, b), sq(&c, a, b));
            assert!(
                (full - small).abs() <= 1e-8 * (1.0 + full),
                "{full} vs {small}"
            );
        }
        let loo = |v: &Mat<f64>| {
            let e = Kriging::fit(params.as_ref(), v.as_ref(), &given())
                .unwrap()
                .loo_errors()
                .unwrap();
            (0..e.nrows())
                .flat_map(|i| (0..e.ncols()).map(move |j| (i, j)))
                .map(|(i, j)| e[(i, j)].powi(2))
                .sum::<f64>()
        };
        let (full, small) = (loo(&values), loo(&c));
        assert!(
            (full - small).abs() <= 1e-8 * full,
            "{n} x {dv}: LOO {full} vs {small}"
        );
    }
    // A looser tolerance keeps fewer columns; zero values give one zero column.
    let (_, values) = data(50, 80, 6);
    assert!(compress_columns(values.as_ref(), 1e-2).ncols() < 6);
    let zero = compress_columns(Mat::<f64>::zeros(4, 9).as_ref(), 1e-6);
    assert_eq!(zero.shape(), (4, 1));
}

/// Above `SEARCH_SAMPLES` the variogram search estimates the empirical variogram on that many
/// evenly strided samples: its pair count is theirs, and the search still installs a variogram
/// that predicts the samples.
#[test]
fn empirical_variogram_of_a_large_set_is_estimated_on_a_subsample() {
    let n = kriging::search::SEARCH_SAMPLES + 300;
    let (params, values) = data(n, 3, 2);
    let k = Kriging::fit(params.as_ref(), values.as_ref(), &KrigingConfig::default()).unwrap();
    let emp = k
        .empirical()
        .expect("the search keeps its empirical variogram");
    let m = kriging::search::SEARCH_SAMPLES;
    assert_eq!(emp.counts.iter().sum::<usize>(), m * (m - 1) / 2);
    let mut out = [0.0; 3];
    k.predict(&[params[(5, 0)], params[(5, 1)]], &mut out)
        .unwrap();
    assert!((out[0] - values[(5, 0)]).abs() < 0.05 * (1.0 + values[(5, 0)].abs()));
}

/// Above `EAGER_INVERSE_MAX_SAMPLES` a fit keeps the LU factors: its dual coefficients (solved)
/// and its projections (`project_rows`, solved) agree with the inverse it forms when asked.
#[test]
fn large_systems_solve_with_their_factors_and_agree_with_the_inverse() {
    let n = kriging::EAGER_INVERSE_MAX_SAMPLES + 40;
    let (params, values) = data(n, 3, 2);
    let k = Kriging::fit(params.as_ref(), values.as_ref(), &given()).unwrap();
    // Ordinary-kriging weights from the inverse (formed now) against the dual form of ordinary
    // kriging over the same samples (the same system: the trend does not enter `A`).
    let c = [0.31, 0.57];
    let mut w = vec![0.0; n];
    k.weights(&c, &mut w).unwrap();
    assert!(
        (w.iter().sum::<f64>() - 1.0).abs() < 1e-9,
        "weights sum to one"
    );
    let mut by_dual = [0.0; 3];
    let trend_free = Kriging::fit(
        params.as_ref(),
        values.as_ref(),
        &KrigingConfig {
            method: kriging::Method::Ordinary,
            ..given()
        },
    )
    .unwrap();
    trend_free.predict(&c, &mut by_dual).unwrap();
    for j in 0..3 {
        let by_weights: f64 = (0..n).map(|i| w[i] * values[(i, j)]).sum();
        assert!(
            (by_weights - by_dual[j]).abs() < 1e-8 * (1.0 + by_weights.abs()),
            "value {j}: weights {by_weights} vs dual {}",
            by_dual[j]
        );
    }
    // U^t A^-1[:S, :] by the factors against the inverse.
    let u = Mat::from_fn(n, 2, |i, l| ((i * (l + 2)) % 13) as f64 - 6.0);
    let q = k.project_rows(u.as_ref()).unwrap();
    assert_eq!(q.shape(), (2, n + 1));
    let a = k.system_inverse();
    let mut worst = 0.0f64;
    for l in 0..2 {
        for j in [0, 1, n / 2, n] {
            let want: f64 = (0..n).map(|i| u[(i, l)] * a[(i, j)]).sum();
            worst = worst.max((want - q[(l, j)]).abs() / (1.0 + want.abs()));
        }
    }
    assert!(
        worst < 1e-8,
        "projection by the factors differs by {worst:e}"
    );
    let bad = Mat::<f64>::zeros(n - 1, 2);
    assert!(k.project_rows(bad.as_ref()).is_err());
}
