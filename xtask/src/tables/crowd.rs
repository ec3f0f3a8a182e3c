//! Section 5.2: crowd frame rates with the level-of-detail model and with the baselines, in two
//! scenes, with and without level of detail, on one and two threads.
//!
//! Every crowd keeps the paper-scale density of the default crowd (100 walkers on a 100 m field,
//! 0.01 walkers per m²) and each frame counts culling, clip kernels, poses and forward kinematics
//! (`crowd_sim::StageTimings`), not rendering. Two scenes ([`Scene`]): the camera walking inside the
//! crowd (*ground*: most walkers culled or beyond the last level) and circling above the field's edge
//! (*overview*: most of the crowd in view, at every level). A new crowd spreads its first clip builds
//! over its first cycle, so the first [`WARMUP_S`] seconds are a warm-up, timed apart (its slowest
//! frame is reported).
//!
//! Sources, each under two policies:
//! - *LOD policy* (fair): the paper's distance policy for all three sources, the same culling, the same
//!   root-only walkers and the same joint counts; the model ([`motion_lod::LodSource`]) also drops to
//!   smaller cores with distance, PCA ([`motion_lod::PcaSource`]) to fewer components, naive
//!   ([`motion_lod::NaiveSource`]) blends the raw samples whatever the distance. Both baselines use the
//!   `O(S D)` dual form of kriging.
//! - *no level of detail*: every walker at full detail (all joints, finest level), visible or not.
//!
//! Frame times ([`measure_frame_times`]): the model under its policy at 100,000 and 1,000,000 walkers
//! on each thread count, the median, 99th percentile and slowest of 150 frames after the warm-up, and
//! the clip builds per frame, beside the same number of frames of fixed work of the same length on
//! the same pool ([`fixed_work_times`]): the spread the machine gives any frame.

use std::time::Instant;

use anyhow::{Context, Result};
use crowd_sim::{
    Camera, ClipSource, Crowd, CrowdConfig, CrowdReport, Culling, FrameStats, FrameTimes, Scene,
};
use lod_policy::{DistancePolicy, FullDetail, LevelPolicy, ViewParams};
use motion_lod::progress::Progress;
use motion_lod::{Analysis, LodSource, MotionModel, NaiveSource, PcaSource};

/// Principal components of the PCA baseline at its first level (the paper: `R_P,max = 40`).
pub const PCA_RANK: usize = 40;

/// Walkers per square metre of every crowd (the default crowd: 100 walkers on 100 m x 100 m).
pub const DENSITY: f32 = 0.01;

/// Seconds of warm-up before the timed frames: longer than any cycle, so that the first clip builds,
/// spread over the first cycle, are done.
pub const WARMUP_S: f32 = 1.5;

/// One crowd size and how many frames to time at it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CrowdSize {
    /// Walkers.
    pub walkers: usize,
    /// Timed frames (after the warm-up).
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
            frames: 60,
        },
        CrowdSize {
            walkers: 100_000,
            frames: 20,
        },
    ]
}

/// The crowd sizes whose frame times are measured ([`measure_frame_times`]): 100,000 and 1,000,000
/// walkers, [`FRAME_TIME_FRAMES`] timed frames each.
pub fn frame_time_sizes() -> Vec<CrowdSize> {
    [100_000, 1_000_000]
        .map(|walkers| CrowdSize {
            walkers,
            frames: FRAME_TIME_FRAMES,
        })
        .to_vec()
}

/// Timed frames of each frame-time run: enough for a 99th percentile that is not the worst frame.
pub const FRAME_TIME_FRAMES: usize = 150;

/// The frame-time goal: the slowest timed frame at most this many times the median.
pub const WORST_OVER_MEDIAN_GOAL: f64 = 1.5;

/// Frame times of the model under the LOD policy at one size, scene and thread count.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameTimeRow {
    /// Camera scene.
    pub scene: Scene,
    /// Walkers.
    pub walkers: usize,
    /// Rayon threads.
    pub threads: usize,
    /// Median, 99th percentile and worst of the timed frames (after [`WARMUP_S`]).
    pub times: FrameTimes,
    /// Clip kernels built per timed frame: median and most (no frame rebuilds a burst).
    pub builds_median: usize,
    /// The most clip kernels one timed frame built.
    pub builds_max: usize,
    /// The same number of frames of fixed work on the same pool, sized to this row's median
    /// ([`fixed_work_times`]), run right after it: the spread the machine itself gives a frame of
    /// that length.
    pub fixed_work: FrameTimes,
}

/// Frame times of the model under the distance policy at each of `sizes`, in both scenes, on each of
/// `threads`: the median, 99th percentile and slowest frame after the warm-up, and the clip builds per
/// frame (issue 35's smooth-frames goal: the slowest frame at most [`WORST_OVER_MEDIAN_GOAL`] times
/// the median).
pub fn measure_frame_times(
    model: &MotionModel,
    sizes: &[CrowdSize],
    threads: &[usize],
    progress: &dyn Progress,
) -> Result<Vec<FrameTimeRow>> {
    let lod = LodSource::new(model);
    let policy = DistancePolicy::for_model(model.lod());
    progress.stage(
        "frame times (the model under its policy; 2 scenes; sizes; threads)",
        (Scene::ALL.len() * sizes.len() * threads.len()) as u64,
    );
    let mut rows = Vec::new();
    for &size in sizes {
        for scene in Scene::ALL {
            for &t in threads {
                let run =
                    run_on(t, &lod, &policy, scene, Culling::Scan, size).with_context(|| {
                        format!(
                            "frame times of {} walkers ({}, {t} threads)",
                            size.walkers,
                            scene.name()
                        )
                    })?;
                let times = run.report.frame_times(0).context("no timed frame")?;
                let fixed_work = fixed_work_times(t, times.p50_ms, size.frames)?;
                let mut builds = run.builds;
                builds.sort_unstable();
                rows.push(FrameTimeRow {
                    scene,
                    walkers: size.walkers,
                    threads: t,
                    times,
                    builds_median: builds[(builds.len() - 1) / 2],
                    builds_max: builds.last().copied().unwrap_or(0),
                    fixed_work,
                });
                progress.inc(1);
            }
        }
    }
    Ok(rows)
}

/// Tasks of [`fixed_work_times`]'s calibration frame.
const FIXED_WORK_TASKS: usize = 256;

/// One task of fixed work: [`FIXED_WORK_ROUNDS`] rounds of multiply-adds over 64 doubles on the
/// stack (in the first-level cache: no memory traffic, no allocation, no lock), about 20 µs.
fn fixed_task(seed: usize) -> f64 {
    let mut v = [0.0f64; 64];
    for (i, x) in v.iter_mut().enumerate() {
        *x = (seed * 64 + i) as f64 * 1e-6;
    }
    for round in 0..FIXED_WORK_ROUNDS {
        let c = 1e-9 * round as f64;
        for x in &mut v {
            *x = *x * 0.999_999 + c;
        }
    }
    v.iter().sum()
}

/// Rounds of one [`fixed_task`].
const FIXED_WORK_ROUNDS: usize = 2_000;

/// Times of one frame of `tasks` [`fixed_task`]s spread over the current pool the way the crowd
/// spreads its chunks of walkers (rayon's work stealing), seconds.
fn fixed_work_frame(tasks: usize) -> f64 {
    use rayon::prelude::*;
    let t0 = Instant::now();
    let sum: f64 = (0..tasks).into_par_iter().map(fixed_task).sum();
    std::hint::black_box(sum);
    t0.elapsed().as_secs_f64()
}

/// The machine's own frame-time spread at a frame of `median_ms` on a pool of `threads`: `frames`
/// frames of the same fixed work (equal tasks of arithmetic in the first-level cache, spread over
/// the pool by work stealing as the crowd's chunks are), sized so that a frame takes about
/// `median_ms`, after ten untimed frames. Every frame does the same operations, so a slow one is the
/// machine (another process, the hypervisor, the clock), not the work: a crowd's slowest frame over
/// its median can be read against this one's.
pub fn fixed_work_times(threads: usize, median_ms: f64, frames: usize) -> Result<FrameTimes> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .context("thread pool")?
        .install(|| {
            // Calibration: the median of nine frames of FIXED_WORK_TASKS tasks.
            let mut probe: Vec<f64> = (0..9).map(|_| fixed_work_frame(FIXED_WORK_TASKS)).collect();
            probe.sort_by(f64::total_cmp);
            let per_task_ms = probe[4] * 1e3 / FIXED_WORK_TASKS as f64;
            let tasks = ((median_ms / per_task_ms).round() as usize).max(threads);
            for _ in 0..10 {
                fixed_work_frame(tasks);
            }
            let seconds: Vec<f64> = (0..frames).map(|_| fixed_work_frame(tasks)).collect();
            FrameTimes::of_seconds(&seconds).context("no fixed-work frame")
        })
}

/// Which detail policy a run used.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PolicyKind {
    /// The paper's distance policy (culling, root only beyond the last level, fewer joints).
    Lod,
    /// Every walker at full detail.
    Full,
    /// Every walker root only whatever its distance or visibility: the cost of a far or culled
    /// walker (issue 16's first deliverable), run on one thread in the ground scene.
    RootOnly,
    /// The distance policy with walkers that have joints held to accuracy levels `0..=k` (finer
    /// than the policy's choice where it is coarser; root-only walkers as the policy gives them):
    /// `k = 0` is the policy with level 0 and root only, each larger `k` one more level, so the
    /// frame rates side by side are what each level saves.
    UpToLevel(usize),
}

impl PolicyKind {
    /// The policy's name in the tables.
    pub fn label(self) -> String {
        match self {
            PolicyKind::Lod => "LOD".into(),
            PolicyKind::Full => "no LOD".into(),
            PolicyKind::RootOnly => "root only".into(),
            PolicyKind::UpToLevel(0) => "LOD, level 0 and root only".into(),
            PolicyKind::UpToLevel(k) => format!("LOD, levels 0-{k} and root only"),
        }
    }
}

/// The measurement of one crowd.
#[derive(Debug, Clone, PartialEq)]
pub struct CrowdRow {
    /// Camera scene.
    pub scene: Scene,
    /// Walkers.
    pub walkers: usize,
    /// `lod`, `naive` or `pca`.
    pub source: &'static str,
    /// Detail policy.
    pub policy: PolicyKind,
    /// Rayon threads.
    pub threads: usize,
    /// How the crowd found the walkers in view.
    pub culling: Culling,
    /// Frame rates and stage timings of the timed frames; `None` when the run was skipped.
    pub report: Option<CrowdReport>,
    /// Seconds of the warm-up ([`WARMUP_S`] of simulated time).
    pub warmup_s: f64,
    /// Slowest warm-up frame (s).
    pub warmup_worst_s: f64,
    /// Why the run was skipped, if it was.
    pub skipped: Option<String>,
}

impl CrowdRow {
    /// Mean frames per second, if run.
    pub fn fps(&self) -> Option<f64> {
        self.report.as_ref().map(|r| r.fps_mean)
    }

    /// Walkers animated per second per thread (walkers x mean fps / threads), if run.
    pub fn walkers_per_thread_s(&self) -> Option<f64> {
        self.fps()
            .map(|f| self.walkers as f64 * f / self.threads.max(1) as f64)
    }

    /// The policy's name, with the culling when it is not the default scan.
    pub fn label(&self) -> String {
        match self.culling {
            Culling::Scan => self.policy.label(),
            Culling::Tree => format!("{}, tree culling", self.policy.label()),
        }
    }

    /// Thread time per walker and frame (ns): the inverse of [`CrowdRow::walkers_per_thread_s`].
    pub fn ns_per_walker_frame(&self) -> Option<f64> {
        self.walkers_per_thread_s().map(|w| 1e9 / w)
    }
}

/// What [`run_one`] measured.
struct Timed {
    /// Frame rates and stage timings of the timed frames.
    report: CrowdReport,
    /// Seconds of the warm-up.
    warmup_s: f64,
    /// Its slowest frame (s).
    warmup_worst_s: f64,
    /// Clip kernels built in each timed frame.
    builds: Vec<usize>,
}

/// Runs one crowd: [`WARMUP_S`] of warm-up frames, then `frames` timed frames.
fn run_one<S: ClipSource, P: LevelPolicy + Sync>(
    source: &S,
    policy: &P,
    scene: Scene,
    culling: Culling,
    size: CrowdSize,
) -> Result<Timed> {
    let config = CrowdConfig {
        culling,
        ..CrowdConfig::with_density(size.walkers, DENSITY)
    };
    let mut crowd = Crowd::new(source, config).context("creating the crowd")?;
    let path = scene.path(config.field_size_m);
    let lens = scene.lens(Camera::default(), config.field_size_m);
    let dt = 1.0 / config.fps;
    let warmup = (WARMUP_S * config.fps).ceil() as usize;
    let mut stats = FrameStats::default();
    let (mut warmup_s, mut worst) = (0.0f64, 0.0f64);
    for f in 0..warmup {
        let t0 = Instant::now();
        crowd
            .step_into(
                source,
                policy,
                &path.camera_at(f as f32 * dt, &lens),
                dt,
                &mut stats,
            )
            .context("warm-up frame")?;
        let s = t0.elapsed().as_secs_f64();
        warmup_s += s;
        worst = worst.max(s);
    }
    let mut report = CrowdReport::with_frames(size.frames);
    let mut builds = Vec::with_capacity(size.frames);
    for f in warmup..warmup + size.frames {
        let cam = path.camera_at(f as f32 * dt, &lens);
        crowd
            .step_into(source, policy, &cam, dt, &mut stats)
            .with_context(|| format!("frame {f}"))?;
        report.add(&stats);
        builds.push(stats.kernels_built);
    }
    Ok(Timed {
        report,
        warmup_s,
        warmup_worst_s: worst,
        builds,
    })
}

/// [`run_one`] on a pool of `threads` threads.
fn run_on<S: ClipSource, P: LevelPolicy + Sync>(
    threads: usize,
    source: &S,
    policy: &P,
    scene: Scene,
    culling: Culling,
    size: CrowdSize,
) -> Result<Timed> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .context("thread pool")?
        .install(|| run_one(source, policy, scene, culling, size))
}

/// What one run is: scene, source, policy, threads.
#[derive(Debug, Clone, Copy)]
struct RunSpec {
    scene: Scene,
    source: &'static str,
    policy: PolicyKind,
    threads: usize,
    culling: Culling,
}

/// A run of `source` at `size`, or a skipped row when its warm-up is predicted (linearly in walkers
/// from this run kind's previous size, kept in `warmup_per_walker`) to exceed `max_warmup_s`.
fn timed_or_skipped<S: ClipSource, P: LevelPolicy + Sync>(
    spec: RunSpec,
    source: &S,
    policy: &P,
    size: CrowdSize,
    max_warmup_s: f64,
    warmup_per_walker: &mut Option<f64>,
) -> Result<CrowdRow> {
    let row = |report, warmup_s, warmup_worst_s, skipped| CrowdRow {
        scene: spec.scene,
        walkers: size.walkers,
        source: spec.source,
        policy: spec.policy,
        threads: spec.threads,
        culling: spec.culling,
        report,
        warmup_s,
        warmup_worst_s,
        skipped,
    };
    let predicted = warmup_per_walker.map(|w| w * size.walkers as f64);
    if let Some(p) = predicted.filter(|&p| p > max_warmup_s) {
        return Ok(row(
            None,
            f64::NAN,
            f64::NAN,
            Some(format!(
                "not run: its warm-up would take about {p:.0} s (measured per walker at the previous size)"
            )),
        ));
    }
    let run = run_on(spec.threads, source, policy, spec.scene, spec.culling, size).with_context(
        || {
            format!(
                "{} crowd of {} walkers ({}, {} threads)",
                spec.source,
                size.walkers,
                spec.scene.name(),
                spec.threads
            )
        },
    )?;
    *warmup_per_walker = Some(run.warmup_s / size.walkers as f64);
    Ok(row(
        Some(run.report),
        run.warmup_s,
        run.warmup_worst_s,
        None,
    ))
}

/// Timed frames (at least) of each run that holds the policy to levels `0..=k`
/// ([`PolicyKind::UpToLevel`]).
pub const CAPPED_FRAMES: usize = 150;

/// Threads of the main runs (this machine's two cores).
pub const MAIN_THREADS: usize = 2;

/// Measures, in both scenes and at every size: the three sources under the LOD policy and at full
/// detail on [`MAIN_THREADS`] threads, and the model under the LOD policy on each of `threads`
/// (its walkers per second per thread), and, in the ground scene at the largest size, the model with
/// every walker root only on one thread ([`PolicyKind::RootOnly`]) and the model under the LOD
/// policy with the culling tree ([`Culling::Tree`]) instead of the scan. A baseline or full-detail run
/// whose warm-up is predicted to exceed `max_warmup_s` is skipped and says so.
pub fn measure(
    model: &MotionModel,
    analysis: &Analysis,
    sizes: &[CrowdSize],
    threads: &[usize],
    max_warmup_s: f64,
    progress: &dyn Progress,
) -> Result<Vec<CrowdRow>> {
    let lod = LodSource::new(model);
    let naive = NaiveSource::new(model, analysis).context("naive baseline")?;
    let pca = PcaSource::new(model, analysis, PCA_RANK).context("PCA baseline")?;
    let lod_policy = DistancePolicy::for_model(model.lod());
    let full = FullDetail::for_model(model.lod());
    let runs_per_size = 6 + threads.iter().filter(|&&t| t != MAIN_THREADS).count();
    let used_levels = (0..model.lod().levels().len())
        .filter(|&l| model.lod().level_serves_joints(l))
        .count();
    progress.stage(
        "crowds (2 scenes; LOD, naive, PCA; LOD policy and full detail; threads; levels)",
        (Scene::ALL.len() * (sizes.len() * runs_per_size + used_levels) + 2) as u64,
    );
    let mut rows = Vec::new();
    for scene in Scene::ALL {
        // Warm-up per walker of each run kind, for skipping: [source][policy].
        let mut warm = [[None; 2]; 3];
        let mut warm_threads = vec![None; threads.len()];
        for &size in sizes {
            for (p, policy) in [PolicyKind::Lod, PolicyKind::Full].into_iter().enumerate() {
                for (k, name) in ["lod", "pca", "naive"].into_iter().enumerate() {
                    let spec = RunSpec {
                        scene,
                        source: name,
                        policy,
                        threads: MAIN_THREADS,
                        culling: Culling::Scan,
                    };
                    // The model under its own policy is always run (it is what the tables are about).
                    let limit = if (k, p) == (0, 0) {
                        f64::INFINITY
                    } else {
                        max_warmup_s
                    };
                    let w = &mut warm[k][p];
                    let row = match (k, policy == PolicyKind::Lod) {
                        (0, true) => timed_or_skipped(spec, &lod, &lod_policy, size, limit, w),
                        (0, false) => timed_or_skipped(spec, &lod, &full, size, limit, w),
                        (1, true) => timed_or_skipped(spec, &pca, &lod_policy, size, limit, w),
                        (1, false) => timed_or_skipped(spec, &pca, &full, size, limit, w),
                        (_, true) => timed_or_skipped(spec, &naive, &lod_policy, size, limit, w),
                        (_, false) => timed_or_skipped(spec, &naive, &full, size, limit, w),
                    }?;
                    rows.push(row);
                    progress.inc(1);
                }
            }
            for (i, &t) in threads.iter().enumerate() {
                if t == MAIN_THREADS {
                    continue;
                }
                let spec = RunSpec {
                    scene,
                    source: "lod",
                    policy: PolicyKind::Lod,
                    threads: t,
                    culling: Culling::Scan,
                };
                rows.push(timed_or_skipped(
                    spec,
                    &lod,
                    &lod_policy,
                    size,
                    max_warmup_s,
                    &mut warm_threads[i],
                )?);
                progress.inc(1);
            }
        }
    }
    if let Some(&size) = sizes.iter().max_by_key(|s| s.walkers) {
        // What each accuracy level saves: the policy held to levels 0..=k, for every level it uses.
        let used: Vec<usize> = (0..model.lod().levels().len())
            .filter(|&l| model.lod().level_serves_joints(l))
            .collect();
        for scene in Scene::ALL {
            for &k in &used {
                let spec = RunSpec {
                    scene,
                    source: "lod",
                    policy: PolicyKind::UpToLevel(k),
                    threads: MAIN_THREADS,
                    culling: Culling::Scan,
                };
                let capped = |d: f32, visible: bool, view: &ViewParams| {
                    let detail = lod_policy.detail(d, visible, view);
                    if detail.active_joints == 0 {
                        detail
                    } else {
                        lod_policy::Detail::new(detail.accuracy.min(k), detail.active_joints)
                    }
                };
                // The differences are a few percent: time more frames than the size's default.
                let long = CrowdSize {
                    frames: size.frames.max(CAPPED_FRAMES),
                    ..size
                };
                let mut warm = None;
                rows.push(timed_or_skipped(
                    spec,
                    &lod,
                    &capped,
                    long,
                    f64::INFINITY,
                    &mut warm,
                )?);
                progress.inc(1);
            }
        }
        let spec = RunSpec {
            scene: Scene::Ground,
            source: "lod",
            policy: PolicyKind::RootOnly,
            threads: 1,
            culling: Culling::Scan,
        };
        let root = model.lod().root_only();
        let root_only = move |_: f32, _: bool, _: &ViewParams| root;
        let mut warm = None;
        rows.push(timed_or_skipped(
            spec,
            &lod,
            &root_only,
            size,
            f64::INFINITY,
            &mut warm,
        )?);
        progress.inc(1);
        let spec = RunSpec {
            policy: PolicyKind::Lod,
            threads: MAIN_THREADS,
            culling: Culling::Tree,
            ..spec
        };
        let mut warm = None;
        rows.push(timed_or_skipped(
            spec,
            &lod,
            &lod_policy,
            size,
            f64::INFINITY,
            &mut warm,
        )?);
        progress.inc(1);
    }
    Ok(rows)
}

/// The row of `source` under `policy` on [`MAIN_THREADS`] threads for `scene` and `walkers`.
pub fn find<'a>(
    rows: &'a [CrowdRow],
    scene: Scene,
    walkers: usize,
    source: &str,
    policy: PolicyKind,
) -> Option<&'a CrowdRow> {
    rows.iter().find(|r| {
        r.scene == scene
            && r.walkers == walkers
            && r.source == source
            && r.policy == policy
            && r.threads == MAIN_THREADS
            && r.culling == Culling::Scan
    })
}

/// Mean frame-time of `a` over that of `b` inverted: `fps(a) / fps(b)`, when both ran.
pub fn ratio(a: Option<&CrowdRow>, b: Option<&CrowdRow>) -> Option<f64> {
    Some(a?.fps()? / b?.fps()?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_work_frames_are_timed_on_the_pool_asked_for() {
        for threads in [1, 2] {
            let t = fixed_work_times(threads, 1.0, 7).unwrap();
            assert_eq!(t.frames, 7);
            assert!(t.p50_ms > 0.0 && t.p50_ms <= t.p99_ms && t.p99_ms <= t.worst_ms);
        }
        // The work is arithmetic that depends on its task: it cannot be folded away.
        assert_ne!(fixed_task(0), fixed_task(1));
    }
}
