//! Higher-order SVD, full and truncated (de Lathauwer et al. 2000; paper eq. 2 and 3).

use crate::eig::leading_eigen;
use crate::gram::gram_into;
use crate::project::multi_product;
use crate::{HosvdError, Tucker};
use faer::Mat;
use tensor_ops::{Tensor3, check_ranks};

/// Checks that `x` is non-empty and finite and that `ranks` fit its dims.
pub(crate) fn validate(x: &Tensor3, ranks: [usize; 3]) -> Result<(), HosvdError> {
    if x.is_empty() {
        return Err(HosvdError::EmptyTensor { dims: x.dims() });
    }
    x.check_finite()?;
    check_ranks(x.dims(), ranks)?;
    Ok(())
}

/// The leading `ranks[n]` eigenvectors of each mode's Gram matrix `X_(n) X_(n)^T`, i.e. the
/// leading left singular vectors of each unfolding, without any SVD of a wide unfolding.
pub(crate) fn hosvd_factors(x: &Tensor3, ranks: [usize; 3]) -> Result<[Mat<f64>; 3], HosvdError> {
    let mut out: [Mat<f64>; 3] = std::array::from_fn(|_| Mat::<f64>::zeros(0, 0));
    for (mode, f) in out.iter_mut().enumerate() {
        *f = mode_factor(x, mode, ranks[mode])?;
    }
    Ok(out)
}

/// The leading `rank` eigenvectors of mode `mode`'s Gram matrix `X_(n) X_(n)^T`: one HOSVD factor.
pub(crate) fn mode_factor(x: &Tensor3, mode: usize, rank: usize) -> Result<Mat<f64>, HosvdError> {
    let d = x.dims();
    let mut g = Mat::<f64>::zeros(d[mode], d[mode]);
    gram_into(x.as_slice(), d, mode, g.as_mut());
    Ok(leading_eigen(g.as_ref(), rank, mode)?.1)
}

/// The projection core `Z = X x_0 U_0^T x_1 U_1^T x_2 U_2^T`.
pub(crate) fn project_core(x: &Tensor3, factors: &[Mat<f64>; 3]) -> Result<Tensor3, HosvdError> {
    Ok(multi_product(
        x,
        [
            Some(factors[0].transpose()),
            Some(factors[1].transpose()),
            Some(factors[2].transpose()),
        ],
    )?)
}

/// Truncated HOSVD at `ranks` (paper eq. 3): `U_n` = the leading `R_n` eigenvectors of the
/// mode-n Gram matrix `X_(n) X_(n)^T` (eigenvalues = squared mode-n singular values),
/// `Z = X x_0 U_0^T x_1 U_1^T x_2 U_2^T`. The returned core is rotated into ordered form
/// ([`Tucker::into_ordered`]); the model `X~` is the truncated HOSVD's.
///
/// Errors: [`HosvdError::EmptyTensor`], NaN/inf in `x` or a rank that is zero or above its mode
/// size ([`HosvdError::Tensor`]), [`HosvdError::GramOverflow`] when the data are so large that a
/// Gram matrix overflows (values around `1e154` and above), [`HosvdError::Eigen`].
pub fn hosvd(x: &Tensor3, ranks: [usize; 3]) -> Result<Tucker, HosvdError> {
    validate(x, ranks)?;
    let factors = hosvd_factors(x, ranks)?;
    let core = project_core(x, &factors)?;
    let t = Tucker { core, factors };
    if ranks == x.dims() {
        // The full HOSVD core is all-orthogonal and ordered by construction (Th. 2).
        Ok(t)
    } else {
        t.into_ordered()
    }
}

/// Full HOSVD (paper eq. 2): square orthogonal factors, `X = Z x_0 U_0 x_1 U_1 x_2 U_2` exactly
/// (up to rounding), the core all-orthogonal with decreasing mode-n singular values.
pub fn hosvd_full(x: &Tensor3) -> Result<Tucker, HosvdError> {
    hosvd(x, x.dims())
}
