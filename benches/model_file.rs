//! Clip kernels and poses of a model FILE (`MOTION_LOD_BENCH_MODEL=path.mlod`, for example a model
//! built from the Bandai data with `motion-lod build`): root-only, the last accuracy level and full
//! detail, so the runtime's costs are measured at a real sample count (S = 800 for Bandai) rather
//! than the embedded fixtures'. Also one frame of a crowd of walkers that are all root only, on one
//! thread, at 2,000 walkers (which stay in cache) and at 100,000 (time per walker-frame = frame
//! time / walkers; criterion prints the walkers per second). And the runtime model read from the
//! file's bytes. Without the variable it prints how to set it and measures nothing.

use std::hint::black_box;
use std::path::PathBuf;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use crowd_sim::{Camera, Crowd, CrowdConfig, FrameStats, Scene};
use lod_policy::{ClipKernel, Controls, Detail, KernelScratch, ViewParams};
use motion_lod::{LodSource, MotionModel};

fn bench(c: &mut Criterion) {
    let Some(path) = std::env::var_os("MOTION_LOD_BENCH_MODEL").map(PathBuf::from) else {
        eprintln!(
            "model_file: set MOTION_LOD_BENCH_MODEL to a model file (motion-lod build --output \
             FILE DIR) to measure it; nothing measured"
        );
        return;
    };
    let model = MotionModel::load(&path).expect("MOTION_LOD_BENCH_MODEL loads");
    let lod = model.lod();
    let cs = lod.controls();
    // Controls spread over the data's range (a fixed low-discrepancy walk, so every run is the same).
    let controls: Vec<Controls> = (0..64)
        .map(|i| {
            Controls::from_array(std::array::from_fn(|k| {
                let u = ((i as f32 + 0.5) * (0.618_034 + 0.1 * k as f32)).fract();
                cs.min[k] + u * (cs.max[k] - cs.min[k])
            }))
        })
        .collect();
    let mut scratch = KernelScratch::new(lod);
    let mut kernel = ClipKernel::new(lod);
    let mut pose = vec![0.0f32; lod.p()];
    let last = lod.levels().len() - 1;
    let name = path
        .file_stem()
        .map_or("model".into(), |s| s.to_string_lossy().into_owned());
    let mut g = c.benchmark_group(format!("model_file/{name}"));
    for (case, detail) in [
        ("root_only", lod.root_only()),
        ("last_level_all_joints", Detail::new(last, lod.joints())),
        ("level0_all_joints", lod.full_detail()),
    ] {
        let mut i = 0;
        g.bench_function(BenchmarkId::new("build_kernel", case), |b| {
            b.iter(|| {
                i = (i + 1) % controls.len();
                lod.build_kernel(black_box(&controls[i]), detail, &mut scratch, &mut kernel)
                    .unwrap();
                black_box(kernel.duration())
            })
        });
        let mut i = 0;
        g.bench_function(BenchmarkId::new("kriging_weights", case), |b| {
            let level = lod.check_detail(detail).unwrap().accuracy;
            let lv = lod.levels()[level];
            b.iter(|| {
                i = (i + 1) % controls.len();
                let w = lod
                    .kriging_weights(black_box(&controls[i]), lv.key, lv.ranks.s, &mut scratch)
                    .unwrap();
                black_box(w[0])
            })
        });
        lod.build_kernel(&controls[0], detail, &mut scratch, &mut kernel)
            .unwrap();
        let rows = if detail.active_joints == 0 {
            7
        } else {
            lod.p()
        };
        let mut phase = 0.0f32;
        g.bench_function(BenchmarkId::new("pose", case), |b| {
            b.iter(|| {
                phase = (phase + 0.37) % (lod.t() - 1) as f32;
                lod.pose_rows(&kernel, black_box(phase), &mut pose[..rows])
                    .unwrap();
                black_box(pose[0])
            })
        });
    }
    // Reading the runtime model from the file's bytes, as an engine, the C ABI and the browser
    // do: the framing and checksums, the decode, the array checks and the play check
    // (`RuntimeModel::check_played`: every accuracy level at the middle of the controls, every
    // aligned frame).
    let bytes = std::fs::read(&path).expect("MOTION_LOD_BENCH_MODEL reads");
    g.bench_function("read_runtime_model", |b| {
        b.iter(|| {
            let model = lod_policy::RuntimeModel::from_bytes(black_box(&bytes)).unwrap();
            black_box(model.lod().p())
        })
    });
    g.finish();
    for walkers in [2_000, 100_000] {
        root_only_crowd(c, &model, &name, walkers);
    }
}

/// One frame of `walkers` walkers held root only whatever their distance or visibility (ground
/// scene, 0.01 walkers per m², after a 1.5 s warm-up) on a one-thread pool: the per-walker cost of
/// a far or culled walker, clip builds at its cycle ends included.
fn root_only_crowd(c: &mut Criterion, model: &MotionModel, name: &str, walkers: usize) {
    let config = CrowdConfig {
        seed: 7,
        ..CrowdConfig::with_density(walkers, 0.01)
    };
    let source = LodSource::new(model);
    let root_only = model.lod().root_only();
    let policy = move |_: f32, _: bool, _: &ViewParams| root_only;
    let scene = Scene::Ground;
    let path = scene.path(config.field_size_m);
    let lens = scene.lens(Camera::default(), config.field_size_m);
    let dt = 1.0 / config.fps;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a one-thread pool");
    let mut g = c.benchmark_group(format!("model_file/{name}"));
    g.sample_size(20);
    g.throughput(Throughput::Elements(walkers as u64));
    let mut crowd = Crowd::new(&source, config).expect("the crowd builds");
    let mut stats = FrameStats::default();
    let mut f = 0u32;
    let mut step = || {
        let cam = path.camera_at(f as f32 * dt, &lens);
        crowd
            .step_into(&source, &policy, &cam, dt, &mut stats)
            .expect("a frame");
        f += 1;
        stats.kernels_built
    };
    for _ in 0..45 {
        pool.install(&mut step);
    }
    g.bench_function(
        BenchmarkId::new("crowd_root_only_one_thread", walkers),
        |b| b.iter(|| black_box(pool.install(&mut step))),
    );
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
