//! n-mode products of a tensor with a matrix or a vector, and Tucker reconstruction.
//!
//! The n-mode product (de Lathauwer et al. 2000, Definition 8) of `X` (`I_0 x I_1 x I_2`) with
//! `A` (`J x I_n`) is the tensor `Y = X x_n A` with `I_n` replaced by `J`:
//!
//! `Y(.., j, ..) = sum_{i_n} A(j, i_n) X(.., i_n, ..)`,  equivalently `Y_(n) = A X_(n)`.
//!
//! Every product here is one or a few faer matrix products on zero-copy views of the storage
//! (no unfolding is materialised). [`mode_product_into`] spreads a large product over the current
//! rayon pool with the bits of the single-threaded product ([`crate::par::matmul_blocked`], or
//! its slices in parallel for mode 1), so the result is the same for any thread count.

use crate::par::{PARALLEL_MIN_FLOPS, matmul_blocked};
use crate::tensor::{check_mode, checked_len};
use crate::{Tensor3, TensorError};
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatMut, MatRef, Par};
use rayon::prelude::*;

/// Mode-1 slices one parallel task of [`mode_product_into`] takes at least.
const SLICES_PER_TASK: usize = 16;

/// Shape of `X x_mode A` for a tensor of shape `dims` and a matrix with `rows` rows.
///
/// Errors: [`TensorError::BadMode`] if `mode >= 3`.
pub fn product_dims(dims: [usize; 3], mode: usize, rows: usize) -> Result<[usize; 3], TensorError> {
    check_mode(mode)?;
    let mut d = dims;
    d[mode] = rows;
    Ok(d)
}

/// Writes `X x_mode A` into `out` (length `I J K` with `I_mode` replaced by `A.nrows()`),
/// without allocating. `x` is the storage of a tensor of shape `dims`.
///
/// Errors: [`TensorError::BadMode`], [`TensorError::ShapeMismatch`] when `A.ncols() != dims[mode]`,
/// `x.len()` or `out.len()` do not match.
pub fn mode_product_into(
    x: &[f64],
    dims: [usize; 3],
    mode: usize,
    a: MatRef<'_, f64>,
    out: &mut [f64],
) -> Result<(), TensorError> {
    check_mode(mode)?;
    let len = checked_len(dims)?;
    if x.len() != len {
        return Err(TensorError::ShapeMismatch {
            what: "mode_product_into: tensor data length",
            expected: len,
            found: x.len(),
        });
    }
    if a.ncols() != dims[mode] {
        return Err(TensorError::ShapeMismatch {
            what: "mode_product: matrix columns (mode size)",
            expected: dims[mode],
            found: a.ncols(),
        });
    }
    let od = product_dims(dims, mode, a.nrows())?;
    let olen = checked_len(od)?;
    if out.len() != olen {
        return Err(TensorError::ShapeMismatch {
            what: "mode_product_into: output length",
            expected: olen,
            found: out.len(),
        });
    }
    if olen == 0 {
        return Ok(());
    }
    if len == 0 {
        out.fill(0.0);
        return Ok(());
    }
    let [i0, i1, i2] = dims;
    match mode {
        0 => {
            // Y as J x (I1 I2) = A (J x I0) * X as I0 x (I1 I2).
            let xm = MatRef::from_column_major_slice(x, i0, i1 * i2);
            let om = MatMut::from_column_major_slice_mut(out, od[0], i1 * i2);
            matmul_blocked(om, a, xm);
        }
        1 => {
            // Per slice k: Y_k (I0 x J) = X_k (I0 x I1) * A^T (I1 x J), each slice on its own
            // (single-threaded), slices in parallel when the product is large.
            let ob = i0 * od[1];
            let slice = |(k, oslice): (usize, &mut [f64])| {
                let xk =
                    MatRef::from_column_major_slice(&x[k * i0 * i1..(k + 1) * i0 * i1], i0, i1);
                let om = MatMut::from_column_major_slice_mut(oslice, i0, od[1]);
                matmul(om, Accum::Replace, xk, a.transpose(), 1.0, Par::Seq);
            };
            if olen * i1 < PARALLEL_MIN_FLOPS {
                out.chunks_exact_mut(ob).enumerate().for_each(slice);
            } else {
                out.par_chunks_exact_mut(ob)
                    .enumerate()
                    .with_min_len(SLICES_PER_TASK)
                    .for_each(slice);
            }
        }
        _ => {
            // Y as (I0 I1) x J = X as (I0 I1) x I2 * A^T.
            let xm = MatRef::from_column_major_slice(x, i0 * i1, i2);
            let om = MatMut::from_column_major_slice_mut(out, i0 * i1, od[2]);
            matmul_blocked(om, xm, a.transpose());
        }
    }
    Ok(())
}

/// Writes `X x_mode v^T` (the contraction of mode `mode` with the vector `v`) into `out`, a
/// matrix over the two remaining modes in increasing mode order: `out(p, q) = sum_i v_i X(.., i, ..)`
/// with `(p, q)` = `(j, k)` for mode 0, `(i, k)` for mode 1, `(i, j)` for mode 2. No allocation.
///
/// Errors: [`TensorError::BadMode`], [`TensorError::ShapeMismatch`] for a wrong `v` length,
/// data length or output shape.
pub fn mode_vec_product_into(
    x: &[f64],
    dims: [usize; 3],
    mode: usize,
    v: &[f64],
    mut out: MatMut<'_, f64>,
) -> Result<(), TensorError> {
    check_mode(mode)?;
    let len = checked_len(dims)?;
    if x.len() != len {
        return Err(TensorError::ShapeMismatch {
            what: "mode_vec_product_into: tensor data length",
            expected: len,
            found: x.len(),
        });
    }
    if v.len() != dims[mode] {
        return Err(TensorError::ShapeMismatch {
            what: "mode_vec_product: vector length (mode size)",
            expected: dims[mode],
            found: v.len(),
        });
    }
    let (p, q) = match mode {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    };
    if out.nrows() != dims[p] {
        return Err(TensorError::ShapeMismatch {
            what: "mode_vec_product_into: output rows",
            expected: dims[p],
            found: out.nrows(),
        });
    }
    if out.ncols() != dims[q] {
        return Err(TensorError::ShapeMismatch {
            what: "mode_vec_product_into: output columns",
            expected: dims[q],
            found: out.ncols(),
        });
    }
    let [i0, i1, i2] = dims;
    out.fill(0.0);
    match mode {
        0 => {
            for k in 0..i2 {
                for j in 0..i1 {
                    let o = i0 * (j + i1 * k);
                    let fibre = &x[o..o + i0];
                    let mut acc = 0.0;
                    for (a, b) in fibre.iter().zip(v) {
                        acc += a * b;
                    }
                    out[(j, k)] = acc;
                }
            }
        }
        1 => {
            for k in 0..i2 {
                for (j, &vj) in v.iter().enumerate() {
                    let o = i0 * (j + i1 * k);
                    for i in 0..i0 {
                        out[(i, k)] += vj * x[o + i];
                    }
                }
            }
        }
        _ => {
            for (k, &vk) in v.iter().enumerate() {
                for j in 0..i1 {
                    let o = i0 * (j + i1 * k);
                    for i in 0..i0 {
                        out[(i, j)] += vk * x[o + i];
                    }
                }
            }
        }
    }
    Ok(())
}

impl Tensor3 {
    /// The n-mode product `X x_mode A` with `A` of shape `J x I_mode` (de Lathauwer et al.
    /// 2000, Def. 8; `Y_(n) = A X_(n)`).
    ///
    /// # Panics
    /// If `mode >= 3` or `A.ncols() != I_mode`; use [`Tensor3::try_mode_product`] for untrusted shapes.
    pub fn mode_product(&self, mode: usize, a: MatRef<'_, f64>) -> Tensor3 {
        self.try_mode_product(mode, a)
            .expect("Tensor3::mode_product")
    }

    /// Checked [`Tensor3::mode_product`]. NaN/inf in `A` propagate and are reported as
    /// [`TensorError::NonFinite`].
    pub fn try_mode_product(
        &self,
        mode: usize,
        a: MatRef<'_, f64>,
    ) -> Result<Tensor3, TensorError> {
        check_mode(mode)?;
        let od = product_dims(self.dims(), mode, a.nrows())?;
        let mut out = vec![0.0; checked_len(od)?];
        mode_product_into(self.as_slice(), self.dims(), mode, a, &mut out)?;
        Tensor3::from_vec(od, out)
    }

    /// The n-mode product with a vector, `X x_mode v^T`, as a matrix over the remaining two
    /// modes in increasing order (`J x K` for mode 0, `I x K` for mode 1, `I x J` for mode 2).
    ///
    /// # Panics
    /// If `mode >= 3` or `v.len() != I_mode`; use [`Tensor3::try_mode_vec_product`] for untrusted shapes.
    pub fn mode_vec_product(&self, mode: usize, v: &[f64]) -> Mat<f64> {
        self.try_mode_vec_product(mode, v)
            .expect("Tensor3::mode_vec_product")
    }

    /// Checked [`Tensor3::mode_vec_product`].
    pub fn try_mode_vec_product(&self, mode: usize, v: &[f64]) -> Result<Mat<f64>, TensorError> {
        check_mode(mode)?;
        let d = self.dims();
        let (p, q) = match mode {
            0 => (1, 2),
            1 => (0, 2),
            _ => (0, 1),
        };
        let mut out = Mat::<f64>::zeros(d[p], d[q]);
        mode_vec_product_into(self.as_slice(), d, mode, v, out.as_mut())?;
        Ok(out)
    }
}

/// Tucker reconstruction `X = Z x_0 U_0 x_1 U_1 x_2 U_2` (paper eq. 2/3) from a core `Z`
/// (`R_0 x R_1 x R_2`) and factors `U_n` (`I_n x R_n`).
///
/// # Panics
/// If `factors[n].ncols() != core.dims()[n]`; use [`try_reconstruct`] for untrusted shapes.
pub fn reconstruct(core: &Tensor3, factors: [MatRef<'_, f64>; 3]) -> Tensor3 {
    try_reconstruct(core, factors).expect("tensor_ops::reconstruct")
}

/// Checked [`reconstruct`]: [`TensorError::ShapeMismatch`] when a factor's column count differs
/// from the core's size in that mode.
pub fn try_reconstruct(
    core: &Tensor3,
    factors: [MatRef<'_, f64>; 3],
) -> Result<Tensor3, TensorError> {
    for (mode, f) in factors.iter().enumerate() {
        if f.ncols() != core.dims()[mode] {
            return Err(TensorError::ShapeMismatch {
                what: "reconstruct: factor columns (core size)",
                expected: core.dims()[mode],
                found: f.ncols(),
            });
        }
    }
    let t = core.try_mode_product(0, factors[0])?;
    let t = t.try_mode_product(1, factors[1])?;
    t.try_mode_product(2, factors[2])
}
