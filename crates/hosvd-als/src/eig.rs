//! Leading eigenvectors of symmetric (Gram) matrices, deterministic and single-threaded.

use crate::HosvdError;
use faer::diag::Diag;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::evd::{ComputeEigenvectors, self_adjoint_evd, self_adjoint_evd_scratch};
use faer::{Mat, MatMut, MatRef, Par};

/// Eigenvalues in decreasing order and the matching leading `r` eigenvectors (columns) of the
/// symmetric matrix `g`, using only its lower triangle.
///
/// faer returns eigenvalues in increasing order; they are reversed here. Each eigenvector is
/// sign-normalised so that its largest-magnitude entry (first one on ties) is positive, which
/// makes the result a deterministic function of `g`. `mode` only labels errors:
/// [`HosvdError::GramOverflow`] when the lower triangle holds a non-finite entry (a Gram matrix of
/// finite data that overflowed), [`HosvdError::Eigen`] when the solver fails.
pub(crate) fn leading_eigen(
    g: MatRef<'_, f64>,
    r: usize,
    mode: usize,
) -> Result<(Vec<f64>, Mat<f64>), HosvdError> {
    let n = g.nrows();
    debug_assert_eq!(n, g.ncols());
    debug_assert!(r <= n);
    if (0..n).any(|j| (j..n).any(|i| !g[(i, j)].is_finite())) {
        return Err(HosvdError::GramOverflow { mode, size: n });
    }
    let mut s = Diag::<f64>::zeros(n);
    let mut u = Mat::<f64>::zeros(n, n);
    let req =
        self_adjoint_evd_scratch::<f64>(n, ComputeEigenvectors::Yes, Par::Seq, Default::default());
    let mut buf = MemBuffer::new(req);
    self_adjoint_evd(
        g,
        s.as_mut(),
        Some(u.as_mut()),
        Par::Seq,
        MemStack::new(&mut buf),
        Default::default(),
    )
    .map_err(|_| HosvdError::Eigen { mode, size: n })?;
    let sv = s.column_vector();
    let values: Vec<f64> = (0..n).rev().map(|i| sv[i]).collect();
    let mut lead = Mat::<f64>::zeros(n, r);
    for c in 0..r {
        let src = n - 1 - c;
        for i in 0..n {
            lead[(i, c)] = u[(i, src)];
        }
    }
    normalize_signs(lead.as_mut());
    Ok((values, lead))
}

/// The leading `r` left singular vectors of the mode-2 unfolding `Y_(2)` (`I_2 x I_0 I_1`) of the
/// tensor with storage `y` and shape `dims`, when it has more rows than columns (`I_2 > I_0 I_1`,
/// more samples than fibres): from the eigenvectors `V` of the smaller Gram `Y_(2)^T Y_(2)`
/// (`I_0 I_1` square) as `U = Y_(2) V Lambda^(-1/2)`, re-orthonormalised (modified Gram-Schmidt)
/// and sign-normalised as [`leading_eigen`]'s. The same subspace as the eigenvectors of
/// `Y_(2) Y_(2)^T` (`I_2` square, `I_2^3` work) in `(I_0 I_1)^3` work. `None` when a leading
/// eigenvalue is not above `1e-13` of the largest (a rank-deficient unfolding: the caller takes
/// the larger Gram).
pub(crate) fn leading_mode2_vectors(
    y: &[f64],
    dims: [usize; 3],
    r: usize,
) -> Result<Option<Mat<f64>>, HosvdError> {
    use tensor_ops::par::matmul_blocked;
    let (m, s) = (dims[0] * dims[1], dims[2]);
    debug_assert!(s > m && r <= m);
    // Columns of `y_mat` are the samples: Y_(2)^T.
    let y_mat = MatRef::from_column_major_slice(y, m, s);
    let mut h = Mat::<f64>::zeros(m, m);
    matmul_blocked(h.as_mut(), y_mat, y_mat.transpose());
    let (values, v) = leading_eigen(h.as_ref(), r, 2)?;
    let top = values.first().copied().unwrap_or(0.0);
    // Also false for NaN: a leading value that is not clearly positive sends the caller back.
    let clear = |l: f64| l.is_finite() && l > 1e-13 * top;
    if !(top.is_finite() && top > 0.0 && values[..r].iter().all(|&l| clear(l))) {
        return Ok(None);
    }
    let mut u = Mat::<f64>::zeros(s, r);
    matmul_blocked(u.as_mut(), y_mat.transpose(), v.as_ref());
    for c in 0..r {
        for k in 0..c {
            let dot: f64 = (0..s).map(|i| u[(i, k)] * u[(i, c)]).sum();
            for i in 0..s {
                u[(i, c)] -= dot * u[(i, k)];
            }
        }
        let norm = (0..s).map(|i| u[(i, c)] * u[(i, c)]).sum::<f64>().sqrt();
        if !(norm > 0.0 && norm.is_finite()) {
            return Ok(None);
        }
        for i in 0..s {
            u[(i, c)] /= norm;
        }
    }
    normalize_signs(u.as_mut());
    Ok(Some(u))
}

/// Flips columns so that each column's largest-magnitude entry is positive. Returns which
/// columns were flipped.
pub(crate) fn normalize_signs(mut m: MatMut<'_, f64>) -> Vec<bool> {
    let mut flipped = Vec::with_capacity(m.ncols());
    for c in 0..m.ncols() {
        let mut best = 0.0f64;
        let mut sign = 1.0;
        for i in 0..m.nrows() {
            let v = m[(i, c)];
            if v.abs() > best {
                best = v.abs();
                sign = v.signum();
            }
        }
        let flip = sign < 0.0;
        if flip {
            for i in 0..m.nrows() {
                m[(i, c)] = -m[(i, c)];
            }
        }
        flipped.push(flip);
    }
    flipped
}
