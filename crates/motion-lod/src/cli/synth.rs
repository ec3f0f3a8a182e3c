//! `motion-lod synth model.mlod --dx --dz --turn [--height] -o walk.bvh|walk.glb`: a walk as a BVH
//! file, or as glTF 2.0 binary when the output ends in `.glb` (format by extension).

use std::path::PathBuf;

use anyhow::{Context as _, bail};
use clap::Args;
use lod_policy::{Controls, Detail, StyleMix};
use motion_lod::MotionModel;
use motion_lod::style::parse_style_mix;
use motion_lod::synth::WalkRequest;
use motion_lod::track::parse_track;

/// Arguments of `motion-lod synth`.
#[derive(Debug, Args)]
pub struct SynthArgs {
    /// The model file.
    #[arg(value_name = "MODEL")]
    pub model: PathBuf,
    /// Sideways root displacement per cycle, metres (+ = to the character's left).
    #[arg(long, allow_hyphen_values = true, required_unless_present = "track", value_parser = super::ranges::finite_f32)]
    pub dx: Option<f32>,
    /// Forward root displacement per cycle, metres.
    #[arg(long, allow_hyphen_values = true, required_unless_present = "track", value_parser = super::ranges::finite_f32)]
    pub dz: Option<f32>,
    /// Heading change per cycle, degrees (+ = left).
    #[arg(long, allow_hyphen_values = true, required_unless_present = "track", value_parser = super::ranges::finite_f32)]
    pub turn: Option<f32>,
    /// Standing height of the character, metres (default: the middle of the data's range).
    #[arg(long, value_parser = super::ranges::finite_f32)]
    pub height: Option<f32>,
    /// The performer's style, for a model built with style labels: one style (`elderly`), a blend
    /// (`elderly=0.5,youthful=0.5`; weights are scaled to sum to 1), or `data` for the data's own
    /// mix (the default).
    #[arg(long, value_name = "STYLE")]
    pub style: Option<String>,
    /// Controls over time from a CSV file (`time,dx,dz,turn[,height][,style]`, time in seconds,
    /// turn in degrees; each row applied at the next cycle seam; see `motion-lod explain track`).
    /// Replaces --dx, --dz, --turn, --style and --cycles.
    #[arg(long, value_name = "CSV", conflicts_with_all = ["dx", "dz", "turn", "style", "cycles"])]
    pub track: Option<PathBuf>,
    /// Accuracy level (0 = full detail; 0..=10000, and below the model's level count).
    #[arg(long, default_value_t = 0, value_parser = super::ranges::count(super::ranges::LEVEL))]
    pub level: usize,
    /// Evaluated joints (default: all; 0..=10000, more than the model has means all).
    #[arg(long, value_parser = super::ranges::count(super::ranges::JOINTS))]
    pub joints: Option<usize>,
    /// Number of cycles (1..=10000).
    #[arg(long, default_value_t = 4, value_parser = super::ranges::count(super::ranges::CYCLES))]
    pub cycles: usize,
    /// Output frames per second (1 to 1000).
    #[arg(long, default_value_t = 30.0, value_parser = super::ranges::fps)]
    pub fps: f64,
    /// Switch cycles as they are, without the seam transition (what the crowd does far away).
    #[arg(long)]
    pub no_blend: bool,
    /// Let feet slide as synthesized (no foot lock).
    #[arg(long)]
    pub no_foot_lock: bool,
    /// Refuse controls outside the data's range instead of clamping them.
    #[arg(long)]
    pub strict: bool,
    /// The file to write (atomically): `.glb` for glTF 2.0 binary (skinned body and animation, for
    /// engines and browsers), anything else for BVH.
    #[arg(short, long, value_name = "FILE")]
    pub output: PathBuf,
}

/// Runs the subcommand.
pub fn run(args: SynthArgs) -> anyhow::Result<()> {
    let ext = super::build::suffix(&args.output);
    if ext.as_deref() == Some("gltf") {
        bail!(
            "{}: glTF is written as binary .glb only; use a name ending in .glb",
            args.output.display()
        );
    }
    let glb = ext.as_deref() == Some("glb");
    super::build::check_writable(&args.output)?;
    let mut inputs = vec![("the model", args.model.as_path())];
    if let Some(track) = &args.track {
        inputs.push(("the track", track.as_path()));
    }
    super::build::check_not_input(&args.output, &inputs)?;
    let model = MotionModel::load(&args.model)
        .with_context(|| format!("reading {}", args.model.display()))?;
    let range = model.control_range();
    let default_height = 0.5 * (range[3].0 + range[3].1);
    let height = args.height.unwrap_or(default_height);
    let track = match &args.track {
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("reading the track {}", path.display()))?;
            let rows = parse_track(&text, model.styles(), height)
                .with_context(|| format!("track {}", path.display()))?;
            Some(rows)
        }
        None => None,
    };
    let style = match &args.style {
        Some(text) => parse_style_mix(model.styles(), text)?,
        None => StyleMix::DATA_MIX,
    };
    let controls = match &track {
        Some(rows) => rows[0].1,
        None => Controls::from_array([
            args.dx.unwrap_or(0.0),
            args.dz.unwrap_or(0.0),
            args.turn.unwrap_or(0.0).to_radians(),
            height,
        ])
        .with_style(style),
    };
    let all: Vec<Controls> = match &track {
        Some(rows) => rows.iter().map(|r| r.1).collect(),
        None => vec![controls],
    };
    // Every control the model ignores, given a value other than its default, is said once.
    let given = |k: usize, c: &Controls| match k {
        0 => c.dx != 0.0,
        1 => track.is_some() || args.dz.is_some(),
        2 => c.turn != 0.0,
        // A track's height column as much as `--height` (the column was ignored unsaid).
        _ => args.height.is_some() || (track.is_some() && c.height != height),
    };
    let names = Controls::NAMES;
    let ignored = model.ignored_controls();
    for k in 0..names.len() {
        let (lo, hi) = range[k];
        let values: Vec<f32> = all.iter().map(|c| c.to_array()[k]).collect();
        if ignored[k] {
            if let Some(c) = all.iter().find(|c| given(k, c)) {
                let v = c.to_array()[k];
                let show = if k == 2 { v.to_degrees() } else { v };
                let implied = model.lod().controls().implied(k, c);
                let implied = if k == 2 {
                    implied.to_degrees()
                } else {
                    implied
                };
                eprintln!(
                    "warning: {} {show:.3} has no effect: the model ignores {} ({}); the walk takes \
                    the {} the other controls imply ({implied:.3}); see `motion-lod info`",
                    names[k],
                    names[k],
                    model.why_ignored(k).unwrap_or_default(),
                    names[k]
                );
            }
            continue;
        }
        if let Some(&v) = values.iter().find(|&&v| v < lo || v > hi) {
            let (show, lo_s, hi_s) = if k == 2 {
                (v.to_degrees(), lo.to_degrees(), hi.to_degrees())
            } else {
                (v, lo, hi)
            };
            let msg = format!(
                "{} {show:.3} is outside the data's range [{lo_s:.3}, {hi_s:.3}]",
                names[k]
            );
            if args.strict {
                bail!("{msg} (--strict)");
            }
            eprintln!("warning: {msg}; clamped");
        }
    }
    // Each control in its range is not enough: the combination may lie beyond every take.
    let hull = motion_lod::hull::ControlHull::of(&model);
    let clamp = model.lod().controls();
    // The hull is measured, and the controls named, as the runtime uses them: clamped into range.
    let outside: Vec<(usize, f64, Controls)> = all
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let mut a = c.to_array();
            for (k, v) in a.iter_mut().enumerate() {
                *v = v.clamp(clamp.min[k], clamp.max[k]);
            }
            let clamped = Controls::from_array(a);
            (i, hull.distance(&clamped), clamped)
        })
        .filter(|&(_, dist, _)| dist > motion_lod::hull::HULL_TOLERANCE)
        .collect();
    if let Some(&(i, dist, c)) = outside.iter().max_by(|a, b| a.1.total_cmp(&b.1)) {
        let was_clamped = c.to_array() != all[i].to_array();
        let which = if track.is_some() {
            format!(
                "{} of the track's {} rows lie (the farthest, row {}: ",
                outside.len(),
                all.len(),
                i + 1
            )
        } else {
            "the controls lie (".to_string()
        };
        eprintln!(
            "warning: {which}dx {:.3} m, dz {:.3} m, turn {:.1} deg{}) outside the data's hull, \
             {dist:.2} standard deviations beyond any mix of the training controls: each control is \
             in its range but no take walks like that, so the walk extrapolates and may pop or skate \
             (see `motion-lod explain hull`)",
            c.dx,
            c.dz,
            c.turn.to_degrees(),
            if was_clamped { ", once clamped" } else { "" }
        );
    }
    let req = WalkRequest {
        controls,
        detail: Detail::new(
            args.level,
            args.joints
                .map_or(model.lod().joints(), |j| j.min(model.lod().joints())),
        ),
        cycles: args.cycles,
        fps: args.fps,
        blend: !args.no_blend,
        plant_feet: !args.no_foot_lock,
    };
    let walk = match &track {
        Some(rows) => model.synthesize_track(&req, rows),
        None => model.synthesize_walk(&req),
    }
    .context("synthesizing the walk")?;
    let cycles = walk.cycles;
    if glb {
        let name = args
            .output
            .file_stem()
            .map_or_else(|| "walk".into(), |s| s.to_string_lossy().into_owned());
        let scene = motion_lod::gltf::export_walk(&model, &walk, args.level, &name)
            .context("converting to glTF")?;
        scene
            .write(&args.output)
            .with_context(|| format!("writing {}", args.output.display()))?;
        let frames = walk.poses.len() / model.layout.dof();
        out!(
            "wrote {}: {} cycles of {:.3} s, {frames} frames at {} fps (glTF 2.0; view it with \
             `motion-lod view {}`)",
            args.output.display(),
            cycles,
            walk.cycle_seconds,
            args.fps,
            args.output.display()
        );
        return Ok(());
    }
    // The skeleton's own OFFSETs, with the rest pose's hips over the origin.
    let motion =
        motion_io::with_rest_at_origin(&model.walk_motion(&walk).context("converting to BVH")?);
    motion_io::write_bvh(&motion, &args.output)
        .with_context(|| format!("writing {}", args.output.display()))?;
    out!(
        "wrote {}: {} cycles of {:.3} s, {} frames at {} fps",
        args.output.display(),
        cycles,
        walk.cycle_seconds,
        motion.frame_count(),
        args.fps
    );
    Ok(())
}
