//! HOSVD and HOOI: orthonormality, exactness, all-orthogonality, ALS optimality, errors.

use faer::{Mat, MatRef};
use hosvd_als::synthetic::decaying_tucker;
use hosvd_als::{AlsOptions, HosvdError, Tucker, hooi, hooi_with_start, hosvd, hosvd_full};
use proptest::prelude::*;
use tensor_ops::{Tensor3, TensorError};

fn orthonormality_defect(u: MatRef<'_, f64>) -> f64 {
    let g = u.transpose() * u;
    (g - Mat::<f64>::identity(u.ncols(), u.ncols())).norm_max()
}

/// Max |off-diagonal| of Z_(n) Z_(n)^T relative to ||Z||^2, and whether the diagonal decreases.
fn all_orthogonality(t: &Tucker, mode: usize) -> (f64, bool) {
    let zn = t.core.unfold(mode);
    let g = &zn * zn.transpose();
    let scale = t.core.squared_norm().max(1e-300);
    let mut off = 0.0f64;
    let mut decreasing = true;
    for a in 0..g.nrows() {
        for b in 0..g.ncols() {
            if a != b {
                off = off.max(g[(a, b)].abs() / scale);
            }
        }
        if a > 0 && g[(a, a)] > g[(a - 1, a - 1)] * (1.0 + 1e-9) + 1e-12 * scale {
            decreasing = false;
        }
    }
    (off, decreasing)
}

fn small_tensor() -> impl Strategy<Value = (Tensor3, [usize; 3])> {
    (2usize..7, 2usize..7, 2usize..8, any::<u64>(), 0.0f64..0.2).prop_flat_map(
        |(a, b, c, seed, noise)| {
            let x = decaying_tucker([a, b, c], [3, 3, 3], 2.0, noise, seed).unwrap();
            (
                (Just(x)),
                (1..=a, 1..=b, 1..=c).prop_map(|(p, q, r)| [p, q, r]),
            )
        },
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(40))]

    #[test]
    fn full_hosvd_is_exact_orthonormal_and_all_orthogonal((x, _r) in small_tensor()) {
        let t = hosvd_full(&x).unwrap();
        for n in 0..3 {
            prop_assert!(orthonormality_defect(t.factors[n].as_ref()) < 1e-10);
            let (off, dec) = all_orthogonality(&t, n);
            prop_assert!(off < 1e-9, "mode {} off-diagonal {}", n, off);
            prop_assert!(dec, "mode {} singular values not decreasing", n);
        }
        let y = t.reconstruct();
        let err = y.as_slice().iter().zip(x.as_slice()).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        prop_assert!(err < 1e-10 * (1.0 + x.frobenius_norm()), "reconstruction error {}", err);
    }

    #[test]
    fn als_never_worse_than_truncated_hosvd((x, r) in small_tensor()) {
        let h = hosvd(&x, r).unwrap();
        let (a, rep) = hooi(&x, r, &AlsOptions::default()).unwrap();
        let xn2 = x.squared_norm();
        let e_h = (xn2 - h.core_squared_norm()).max(0.0);
        let e_a = (xn2 - a.core_squared_norm()).max(0.0);
        prop_assert!(e_a <= e_h + 1e-10 * xn2, "ALS {} above HOSVD {}", e_a, e_h);
        // Reported errors agree with an explicit reconstruction.
        let explicit = a.explicit_mse(&x).unwrap();
        prop_assert!((rep.mse - explicit).abs() <= 1e-9 * (xn2 / x.len() as f64), "{} vs {}", rep.mse, explicit);
        prop_assert!((rep.rel_error - (explicit * x.len() as f64 / xn2).sqrt()).abs() < 1e-6);
        for n in 0..3 {
            prop_assert!(orthonormality_defect(a.factors[n].as_ref()) < 1e-10);
            prop_assert!(orthonormality_defect(h.factors[n].as_ref()) < 1e-10);
            let (off, dec) = all_orthogonality(&a, n);
            prop_assert!(off < 1e-9 && dec, "HOOI core not ordered in mode {}: {}", n, off);
        }
    }
}

#[test]
fn hooi_is_deterministic_and_reports_iterations() {
    let x = decaying_tucker([12, 14, 16], [8, 8, 8], 4.0, 0.05, 3).unwrap();
    let opts = AlsOptions {
        tol: 1e-12,
        max_iter: 50,
    };
    let (a, ra) = hooi(&x, [4, 5, 6], &opts).unwrap();
    let (b, rb) = hooi(&x, [4, 5, 6], &opts).unwrap();
    assert_eq!(a, b);
    assert_eq!(ra, rb);
    assert!(ra.iterations >= 1 && ra.iterations <= 50);
    let (_, r1) = hooi(
        &x,
        [4, 5, 6],
        &AlsOptions {
            tol: 0.0,
            max_iter: 3,
        },
    )
    .unwrap();
    assert_eq!((r1.iterations, r1.converged), (3, false));
    assert!(r1.mse >= ra.mse - 1e-12);
    // Same result under a 2-thread pool (key search uses rayon; kernels are sequential).
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let (c, _) = pool.install(|| hooi(&x, [4, 5, 6], &opts)).unwrap();
    assert_eq!(a, c);
}

#[test]
fn warm_start_never_above_the_truncation_it_starts_from() {
    let x = decaying_tucker([10, 11, 12], [7, 7, 7], 3.0, 0.05, 9).unwrap();
    let (big, _) = hooi(&x, [6, 6, 6], &AlsOptions::default()).unwrap();
    let small = big.truncate([4, 3, 5]).unwrap();
    let trunc_err = x.squared_norm() - small.core_squared_norm();
    let start = [
        small.factors[0].as_ref(),
        small.factors[1].as_ref(),
        small.factors[2].as_ref(),
    ];
    let (t, rep) = hooi_with_start(&x, start, &AlsOptions::default()).unwrap();
    assert_eq!(t.ranks(), [4, 3, 5]);
    assert!(rep.mse * x.len() as f64 <= trunc_err + 1e-10 * x.squared_norm());
    // A truncated ordered model is a projection: its error follows from the core norm.
    let explicit = small.explicit_mse(&x).unwrap() * x.len() as f64;
    assert!((explicit - trunc_err).abs() < 1e-9 * x.squared_norm());
}

#[test]
fn sample_core_is_core_times_sample_row() {
    let x = decaying_tucker([6, 7, 9], [4, 4, 4], 2.0, 0.01, 5).unwrap();
    let t = hosvd(&x, [3, 4, 5]).unwrap();
    for i in [0, 4, 8] {
        let k = t.sample_core(i);
        let row: Vec<f64> = (0..5).map(|s| t.factors[2][(i, s)]).collect();
        let expect = t.core.mode_vec_product(2, &row);
        assert!((k - expect).norm_max() < 1e-14);
    }
    let mut out = Mat::<f64>::zeros(3, 4);
    assert!(t.sample_core_into(9, out.as_mut()).is_err());
    let mut wrong = Mat::<f64>::zeros(4, 3);
    assert!(t.sample_core_into(0, wrong.as_mut()).is_err());
    t.sample_core_into(2, out.as_mut()).unwrap();
    assert_eq!(out, t.sample_core(2));
    // Mode singular values are decreasing for the ordered core.
    for n in 0..3 {
        let s = t.mode_singular_values(n).unwrap();
        assert!(s.windows(2).all(|w| w[0] >= w[1] * (1.0 - 1e-12)), "{s:?}");
    }
}

#[test]
fn bad_input_is_a_typed_error() {
    let x = decaying_tucker([4, 5, 6], [2, 2, 2], 1.0, 0.0, 1).unwrap();
    assert!(matches!(
        hosvd(&x, [0, 1, 1]),
        Err(HosvdError::Tensor(TensorError::BadRank { mode: 0, .. }))
    ));
    assert!(matches!(
        hooi(&x, [4, 6, 1], &AlsOptions::default()),
        Err(HosvdError::Tensor(TensorError::BadRank {
            mode: 1,
            rank: 6,
            size: 5
        }))
    ));
    let mut y = x.clone();
    let (i, j, k) = (3, 2, 1);
    y.as_mut_slice()[i + 4 * (j + 5 * k)] = f64::NAN;
    match hosvd(&y, [2, 2, 2]) {
        Err(HosvdError::Tensor(TensorError::NonFinite {
            i: 3, j: 2, k: 1, ..
        })) => {}
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        hosvd_full(&Tensor3::zeros([0, 2, 2])),
        Err(HosvdError::EmptyTensor { .. })
    ));
    assert!(matches!(
        hooi(
            &x,
            [1, 1, 1],
            &AlsOptions {
                tol: f64::NAN,
                max_iter: 5
            }
        ),
        Err(HosvdError::BadOption { field: "tol", .. })
    ));
    assert!(matches!(
        hooi(
            &x,
            [1, 1, 1],
            &AlsOptions {
                tol: 1e-8,
                max_iter: 0
            }
        ),
        Err(HosvdError::BadOption {
            field: "max_iter",
            ..
        })
    ));
    let f = [
        Mat::<f64>::zeros(4, 2),
        Mat::<f64>::zeros(3, 2),
        Mat::<f64>::zeros(6, 2),
    ];
    assert!(matches!(
        hooi_with_start(
            &x,
            [f[0].as_ref(), f[1].as_ref(), f[2].as_ref()],
            &AlsOptions::default()
        ),
        Err(HosvdError::BadStart { mode: 1, .. })
    ));
    // An all-zero tensor decomposes with zero error.
    let (_, rep) = hooi(
        &Tensor3::zeros([3, 3, 3]),
        [2, 2, 2],
        &AlsOptions::default(),
    )
    .unwrap();
    assert_eq!((rep.mse, rep.rel_error), (0.0, 0.0));
}

/// The decompositions spread their large products over the pool's threads in fixed blocks
/// (`tensor_ops::par`): HOOI through the fibre Gram (more samples than fibres) and through the
/// sample Gram, and the HOSVD, give the same bits on pools of one, two and three threads.
#[test]
fn decompositions_are_the_same_bits_on_any_pool() {
    let bits = |t: &Tucker| -> Vec<u64> {
        let mut v: Vec<u64> = t.core.as_slice().iter().map(|x| x.to_bits()).collect();
        for f in &t.factors {
            for j in 0..f.ncols() {
                v.extend((0..f.nrows()).map(|i| f[(i, j)].to_bits()));
            }
        }
        v
    };
    let opts = AlsOptions {
        tol: 0.0,
        max_iter: 3,
    };
    // 12 x 10 fibres under 1,500 samples (the fibre Gram), and 30 x 20 over 400 (the sample Gram):
    // both large enough for the blocked products to split.
    for (dims, ranks) in [
        ([40, 30, 1500], [12, 10, 20]),
        ([60, 40, 400], [30, 20, 25]),
    ] {
        let x = decaying_tucker(dims, [20, 20, 30], 4.0, 0.01, 5).unwrap();
        let runs: Vec<(Vec<u64>, Vec<u64>)> = [1, 2, 3]
            .iter()
            .map(|&threads| {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                pool.install(|| {
                    let (t, _) = hooi(&x, ranks, &opts).unwrap();
                    (bits(&t), bits(&hosvd(&x, ranks).unwrap()))
                })
            })
            .collect();
        assert!(runs[0].0.iter().any(|&b| b != 0));
        for (threads, run) in [2, 3].iter().zip(&runs[1..]) {
            assert!(
                run.0 == runs[0].0,
                "{dims:?}: HOOI differs on {threads} threads"
            );
            assert!(
                run.1 == runs[0].1,
                "{dims:?}: HOSVD differs on {threads} threads"
            );
        }
    }
}

/// Finite data so large that the Gram matrices overflow: the error says so (it used to blame the
/// eigensolver's convergence).
#[test]
fn overflowing_gram_matrices_are_named() {
    let x = decaying_tucker([4, 5, 6], [2, 2, 2], 1.0, 0.0, 1).unwrap();
    for scale in [1e160, 1e200] {
        let mut big = x.clone();
        big.as_mut_slice().iter_mut().for_each(|v| *v *= scale);
        big.check_finite().unwrap();
        let err = hosvd(&big, [2, 2, 2]).unwrap_err();
        assert!(
            matches!(err, HosvdError::GramOverflow { mode: 0, size: 4 }),
            "{err}"
        );
        assert!(err.to_string().contains("too large"), "{err}");
        let err = hooi(&big, [2, 2, 2], &AlsOptions::default()).unwrap_err();
        assert!(matches!(err, HosvdError::GramOverflow { .. }), "{err}");
    }
}

/// A `Tucker` whose public fields disagree (a factor with another column count than the core)
/// gives errors from the methods that return `Result`, and `mode_singular_values` checks the mode.
#[test]
fn inconsistent_tucker_fields_are_errors() {
    let x = decaying_tucker([4, 5, 6], [2, 2, 2], 1.0, 0.01, 1).unwrap();
    let good = hosvd(&x, [3, 3, 3]).unwrap();
    assert!(good.check().is_ok());
    assert_eq!(good.try_reconstruct().unwrap(), good.reconstruct());
    assert!(matches!(
        good.mode_singular_values(3),
        Err(HosvdError::Tensor(TensorError::BadMode { mode: 3 }))
    ));
    for (mode, cols) in [(2, 2), (0, 1), (1, 4)] {
        let mut bad = good.clone();
        let f = &bad.factors[mode];
        bad.factors[mode] = Mat::from_fn(f.nrows(), cols, |i, j| if i == j { 1.0 } else { 0.0 });
        let shape = |r: Result<(), HosvdError>| {
            matches!(
                r,
                Err(HosvdError::Tensor(TensorError::ShapeMismatch { expected: 3, found, .. }))
                    if found == cols
            )
        };
        assert!(shape(bad.check()), "{mode}");
        let mut out = Mat::<f64>::zeros(3, 3);
        assert!(shape(bad.sample_core_into(0, out.as_mut())), "{mode}");
        assert!(shape(bad.truncate([2, 2, 2]).map(|_| ())), "{mode}");
        assert!(shape(bad.try_reconstruct().map(|_| ())), "{mode}");
        assert!(bad.explicit_mse(&x).is_err(), "{mode}");
        assert!(shape(bad.clone().into_ordered().map(|_| ())), "{mode}");
    }
}

/// Noise that is not finite is refused, not returned as a tensor of NaN.
#[test]
fn synthetic_tensors_refuse_non_finite_parameters() {
    for noise in [f64::NAN, f64::INFINITY] {
        assert!(matches!(
            decaying_tucker([3, 4, 5], [2, 2, 2], 1.0, noise, 1),
            Err(TensorError::NonFinite { .. })
        ));
    }
    assert!(decaying_tucker([3, 4, 5], [2, 2, 2], f64::NAN, 0.0, 1).is_err());
    assert!(decaying_tucker([3, 4, 5], [2, 2, 2], 1.0, 0.5, 1).is_ok());
}
