//! Benchmarks with the REAL model built from the embedded fixtures (paper defaults): clip kernels and
//! per-frame poses at the first and last accuracy levels, forward kinematics of the model's skeleton,
//! and one crowd frame (cull + kernels + poses + FK) of 1k walkers in both scenes (ground and
//! overview cameras) with the model's `LodSource` under the paper's distance policy, with the PCA
//! baseline (40 components, fewer per level) and the naive source under the same policy (the fair
//! comparison), and with the naive source at full detail (no level of detail).

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use crowd_sim::{Camera, ClipSource, Crowd, CrowdConfig, FrameStats, Scene};
use glam::Vec3;
use lod_policy::{ClipKernel, Detail, DistancePolicy, FullDetail, KernelScratch, LevelPolicy};
use motion_lod::dataset::DataSpec;
use motion_lod::progress::NoProgress;
use motion_lod::{Analysis, BuildConfig, LodSource, MotionModel, NaiveSource, PcaSource};

/// Walkers per square metre (the default crowd's density: 100 on a 100 m field).
const DENSITY: f32 = 0.01;

fn model() -> (MotionModel, Analysis) {
    let data = DataSpec::default()
        .load_with_default(motion_io::test_data::fixture_takes(), &|_, _| {})
        .expect("embedded fixtures load");
    MotionModel::build_with_analysis(&data.training, &BuildConfig::default(), &NoProgress)
        .expect("model builds from the fixtures")
}

fn kernels_and_poses(c: &mut Criterion, model: &MotionModel, analysis: &Analysis) {
    let lod = model.lod();
    let controls: Vec<lod_policy::Controls> = analysis
        .controls
        .iter()
        .step_by(4)
        .map(|&c| lod_policy::Controls::from_f64(c))
        .collect();
    let mut scratch = KernelScratch::new(lod);
    let mut kernel = ClipKernel::new(lod);
    let mut pose = vec![0.0f32; lod.p()];
    let last = lod.levels().len() - 1;
    let mut g = c.benchmark_group("model_fixtures");
    for (name, detail) in [
        ("level0_all_joints", lod.full_detail()),
        ("last_level_all_joints", Detail::new(last, lod.joints())),
        ("root_only", lod.root_only()),
    ] {
        let mut i = 0;
        g.bench_function(BenchmarkId::new("build_kernel", name), |b| {
            b.iter(|| {
                i = (i + 1) % controls.len();
                lod.build_kernel(black_box(&controls[i]), detail, &mut scratch, &mut kernel)
                    .unwrap();
                black_box(kernel.duration())
            })
        });
        lod.build_kernel(&controls[0], detail, &mut scratch, &mut kernel)
            .unwrap();
        let mut phase = 0.0f32;
        g.bench_function(BenchmarkId::new("pose", name), |b| {
            b.iter(|| {
                phase = (phase + 0.37) % (lod.t() - 1) as f32;
                lod.pose(&kernel, black_box(phase), &mut pose).unwrap();
                black_box(pose[0])
            })
        });
    }
    lod.build_kernel(&controls[0], lod.full_detail(), &mut scratch, &mut kernel)
        .unwrap();
    lod.pose(&kernel, 10.0, &mut pose).unwrap();
    let layout = &model.layout;
    let mut world = vec![Vec3::ZERO; layout.skeleton().joints.len()];
    g.bench_function("forward_kinematics_all_joints", |b| {
        b.iter(|| {
            layout.joint_positions(black_box(&pose), layout.joint_count(), &mut world);
            black_box(world[0])
        })
    });
    g.finish();
}

fn crowd_frame(c: &mut Criterion, model: &MotionModel, analysis: &Analysis) {
    let lod = model.lod();
    let lod_policy = DistancePolicy::for_model(lod);
    let full = FullDetail::for_model(lod);
    let walkers = 1_000;
    let config = CrowdConfig {
        seed: 7,
        ..CrowdConfig::with_density(walkers, DENSITY)
    };
    let mut g = c.benchmark_group("model_crowd_frame");
    g.sample_size(20);
    let source = LodSource::new(model);
    let pca = PcaSource::new(model, analysis, 40).expect("PCA basis of the fixtures");
    let naive = NaiveSource::new(model, analysis).expect("naive source of the fixtures");
    for scene in Scene::ALL {
        let id = |name: &str| BenchmarkId::new(format!("{}/{name}", scene.name()), walkers);
        frame(&mut g, id("lod"), &source, &lod_policy, scene, config);
        frame(&mut g, id("pca"), &pca, &lod_policy, scene, config);
        frame(&mut g, id("naive"), &naive, &lod_policy, scene, config);
        frame(&mut g, id("naive_no_lod"), &naive, &full, scene, config);
    }
    g.finish();
}

/// One crowd frame of `source` under `policy` in `scene`, after a 1.5 s warm-up.
fn frame<S: ClipSource, P: LevelPolicy + Sync>(
    g: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    id: BenchmarkId,
    source: &S,
    policy: &P,
    scene: Scene,
    config: CrowdConfig,
) {
    let path = scene.path(config.field_size_m);
    let lens = scene.lens(Camera::default(), config.field_size_m);
    let dt = 1.0 / config.fps;
    let mut crowd = Crowd::new(source, config).unwrap();
    for f in 0..45 {
        let cam = path.camera_at(f as f32 * dt, &lens);
        crowd.step(source, policy, &cam, dt).unwrap();
    }
    let mut f = 45u32;
    let mut stats = FrameStats::default();
    g.bench_function(id, |b| {
        b.iter(|| {
            let cam = path.camera_at(f as f32 * dt, &lens);
            crowd
                .step_into(source, policy, &cam, dt, &mut stats)
                .unwrap();
            f += 1;
            black_box(stats.visible)
        })
    });
}

fn bench(c: &mut Criterion) {
    let (model, analysis) = model();
    kernels_and_poses(c, &model, &analysis);
    crowd_frame(c, &model, &analysis);
}

criterion_group!(benches, bench);
criterion_main!(benches);
