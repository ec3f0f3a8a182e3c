//! Crowd benchmarks: one frame (cull + kernels + poses + FK) at 1k and 10k walkers with the
//! procedural source, the paper's distance policy and the camera walking inside the crowd; and
//! BVH rebuild versus refit at 10k and 100k walker boxes.

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use crowd_sim::culling::WalkerAabbTree;
use crowd_sim::testing::{ProceduralSource, paper_distance_policy};
use crowd_sim::{Bounds, Camera, CameraPath, ClipSource, Crowd, CrowdConfig, Frustum};
use glam::Vec3;
use lod_policy::SplitMix64;
use std::hint::black_box;

/// Walkers per square metre.
const DENSITY: f32 = 0.1;

fn frame(c: &mut Criterion) {
    let source = ProceduralSource::new();
    let policy = paper_distance_policy(source.levels());
    let mut g = c.benchmark_group("crowd_frame");
    for walkers in [1_000usize, 10_000] {
        let config = CrowdConfig {
            seed: 7,
            fps: 60.0,
            ..CrowdConfig::with_density(walkers, DENSITY)
        };
        let mut crowd = Crowd::new(&source, config).unwrap();
        let path = CameraPath::inside_crowd(config.field_size_m);
        let lens = Camera::default();
        let dt = 1.0 / config.fps;
        // Warm up: every walker past its first cycle.
        for f in 0..90 {
            crowd
                .step(&source, &policy, &path.camera_at(f as f32 * dt, &lens), dt)
                .unwrap();
        }
        let mut f = 90u32;
        let mut stats = crowd_sim::FrameStats::default();
        g.bench_function(BenchmarkId::from_parameter(walkers), |b| {
            b.iter(|| {
                let cam = path.camera_at(f as f32 * dt, &lens);
                crowd
                    .step_into(&source, &policy, &cam, dt, &mut stats)
                    .unwrap();
                f += 1;
                black_box(stats.visible)
            })
        });
        // One report line per size with the stage split and the level histogram.
        let report = crowd.run(&source, &policy, &path, &lens, 120).unwrap();
        eprintln!("{walkers} walkers, 120 frames:\n{report}");
    }
    g.finish();
}

fn boxes(n: usize, field: f32, seed: u64) -> Vec<Bounds> {
    let mut g = SplitMix64::new(seed);
    (0..n)
        .map(|_| {
            let c = Vec3::new(
                g.range(-0.5 * field, 0.5 * field),
                0.0,
                g.range(-0.5 * field, 0.5 * field),
            );
            Bounds {
                min: c - Vec3::new(0.9, 0.25, 0.9),
                max: c + Vec3::new(0.9, 2.1, 0.9),
            }
        })
        .collect()
}

fn bvh(c: &mut Criterion) {
    let mut g = c.benchmark_group("crowd_bvh");
    for n in [10_000usize, 100_000] {
        let field = (n as f32 / DENSITY).sqrt();
        let a = boxes(n, field, 1);
        // Every box moved by up to ~3 cm, as between two frames.
        let moved: Vec<Bounds> = a
            .iter()
            .enumerate()
            .map(|(i, b)| {
                let d = Vec3::new(
                    ((i % 7) as f32 - 3.0) * 0.01,
                    0.0,
                    ((i % 5) as f32 - 2.0) * 0.01,
                );
                Bounds {
                    min: b.min + d,
                    max: b.max + d,
                }
            })
            .collect();
        let mut tree = WalkerAabbTree::new(&a);
        g.bench_function(BenchmarkId::new("rebuild", n), |b| {
            b.iter(|| tree.rebuild(black_box(&moved)))
        });
        g.bench_function(BenchmarkId::new("refit", n), |b| {
            b.iter(|| tree.refit(black_box(&moved)))
        });
        let cam = Camera {
            position: Vec3::new(0.0, 1.7, 0.0),
            target: Vec3::new(10.0, 1.2, 10.0),
            ..Camera::default()
        };
        let fr = Frustum::from_camera(&cam).unwrap();
        let mut vis = vec![false; n];
        g.bench_function(BenchmarkId::new("query", n), |b| {
            b.iter(|| tree.query(black_box(&fr), &mut vis))
        });
        // What `Culling::Scan` does instead of refit + query: every box against the frustum.
        g.bench_function(BenchmarkId::new("scan", n), |b| {
            b.iter(|| {
                let mut count = 0usize;
                for (v, bx) in vis.iter_mut().zip(black_box(&moved)) {
                    *v = fr.intersects(bx);
                    count += usize::from(*v);
                }
                count
            })
        });
    }
    g.finish();
}

criterion_group!(benches, frame, bvh);
criterion_main!(benches);
