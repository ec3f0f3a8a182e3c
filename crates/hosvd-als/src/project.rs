//! Multi-mode products `X x_a A x_b B ...` applied in the cheapest order.

use faer::MatRef;
use tensor_ops::{Tensor3, TensorError, mode_product_into, product_dims};

/// Flop estimate of applying the given modes in `order`.
fn cost(dims: [usize; 3], mats: &[Option<MatRef<'_, f64>>; 3], order: &[usize]) -> u128 {
    let mut d = dims;
    let mut total = 0u128;
    for &m in order {
        if let Some(a) = mats[m] {
            total += (a.nrows() as u128) * (d[0] as u128) * (d[1] as u128) * (d[2] as u128);
            d[m] = a.nrows();
        }
    }
    total
}

/// `X x_0 M_0 x_1 M_1 x_2 M_2` over the modes where `mats[n]` is `Some`, in the order of least
/// flops (products over different modes commute).
pub(crate) fn multi_product(
    x: &Tensor3,
    mats: [Option<MatRef<'_, f64>>; 3],
) -> Result<Tensor3, TensorError> {
    const ORDERS: [[usize; 3]; 6] = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    let best = ORDERS
        .iter()
        .min_by_key(|o| cost(x.dims(), &mats, &o[..]))
        .copied()
        .unwrap_or([0, 1, 2]);
    let mut cur = x.as_slice().to_vec();
    let mut d = x.dims();
    for m in best {
        if let Some(a) = mats[m] {
            debug_assert_eq!(a.ncols(), d[m]);
            let nd = product_dims(d, m, a.nrows())?;
            let mut out = vec![0.0; nd[0] * nd[1] * nd[2]];
            mode_product_into(&cur, d, m, a, &mut out)?;
            cur = out;
            d = nd;
        }
    }
    // Re-checks finiteness: an overflow to inf is reported, not propagated.
    Tensor3::from_vec(d, cur)
}
