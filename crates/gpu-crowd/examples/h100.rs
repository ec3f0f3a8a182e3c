//! The device check of issue 32, for a machine with a GPU (an H100): milliseconds a frame for
//! 1,000,000 walkers at full detail and 10,000,000 under the distance policy (ground camera,
//! density 0.01), seams and the foot lock off as in the figures, and GPU memory a walker,
//! with the CPU crowd's figure for the first beside them (each GPU crowd timed by `step`, which
//! waits for every frame, then by `submit`, which keeps one frame in flight); then the second crowd again with the CPU
//! crowd's defaults, seams inertialized and feet locked at every level (last, so that a time limit
//! cuts it before the others).
//!
//! `cargo run --release -p gpu-crowd --example h100 -- [MODEL.mlod] [--full N] [--lod N] [--frames N]`
//! (without a model, the fixture model is built from `fixtures/`).

use std::time::Instant;

use crowd_sim::{Camera, Crowd, CrowdConfig, Scene};
use gpu_crowd::{Gpu, GpuCrowd, GpuOptions};
use lod_policy::{DistancePolicy, FullDetail, LevelPolicy};
use motion_lod::{LodSource, MotionModel};

fn arg(args: &[String], name: &str, default: usize) -> usize {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// Times `walkers` on the GPU and prints the row `GPU, {walkers} walkers, {label}: ...`.
#[allow(clippy::too_many_arguments)]
fn time_gpu(
    label: &str,
    gpu: &Gpu,
    model: &MotionModel,
    walkers: usize,
    policy: &dyn LevelPolicy,
    options: GpuOptions,
    frames: usize,
    seams_and_lock: bool,
) -> Result<(), Box<dyn std::error::Error>> {
    let levels = if seams_and_lock { usize::MAX } else { 0 };
    let config = CrowdConfig {
        seam_levels: levels,
        foot_lock_levels: levels,
        ..CrowdConfig::with_density(walkers, 0.01)
    };
    let mut crowd = GpuCrowd::new(gpu, model.runtime(), config, options)?;
    let field = crowd.config().field_size_m;
    let (path, lens) = (
        Scene::Ground.path(field),
        Scene::Ground.lens(Camera::default(), field),
    );
    let dt = 1.0 / config.fps;
    let mut ms = Vec::new();
    let mut last = None;
    for f in 0..30 + frames {
        let stats = crowd.step(policy, &path.camera_at(f as f32 * dt, &lens), dt)?;
        if f >= 30 {
            ms.push(stats.wall.as_secs_f64() * 1e3);
        }
        last = Some(stats);
    }
    // The same number of frames again through `submit` (one frame in flight, as an engine runs
    // it): the time between frames.
    let t = Instant::now();
    for f in 30 + frames..30 + 2 * frames {
        crowd.submit(policy, &path.camera_at(f as f32 * dt, &lens), dt)?;
    }
    crowd.finish()?;
    let pipelined = t.elapsed().as_secs_f64() * 1e3 / frames as f64;
    let mean = ms.iter().sum::<f64>() / ms.len() as f64;
    ms.sort_by(f64::total_cmp);
    let last = last.expect("a frame");
    let hist = &last.level_histogram;
    println!(
        "GPU, {walkers} walkers, {label}: {mean:.2} ms a frame (median {:.2}; through submit, \
         one frame in flight: {pipelined:.2}), {:.0} bytes a walker; last frame: {} with joints, \
         {} shown root only for want of a joint slot, {} clips built",
        ms[ms.len() / 2],
        crowd.gpu_bytes() as f64 / walkers as f64,
        hist[..hist.len() - 1]
            .iter()
            .map(|&c| u64::from(c))
            .sum::<u64>(),
        last.slot_faults,
        last.kernels_built
    );
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (full_n, lod_n, frames) = (
        arg(&args, "--full", 1_000_000),
        arg(&args, "--lod", 10_000_000),
        arg(&args, "--frames", 60),
    );
    let model = match args.first().filter(|a| !a.starts_with("--")) {
        Some(path) => MotionModel::load(std::path::Path::new(path))?,
        None => {
            let loaded = motion_lod::dataset::DataSpec::default()
                .load_with_default(motion_io::test_data::fixture_takes(), &|_, _| {})?;
            MotionModel::build(
                &loaded.training,
                &Default::default(),
                &motion_lod::progress::NoProgress,
            )?
        }
    };
    let gpu = Gpu::new()?;
    println!("adapter: {}", gpu.adapter_name());
    let lod = model.lod();
    time_gpu(
        "full detail",
        &gpu,
        &model,
        full_n,
        &FullDetail::for_model(lod),
        GpuOptions::default(),
        frames,
        false,
    )?;
    // Under the policy few walkers hold joints: 2% of them get a joint slot.
    let options = GpuOptions {
        joint_slots: Some((lod_n / 50).max(1)),
        ..GpuOptions::default()
    };
    time_gpu(
        "distance policy",
        &gpu,
        &model,
        lod_n,
        &DistancePolicy::for_model(lod),
        options,
        frames,
        false,
    )?;
    // The CPU crowd on the same machine, same scene, full detail (all threads).
    let source = LodSource::new(&model);
    let config = CrowdConfig {
        seam_levels: 0,
        foot_lock_levels: 0,
        ..CrowdConfig::with_density(full_n, 0.01)
    };
    let mut cpu = Crowd::new(&source, config)?;
    let field = cpu.config().field_size_m;
    let (path, lens) = (
        Scene::Ground.path(field),
        Scene::Ground.lens(Camera::default(), field),
    );
    let policy = FullDetail::for_model(lod);
    let dt = 1.0 / config.fps;
    let mut ms = Vec::new();
    for f in 0..10 + frames.min(20) {
        let t = Instant::now();
        cpu.step(&source, &policy, &path.camera_at(f as f32 * dt, &lens), dt)?;
        if f >= 10 {
            ms.push(t.elapsed().as_secs_f64() * 1e3);
        }
    }
    println!(
        "CPU ({} threads), {full_n} walkers, full detail: {:.1} ms a frame",
        rayon_threads(),
        ms.iter().sum::<f64>() / ms.len() as f64
    );
    drop(cpu);
    // The same crowd as the second with the CPU crowd's defaults: seams and the foot lock on.
    time_gpu(
        "distance policy, seams and foot lock on",
        &gpu,
        &model,
        lod_n,
        &DistancePolicy::for_model(lod),
        options,
        frames,
        true,
    )?;
    Ok(())
}

fn rayon_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}
