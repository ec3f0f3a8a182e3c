//! The dense three-mode tensor: storage, element access, norm, truncation and sample blocks.

use crate::TensorError;
use faer::MatRef;

/// A dense real `I x J x K` tensor, element `(i, j, k)` stored at `i + I * (j + J * k)`
/// (first index fastest, numpy's Fortran order; see `docs/architecture.md`).
///
/// Mode 0 is the joint-DOF mode (P), mode 1 time (T), mode 2 samples (S). Each slice `k` of
/// mode 2 is a contiguous `I x J` column-major block ([`Tensor3::sample`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Tensor3 {
    dims: [usize; 3],
    data: Vec<f64>,
}

/// Number of elements of a tensor with `dims`, or [`TensorError::DimsOverflow`] when the product
/// of the *nonzero* dimensions overflows `usize`: an empty tensor of dims `[0, usize::MAX, 2]`
/// would make every product of two dimensions (unfolding widths, slice sizes) wrap.
pub(crate) fn checked_len(dims: [usize; 3]) -> Result<usize, TensorError> {
    dims.iter()
        .try_fold(1usize, |acc, &d| acc.checked_mul(d.max(1)))
        .ok_or(TensorError::DimsOverflow { dims })?;
    Ok(dims[0] * dims[1] * dims[2])
}

/// Checks that `mode < 3`.
pub(crate) fn check_mode(mode: usize) -> Result<(), TensorError> {
    if mode < 3 {
        Ok(())
    } else {
        Err(TensorError::BadMode { mode })
    }
}

/// Checks `1 <= ranks[n] <= dims[n]` for every mode.
pub fn check_ranks(dims: [usize; 3], ranks: [usize; 3]) -> Result<(), TensorError> {
    for mode in 0..3 {
        if ranks[mode] == 0 || ranks[mode] > dims[mode] {
            return Err(TensorError::BadRank {
                mode,
                rank: ranks[mode],
                size: dims[mode],
            });
        }
    }
    Ok(())
}

impl Tensor3 {
    /// An all-zero tensor of shape `dims` (a zero dimension gives an empty tensor).
    ///
    /// # Panics
    /// If the element count, or the product of the nonzero dimensions, overflows `usize` (no
    /// allocation could hold it anyway; see [`TensorError::DimsOverflow`]).
    pub fn zeros(dims: [usize; 3]) -> Self {
        let len = checked_len(dims).expect("Tensor3::zeros: dims overflow usize");
        Self {
            dims,
            data: vec![0.0; len],
        }
    }

    /// Wraps `data` laid out as `i + I * (j + J * k)`.
    ///
    /// Errors: [`TensorError::DimsOverflow`] if the product of the nonzero dimensions overflows
    /// `usize` (even for an empty tensor), [`TensorError::SizeMismatch`] if `data.len() != I J K`,
    /// [`TensorError::NonFinite`] (with the index of the first bad value) if any value is NaN or
    /// infinite.
    pub fn from_vec(dims: [usize; 3], data: Vec<f64>) -> Result<Self, TensorError> {
        let expected = checked_len(dims)?;
        if data.len() != expected {
            return Err(TensorError::SizeMismatch {
                dims,
                expected,
                found: data.len(),
            });
        }
        let t = Self { dims, data };
        t.check_finite()?;
        Ok(t)
    }

    /// Builds a tensor from a function of the index `(i, j, k)`. Non-finite results are
    /// rejected like in [`Tensor3::from_vec`].
    pub fn from_fn(
        dims: [usize; 3],
        mut f: impl FnMut(usize, usize, usize) -> f64,
    ) -> Result<Self, TensorError> {
        let len = checked_len(dims)?;
        let mut data = Vec::with_capacity(len);
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    data.push(f(i, j, k));
                }
            }
        }
        Self::from_vec(dims, data)
    }

    /// Returns the first NaN or infinite value with its index, if any.
    pub fn check_finite(&self) -> Result<(), TensorError> {
        match self.data.iter().position(|v| !v.is_finite()) {
            None => Ok(()),
            Some(pos) => {
                let [i, j, k] = self.index_of(pos);
                Err(TensorError::NonFinite {
                    i,
                    j,
                    k,
                    value: self.data[pos],
                })
            }
        }
    }

    /// The index `(i, j, k)` of linear position `pos` (`pos < len()`).
    ///
    /// # Panics
    /// If `I` or `J` is zero (an empty tensor has no positions).
    pub fn index_of(&self, pos: usize) -> [usize; 3] {
        let [ni, nj, _] = self.dims;
        [pos % ni, (pos / ni) % nj, pos / (ni * nj)]
    }

    /// The shape `[I, J, K]`.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Number of elements `I J K`.
    pub fn len(&self) -> usize {
        self.data.len()
    }

    /// True when some dimension is zero.
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// The elements in storage order `i + I * (j + J * k)`.
    pub fn as_slice(&self) -> &[f64] {
        &self.data
    }

    /// Mutable elements in storage order. Writing NaN/inf here is not checked until a
    /// decomposition or [`Tensor3::check_finite`] looks at the data.
    pub fn as_mut_slice(&mut self) -> &mut [f64] {
        &mut self.data
    }

    /// Consumes the tensor and returns its storage.
    pub fn into_vec(self) -> Vec<f64> {
        self.data
    }

    /// Linear position of `(i, j, k)`.
    #[inline]
    fn offset(&self, i: usize, j: usize, k: usize) -> usize {
        debug_assert!(i < self.dims[0] && j < self.dims[1] && k < self.dims[2]);
        i + self.dims[0] * (j + self.dims[1] * k)
    }

    /// Element `(i, j, k)`.
    ///
    /// # Panics
    /// If an index is out of range.
    #[inline]
    pub fn get(&self, i: usize, j: usize, k: usize) -> f64 {
        assert!(
            i < self.dims[0] && j < self.dims[1] && k < self.dims[2],
            "Tensor3::get({i}, {j}, {k}) out of range for dims {:?}",
            self.dims
        );
        self.data[self.offset(i, j, k)]
    }

    /// Sets element `(i, j, k)`.
    ///
    /// # Panics
    /// If an index is out of range.
    #[inline]
    pub fn set(&mut self, i: usize, j: usize, k: usize, value: f64) {
        assert!(
            i < self.dims[0] && j < self.dims[1] && k < self.dims[2],
            "Tensor3::set({i}, {j}, {k}) out of range for dims {:?}",
            self.dims
        );
        let o = self.offset(i, j, k);
        self.data[o] = value;
    }

    /// The contiguous `I x J` column-major block of slice `k` of mode 2 (sample `k`: one
    /// mode-0 vector per mode-1 index, i.e. one pose vector per frame).
    ///
    /// # Panics
    /// If `k >= K`.
    pub fn sample(&self, k: usize) -> &[f64] {
        assert!(
            k < self.dims[2],
            "sample {k} out of range (K = {})",
            self.dims[2]
        );
        let b = self.dims[0] * self.dims[1];
        &self.data[k * b..(k + 1) * b]
    }

    /// Slice `k` of mode 2 as an `I x J` matrix view (no copy).
    ///
    /// # Panics
    /// If `k >= K`.
    pub fn sample_mat(&self, k: usize) -> MatRef<'_, f64> {
        MatRef::from_column_major_slice(self.sample(k), self.dims[0], self.dims[1])
    }

    /// The data seen as the `I x (J K)` column-major matrix whose column `j + J k` is the
    /// mode-0 fibre `X(:, j, k)` (no copy).
    ///
    /// This is the mode-0 unfolding with Kolda's column order; it differs from
    /// [`Tensor3::unfold`]`(0)` (de Lathauwer's order) by a column permutation only, so its
    /// Gram matrix and left singular vectors are the same.
    pub fn as_mode0_matrix(&self) -> MatRef<'_, f64> {
        MatRef::from_column_major_slice(&self.data, self.dims[0], self.dims[1] * self.dims[2])
    }

    /// The data seen as the `(I J) x K` column-major matrix whose column `k` is sample `k`
    /// flattened (no copy). Its transpose is the mode-2 unfolding up to a column permutation.
    pub fn as_mode2_matrix(&self) -> MatRef<'_, f64> {
        MatRef::from_column_major_slice(&self.data, self.dims[0] * self.dims[1], self.dims[2])
    }

    /// Frobenius norm `||X||_F = sqrt(sum_ijk x_ijk^2)`, accumulated in a fixed order.
    pub fn frobenius_norm(&self) -> f64 {
        self.squared_norm().sqrt()
    }

    /// Squared Frobenius norm `sum_ijk x_ijk^2`, accumulated in a fixed order.
    pub fn squared_norm(&self) -> f64 {
        squared_norm(&self.data)
    }

    /// The leading sub-tensor `X(0..R0, 0..R1, 0..R2)`.
    ///
    /// Errors: [`TensorError::BadRank`] if some rank is zero or exceeds its mode size.
    pub fn truncate(&self, ranks: [usize; 3]) -> Result<Tensor3, TensorError> {
        check_ranks(self.dims, ranks)?;
        let mut data = Vec::with_capacity(ranks[0] * ranks[1] * ranks[2]);
        for k in 0..ranks[2] {
            for j in 0..ranks[1] {
                let o = self.offset(0, j, k);
                data.extend_from_slice(&self.data[o..o + ranks[0]]);
            }
        }
        Ok(Tensor3 { dims: ranks, data })
    }

    /// Squared Frobenius norm of the leading sub-tensor `X(0..R0, 0..R1, 0..R2)` without
    /// copying it. Ranks larger than the dims are clamped.
    pub fn leading_squared_norm(&self, ranks: [usize; 3]) -> f64 {
        let r = [
            ranks[0].min(self.dims[0]),
            ranks[1].min(self.dims[1]),
            ranks[2].min(self.dims[2]),
        ];
        let mut acc = 0.0;
        for k in 0..r[2] {
            for j in 0..r[1] {
                if r[0] > 0 {
                    let o = self.offset(0, j, k);
                    acc += squared_norm(&self.data[o..o + r[0]]);
                }
            }
        }
        acc
    }
}

/// Sum of squares of `v` with four independent accumulators (fixed order, deterministic).
pub fn squared_norm(v: &[f64]) -> f64 {
    let mut acc = [0.0f64; 4];
    let chunks = v.chunks_exact(4);
    let rest = chunks.remainder();
    for c in chunks {
        acc[0] += c[0] * c[0];
        acc[1] += c[1] * c[1];
        acc[2] += c[2] * c[2];
        acc[3] += c[3] * c[3];
    }
    let mut tail = 0.0;
    for x in rest {
        tail += x * x;
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}
