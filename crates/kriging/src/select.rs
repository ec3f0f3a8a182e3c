//! Which parameter dimensions carry signal: forward selection by leave-one-out error
//! ([`select_dims`]), or backward elimination by cross-validation over given folds
//! ([`select_dims_by_folds`]).
//!
//! A dimension that varies over the samples only by noise (a control that the data set holds nearly
//! constant, measured with jitter) still tilts the regression-kriging trend and stretches the distances:
//! predictions then change with it although the data cannot say how. [`select_dims`] drops such
//! dimensions the way a constant one is dropped (scale 0: out of the trend and out of the distances).
//!
//! The rule (forward selection). For a set of dimensions `D`, fit the kriging on `D` (each fit
//! chooses its own variogram as [`Kriging::fit`] does; above [`TRIAL_SEARCH_MAX_SAMPLES`] samples
//! the trials reuse the variogram chosen on every dimension, and the dimensions finally kept get their
//! own search) and take its leave-one-out errors
//! ([`Kriging::loo_errors`]) over the scored value columns: `e_i(D)^2` per sample and `E(D)` their root
//! mean. Start with the single dimension that predicts best (kriging needs one). Adding a dimension `k`
//! lowers the squared error of sample `i` by `r_i = e_i(D)^2 - e_i(D + k)^2`; its significance is the
//! paired t statistic `t = mean(r) / (sd(r) / sqrt(S))`. Dimension `k` carries signal when adding it
//! lowers the error both beyond noise (`t >= min_t`) and by more than a relative margin
//! (`E(D) > (1 + margin) E(D + k)`). Of the dimensions with signal, the one giving the smallest error
//! is added, and the test repeats on the others until none has signal. A control must earn its place:
//! with few samples a real but weak effect is dropped rather than a noisy one kept, which is the
//! failure this guards against (a trend tilted by noise).
//!
//! The other rule (backward elimination, [`select_dims_by_folds`]) turns the burden around: every
//! varying dimension stays unless dropping it lowers the error of a cross-validation over folds the
//! caller gives (whole groups of samples held out together) by more than a margin. Leave-one-out
//! favours dropping a dimension along which neighbouring samples of one group agree anyway; held-out
//! groups show whether the dimension predicts new ones.

use faer::MatRef;
use serde::{Deserialize, Serialize};

use crate::config::{KrigingConfig, ModelChoice};
use crate::error::KrigingError;
use crate::kriging::Kriging;
use crate::scaling::{ParamScaling, ScalingChoice};

/// What [`select_dims`] decided for one parameter dimension.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum DimDecision {
    /// Constant over the samples: dropped by the scaling itself.
    Constant,
    /// Kept: adding it lowered the leave-one-out error beyond noise and beyond the margin (or it is
    /// the first dimension, which kriging needs).
    Kept {
        /// Leave-one-out RMSE once it was added.
        loo_with: f64,
        /// Leave-one-out RMSE before (infinite for the first dimension).
        loo_without: f64,
        /// Paired t statistic of the fall in per-sample squared error (infinite for the first).
        t: f64,
    },
    /// Dropped: adding it to the kept dimensions did not lower the leave-one-out error beyond noise
    /// or beyond the margin.
    NoSignal {
        /// Leave-one-out RMSE with it added to the kept dimensions (infinite when that fit failed).
        loo_with: f64,
        /// Leave-one-out RMSE of the kept dimensions.
        loo_without: f64,
        /// Paired t statistic of the fall in per-sample squared error with it.
        t: f64,
    },
    /// Kept by [`select_dims_by_folds`]: dropping it from the kept dimensions does not lower the
    /// cross-validated error by more than the margin.
    KeptByFolds {
        /// Cross-validated RMSE of the kept dimensions.
        cv_with: f64,
        /// Cross-validated RMSE without it (infinite when it is the only dimension kept, or when
        /// that fit failed).
        cv_without: f64,
        /// Folds of the cross-validation.
        folds: usize,
    },
    /// Dropped by [`select_dims_by_folds`]: dropping it lowered the cross-validated error by more
    /// than the margin.
    DroppedByFolds {
        /// Cross-validated RMSE of the dimensions kept before it was dropped (it among them).
        cv_with: f64,
        /// Cross-validated RMSE once it was dropped.
        cv_without: f64,
        /// Folds of the cross-validation.
        folds: usize,
    },
    /// Kept by [`select_dims_by_folds`] (the figures of [`DimDecision::KeptByFolds`]), then dropped
    /// by the caller's own check of the fitted model (in `motion-lod`: walks that fail its
    /// motion-quality thresholds with the dimension in). This crate never decides it.
    Overruled {
        /// Cross-validated RMSE of the dimensions the cross-validation kept.
        cv_with: f64,
        /// Cross-validated RMSE without this one.
        cv_without: f64,
        /// Folds of the cross-validation.
        folds: usize,
    },
}

impl DimDecision {
    /// True when the dimension is out of the model (constant, no signal, dropped by the
    /// cross-validation or overruled).
    pub fn dropped(&self) -> bool {
        !matches!(
            self,
            DimDecision::Kept { .. } | DimDecision::KeptByFolds { .. }
        )
    }
}

/// The thresholds of [`select_dims`] (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SelectRule {
    /// Relative rise of the leave-one-out RMSE a dimension must cause when removed (`>= 0`).
    pub margin: f64,
    /// Paired t statistic the rise must reach (`>= 0`; 2 is about 97.5% one-sided).
    pub min_t: f64,
}

/// The result of [`select_dims`].
#[derive(Debug, Clone)]
pub struct DimSelection {
    /// The kriging fitted on the kept dimensions (dropped ones have scale 0).
    pub kriging: Kriging,
    /// One decision per parameter dimension.
    pub decisions: Vec<DimDecision>,
    /// The error the selection compared, of `kriging`'s dimensions: the leave-one-out RMSE of
    /// `kriging` over the scored columns ([`select_dims`]), or their RMSE over the held-out folds
    /// ([`select_dims_by_folds`]).
    pub rmse: f64,
}

/// Up to this many samples every trial of [`select_dims`] chooses its own variogram; above, the
/// trials reuse the one chosen on every dimension (at 800 samples a search per trial made the
/// selection 70 s of a motion model's build).
pub const TRIAL_SEARCH_MAX_SAMPLES: usize = 256;

/// A fitted kriging with its per-sample squared leave-one-out errors.
type Fitted = (Kriging, Vec<f64>);

/// Per-sample squared leave-one-out error of `k` over the scored columns.
fn sample_errors(k: &Kriging, scored: Option<&[bool]>) -> Result<Vec<f64>, KrigingError> {
    let e = k.loo_errors()?;
    Ok((0..e.nrows())
        .map(|i| {
            (0..e.ncols())
                .filter(|&j| scored.is_none_or(|m| m[j]))
                .map(|j| e[(i, j)] * e[(i, j)])
                .sum()
        })
        .collect())
}

/// The mask of scored value columns, when given, has one entry per column and scores one at least.
fn check_scored(scored: Option<&[bool]>, columns: usize) -> Result<(), KrigingError> {
    let Some(mask) = scored else {
        return Ok(());
    };
    if mask.len() != columns {
        return Err(KrigingError::ShapeMismatch {
            what: "scored columns vs value columns",
            expected: columns,
            got: mask.len(),
        });
    }
    if !mask.iter().any(|&m| m) {
        return Err(KrigingError::InvalidConfig(
            "dimension selection scores no value column".into(),
        ));
    }
    Ok(())
}

fn rmse(sq: &[f64]) -> f64 {
    (sq.iter().sum::<f64>() / sq.len().max(1) as f64).sqrt()
}

/// Paired t statistic of `without - with` (infinite when the differences are all equal and
/// positive, 0 when all equal and not positive).
fn paired_t(with: &[f64], without: &[f64]) -> f64 {
    let n = with.len() as f64;
    let r: Vec<f64> = without.iter().zip(with).map(|(a, b)| a - b).collect();
    let mean = r.iter().sum::<f64>() / n;
    let var = r.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    let se = (var / n).sqrt();
    if se > 0.0 {
        mean / se
    } else if mean > 0.0 {
        f64::INFINITY
    } else {
        0.0
    }
}

/// Fits `params` (S x d) to `values` (S x D) with `config` and drops the dimensions that carry no
/// signal by `rule` (see the module documentation). The leave-one-out error is measured over the value
/// columns `scored` marks (all when `None`): a caller leaves out the columns that a parameter measures
/// by construction, whose prediction it trivially improves. The scaling of the kept dimensions is the
/// one `config.scaling` gives; the returned kriging uses it as [`ScalingChoice::Given`].
///
/// Errors: those of [`Kriging::fit`] on all dimensions, a negative or non-finite threshold, a mask of
/// the wrong length or scoring nothing. A fit without some dimension that fails (e.g. duplicate
/// points) only means that dimension is kept. Deterministic.
///
/// ```
/// use kriging::faer::Mat;
/// use kriging::{select_dims, KrigingConfig, SelectRule};
///
/// // 40 samples over 2 parameters: the values depend on the first only; the second is jitter.
/// let halton = |i: usize, b: usize| {
///     let (mut f, mut r, mut n) = (1.0, 0.0, i + 1);
///     while n > 0 { f /= b as f64; r += f * (n % b) as f64; n /= b; }
///     r
/// };
/// let params = Mat::from_fn(40, 2, |i, k| if k == 0 { halton(i, 2) } else { 0.01 * halton(i, 3) });
/// let values = Mat::from_fn(40, 1, |i, _| (4.0 * params[(i, 0)]).sin());
/// let rule = SelectRule { margin: 0.05, min_t: 2.0 };
/// let sel = select_dims(params.as_ref(), values.as_ref(), &KrigingConfig::default(), rule, None)?;
/// assert!(!sel.decisions[0].dropped());
/// assert!(sel.decisions[1].dropped());
/// assert_eq!(sel.kriging.dropped_dims(), [1]);
/// # Ok::<(), kriging::KrigingError>(())
/// ```
pub fn select_dims(
    params: MatRef<'_, f64>,
    values: MatRef<'_, f64>,
    config: &KrigingConfig,
    rule: SelectRule,
    scored: Option<&[bool]>,
) -> Result<DimSelection, KrigingError> {
    for (what, v) in [("margin", rule.margin), ("min_t", rule.min_t)] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(KrigingError::InvalidConfig(format!(
                "dimension selection {what} {v} must be finite and >= 0"
            )));
        }
    }
    crate::kriging::check_inputs(params, values)?;
    check_scored(scored, values.ncols())?;
    let base = ParamScaling::from_choice(&config.scaling, params)?;
    // `model`: the variogram choice of the fit (the caller's for the fits that are kept, the one
    // chosen on every dimension for the trials).
    let fit_with = |scaling: &ParamScaling, model: &ModelChoice| -> Result<Fitted, KrigingError> {
        let cfg = KrigingConfig {
            scaling: ScalingChoice::Given(scaling.clone()),
            model: *model,
            ..config.clone()
        };
        let k = Kriging::fit(params, values, &cfg)?;
        let e = sample_errors(&k, scored)?;
        Ok((k, e))
    };
    // One variogram search on every dimension. With many samples the trials reuse its variogram, so
    // that each costs one kriging solve instead of a search over every candidate; with few, each
    // trial searches its own (cheap there, and closer to the fit that will be kept).
    let all_dims = fit_with(&base, &config.model)?;
    let trial_model = if params.nrows() > TRIAL_SEARCH_MAX_SAMPLES {
        ModelChoice::Given(*all_dims.0.variogram())
    } else {
        config.model
    };
    let fit = |scaling: &ParamScaling| fit_with(scaling, &trial_model);
    let d = base.dims();
    let mut decisions: Vec<Option<DimDecision>> = (0..d)
        .map(|k| (base.scale[k] == 0.0).then_some(DimDecision::Constant))
        .collect();
    // The scaling with only the dimensions in `on`.
    let only = |on: &[usize]| {
        let mut s = base.clone();
        for (k, v) in s.scale.iter_mut().enumerate() {
            if !on.contains(&k) {
                *v = 0.0;
            }
        }
        s
    };
    let mut chosen: Vec<usize> = Vec::new();
    let mut current: Option<Fitted> = None;
    loop {
        let remaining: Vec<usize> = (0..d).filter(|&k| decisions[k].is_none()).collect();
        if remaining.is_empty() {
            break;
        }
        // (dimension, fit with it added, its RMSE, t of the fall in error) per remaining dimension.
        let mut trials: Vec<(usize, Option<Fitted>, f64, f64)> = Vec::new();
        for &k in &remaining {
            let mut on = chosen.clone();
            on.push(k);
            match fit(&only(&on)) {
                Ok((kr, e)) => {
                    let loo = rmse(&e);
                    let t = current
                        .as_ref()
                        .map_or(f64::INFINITY, |(_, cur)| paired_t(&e, cur));
                    trials.push((k, Some((kr, e)), loo, t));
                }
                Err(_) => trials.push((k, None, f64::INFINITY, 0.0)),
            }
        }
        let loo_without = current.as_ref().map_or(f64::INFINITY, |(_, e)| rmse(e));
        let signal = |loo: f64, t: f64| t >= rule.min_t && loo_without > loo * (1.0 + rule.margin);
        // Of the dimensions with signal, the one that predicts best (ties: the lowest).
        let best = trials
            .iter()
            .enumerate()
            .filter(|(_, (_, f, loo, t))| f.is_some() && signal(*loo, *t))
            .min_by(|a, b| a.1.2.total_cmp(&b.1.2))
            .map(|(i, _)| i);
        match best {
            Some(i) => {
                let (k, trial, loo_with, t) = trials.swap_remove(i);
                decisions[k] = Some(DimDecision::Kept {
                    loo_with,
                    loo_without,
                    t,
                });
                chosen.push(k);
                current = trial;
            }
            None => {
                for (k, _, loo_with, t) in trials {
                    decisions[k] = Some(DimDecision::NoSignal {
                        loo_with,
                        loo_without,
                        t,
                    });
                }
                break;
            }
        }
    }
    let varying = (0..d).filter(|&k| base.scale[k] != 0.0).count();
    let (current, current_err) = match current {
        // Every varying dimension kept: the search on all of them is the fit.
        Some(_) if chosen.len() == varying => all_dims,
        // The kept dimensions get their own variogram search.
        Some(_) => fit_with(&only(&chosen), &config.model)?,
        // No dimension could be fitted alone: fall back to every non-constant one.
        None => {
            let (kr, e) = all_dims;
            for (k, dec) in decisions.iter_mut().enumerate() {
                if base.scale[k] != 0.0 {
                    *dec = Some(DimDecision::Kept {
                        loo_with: rmse(&e),
                        loo_without: f64::INFINITY,
                        t: f64::INFINITY,
                    });
                }
            }
            (kr, e)
        }
    };
    Ok(DimSelection {
        kriging: current,
        decisions: decisions
            .into_iter()
            .map(|d| d.expect("every dimension decided"))
            .collect(),
        rmse: rmse(&current_err),
    })
}

/// Fits `params` (S x d) to `values` (S x D) with `config` and keeps every varying dimension unless
/// dropping it lowers the cross-validated error by more than `margin` (relative): backward
/// elimination by held-out error.
///
/// `fold[i]` is the fold of sample `i` (`0..folds`, each fold non-empty: a caller that holds whole
/// groups out together, e.g. the takes of a motion capture, says so here). The error `E(D)` of a set
/// of dimensions `D` is the root mean square, over every held-out sample and the value columns
/// `scored` marks (all when `None`), of the prediction of each fold by a kriging refitted on the
/// other folds with the dimensions `D` (the scaling of `config.scaling`, the others at scale 0) and
/// the variogram chosen once on every dimension and every sample. Starting from every varying
/// dimension, the dimension `k` whose dropping gives the smallest `E(D - k)` is dropped while
/// `E(D) > (1 + margin) E(D - k)`, down to one dimension (kriging needs one); a trial whose fits
/// fail counts as infinite error. The returned kriging is the fit on the dimensions kept with its
/// own variogram search (the search on every dimension when all are kept), with
/// [`ScalingChoice::Given`] as in [`select_dims`]. Unlike [`select_dims`], a dimension stays
/// unless the data show that it hurts: the rule never does worse than keeping every dimension on
/// the error it measures.
///
/// Errors: those of [`Kriging::fit`] on all dimensions, a negative or non-finite margin, a fold
/// vector of the wrong length, fewer than 2 folds or an empty fold, a mask of the wrong length or
/// scoring nothing. Deterministic (trials run in parallel, their results are taken in dimension
/// order).
///
/// ```
/// use kriging::faer::Mat;
/// use kriging::{select_dims_by_folds, KrigingConfig};
///
/// // 40 samples over 2 parameters: the values depend on the first only; the second is noise.
/// let halton = |i: usize, b: usize| {
///     let (mut f, mut r, mut n) = (1.0, 0.0, i + 1);
///     while n > 0 { f /= b as f64; r += f * (n % b) as f64; n /= b; }
///     r
/// };
/// let params = Mat::from_fn(40, 2, |i, k| if k == 0 { halton(i, 2) } else { halton(i, 3) });
/// let values = Mat::from_fn(40, 1, |i, _| (4.0 * params[(i, 0)]).sin() + 0.3 * (halton(i, 5) - 0.5));
/// let fold: Vec<usize> = (0..40).map(|i| i % 5).collect();
/// let sel = select_dims_by_folds(params.as_ref(), values.as_ref(), &KrigingConfig::default(), 0.01, &fold, None)?;
/// assert!(!sel.decisions[0].dropped());
/// # Ok::<(), kriging::KrigingError>(())
/// ```
pub fn select_dims_by_folds(
    params: MatRef<'_, f64>,
    values: MatRef<'_, f64>,
    config: &KrigingConfig,
    margin: f64,
    fold: &[usize],
    scored: Option<&[bool]>,
) -> Result<DimSelection, KrigingError> {
    use rayon::prelude::*;
    if !(margin.is_finite() && margin >= 0.0) {
        return Err(KrigingError::InvalidConfig(format!(
            "dimension selection margin {margin} must be finite and >= 0"
        )));
    }
    crate::kriging::check_inputs(params, values)?;
    let s = params.nrows();
    if fold.len() != s {
        return Err(KrigingError::ShapeMismatch {
            what: "folds vs samples",
            expected: s,
            got: fold.len(),
        });
    }
    // A label of at least `s` leaves a fold empty (and `usize::MAX + 1` would wrap).
    if let Some(&big) = fold.iter().find(|&&f| f >= s) {
        return Err(KrigingError::InvalidConfig(format!(
            "cross-validation folds are labelled 0..folds with folds at most the {s} samples, \
             got the label {big}"
        )));
    }
    let folds = fold.iter().max().map_or(0, |&f| f + 1);
    if folds < 2 || (0..folds).any(|f| !fold.contains(&f)) {
        return Err(KrigingError::InvalidConfig(format!(
            "cross-validation needs at least 2 folds, each with a sample (got {folds} folds)"
        )));
    }
    check_scored(scored, values.ncols())?;
    let base = ParamScaling::from_choice(&config.scaling, params)?;
    let with_scaling = |scaling: &ParamScaling, model: &ModelChoice| KrigingConfig {
        scaling: ScalingChoice::Given(scaling.clone()),
        model: *model,
        ..config.clone()
    };
    let all_dims = Kriging::fit(params, values, &with_scaling(&base, &config.model))?;
    let trial_model = ModelChoice::Given(*all_dims.variogram());
    let d = base.dims();
    let only = |on: &[usize]| {
        let mut sc = base.clone();
        for (k, v) in sc.scale.iter_mut().enumerate() {
            if !on.contains(&k) {
                *v = 0.0;
            }
        }
        sc
    };
    // The held-out RMSE of the dimensions `on` (infinite when a fold's fit fails).
    let rows = |idx: &[usize], m: MatRef<'_, f64>| crate::linalg::select_rows(m, idx);
    let cv = |on: &[usize]| -> f64 {
        let cfg = with_scaling(&only(on), &trial_model);
        let per_fold: Vec<Option<(f64, usize)>> = (0..folds)
            .into_par_iter()
            .map(|f| {
                let (test, train): (Vec<usize>, Vec<usize>) = (0..s).partition(|&i| fold[i] == f);
                let k = Kriging::fit(
                    rows(&train, params).as_ref(),
                    rows(&train, values).as_ref(),
                    &cfg,
                )
                .ok()?;
                let pred = k.predict_rows(rows(&test, params).as_ref()).ok()?;
                let sq = held_out_squared_error(pred.as_ref(), values, &test, scored);
                Some((sq, test.len()))
            })
            .collect();
        let (mut sq, mut n) = (0.0, 0usize);
        for r in per_fold {
            match r {
                Some((e, m)) => {
                    sq += e;
                    n += m;
                }
                None => return f64::INFINITY,
            }
        }
        let e = (sq / n.max(1) as f64).sqrt();
        if e.is_finite() { e } else { f64::INFINITY }
    };
    let mut decisions: Vec<Option<DimDecision>> = (0..d)
        .map(|k| (base.scale[k] == 0.0).then_some(DimDecision::Constant))
        .collect();
    let mut kept: Vec<usize> = (0..d).filter(|&k| base.scale[k] != 0.0).collect();
    let mut current = cv(&kept);
    // The error without each kept dimension, from the last round.
    let mut without: Vec<(usize, f64)> = Vec::new();
    while !kept.is_empty() {
        without = if kept.len() == 1 {
            vec![(kept[0], f64::INFINITY)]
        } else {
            kept.par_iter()
                .map(|&k| {
                    let on: Vec<usize> = kept.iter().copied().filter(|&j| j != k).collect();
                    (k, cv(&on))
                })
                .collect()
        };
        // The dimension whose dropping lowers the error most (ties: the lowest index).
        let best = without
            .iter()
            .copied()
            .filter(|&(_, e)| e.is_finite())
            .min_by(|a, b| a.1.total_cmp(&b.1));
        match best {
            Some((k, e)) if current > (1.0 + margin) * e => {
                decisions[k] = Some(DimDecision::DroppedByFolds {
                    cv_with: current,
                    cv_without: e,
                    folds,
                });
                kept.retain(|&j| j != k);
                current = e;
            }
            _ => break,
        }
    }
    for (k, e) in without {
        if kept.contains(&k) {
            decisions[k] = Some(DimDecision::KeptByFolds {
                cv_with: current,
                cv_without: e,
                folds,
            });
        }
    }
    let varying = (0..d).filter(|&k| base.scale[k] != 0.0).count();
    let kriging = if kept.len() == varying {
        all_dims
    } else {
        Kriging::fit(params, values, &with_scaling(&only(&kept), &config.model))?
    };
    Ok(DimSelection {
        kriging,
        decisions: decisions
            .into_iter()
            .map(|d| d.expect("every dimension decided"))
            .collect(),
        rmse: current,
    })
}

/// The squared error, summed over the held-out samples `test` and the value columns `scored`
/// marks (all when `None`), of `pred` (one row per held-out sample, in `test`'s order) against
/// `values` (S x D). Column by column, so that the column-major values are read in runs.
///
/// # Panics
///
/// When the shapes do not fit together: `pred` must have one row per entry of `test` and a
/// column for every scored value column, every entry of `test` must be a row of `values`, and
/// `scored` (when given) must have an entry for every value column.
pub fn held_out_squared_error(
    pred: MatRef<'_, f64>,
    values: MatRef<'_, f64>,
    test: &[usize],
    scored: Option<&[bool]>,
) -> f64 {
    assert!(
        scored.is_none_or(|m| m.len() >= values.ncols()),
        "held_out_squared_error: the scored mask has {} entries for {} value columns",
        scored.map_or(0, <[bool]>::len),
        values.ncols()
    );
    let last_scored = (0..values.ncols())
        .rev()
        .find(|&j| scored.is_none_or(|m| m[j]));
    assert!(
        pred.nrows() == test.len() && last_scored.is_none_or(|j| j < pred.ncols()),
        "held_out_squared_error: predictions {} x {} for {} held-out samples of {} value columns",
        pred.nrows(),
        pred.ncols(),
        test.len(),
        values.ncols()
    );
    assert!(
        test.iter().all(|&i| i < values.nrows()),
        "held_out_squared_error: a held-out sample index is not below {} (the rows of values)",
        values.nrows()
    );
    (0..values.ncols())
        .filter(|&j| scored.is_none_or(|m| m[j]))
        .map(|j| {
            let (p, v) = (pred.col(j), values.col(j));
            test.iter()
                .enumerate()
                .map(|(t, &i)| (p[t] - v[i]).powi(2))
                .sum::<f64>()
        })
        .sum()
}
