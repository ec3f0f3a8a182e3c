//! HOOI / ALS: the best rank-`(R_0, R_1, R_2)` Tucker approximation by alternating least squares
//! (de Lathauwer, De Moor, Vandewalle 2000b; paper section 3.2 and 4.1).

use crate::eig::{leading_eigen, leading_mode2_vectors};
use crate::gram::gram_into;
use crate::hosvd::{hosvd_factors, mode_factor, validate};
use crate::project::multi_product;
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
    let start = start_factors(x, ranks)?;
    run(
        x,
        ranks,
        [start[0].as_ref(), start[1].as_ref(), start[2].as_ref()],
        opts,
    )
}

/// HOOI's starting factors: the HOSVD's (`crate::hosvd`), except with more samples (mode 2) than
/// the product of the other two ranks (and a sample rank within that product), where the sample factor is that of the tensor projected on
/// the first two HOSVD factors, `X x_0 U_0^T x_1 U_1^T`, through its smaller Gram (the sequentially
/// truncated HOSVD's last step, Vannieuwenhoven et al. 2012): the `S x S` Gram of a set of
/// thousands of cycles is never formed.
fn start_factors(x: &Tensor3, ranks: [usize; 3]) -> Result<[Mat<f64>; 3], HosvdError> {
    if !fibre_gram_is_smaller([ranks[0], ranks[1], x.dims()[2]], ranks[2]) {
        return hosvd_factors(x, ranks);
    }
    let (u0, u1) = (mode_factor(x, 0, ranks[0])?, mode_factor(x, 1, ranks[1])?);
    let y = multi_product(x, [Some(u0.transpose()), Some(u1.transpose()), None])?;
    let mut g2 = Mat::<f64>::zeros(0, 0);
    let u2 = sample_factor(y.as_slice(), y.dims(), ranks[2], &mut g2)?;
    Ok([u0, u1, u2])
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
    let od = product_dims(dims, mode, a.nrows())?;
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
        // The sample mode's Gram is only formed when it is the smaller one (see `sample_factor`).
        g: std::array::from_fn(|n| {
            let size = if n == 2 && fibre_gram_is_smaller([r[0], r[1], d[2]], r[2]) {
                0
            } else {
                d[n]
            };
            Mat::<f64>::zeros(size, size)
        }),
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
        u[2] = sample_factor(&b.y2, dy2, r[2], &mut b.g[2])?;
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

/// The leading `r` left singular vectors of the mode-2 (sample) unfolding of `y` (shape `dims`):
/// through the `I_0 I_1` Gram when there are more samples than that ([`leading_mode2_vectors`]:
/// a build over thousands of cycles never forms the `S x S` Gram, whose eigenvectors cost `S^3`),
/// else the eigenvectors of the sample Gram, formed in `g` (resized when it is not `I_2`
/// square).
pub(crate) fn sample_factor(
    y: &[f64],
    dims: [usize; 3],
    r: usize,
    g: &mut Mat<f64>,
) -> Result<Mat<f64>, HosvdError> {
    if fibre_gram_is_smaller(dims, r)
        && let Some(u) = leading_mode2_vectors(y, dims, r)?
    {
        return Ok(u);
    }
    if g.nrows() != dims[2] {
        *g = Mat::zeros(dims[2], dims[2]);
    }
    gram_into(y, dims, 2, g.as_mut());
    Ok(leading_eigen(g.as_ref(), r, 2)?.1)
}

/// Whether the sample factor (rank `r`) of a tensor of shape `dims` (`I_0 I_1` fibres, `I_2`
/// samples) comes from the fibre Gram ([`leading_mode2_vectors`]): more samples than fibres, and
/// no more components than fibres.
fn fibre_gram_is_smaller(dims: [usize; 3], r: usize) -> bool {
    let fibres = dims[0] * dims[1];
    dims[2] > fibres && r <= fibres
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic tensor with decaying structure in every mode plus a little noise.
    fn tensor(dims: [usize; 3]) -> Tensor3 {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        Tensor3::from_fn(dims, |i, j, k| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let noise = (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
            let (a, b, c) = (i as f64, j as f64, k as f64);
            (0.3 * a + 0.1 * c).sin() * (1.0 + 0.2 * b).cos()
                + 0.5 * (0.05 * c * (1.0 + a)).cos() * (0.3 * b).sin()
                + 0.1 * (0.01 * c * b).sin()
                + 0.01 * noise
        })
        .expect("finite")
    }

    /// `U U^t`, the projector on the columns of `u`.
    fn projector(u: MatRef<'_, f64>) -> Mat<f64> {
        u * u.transpose()
    }

    #[test]
    fn the_sample_factor_through_the_small_gram_spans_the_large_grams_subspace() {
        // 4 x 5 fibres (20) and 300 samples: the small Gram is 20 square, the large 300.
        let x = tensor([4, 5, 300]);
        let d = x.dims();
        let mut g = Mat::zeros(0, 0);
        let small = sample_factor(x.as_slice(), d, 6, &mut g).expect("small route");
        assert_eq!(g.nrows(), 0, "the large Gram was not formed");
        let mut big = Mat::zeros(d[2], d[2]);
        gram_into(x.as_slice(), d, 2, big.as_mut());
        let large = leading_eigen(big.as_ref(), 6, 2).expect("eigen").1;
        let diff = projector(small.as_ref()) - projector(large.as_ref());
        let worst = (0..d[2])
            .flat_map(|i| (0..d[2]).map(move |j| (i, j)))
            .fold(0.0f64, |m, (i, j)| m.max(diff[(i, j)].abs()));
        assert!(worst < 1e-9, "projectors differ by {worst}");
        // Orthonormal columns, signs as leading_eigen gives them.
        let gram = small.transpose() * small.as_ref();
        for i in 0..6 {
            for j in 0..6 {
                let want = if i == j { 1.0 } else { 0.0 };
                assert!(
                    (gram[(i, j)] - want).abs() < 1e-12,
                    "({i}, {j}): {}",
                    gram[(i, j)]
                );
            }
            assert!((small[(0, i)] * large[(0, i)]) >= 0.0 || small[(0, i)].abs() < 1e-9);
        }
    }

    #[test]
    fn hooi_with_many_samples_reaches_the_error_of_the_large_gram_route() {
        // Ranks 3 x 3 (9 fibres) over 120 samples: HOOI starts from the projected sample factor
        // and updates it through the small Gram; its error is no worse than that of the run
        // started from the classical HOSVD (ALS from two starts stops at two nearby points).
        let x = tensor([6, 7, 120]);
        let opts = AlsOptions::default();
        let ranks = [3, 3, 5];
        let (_, fast) = hooi(&x, ranks, &opts).expect("hooi");
        let classical = hosvd_factors(&x, ranks).expect("hosvd");
        let (_, reference) = hooi_with_start(
            &x,
            [
                classical[0].as_ref(),
                classical[1].as_ref(),
                classical[2].as_ref(),
            ],
            &opts,
        )
        .expect("hooi from the HOSVD");
        assert!(
            fast.mse <= reference.mse * (1.0 + 1e-4),
            "{} against {}",
            fast.mse,
            reference.mse
        );
    }
}
