//! Weighted least-squares fit of a theoretical variogram to the empirical one (appendix A).

use serde::{Deserialize, Serialize};

use crate::empirical::EmpiricalVariogram;
use crate::error::KrigingError;
use crate::nested::{NestedVariogram, Structure};
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
    /// Which parameters ended at a bound of their search interval: the fit is then the best
    /// *within the bounds*, and the data may want a value beyond (check before trusting it).
    #[serde(default)]
    pub bounds: FitBounds,
}

/// Which fitted parameters of [`fit_variogram`] or [`fit_nested`] ended at a bound (within
/// `1e-6` of the search interval's width, on the scale searched: logarithmic for ranges and the
/// Matérn `nu`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct FitBounds {
    /// The nugget was fitted and ended at 0, its lower bound (common and often right: the
    /// variogram then starts continuously at the origin).
    pub nugget_at_zero: bool,
    /// A range ended at an end of its search interval `[h_1 / 4, 5 h_max]` (`h_1` the first
    /// non-empty interval centre, `h_max` the largest lag): at the upper end the data show no
    /// sill (try an unbounded model), at the lower end no correlation beyond the first interval.
    pub range_at_bound: bool,
    /// The exponent ended at an end of its interval: power `[0.02, 1.98]`, Matérn smoothness
    /// `nu` in [`MATERN_NU_BOUNDS`] (at the upper end the data want a gaussian shape).
    pub exponent_at_bound: bool,
}

impl FitBounds {
    /// Whether a range or an exponent ended at a bound (a zero nugget is not counted).
    pub fn any(&self) -> bool {
        self.range_at_bound || self.exponent_at_bound
    }
}

/// Smoothness values `nu` a Matérn fit chose from before `nu` became a continuous parameter; no
/// longer used by [`fit_variogram`] (which searches [`MATERN_NU_BOUNDS`]), kept for callers.
pub const MATERN_NUS: [f64; 6] = [0.25, 0.5, 1.0, 1.5, 2.5, 5.0];

/// The interval `[0.2, 30]` over which [`fit_variogram`] searches the Matérn smoothness `nu`
/// (GSTools' default bounds for its Matérn model).
pub const MATERN_NU_BOUNDS: (f64, f64) = (0.2, 30.0);

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
/// exponent in `[0.02, 1.98]` for the power model, none for the linear model; for the Matérn
/// model the smoothness `nu` too, a continuous parameter in [`MATERN_NU_BOUNDS`]). For each
/// `theta`, `n` and `s` enter linearly and are solved in closed form with the bounds enforced;
/// `theta` is found by a log-spaced grid followed by golden-section refinement, both
/// deterministic; Matérn's `nu` by the same search (log scale, 16 points, 40 golden steps) over
/// the best fit for each `nu`. Parameters that end at a bound are reported in
/// [`FittedVariogram::bounds`].
///
/// Errors: no non-empty interval, an all-zero empirical variogram (the values do not vary), a
/// best fit with zero sill (no spatial correlation: a pure nugget), and a malformed hand-built
/// `emp` (its fields are public): `centers`, `gamma` and `counts` of different lengths, a
/// `bin_width` that is not finite and > 0, or a non-empty interval whose centre or semi-variance
/// is not finite or whose centre is not > 0. All are [`KrigingError::VariogramFit`].
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
/// assert!(!fit.bounds.any());
/// // Matérn: the smoothness is fitted as a continuous parameter (here nu = 0.8 is recovered).
/// let m = Variogram::new(VariogramModel::Matern, 0.1, 1.0, 120.0, 0.8)?;
/// let emp_m = EmpiricalVariogram { gamma: emp.centers.iter().map(|&h| m.eval(h)).collect(), ..emp.clone() };
/// let fm = fit_variogram(&emp_m, VariogramModel::Matern, &FitOptions::default())?;
/// assert!((fm.variogram.exponent - 0.8).abs() < 1e-3, "{:?}", fm.variogram);
/// // A linear rise fitted by a bounded model: no sill in reach, the range ends at its bound.
/// let lin = EmpiricalVariogram { gamma: emp.centers.clone(), ..emp.clone() };
/// let fl = fit_variogram(&lin, VariogramModel::Exponential, &FitOptions::default())?;
/// assert!(fl.bounds.range_at_bound);
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
    let p = points(emp, opts).map_err(fail)?;
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
            VariogramModel::Linear => (1.0, objective(1.0), false),
            VariogramModel::Power => search(&mut objective, 0.02, 1.98, false, GRID, GOLDEN_STEPS),
            _ => {
                let lo = p.h[0] * 0.25;
                search(&mut objective, lo, 5.0 * hmax, true, GRID, GOLDEN_STEPS)
            }
        }
    };
    // The Matérn smoothness: the same bounded search, each point the best fit over the range.
    let ((nu, nu_at_bound), (theta, (n, s, wsse), theta_at_bound)) =
        if model == VariogramModel::Matern {
            let mut best = None;
            let mut outer = |nu: f64| {
                let r = fit_shape(nu);
                let v = r.1;
                best = match best {
                    Some((b, _)) if b <= v.2 => best,
                    _ => Some((v.2, (nu, r))),
                };
                v
            };
            let (lo, hi) = MATERN_NU_BOUNDS;
            let (_, _, at) = search(&mut outer, lo, hi, true, 16, 40);
            // The best fit evaluated (the search's best point, with its range fit).
            let (_, (nu_b, r)) = best.expect("the search evaluates at least one nu");
            ((nu_b, at), r)
        } else {
            let r = fit_shape(1.0);
            let at = model == VariogramModel::Power && r.2;
            ((1.0, at), r)
        };
    let range_at_bound = model.has_range() && theta_at_bound;
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
    let bounds = FitBounds {
        nugget_at_zero: opts.nugget && n == 0.0,
        range_at_bound,
        exponent_at_bound: nu_at_bound,
    };
    Ok(FittedVariogram {
        variogram,
        wsse,
        bounds,
    })
}

/// The non-empty intervals of `emp` with their weights; `Err(reason)` when none or all zero, or
/// when a hand-built `emp` is malformed: fields of different lengths, a bin width that is not
/// finite and > 0, or a non-empty interval whose centre is not finite and > 0 (the range search
/// runs on the logarithm of the first centre).
fn points(emp: &EmpiricalVariogram, opts: &FitOptions) -> Result<Points, &'static str> {
    if emp.centers.len() != emp.counts.len() || emp.gamma.len() != emp.counts.len() {
        return Err("the empirical variogram's centers, gamma and counts have different lengths");
    }
    if !(emp.bin_width.is_finite() && emp.bin_width > 0.0) {
        return Err("the empirical variogram's bin width must be finite and > 0");
    }
    if (0..emp.counts.len())
        .any(|u| emp.counts[u] > 0 && emp.centers[u].is_finite() && emp.centers[u] <= 0.0)
    {
        return Err("the empirical variogram has a non-empty interval whose centre is not > 0");
    }
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
            return Err("the empirical variogram holds a non-finite value");
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
        return Err("the empirical variogram has no non-empty interval");
    }
    if ymax.is_nan() || ymax <= 0.0 {
        return Err(
            "the empirical variogram is zero everywhere (the values do not vary over the samples)",
        );
    }
    Ok(p)
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

/// Minimises `obj(theta).2` over `[lo, hi]` (`grid` points, log-spaced when `log`), then refines
/// by `steps` golden-section steps between the grid neighbours of the best grid point. Returns the
/// best `theta`, its objective and whether it lies at an end of `[lo, hi]`.
fn search(
    obj: &mut impl FnMut(f64) -> (f64, f64, f64),
    lo: f64,
    hi: f64,
    log: bool,
    grid_n: usize,
    steps: usize,
) -> (f64, (f64, f64, f64), bool) {
    let to = |t: f64| if log { t.exp() } else { t };
    let (a, b) = if log { (lo.ln(), hi.ln()) } else { (lo, hi) };
    let grid: Vec<f64> = (0..grid_n)
        .map(|i| a + (b - a) * i as f64 / (grid_n - 1) as f64)
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
    let mut x1 = grid[(best + 1).min(grid_n - 1)];
    let phi = 0.5 * (5f64.sqrt() - 1.0);
    let mut c = x1 - phi * (x1 - x0);
    let mut d = x0 + phi * (x1 - x0);
    let mut fc = obj(to(c));
    let mut fd = obj(to(d));
    for _ in 0..steps {
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
    let at_bound = (theta - a).abs() <= 1e-6 * (b - a) || (b - theta).abs() <= 1e-6 * (b - a);
    // A grid end is returned as the bound itself (exp(ln(hi)) may be an ulp off).
    let theta = if theta == a {
        lo
    } else if theta == b {
        hi
    } else {
        to(theta)
    };
    (theta, val, at_bound)
}

/// A nested variogram fitted by [`fit_nested`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NestedFit {
    /// The fitted variogram: the nugget and one structure per requested model, in the order given.
    pub variogram: NestedVariogram,
    /// `sum_u w_u (gamma(h_u) - gamma_u)^2` over non-empty intervals.
    pub wsse: f64,
    /// The nugget was fitted and ended at 0.
    pub nugget_at_zero: bool,
    /// Per structure: its range ended at an end of the search interval `[h_1 / 4, 5 h_max]`.
    pub range_at_bound: Vec<bool>,
}

/// Grid points per range in [`fit_nested`]'s start search (one, two and three structures).
const NESTED_GRID: [usize; 3] = [48, 24, 12];
/// Nelder-Mead iterations of [`fit_nested`]'s refinement.
const NESTED_NM_ITERS: usize = 400;

/// Fits a nested variogram `gamma(h) = n + sum_k s_k f_k(h; a_k)` with one to three structures
/// (the shapes `models`, each bounded and without an exponent: spherical, exponential, gaussian,
/// cardinal sine) to `emp` by weighted least squares,
/// `min sum_u w_u (n + sum_k s_k f_k(h_u; a_k) - gamma_u)^2` over `n >= 0` (or `n = 0` when
/// `opts.nugget` is false), `s_k >= 0` and ranges `a_k` in `[h_1 / 4, 5 h_max]` (`h_1` the first
/// non-empty interval centre, `h_max` the largest lag), with the weights `w_u` of
/// [`FitOptions::weights`].
///
/// The sills enter linearly: for given ranges they are the non-negative least-squares solution,
/// found exactly by trying every set of active bounds. The ranges are searched on a logarithmic
/// grid (48, 24 or 12 points per range for one, two or three structures; a structure's range not
/// below the previous one's when both have the same shape, so that the order is fixed: short
/// first), then refined by Nelder-Mead in the logarithms of the ranges (400 iterations, clamped to
/// the bounds). Deterministic. Ranges that end at a bound are flagged in
/// [`NestedFit::range_at_bound`].
///
/// Errors: no model or more than three, a model that is unbounded or has an exponent (linear,
/// power, Matérn), the errors of [`fit_variogram`] on the empirical variogram, and a best fit in
/// which a structure has zero sill (the data support fewer structures: fit fewer).
///
/// ```
/// use kriging::{fit_nested, EmpiricalVariogram, FitOptions, NestedVariogram, VariogramModel};
///
/// // A short spherical and a long exponential structure with a nugget, sampled exactly.
/// let truth = NestedVariogram::single(VariogramModel::Spherical, 0.1, 0.4, 150.0)?
///     .with(VariogramModel::Exponential, 0.6, 900.0, 1.0);
/// let centers: Vec<f64> = (0..40).map(|u| 25.0 * (u as f64 + 0.5)).collect();
/// let emp = EmpiricalVariogram {
///     bin_width: 25.0,
///     gamma: centers.iter().map(|&h| truth.eval(h)).collect(),
///     counts: vec![100; 40],
///     centers,
/// };
/// let models = [VariogramModel::Spherical, VariogramModel::Exponential];
/// let fit = fit_nested(&emp, &models, &FitOptions::default())?;
/// let v = &fit.variogram;
/// assert!((v.nugget - 0.1).abs() < 1e-4);
/// assert!((v.structures[0].range - 150.0).abs() < 0.1 && (v.structures[1].range - 900.0).abs() < 1.0);
/// assert!(fit.wsse < 1e-8 && !fit.range_at_bound.contains(&true));
/// # Ok::<(), kriging::KrigingError>(())
/// ```
pub fn fit_nested(
    emp: &EmpiricalVariogram,
    models: &[VariogramModel],
    opts: &FitOptions,
) -> Result<NestedFit, KrigingError> {
    let fail = |reason: String| KrigingError::VariogramFit {
        model: models.first().copied(),
        reason,
    };
    let m = models.len();
    if !(1..=3).contains(&m) {
        return Err(KrigingError::InvalidConfig(format!(
            "a nested fit takes one to three structures, got {m}"
        )));
    }
    if let Some(bad) = models
        .iter()
        .find(|md| !md.has_range() || md.has_exponent())
    {
        return Err(KrigingError::InvalidConfig(format!(
            "a nested fit takes bounded models without an exponent (spherical, exponential, \
             gaussian, cardinal sine), got {}",
            bad.name()
        )));
    }
    let p = points(emp, opts).map_err(|r| fail(r.to_string()))?;
    let hmax = emp.bin_width * emp.counts.len() as f64;
    let (a, b) = ((p.h[0] * 0.25).ln(), (5.0 * hmax).ln());
    // Columns: 1 (nugget) then one per structure.
    let nu = p.h.len();
    let mut cols = vec![0.0; nu * m];
    let mut eval = |logr: &[f64]| -> (f64, Vec<f64>) {
        for k in 0..m {
            let r = logr[k].clamp(a, b).exp();
            for u in 0..nu {
                cols[k * nu + u] = shape(models[k], p.h[u], r, 1.0);
            }
        }
        nnls(&cols, m, &p, opts.nugget)
    };
    // Grid start.
    let g = NESTED_GRID[m - 1];
    let grid: Vec<f64> = (0..g)
        .map(|i| a + (b - a) * i as f64 / (g - 1) as f64)
        .collect();
    let mut best: Option<(f64, Vec<usize>)> = None;
    let mut idx = vec![0usize; m];
    loop {
        let ordered = (1..m).all(|k| models[k] != models[k - 1] || idx[k] >= idx[k - 1]);
        if ordered {
            let lr: Vec<f64> = idx.iter().map(|&i| grid[i]).collect();
            let (w, _) = eval(&lr);
            if best.as_ref().is_none_or(|bb| w < bb.0) {
                best = Some((w, idx.clone()));
            }
        }
        // Next index tuple (odometer).
        let mut k = 0;
        while k < m {
            idx[k] += 1;
            if idx[k] < g {
                break;
            }
            idx[k] = 0;
            k += 1;
        }
        if k == m {
            break;
        }
    }
    let (_, start) = best.ok_or_else(|| fail("no admissible start".into()))?;
    // Nelder-Mead in log-range space.
    let step = (b - a) / (g - 1) as f64;
    let mut simplex: Vec<Vec<f64>> = vec![start.iter().map(|&i| grid[i]).collect()];
    for k in 0..m {
        let mut v = simplex[0].clone();
        v[k] = if v[k] + step <= b {
            v[k] + step
        } else {
            v[k] - step
        };
        simplex.push(v);
    }
    let clamp = |v: &mut Vec<f64>| v.iter_mut().for_each(|x| *x = x.clamp(a, b));
    let mut vals: Vec<f64> = simplex.iter().map(|v| eval(v).0).collect();
    for _ in 0..NESTED_NM_ITERS {
        let mut order: Vec<usize> = (0..=m).collect();
        order.sort_by(|&i, &j| vals[i].total_cmp(&vals[j]));
        simplex = order.iter().map(|&i| simplex[i].clone()).collect();
        vals = order.iter().map(|&i| vals[i]).collect();
        let centroid: Vec<f64> = (0..m)
            .map(|k| simplex[..m].iter().map(|v| v[k]).sum::<f64>() / m as f64)
            .collect();
        let along = |t: f64| -> Vec<f64> {
            let mut v: Vec<f64> = (0..m)
                .map(|k| centroid[k] + t * (simplex[m][k] - centroid[k]))
                .collect();
            v.iter_mut().for_each(|x| *x = x.clamp(a, b));
            v
        };
        let xr = along(-1.0);
        let fr = eval(&xr).0;
        if fr < vals[0] {
            let xe = along(-2.0);
            let fe = eval(&xe).0;
            if fe < fr {
                (simplex[m], vals[m]) = (xe, fe);
            } else {
                (simplex[m], vals[m]) = (xr, fr);
            }
        } else if fr < vals[m - 1] {
            (simplex[m], vals[m]) = (xr, fr);
        } else {
            let xc = along(0.5);
            let fc = eval(&xc).0;
            if fc < vals[m] {
                (simplex[m], vals[m]) = (xc, fc);
            } else {
                for i in 1..=m {
                    let mut v: Vec<f64> = (0..m)
                        .map(|k| simplex[0][k] + 0.5 * (simplex[i][k] - simplex[0][k]))
                        .collect();
                    clamp(&mut v);
                    vals[i] = eval(&v).0;
                    simplex[i] = v;
                }
            }
        }
    }
    let bi = (0..=m)
        .min_by(|&i, &j| vals[i].total_cmp(&vals[j]))
        .unwrap_or(0);
    let lr = simplex[bi].clone();
    let (wsse, coef) = eval(&lr);
    let nugget = coef[0];
    let mut structures = Vec::with_capacity(m);
    for k in 0..m {
        if coef[k + 1].is_nan() || coef[k + 1] <= 0.0 {
            return Err(fail(format!(
                "structure {k} ({}) has zero sill at the best fit: the data support fewer \
                 structures",
                models[k].name()
            )));
        }
        structures.push(Structure {
            model: models[k],
            sill: coef[k + 1],
            range: lr[k].clamp(a, b).exp(),
            exponent: 1.0,
        });
    }
    let tol = 1e-6 * (b - a);
    let range_at_bound = lr
        .iter()
        .map(|&t| (t - a).abs() <= tol || (b - t).abs() <= tol)
        .collect();
    let variogram = NestedVariogram { nugget, structures };
    variogram.validate()?;
    Ok(NestedFit {
        variogram,
        wsse,
        nugget_at_zero: opts.nugget && nugget == 0.0,
        range_at_bound,
    })
}

/// Non-negative weighted least squares for `y ~ c_0 + sum_k c_k f_k` (`cols`: `m` columns of
/// length `p.h.len()`, one after the other), `c >= 0`, `c_0 = 0` unless `nugget`. Tries every set
/// of free coefficients and keeps the feasible solution with the smallest error (exact for the
/// at most four unknowns here). Returns `(wsse, [c_0, c_1, ..., c_m])`.
fn nnls(cols: &[f64], m: usize, p: &Points, nugget: bool) -> (f64, Vec<f64>) {
    let nu = p.h.len();
    let q = m + 1;
    let col = |j: usize, u: usize| if j == 0 { 1.0 } else { cols[(j - 1) * nu + u] };
    // Normal equations of all q columns.
    let mut ata = vec![0.0; q * q];
    let mut atb = vec![0.0; q];
    for u in 0..nu {
        for i in 0..q {
            let ci = col(i, u) * p.w[u];
            atb[i] += ci * p.y[u];
            for j in 0..q {
                ata[i * q + j] += ci * col(j, u);
            }
        }
    }
    let wsse_of = |c: &[f64]| -> f64 {
        (0..nu)
            .map(|u| {
                let r = (0..q).map(|j| c[j] * col(j, u)).sum::<f64>() - p.y[u];
                p.w[u] * r * r
            })
            .sum()
    };
    let mut best = (f64::INFINITY, vec![0.0; q]);
    for mask in 0..(1usize << q) {
        if !nugget && mask & 1 == 1 {
            continue;
        }
        let free: Vec<usize> = (0..q).filter(|&j| mask >> j & 1 == 1).collect();
        let mut c = vec![0.0; q];
        if !free.is_empty() {
            let Some(sol) = solve_small(&ata, &atb, q, &free) else {
                continue;
            };
            if sol.iter().any(|&v| v < 0.0 || !v.is_finite()) {
                continue;
            }
            for (&j, &v) in free.iter().zip(&sol) {
                c[j] = v;
            }
        }
        let w = wsse_of(&c);
        if w < best.0 {
            best = (w, c);
        }
    }
    best
}

/// Solves the normal equations restricted to the `free` unknowns by Gaussian elimination with
/// partial pivoting; `None` when (nearly) singular.
fn solve_small(ata: &[f64], atb: &[f64], q: usize, free: &[usize]) -> Option<Vec<f64>> {
    let k = free.len();
    let mut a: Vec<f64> = free
        .iter()
        .flat_map(|&i| free.iter().map(move |&j| ata[i * q + j]))
        .collect();
    let mut b: Vec<f64> = free.iter().map(|&i| atb[i]).collect();
    let scale = a.iter().fold(0.0f64, |s, v| s.max(v.abs()));
    for c in 0..k {
        let piv = (c..k).max_by(|&i, &j| a[i * k + c].abs().total_cmp(&a[j * k + c].abs()))?;
        if a[piv * k + c].is_nan() || a[piv * k + c].abs() <= 1e-13 * scale {
            return None;
        }
        if piv != c {
            for j in 0..k {
                a.swap(c * k + j, piv * k + j);
            }
            b.swap(c, piv);
        }
        for r in c + 1..k {
            let f = a[r * k + c] / a[c * k + c];
            for j in c..k {
                a[r * k + j] -= f * a[c * k + j];
            }
            b[r] -= f * b[c];
        }
    }
    let mut x = vec![0.0; k];
    for c in (0..k).rev() {
        let s: f64 = (c + 1..k).map(|j| a[c * k + j] * x[j]).sum();
        x[c] = (b[c] - s) / a[c * k + c];
    }
    Some(x)
}

/// The range of `model` that best fits `emp` by weighted least squares with the nugget, partial
/// sill and exponent held fixed (search as in [`fit_variogram`]). Returns `(range, wsse, at_bound)`.
pub(crate) fn fit_range_fixed(
    emp: &EmpiricalVariogram,
    fixed: &Variogram,
    opts: &FitOptions,
) -> Result<(f64, f64, bool), KrigingError> {
    let p = points(emp, opts).map_err(|r| KrigingError::VariogramFit {
        model: Some(fixed.model),
        reason: r.to_string(),
    })?;
    let hmax = emp.bin_width * emp.counts.len() as f64;
    let mut obj = |range: f64| {
        let w: f64 = (0..p.h.len())
            .map(|u| {
                let g = fixed.nugget
                    + fixed.sill * shape(fixed.model, p.h[u], range, fixed.exponent)
                    - p.y[u];
                p.w[u] * g * g
            })
            .sum();
        (0.0, 0.0, w)
    };
    let (range, val, at) = search(
        &mut obj,
        p.h[0] * 0.25,
        5.0 * hmax,
        true,
        GRID,
        GOLDEN_STEPS,
    );
    Ok((range, val.2, at))
}
