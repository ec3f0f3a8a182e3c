//! Leave-one-out search of the variogram's shape ([`crate::Selection::LooSearch`]).
//!
//! Fitting a model to the empirical variogram and keeping the one with the best leave-one-out error
//! ([`crate::Selection::BestLoo`]) only ranks the fitted shapes. When the residuals hold much variation
//! that the parameters do not explain (walking style in motion data), the fitted ranges come out tiny and
//! kriging degenerates to the trend plus spikes at the samples. The search also tries a fixed grid of
//! shapes, scaled to the data, and keeps whichever predicts the held-out samples best:
//!
//! - models [`SEARCH_MODELS`] (bounded: spherical, exponential, gaussian);
//! - ranges `f h_mean` for `f` in [`SEARCH_RANGES`], `h_mean` the mean distance between samples in
//!   scaled parameter space;
//! - nuggets `g s` for `g` in [`SEARCH_NUGGETS`], `s` the partial sill, set to the mean semi-variance
//!   of the empirical variogram (the weights do not depend on the variogram's scale, only on its shape
//!   and the nugget-to-sill ratio; the scale only makes the reported variogram readable).
//!
//! A nugget acts as independent noise on each sample: the predictor then smooths instead of
//! interpolating, which is what noisy samples need.
//!
//! Cost: every candidate needs its own `(S+1)` inverse (candidates are scored in parallel). The values enter the leave-one-out error
//! linearly, so candidates are ranked on the values compressed to their [`SEARCH_COLUMNS`] leading
//! principal columns (`X V_k`, exact when `X` has at most that rank), which keeps each candidate at
//! about one inverse whatever the number of values; and on at most [`SEARCH_SAMPLES`] samples
//! ([`search_rows`]), which keeps the search's cost the same beyond that many samples (the
//! winner is installed on all of them: one inverse of the full system). The empirical variogram
//! that starts each candidate's fit is binned over the pairs of the same samples.
//!
//! ```
//! use kriging::faer::Mat;
//! use kriging::search::{SEARCH_MODELS, SEARCH_NUGGETS, SEARCH_RANGES};
//! use kriging::{Kriging, KrigingConfig, ModelChoice, Selection};
//!
//! // 60 samples of a smooth surface plus noise that the parameters do not explain.
//! let params = Mat::from_fn(60, 2, |i, k| ((i * (7 + 4 * k) + 3 * k) % 60) as f64 / 59.0);
//! let noise = |i: usize| ((i * 37 % 11) as f64 - 5.0) * 0.02;
//! let values = Mat::from_fn(60, 1, |i, _| {
//!     (3.0 * params[(i, 0)]).sin() + params[(i, 1)] * params[(i, 1)] + noise(i)
//! });
//! // The search (the motion model's default) against the best fit to the empirical variogram.
//! let searched = Kriging::fit(params.as_ref(), values.as_ref(), &KrigingConfig::motion())?;
//! let fitted = KrigingConfig { model: ModelChoice::Auto(Selection::BestFit), ..KrigingConfig::motion() };
//! let fitted = Kriging::fit(params.as_ref(), values.as_ref(), &fitted)?;
//! // The search keeps whichever shape predicts the left-out samples best, fitted ones included.
//! let (s, f) = (searched.leave_one_out()?.rmse, fitted.leave_one_out()?.rmse);
//! assert!(s <= f + 1e-12, "search {s} against fit {f}");
//! assert_eq!(SEARCH_MODELS.len() * SEARCH_RANGES.len() * SEARCH_NUGGETS.len(), 75); // the grid
//! # Ok::<(), kriging::KrigingError>(())
//! ```

use faer::{Mat, MatRef};
use rayon::prelude::*;

use crate::config::{CandidateReport, KrigingConfig, ModelChoice};
use crate::empirical::{EmpiricalVariogram, PairDistances};
use crate::error::KrigingError;
use crate::fit::{FitOptions, fit_variogram};
use crate::kriging::Kriging;
use crate::variogram::{Variogram, VariogramModel};

/// Models of the grid (bounded ones: their range is the shape parameter searched).
pub const SEARCH_MODELS: [VariogramModel; 3] = [
    VariogramModel::Spherical,
    VariogramModel::Exponential,
    VariogramModel::Gaussian,
];
/// Ranges of the grid, in units of the mean distance between samples.
pub const SEARCH_RANGES: [f64; 5] = [0.5, 1.0, 2.0, 4.0, 8.0];
/// Nugget-to-sill ratios of the grid.
pub const SEARCH_NUGGETS: [f64; 5] = [0.0, 0.03, 0.1, 0.3, 1.0];
/// Principal columns of the values on which candidates are ranked.
pub const SEARCH_COLUMNS: usize = 48;
/// Most samples candidates are ranked on: beyond it, on this many evenly strided samples
/// ([`search_rows`]), so that the search costs the same whatever the sample count (each candidate's
/// leave-one-out needs its own `(S + 1)` inverse, `S^3` work); the winner is then installed on all
/// samples.
pub const SEARCH_SAMPLES: usize = 1000;

/// The samples candidates are ranked on: all of `s` up to [`SEARCH_SAMPLES`], else
/// [`SEARCH_SAMPLES`] of them evenly strided (`floor(k s / SEARCH_SAMPLES)`), which keeps the
/// spread of a set whose samples come in order (takes, performers).
pub fn search_rows(s: usize) -> Vec<usize> {
    if s <= SEARCH_SAMPLES {
        (0..s).collect()
    } else {
        (0..SEARCH_SAMPLES)
            .map(|k| k * s / SEARCH_SAMPLES)
            .collect()
    }
}

/// `X V_k`: the values (S x D) projected on their `k` leading right singular vectors
/// ([`crate::linalg::leading_columns`]). Returned unchanged when `D <= k`.
pub(crate) fn compress(values: MatRef<'_, f64>, k: usize) -> Mat<f64> {
    if values.ncols() <= k {
        return values.to_owned();
    }
    crate::linalg::leading_columns(values, |_| k)
}

/// Mean distance between distinct samples.
fn mean_distance(dist: &PairDistances, s: usize) -> f64 {
    let mut sum = 0.0;
    for i in 0..s {
        for j in i + 1..s {
            sum += dist.get(i, j);
        }
    }
    sum / (s * (s - 1) / 2).max(1) as f64
}

/// Every model of [`VariogramModel::ALL`] fitted to `emp` (not yet scored); a failed fit keeps its
/// error.
pub(crate) fn fitted_candidates(
    emp: &EmpiricalVariogram,
    opts: &FitOptions,
) -> Vec<CandidateReport> {
    let mut out = Vec::new();
    for m in VariogramModel::ALL {
        let mut rep = CandidateReport {
            model: m,
            variogram: None,
            wsse: None,
            loo_rmse: None,
            error: None,
            bounds: None,
        };
        match fit_variogram(emp, m, opts) {
            Ok(f) => {
                rep.variogram = Some(f.variogram);
                rep.wsse = Some(f.wsse);
                rep.bounds = Some(f.bounds);
            }
            Err(e) => rep.error = Some(e.to_string()),
        }
        out.push(rep);
    }
    out
}

/// Every candidate variogram: the models fitted to `emp` ([`fitted_candidates`]), then the grid.
pub(crate) fn candidates(
    emp: &EmpiricalVariogram,
    dist: &PairDistances,
    s: usize,
    opts: &FitOptions,
) -> Vec<CandidateReport> {
    let mut out = fitted_candidates(emp, opts);
    let (sum, n) = emp
        .gamma
        .iter()
        .zip(&emp.counts)
        .filter(|(_, c)| **c > 0)
        .fold((0.0, 0usize), |(s, n), (g, _)| (s + g, n + 1));
    let h = mean_distance(dist, s);
    if !(n > 0 && sum > 0.0 && sum.is_finite() && h.is_finite() && h > 0.0) {
        // Residuals without variation (or samples without spread): no shape to search, and no
        // model fits either, which `Kriging::fit` reports.
        return out;
    }
    let sill = sum / n as f64;
    for model in SEARCH_MODELS {
        for f in SEARCH_RANGES {
            for g in SEARCH_NUGGETS {
                out.push(CandidateReport {
                    model,
                    variogram: Some(Variogram {
                        model,
                        nugget: g * sill,
                        sill,
                        range: f * h,
                        exponent: 1.0,
                    }),
                    wsse: None,
                    loo_rmse: None,
                    error: None,
                    bounds: None,
                });
            }
        }
    }
    out
}

/// Ranks `candidates` by leave-one-out RMSE of kriging with each variogram on `probe` values (filled in
/// place) and returns their indices, best first (ties to the earlier candidate); failed candidates
/// get their error and are left out.
pub(crate) fn rank(
    params: MatRef<'_, f64>,
    probe: MatRef<'_, f64>,
    config: &KrigingConfig,
    candidates: &mut [CandidateReport],
) -> Vec<usize> {
    // Candidates are independent: score them in parallel (each on one thread, so the scores are the
    // same for any pool size).
    candidates.par_iter_mut().for_each(|rep| {
        let Some(v) = rep.variogram else { return };
        let given = KrigingConfig {
            model: ModelChoice::Given(v),
            ..config.clone()
        };
        let score: Result<f64, KrigingError> =
            Kriging::fit(params, probe, &given).and_then(|k| Ok(k.leave_one_out()?.rmse));
        match score {
            Ok(r) if r.is_finite() => rep.loo_rmse = Some(r),
            Ok(r) => rep.error = Some(format!("non-finite leave-one-out error {r}")),
            Err(e) => rep.error = Some(e.to_string()),
        }
    });
    let mut order: Vec<usize> = (0..candidates.len())
        .filter(|&i| candidates[i].loo_rmse.is_some())
        .collect();
    order.sort_by(|&a, &b| {
        let (ra, rb) = (candidates[a].loo_rmse, candidates[b].loo_rmse);
        ra.unwrap_or(f64::INFINITY)
            .total_cmp(&rb.unwrap_or(f64::INFINITY))
            .then(a.cmp(&b))
    });
    order
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_search_rows_are_all_samples_up_to_the_limit_then_evenly_strided() {
        assert_eq!(search_rows(5), vec![0, 1, 2, 3, 4]);
        assert_eq!(search_rows(SEARCH_SAMPLES).len(), SEARCH_SAMPLES);
        for s in [SEARCH_SAMPLES + 1, 2 * SEARCH_SAMPLES + 7, 10_000] {
            let rows = search_rows(s);
            assert_eq!(rows.len(), SEARCH_SAMPLES);
            assert_eq!(rows[0], 0);
            assert!(rows.windows(2).all(|w| w[0] < w[1]), "increasing");
            assert!(*rows.last().unwrap() < s);
            // Even: consecutive picks are floor(s / limit) or one more apart.
            let step = s / SEARCH_SAMPLES;
            assert!(
                rows.windows(2)
                    .all(|w| w[1] - w[0] == step || w[1] - w[0] == step + 1)
            );
        }
    }
}
