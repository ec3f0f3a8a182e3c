//! Radial basis function interpolation with a linear polynomial (Rose, Cohen and Bodenheimer,
//! "Verbs and Adverbs", 1998), the baseline the paper compares kriging against.

use faer::{Mat, MatRef};
use serde::{Deserialize, Serialize};

use crate::config::LooReport;
use crate::empirical::PairDistances;
use crate::error::KrigingError;
use crate::kriging::{augmented_params, check_query, scaled_dist};
use crate::linalg::{checked_inverse, matmul, sym_eigen};
use crate::scaling::{ParamScaling, ScalingChoice};

/// The radial function `phi(r)`.
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

/// Configuration of [`Rbf::fit`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct RbfConfig {
    /// Radial function.
    pub kernel: RbfKernel,
    /// Per-dimension scaling of the parameters.
    pub scaling: ScalingChoice,
}

/// A fitted RBF interpolant `x(c) = sum_i w_i phi(|c - c_i|) + a^t [c; 1]`.
///
/// Solved as the symmetric system `M = [Phi Q; Q^t 0]` where the columns of `Q` are an orthonormal
/// basis of the span of `C^t` (the linear polynomials at the samples; dimensions that are constant
/// or collinear are removed with a relative eigenvalue tolerance of 1e-12 on `C C^t`). The
/// interpolant is linear in the sample values, so it is also expressed as weights
/// `b(c) = M^-1[:S, :] [phi(c); q(c)]` on them: they sum to one and reproduce linear functions.
/// (Rose et al. first fit the hyperplane by least squares and then interpolate the residuals; the
/// augmented system gives the same kind of interpolant and is regular for any distinct samples.)
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
}

impl Rbf {
    /// Fits the interpolant to `params` (S x d) and `values` (S x D).
    ///
    /// Errors: shapes, NaN/inf, fewer than 2 samples, all parameters equal, duplicate parameter
    /// points (both indices), a singular system, a Gaussian width that is not finite and positive.
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
        if params.nrows() != values.nrows() {
            return Err(KrigingError::ShapeMismatch {
                what: "values rows vs parameter rows",
                expected: params.nrows(),
                got: values.nrows(),
            });
        }
        if params.ncols() == 0 || values.ncols() == 0 {
            return Err(KrigingError::ShapeMismatch {
                what: "parameter and value dimensions (need at least one each)",
                expected: 1,
                got: 0,
            });
        }
        crate::check_finite("params", params)?;
        crate::check_finite("values", values)?;
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
        if let Some((first, second)) = dist.first_duplicate(dist.duplicate_tol()) {
            return Err(KrigingError::DuplicateParams {
                what: "rbf",
                first,
                second,
            });
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
        let n = s + q;
        let m = Mat::from_fn(n, n, |i, j| {
            if i < s && j < s {
                if i == j {
                    config.kernel.eval(0.0)
                } else {
                    config.kernel.eval(dist.get(i, j))
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
        let dm = crate::linalg::matmul_par_cols(minv.as_ref().subcols(0, s), values);
        let mut dual = Vec::with_capacity(n * values.ncols());
        for i in 0..n {
            for j in 0..values.ncols() {
                dual.push(dm[(i, j)]);
            }
        }
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
            minv,
            dual,
            values: values.to_owned(),
        })
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

    /// Leave-one-out errors (S x D) in closed form (Rippa 1999): `e_k = (M^-1 [X; 0])_k / (M^-1)_kk`.
    pub fn loo_errors(&self) -> Result<Mat<f64>, KrigingError> {
        let s = self.n_samples();
        let dv = self.n_values();
        let mut err = Mat::zeros(s, dv);
        for k in 0..s {
            let mkk = self.minv[(k, k)];
            if mkk == 0.0 || !mkk.is_finite() {
                return Err(KrigingError::Singular {
                    what: "rbf leave-one-out",
                    size: s,
                    pivot_ratio: 0.0,
                    residual: f64::NAN,
                });
            }
            for j in 0..dv {
                err[(k, j)] = self.dual[k * dv + j] / mkk;
            }
        }
        Ok(err)
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
