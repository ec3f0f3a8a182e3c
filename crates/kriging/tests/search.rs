//! The leave-one-out variogram search (`Selection::LooSearch`, the default).

use crate::common;

use common::*;
use faer::Mat;
use kriging::search::{SEARCH_COLUMNS, SEARCH_MODELS, SEARCH_NUGGETS, SEARCH_RANGES};
use kriging::*;

fn config(sel: Selection) -> KrigingConfig {
    KrigingConfig {
        model: ModelChoice::Auto(sel),
        bins: 10,
        ..KrigingConfig::default()
    }
}

/// `n` random controls in [0, 1]^2 and the smooth field plus independent noise of amplitude `noise`
/// (also returned without the noise).
fn noisy(n: usize, noise: f64, seed: u64) -> (Mat<f64>, Mat<f64>, Mat<f64>) {
    let (p, x) = data(n, 2, seed);
    let mut r = Rng(seed ^ 0x9e37_79b9);
    let xn: Vec<Vec<f64>> = x
        .iter()
        .map(|row| row.iter().map(|v| v + noise * (r.next() - 0.5)).collect())
        .collect();
    (to_mat(&p), to_mat(&xn), to_mat(&x))
}

fn loo_rmse(p: &Mat<f64>, x: &Mat<f64>, sel: Selection) -> (f64, Kriging) {
    let k = Kriging::fit(p.as_ref(), x.as_ref(), &config(sel)).unwrap();
    (k.leave_one_out().unwrap().rmse, k)
}

#[test]
fn search_is_the_default_and_never_worse_than_the_fitted_models() {
    assert_eq!(
        KrigingConfig::default().model,
        ModelChoice::Auto(Selection::LooSearch)
    );
    for seed in [3, 17, 99] {
        let (p, x, _) = noisy(40, 0.6, seed);
        // D = 3 <= SEARCH_COLUMNS: the search ranks on the values themselves, so its choice is the
        // best of a superset of BestLoo's candidates.
        let (fitted, _) = loo_rmse(&p, &x, Selection::BestLoo);
        let (searched, k) = loo_rmse(&p, &x, Selection::LooSearch);
        assert!(
            searched <= fitted + 1e-12,
            "seed {seed}: {searched} > {fitted}"
        );
        let n = VariogramModel::ALL.len()
            + SEARCH_MODELS.len() * SEARCH_RANGES.len() * SEARCH_NUGGETS.len();
        assert_eq!(k.candidates().len(), n);
        let best = k
            .candidates()
            .iter()
            .filter_map(|c| c.loo_rmse)
            .fold(f64::INFINITY, f64::min);
        assert!(
            (best - searched).abs() <= 1e-9 * best.max(1.0),
            "{best} vs {searched}"
        );
    }
}

#[test]
fn noisy_samples_get_a_nugget_and_predict_the_truth_better() {
    let (p, x, _) = noisy(60, 1.0, 7);
    let (_, fitted) = loo_rmse(&p, &x, Selection::BestLoo);
    let (_, searched) = loo_rmse(&p, &x, Selection::LooSearch);
    assert!(
        searched.variogram().nugget > 0.0,
        "{:?}",
        searched.variogram()
    );
    // Error against the noiseless field on a grid of new controls.
    let err = |k: &Kriging| {
        let mut sum = 0.0;
        let mut y = vec![0.0; 3];
        for i in 0..11 {
            for j in 0..11 {
                let c = [i as f64 / 10.0, j as f64 / 10.0];
                k.predict(&c, &mut y).unwrap();
                let f = field(&c);
                sum += (0..3).map(|d| (y[d] - f[d]).powi(2)).sum::<f64>();
            }
        }
        sum.sqrt()
    };
    assert!(
        err(&searched) < err(&fitted),
        "search {} against fitted {}",
        err(&searched),
        err(&fitted)
    );
}

#[test]
fn many_values_are_ranked_on_their_leading_columns() {
    // D = 200 > SEARCH_COLUMNS values of rank 3 (every column a mix of the three field outputs):
    // compression is exact, so the choice equals the search on the three outputs themselves.
    let (p, x, _) = noisy(30, 0.4, 11);
    let d = 200;
    assert!(d > SEARCH_COLUMNS);
    let wide = Mat::from_fn(30, d, |i, j| {
        let a = (j as f64 * 0.37).sin();
        let b = (j as f64 * 0.11).cos();
        a * x[(i, 0)] + b * x[(i, 1)] + (a - b) * x[(i, 2)]
    });
    let (_, narrow_fit) = loo_rmse(&p, &x, Selection::LooSearch);
    let (_, wide_fit) = loo_rmse(&p, &wide, Selection::LooSearch);
    let (vn, vw) = (narrow_fit.variogram(), wide_fit.variogram());
    assert_eq!((vn.model, vn.range), (vw.model, vw.range));
    assert!((vn.nugget / vn.sill - vw.nugget / vw.sill).abs() < 1e-9);
}

#[test]
fn the_choice_does_not_depend_on_the_thread_count() {
    let (p, x, _) = noisy(50, 0.5, 5);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let k = Kriging::fit(p.as_ref(), x.as_ref(), &config(Selection::LooSearch)).unwrap();
            let scores: Vec<Option<u64>> = k
                .candidates()
                .iter()
                .map(|c| c.loo_rmse.map(f64::to_bits))
                .collect();
            (*k.variogram(), scores)
        })
    };
    assert_eq!(run(1), run(2));
}

/// Beyond `SEARCH_SAMPLES` samples the shapes are ranked on an evenly strided subset
/// (`search::search_rows`) and the winner is installed on every sample: the fit interpolates all
/// of them, and it predicts held-out points of the smooth field as well as a search over the
/// subset alone predicts them.
#[test]
fn a_search_over_more_samples_than_it_ranks_on_installs_the_winner_on_all() {
    use kriging::search::{SEARCH_SAMPLES, search_rows};
    let n = SEARCH_SAMPLES + 200;
    let (p, x, _) = noisy(n, 0.0, 41);
    let all = Kriging::fit(p.as_ref(), x.as_ref(), &config(Selection::LooSearch)).unwrap();
    assert_eq!(all.n_samples(), n);
    let ranked = all
        .candidates()
        .iter()
        .filter(|c| c.loo_rmse.is_some())
        .count();
    assert!(ranked > 10, "{ranked} candidates ranked");
    // Installed on all samples: the system is (S + 1) square.
    assert_eq!(all.system_inverse().nrows(), n + 1);
    // The subset alone, searched the same way.
    let rows = search_rows(n);
    let pick = |m: &Mat<f64>| Mat::from_fn(rows.len(), m.ncols(), |i, k| m[(rows[i], k)]);
    let subset = Kriging::fit(
        pick(&p).as_ref(),
        pick(&x).as_ref(),
        &config(Selection::LooSearch),
    )
    .unwrap();
    let (q, truth, _) = noisy(50, 0.0, 97);
    let mut out = vec![0.0; x.ncols()];
    let mut err = |k: &Kriging| {
        let mut sq = 0.0;
        for i in 0..q.nrows() {
            let c: Vec<f64> = (0..q.ncols()).map(|j| q[(i, j)]).collect();
            k.predict(&c, &mut out).unwrap();
            sq += (0..out.len())
                .map(|j| (out[j] - truth[(i, j)]).powi(2))
                .sum::<f64>();
        }
        (sq / q.nrows() as f64).sqrt()
    };
    let (e_all, e_subset) = (err(&all), err(&subset));
    assert!(
        e_all <= e_subset * 1.05 + 1e-12,
        "all {e_all} against the subset's {e_subset}"
    );
}
