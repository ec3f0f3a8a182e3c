//! Weighted least-squares fit of a theoretical variogram to the empirical one (appendix A).

use serde::{Deserialize, Serialize};

use crate::empirical::EmpiricalVariogram;
use crate::error::KrigingError;
use crate::variogram::{Variogram, VariogramModel, shape};

/// Weights of the intervals in the least-squares fit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum FitWeights {
    /// `w_u = n(I_u)`, the pair count of the interval.
    #[default]
    PairCounts,
    /// Cressie's `w_u = n(I_u) / gamma_u^2`, with the empirical `gamma_u` standing in for the
    /// model value (the usual one-step approximation).
    Cressie,
}

/// Options of [`fit_variogram`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FitOptions {
    /// Fit a nugget (`>= 0`); when false the nugget is fixed at 0.
    pub nugget: bool,
    /// Interval weights.
    pub weights: FitWeights,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            nugget: true,
            weights: FitWeights::PairCounts,
        }
    }
}

/// A fitted variogram with its weighted sum of squared errors over the non-empty intervals.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FittedVariogram {
    /// The fitted model.
    pub variogram: Variogram,
    /// `sum_u w_u (gamma(h_u) - gamma_u)^2` over non-empty intervals.
    pub wsse: f64,
}

/// Smoothness values `nu` a Matérn fit chooses from.
pub const MATERN_NUS: [f64; 6] = [0.25, 0.5, 1.0, 1.5, 2.5, 5.0];

/// Grid size of the bounded 1-D search over the range or the exponent.
const GRID: usize = 48;
/// Golden-section refinement steps after the grid.
const GOLDEN_STEPS: usize = 60;

struct Points {
    h: Vec<f64>,
    y: Vec<f64>,
    w: Vec<f64>,
}

/// Fits `model` to `emp` by weighted least squares: `min sum_u w_u (n + s f(h_u; theta) - gamma_u)^2`
/// over nugget `n >= 0`, sill `s > 0` and the shape parameter `theta` (range for bounded models,
/// exponent in (0, 2) for the power model, none for the linear model; the Matérn smoothness `nu`
/// is the best of [`MATERN_NUS`]). For each `theta`, `n` and
/// `s` enter linearly and are solved in closed form with the bounds enforced; `theta` is found by a
/// log-spaced grid followed by golden-section refinement, both deterministic.
///
/// Errors: no non-empty interval, an all-zero empirical variogram (the values do not vary), or a
/// best fit with zero sill (no spatial correlation: a pure nugget).
///
/// ```
/// use kriging::{fit_variogram, EmpiricalVariogram, FitOptions, Variogram, VariogramModel};
///
/// // An empirical variogram that follows a known spherical model exactly.
/// let truth = Variogram::new(VariogramModel::Spherical, 0.2, 1.5, 400.0, 1.0)?;
/// let centers: Vec<f64> = (0..20).map(|u| 25.0 * (u as f64 + 0.5)).collect();
/// let emp = EmpiricalVariogram {
///     bin_width: 25.0,
///     gamma: centers.iter().map(|&h| truth.eval(h)).collect(),
///     counts: vec![50; 20],
///     centers,
/// };
/// let fit = fit_variogram(&emp, VariogramModel::Spherical, &FitOptions::default())?;
/// let v = fit.variogram;
/// assert!((v.nugget - 0.2).abs() < 1e-3 && (v.sill - 1.5).abs() < 1e-3);
/// assert!((v.range - 400.0).abs() < 1.0);
/// assert!(fit.wsse < 1e-6);
/// // A worse shape fits worse.
/// let gauss = fit_variogram(&emp, VariogramModel::Gaussian, &FitOptions::default())?;
/// assert!(gauss.wsse > 100.0 * fit.wsse);
/// // Without a nugget the fit must make do with nugget 0.
/// let no_nugget = FitOptions { nugget: false, ..FitOptions::default() };
/// assert_eq!(fit_variogram(&emp, VariogramModel::Spherical, &no_nugget)?.variogram.nugget, 0.0);
/// # Ok::<(), kriging::KrigingError>(())
/// ```
pub fn fit_variogram(
    emp: &EmpiricalVariogram,
    model: VariogramModel,
    opts: &FitOptions,
) -> Result<FittedVariogram, KrigingError> {
    let fail = |reason: &str| KrigingError::VariogramFit {
        model: Some(model),
        reason: reason.to_string(),
    };
    let mut p = Points {
        h: Vec::new(),
        y: Vec::new(),
        w: Vec::new(),
    };
    let ymax = emp.gamma.iter().fold(0.0f64, |m, v| m.max(*v));
    for u in 0..emp.counts.len() {
        let (n, g, h) = (emp.counts[u], emp.gamma[u], emp.centers[u]);
        if n == 0 {
            continue;
        }
        if !(g.is_finite() && h.is_finite()) {
            return Err(fail("the empirical variogram holds a non-finite value"));
        }
        let w = match opts.weights {
            FitWeights::PairCounts => n as f64,
            FitWeights::Cressie => {
                let floor = 1e-6 * ymax;
                n as f64 / (g * g).max(floor * floor)
            }
        };
        p.h.push(h);
        p.y.push(g);
        p.w.push(w);
    }
    if p.h.is_empty() {
        return Err(fail("the empirical variogram has no non-empty interval"));
    }
    if ymax.is_nan() || ymax <= 0.0 {
        return Err(fail(
            "the empirical variogram is zero everywhere (the values do not vary over the samples)",
        ));
    }
    let hmax = emp.bin_width * emp.counts.len() as f64;
    let mut f = vec![0.0; p.h.len()];
    let mut fit_shape = |exp_fixed: f64| {
        let mut objective = |theta: f64| -> (f64, f64, f64) {
            let (range, exponent) = match model {
                VariogramModel::Power => (0.0, theta),
                _ => (theta, exp_fixed),
            };
            for (fu, &h) in f.iter_mut().zip(&p.h) {
                *fu = shape(model, h, range, exponent);
            }
            linear_fit(&f, &p, opts.nugget)
        };
        match model {
            VariogramModel::Linear => (1.0, objective(1.0)),
            VariogramModel::Power => search(&mut objective, 0.02, 1.98, false),
            _ => {
                let lo = p.h[0] * 0.25;
                search(&mut objective, lo, 5.0 * hmax, true)
            }
        }
    };
    // The Matérn smoothness is chosen from a fixed set (the best fit over it); other models have
    // no second shape parameter.
    let (nu, (theta, (n, s, wsse))) = if model == VariogramModel::Matern {
        type Fit = (f64, (f64, (f64, f64, f64)));
        let mut best: Option<Fit> = None;
        for nu in MATERN_NUS {
            let r = fit_shape(nu);
            if best.is_none_or(|b| r.1.2 < b.1.1.2) {
                best = Some((nu, r));
            }
        }
        best.expect("MATERN_NUS is not empty")
    } else {
        (1.0, fit_shape(1.0))
    };
    if !s.is_finite() || s <= 0.0 {
        return Err(fail(
            "the best fit has zero sill (no spatial correlation: a pure nugget)",
        ));
    }
    let variogram = match model {
        VariogramModel::Linear => Variogram::new(model, n, s, 0.0, 1.0)?,
        VariogramModel::Power => Variogram::new(model, n, s, 0.0, theta)?,
        _ => Variogram::new(model, n, s, theta, nu)?,
    };
    Ok(FittedVariogram { variogram, wsse })
}

/// Weighted least squares for `(n, s)` in `n + s f` with `n >= 0` (or `n = 0`) and `s >= 0`.
/// Returns `(n, s, wsse)`.
fn linear_fit(f: &[f64], p: &Points, nugget: bool) -> (f64, f64, f64) {
    let (mut a11, mut a12, mut a22, mut b1, mut b2) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for ((&fu, &yu), &wu) in f.iter().zip(&p.y).zip(&p.w) {
        a11 += wu;
        a12 += wu * fu;
        a22 += wu * fu * fu;
        b1 += wu * yu;
        b2 += wu * fu * yu;
    }
    let sill_only = || if a22 > 0.0 { (b2 / a22).max(0.0) } else { 0.0 };
    let det = a11 * a22 - a12 * a12;
    let (n, s) = if nugget && det > 1e-12 * a11 * a22 {
        let n = (a22 * b1 - a12 * b2) / det;
        let s = (a11 * b2 - a12 * b1) / det;
        if n < 0.0 {
            (0.0, sill_only())
        } else if s < 0.0 {
            (b1 / a11, 0.0)
        } else {
            (n, s)
        }
    } else {
        (0.0, sill_only())
    };
    let wsse = f
        .iter()
        .zip(&p.y)
        .zip(&p.w)
        .map(|((&fu, &yu), &wu)| {
            let r = n + s * fu - yu;
            wu * r * r
        })
        .sum();
    (n, s, wsse)
}

/// Minimises `obj(theta).2` over `[lo, hi]` (log-spaced grid when `log`), then refines by golden
/// section between the grid neighbours of the best grid point.
fn search(
    obj: &mut impl FnMut(f64) -> (f64, f64, f64),
    lo: f64,
    hi: f64,
    log: bool,
) -> (f64, (f64, f64, f64)) {
    let to = |t: f64| if log { t.exp() } else { t };
    let (a, b) = if log { (lo.ln(), hi.ln()) } else { (lo, hi) };
    let grid: Vec<f64> = (0..GRID)
        .map(|i| a + (b - a) * i as f64 / (GRID - 1) as f64)
        .collect();
    let mut best = 0;
    let mut best_val = obj(to(grid[0]));
    for (i, &g) in grid.iter().enumerate().skip(1) {
        let v = obj(to(g));
        if v.2 < best_val.2 {
            best = i;
            best_val = v;
        }
    }
    let mut x0 = grid[best.saturating_sub(1)];
    let mut x1 = grid[(best + 1).min(GRID - 1)];
    let phi = 0.5 * (5f64.sqrt() - 1.0);
    let mut c = x1 - phi * (x1 - x0);
    let mut d = x0 + phi * (x1 - x0);
    let mut fc = obj(to(c));
    let mut fd = obj(to(d));
    for _ in 0..GOLDEN_STEPS {
        if fc.2 < fd.2 {
            x1 = d;
            d = c;
            fd = fc;
            c = x1 - phi * (x1 - x0);
            fc = obj(to(c));
        } else {
            x0 = c;
            c = d;
            fc = fd;
            d = x0 + phi * (x1 - x0);
            fd = obj(to(d));
        }
    }
    let mut theta = grid[best];
    let mut val = best_val;
    if fc.2 < val.2 {
        theta = c;
        val = fc;
    }
    if fd.2 < val.2 {
        theta = d;
        val = fd;
    }
    (to(theta), val)
}
