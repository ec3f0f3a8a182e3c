//! Geostatistical kriging ([`kriging::Krige`]) against PyKrige and GSTools on the same problem as
//! `crates/kriging/scripts/bench_python.py`: n = 2000 Halton points on [0, 10000]^2, ordinary
//! kriging with a given spherical variogram, fit plus predictions and variances on a 100 x 100 grid.
//! Run: `cargo bench -p motion-lod-benches --bench kriging_geo`.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use kriging::faer::Mat;
use kriging::{Drift, Krige, Neighbourhood, NestedVariogram, VariogramModel};

mod halton_points;

const N: usize = 2000;
const GRID: usize = 100;

fn data() -> (Mat<f64>, Vec<f64>) {
    halton_points::problem(N)
}

fn grid() -> Vec<f64> {
    (0..GRID)
        .map(|i| 10000.0 * i as f64 / (GRID - 1) as f64)
        .collect()
}

fn bench(c: &mut Criterion) {
    let (coords, z) = data();
    let g = grid();
    let v = NestedVariogram::single(VariogramModel::Spherical, 0.05, 1.0, 3000.0).unwrap();
    let mut group = c.benchmark_group("geo_n2000_grid100");
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(20));
    group.bench_function("ok_fit_and_grid_with_variance", |b| {
        b.iter(|| {
            let m = Krige::new()
                .variogram(v.clone())
                .fit(black_box(coords.as_ref()), &z)
                .unwrap();
            m.predict_grid(&g, &g).unwrap()
        })
    });
    group.bench_function("uk_linear_fit_and_grid_with_variance", |b| {
        b.iter(|| {
            let m = Krige::new()
                .drift(Drift::Linear)
                .variogram(v.clone())
                .fit(black_box(coords.as_ref()), &z)
                .unwrap();
            m.predict_grid(&g, &g).unwrap()
        })
    });
    group.bench_function("ok_variogram_fit_and_grid_with_variance", |b| {
        b.iter(|| {
            let m = Krige::new().fit(black_box(coords.as_ref()), &z).unwrap();
            m.predict_grid(&g, &g).unwrap()
        })
    });
    group.bench_function("ok_nearest32_fit_and_grid_with_variance", |b| {
        b.iter(|| {
            let m = Krige::new()
                .variogram(v.clone())
                .neighbourhood(Neighbourhood::Nearest { k: 32 })
                .fit(black_box(coords.as_ref()), &z)
                .unwrap();
            m.predict_grid(&g, &g).unwrap()
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
