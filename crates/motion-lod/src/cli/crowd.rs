//! `motion-lod crowd [MODEL] --walkers N --seconds S`: a crowd animated by the model, timed, optionally
//! rendered and compared with naive interpolation and with the PCA baseline.

use std::path::PathBuf;

use anyhow::{Context as _, bail};
use clap::{Args, ValueEnum};
use crowd_sim::{Camera, ClipSource, CrowdConfig, CrowdReport, CrowdStyle, Culling, Scene};
use lod_policy::{DistancePolicy, FullDetail, LodModel, ScreenSpacePolicy};
use motion_lod::build::Analysis;
use motion_lod::crowd::{CrowdOutcome, CrowdRun, check_render_dir, run_crowd};
use motion_lod::gltf::crowd::{CrowdClip, export_crowd};
use motion_lod::progress::NoProgress;
use motion_lod::{LodSource, MotionModel, NaiveSource, PcaSource};
use serde::Serialize;

use super::data::load;
use motion_lod::style::parse_style_mix;

/// Level-of-detail policy.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum PolicyArg {
    /// The paper's distance schedule (30 m, 50 m per key level, one joint fewer per 10 m).
    Distance,
    /// The cheapest level whose measured error projects under the pixel budget.
    Screen,
}

/// Where the camera is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum CameraArg {
    /// Walking at eye height inside the crowd (most walkers culled or root only).
    Ground,
    /// Circling above the field's edge, most of the crowd in view at every level.
    Overview,
}

impl From<CameraArg> for Scene {
    fn from(c: CameraArg) -> Scene {
        match c {
            CameraArg::Ground => Scene::Ground,
            CameraArg::Overview => Scene::Overview,
        }
    }
}

/// How the walkers in view are found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum CullingArg {
    /// Every walker's box tested against the frustum in the frame's parallel pass.
    Scan,
    /// An AABB tree over the boxes, refitted every frame and queried with the frustum.
    Tree,
}

impl From<CullingArg> for Culling {
    fn from(c: CullingArg) -> Culling {
        match c {
            CullingArg::Scan => Culling::Scan,
            CullingArg::Tree => Culling::Tree,
        }
    }
}

/// Arguments of `motion-lod crowd`.
#[derive(Debug, Args)]
pub struct CrowdArgs {
    /// The model file (default: a model built from the embedded data set).
    #[arg(value_name = "MODEL")]
    pub model: Option<PathBuf>,
    /// Number of walkers (1..=1000000).
    #[arg(long, default_value_t = 1000, value_parser = super::ranges::count(super::ranges::WALKERS))]
    pub walkers: usize,
    /// Simulated seconds (0.001 to 3600).
    #[arg(long, default_value_t = 10.0, value_parser = super::ranges::seconds)]
    pub seconds: f32,
    /// Walkers per square metre, sets the field size (0.000001 to 10).
    #[arg(long, default_value_t = 0.05, value_parser = super::ranges::density)]
    pub density: f32,
    /// Frames per second of the simulation (1 to 1000).
    #[arg(long, default_value_t = 30.0, value_parser = super::ranges::fps_f32)]
    pub fps: f32,
    /// Seed of the walkers' paths.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Level-of-detail policy.
    #[arg(long, value_enum, default_value_t = PolicyArg::Distance, conflicts_with = "no_lod")]
    pub policy: PolicyArg,
    /// Every walker at full detail, visible or not, with every source: no level of detail at all.
    #[arg(long)]
    pub no_lod: bool,
    /// Camera: `ground` walks inside the crowd, `overview` circles above it.
    #[arg(long, value_enum, default_value_t = CameraArg::Ground)]
    pub camera: CameraArg,
    /// Culling: `scan` tests every walker's box in the frame's pass, `tree` queries an AABB tree
    /// (the same walkers in view either way).
    #[arg(long, value_enum, default_value_t = CullingArg::Scan)]
    pub culling: CullingArg,
    /// Animate with naive interpolation instead of the model (the same culling, root-only walkers and
    /// joint counts; no cheaper accuracy level).
    #[arg(long, conflicts_with_all = ["compare_naive", "pca"])]
    pub naive: bool,
    /// Also run the naive source on the same crowd (same policy) and print the speed ratio.
    #[arg(long)]
    pub compare_naive: bool,
    /// Animate with the PCA baseline instead of the model (its components reduced per accuracy level
    /// under the same policy).
    #[arg(long, conflicts_with = "compare_pca")]
    pub pca: bool,
    /// Also run the PCA baseline on the same crowd (same policy) and print the speed ratio.
    #[arg(long)]
    pub compare_pca: bool,
    /// Principal components kept by the PCA baseline (the paper: 40; 1..=10000, at most P used).
    #[arg(long, default_value_t = 40, value_parser = super::ranges::count(super::ranges::PCA_RANK))]
    pub pca_rank: usize,
    /// Write PNG frames, top-down maps and a GIF here (created when missing); frames and maps
    /// an earlier run left there past this run's last (`frame_NNNNN.png`, `map_NNNNN.png`) are
    /// removed, no other file.
    #[arg(long, value_name = "DIR")]
    pub render: Option<PathBuf>,
    /// Render every n-th frame (1..=1000000).
    #[arg(long, default_value_t = 30, value_parser = super::ranges::count(super::ranges::RENDER_EVERY), requires = "render")]
    pub render_every: usize,
    /// Print one JSON line instead of the report.
    #[arg(long)]
    pub json: bool,
    /// The walkers' style, for a model built with style labels: by default each walker walks one
    /// of the model's styles, drawn with the data's shares (a crowd of the data's mix); a style
    /// name (`elderly`) or a blend (`elderly=0.5,youthful=0.5`; weights are scaled to sum to 1)
    /// gives every walker that style.
    #[arg(long, value_name = "STYLE")]
    pub style: Option<String>,
    /// Also write a short clip of this crowd as glTF 2.0 binary (`.glb`): one skinned character per
    /// exported walker, coloured by its level of detail (view it with `motion-lod view FILE`). The
    /// clip is the crowd seen from `--camera` (its levels and the walkers chosen follow that
    /// camera), under `--policy` (or full detail with `--no-lod`), animated by the model; every
    /// walker starts mid-stride at its detail.
    #[arg(long, value_name = "FILE.glb")]
    pub export: Option<PathBuf>,
    /// Walkers written by `--export`, spread evenly over their distance from the camera (1..=1000).
    #[arg(long, default_value_t = 24, value_parser = super::ranges::count((1, 1000)), requires = "export")]
    pub export_walkers: usize,
    /// Seconds recorded by `--export` (0.001 to 60).
    #[arg(long, default_value_t = 3.0, value_parser = super::ranges::export_seconds, requires = "export")]
    pub export_seconds: f32,
    /// Run the crowd on the GPU (crate `gpu-crowd`, wgpu compute shaders; Vulkan by default) and
    /// time its frames; needs a build with `--features gpu`. Seams are inertialized and feet locked
    /// as on the CPU (its defaults: at every level). With `--render`, frames are drawn on the GPU
    /// straight from the crowd's buffers (`gpu_crowd::Preview`; no top-down maps).
    #[arg(long, conflicts_with_all = ["naive", "pca", "compare_naive", "compare_pca", "export"])]
    pub gpu: bool,
    /// With `--gpu`: walkers that can hold joints at once (`gpu_crowd::GpuOptions::joint_slots`),
    /// a count (`20000`, up to 1000000) or a share of the walkers (`2%`, 0 to 100); the GPU
    /// allocates only these slots' clips, and when more walkers want joints the slots go to those
    /// in view nearest the camera, the others shown root only. Default: one a walker.
    #[arg(long, value_parser = super::ranges::joint_slots, requires = "gpu")]
    pub joint_slots: Option<super::ranges::JointSlots>,
}

#[derive(Debug, Serialize)]
struct Fps {
    worst: f64,
    mean: f64,
    best: f64,
}

impl From<&CrowdReport> for Fps {
    fn from(r: &CrowdReport) -> Fps {
        Fps {
            worst: r.fps_worst,
            mean: r.fps_mean,
            best: r.fps_best,
        }
    }
}

#[derive(Debug, Serialize)]
struct Summary {
    walkers: usize,
    frames: usize,
    fps: Fps,
    naive_fps: Option<Fps>,
    /// Mean frame rate of the main source over that of the naive source.
    ratio: Option<f64>,
    pca_fps: Option<Fps>,
    /// Mean frame rate of the main source over that of the PCA source.
    pca_ratio: Option<f64>,
    levels: Vec<u32>,
    /// Field size used, metres (enlarged when the model's turn range needs larger paths).
    field_m: f32,
    /// The field size asked for, when it was enlarged.
    field_enlarged_from: Option<f32>,
    /// Clips the main source failed to build over the run (the walkers kept their previous clips).
    clip_faults: u64,
    /// Frame times of the main source after the first second of simulated time (milliseconds):
    /// median, 99th percentile and worst; `None` when the run is not longer than a second.
    frame_ms: Option<FrameMs>,
}

/// Frame-time percentiles after the warm-up, milliseconds.
#[derive(Debug, Serialize)]
struct FrameMs {
    /// Simulated seconds left out at the start (the first cycle's clip builds).
    after_s: f64,
    /// Frames counted.
    frames: usize,
    p50: f64,
    p99: f64,
    worst: f64,
    /// Buffers the frame loop allocated over those frames (`crowd_sim::FrameStats::allocations`:
    /// clips, seam transitions and foot locks the crowd's stock made at a new peak of need).
    allocations: usize,
    /// Frames among those that allocated.
    allocating_frames: usize,
}

/// Simulated seconds a run's first frames are left out of its frame-time percentiles: the first
/// second, where every walker builds its first clips.
const WARMUP_S: f64 = 1.0;

/// The frame-time percentiles of `report` after [`WARMUP_S`] at `fps`.
fn frame_ms(report: &CrowdReport, fps: f32) -> Option<FrameMs> {
    let warmup = (WARMUP_S * f64::from(fps)).round() as usize;
    let (allocations, allocating_frames) = report.allocations(warmup);
    report.frame_times(warmup).map(|t| FrameMs {
        after_s: WARMUP_S,
        frames: t.frames,
        p50: t.p50_ms,
        p99: t.p99_ms,
        worst: t.worst_ms,
        allocations,
        allocating_frames,
    })
}

/// The model to animate and, when the naive or PCA source is needed, the analysis it was built from.
impl CrowdArgs {
    /// The policy's name as the report prints it.
    pub(super) fn policy_name(&self) -> &'static str {
        match (self.no_lod, self.policy) {
            (true, _) => "no level of detail",
            (false, PolicyArg::Distance) => "distance",
            (false, PolicyArg::Screen) => "screen-space",
        }
    }
}

/// The crowd's styles from `--style` (a name, a blend, or `data`; none: the data's mix).
pub(super) fn crowd_style(model: &MotionModel, style: Option<&str>) -> anyhow::Result<CrowdStyle> {
    Ok(match style {
        None => CrowdStyle::DataMix,
        Some(text) => match parse_style_mix(model.styles(), text)? {
            mix if mix.is_data_mix() => CrowdStyle::DataMix,
            mix => CrowdStyle::Each(mix),
        },
    })
}

/// The lens every crowd command times and renders with: 960 x 540 pixels, the default field of
/// view.
pub(super) fn view_lens() -> Camera {
    Camera {
        image_width: 960,
        image_height: 540,
        aspect: 960.0 / 540.0,
        ..Camera::default()
    }
}

pub(super) fn model_and_analysis(
    path: Option<&PathBuf>,
    need_analysis: bool,
    quiet: bool,
) -> anyhow::Result<(MotionModel, Option<Analysis>)> {
    let model = match path {
        Some(p) => MotionModel::load(p).with_context(|| format!("reading {}", p.display()))?,
        None => {
            let spec = motion_lod::dataset::DataSpec::default();
            let loaded = load(&spec, None, quiet)?;
            let config = motion_lod::BuildConfig::default();
            let (mut model, analysis) =
                MotionModel::build_with_analysis(&loaded.training, &config, &NoProgress)
                    .context("building the model from the embedded data")?;
            model.report.data = Some(spec);
            return Ok((model, need_analysis.then_some(analysis)));
        }
    };
    if !need_analysis {
        return Ok((model, None));
    }
    let spec = model.report.data.clone().context(
        "the model does not record its training data, which the naive and PCA sources need",
    )?;
    let style = model.style.as_ref().map(|s| s.spec.clone());
    let loaded = load(&spec, style.as_ref(), quiet)?;
    let analysis = Analysis::run_guarded(&loaded.training, &model.report.config, &NoProgress)
        .context("rebuilding the samples for the naive or PCA source")?;
    Ok((model, Some(analysis)))
}

/// Runs the subcommand.
pub fn run(args: CrowdArgs) -> anyhow::Result<()> {
    if args.walkers == 0 {
        bail!("--walkers must be at least 1");
    }
    if !(args.density.is_finite() && args.density > 0.0) {
        bail!("--density must be a positive number of walkers per square metre");
    }
    if let Some(dir) = &args.render {
        check_render_dir(dir).with_context(|| format!("render folder {}", dir.display()))?;
    }
    if args.pca_rank == 0 {
        bail!("--pca-rank must be at least 1");
    }
    if let Some(path) = &args.export {
        if super::build::suffix(path).as_deref() != Some("glb") {
            bail!(
                "--export {}: the clip is written as glTF binary; use a name ending in .glb",
                path.display()
            );
        }
        // Say now, not after the crowd has run, when the clip cannot be written where asked.
        super::build::check_writable(path).context("--export")?;
        if let Some(model) = &args.model {
            super::build::check_not_input(path, &[("the model", model.as_path())])
                .context("--export")?;
        }
    }
    if args.gpu {
        return super::gpu::run(&args);
    }
    let need_analysis = args.naive || args.compare_naive || args.pca || args.compare_pca;
    let (model, analysis) = model_and_analysis(args.model.as_ref(), need_analysis, args.json)?;
    let run = CrowdRun {
        config: CrowdConfig {
            seed: args.seed,
            fps: args.fps,
            culling: args.culling.into(),
            style: crowd_style(&model, args.style.as_deref())?,
            ..CrowdConfig::with_density(args.walkers, args.density)
        },
        seconds: args.seconds,
        lens: view_lens(),
        scene: args.camera.into(),
        render: args.render.clone().map(|d| (d, args.render_every)),
    };
    let lod = model.lod();
    let compare_run = CrowdRun {
        render: None,
        ..run.clone()
    };
    let full = args.no_lod;
    let main = if args.naive {
        let analysis = analysis.as_ref().context("naive source")?;
        let source = NaiveSource::new(&model, analysis).context("naive source")?;
        run_with_policy(&source, args.policy, full, lod, &run)?
    } else if args.pca {
        run_with_policy(
            &pca_source(&model, analysis.as_ref(), args.pca_rank)?,
            args.policy,
            full,
            lod,
            &run,
        )?
    } else {
        run_with_policy(&LodSource::new(&model), args.policy, full, lod, &run)?
    };
    let naive = match &analysis {
        Some(a) if args.compare_naive && !args.naive => {
            let source = NaiveSource::new(&model, a).context("naive source")?;
            Some(run_with_policy(
                &source,
                args.policy,
                full,
                lod,
                &compare_run,
            )?)
        }
        _ => None,
    };
    let pca = if args.compare_pca && !args.pca {
        let source = pca_source(&model, analysis.as_ref(), args.pca_rank)?;
        Some(run_with_policy(
            &source,
            args.policy,
            full,
            lod,
            &compare_run,
        )?)
    } else {
        None
    };
    let exported = match &args.export {
        Some(path) => Some(export_clip(&model, &args, &run, path)?),
        None => None,
    };
    let ratio_to = |other: &CrowdOutcome| main.report.fps_mean / other.report.fps_mean.max(1e-12);
    let ratio = naive.as_ref().map(ratio_to);
    let pca_ratio = pca.as_ref().map(ratio_to);
    if args.json {
        let summary = Summary {
            field_m: main.field_m,
            field_enlarged_from: main.field_enlarged_from,
            walkers: args.walkers,
            frames: main.report.frames,
            fps: Fps::from(&main.report),
            naive_fps: naive.as_ref().map(|n| Fps::from(&n.report)),
            ratio,
            pca_fps: pca.as_ref().map(|n| Fps::from(&n.report)),
            pca_ratio,
            levels: main.last.level_histogram.clone(),
            clip_faults: main.report.clip_faults,
            frame_ms: frame_ms(&main.report, args.fps),
        };
        out!("{}", serde_json::to_string(&summary)?);
        if let Some(msg) = exported {
            eprintln!("{msg}");
        }
        return Ok(());
    }
    let (source_name, short) = if args.naive {
        ("naive interpolation", "naive")
    } else if args.pca {
        ("PCA baseline (components per accuracy level)", "PCA")
    } else {
        ("multilinear LOD", "LOD")
    };
    out!(
        "{} walkers, {} s at {} fps ({} frames), {source_name}, field {:.0} m",
        args.walkers,
        args.seconds,
        args.fps,
        main.report.frames,
        main.field_m
    );
    out!(
        "scene: camera {}, {} walkers per square metre, seed {}, {} policy; every frame timed from \
         the first (clip builds of the first cycle included); `cargo xtask tables` (section 4) times \
         another scene: density 0.01 after a warm-up",
        match args.camera {
            CameraArg::Ground => "on the ground inside the crowd",
            CameraArg::Overview => "circling above the field",
        },
        args.density,
        args.seed,
        args.policy_name()
    );
    if let Some(from) = main.field_enlarged_from {
        out!(
            "note: the model turns little per cycle, so its walkers need paths of large radius: \
             field enlarged from {from:.0} m to {:.0} m",
            main.field_m
        );
    }
    out!("{}", main.report);
    if let Some(t) = frame_ms(&main.report, args.fps) {
        out!(
            "frame times after the first {WARMUP_S} s ({} frames): median {:.2} ms, p99 {:.2} ms, \
             worst {:.2} ms ({:.2}x the median); buffers allocated: {} in {} frames",
            t.frames,
            t.p50,
            t.p99,
            t.worst,
            t.worst / t.p50.max(1e-12),
            t.allocations,
            t.allocating_frames
        );
    }
    out!(
        "levels in the last frame (accuracy 0.., then root only): {:?}",
        main.last.level_histogram
    );
    if let (Some(n), Some(r)) = (&naive, ratio) {
        out!("naive interpolation on the same crowd (same policy):");
        out!("{}", n.report);
        out!("{short} / naive mean frame rate: {r:.2}x");
    }
    if let (Some(n), Some(r)) = (&pca, pca_ratio) {
        out!("PCA baseline on the same crowd (same policy):");
        out!("{}", n.report);
        out!("{short} / PCA mean frame rate: {r:.2}x");
    }
    if let Some(msg) = exported {
        out!("{msg}");
    }
    if let Some(dir) = &args.render {
        out!(
            "{}",
            rendered_line(
                &format!("rendered {} frames into {}", main.rendered, dir.display()),
                "frame_*.png, map_*.png",
                main.gif.as_deref(),
                main.stale_removed
            )
        );
    }
    Ok(())
}

/// The line `crowd --render` ends with: `what` (frames and folder), the files' patterns, the GIF
/// and the files an earlier run left there that were removed.
pub(super) fn rendered_line(
    what: &str,
    patterns: &str,
    gif: Option<&std::path::Path>,
    stale_removed: usize,
) -> String {
    format!(
        "{what} ({patterns}){}{}",
        gif.map_or(String::new(), |g| format!(" and {}", g.display())),
        match stale_removed {
            0 => String::new(),
            n => format!("; removed {n} files an earlier run had left there under these names"),
        }
    )
}

/// Records `--export-seconds` of the crowd of `run` (the model's source, the chosen policy, or full
/// detail under `--no-lod`) seen from the camera of `--camera` (its path decides every walker's
/// detail and visibility, and which walkers are written), every walker starting mid-stride at its
/// detail ([`export_crowd`]), and writes `--export-walkers` of its walkers to `path`; returns the
/// line to print.
fn export_clip(
    model: &MotionModel,
    args: &CrowdArgs,
    run: &CrowdRun,
    path: &std::path::Path,
) -> anyhow::Result<String> {
    let clip = CrowdClip {
        config: run.config,
        lens: run.lens,
        scene: run.scene,
        seconds: args.export_seconds,
        exported: args.export_walkers,
    };
    let lod = model.lod();
    let (scene, summary) = match args.policy {
        _ if args.no_lod => export_crowd(model, &FullDetail::for_model(lod), &clip),
        PolicyArg::Distance => export_crowd(model, &DistancePolicy::for_model(lod), &clip),
        PolicyArg::Screen => export_crowd(
            model,
            &ScreenSpacePolicy::for_model(lod).context("screen-space policy")?,
            &clip,
        ),
    }
    .context("recording the crowd clip")?;
    scene
        .write(path)
        .with_context(|| format!("writing {}", path.display()))?;
    let levels = lod.levels().len();
    let per_level: Vec<String> = summary
        .level_counts
        .iter()
        .enumerate()
        .filter(|(_, c)| **c > 0)
        .map(|(b, c)| format!("{c} at {}", motion_lod::gltf::level_label(b, levels)))
        .collect();
    Ok(format!(
        "wrote {}: {} walkers x {} frames ({}); view it with `motion-lod view {}`",
        path.display(),
        summary.walkers,
        summary.frames,
        per_level.join(", "),
        path.display()
    ))
}

/// The PCA baseline over the model's training samples.
fn pca_source<'m>(
    model: &'m MotionModel,
    analysis: Option<&'m Analysis>,
    rank: usize,
) -> anyhow::Result<PcaSource<'m>> {
    let analysis = analysis.context("PCA source")?;
    PcaSource::new(model, analysis, rank).context("building the PCA baseline")
}

/// Runs `source` under the chosen level-of-detail policy of the model `lod` (every source shares its
/// accuracy levels and joints, so the same culling, root-only walkers and joint counts), or with every
/// walker at full detail when `full_detail` is set.
fn run_with_policy<S: ClipSource>(
    source: &S,
    policy: PolicyArg,
    full_detail: bool,
    lod: &LodModel,
    run: &CrowdRun,
) -> anyhow::Result<CrowdOutcome> {
    if full_detail {
        return Ok(run_crowd(source, &FullDetail::for_model(lod), run)?);
    }
    Ok(match policy {
        PolicyArg::Distance => run_crowd(source, &DistancePolicy::for_model(lod), run)?,
        PolicyArg::Screen => run_crowd(
            source,
            &ScreenSpacePolicy::for_model(lod).context("screen-space policy")?,
            run,
        )?,
    })
}
