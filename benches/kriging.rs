//! Benchmarks of the `kriging` crate at the paper's sizes: S = 186 samples over a 3-D control
//! space, R = 60 projected rows (R_S), D = 60 values per sample.

use criterion::{Criterion, criterion_group, criterion_main};
use faer::Mat;
use kriging::{
    Kriging, KrigingConfig, Method, ModelChoice, ProjectedQuery, Selection, VariogramModel,
};
use std::hint::black_box;

const S: usize = 186;
const R: usize = 60;
const D: usize = 60;

/// Deterministic pseudo-random numbers in [0, 1).
fn lcg(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (*state >> 11) as f64 / (1u64 << 53) as f64
}

/// Controls (dx, dz, turn) and smooth values with some noise.
fn data() -> (Mat<f64>, Mat<f64>) {
    let mut st = 7u64;
    let params = Mat::from_fn(S, 3, |_, k| match k {
        0 => 0.4 * (lcg(&mut st) - 0.5),
        1 => 0.8 + 0.8 * lcg(&mut st),
        _ => 1.5 * (lcg(&mut st) - 0.5),
    });
    let mut st2 = 11u64;
    let values = Mat::from_fn(S, D, |i, j| {
        let c = [params[(i, 0)], params[(i, 1)], params[(i, 2)]];
        (j as f64 * 0.1 + 3.0 * c[0]).sin() + c[1] * c[2] * (j % 5) as f64 + 0.05 * lcg(&mut st2)
    });
    (params, values)
}

fn bench(c: &mut Criterion) {
    let (params, values) = data();
    let fixed = KrigingConfig {
        method: Method::Regression,
        model: ModelChoice::Fixed(VariogramModel::Exponential),
        ..KrigingConfig::default()
    };
    let auto = KrigingConfig {
        model: ModelChoice::Auto(Selection::BestLoo),
        ..fixed.clone()
    };
    let mut st = 3u64;
    let l = Mat::from_fn(R, S, |_, _| lcg(&mut st) - 0.5);
    let mut g = c.benchmark_group("kriging");
    g.sample_size(20);
    g.bench_function("setup_fit_fixed_exponential_S186_d3_D60", |b| {
        b.iter(|| Kriging::fit(black_box(params.as_ref()), values.as_ref(), &fixed).unwrap())
    });
    g.bench_function("setup_fit_auto_bestloo_S186_d3_D60", |b| {
        b.iter(|| Kriging::fit(black_box(params.as_ref()), values.as_ref(), &auto).unwrap())
    });
    let k = Kriging::fit(params.as_ref(), values.as_ref(), &fixed).unwrap();
    g.bench_function("setup_projected_R60", |b| {
        b.iter(|| ProjectedQuery::new(black_box(&k), l.as_ref()).unwrap())
    });
    g.finish();

    let pq = ProjectedQuery::new(&k, l.as_ref()).unwrap();
    let q = [0.05, 1.1, 0.3];
    let mut w = vec![0.0; S];
    let mut gamma = vec![0.0; S + 1];
    let mut out = vec![0.0; R];
    let mut pred = vec![0.0; D];
    let mut g = c.benchmark_group("kriging_query");
    g.bench_function("weights_S186", |b| {
        b.iter(|| k.weights(black_box(&q), &mut w).unwrap())
    });
    g.bench_function("plain_weights_then_L_R60", |b| {
        b.iter(|| {
            k.weights(black_box(&q), &mut w).unwrap();
            for (r, o) in out.iter_mut().enumerate() {
                *o = (0..S).map(|j| l[(r, j)] * w[j]).sum();
            }
            black_box(&out);
        })
    });
    g.bench_function("projected_query_R60", |b| {
        b.iter(|| pq.query(black_box(&q), &mut gamma, &mut out).unwrap())
    });
    g.bench_function("predict_D60", |b| {
        b.iter(|| k.predict(black_box(&q), &mut pred).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
