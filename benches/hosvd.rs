//! HOSVD, HOOI and the key-level search at the paper's shape 94 x 100 x 186 (synthetic data with
//! a decaying multilinear spectrum, `hosvd_als::synthetic::decaying_tucker`), and ten HOOI sweeps
//! at issue 35's Bandai shape (67 x 100 x 800, ranks 40, 40, 60) and at 10,000 samples (67 x 34 x
//! 10,000, the key's ranks 29, 34, 60) on pools of one thread and of every core, for the speed-up
//! the decomposition gets from more threads (its results are the same bits on any pool).
//!
//! Run: `cargo bench -p motion-lod-benches --bench hosvd`.

use criterion::{Criterion, criterion_group, criterion_main};
use hosvd_als::synthetic::decaying_tucker;
use hosvd_als::{AlsOptions, KeySearchConfig, hooi, hosvd, hosvd_full, key_levels};
use std::hint::black_box;

const DIMS: [usize; 3] = [94, 100, 186];

fn bench(c: &mut Criterion) {
    let x = decaying_tucker(DIMS, [60, 60, 90], 6.0, 0.01, 1).expect("synthetic tensor");
    let mut g = c.benchmark_group("hosvd_94x100x186");
    g.sample_size(10);
    g.bench_function("hosvd_truncated_40_40_60", |b| {
        b.iter(|| hosvd(black_box(&x), [40, 40, 60]).unwrap())
    });
    g.bench_function("hosvd_full", |b| {
        b.iter(|| hosvd_full(black_box(&x)).unwrap())
    });
    let opts = AlsOptions {
        tol: 1e-8,
        max_iter: 100,
    };
    g.bench_function("hooi_40_40_60_tol1e-8", |b| {
        b.iter(|| hooi(black_box(&x), [40, 40, 60], &opts).unwrap())
    });
    // A fixed amount of work per run: 10 sweeps regardless of convergence.
    let ten = AlsOptions {
        tol: 0.0,
        max_iter: 10,
    };
    g.bench_function("hooi_40_40_60_10_sweeps", |b| {
        b.iter(|| hooi(black_box(&x), [40, 40, 60], &ten).unwrap())
    });
    let cfg = KeySearchConfig::default();
    g.bench_function("key_levels_10_from_40_40_60_to_7_7_9", |b| {
        b.iter(|| key_levels(black_box(&x), &cfg).unwrap())
    });
    g.finish();
    threads(c);
}

/// Ten HOOI sweeps at two larger shapes on one thread and on every core.
fn threads(c: &mut Criterion) {
    let ten = AlsOptions {
        tol: 0.0,
        max_iter: 10,
    };
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut pools = vec![1];
    if cores > 1 {
        pools.push(cores);
    }
    for (dims, core, ranks) in [
        ([67, 100, 800], [60, 60, 90], [40, 40, 60]),
        ([67, 34, 10_000], [50, 34, 90], [29, 34, 60]),
    ] {
        let x = decaying_tucker(dims, core, 6.0, 0.01, 2).expect("synthetic tensor");
        let mut g = c.benchmark_group(format!("hooi_{}x{}x{}", dims[0], dims[1], dims[2]));
        g.sample_size(10);
        for &t in &pools {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(t)
                .build()
                .expect("a thread pool");
            g.bench_function(
                format!(
                    "10_sweeps_{}_{}_{}_{t}_threads",
                    ranks[0], ranks[1], ranks[2]
                ),
                |b| b.iter(|| pool.install(|| hooi(black_box(&x), ranks, &ten).unwrap())),
            );
        }
        g.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
