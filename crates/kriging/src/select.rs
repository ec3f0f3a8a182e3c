//! Which parameter dimensions carry signal: backward elimination by leave-one-out error.
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
}

impl DimDecision {
    /// True when the dimension is out of the model (constant or no signal).
    pub fn dropped(&self) -> bool {
        !matches!(self, DimDecision::Kept { .. })
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
    /// Leave-one-out RMSE of `kriging` (over the scored columns).
    pub loo_rmse: f64,
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
    if let Some(mask) = scored {
        if mask.len() != values.ncols() {
            return Err(KrigingError::ShapeMismatch {
                what: "scored columns vs value columns",
                expected: values.ncols(),
                got: mask.len(),
            });
        }
        if !mask.iter().any(|&m| m) {
            return Err(KrigingError::InvalidConfig(
                "dimension selection scores no value column".into(),
            ));
        }
    }
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
        loo_rmse: rmse(&current_err),
    })
}
