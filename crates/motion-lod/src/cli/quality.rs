//! `motion-lod quality MODEL`: the motion-quality meter over a grid of walks covering the data's
//! controls, at every accuracy level (or one), beside the data's own takes; with `--crowd`, over
//! crowd walkers as the crowd plays them (transitions inertialized near, switched far; planted
//! feet near).

use std::path::PathBuf;

use anyhow::{Context as _, bail};
use clap::Args;
use lod_policy::Detail;
use motion_lod::MotionModel;
use motion_lod::quality::{self, MotionQuality};
use motion_lod::synth::WalkRequest;
use motion_lod::walk_quality::{self, GridWalk};
use serde::Serialize;

/// Arguments of `motion-lod quality`.
#[derive(Debug, Args)]
pub struct QualityArgs {
    /// The model file.
    #[arg(value_name = "MODEL")]
    pub model: PathBuf,
    /// Only this accuracy level (0 = full detail; default: every level; 0..=10000, and below the
    /// model's count).
    #[arg(long, value_parser = super::ranges::count(super::ranges::LEVEL), conflicts_with = "crowd")]
    pub level: Option<usize>,
    /// Evaluated joints (default: all; 0..=10000, more than the model has means all).
    #[arg(long, value_parser = super::ranges::count(super::ranges::JOINTS))]
    pub joints: Option<usize>,
    /// Cycles per walk (2 to 64).
    #[arg(long, default_value_t = 4, conflicts_with = "crowd")]
    pub cycles: usize,
    /// Switch cycles without the seam transition (as the crowd does for far walkers).
    #[arg(long)]
    pub no_blend: bool,
    /// Let feet slide as synthesized (no foot lock).
    #[arg(long)]
    pub no_foot_lock: bool,
    /// Measure crowd walkers as the crowd plays them instead of the walk grid: the distance
    /// policy, the camera of `--camera`, each walker's longest stretch drawn, in view with joints (near
    /// walkers inertialize their seams and plant their feet, far ones switch clips as they are;
    /// `--no-blend` and `--no-foot-lock` turn those off for every walker).
    #[arg(long)]
    pub crowd: bool,
    /// Walkers of `--crowd` (1..=10000).
    #[arg(long, default_value_t = 200, value_parser = super::ranges::count((1, 10_000)), requires = "crowd")]
    pub walkers: usize,
    /// Walkers per square metre of `--crowd`, sets the field size (0.000001 to 10).
    #[arg(long, default_value_t = 0.01, value_parser = super::ranges::density, requires = "crowd")]
    pub density: f32,
    /// Simulated seconds of `--crowd` (0.001 to 3600).
    #[arg(long, default_value_t = 10.0, value_parser = super::ranges::seconds, requires = "crowd")]
    pub seconds: f32,
    /// Camera of `--crowd`: `ground` walks inside the crowd, `overview` circles above it.
    #[arg(long, value_enum, default_value_t = super::crowd::CameraArg::Overview, requires = "crowd")]
    pub camera: super::crowd::CameraArg,
    /// Print one JSON document instead of the table.
    #[arg(long)]
    pub json: bool,
    /// For a model with styles: the grid's walks in this style (a name, a blend
    /// `elderly=0.5,youthful=0.5`, weights scaled to sum to 1, or `data`, the default), measured
    /// against that style's own takes, with each walk's posture (knee extension, head pitch) and the style whose cycles it
    /// resembles most.
    #[arg(long, value_name = "STYLE")]
    pub style: Option<String>,
    /// Measure a walk recorded from the live page (`motion-lod view MODEL.mlod`, the "record"
    /// button: `walk-recording.json`) instead of the walk grid, against the data's takes.
    #[arg(long, value_name = "FILE.json", conflicts_with = "crowd")]
    pub recorded: Option<PathBuf>,
}

/// One measured walk.
#[derive(Debug, Serialize)]
struct Row {
    walk: GridWalk,
    level: usize,
    joints: usize,
    quality: MotionQuality,
    /// The data's figures at the walk's step length (`QualityReference::at_step`): what `x data`
    /// divides by.
    data: MotionQuality,
    /// The walk's pop over the data's at its step (`x data`).
    pop_x: f64,
    /// The walk's skate over the data's at its step (`x data`).
    skate_x: f64,
    cycle_seconds: f64,
    data_cycle_seconds: Option<f64>,
    /// Knee extension and head pitch of the walk, for a model with styles.
    #[serde(skip_serializing_if = "Option::is_none")]
    posture: Option<motion_lod::posture::Posture>,
    /// The style whose training cycles' posture is nearest the walk's.
    #[serde(skip_serializing_if = "Option::is_none")]
    looks_like: Option<String>,
}

/// Runs the subcommand.
pub fn run(args: QualityArgs) -> anyhow::Result<()> {
    if !(2..=64).contains(&args.cycles) {
        bail!("--cycles {} is outside 2..=64", args.cycles);
    }
    let model = MotionModel::load(&args.model)
        .with_context(|| format!("reading {}", args.model.display()))?;
    let Some(pooled) = model.report.quality.clone() else {
        bail!(
            "{} has no motion-quality reference: the build did not find the feet; rebuild it",
            args.model.display()
        );
    };
    let style = match &args.style {
        Some(text) => motion_lod::style::parse_style_mix(model.styles(), text)?,
        None => lod_policy::StyleMix::DATA_MIX,
    };
    // A style's walks are held to that style's own takes.
    let reference = model
        .style
        .as_ref()
        .and_then(|st| st.reference_for(&style, Some(&pooled)))
        .unwrap_or(&pooled)
        .clone();
    let postures = model
        .style
        .as_ref()
        .map(|st| st.posture.as_slice())
        .filter(|p| !p.is_empty());
    if args.crowd {
        return run_crowd(&args, &model, &reference);
    }
    if let Some(path) = &args.recorded {
        return run_recorded(&args, path, &model, &reference);
    }
    let levels = model.lod().levels().len();
    let chosen: Vec<usize> = match args.level {
        Some(l) if l >= levels => bail!("--level {l}: the model has levels 0..{}", levels - 1),
        Some(l) => vec![l],
        None => (0..levels).collect(),
    };
    let joints = args
        .joints
        .unwrap_or(model.lod().joints())
        .min(model.lod().joints());
    let grid = walk_quality::walk_grid(&model);
    let mut rows = Vec::new();
    for &level in &chosen {
        for walk in &grid {
            let req = WalkRequest {
                // The grid's own style (a corner's sample's, else the data's mix) unless asked.
                controls: if args.style.is_some() {
                    walk.controls.with_style(style)
                } else {
                    walk.controls
                },
                detail: Detail::new(level, joints),
                cycles: args.cycles,
                fps: 30.0,
                blend: !args.no_blend,
                plant_feet: !args.no_foot_lock,
            };
            let w = model
                .synthesize_walk(&req)
                .with_context(|| format!("synthesizing `{}` at level {level}", walk.name))?;
            let q = walk_quality::measure_walk(&model, &w)
                .with_context(|| format!("measuring `{}` at level {level}", walk.name))?;
            let step = f64::from(walk.controls.dx).hypot(f64::from(walk.controls.dz));
            // A corner walk of one style (a model with styles, no --style) against that style's takes.
            let walk_reference = match (&args.style, &model.style) {
                (None, Some(st)) => st
                    .reference_for(&walk.controls.style, Some(&pooled))
                    .unwrap_or(&reference),
                _ => &reference,
            };
            let data = walk_reference.at_step(step);
            let posture = postures.and_then(|_| walk_quality::walk_posture(&model, &w));
            let looks_like = posture.zip(postures).and_then(|(p, styles)| {
                motion_lod::posture::nearest_style(&p, styles).map(|j| styles[j].style.clone())
            });
            rows.push(Row {
                walk: walk.clone(),
                level,
                joints,
                quality: q,
                data,
                pop_x: q.pop_cm / data.pop_cm,
                skate_x: q.skate_cm_s / data.skate_cm_s,
                cycle_seconds: w.cycle_seconds,
                data_cycle_seconds: reference.duration_for_step(step),
                posture,
                looks_like,
            });
        }
    }
    if args.json {
        #[derive(Serialize)]
        struct Doc<'a> {
            reference: &'a quality::QualityReference,
            walks: &'a [Row],
        }
        let mut reference = reference.clone();
        reference.cycle_steps.clear();
        out!(
            "{}",
            serde_json::to_string(&Doc {
                reference: &reference,
                walks: &rows
            })?
        );
        return Ok(());
    }
    let m = &reference.median;
    if let Some(styles) = postures {
        out!("posture of each style's cycles (median, 10th-90th percentile):");
        for st in styles {
            out!(
                "  {:<12} knee extension {:5.1} deg ({:.1}-{:.1}), head pitch {:5.1} deg ({:.1}-{:.1}), {} cycles",
                st.style,
                st.knee_extension_deg.median,
                st.knee_extension_deg.p10,
                st.knee_extension_deg.p90,
                st.head_pitch_deg.median,
                st.head_pitch_deg.p10,
                st.head_pitch_deg.p90,
                st.cycles
            );
        }
    }
    out!(
        "data ({} takes): pop {:.2} cm/frame^2, skate {:.2} cm/s, contact {:.2}, floating {:.2} cm, \
         float {:.2} cm, facing {:.1} deg (range {:.1}..{:.1}), floor at {:.3} m",
        reference.takes,
        m.pop_cm,
        m.skate_cm_s,
        m.contact_share,
        m.floating_cm,
        m.float_cm,
        m.facing_deg,
        reference.facing_range_deg.0,
        reference.facing_range_deg.1,
        reference.floor_m
    );
    let posture_head = if postures.is_some() {
        format!(" {:>6} {:>6}  {}", "knee", "head", "looks like")
    } else {
        String::new()
    };
    out!(
        "x data: the walk's figure over the data's takes of similar step length (`explain x data`)"
    );
    out!(
        "{:<16} {:>5} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>12}{posture_head}",
        "walk",
        "level",
        "pop",
        "x data",
        "seam",
        "skate",
        "x data",
        "contact",
        "floating",
        "floor",
        "float",
        "facing",
        "cycle/data"
    );
    for r in &rows {
        let q = &r.quality;
        let posture = match (&r.posture, &r.looks_like) {
            (Some(p), looks) => format!(
                " {:>6.1} {:>6.1}  {}",
                p.knee_extension_deg,
                p.head_pitch_deg,
                looks.as_deref().unwrap_or("-")
            ),
            _ => String::new(),
        };
        out!(
            "{:<16} {:>5} {:>8.2} {:>8.2} {:>8.2} {:>8.2} {:>8.2} {:>8.2} {:>8.2} {:>8.2} {:>8.2} {:>8.1} {:>12}{posture}",
            r.walk.name,
            r.level,
            q.pop_cm,
            r.pop_x,
            q.seam_pop_cm,
            q.skate_cm_s,
            r.skate_x,
            q.contact_share,
            q.floating_cm,
            q.floor_offset_cm,
            q.float_cm,
            q.facing_deg,
            r.data_cycle_seconds
                .map(|d| format!("{:.2}/{:.2}", r.cycle_seconds, d))
                .unwrap_or_default()
        );
    }
    let outside: Vec<&str> = grid
        .iter()
        .filter(|w| !w.in_hull)
        .map(|w| w.name.as_str())
        .collect();
    if !outside.is_empty() {
        out!(
            "outside the data's hull (measured, held to no threshold; `explain hull`): {}",
            outside.join(", ")
        );
    }
    Ok(())
}

/// `--recorded`: the meter over a walk recorded from the live page.
fn run_recorded(
    args: &QualityArgs,
    path: &std::path::Path,
    model: &MotionModel,
    reference: &quality::QualityReference,
) -> anyhow::Result<()> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let recording = motion_lod::recording::Recording::parse(&text)
        .with_context(|| format!("reading {}", path.display()))?;
    let track = recording
        .track(model)
        .with_context(|| format!("{} against {}", path.display(), args.model.display()))?;
    let q = motion_lod::crowd::measure_track(model, &track, recording.frame_time)
        .with_context(|| format!("measuring {}", path.display()))?;
    let m = &reference.median;
    let (lo, hi) = (
        track.levels.iter().min().copied().unwrap_or(0),
        track.levels.iter().max().copied().unwrap_or(0),
    );
    if args.json {
        #[derive(Serialize)]
        struct Doc<'a> {
            data: &'a MotionQuality,
            recorded: &'a MotionQuality,
            frames: usize,
            seams: usize,
            frame_time: f64,
            levels: (usize, usize),
        }
        out!(
            "{}",
            serde_json::to_string(&Doc {
                data: m,
                recorded: &q,
                frames: recording.frames.len(),
                seams: track.seams.len(),
                frame_time: recording.frame_time,
                levels: (lo, hi),
            })?
        );
        return Ok(());
    }
    out!(
        "{}: {} frames of {:.4} s, {} seams, levels {lo}..{hi} (measured from the first seam)",
        path.display(),
        recording.frames.len(),
        recording.frame_time,
        track.seams.len()
    );
    out!(
        "data ({} takes): pop {:.2} cm/frame^2, skate {:.2} cm/s, contact {:.2}, floating {:.2} cm",
        reference.takes,
        m.pop_cm,
        m.skate_cm_s,
        m.contact_share,
        m.floating_cm
    );
    out!(
        "recorded: pop {:.2} cm/frame^2 ({:.2}x the data), seam pop {:.2}, skate {:.2} cm/s ({:.2}x), \
         contact {:.2}, floating {:.2} cm, floor offset {:.2} cm",
        q.pop_cm,
        q.pop_cm / m.pop_cm,
        q.seam_pop_cm,
        q.skate_cm_s,
        q.skate_cm_s / m.skate_cm_s,
        q.contact_share,
        q.floating_cm,
        q.floor_offset_cm
    );
    Ok(())
}

/// `--crowd`: the meter over crowd walkers as the crowd plays them.
fn run_crowd(
    args: &QualityArgs,
    model: &MotionModel,
    reference: &quality::QualityReference,
) -> anyhow::Result<()> {
    use motion_lod::crowd_sim::CrowdConfig;
    let defaults = CrowdConfig::default();
    let config = CrowdConfig {
        seam_levels: if args.no_blend {
            0
        } else {
            defaults.seam_levels
        },
        foot_lock_levels: if args.no_foot_lock {
            0
        } else {
            defaults.foot_lock_levels
        },
        ..CrowdConfig::with_density(args.walkers, args.density)
    };
    let policy = lod_policy::DistancePolicy::for_model(model.lod());
    let walkers =
        motion_lod::crowd::crowd_quality(model, config, args.camera.into(), &policy, args.seconds)
            .context("measuring the crowd")?;
    if args.json {
        #[derive(Serialize)]
        struct Doc<'a> {
            data: &'a MotionQuality,
            walkers: &'a [motion_lod::crowd::WalkerQuality],
        }
        out!(
            "{}",
            serde_json::to_string(&Doc {
                data: &reference.median,
                walkers: &walkers
            })?
        );
        return Ok(());
    }
    let m = &reference.median;
    out!(
        "scene: {} walkers, {} per m^2, {} camera, distance policy, {} s at 30 fps; each walker's \
         longest stretch drawn (in view, with joints; after its first seam, at least two cycles)",
        args.walkers,
        args.density,
        match args.camera {
            super::crowd::CameraArg::Ground => "ground",
            super::crowd::CameraArg::Overview => "overview",
        },
        args.seconds
    );
    out!(
        "data ({} takes): pop {:.2} cm/frame^2, skate {:.2} cm/s, contact {:.2}",
        reference.takes,
        m.pop_cm,
        m.skate_cm_s,
        m.contact_share
    );
    out!(
        "{:>6} {:>7} {:>7} {:>7} {:>6} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8}",
        "walker",
        "frames",
        "levels",
        "joints",
        "seams",
        "pop",
        "x data",
        "seam",
        "skate",
        "x data",
        "contact",
        "floating",
        "floor"
    );
    for w in &walkers {
        let q = &w.quality;
        out!(
            "{:>6} {:>7} {:>7} {:>7} {:>6} {:>8.2} {:>8.2} {:>8.2} {:>8.2} {:>8.2} {:>8.2} {:>8.2} {:>8.2}",
            w.walker,
            w.frames,
            format!("{}-{}", w.levels.0, w.levels.1),
            format!("{}-{}", w.joints.0, w.joints.1),
            w.seams,
            q.pop_cm,
            q.pop_cm / m.pop_cm,
            q.seam_pop_cm,
            q.skate_cm_s,
            q.skate_cm_s / m.skate_cm_s,
            q.contact_share,
            q.floating_cm,
            q.floor_offset_cm
        );
    }
    if walkers.is_empty() {
        out!(
            "no walker was drawn (in view, with joints) for two cycles; try more --seconds or --walkers"
        );
    }
    Ok(())
}
