//! Mode-n Gram matrices `X_(n) X_(n)^T` computed on views of the storage (no unfolding copy).

use faer::linalg::matmul::matmul;
use faer::{Accum, MatMut, MatRef, Par};
use tensor_ops::par::matmul_blocked;

/// Writes the mode-`mode` Gram matrix `G_n = X_(n) X_(n)^T` (`I_n x I_n`) of the tensor with
/// storage `x` and shape `dims` into `g`.
///
/// `G_n(a, b) = sum over the other two indices of X(.., a, ..) X(.., b, ..)`; column order of
/// the unfolding does not matter. Mode 0 is one product of the `I_0 x I_1 I_2` view with its
/// transpose, mode 2 one product of the `I_0 I_1 x I_2` view, mode 1 a sum of `I_2` slice
/// products `X_k^T X_k`. The left singular vectors of `X_(n)` are the eigenvectors of `G_n`
/// (de Lathauwer et al. 2000, Th. 2), which is how HOSVD factors are computed here. Modes 0 and 2
/// run in parallel on the current pool with the bits of the single-threaded product
/// ([`matmul_blocked`]); mode 1 (a sum of slice products) runs single-threaded.
pub(crate) fn gram_into(x: &[f64], dims: [usize; 3], mode: usize, mut g: MatMut<'_, f64>) {
    let [i0, i1, i2] = dims;
    debug_assert_eq!(x.len(), i0 * i1 * i2);
    debug_assert_eq!(g.nrows(), dims[mode]);
    debug_assert_eq!(g.ncols(), dims[mode]);
    match mode {
        0 => {
            let m = MatRef::from_column_major_slice(x, i0, i1 * i2);
            matmul_blocked(g, m, m.transpose());
        }
        1 => {
            g.fill(0.0);
            for k in 0..i2 {
                let xk =
                    MatRef::from_column_major_slice(&x[k * i0 * i1..(k + 1) * i0 * i1], i0, i1);
                matmul(&mut g, Accum::Add, xk.transpose(), xk, 1.0, Par::Seq);
            }
        }
        _ => {
            let m = MatRef::from_column_major_slice(x, i0 * i1, i2);
            matmul_blocked(g, m.transpose(), m);
        }
    }
}
