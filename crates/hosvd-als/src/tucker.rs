//! The Tucker model `X ~ Z x_0 U_0 x_1 U_1 x_2 U_2` with an ordered core.

use crate::HosvdError;
use crate::eig::{leading_eigen, normalize_signs};
use crate::gram::gram_into;
use crate::project::multi_product;
use crate::storage::tucker_bytes;
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatMut, Par};
use tensor_ops::{Tensor3, TensorError, check_ranks, mode_vec_product_into};

/// A Tucker decomposition (paper eq. 2/3): core `Z` (`R_0 x R_1 x R_2`) and factors `U_n`
/// (`I_n x R_n`, orthonormal columns; the paper writes their transposes).
///
/// Every `Tucker` built by this crate has an *ordered* core: all-orthogonal (the mode-n slices
/// of `Z` are mutually orthogonal) with the mode-n singular values `||Z(.., r, ..)||` decreasing
/// in `r`, so [`Tucker::truncate`] to leading sub-blocks is the natural reduction (paper 4.1).
/// Factor column signs are fixed (largest-magnitude entry positive) for determinism.
///
/// The fields are public; factor `n` must have `R_n` columns, `R_n` the core's size in mode `n`
/// (as every `Tucker` of this crate has). The methods returning `Result` check it
/// ([`Tucker::check`]); [`Tucker::reconstruct`] and [`Tucker::sample_core`] panic on it.
#[derive(Clone, Debug, PartialEq)]
pub struct Tucker {
    /// The core tensor `Z`.
    pub core: Tensor3,
    /// The factor matrices `U_0, U_1, U_2` (`I_n x R_n`).
    pub factors: [Mat<f64>; 3],
}

impl Tucker {
    /// The rank triple `(R_0, R_1, R_2)` (the core's dims).
    pub fn ranks(&self) -> [usize; 3] {
        self.core.dims()
    }

    /// The dims `(I_0, I_1, I_2)` of the approximated tensor (the factors' row counts).
    pub fn dims(&self) -> [usize; 3] {
        [
            self.factors[0].nrows(),
            self.factors[1].nrows(),
            self.factors[2].nrows(),
        ]
    }

    /// Checks that factor `n` has as many columns as the core's size in mode `n` (the invariant
    /// that the public fields let a caller break).
    ///
    /// Errors: [`HosvdError::Tensor`] with [`TensorError::ShapeMismatch`] naming the columns
    /// expected and found.
    pub fn check(&self) -> Result<(), HosvdError> {
        let r = self.ranks();
        for (n, f) in self.factors.iter().enumerate() {
            if f.ncols() != r[n] {
                return Err(TensorError::ShapeMismatch {
                    what: [
                        "Tucker: factor 0 columns (core size in mode 0)",
                        "Tucker: factor 1 columns (core size in mode 1)",
                        "Tucker: factor 2 columns (core size in mode 2)",
                    ][n],
                    expected: r[n],
                    found: f.ncols(),
                }
                .into());
            }
        }
        Ok(())
    }

    /// Squared Frobenius norm of the core, `||Z||^2`. With orthonormal factors and a core that is
    /// the projection `X x_n U_n^T` (HOSVD and HOOI cores are), `||X - X~||^2 = ||X||^2 - ||Z||^2`.
    pub fn core_squared_norm(&self) -> f64 {
        self.core.squared_norm()
    }

    /// Leading truncation (paper 4.1): core `Z(0..R_0, 0..R_1, 0..R_2)` and the first `R_n`
    /// columns of each factor.
    ///
    /// Errors: [`HosvdError::Tensor`] with [`TensorError::BadRank`] if a rank is zero or larger
    /// than the current rank in that mode, [`TensorError::ShapeMismatch`] for inconsistent fields
    /// ([`Tucker::check`]).
    pub fn truncate(&self, ranks: [usize; 3]) -> Result<Tucker, HosvdError> {
        self.check()?;
        let core = self.core.truncate(ranks)?;
        let factors =
            std::array::from_fn(|n| self.factors[n].as_ref().subcols(0, ranks[n]).to_owned());
        Ok(Tucker { core, factors })
    }

    /// The approximation `X~ = Z x_0 U_0 x_1 U_1 x_2 U_2` (`I_0 x I_1 x I_2`).
    ///
    /// # Panics
    /// If the fields are inconsistent ([`Tucker::check`]) or the product overflows to a non-finite
    /// value; see [`Tucker::try_reconstruct`] for the checked form.
    pub fn reconstruct(&self) -> Tensor3 {
        tensor_ops::reconstruct(
            &self.core,
            [
                self.factors[0].as_ref(),
                self.factors[1].as_ref(),
                self.factors[2].as_ref(),
            ],
        )
    }

    /// Checked [`Tucker::reconstruct`].
    ///
    /// Errors: [`TensorError::ShapeMismatch`] for inconsistent fields, [`TensorError::NonFinite`]
    /// when the product overflows.
    pub fn try_reconstruct(&self) -> Result<Tensor3, HosvdError> {
        Ok(tensor_ops::try_reconstruct(
            &self.core,
            [
                self.factors[0].as_ref(),
                self.factors[1].as_ref(),
                self.factors[2].as_ref(),
            ],
        )?)
    }

    /// The per-sample core of paper eq. 7, `K_i = Z x_2 u_{S,i}` (`R_0 x R_1`), where
    /// `u_{S,i}` is row `i` of the mode-2 factor: `K_i(p, t) = sum_s Z(p, t, s) U_2(i, s)`.
    ///
    /// # Panics
    /// If `i >= I_2` or the fields are inconsistent ([`Tucker::check`]); see
    /// [`Tucker::sample_core_into`] for the checked, allocation-free form.
    pub fn sample_core(&self, i: usize) -> Mat<f64> {
        let r = self.ranks();
        let mut out = Mat::<f64>::zeros(r[0], r[1]);
        self.sample_core_into(i, out.as_mut())
            .expect("Tucker::sample_core");
        out
    }

    /// Writes `K_i = Z x_2 u_{S,i}` into `out` (`R_0 x R_1`) without allocating.
    ///
    /// Errors: [`TensorError::ShapeMismatch`] if `i >= I_2`, `out` has the wrong shape or the
    /// fields are inconsistent ([`Tucker::check`]).
    pub fn sample_core_into(&self, i: usize, out: MatMut<'_, f64>) -> Result<(), HosvdError> {
        self.check()?;
        let u2 = &self.factors[2];
        if i >= u2.nrows() {
            return Err(TensorError::ShapeMismatch {
                what: "sample_core: sample index must be below the sample count",
                expected: u2.nrows(),
                found: i,
            }
            .into());
        }
        let r = self.ranks();
        if (out.nrows(), out.ncols()) != (r[0], r[1]) {
            return Err(TensorError::ShapeMismatch {
                what: "sample_core_into: output elements (R_0 x R_1)",
                expected: r[0] * r[1],
                found: out.nrows() * out.ncols(),
            }
            .into());
        }
        // K_i = sum_s U_2(i, s) Z(.., .., s): a weighted sum of contiguous core slices.
        let z = self.core.as_slice();
        let mut out = out;
        out.fill(0.0);
        for s in 0..r[2] {
            let w = u2[(i, s)];
            let block = &z[s * r[0] * r[1]..(s + 1) * r[0] * r[1]];
            for t in 0..r[1] {
                for p in 0..r[0] {
                    out[(p, t)] += w * block[p + r[0] * t];
                }
            }
        }
        Ok(())
    }

    /// `Z x_2 w^T` for a sample-space weight vector `w` (length `R_2`): the blended core
    /// `sum_s w_s Z(.., .., s)` (`R_0 x R_1`, paper eq. 6 with `w_S = w`), written into `out`.
    ///
    /// Errors: [`TensorError::ShapeMismatch`] for a wrong `w` length or `out` shape.
    pub fn blend_core_into(&self, w: &[f64], out: MatMut<'_, f64>) -> Result<(), HosvdError> {
        Ok(mode_vec_product_into(
            self.core.as_slice(),
            self.core.dims(),
            2,
            w,
            out,
        )?)
    }

    /// The mode-n singular values of the core, `sigma^(n)_r = ||Z(.., r, ..)||` (de Lathauwer et
    /// al. 2000, Th. 2), for `r = 0..R_n`. Decreasing for an ordered core.
    ///
    /// Errors: [`TensorError::BadMode`] if `mode >= 3`.
    pub fn mode_singular_values(&self, mode: usize) -> Result<Vec<f64>, HosvdError> {
        if mode >= 3 {
            return Err(TensorError::BadMode { mode }.into());
        }
        let d = self.core.dims();
        let mut s = vec![0.0; d[mode]];
        let z = self.core.as_slice();
        let mut pos = 0;
        for k in 0..d[2] {
            for j in 0..d[1] {
                for i in 0..d[0] {
                    let idx = [i, j, k];
                    s[idx[mode]] += z[pos] * z[pos];
                    pos += 1;
                }
            }
        }
        Ok(s.iter().map(|v| v.sqrt()).collect())
    }

    /// Storage of the core and the three factors in bytes, for elements of `value_bytes` bytes
    /// (8 for f64, 4 for f32; see [`crate::storage`]).
    pub fn bytes(&self, value_bytes: usize) -> usize {
        tucker_bytes(self.dims(), self.ranks(), value_bytes)
    }

    /// Mean squared error `||X - X~||_F^2 / (I_0 I_1 I_2)` computed explicitly by reconstruction
    /// (for verification; decompositions report it from norms without forming `X~`).
    ///
    /// Errors: [`TensorError::ShapeMismatch`] if `x` has other dims than the model or the fields
    /// are inconsistent ([`Tucker::check`]), [`TensorError::NonFinite`] if the reconstruction
    /// overflows.
    pub fn explicit_mse(&self, x: &Tensor3) -> Result<f64, HosvdError> {
        if x.dims() != self.dims() {
            return Err(TensorError::ShapeMismatch {
                what: "explicit_mse: tensor elements",
                expected: self
                    .dims()
                    .iter()
                    .fold(1, |a: usize, &d| a.saturating_mul(d)),
                found: x.len(),
            }
            .into());
        }
        let y = self.try_reconstruct()?;
        let mut acc = 0.0;
        for (a, b) in x.as_slice().iter().zip(y.as_slice()) {
            acc += (a - b) * (a - b);
        }
        Ok(acc / x.len().max(1) as f64)
    }

    /// Rotates core and factors into the ordered form without changing the model `X~`.
    ///
    /// With the HOSVD of the core itself, `Z = W x_0 V_0 x_1 V_1 x_2 V_2` (`V_n` the eigenvectors
    /// of `Z_(n) Z_(n)^T`, eigenvalues decreasing), the same model is `W x_n (U_n V_n)`; `W` is
    /// all-orthogonal and ordered. Column signs of `U_n V_n` are then normalised (largest entry
    /// positive) and the matching core slices flipped.
    ///
    /// Errors: [`TensorError::ShapeMismatch`] for inconsistent fields ([`Tucker::check`]),
    /// [`TensorError::BadRank`] if a rank is zero or above its mode size, and the eigensolver's
    /// errors ([`HosvdError::GramOverflow`], [`HosvdError::Eigen`]).
    pub fn into_ordered(self) -> Result<Tucker, HosvdError> {
        self.check()?;
        let r = self.ranks();
        check_ranks(self.dims(), r)?;
        let mut v: [Mat<f64>; 3] = std::array::from_fn(|_| Mat::<f64>::zeros(0, 0));
        for (mode, vm) in v.iter_mut().enumerate() {
            let mut g = Mat::<f64>::zeros(r[mode], r[mode]);
            gram_into(self.core.as_slice(), r, mode, g.as_mut());
            *vm = leading_eigen(g.as_ref(), r[mode], mode)?.1;
        }
        let vt: [Mat<f64>; 3] = std::array::from_fn(|n| v[n].transpose().to_owned());
        let mut core = multi_product(
            &self.core,
            [
                Some(vt[0].as_ref()),
                Some(vt[1].as_ref()),
                Some(vt[2].as_ref()),
            ],
        )?;
        let mut factors: [Mat<f64>; 3] =
            std::array::from_fn(|n| Mat::<f64>::zeros(self.factors[n].nrows(), r[n]));
        for n in 0..3 {
            matmul(
                factors[n].as_mut(),
                Accum::Replace,
                self.factors[n].as_ref(),
                v[n].as_ref(),
                1.0,
                Par::Seq,
            );
            let flipped = normalize_signs(factors[n].as_mut());
            flip_core_slices(&mut core, n, &flipped);
        }
        Ok(Tucker { core, factors })
    }
}

/// Negates the mode-`mode` slices of `core` whose flag is set.
pub(crate) fn flip_core_slices(core: &mut Tensor3, mode: usize, flipped: &[bool]) {
    if !flipped.iter().any(|&f| f) {
        return;
    }
    let d = core.dims();
    let z = core.as_mut_slice();
    let mut pos = 0;
    for k in 0..d[2] {
        for j in 0..d[1] {
            for i in 0..d[0] {
                if flipped[[i, j, k][mode]] {
                    z[pos] = -z[pos];
                }
                pos += 1;
            }
        }
    }
}
