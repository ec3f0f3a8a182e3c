//! Matrix products spread over the threads of the current rayon pool with the bits of the
//! single-threaded product.
//!
//! [`matmul_blocked`] splits the output into fixed blocks of [`BLOCK`] or [`MIN_BLOCK`] columns
//! (or rows, when the output has too few columns; the last block takes the remainder, so no
//! block is a matrix-vector product, which faer sums in another order) and computes each block
//! as its own single-threaded faer product. The blocks depend only on the shapes, never on the pool, and every output entry
//! is the same single-threaded sum over the shared dimension as in the one-call product: faer's
//! loop over that dimension does not depend on the output's extent, which the tests check bit
//! for bit on the shapes the decompositions use. So the result is the same on a pool of any size,
//! and the same as the single-threaded product (`Par::Seq`).

use faer::linalg::matmul::matmul;
use faer::{Accum, MatMut, MatRef, Par};
use rayon::prelude::*;

/// Columns (or rows) of the output in one block of [`matmul_blocked`].
pub const BLOCK: usize = 64;

/// Columns (or rows) of the output in one block of [`matmul_blocked`] when the output is narrow
/// (fewer than `8 BLOCK` of them): a Gram matrix of a few dozen rows still splits.
pub const MIN_BLOCK: usize = 16;

/// The block width of an output `extent` columns (or rows) wide: [`BLOCK`], or [`MIN_BLOCK`]
/// below `8 BLOCK`. A function of the shape alone, never of the pool.
fn block_for(extent: usize) -> usize {
    if extent >= 8 * BLOCK {
        BLOCK
    } else {
        MIN_BLOCK
    }
}

/// Products of fewer multiply-adds than this run as one single-threaded call (the same bits; a
/// parallel split would cost more than it saves).
pub const PARALLEL_MIN_FLOPS: usize = 1 << 20;

/// `out = lhs * rhs` (`out` is `lhs.nrows() x rhs.ncols()`, overwritten), in fixed blocks of
/// [`BLOCK`] output columns ([`MIN_BLOCK`] when there are fewer than `8 BLOCK`; the last block up
/// to twice as wide), or of rows when `out` has fewer than `2 MIN_BLOCK` columns, computed in
/// parallel on the current rayon pool, each block single-threaded. The same bits as
/// `matmul(out, Accum::Replace, lhs, rhs, 1.0, Par::Seq)` on any pool (see the module
/// documentation). Products of fewer than [`PARALLEL_MIN_FLOPS`] multiply-adds run as that one
/// call.
///
/// Panics (as faer's `matmul` does) when the shapes do not agree; callers pass shapes that agree by
/// construction.
pub fn matmul_blocked(out: MatMut<'_, f64>, lhs: MatRef<'_, f64>, rhs: MatRef<'_, f64>) {
    assert!(
        out.nrows() == lhs.nrows() && out.ncols() == rhs.ncols() && lhs.ncols() == rhs.nrows(),
        "matmul_blocked: {}x{} = {}x{} * {}x{}",
        out.nrows(),
        out.ncols(),
        lhs.nrows(),
        lhs.ncols(),
        rhs.nrows(),
        rhs.ncols()
    );
    let flops = out.nrows() * out.ncols() * lhs.ncols();
    let by_columns = out.ncols() >= 2 * MIN_BLOCK;
    let extent = if by_columns { out.ncols() } else { out.nrows() };
    let block = block_for(extent);
    // Whole blocks, the last one taking the remainder (so no block is narrower than the others:
    // a block of one column or row would be a matrix-vector product, summed in another order).
    let blocks = extent / block;
    if flops < PARALLEL_MIN_FLOPS || blocks < 2 {
        matmul(out, Accum::Replace, lhs, rhs, 1.0, Par::Seq);
        return;
    }
    let mut parts = Vec::with_capacity(blocks);
    let mut rest = out;
    let mut start = 0;
    for b in 0..blocks {
        let len = if b + 1 == blocks {
            extent - start
        } else {
            block
        };
        let (block, tail) = if by_columns {
            rest.split_at_col_mut(len)
        } else {
            rest.split_at_row_mut(len)
        };
        parts.push((start, len, block));
        rest = tail;
        start += len;
    }
    parts.into_par_iter().for_each(|(start, len, block)| {
        let (l, r) = if by_columns {
            (lhs, rhs.subcols(start, len))
        } else {
            (lhs.subrows(start, len), rhs)
        };
        matmul(block, Accum::Replace, l, r, 1.0, Par::Seq);
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::Mat;

    fn random(rows: usize, cols: usize, seed: u64) -> Mat<f64> {
        let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        Mat::from_fn(rows, cols, |_, _| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        })
    }

    fn bits(m: &Mat<f64>) -> Vec<u64> {
        (0..m.ncols())
            .flat_map(|j| (0..m.nrows()).map(move |i| (i, j)))
            .map(|(i, j)| m[(i, j)].to_bits())
            .collect()
    }

    /// The shapes of the decompositions' products (a Gram over many samples, a mode-0 product
    /// over long rows, a mode-2 product with few columns), and odd sizes around the block.
    #[test]
    fn blocked_products_have_the_bits_of_the_single_threaded_product_on_any_pool() {
        for (m, k, n) in [
            (300, 4000, 300),
            (700, 3000, 60),
            (29, 67, 20000),
            (65, 1000, 129),
            (129, 1000, 65),
            (64, 2000, 64),
            (1, 5000, 300),
            (300, 5000, 1),
            (200, 777, 191),
            (2278, 500, 34),
            (67, 20000, 67),
            (67, 2000, 34),
            (34, 3000, 34),
            (986, 3000, 986),
            (10000, 986, 60),
        ] {
            let (a, b) = (random(m, k, 1), random(k, n, 2));
            let mut want = Mat::<f64>::zeros(m, n);
            matmul(
                want.as_mut(),
                Accum::Replace,
                a.as_ref(),
                b.as_ref(),
                1.0,
                Par::Seq,
            );
            for threads in [1, 2, 3] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let mut got = Mat::<f64>::from_fn(m, n, |_, _| f64::NAN);
                pool.install(|| matmul_blocked(got.as_mut(), a.as_ref(), b.as_ref()));
                assert_eq!(bits(&got), bits(&want), "{m}x{k}x{n} on {threads} threads");
            }
        }
    }

    #[test]
    #[should_panic(expected = "matmul_blocked")]
    fn disagreeing_shapes_are_refused() {
        let (a, b) = (random(3, 4, 1), random(5, 2, 2));
        let mut out = Mat::<f64>::zeros(3, 2);
        matmul_blocked(out.as_mut(), a.as_ref(), b.as_ref());
    }
}
