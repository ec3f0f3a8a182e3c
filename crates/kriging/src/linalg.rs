//! Small dense linear-algebra helpers on faer, all single-threaded (`Par::Seq`) so that results are
//! bit-identical whatever the size of rayon's pool.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::lu::partial_pivoting::{factor, inverse};
use faer::{Accum, Mat, MatRef, Par};

use crate::error::KrigingError;

/// Largest pivot ratio |u_min| / |u_max| treated as singular.
const PIVOT_RATIO_MIN: f64 = 1e-13;
/// Largest relative residual of the probe solve accepted.
const RESIDUAL_MAX: f64 = 1e-8;

/// `dst = a * b`, single-threaded.
pub(crate) fn matmul(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    let mut dst = Mat::zeros(a.nrows(), b.ncols());
    faer::linalg::matmul::matmul(dst.as_mut(), Accum::Replace, a, b, 1.0, Par::Seq);
    dst
}

/// Inverse of a square matrix by LU with partial pivoting, symmetrised when `symmetric` (the
/// kriging and RBF matrices are symmetric; the LU inverse is only nearly so).
///
/// Fails with [`KrigingError::Singular`] when the smallest/largest absolute pivot is below 1e-13,
/// when the inverse holds a non-finite entry, or when a probe solve `A (A^-1 v) = v` has a relative
/// residual above 1e-8.
pub(crate) fn checked_inverse(
    a: MatRef<'_, f64>,
    symmetric: bool,
    what: &'static str,
) -> Result<Mat<f64>, KrigingError> {
    let n = a.nrows();
    debug_assert_eq!(n, a.ncols());
    let mut lu = a.to_owned();
    let mut perm = vec![0usize; n];
    let mut perm_inv = vec![0usize; n];
    let mut mem = MemBuffer::new(factor::lu_in_place_scratch::<usize, f64>(
        n,
        n,
        Par::Seq,
        Default::default(),
    ));
    let (_, p) = factor::lu_in_place(
        lu.as_mut(),
        &mut perm,
        &mut perm_inv,
        Par::Seq,
        MemStack::new(&mut mem),
        Default::default(),
    );
    let mut umax = 0.0f64;
    let mut umin = f64::INFINITY;
    for i in 0..n {
        let u = lu[(i, i)].abs();
        umax = umax.max(u);
        umin = umin.min(u);
    }
    let pivot_ratio = if umax > 0.0 && umax.is_finite() {
        umin / umax
    } else {
        0.0
    };
    let singular = |residual: f64| KrigingError::Singular {
        what,
        size: n,
        pivot_ratio,
        residual,
    };
    if pivot_ratio.is_nan() || pivot_ratio < PIVOT_RATIO_MIN {
        return Err(singular(f64::NAN));
    }
    let mut inv = Mat::zeros(n, n);
    let mut mem = MemBuffer::new(inverse::inverse_scratch::<usize, f64>(n, Par::Seq));
    inverse::inverse(
        inv.as_mut(),
        lu.as_ref(),
        lu.as_ref(),
        p,
        Par::Seq,
        MemStack::new(&mut mem),
    );
    if symmetric {
        for j in 0..n {
            for i in 0..j {
                let m = 0.5 * (inv[(i, j)] + inv[(j, i)]);
                inv[(i, j)] = m;
                inv[(j, i)] = m;
            }
        }
    }
    for j in 0..n {
        for i in 0..n {
            if !inv[(i, j)].is_finite() {
                return Err(singular(f64::INFINITY));
            }
        }
    }
    // Probe: v_i in [1, 2), x = inv v, r = a x - v.
    let v: Vec<f64> = (0..n).map(|i| 1.0 + (i % 7) as f64 / 7.0).collect();
    let mut x = vec![0.0; n];
    for (j, &vj) in v.iter().enumerate() {
        for (i, xi) in x.iter_mut().enumerate() {
            *xi += inv[(i, j)] * vj;
        }
    }
    let mut rmax = 0.0f64;
    let mut anorm = 0.0f64;
    for i in 0..n {
        let mut r = -v[i];
        let mut row = 0.0;
        for (j, xj) in x.iter().enumerate() {
            r += a[(i, j)] * xj;
            row += a[(i, j)].abs();
        }
        rmax = rmax.max(r.abs());
        anorm = anorm.max(row);
    }
    let xmax = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let residual = rmax / (anorm * xmax + 2.0);
    if residual.is_nan() || residual > RESIDUAL_MAX {
        return Err(singular(residual));
    }
    Ok(inv)
}

/// Eigen-decomposition of a small symmetric matrix: (ascending eigenvalues, eigenvectors as columns).
pub(crate) fn sym_eigen(a: MatRef<'_, f64>) -> (Vec<f64>, Mat<f64>) {
    use faer::linalg::evd::{self, ComputeEigenvectors};
    let n = a.nrows();
    let mut s = faer::diag::Diag::<f64>::zeros(n);
    let mut u = Mat::<f64>::zeros(n, n);
    let mut mem = MemBuffer::new(evd::self_adjoint_evd_scratch::<f64>(
        n,
        ComputeEigenvectors::Yes,
        Par::Seq,
        Default::default(),
    ));
    let res = evd::self_adjoint_evd(
        a,
        s.as_mut(),
        Some(u.as_mut()),
        Par::Seq,
        MemStack::new(&mut mem),
        Default::default(),
    );
    if res.is_err() {
        // Convergence failure on a tiny finite matrix is not expected; report "no spectrum" so
        // that callers treat the matrix as zero (rank 0) instead of panicking.
        return (vec![0.0; n], Mat::identity(n, n));
    }
    ((0..n).map(|i| s[i]).collect(), u)
}

/// Relative eigenvalue tolerance of the pseudo-inverses of `C C^t` (trend of eq. 8, RBF polynomial
/// basis): eigenvalues at most `PINV_RTOL * max` are zero.
/// For a Gram matrix G = C C^T this is a singular value tolerance of about 1e-6 on C.
pub const PINV_RTOL: f64 = 1e-12;

/// Moore-Penrose pseudo-inverse of a symmetric positive semi-definite matrix through its
/// eigen-decomposition, eigenvalues `<= PINV_RTOL * max(eig)` treated as zero. Returns the
/// pseudo-inverse and the numerical rank.
///
/// ```
/// use kriging::faer::Mat;
/// use kriging::sym_pinv;
///
/// // A rank-1 matrix v v^t with v = (1, 2): its pseudo-inverse is v v^t / |v|^4.
/// let g = Mat::from_fn(2, 2, |i, j| [1.0, 2.0][i] * [1.0, 2.0][j]);
/// let (p, rank) = sym_pinv(g.as_ref());
/// assert_eq!(rank, 1);
/// for i in 0..2 {
///     for j in 0..2 {
///         assert!((p[(i, j)] - g[(i, j)] / 25.0).abs() < 1e-14);
///     }
/// }
/// ```
pub fn sym_pinv(g: MatRef<'_, f64>) -> (Mat<f64>, usize) {
    let n = g.nrows();
    let (vals, vecs) = sym_eigen(g);
    let vmax = vals.iter().fold(0.0f64, |m, v| m.max(*v));
    let tol = PINV_RTOL * vmax;
    let mut out = Mat::zeros(n, n);
    let mut rank = 0;
    for (k, &lam) in vals.iter().enumerate() {
        if lam > tol && lam > 0.0 {
            rank += 1;
            let inv = 1.0 / lam;
            for j in 0..n {
                let vj = vecs[(j, k)] * inv;
                for i in 0..n {
                    out[(i, j)] += vecs[(i, k)] * vj;
                }
            }
        }
    }
    (out, rank)
}

/// Column-block width of [`matmul_par_cols`]; fixed, so the result does not depend on the number
/// of threads.
const COL_BLOCK: usize = 128;

/// `a * b` with the columns of `b` split into fixed blocks of 128 computed in parallel (rayon),
/// each block single-threaded: bit-identical for any pool size.
pub(crate) fn matmul_par_cols(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    use rayon::prelude::*;
    let n = b.ncols();
    // Small products stay on one thread; the choice depends on the sizes only, never on the pool.
    if n <= COL_BLOCK || a.nrows() * a.ncols() * n < (1 << 24) {
        return matmul(a, b);
    }
    let blocks: Vec<Mat<f64>> = (0..n.div_ceil(COL_BLOCK))
        .into_par_iter()
        .map(|k| {
            let start = k * COL_BLOCK;
            let w = COL_BLOCK.min(n - start);
            matmul(a, b.subcols(start, w))
        })
        .collect();
    let mut out = Mat::zeros(a.nrows(), n);
    for (k, blk) in blocks.iter().enumerate() {
        out.as_mut()
            .subcols_mut(k * COL_BLOCK, blk.ncols())
            .copy_from(blk.as_ref());
    }
    out
}
