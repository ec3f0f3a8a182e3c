//! The GPU crowd's row of section 4 (`cargo xtask tables` built with `--features gpu`): 10,000
//! walkers under the distance policy on the ground camera, timed on whatever adapter there is and
//! named (Mesa's lavapipe runs on the CPU: its figure says nothing about a GPU).

use motion_lod::MotionModel;

/// Walkers, frames and density of the row.
const WALKERS: usize = 10_000;
const FRAMES: usize = 90;
const DENSITY: f32 = 0.01;

/// The row as Markdown: the adapter and the mean and median frame times, or why there is none.
pub fn section(model: &MotionModel) -> String {
    let head = format!(
        "\n### GPU crowd (`gpu-crowd`, wgpu compute shaders)\n\n{WALKERS} walkers at {DENSITY} per m², \
         ground camera, distance policy, {FRAMES} frames after a 1 s warm-up; seams and foot lock off \
         (the GPU crowd inertializes seams and locks feet too, but this row is timed without). \
         A frame is the whole step: upload, compute, read-back of its counters.\n\n\
         | adapter | ms a frame (mean) | median | GPU memory a walker |\n|---|---:|---:|---:|\n"
    );
    format!("{head}{}\n", row(model))
}

#[cfg(feature = "gpu")]
fn row(model: &MotionModel) -> String {
    use crowd_sim::{Camera, CrowdConfig, Scene};
    use gpu_crowd::{Gpu, GpuCrowd, GpuError, GpuOptions};
    use lod_policy::DistancePolicy;
    let gpu = match Gpu::new() {
        Ok(g) => g,
        Err(GpuError::NoAdapter { .. }) => return "| no adapter | - | - | - |".into(),
        Err(e) => return format!("| no device: {e} | - | - | - |"),
    };
    let config = CrowdConfig {
        seam_levels: 0,
        foot_lock_levels: 0,
        ..CrowdConfig::with_density(WALKERS, DENSITY)
    };
    let run = || -> Result<(f64, f64, f64), GpuError> {
        let mut crowd = GpuCrowd::new(&gpu, model.runtime(), config, GpuOptions::default())?;
        let field = crowd.config().field_size_m;
        let (path, lens) = (
            Scene::Ground.path(field),
            Scene::Ground.lens(Camera::default(), field),
        );
        let policy = DistancePolicy::for_model(model.lod());
        let dt = 1.0 / config.fps;
        let warmup = config.fps.round() as usize;
        let mut ms = Vec::new();
        for f in 0..warmup + FRAMES {
            let stats = crowd.step(&policy, &path.camera_at(f as f32 * dt, &lens), dt)?;
            if f >= warmup {
                ms.push(stats.wall.as_secs_f64() * 1e3);
            }
        }
        let mean = ms.iter().sum::<f64>() / ms.len() as f64;
        ms.sort_by(f64::total_cmp);
        Ok((
            mean,
            ms[ms.len() / 2],
            crowd.gpu_bytes() as f64 / WALKERS as f64,
        ))
    };
    match run() {
        Ok((mean, median, bytes)) => format!(
            "| {} | {mean:.2} | {median:.2} | {bytes:.0} B |",
            gpu.adapter_name()
        ),
        Err(e) => format!("| {}: {e} | - | - | - |", gpu.adapter_name()),
    }
}

#[cfg(not(feature = "gpu"))]
fn row(_model: &MotionModel) -> String {
    "| not built: run `cargo run --release -p xtask --features gpu -- tables` | - | - | - |".into()
}
