//! Radial basis function interpolation with a linear polynomial (Rose, Cohen and Bodenheimer,
//! "Verbs and Adverbs", 1998), the baseline the paper compares kriging against, with an optional
//! smoothing (ridge) term `Phi + lambda I` chosen by leave-one-out error.

use faer::{Mat, MatRef};
use serde::{Deserialize, Serialize};

use crate::config::LooReport;
use crate::empirical::PairDistances;
use crate::error::KrigingError;
use crate::kriging::{augmented_params, check_inputs, check_query, dual_coefficients, scaled_dist};
use crate::linalg::{checked_inverse, matmul, sym_eigen};
use crate::scaling::{ParamScaling, ScalingChoice};

/// The radial function `phi(r)`.
///
/// ```
/// use kriging::faer::Mat;
/// use kriging::{Rbf, RbfConfig, RbfKernel};
///
/// assert_eq!(RbfKernel::Linear.eval(2.0), 2.0);
/// assert_eq!(RbfKernel::Cubic.eval(2.0), 8.0);
/// assert_eq!(RbfKernel::ThinPlate.eval(0.0), 0.0);
/// assert!((RbfKernel::ThinPlate.eval(std::f64::consts::E) - std::f64::consts::E.powi(2)).abs() < 1e-12);
/// assert!((RbfKernel::Gaussian { width: 2.0 }.eval(2.0) - (-1.0f64).exp()).abs() < 1e-15);
/// assert_eq!(RbfKernel::default(), RbfKernel::Cubic); // Rose et al.'s choice
/// assert_eq!(RbfKernel::ThinPlate.name(), "thin-plate");
///
/// // An interpolant with the thin-plate spline instead of the default cubic.
/// let c = Mat::from_fn(6, 1, |i, _| i as f64);
/// let x = Mat::from_fn(6, 1, |i, _| (i as f64).sqrt());
/// let config = RbfConfig { kernel: RbfKernel::ThinPlate, ..RbfConfig::default() };
/// let rbf = Rbf::fit(c.as_ref(), x.as_ref(), &config)?;
/// assert_eq!(rbf.kernel(), RbfKernel::ThinPlate);
/// let mut out = [0.0];
/// rbf.predict(&[2.5], &mut out)?;
/// assert!(out[0] > 2f64.sqrt() && out[0] < 3f64.sqrt());
/// # Ok::<(), kriging::KrigingError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub enum RbfKernel {
    /// `phi(r) = r`.
    Linear,
    /// `phi(r) = r^3` (conditionally positive definite of order 2: regular with the linear term).
    #[default]
    Cubic,
    /// `phi(r) = r^2 ln r` (0 at `r = 0`).
    ThinPlate,
    /// `phi(r) = exp(-(r / width)^2)`, `width > 0`.
    Gaussian {
        /// Kernel width in scaled parameter units.
        width: f64,
    },
}

impl RbfKernel {
    /// Evaluates `phi(r)`.
    #[inline]
    pub fn eval(&self, r: f64) -> f64 {
        match *self {
            RbfKernel::Linear => r,
            RbfKernel::Cubic => r * r * r,
            RbfKernel::ThinPlate => {
                if r > 0.0 {
                    r * r * r.ln()
                } else {
                    0.0
                }
            }
            RbfKernel::Gaussian { width } => {
                let t = r / width;
                (-t * t).exp()
            }
        }
    }

    /// Lower-case name (`"linear"`, `"cubic"`, `"thin-plate"`, `"gaussian"`).
    pub fn name(&self) -> &'static str {
        match self {
            RbfKernel::Linear => "linear",
            RbfKernel::Cubic => "cubic",
            RbfKernel::ThinPlate => "thin-plate",
            RbfKernel::Gaussian { .. } => "gaussian",
        }
    }
}

/// Relative smoothing grid of [`RbfSmoothing::Loo`]: the candidates are `f * mean_ij |Phi_ij|`
/// for each factor `f` here (0, then `1e-8 .. 1e0` by decades), tried in this order.
pub const RBF_SMOOTHING_GRID: [f64; 10] =
    [0.0, 1e-8, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1, 1.0];

/// The smoothing (ridge) term `lambda` of the RBF system `[Phi + lambda I, Q; Q^t, 0]`.
///
/// With `lambda = 0` the RBF interpolates the samples exactly; this is the paper's baseline (Rose et
/// al.). When several samples have nearly the same parameters (for example the cycles of one take)
/// `Phi` is nearly singular and the exact interpolant oscillates wildly between them; `lambda > 0`
/// bounds the smallest eigenvalue of the kernel block away from zero (on the polynomial-free subspace,
/// for the conditionally positive definite cubic, thin-plate and Gaussian kernels) and turns the
/// interpolant into a smoothing spline: the fitted value at sample `k` is `x_k - lambda w_k`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub enum RbfSmoothing {
    /// `lambda = 0`: exact interpolation, the paper's baseline. Duplicate parameter points are an
    /// error ([`KrigingError::DuplicateParams`]).
    None,
    /// A given `lambda >= 0` (finite), in the units of `phi` (scaled parameter distances).
    Fixed(f64),
    /// `lambda` chosen as the candidate of smallest leave-one-out RMSE over the fitted values,
    /// from `RBF_SMOOTHING_GRID[i] * mean_ij |Phi_ij|` (see [`RBF_SMOOTHING_GRID`]); ties go to the
    /// smaller `lambda`. `lambda = 0` is skipped when two samples share their parameters, and
    /// candidates whose system is singular are skipped.
    #[default]
    Loo,
}

/// Configuration of [`Rbf::fit`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct RbfConfig {
    /// Radial function.
    pub kernel: RbfKernel,
    /// Per-dimension scaling of the parameters.
    pub scaling: ScalingChoice,
    /// Smoothing term on the kernel block (default: chosen by leave-one-out error).
    #[serde(default)]
    pub smoothing: RbfSmoothing,
}

/// One smoothing value tried by [`RbfSmoothing::Loo`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SmoothingCandidate {
    /// The smoothing `lambda`.
    pub lambda: f64,
    /// Its leave-one-out RMSE over the fitted values (over their leading principal columns when
    /// there are more than [`crate::search::SEARCH_COLUMNS`]), `None` when the candidate was skipped
    /// (duplicate parameters at `lambda = 0`, singular system, non-finite error).
    pub loo_rmse: Option<f64>,
}

/// A fitted RBF interpolant `x(c) = sum_i w_i phi(|c - c_i|) + a^t [c; 1]`.
///
/// Solved as the symmetric system `M = [Phi + lambda I, Q; Q^t, 0] [w; a] = [X; 0]`
/// (`lambda` from [`RbfSmoothing`], 0 for exact interpolation) where the columns of `Q` are an orthonormal
/// basis of the span of `C^t` (the linear polynomials at the samples; dimensions that are constant
/// or collinear are removed with a relative eigenvalue tolerance of 1e-12 on `C C^t`). The
/// interpolant is linear in the sample values, so it is also expressed as weights
/// `b(c) = M^-1[:S, :] [phi(c); q(c)]` on them: they sum to one and reproduce linear functions
/// (also with smoothing, because `Q^t w = 0` keeps linear data out of the kernel part).
/// (Rose et al. first fit the hyperplane by least squares and then interpolate the residuals; the
/// augmented system gives the same kind of interpolant and is regular for any distinct samples.)
///
/// ```
/// use kriging::faer::Mat;
/// use kriging::{Rbf, RbfConfig, RbfSmoothing, ScalingChoice};
///
/// let c: [[f64; 2]; 6] = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [0.5, 0.5], [0.2, 0.9]];
/// let params = Mat::from_fn(6, 2, |i, k| c[i][k]);
/// // Two value columns: a plane and a curved function.
/// let values = Mat::from_fn(6, 2, |i, j| {
///     if j == 0 { 1.0 + 2.0 * c[i][0] - c[i][1] } else { (3.0 * c[i][0]).sin() * c[i][1] }
/// });
/// let config = RbfConfig {
///     smoothing: RbfSmoothing::None, // exact interpolation
///     scaling: ScalingChoice::None,
///     ..RbfConfig::default()         // cubic kernel
/// };
/// let rbf = Rbf::fit(params.as_ref(), values.as_ref(), &config)?;
/// let mut x = [0.0; 2];
/// rbf.predict(&[0.2, 0.9], &mut x)?; // exact at a sample
/// assert!((x[0] - values[(5, 0)]).abs() < 1e-10 && (x[1] - values[(5, 1)]).abs() < 1e-10);
/// rbf.predict(&[0.7, 0.3], &mut x)?; // reproduces the plane anywhere
/// assert!((x[0] - (1.0 + 1.4 - 0.3)).abs() < 1e-10);
/// let mut b = [0.0; 6];
/// rbf.weights(&[0.7, 0.3], &mut b)?; // the same prediction as weights on the samples
/// assert!((b.iter().sum::<f64>() - 1.0).abs() < 1e-12);
/// let xb: f64 = (0..6).map(|i| b[i] * values[(i, 1)]).sum();
/// assert!((xb - x[1]).abs() < 1e-12);
/// assert_eq!(rbf.leave_one_out()?.per_sample.len(), 6);
/// # Ok::<(), kriging::KrigingError>(())
/// ```
#[derive(Debug, Clone)]
pub struct Rbf {
    kernel: RbfKernel,
    scaling: ParamScaling,
    dropped: Vec<usize>,
    scaled: Mat<f64>,
    scaled_rows: Vec<f64>,
    /// (d+1) x q: polynomial basis values are `q(c) = poly^t [scaled c; 1]`.
    poly: Mat<f64>,
    /// (S+q) x (S+q) symmetric inverse of M.
    minv: Mat<f64>,
    /// Row-major (S+q) x D: `M^-1[:, :S] X`.
    dual: Vec<f64>,
    values: Mat<f64>,
    /// The smoothing `lambda` in use.
    lambda: f64,
    /// The candidates tried by leave-one-out choice (empty for `None` and `Fixed`).
    candidates: Vec<SmoothingCandidate>,
}

/// `mean_ij |Phi_ij|` over all `S^2` entries, the unit of the smoothing grid (1 if it is 0 or not
/// finite, which only an underflowing Gaussian kernel can give).
fn kernel_scale(phi: MatRef<'_, f64>) -> f64 {
    let mut sum = 0.0;
    for j in 0..phi.ncols() {
        for i in 0..phi.nrows() {
            sum += phi[(i, j)].abs();
        }
    }
    let mean = sum / (phi.nrows() * phi.ncols()).max(1) as f64;
    if mean > 0.0 && mean.is_finite() {
        mean
    } else {
        1.0
    }
}

/// `M^-1` and `M^-1[:, :S] X` (row-major) of one smoothing value.
struct Solved {
    minv: Mat<f64>,
    dual: Vec<f64>,
}

/// Inverts `M = [Phi + lambda I, Q; Q^t, 0]` and forms the dual coefficients `M^-1[:, :S] X`.
fn solve_smoothed(
    phi: MatRef<'_, f64>,
    qmat: MatRef<'_, f64>,
    lambda: f64,
    values: MatRef<'_, f64>,
) -> Result<Solved, KrigingError> {
    let (s, q) = qmat.shape();
    debug_assert_eq!(phi.shape(), (s, s));
    let n = s + q;
    let m = Mat::from_fn(n, n, |i, j| {
        if i < s && j < s {
            if i == j {
                phi[(i, j)] + lambda
            } else {
                phi[(i, j)]
            }
        } else if i < s {
            qmat[(i, j - s)]
        } else if j < s {
            qmat[(j, i - s)]
        } else {
            0.0
        }
    });
    let minv = checked_inverse(m.as_ref(), true, "rbf")?;
    let dual = dual_coefficients(minv.as_ref(), values);
    Ok(Solved { minv, dual })
}

/// Leave-one-out RMSE `sqrt(1/S sum_k |e_k|^2)` with Rippa's `e_k = dual_k / (M^-1)_kk`;
/// `None` when a diagonal entry is zero or the result is not finite.
fn loo_rmse(solved: &Solved, s: usize, dv: usize) -> Option<f64> {
    let mut sum = 0.0;
    for k in 0..s {
        let mkk = solved.minv[(k, k)];
        if mkk == 0.0 || !mkk.is_finite() {
            return None;
        }
        for v in &solved.dual[k * dv..(k + 1) * dv] {
            let e = v / mkk;
            sum += e * e;
        }
    }
    let rmse = (sum / s as f64).sqrt();
    rmse.is_finite().then_some(rmse)
}

impl Rbf {
    /// Fits the interpolant to `params` (S x d) and `values` (S x D).
    ///
    /// With [`RbfSmoothing::Loo`] one `(S+q)` inverse is formed per grid value (the distance and
    /// kernel matrices are computed once); the values are ranked on their
    /// [`crate::search::SEARCH_COLUMNS`] leading principal columns, exact when they have at most that
    /// rank, and the chosen value is solved once on the values themselves.
    ///
    /// Errors: shapes, NaN/inf, fewer than 2 samples, all parameters equal, duplicate parameter
    /// points without smoothing (both indices), a singular system (for `Loo`: every candidate),
    /// a Gaussian width that is not finite and positive, a fixed smoothing that is negative or not
    /// finite.
    pub fn fit(
        params: MatRef<'_, f64>,
        values: MatRef<'_, f64>,
        config: &RbfConfig,
    ) -> Result<Rbf, KrigingError> {
        if let RbfKernel::Gaussian { width } = config.kernel {
            if !(width.is_finite() && width > 0.0) {
                return Err(KrigingError::InvalidConfig(format!(
                    "gaussian RBF width {width} must be finite and > 0"
                )));
            }
        }
        if let RbfSmoothing::Fixed(lambda) = config.smoothing {
            if !(lambda.is_finite() && lambda >= 0.0) {
                return Err(KrigingError::InvalidConfig(format!(
                    "RBF smoothing lambda {lambda} must be finite and >= 0"
                )));
            }
        }
        check_inputs(params, values)?;
        let s = params.nrows();
        if s < 2 {
            return Err(KrigingError::TooFewSamples {
                what: "rbf",
                needed: 2,
                got: s,
            });
        }
        let scaling = ParamScaling::from_choice(&config.scaling, params)?;
        let scaled = scaling.apply_rows(params);
        let dist = PairDistances::new(scaled.as_ref());
        if dist.max().is_nan() || dist.max() <= 0.0 {
            return Err(KrigingError::NoSpread { samples: s });
        }
        let duplicate = dist.first_duplicate(dist.duplicate_tol());
        let exact_duplicate_error = |(first, second)| KrigingError::DuplicateParams {
            what: "rbf",
            first,
            second,
        };
        match config.smoothing {
            RbfSmoothing::None | RbfSmoothing::Fixed(0.0) => {
                if let Some(pair) = duplicate {
                    return Err(exact_duplicate_error(pair));
                }
            }
            _ => {}
        }
        let c = augmented_params(scaled.as_ref());
        let g = matmul(c.as_ref(), c.transpose());
        let (vals, vecs) = sym_eigen(g.as_ref());
        let vmax = vals.iter().fold(0.0f64, |m, v| m.max(*v));
        let keep: Vec<usize> = (0..vals.len())
            .rev()
            .filter(|&k| vals[k] > crate::linalg::PINV_RTOL * vmax && vals[k] > 0.0)
            .collect();
        let q = keep.len();
        let poly = Mat::from_fn(c.nrows(), q, |l, k| {
            vecs[(l, keep[k])] / vals[keep[k]].sqrt()
        });
        let qmat = matmul(c.transpose(), poly.as_ref()); // S x q, orthonormal columns
        let phi = Mat::from_fn(s, s, |i, j| {
            if i == j {
                config.kernel.eval(0.0)
            } else {
                config.kernel.eval(dist.get(i, j))
            }
        });
        let mut candidates = Vec::new();
        let (lambda, solved) = match config.smoothing {
            RbfSmoothing::None => (
                0.0,
                solve_smoothed(phi.as_ref(), qmat.as_ref(), 0.0, values)?,
            ),
            RbfSmoothing::Fixed(lambda) => (
                lambda,
                solve_smoothed(phi.as_ref(), qmat.as_ref(), lambda, values)?,
            ),
            RbfSmoothing::Loo => {
                let scale = kernel_scale(phi.as_ref());
                // Candidates are ranked on the values' leading principal columns (the leave-one-out
                // error is linear in the values), as the kriging search ranks its variograms.
                let probe = crate::search::compress(values, crate::search::SEARCH_COLUMNS);
                let compressed = probe.ncols() < values.ncols();
                let mut best: Option<(f64, f64, Solved)> = None;
                let mut last_err = None;
                for f in RBF_SMOOTHING_GRID {
                    let lambda = f * scale;
                    if lambda == 0.0 && duplicate.is_some() {
                        candidates.push(SmoothingCandidate {
                            lambda,
                            loo_rmse: None,
                        });
                        last_err = duplicate.map(exact_duplicate_error);
                        continue;
                    }
                    let rmse =
                        match solve_smoothed(phi.as_ref(), qmat.as_ref(), lambda, probe.as_ref()) {
                            Ok(solved) => {
                                let rmse = loo_rmse(&solved, s, probe.ncols());
                                if let Some(r) = rmse {
                                    if best.as_ref().is_none_or(|b| r < b.1) {
                                        best = Some((lambda, r, solved));
                                    }
                                } else {
                                    last_err = Some(KrigingError::Singular {
                                        what: "rbf leave-one-out",
                                        size: s,
                                        pivot_ratio: 0.0,
                                        residual: f64::NAN,
                                    });
                                }
                                rmse
                            }
                            Err(e) => {
                                last_err = Some(e);
                                None
                            }
                        };
                    candidates.push(SmoothingCandidate {
                        lambda,
                        loo_rmse: rmse,
                    });
                }
                match best {
                    Some((lambda, _, solved)) if !compressed => (lambda, solved),
                    Some((lambda, _, _)) => (
                        lambda,
                        solve_smoothed(phi.as_ref(), qmat.as_ref(), lambda, values)?,
                    ),
                    None => {
                        return Err(last_err.unwrap_or(KrigingError::Singular {
                            what: "rbf",
                            size: s + q,
                            pivot_ratio: 0.0,
                            residual: f64::NAN,
                        }));
                    }
                }
            }
        };
        let mut scaled_rows = Vec::with_capacity(s * scaled.ncols());
        for i in 0..s {
            for k in 0..scaled.ncols() {
                scaled_rows.push(scaled[(i, k)]);
            }
        }
        Ok(Rbf {
            kernel: config.kernel,
            dropped: scaling.dropped(),
            scaling,
            scaled,
            scaled_rows,
            poly,
            minv: solved.minv,
            dual: solved.dual,
            values: values.to_owned(),
            lambda,
            candidates,
        })
    }

    /// The smoothing `lambda` in use (0 for exact interpolation).
    pub fn smoothing(&self) -> f64 {
        self.lambda
    }

    /// The candidates tried by [`RbfSmoothing::Loo`], in grid order (empty for the other choices).
    pub fn smoothing_candidates(&self) -> &[SmoothingCandidate] {
        &self.candidates
    }

    /// Number of samples S.
    pub fn n_samples(&self) -> usize {
        self.scaled.nrows()
    }

    /// Number of parameter dimensions d.
    pub fn n_params(&self) -> usize {
        self.scaled.ncols()
    }

    /// Number of value dimensions D.
    pub fn n_values(&self) -> usize {
        self.values.ncols()
    }

    /// The radial function.
    pub fn kernel(&self) -> RbfKernel {
        self.kernel
    }

    /// The parameter scaling.
    pub fn scaling(&self) -> &ParamScaling {
        &self.scaling
    }

    /// Dimensions dropped by the scaling (constant over the samples).
    pub fn dropped_dims(&self) -> &[usize] {
        &self.dropped
    }

    /// Scaled sample parameters (S x d).
    pub fn scaled_params(&self) -> MatRef<'_, f64> {
        self.scaled.as_ref()
    }

    /// Number of polynomial basis functions kept (`d' + 1` for `d'` independent dimensions).
    pub fn poly_terms(&self) -> usize {
        self.poly.ncols()
    }

    /// Value `q_k(c)` of polynomial basis function `k` at the (unscaled) query `c`.
    #[inline]
    fn poly_value(&self, c: &[f64], k: usize) -> f64 {
        let d = c.len();
        let mut v = self.poly[(d, k)];
        for (l, &cl) in c.iter().enumerate() {
            v += (cl - self.scaling.offset[l]) * self.scaling.scale[l] * self.poly[(l, k)];
        }
        v
    }

    /// Equivalent linear weights `b(c)` (length S) on the sample values: the interpolant at `c`
    /// is `sum_i b_i(c) x_i`. They sum to one. No allocation.
    pub fn weights(&self, c: &[f64], out: &mut [f64]) -> Result<(), KrigingError> {
        let s = self.n_samples();
        check_query(c, self.n_params(), out.len(), s)?;
        out.fill(0.0);
        for j in 0..s {
            let p = self
                .kernel
                .eval(scaled_dist(&self.scaling, &self.scaled_rows, c, j));
            for (o, a) in out.iter_mut().zip(&self.minv.col_as_slice(j)[..s]) {
                *o += p * a;
            }
        }
        for k in 0..self.poly_terms() {
            let p = self.poly_value(c, k);
            for (o, a) in out.iter_mut().zip(&self.minv.col_as_slice(s + k)[..s]) {
                *o += p * a;
            }
        }
        Ok(())
    }

    /// The interpolated value at `c` (length D). No allocation.
    pub fn predict(&self, c: &[f64], out: &mut [f64]) -> Result<(), KrigingError> {
        let s = self.n_samples();
        let dv = self.n_values();
        check_query(c, self.n_params(), out.len(), dv)?;
        out.fill(0.0);
        for j in 0..s {
            let p = self
                .kernel
                .eval(scaled_dist(&self.scaling, &self.scaled_rows, c, j));
            for (o, a) in out.iter_mut().zip(&self.dual[j * dv..(j + 1) * dv]) {
                *o += p * a;
            }
        }
        for k in 0..self.poly_terms() {
            let p = self.poly_value(c, k);
            let r = s + k;
            for (o, a) in out.iter_mut().zip(&self.dual[r * dv..(r + 1) * dv]) {
                *o += p * a;
            }
        }
        Ok(())
    }

    /// `(M^-1)_kk`, the divisor of Rippa's leave-one-out form; an error when it is zero or not finite.
    fn loo_pivot(&self, k: usize) -> Result<f64, KrigingError> {
        let mkk = self.minv[(k, k)];
        if mkk == 0.0 || !mkk.is_finite() {
            return Err(KrigingError::Singular {
                what: "rbf leave-one-out",
                size: self.n_samples(),
                pivot_ratio: 0.0,
                residual: f64::NAN,
            });
        }
        Ok(mkk)
    }

    /// Leave-one-out errors (S x D) in closed form (Rippa 1999): `e_k = (M^-1 [X; 0])_k / (M^-1)_kk`.
    ///
    /// With smoothing this is still exact for the refit without sample `k` at the same `lambda`
    /// (the regularised kernel `phi(|c_i - c_j|) + lambda delta_ij` is just another symmetric kernel
    /// on the sample indices), evaluated at `c_k` where the smoothing term does not act.
    pub fn loo_errors(&self) -> Result<Mat<f64>, KrigingError> {
        let s = self.n_samples();
        let dv = self.n_values();
        let mut err = Mat::zeros(s, dv);
        for k in 0..s {
            let mkk = self.loo_pivot(k)?;
            for j in 0..dv {
                err[(k, j)] = self.dual[k * dv + j] / mkk;
            }
        }
        Ok(err)
    }

    /// Leave-one-out weights `W` (S x S): the refit without sample `k` (same `lambda`) predicts
    /// `sum_j W_kj x_j` at `c_k`, for any values. From Rippa's form, `E(X) = I - W` applied to `X`:
    /// `W_kk = 0`, `W_kj = -(M^-1)_kj / (M^-1)_kk`. Rows sum to one.
    pub fn loo_weights(&self) -> Result<Mat<f64>, KrigingError> {
        let s = self.n_samples();
        let mut w = Mat::zeros(s, s);
        for k in 0..s {
            let mkk = self.loo_pivot(k)?;
            for j in 0..s {
                if j != k {
                    w[(k, j)] = -self.minv[(k, j)] / mkk;
                }
            }
        }
        Ok(w)
    }

    /// Leave-one-out cross validation summarised as in [`crate::Kriging::leave_one_out`].
    pub fn leave_one_out(&self) -> Result<LooReport, KrigingError> {
        let e = self.loo_errors()?;
        let per = (0..e.nrows())
            .map(|k| {
                (0..e.ncols())
                    .map(|j| e[(k, j)] * e[(k, j)])
                    .sum::<f64>()
                    .sqrt()
            })
            .collect();
        Ok(LooReport::from_norms(per))
    }
}
