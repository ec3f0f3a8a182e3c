//! Small dense linear-algebra helpers on faer. Every faer call is single-threaded (`Par::Seq`);
//! the parallel ones split their work into fixed column blocks, each computed alone, so that results
//! are bit-identical whatever the size of rayon's pool.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::lu::partial_pivoting::{factor, inverse, solve};
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
    checked_inverse_of(a.to_owned(), &|i, j| a[(i, j)], symmetric, what)
}

/// [`checked_inverse`] of a matrix given by value, factorised in its own storage (one `n x n`
/// matrix less at the peak: what a system over ten thousand samples needs); `entry(i, j)` gives
/// the matrix's entries again for the probe solve.
pub(crate) fn checked_inverse_of(
    a: Mat<f64>,
    entry: &(dyn Fn(usize, usize) -> f64 + Sync),
    symmetric: bool,
    what: &'static str,
) -> Result<Mat<f64>, KrigingError> {
    let lu = CheckedLu::factor_unprobed(a, what)?;
    let inv = lu.inverse(symmetric);
    if inv.col_iter().any(|c| c.iter().any(|v| !v.is_finite())) {
        return Err(lu.singular(f64::INFINITY));
    }
    // Probe: v_i in [1, 2), x = inv v, r = a x - v.
    let v = probe_vector(lu.n());
    let mut x = vec![0.0; lu.n()];
    for (j, &vj) in v.iter().enumerate() {
        for (i, xi) in x.iter_mut().enumerate() {
            *xi += inv[(i, j)] * vj;
        }
    }
    lu.check_probe(&v, &x, entry)?;
    Ok(inv)
}

/// The probe right-hand side of the factorisation checks: `v_i` in `[1, 2)`.
fn probe_vector(n: usize) -> Vec<f64> {
    (0..n).map(|i| 1.0 + (i % 7) as f64 / 7.0).collect()
}

/// The `n x m` matrix of `entry(i, j)`, its columns filled in fixed blocks of [`SOLVE_BLOCK`] in
/// parallel (each entry computed alone: the same bits as [`Mat::from_fn`], for any pool size).
pub(crate) fn from_fn_par(
    n: usize,
    m: usize,
    entry: &(dyn Fn(usize, usize) -> f64 + Sync),
) -> Mat<f64> {
    use rayon::prelude::*;
    let mut out = Mat::zeros(n, m);
    let blocks: Vec<_> = column_blocks(out.as_mut())
        .into_iter()
        .enumerate()
        .collect();
    blocks.into_par_iter().for_each(|(b, mut blk)| {
        let j0 = b * SOLVE_BLOCK;
        for j in 0..blk.ncols() {
            for i in 0..n {
                blk[(i, j)] = entry(i, j0 + j);
            }
        }
    });
    out
}

/// `m` split into consecutive blocks of [`SOLVE_BLOCK`] columns (the last one narrower): the
/// fixed work units of this module's parallel loops.
fn column_blocks(m: faer::MatMut<'_, f64>) -> Vec<faer::MatMut<'_, f64>> {
    let mut out = Vec::with_capacity(m.ncols().div_ceil(SOLVE_BLOCK));
    let mut rest = m;
    while rest.ncols() > 0 {
        let w = SOLVE_BLOCK.min(rest.ncols());
        let (blk, tail) = rest.split_at_col_mut(w);
        out.push(blk);
        rest = tail;
    }
    out
}

/// faer's LU with partial pivoting of a square matrix, single-threaded: `P A = L U` with
/// `(P A)[i] = A[perm[i]]`.
fn faer_lu_in_place(a: faer::MatMut<'_, f64>, perm: &mut [usize], perm_inv: &mut [usize]) {
    let n = a.nrows();
    let mut mem = MemBuffer::new(factor::lu_in_place_scratch::<usize, f64>(
        n,
        a.ncols(),
        Par::Seq,
        Default::default(),
    ));
    factor::lu_in_place(
        a,
        perm,
        perm_inv,
        Par::Seq,
        MemStack::new(&mut mem),
        Default::default(),
    );
}

/// Panel width of [`blocked_lu_in_place`].
const LU_PANEL: usize = 128;

/// LU with partial pivoting of a square matrix by panels of [`LU_PANEL`] columns, right-looking
/// (faer's convention: `P A = L U`, `(P A)[i] = A[perm[i]]`): each panel is factorised by faer
/// single-threaded, its row interchanges applied to the other columns, and the rows to its right
/// updated (`U_12 = L_11^-1 A_12`, `A_22 -= L_21 U_12`) in fixed blocks of [`SOLVE_BLOCK`]
/// columns in parallel, each block single-threaded: the same bits for any pool size, and the
/// update, nearly all of the `2 n^3 / 3` flops, on every thread of the pool. Measured on a
/// 6,000 x 6,000 matrix (2026-11-27, 2 vCPUs): 1.8 s on one thread (faer's recursive LU 1.5 s),
/// 1.06 s on two; panels of 64 columns were slower (2.3 s), of 256 no faster.
fn blocked_lu_in_place(mut a: faer::MatMut<'_, f64>, perm: &mut [usize], perm_inv: &mut [usize]) {
    use faer::linalg::triangular_solve::solve_unit_lower_triangular_in_place;
    use faer::reborrow::{Reborrow, ReborrowMut};
    use rayon::prelude::*;
    let n = a.nrows();
    for (i, p) in perm.iter_mut().enumerate() {
        *p = i;
    }
    let mut pp = vec![0usize; n];
    let mut pp_inv = vec![0usize; n];
    let mut k0 = 0;
    while k0 < n {
        let kb = LU_PANEL.min(n - k0);
        let m = n - k0;
        // 1. The panel A[k0.., k0..k0 + kb].
        faer_lu_in_place(
            a.rb_mut().submatrix_mut(k0, k0, m, kb),
            &mut pp[..m],
            &mut pp_inv[..m],
        );
        // 2. Its row interchanges on the columns left and right of it (only the rows it moved).
        let moved: Vec<usize> = (0..m).filter(|&i| pp[i] != i).collect();
        if !moved.is_empty() {
            let src: Vec<usize> = moved.iter().map(|&i| k0 + pp[i]).collect();
            let (left, rest) = a.rb_mut().split_at_col_mut(k0);
            let (_, right) = rest.split_at_col_mut(kb);
            let mut cols = column_blocks(left);
            cols.extend(column_blocks(right));
            cols.into_par_iter().for_each(|mut blk| {
                let mut tmp = vec![0.0; moved.len()];
                for j in 0..blk.ncols() {
                    for (t, &r) in src.iter().enumerate() {
                        tmp[t] = blk[(r, j)];
                    }
                    for (t, &i) in moved.iter().enumerate() {
                        blk[(k0 + i, j)] = tmp[t];
                    }
                }
            });
            let old: Vec<usize> = perm[k0..].to_vec();
            for i in 0..m {
                perm[k0 + i] = old[pp[i]];
            }
        }
        // 3-4. U_12 = L_11^-1 A_12 and A_22 -= L_21 U_12, column block by column block.
        if k0 + kb < n {
            let (left, right) = a.rb_mut().split_at_col_mut(k0 + kb);
            let left = left.rb();
            let l11 = left.submatrix(k0, k0, kb, kb);
            let l21 = left.submatrix(k0 + kb, k0, n - k0 - kb, kb);
            let (top, bottom) = right.split_at_row_mut(k0 + kb);
            let (_, u12) = top.split_at_row_mut(k0);
            let blocks: Vec<_> = column_blocks(u12)
                .into_iter()
                .zip(column_blocks(bottom))
                .collect();
            blocks.into_par_iter().for_each(|(mut ub, ab)| {
                solve_unit_lower_triangular_in_place(l11, ub.rb_mut(), Par::Seq);
                faer::linalg::matmul::matmul(ab, Accum::Add, l21, ub.rb(), -1.0, Par::Seq);
            });
        }
        k0 += kb;
    }
    for (i, &p) in perm.iter().enumerate() {
        perm_inv[p] = i;
    }
}

/// Column-block width of [`CheckedLu::solve`] and of [`blocked_lu_in_place`]'s updates: fixed, so
/// that the result does not depend on the number of threads.
const SOLVE_BLOCK: usize = 64;

/// An LU factorisation with partial pivoting of a square matrix, checked as [`checked_inverse`]
/// checks (pivot ratio, finite probe solve with a small residual): what a large kriging system
/// keeps instead of its inverse, which it forms only when asked.
#[derive(Debug, Clone)]
pub(crate) struct CheckedLu {
    lu: Mat<f64>,
    perm: Vec<usize>,
    perm_inv: Vec<usize>,
    pivot_ratio: f64,
    what: &'static str,
}

impl CheckedLu {
    /// Factorises `a` in its own storage and checks it; `entry(i, j)` gives `a`'s entries again
    /// for the probe solve's residual.
    pub(crate) fn factor(
        a: Mat<f64>,
        entry: &(dyn Fn(usize, usize) -> f64 + Sync),
        what: &'static str,
    ) -> Result<CheckedLu, KrigingError> {
        let lu = CheckedLu::factor_unprobed_with(a, what, blocked_lu_in_place)?;
        let v = probe_vector(lu.n());
        let x = lu.solve(MatRef::from_column_major_slice(&v, v.len(), 1));
        let x: Vec<f64> = x.col(0).iter().copied().collect();
        if x.iter().any(|v| !v.is_finite()) {
            return Err(lu.singular(f64::INFINITY));
        }
        lu.check_probe(&v, &x, entry)?;
        Ok(lu)
    }

    /// The factorisation (faer's, single-threaded) and its pivot check, without the probe solve.
    fn factor_unprobed(a: Mat<f64>, what: &'static str) -> Result<CheckedLu, KrigingError> {
        CheckedLu::factor_unprobed_with(a, what, faer_lu_in_place)
    }

    /// The factorisation by `lu_in_place` (which fills the forward and inverse row
    /// permutations, faer's convention) and its pivot check.
    fn factor_unprobed_with(
        a: Mat<f64>,
        what: &'static str,
        lu_in_place: fn(faer::MatMut<'_, f64>, &mut [usize], &mut [usize]),
    ) -> Result<CheckedLu, KrigingError> {
        let n = a.nrows();
        debug_assert_eq!(n, a.ncols());
        let mut lu = a;
        let mut perm = vec![0usize; n];
        let mut perm_inv = vec![0usize; n];
        lu_in_place(lu.as_mut(), &mut perm, &mut perm_inv);
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
        let out = CheckedLu {
            lu,
            perm,
            perm_inv,
            pivot_ratio,
            what,
        };
        if pivot_ratio.is_nan() || pivot_ratio < PIVOT_RATIO_MIN {
            return Err(out.singular(f64::NAN));
        }
        Ok(out)
    }

    /// The matrix's size `n`.
    pub(crate) fn n(&self) -> usize {
        self.lu.nrows()
    }

    fn singular(&self, residual: f64) -> KrigingError {
        KrigingError::Singular {
            what: self.what,
            size: self.n(),
            pivot_ratio: self.pivot_ratio,
            residual,
        }
    }

    /// Fails when `x`, the solution for the probe `v`, leaves a relative residual
    /// `max |a x - v| / (||a||_inf max |x| + 2)` above 1e-8.
    fn check_probe(
        &self,
        v: &[f64],
        x: &[f64],
        entry: &(dyn Fn(usize, usize) -> f64 + Sync),
    ) -> Result<(), KrigingError> {
        // Rows in parallel, each summed in column order: the same bits for any pool size.
        use rayon::prelude::*;
        let (rmax, anorm) = (0..v.len())
            .into_par_iter()
            .with_min_len(64)
            .map(|i| {
                let mut r = -v[i];
                let mut row = 0.0;
                for (j, xj) in x.iter().enumerate() {
                    let aij = entry(i, j);
                    r += aij * xj;
                    row += aij.abs();
                }
                (r.abs(), row)
            })
            .reduce(|| (0.0f64, 0.0f64), |a, b| (a.0.max(b.0), a.1.max(b.1)));
        let xmax = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let residual = rmax / (anorm * xmax + 2.0);
        if residual.is_nan() || residual > RESIDUAL_MAX {
            return Err(self.singular(residual));
        }
        Ok(())
    }

    fn perm(&self) -> faer::perm::PermRef<'_, usize> {
        faer::perm::PermRef::new_checked(&self.perm, &self.perm_inv, self.n())
    }

    /// The inverse (faer's inverse from the factors), symmetrised when `symmetric` (the mean of
    /// each entry and its mirror).
    pub(crate) fn inverse(&self, symmetric: bool) -> Mat<f64> {
        let n = self.n();
        let mut inv = Mat::zeros(n, n);
        let mut mem = MemBuffer::new(inverse::inverse_scratch::<usize, f64>(n, Par::Seq));
        inverse::inverse(
            inv.as_mut(),
            self.lu.as_ref(),
            self.lu.as_ref(),
            self.perm(),
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
        inv
    }

    /// `A^-1 rhs` (n x m): the columns of `rhs` in fixed blocks of [`SOLVE_BLOCK`] solved in
    /// parallel (rayon), each block single-threaded: bit-identical for any pool size.
    pub(crate) fn solve(&self, rhs: MatRef<'_, f64>) -> Mat<f64> {
        use rayon::prelude::*;
        let (n, m) = rhs.shape();
        debug_assert_eq!(n, self.n());
        let mut out = Mat::zeros(n, m);
        let blocks: Vec<(usize, usize)> = (0..m.div_ceil(SOLVE_BLOCK))
            .map(|k| (k * SOLVE_BLOCK, SOLVE_BLOCK.min(m - k * SOLVE_BLOCK)))
            .collect();
        let solved: Vec<Mat<f64>> = blocks
            .par_iter()
            .map(|&(start, w)| {
                let mut blk = rhs.subcols(start, w).to_owned();
                let mut mem =
                    MemBuffer::new(solve::solve_in_place_scratch::<usize, f64>(n, w, Par::Seq));
                solve::solve_in_place(
                    self.lu.as_ref(),
                    self.lu.as_ref(),
                    self.perm(),
                    blk.as_mut(),
                    Par::Seq,
                    MemStack::new(&mut mem),
                );
                blk
            })
            .collect();
        for (&(start, w), blk) in blocks.iter().zip(&solved) {
            out.as_mut().subcols_mut(start, w).copy_from(blk.as_ref());
        }
        out
    }
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
/// The input must be finite: a NaN or infinite entry gives a meaningless result (in practice the
/// zero matrix and rank 0), so check the input first when it can hold one.
///
/// # Panics
///
/// When `g` is not square.
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
    assert_eq!(
        g.nrows(),
        g.ncols(),
        "sym_pinv needs a square matrix, got {} x {}",
        g.nrows(),
        g.ncols()
    );
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

/// `values` (S x D) in fewer columns for anything that depends on them only through sums of
/// squares of linear combinations of rows (squared distances between samples, squared errors of
/// predictions that blend the samples): `X V_k`, the values projected on their `k` leading right
/// singular vectors, with `k` the fewest that keep all but `rel_energy` of `||X||_F^2`. Every such
/// sum of squares is then kept to within `rel_energy` of `||X||_F^2` times the blend's squared
/// norm; columns beyond `k` carry only the rest. The right singular vectors come from the smaller
/// Gram matrix (`X X^t` or `X^t X`, single-threaded eigendecomposition: deterministic); their signs
/// are the eigensolver's. Returns a copy when `k` would be `D`, and an S x 1 zero column for zero
/// values.
///
/// # Panics
///
/// When `rel_energy` is not in `[0, 1]` (NaN included): it is a fraction of the energy.
///
/// ```
/// use kriging::faer::Mat;
/// // 6 samples of 4 values that lie in a 2-dimensional subspace.
/// let x = Mat::from_fn(6, 4, |i, j| (i as f64) * [1.0, 2.0, 0.0, 1.0][j] + [0.0, 1.0, 1.0, 0.0][j]);
/// let c = kriging::compress_columns(x.as_ref(), 1e-12);
/// assert_eq!(c.ncols(), 2);
/// let d = |m: &Mat<f64>, a: usize, b: usize| (0..m.ncols()).map(|j| (m[(a, j)] - m[(b, j)]).powi(2)).sum::<f64>();
/// assert!((d(&x, 1, 4) - d(&c, 1, 4)).abs() < 1e-9);
/// ```
pub fn compress_columns(values: MatRef<'_, f64>, rel_energy: f64) -> Mat<f64> {
    assert!(
        (0.0..=1.0).contains(&rel_energy),
        "compress_columns: rel_energy {rel_energy} must be in [0, 1]"
    );
    leading_columns(values, |vals| {
        // Ascending eigenvalues: keep the leading ones until the rest is within `rel_energy`.
        let n = vals.len();
        let total: f64 = vals.iter().map(|v| v.max(0.0)).sum();
        if total <= 0.0 || !total.is_finite() {
            return 1;
        }
        let mut rest = total;
        let mut k = 0;
        while k < n && rest > rel_energy * total {
            rest -= vals[n - 1 - k].max(0.0);
            k += 1;
        }
        k
    })
}

/// `X V_k`: the values (S x D) projected on their `k` leading right singular vectors, `k` chosen by
/// `keep` from the Gram matrix's eigenvalues (ascending) and clamped to `1..=min(S, D)`; a copy of
/// the values when `k` is `D`. From the smaller Gram matrix: `X X^t` (then `X V_k = Q_k
/// Lambda_k^(1/2)`, single-threaded) or `X^t X` (then `V_k` itself, the products in fixed column
/// blocks). The eigendecomposition is single-threaded: deterministic; the signs are the
/// eigensolver's.
pub(crate) fn leading_columns(
    values: MatRef<'_, f64>,
    keep: impl FnOnce(&[f64]) -> usize,
) -> Mat<f64> {
    let (s, dv) = values.shape();
    let gram_rows = s <= dv;
    let gram = if gram_rows {
        matmul(values, values.transpose())
    } else {
        matmul_par_cols(values.transpose(), values)
    };
    let (vals, vecs) = sym_eigen(gram.as_ref());
    let n = vals.len();
    let k = keep(&vals).clamp(1, n.max(1));
    if k >= dv {
        return values.to_owned();
    }
    if gram_rows {
        Mat::from_fn(s, k, |i, j| {
            let col = n - 1 - j;
            vecs[(i, col)] * vals[col].max(0.0).sqrt()
        })
    } else {
        let v = Mat::from_fn(dv, k, |i, j| vecs[(i, n - 1 - j)]);
        matmul_par_cols(values, v.as_ref())
    }
}

/// The rows `rows` of `m`, in that order.
pub(crate) fn select_rows(m: MatRef<'_, f64>, rows: &[usize]) -> Mat<f64> {
    Mat::from_fn(rows.len(), m.ncols(), |i, j| m[(rows[i], j)])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A kriging-like system over `n - 1` scattered points: `[Gamma 1; 1^t 0]` with a Gaussian
    /// variogram and a small nugget (symmetric, indefinite: pivoting matters).
    fn system(n: usize) -> Mat<f64> {
        let s = n - 1;
        let pt = |i: usize| {
            let h = |b: usize| {
                let (mut f, mut r, mut k) = (1.0, 0.0, i + 1);
                while k > 0 {
                    f /= b as f64;
                    r += f * (k % b) as f64;
                    k /= b;
                }
                r
            };
            (h(2), h(3))
        };
        Mat::from_fn(n, n, |i, j| {
            if i == s || j == s {
                if i == j { 0.0 } else { 1.0 }
            } else if i == j {
                0.0
            } else {
                let ((a, b), (c, d)) = (pt(i), pt(j));
                let h2 = (a - c).powi(2) + (b - d).powi(2);
                0.01 + (1.0 - (-h2 / 0.09).exp())
            }
        })
    }

    /// The blocked LU (several panels, a ragged last one) solves as faer's LU does, and its
    /// factors are the same bits on pools of 1, 2 and 3 threads.
    #[test]
    fn blocked_lu_solves_like_faers_and_is_the_same_on_any_pool() {
        let n = 2 * LU_PANEL + 37;
        let a = system(n);
        let factor = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| CheckedLu::factor(a.clone(), &|i, j| a[(i, j)], "test").unwrap())
        };
        let one = factor(1);
        for threads in [2, 3] {
            let other = factor(threads);
            assert_eq!(one.perm, other.perm, "{threads} threads: pivots");
            let same = (0..n)
                .all(|j| (0..n).all(|i| one.lu[(i, j)].to_bits() == other.lu[(i, j)].to_bits()));
            assert!(same, "{threads} threads: factors differ");
        }
        let rhs = Mat::from_fn(n, 3, |i, k| ((i * (k + 1)) % 11) as f64 - 5.0);
        let blocked = one.solve(rhs.as_ref());
        let faers = CheckedLu::factor_unprobed(a.clone(), "test")
            .unwrap()
            .solve(rhs.as_ref());
        let scale = faers
            .col_iter()
            .flat_map(|c| c.iter().map(|v| v.abs()).collect::<Vec<_>>())
            .fold(0.0f64, f64::max);
        for k in 0..3 {
            for i in 0..n {
                let d = (blocked[(i, k)] - faers[(i, k)]).abs();
                assert!(
                    d <= 1e-9 * scale,
                    "x[{i}, {k}]: {} vs {}",
                    blocked[(i, k)],
                    faers[(i, k)]
                );
            }
        }
        // A singular system (two equal rows) is refused.
        let mut bad = a.clone();
        for j in 0..n {
            bad[(1, j)] = bad[(0, j)];
        }
        assert!(CheckedLu::factor(bad.clone(), &|i, j| bad[(i, j)], "test").is_err());
    }
}
