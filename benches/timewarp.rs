//! Benchmarks of the `timewarp` crate at the sizes of the Bandai data set: cycles of ~35 frames,
//! features of dimension 60 (20 joint positions), S = 800 cycles.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use timewarp::{
    AlignConfig, AlignMethod, DtwConfig, DtwWorkspace, FrameSeq, align, dtw_with, medoid,
    playback_into,
};

/// A smooth closed curve of `dim` values, `n` frames, time-warped by `a` (|a| < 1).
fn cycle(n: usize, dim: usize, a: f64) -> FrameSeq {
    let mut seq = FrameSeq::zeros(dim, n);
    for k in 0..n {
        let s0 = k as f64 / (n - 1) as f64;
        let s = s0 + a * (std::f64::consts::PI * s0).sin() / std::f64::consts::PI;
        for (c, v) in seq.frame_mut(k).iter_mut().enumerate() {
            let f = 1.0 + (c % 3) as f64;
            *v = (std::f64::consts::TAU * f * s + 0.7 * c as f64).sin();
        }
    }
    seq
}

fn cycles(count: usize) -> Vec<FrameSeq> {
    (0..count)
        .map(|s| cycle(25 + (s * 7) % 17, 60, ((s * 13) % 11) as f64 / 10.0 - 0.5))
        .collect()
}

fn bench_timewarp(c: &mut Criterion) {
    let a = cycle(35, 60, 0.3);
    let b = cycle(33, 60, -0.4);
    let cfg = DtwConfig::default();
    let mut ws = DtwWorkspace::new();
    c.bench_function("timewarp/dtw_35x33_dim60", |bench| {
        bench.iter(|| dtw_with(black_box(&a), black_box(&b), &cfg, &mut ws).unwrap())
    });

    let set = cycles(800);
    let ft = vec![1.0 / 30.0; set.len()];
    let mut group = c.benchmark_group("timewarp_s800");
    group.sample_size(10);
    group.bench_function("medoid", |bench| {
        bench.iter(|| medoid(black_box(&set), &cfg).unwrap())
    });
    let mut align_cfg = AlignConfig::new(33, AlignMethod::Dtw(cfg));
    align_cfg.reference = Some(0);
    group.bench_function("align_dtw_fixed_reference", |bench| {
        bench.iter(|| align(black_box(&set), &set, &ft, &align_cfg).unwrap())
    });
    align_cfg.method = AlignMethod::Uniform;
    group.bench_function("align_uniform", |bench| {
        bench.iter(|| align(black_box(&set), &set, &ft, &align_cfg).unwrap())
    });
    group.finish();

    let al = align(
        &set[..1],
        &set[..1],
        &ft[..1],
        &AlignConfig::new(33, AlignMethod::Uniform),
    )
    .unwrap();
    let aligned = &al.aligned[0];
    // The runtime's clip time table (what a clip kernel fills per clip).
    let mut table = lod_policy::TimeTable::with_capacity(33);
    let incs: Vec<f64> = (0..33)
        .map(|k| aligned.frame(k)[al.increment_col])
        .collect();
    c.bench_function("timewarp/time_table_fill_and_60_phases", |bench| {
        bench.iter(|| {
            table.fill_from(black_box(&incs));
            let mut acc = 0.0;
            for m in 0..60 {
                acc += table.phase_at(m as f64 / 60.0);
            }
            acc
        })
    });
    let mut out = FrameSeq::zeros(60, 0);
    let mut times = Vec::with_capacity(33);
    c.bench_function("timewarp/playback_cycle_at_60fps", |bench| {
        bench.iter(|| {
            playback_into(
                black_box(aligned),
                al.increment_col,
                60.0,
                &mut times,
                &mut out,
            )
            .unwrap()
        })
    });
}

criterion_group!(benches, bench_timewarp);
criterion_main!(benches);
