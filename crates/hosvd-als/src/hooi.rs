//! HOOI / ALS: the best rank-`(R_0, R_1, R_2)` Tucker approximation by alternating least squares
//! (de Lathauwer, De Moor, Vandewalle 2000b; paper section 3.2 and 4.1).

use crate::eig::leading_eigen;
use crate::gram::gram_into;
use crate::hosvd::{hosvd_factors, validate};
use crate::{HosvdError, Tucker};
use faer::{Mat, MatRef};
use serde::{Deserialize, Serialize};
use tensor_ops::{Tensor3, mode_product_into, product_dims};

/// Stopping rule of [`hooi`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct AlsOptions {
    /// Stop when `| ||Z_k|| - ||Z_{k-1}|| | / ||X|| < tol` (the change of the core norm per sweep,
    /// relative to the data norm). `0` runs `max_iter` sweeps.
    pub tol: f64,
    /// Maximum number of sweeps (each updates all three factors once); at least 1.
    pub max_iter: usize,
}

impl Default for AlsOptions {
    /// `tol = 1e-8`, `max_iter = 100`.
    fn default() -> Self {
        Self {
            tol: 1e-8,
            max_iter: 100,
        }
    }
}

impl AlsOptions {
    /// Errors: [`HosvdError::BadOption`] for a negative or non-finite `tol` or `max_iter == 0`.
    pub fn validate(&self) -> Result<(), HosvdError> {
        if !(self.tol.is_finite() && self.tol >= 0.0) {
            return Err(HosvdError::BadOption {
                field: "tol",
                value: self.tol.to_string(),
                reason: "must be finite and >= 0",
            });
        }
        if self.max_iter == 0 {
            return Err(HosvdError::BadOption {
                field: "max_iter",
                value: "0".into(),
                reason: "must be at least 1",
            });
        }
        Ok(())
    }
}

/// What [`hooi`] did.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct AlsReport {
    /// Sweeps run.
    pub iterations: usize,
    /// `||X - X~||_F / ||X||_F` (0 for an all-zero `X`).
    pub rel_error: f64,
    /// The paper's E (section 4.2): `||X - X~||_F^2 / (I_0 I_1 I_2)`.
    pub mse: f64,
    /// True if the tolerance was reached before `max_iter`.
    pub converged: bool,
}

/// Errors of a model whose core is the projection of `x` on orthonormal factors:
/// `||X - X~||^2 = ||X||^2 - ||Z||^2` (no reconstruction). Returns `(mse, rel_error)`.
pub(crate) fn projection_errors(x_norm2: f64, core_norm2: f64, len: usize) -> (f64, f64) {
    let e2 = (x_norm2 - core_norm2).max(0.0);
    let rel = if x_norm2 > 0.0 {
        (e2 / x_norm2).sqrt()
    } else {
        0.0
    };
    (e2 / len.max(1) as f64, rel)
}

/// HOOI for the rank triple `ranks`, started from the truncated HOSVD factors.
///
/// Each sweep updates, for `n = 0, 1, 2`, `U_n` = the leading `R_n` eigenvectors of
/// `Y_(n) Y_(n)^T` with `Y = X x_m U_m^T x_k U_k^T` over the two other modes (which maximises
/// `||X x_0 U_0^T x_1 U_1^T x_2 U_2^T||` over `U_n`), then forms `Z = X x_n U_n^T`. The error
/// `||X - X~||^2 = ||X||^2 - ||Z||^2` never increases from sweep to sweep. The result is rotated
/// into ordered form ([`Tucker::into_ordered`]).
///
/// Errors: as [`crate::hosvd`], plus [`HosvdError::BadOption`] for invalid `opts`.
pub fn hooi(
    x: &Tensor3,
    ranks: [usize; 3],
    opts: &AlsOptions,
) -> Result<(Tucker, AlsReport), HosvdError> {
    validate(x, ranks)?;
    opts.validate()?;
    let start = hosvd_factors(x, ranks)?;
    run(
        x,
        ranks,
        [start[0].as_ref(), start[1].as_ref(), start[2].as_ref()],
        opts,
    )
}

/// HOOI started from given factors `U_n` (`I_n x R_n`, orthonormal columns), e.g. the leading
/// columns of a larger model's factors. The ranks are the factors' column counts. Starting from
/// a truncation of a projection model, the result's error is never above that truncation's.
///
/// Errors: as [`hooi`], plus [`HosvdError::BadStart`] for a factor of the wrong shape.
pub fn hooi_with_start(
    x: &Tensor3,
    start: [MatRef<'_, f64>; 3],
    opts: &AlsOptions,
) -> Result<(Tucker, AlsReport), HosvdError> {
    let ranks = [start[0].ncols(), start[1].ncols(), start[2].ncols()];
    validate(x, ranks)?;
    opts.validate()?;
    for (mode, f) in start.iter().enumerate() {
        if f.nrows() != x.dims()[mode] {
            return Err(HosvdError::BadStart {
                mode,
                rows: f.nrows(),
                cols: f.ncols(),
                expected_rows: x.dims()[mode],
                expected_cols: ranks[mode],
            });
        }
        if let Some((i, j)) = (0..f.ncols())
            .flat_map(|j| (0..f.nrows()).map(move |i| (i, j)))
            .find(|&(i, j)| !f[(i, j)].is_finite())
        {
            return Err(tensor_ops::TensorError::NonFinite {
                i,
                j,
                k: mode,
                value: f[(i, j)],
            }
            .into());
        }
    }
    run(x, ranks, start, opts)
}

/// Scratch buffers of one HOOI run, allocated once.
struct Buffers {
    w2: Vec<f64>,
    y0: Vec<f64>,
    y1: Vec<f64>,
    w0: Vec<f64>,
    y2: Vec<f64>,
    core: Vec<f64>,
    g: [Mat<f64>; 3],
}

/// `out = src x_mode A` for internal buffers whose shapes are consistent by construction.
fn product(
    src: &[f64],
    dims: [usize; 3],
    mode: usize,
    a: MatRef<'_, f64>,
    out: &mut [f64],
) -> Result<[usize; 3], HosvdError> {
    let od = product_dims(dims, mode, a.nrows());
    debug_assert_eq!(out.len(), od[0] * od[1] * od[2]);
    mode_product_into(src, dims, mode, a, out)?;
    Ok(od)
}

fn run(
    x: &Tensor3,
    r: [usize; 3],
    start: [MatRef<'_, f64>; 3],
    opts: &AlsOptions,
) -> Result<(Tucker, AlsReport), HosvdError> {
    let d = x.dims();
    let x_norm2 = x.squared_norm();
    let x_norm = x_norm2.sqrt();
    let mut u: [Mat<f64>; 3] = std::array::from_fn(|n| start[n].to_owned());
    let mut b = Buffers {
        w2: vec![0.0; d[0] * d[1] * r[2]],
        y0: vec![0.0; d[0] * r[1] * r[2]],
        y1: vec![0.0; r[0] * d[1] * r[2]],
        w0: vec![0.0; r[0] * d[1] * d[2]],
        y2: vec![0.0; r[0] * r[1] * d[2]],
        core: vec![0.0; r[0] * r[1] * r[2]],
        g: std::array::from_fn(|n| Mat::<f64>::zeros(d[n], d[n])),
    };
    let mut prev_norm: Option<f64> = None;
    let mut core_norm2 = 0.0;
    let mut iterations = 0;
    let mut converged = false;
    while iterations < opts.max_iter {
        iterations += 1;
        // Mode 0: Y0 = X x_1 U1^T x_2 U2^T (I0 x R1 x R2).
        let dw2 = product(x.as_slice(), d, 2, u[2].transpose(), &mut b.w2)?;
        let dy0 = product(&b.w2, dw2, 1, u[1].transpose(), &mut b.y0)?;
        gram_into(&b.y0, dy0, 0, b.g[0].as_mut());
        if prev_norm.is_none() {
            // ||Z_start||^2 = trace(U0^T G0 U0) with the start factors.
            prev_norm = Some(quad_trace(b.g[0].as_ref(), u[0].as_ref()).max(0.0).sqrt());
        }
        u[0] = leading_eigen(b.g[0].as_ref(), r[0], 0)?.1;
        // Mode 1: Y1 = X x_0 U0^T x_2 U2^T (R0 x I1 x R2), reusing X x_2 U2^T.
        let dy1 = product(&b.w2, dw2, 0, u[0].transpose(), &mut b.y1)?;
        gram_into(&b.y1, dy1, 1, b.g[1].as_mut());
        u[1] = leading_eigen(b.g[1].as_ref(), r[1], 1)?.1;
        // Mode 2: Y2 = X x_0 U0^T x_1 U1^T (R0 x R1 x I2).
        let dw0 = product(x.as_slice(), d, 0, u[0].transpose(), &mut b.w0)?;
        let dy2 = product(&b.w0, dw0, 1, u[1].transpose(), &mut b.y2)?;
        gram_into(&b.y2, dy2, 2, b.g[2].as_mut());
        u[2] = leading_eigen(b.g[2].as_ref(), r[2], 2)?.1;
        // Core Z = Y2 x_2 U2^T.
        product(&b.y2, dy2, 2, u[2].transpose(), &mut b.core)?;
        core_norm2 = tensor_ops::squared_norm(&b.core);
        let norm = core_norm2.sqrt();
        let change = (norm - prev_norm.unwrap_or(0.0)).abs();
        prev_norm = Some(norm);
        if x_norm == 0.0 || change / x_norm < opts.tol {
            converged = true;
            break;
        }
    }
    let core = Tensor3::from_vec(r, std::mem::take(&mut b.core))?;
    let tucker = Tucker { core, factors: u }.into_ordered()?;
    let (mse, rel_error) = projection_errors(x_norm2, core_norm2, x.len());
    Ok((
        tucker,
        AlsReport {
            iterations,
            rel_error,
            mse,
            converged,
        },
    ))
}

/// `trace(U^T G U) = sum_c u_c^T G u_c`.
fn quad_trace(g: MatRef<'_, f64>, u: MatRef<'_, f64>) -> f64 {
    let mut t = 0.0;
    for c in 0..u.ncols() {
        for j in 0..g.ncols() {
            let uj = u[(j, c)];
            let mut s = 0.0;
            for i in 0..g.nrows() {
                s += g[(i, j)] * u[(i, c)];
            }
            t += s * uj;
        }
    }
    t
}
