//! Mode-n unfolding (matricization) and folding with de Lathauwer's column order.
//!
//! De Lathauwer, De Moor and Vandewalle (2000), Definition 1: the mode-n unfolding
//! `A_(n)` is `I_n x (I_{n+1} ... I_N I_1 ... I_{n-1})` and holds `a_{i_1 ... i_N}` in row `i_n`
//! and in a column whose index runs through the remaining modes cyclically, starting after `n`,
//! with the *last* of them fastest. For three modes (0-based here) with `a = n+1 mod 3` and
//! `b = n+2 mod 3`:
//!
//! `A_(n)[i_n, i_a * I_b + i_b] = A[i_0, i_1, i_2]`
//!
//! so `A_(0)` columns are `i_1 I_2 + i_2`, `A_(1)` columns `i_2 I_0 + i_0`, `A_(2)` columns
//! `i_0 I_1 + i_1`. Column order never changes Gram matrices or left singular vectors; for
//! zero-copy views in Kolda's order see [`Tensor3::as_mode0_matrix`].

use crate::tensor::{check_mode, checked_len};
use crate::{Tensor3, TensorError};
use faer::{Mat, MatRef};

/// The two other modes of `mode`, in de Lathauwer's cyclic order `(n+1, n+2) mod 3`.
pub fn cyclic_others(mode: usize) -> (usize, usize) {
    ((mode + 1) % 3, (mode + 2) % 3)
}

impl Tensor3 {
    /// The mode-`mode` unfolding `X_(n)` (`I_n x I_a I_b`), de Lathauwer's column order
    /// `i_a I_b + i_b` with `(a, b) = (n+1, n+2) mod 3` (see the module docs).
    ///
    /// # Panics
    /// If `mode >= 3` (a programming error; use [`Tensor3::try_unfold`] for a checked call).
    pub fn unfold(&self, mode: usize) -> Mat<f64> {
        self.try_unfold(mode).expect("Tensor3::unfold")
    }

    /// Checked [`Tensor3::unfold`]: [`TensorError::BadMode`] if `mode >= 3`.
    pub fn try_unfold(&self, mode: usize) -> Result<Mat<f64>, TensorError> {
        check_mode(mode)?;
        let d = self.dims();
        let (a, b) = cyclic_others(mode);
        let mut m = Mat::<f64>::zeros(d[mode], d[a] * d[b]);
        let x = self.as_slice();
        let mut pos = 0;
        for k in 0..d[2] {
            for j in 0..d[1] {
                for i in 0..d[0] {
                    let idx = [i, j, k];
                    m[(idx[mode], idx[a] * d[b] + idx[b])] = x[pos];
                    pos += 1;
                }
            }
        }
        Ok(m)
    }

    /// Inverse of [`Tensor3::unfold`]: builds the tensor of shape `dims` whose mode-`mode`
    /// unfolding is `m`.
    ///
    /// Errors: [`TensorError::BadMode`], [`TensorError::ShapeMismatch`] if `m` is not
    /// `dims[mode] x (dims[a] dims[b])`, [`TensorError::NonFinite`] for NaN/inf entries.
    pub fn fold(mode: usize, m: MatRef<'_, f64>, dims: [usize; 3]) -> Result<Tensor3, TensorError> {
        check_mode(mode)?;
        let len = checked_len(dims)?;
        let (a, b) = cyclic_others(mode);
        if m.nrows() != dims[mode] {
            return Err(TensorError::ShapeMismatch {
                what: "fold: matrix rows (mode size)",
                expected: dims[mode],
                found: m.nrows(),
            });
        }
        if m.ncols() != dims[a] * dims[b] {
            return Err(TensorError::ShapeMismatch {
                what: "fold: matrix columns (product of the other mode sizes)",
                expected: dims[a] * dims[b],
                found: m.ncols(),
            });
        }
        let mut data = Vec::with_capacity(len);
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    let idx = [i, j, k];
                    data.push(m[(idx[mode], idx[a] * dims[b] + idx[b])]);
                }
            }
        }
        Tensor3::from_vec(dims, data)
    }
}
