//! The greedy key-level search, hybrid accuracy levels and storage accounting.

use hosvd_als::storage::{all_levels_bytes, dense_bytes, key_levels_bytes, mib, tucker_bytes};
use hosvd_als::synthetic::decaying_tucker;
use hosvd_als::{AlsOptions, HosvdError, KeySearchConfig, hybrid_levels, key_levels};

fn data() -> tensor_ops::Tensor3 {
    decaying_tucker([20, 18, 24], [14, 14, 16], 5.0, 0.02, 11).unwrap()
}

fn cfg(levels: usize, max: [usize; 3], min: [usize; 3]) -> KeySearchConfig {
    KeySearchConfig {
        levels,
        max_ranks: max,
        min_ranks: min,
        als: AlsOptions::default(),
    }
}

#[test]
fn key_levels_decrease_in_ranks_and_increase_in_error() {
    let x = data();
    let c = cfg(6, [12, 12, 14], [3, 3, 4]);
    let keys = key_levels(&x, &c).unwrap();
    assert_eq!(keys.levels.len(), 6);
    assert_eq!(keys.levels[0].ranks, [12, 12, 14]);
    assert_eq!(keys.levels[5].ranks, [3, 3, 4]);
    assert!(!keys.clamped);
    for w in keys.levels.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        assert!(
            (0..3).all(|n| b.ranks[n] <= a.ranks[n]) && b.ranks != a.ranks,
            "{:?} -> {:?}",
            a.ranks,
            b.ranks
        );
        assert!(
            b.mse > a.mse,
            "errors not increasing: {} -> {}",
            a.mse,
            b.mse
        );
    }
    // C_E = E_N / (N E_1) and every intermediate key exceeds its threshold l C_E E_1.
    let (e1, en) = (keys.levels[0].mse, keys.levels[5].mse);
    assert!((keys.c_e - en / (6.0 * e1)).abs() <= 1e-12 * keys.c_e);
    for (idx, l) in keys.levels.iter().enumerate().take(5).skip(1) {
        let t = l.threshold.unwrap();
        assert!((t - (idx + 1) as f64 * keys.c_e * e1).abs() <= 1e-9 * t);
        assert!(l.als_runs >= 1, "level {idx} was never confirmed by ALS");
        // A key is accepted when its ALS error exceeds the threshold, or when the ranks left above
        // the minimum are only enough for the levels still to come (one step each).
        let slack: usize = (0..3).map(|n| l.ranks[n] - c.min_ranks[n]).sum();
        let reserve = 6 - 1 - idx;
        assert!(
            l.mse > t || slack <= reserve,
            "level {idx}: mse {} under its threshold {t} with {slack} rank steps left for {reserve} levels",
            l.mse
        );
        assert_eq!(l.tucker.ranks(), l.ranks);
        assert!((l.tucker.explicit_mse(&x).unwrap() - l.mse).abs() <= 1e-8 * l.mse.max(1e-12));
    }
    assert!(
        keys.unconverged().is_empty(),
        "ALS hit its cap at keys {:?}",
        keys.unconverged()
    );
    // Deterministic.
    assert_eq!(key_levels(&x, &c).unwrap(), keys);
}

#[test]
fn clamping_and_too_few_steps_are_reported() {
    let x = decaying_tucker([5, 6, 7], [3, 3, 3], 2.0, 0.05, 2).unwrap();
    let keys = key_levels(&x, &cfg(3, [40, 40, 60], [2, 2, 2])).unwrap();
    assert!(keys.clamped);
    assert_eq!(keys.max_ranks, [5, 6, 7]);
    assert_eq!(keys.levels[0].ranks, [5, 6, 7]);
    // Only 2 single-rank steps between (3,3,3) and (2,2,3): at most 3 levels.
    let keys = key_levels(&x, &cfg(10, [3, 3, 3], [2, 2, 3])).unwrap();
    assert_eq!((keys.levels.len(), keys.requested_levels), (3, 10));
    let one = key_levels(&x, &cfg(1, [3, 3, 3], [2, 2, 2])).unwrap();
    assert_eq!(one.levels.len(), 1);
    assert!(matches!(
        key_levels(&x, &cfg(0, [3, 3, 3], [2, 2, 2])),
        Err(HosvdError::BadKeyConfig(_))
    ));
    assert!(matches!(
        key_levels(&x, &cfg(3, [3, 3, 3], [4, 2, 2])),
        Err(HosvdError::BadKeyConfig(_))
    ));
    assert!(matches!(
        key_levels(&x, &cfg(3, [3, 0, 3], [1, 1, 1])),
        Err(HosvdError::BadKeyConfig(_))
    ));
}

#[test]
fn hybrid_levels_truncate_the_nearest_larger_key() {
    let x = data();
    let keys = key_levels(&x, &cfg(4, [12, 12, 14], [3, 3, 4])).unwrap();
    let acc = hybrid_levels(&keys, 13);
    assert_eq!(acc.len(), 13);
    assert_eq!((acc[0].key, acc[0].ranks), (0, keys.levels[0].ranks));
    // Keys at levels 0, 4, 8, 12.
    for (i, p) in [0usize, 4, 8, 12].iter().enumerate() {
        assert_eq!(acc[*p].ranks, keys.levels[i].ranks);
        assert_eq!(acc[*p].key, i);
    }
    // Within one key's segment the errors grow (truncations of one core lose energy); across a
    // key boundary an ALS key can beat the truncation just above it (the paper's discontinuity).
    let mut prev: Option<(usize, f64)> = None;
    for (j, a) in acc.iter().enumerate() {
        let key = &keys.levels[a.key];
        assert!((0..3).all(|n| a.ranks[n] <= key.ranks[n]));
        if a.key + 1 < keys.levels.len() && j != [0, 4, 8, 12][a.key] {
            let next = &keys.levels[a.key + 1];
            assert!((0..3).all(|n| a.ranks[n] >= next.ranks[n]));
        }
        if j > 0 {
            assert!((0..3).all(|n| a.ranks[n] <= acc[j - 1].ranks[n]));
        }
        let (mse, _) = keys.level_errors(a).unwrap();
        let model = keys.model_at(a).unwrap();
        assert!((model.explicit_mse(&x).unwrap() - mse).abs() <= 1e-8 * mse.max(1e-12));
        if let Some((k, e)) = prev {
            if k == a.key {
                assert!(mse >= e * (1.0 - 1e-9), "level {j}: {mse} < {e}");
            }
        }
        prev = Some((a.key, mse));
    }
    // Fewer accuracy levels than keys: every key once.
    assert_eq!(hybrid_levels(&keys, 2).len(), 4);
}

#[test]
fn storage_counts_cores_and_factors() {
    assert_eq!(
        tucker_bytes([94, 100, 186], [40, 40, 60], 8),
        (40 * 40 * 60 + 94 * 40 + 100 * 40 + 186 * 60) * 8
    );
    assert_eq!(
        tucker_bytes([94, 100, 186], [7, 7, 9], 4),
        (7 * 7 * 9 + 94 * 7 + 100 * 7 + 186 * 9) * 4
    );
    // The paper's 13.34 MB for all samples is 94 x 100 x 186 doubles in MiB.
    assert!((mib(dense_bytes([94, 100, 186], 8)) - 13.34).abs() < 0.005);
    let x = data();
    let keys = key_levels(&x, &cfg(3, [10, 10, 10], [4, 4, 4])).unwrap();
    let sum: usize = keys.levels.iter().map(|l| l.tucker.bytes(8)).sum();
    assert_eq!(key_levels_bytes(&keys, 8), sum);
    assert_eq!(key_levels_bytes(&keys, 4) * 2, sum);
    let acc = hybrid_levels(&keys, 9);
    assert!(all_levels_bytes(x.dims(), &acc, 8) > sum);
}

#[test]
fn convergence_is_reported_per_key() {
    let x = data();
    let converged = key_levels(&x, &cfg(3, [12, 12, 14], [3, 3, 4])).unwrap();
    for (k, l) in converged.levels.iter().enumerate() {
        assert!(
            l.converged,
            "key {k} did not converge in {} sweeps",
            l.iterations
        );
        assert!(l.iterations < AlsOptions::default().max_iter, "key {k}");
    }
    // One sweep with tolerance 0 (which no sweep meets): every key stops at the cap and says so.
    let capped = KeySearchConfig {
        als: AlsOptions {
            tol: 0.0,
            max_iter: 1,
        },
        ..cfg(3, [12, 12, 14], [3, 3, 4])
    };
    let keys = key_levels(&x, &capped).unwrap();
    assert_eq!(
        keys.unconverged(),
        (0..keys.levels.len()).collect::<Vec<_>>()
    );
    assert!(keys.levels.iter().all(|l| l.iterations == 1));
}

/// Byte counts saturate instead of wrapping to small numbers.
#[test]
fn byte_counts_saturate() {
    assert_eq!(dense_bytes([1 << 22; 3], 8), usize::MAX);
    assert_eq!(dense_bytes([1 << 40, 1 << 40, 0], 8), 0);
    assert_eq!(tucker_bytes([10; 3], [1 << 22; 3], 8), usize::MAX);
    assert_eq!(tucker_bytes([usize::MAX; 3], [2; 3], 1), usize::MAX);
    // Ordinary counts are unchanged.
    assert_eq!(dense_bytes([94, 100, 186], 8), 94 * 100 * 186 * 8);
    assert_eq!(
        tucker_bytes([94, 100, 186], [20, 30, 40], 4),
        (20 * 30 * 40 + 94 * 20 + 100 * 30 + 186 * 40) * 4
    );
}

/// Absurd accuracy level counts are lowered to the documented maximum instead of aborting on the
/// allocation (or panicking on `usize::MAX`).
#[test]
fn accuracy_levels_are_capped() {
    let x = data();
    let keys = key_levels(&x, &cfg(3, [8, 8, 8], [3, 3, 3])).unwrap();
    for requested in [1 << 40, usize::MAX] {
        let levels = hybrid_levels(&keys, requested);
        assert_eq!(levels.len(), hosvd_als::MAX_ACCURACY_LEVELS);
        assert_eq!(levels[0].ranks, keys.levels[0].ranks);
        assert_eq!(levels.last().unwrap().ranks, keys.levels[2].ranks);
    }
    assert_eq!(
        hybrid_levels(&keys, hosvd_als::MAX_ACCURACY_LEVELS),
        hybrid_levels(&keys, hosvd_als::MAX_ACCURACY_LEVELS + 1)
    );
    assert_eq!(hybrid_levels(&keys, 28).len(), 28);
}
