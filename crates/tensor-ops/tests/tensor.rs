//! Unfolding, products, truncation, norms and reconstruction against naive definitions.

use faer::Mat;
use proptest::prelude::*;
use tensor_ops::{Tensor3, TensorError, reconstruct, try_reconstruct};

fn tensor_from(dims: [usize; 3], seed: u64) -> Tensor3 {
    let mut s = seed;
    Tensor3::from_fn(dims, |_, _, _| {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    })
    .unwrap()
}

fn mat_from(r: usize, c: usize, seed: u64) -> Mat<f64> {
    let t = tensor_from([r, c, 1], seed);
    Mat::from_fn(r, c, |i, j| t.get(i, j, 0))
}

fn dims_strategy() -> impl Strategy<Value = [usize; 3]> {
    (1usize..6, 1usize..6, 1usize..6).prop_map(|(a, b, c)| [a, b, c])
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn fold_unfold_identity(dims in dims_strategy(), mode in 0usize..3, seed in any::<u64>()) {
        let x = tensor_from(dims, seed);
        let m = x.unfold(mode);
        prop_assert_eq!(m.nrows(), dims[mode]);
        let y = Tensor3::fold(mode, m.as_ref(), dims).unwrap();
        prop_assert_eq!(y, x);
    }

    #[test]
    fn unfold_follows_de_lathauwer(dims in dims_strategy(), seed in any::<u64>()) {
        let x = tensor_from(dims, seed);
        let [i0, i1, i2] = dims;
        let (u0, u1, u2) = (x.unfold(0), x.unfold(1), x.unfold(2));
        for k in 0..i2 { for j in 0..i1 { for i in 0..i0 {
            let v = x.get(i, j, k);
            prop_assert_eq!(u0[(i, j * i2 + k)], v);
            prop_assert_eq!(u1[(j, k * i0 + i)], v);
            prop_assert_eq!(u2[(k, i * i1 + j)], v);
        }}}
    }

    #[test]
    fn mode_product_matches_naive(dims in dims_strategy(), mode in 0usize..3, rows in 1usize..5, seed in any::<u64>()) {
        let x = tensor_from(dims, seed);
        let a = mat_from(rows, dims[mode], seed ^ 0xABCD);
        let y = x.mode_product(mode, a.as_ref());
        let mut od = dims;
        od[mode] = rows;
        prop_assert_eq!(y.dims(), od);
        for k in 0..od[2] { for j in 0..od[1] { for i in 0..od[0] {
            let mut s = 0.0;
            for t in 0..dims[mode] {
                let mut idx = [i, j, k];
                let out = idx[mode];
                idx[mode] = t;
                s += a[(out, t)] * x.get(idx[0], idx[1], idx[2]);
            }
            prop_assert!((y.get(i, j, k) - s).abs() <= 1e-12 * (1.0 + s.abs()));
        }}}
        // Y_(n) = A X_(n) in de Lathauwer's unfolding.
        let lhs = y.unfold(mode);
        let rhs = &a * x.unfold(mode);
        prop_assert!((lhs - rhs).norm_max() < 1e-12);
    }

    #[test]
    fn mode_vec_product_matches_naive(dims in dims_strategy(), mode in 0usize..3, seed in any::<u64>()) {
        let x = tensor_from(dims, seed);
        let v: Vec<f64> = (0..dims[mode]).map(|t| (t as f64 * 0.7).sin() + 0.1).collect();
        let m = x.mode_vec_product(mode, &v);
        let (p, q) = match mode { 0 => (1, 2), 1 => (0, 2), _ => (0, 1) };
        prop_assert_eq!((m.nrows(), m.ncols()), (dims[p], dims[q]));
        for a in 0..dims[p] { for b in 0..dims[q] {
            let mut s = 0.0;
            for (t, vt) in v.iter().enumerate() {
                let mut idx = [0; 3];
                idx[p] = a; idx[q] = b; idx[mode] = t;
                s += vt * x.get(idx[0], idx[1], idx[2]);
            }
            prop_assert!((m[(a, b)] - s).abs() <= 1e-12 * (1.0 + s.abs()));
        }}
    }

    #[test]
    fn truncate_is_leading_block(dims in dims_strategy(), seed in any::<u64>(), f in 0.0f64..1.0) {
        let x = tensor_from(dims, seed);
        let r = [1 + ((dims[0] - 1) as f64 * f) as usize, dims[1], 1 + ((dims[2] - 1) as f64 * f) as usize];
        let t = x.truncate(r).unwrap();
        prop_assert_eq!(t.dims(), r);
        for k in 0..r[2] { for j in 0..r[1] { for i in 0..r[0] {
            prop_assert_eq!(t.get(i, j, k), x.get(i, j, k));
        }}}
        prop_assert!((t.squared_norm() - x.leading_squared_norm(r)).abs() < 1e-12);
    }

    #[test]
    fn reconstruct_matches_naive(r in dims_strategy(), extra in dims_strategy(), seed in any::<u64>()) {
        let core = tensor_from(r, seed);
        let dims = [r[0] + extra[0], r[1] + extra[1], r[2] + extra[2]];
        let f: Vec<Mat<f64>> = (0..3).map(|n| mat_from(dims[n], r[n], seed.wrapping_add(n as u64 + 1))).collect();
        let x = reconstruct(&core, [f[0].as_ref(), f[1].as_ref(), f[2].as_ref()]);
        for (i, j, k) in [(0, 0, 0), (dims[0] - 1, dims[1] - 1, dims[2] - 1), (dims[0] / 2, 0, dims[2] / 2)] {
            let mut s = 0.0;
            for c in 0..r[2] { for b in 0..r[1] { for a in 0..r[0] {
                s += core.get(a, b, c) * f[0][(i, a)] * f[1][(j, b)] * f[2][(k, c)];
            }}}
            prop_assert!((x.get(i, j, k) - s).abs() <= 1e-11 * (1.0 + s.abs()));
        }
    }
}

#[test]
fn frobenius_norm_and_sample_layout() {
    let x = Tensor3::from_fn([3, 4, 5], |i, j, k| (i + 10 * j + 100 * k) as f64).unwrap();
    let naive: f64 = x.as_slice().iter().map(|v| v * v).sum::<f64>().sqrt();
    assert!((x.frobenius_norm() - naive).abs() < 1e-9);
    assert_eq!(x.as_slice()[1 + 3 * (2 + 4 * 3)], x.get(1, 2, 3));
    let s = x.sample(3);
    assert_eq!(s.len(), 12);
    assert_eq!(s[1 + 3 * 2], x.get(1, 2, 3));
    assert_eq!(x.sample_mat(3)[(1, 2)], x.get(1, 2, 3));
    assert_eq!(x.as_mode0_matrix()[(1, 2 + 4 * 3)], x.get(1, 2, 3));
}

#[test]
fn construction_errors_name_what_and_where() {
    match Tensor3::from_vec([2, 2, 2], vec![0.0; 7]) {
        Err(TensorError::SizeMismatch {
            expected: 8,
            found: 7,
            ..
        }) => {}
        other => panic!("{other:?}"),
    }
    let mut v = vec![0.0; 8];
    v[1 + 2 * (1 + 2)] = f64::NAN; // (1, 1, 1)
    match Tensor3::from_vec([2, 2, 2], v) {
        Err(TensorError::NonFinite {
            i: 1, j: 1, k: 1, ..
        }) => {}
        other => panic!("{other:?}"),
    }
    let x = Tensor3::zeros([2, 3, 4]);
    assert!(matches!(
        x.truncate([0, 1, 1]),
        Err(TensorError::BadRank { mode: 0, .. })
    ));
    assert!(matches!(
        x.truncate([2, 4, 1]),
        Err(TensorError::BadRank {
            mode: 1,
            rank: 4,
            size: 3
        })
    ));
    assert!(matches!(
        x.try_unfold(3),
        Err(TensorError::BadMode { mode: 3 })
    ));
    let a = Mat::<f64>::zeros(2, 5);
    assert!(matches!(
        x.try_mode_product(1, a.as_ref()),
        Err(TensorError::ShapeMismatch {
            expected: 3,
            found: 5,
            ..
        })
    ));
    assert!(matches!(
        x.try_mode_vec_product(2, &[1.0; 3]),
        Err(TensorError::ShapeMismatch { .. })
    ));
    let m = Mat::<f64>::zeros(3, 7);
    assert!(Tensor3::fold(1, m.as_ref(), [2, 3, 4]).is_err());
    let f = [
        Mat::<f64>::zeros(4, 2),
        Mat::<f64>::zeros(4, 3),
        Mat::<f64>::zeros(4, 3),
    ];
    assert!(try_reconstruct(&x, [f[0].as_ref(), f[1].as_ref(), f[2].as_ref()]).is_err());
    assert!(Tensor3::zeros([0, 3, 2]).is_empty());
}

/// Element counts use checked products of every dimension: an empty tensor whose other
/// dimensions multiply past `usize` is refused (its unfolding widths would wrap).
#[test]
fn dims_whose_products_overflow_are_refused_even_when_empty() {
    for dims in [
        [0, usize::MAX, 2],
        [usize::MAX, 2, 0],
        [2, 0, usize::MAX],
        [0, 1 << 33, 1 << 33],
    ] {
        assert!(
            matches!(
                Tensor3::from_vec(dims, vec![]),
                Err(TensorError::DimsOverflow { dims: d }) if d == dims
            ),
            "{dims:?}"
        );
        assert!(matches!(
            Tensor3::from_fn(dims, |_, _, _| 0.0),
            Err(TensorError::DimsOverflow { .. })
        ));
    }
    assert!(matches!(
        Tensor3::fold(0, Mat::<f64>::zeros(0, 0).as_ref(), [0, 1 << 33, 1 << 33]),
        Err(TensorError::DimsOverflow { .. })
    ));
    assert!(std::panic::catch_unwind(|| Tensor3::zeros([0, usize::MAX, 2])).is_err());
    // Empty tensors whose dimensions fit are fine.
    let empty = Tensor3::from_vec([0, 1 << 20, 1 << 20], vec![]).unwrap();
    assert_eq!(empty.as_mode0_matrix().ncols(), 1 << 40);
    assert_eq!(Tensor3::zeros([0, 3, 4]).unfold(1).shape(), (3, 0));
}

#[test]
fn product_dims_checks_the_mode() {
    assert_eq!(
        tensor_ops::product_dims([1, 2, 3], 1, 5).unwrap(),
        [1, 5, 3]
    );
    assert!(matches!(
        tensor_ops::product_dims([1, 2, 3], 3, 5),
        Err(TensorError::BadMode { mode: 3 })
    ));
}
