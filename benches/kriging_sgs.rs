//! Sequential Gaussian simulation ([`kriging::Sgs`]) at the scale of issue 37's goal: 100
//! realisations of a 200 x 200 grid conditioned on 2,000 points (the job of
//! `examples/sgs_timing.rs` and `scripts/sgs_gstools_timing.py`: Halton points on [0, 10000]^2,
//! values `sin(x/1500) + cos(y/900) + 1e-4 x`, exponential variogram without nugget, partial sill
//! 1, practical range 3000, simple kriging with the data mean).
//!
//! Run: `cargo bench -p motion-lod-benches --bench kriging_sgs -- --sample-size 10`.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use kriging::faer::Mat;
use kriging::{NestedVariogram, Sgs, SgsPath, VariogramModel};

mod halton_points;

const N: usize = 2000;
const GRID: usize = 200;
const REALISATIONS: usize = 100;

fn data() -> (Mat<f64>, Vec<f64>) {
    halton_points::problem(N)
}

fn bench(c: &mut Criterion) {
    let (coords, z) = data();
    let g: Vec<f64> = (0..GRID)
        .map(|i| 10000.0 * i as f64 / (GRID - 1) as f64)
        .collect();
    let v = NestedVariogram::single(VariogramModel::Exponential, 0.0, 1.0, 3000.0).unwrap();
    let mut group = c.benchmark_group("sgs_n2000_grid200_r100");
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(30));
    for (name, k, path) in [
        ("per_realisation_path_k16", 16, SgsPath::PerRealisation),
        ("shared_path_k16", 16, SgsPath::Shared),
        ("shared_path_k32", 32, SgsPath::Shared),
    ] {
        let sgs = Sgs::new(v.clone())
            .neighbours(k)
            .path(path)
            .seed(2024)
            .realisations(REALISATIONS);
        group.bench_function(name, |b| {
            b.iter(|| {
                sgs.simulate_grid(black_box(coords.as_ref()), &z, &g, &g)
                    .unwrap()
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
