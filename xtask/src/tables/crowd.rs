//! Section 5.2: crowd frames per second (worst, mean, best) with the level-of-detail model and with
//! naive interpolation, at 100 walkers as in the paper and at larger crowds.
//!
//! Every crowd keeps the paper-scale density of the default crowd (100 walkers on a 100 m field,
//! 0.01 walkers per m²), the camera walks inside it ([`CameraPath::inside_crowd`]) and each frame
//! counts culling, clip kernels, poses and forward kinematics (`crowd_sim::StageTimings`), not
//! rendering. The first frame builds a clip for every walker at once; it is run as a warm-up and not
//! counted. The LOD crowd uses the paper's distance policy (section 5.1); the naive crowd blends the
//! raw samples with the kriging weights at full detail for every walker
//! ([`motion_lod::NaiveSource`]); the PCA crowd ([`motion_lod::PcaSource`], the paper's other
//! comparison) blends per-sample DOF coefficients and drops components with the same distance policy.

use std::time::Instant;

use anyhow::{Context, Result};
use crowd_sim::{
    Camera, CameraPath, ClipSource, Crowd, CrowdConfig, CrowdReport, Detail as CrowdDetail,
    DetailPolicy, FrameStats,
};
use lod_policy::{Detail, DistancePolicy, LevelPolicy, LodModel, ViewParams};
use motion_lod::progress::Progress;
use motion_lod::{Analysis, LodSource, MotionModel, NaiveSource, PcaSource};

/// Principal components of the PCA baseline at its first level (the paper: `R_P,max = 40`).
pub const PCA_RANK: usize = 40;

/// Walkers per square metre of every crowd (the default crowd: 100 walkers on 100 m x 100 m).
pub const DENSITY: f32 = 0.01;

/// One crowd size and how many frames to time at it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CrowdSize {
    /// Walkers.
    pub walkers: usize,
    /// Timed frames (after the warm-up frame).
    pub frames: usize,
}

/// The crowd sizes of a full run: 100 (the paper), 1k, 10k, 100k walkers, fewer frames for larger crowds.
pub fn full_sizes() -> Vec<CrowdSize> {
    vec![
        CrowdSize {
            walkers: 100,
            frames: 300,
        },
        CrowdSize {
            walkers: 1_000,
            frames: 150,
        },
        CrowdSize {
            walkers: 10_000,
            frames: 30,
        },
        CrowdSize {
            walkers: 100_000,
            frames: 5,
        },
    ]
}

/// The measurement of one crowd.
#[derive(Debug, Clone, PartialEq)]
pub struct CrowdRow {
    /// Walkers.
    pub walkers: usize,
    /// `lod`, `naive` or `pca`.
    pub source: &'static str,
    /// Frame rates and stage timings of the timed frames; `None` when the run was skipped.
    pub report: Option<CrowdReport>,
    /// Seconds of the warm-up frame (every walker builds its first clip).
    pub warmup_s: f64,
    /// Why the run was skipped, if it was.
    pub skipped: Option<String>,
}

/// The paper's distance policy over `model` as a crowd detail policy (root only: 0 active joints at the
/// coarsest level).
pub fn lod_policy_for(
    model: &LodModel,
) -> impl Fn(f32, bool, &Camera) -> CrowdDetail + Sync + use<> {
    let policy = DistancePolicy::for_model(model);
    let levels = model.levels().len();
    let joints = model.joints();
    move |d: f32, visible: bool, cam: &Camera| {
        let view = ViewParams {
            fov_y_radians: cam.fov_y,
            image_height_px: cam.image_height as f32,
        };
        let det = policy.detail(d, visible, &view);
        let accuracy = if det.accuracy == Detail::SMALLEST {
            levels - 1
        } else {
            det.accuracy.min(levels - 1)
        };
        CrowdDetail {
            accuracy,
            active_joints: det.active_joints.min(joints),
        }
    }
}

/// Runs one crowd: a warm-up frame, then `frames` timed frames.
fn run_one<S: ClipSource, P: DetailPolicy>(
    source: &S,
    policy: &P,
    size: CrowdSize,
) -> Result<(CrowdReport, f64)> {
    let config = CrowdConfig::with_density(size.walkers, DENSITY);
    let mut crowd = Crowd::new(source, config).context("creating the crowd")?;
    let path = CameraPath::inside_crowd(config.field_size_m);
    let lens = Camera::default();
    let dt = 1.0 / config.fps;
    let mut stats = FrameStats::default();
    let t0 = Instant::now();
    crowd
        .step_into(source, policy, &path.camera_at(0.0, &lens), dt, &mut stats)
        .context("warm-up frame")?;
    let warmup_s = t0.elapsed().as_secs_f64();
    let mut report = CrowdReport::new();
    for f in 1..=size.frames {
        let cam = path.camera_at(f as f32 * dt, &lens);
        crowd
            .step_into(source, policy, &cam, dt, &mut stats)
            .with_context(|| format!("frame {f}"))?;
        report.add(&stats);
    }
    Ok((report, warmup_s))
}

/// A run of `source` at `size`, or a skipped row when its warm-up frame is predicted (linearly in
/// walkers from this source's previous size, kept in `warmup_per_walker`) to exceed `max_warmup_s`.
fn timed_or_skipped<S: ClipSource, P: DetailPolicy>(
    name: &'static str,
    source: &S,
    policy: &P,
    size: CrowdSize,
    max_warmup_s: f64,
    warmup_per_walker: &mut Option<f64>,
) -> Result<CrowdRow> {
    let predicted = warmup_per_walker.map(|w| w * size.walkers as f64);
    if let Some(p) = predicted.filter(|&p| p > max_warmup_s) {
        return Ok(CrowdRow {
            walkers: size.walkers,
            source: name,
            report: None,
            warmup_s: f64::NAN,
            skipped: Some(format!(
                "not run: its first frame would take about {p:.0} s (measured per walker at the previous size)"
            )),
        });
    }
    let (report, warmup_s) = run_one(source, policy, size)
        .with_context(|| format!("{name} crowd of {} walkers", size.walkers))?;
    *warmup_per_walker = Some(warmup_s / size.walkers as f64);
    Ok(CrowdRow {
        walkers: size.walkers,
        source: name,
        report: Some(report),
        warmup_s,
        skipped: None,
    })
}

/// Measures every size with the LOD model, with naive interpolation (full detail) and with the PCA
/// baseline (the same distance policy, fewer components with distance). A baseline run whose warm-up
/// is predicted to exceed `max_warmup_s` is skipped and says so.
pub fn measure(
    model: &MotionModel,
    analysis: &Analysis,
    sizes: &[CrowdSize],
    max_warmup_s: f64,
    progress: &dyn Progress,
) -> Result<Vec<CrowdRow>> {
    let lod = LodSource::new(model);
    let naive = NaiveSource::new(model, analysis);
    let pca = PcaSource::new(model, analysis, PCA_RANK).context("PCA baseline")?;
    let lod_policy = lod_policy_for(&model.lod);
    let joints = model.lod.joints();
    let full = move |_d: f32, _v: bool, _c: &Camera| CrowdDetail {
        accuracy: 0,
        active_joints: joints,
    };
    progress.stage("crowds (LOD, naive, PCA)", 3 * sizes.len() as u64);
    let mut rows = Vec::new();
    let (mut lod_warmup, mut naive_warmup, mut pca_warmup) = (None, None, None);
    for &size in sizes {
        rows.push(timed_or_skipped(
            "lod",
            &lod,
            &lod_policy,
            size,
            f64::INFINITY,
            &mut lod_warmup,
        )?);
        progress.inc(1);
        rows.push(timed_or_skipped(
            "naive",
            &naive,
            &full,
            size,
            max_warmup_s,
            &mut naive_warmup,
        )?);
        progress.inc(1);
        rows.push(timed_or_skipped(
            "pca",
            &pca,
            &lod_policy,
            size,
            max_warmup_s,
            &mut pca_warmup,
        )?);
        progress.inc(1);
    }
    Ok(rows)
}
