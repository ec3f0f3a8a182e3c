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
/// makes the result a deterministic function of `g`. `mode` only labels errors.
pub(crate) fn leading_eigen(
    g: MatRef<'_, f64>,
    r: usize,
    mode: usize,
) -> Result<(Vec<f64>, Mat<f64>), HosvdError> {
    let n = g.nrows();
    debug_assert_eq!(n, g.ncols());
    debug_assert!(r <= n);
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
