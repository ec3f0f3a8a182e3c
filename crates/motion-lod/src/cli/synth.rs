//! `motion-lod synth model.mlod --dx --dz --turn [--height] -o walk.bvh|walk.glb`: a walk as a BVH
//! file, or as glTF 2.0 binary when the output ends in `.glb` (format by extension).

use std::path::PathBuf;

use anyhow::{Context as _, bail};
use clap::Args;
use lod_policy::{Controls, Detail};
use motion_lod::MotionModel;
use motion_lod::synth::WalkRequest;

/// Arguments of `motion-lod synth`.
#[derive(Debug, Args)]
pub struct SynthArgs {
    /// The model file.
    #[arg(value_name = "MODEL")]
    pub model: PathBuf,
    /// Sideways root displacement per cycle, metres (+ = to the character's left).
    #[arg(long, allow_hyphen_values = true)]
    pub dx: f32,
    /// Forward root displacement per cycle, metres.
    #[arg(long, allow_hyphen_values = true)]
    pub dz: f32,
    /// Heading change per cycle, degrees (+ = left).
    #[arg(long, allow_hyphen_values = true)]
    pub turn: f32,
    /// Standing height of the character, metres (default: the middle of the data's range).
    #[arg(long)]
    pub height: Option<f32>,
    /// Accuracy level (0 = full detail; 0..=10000, and below the model's level count).
    #[arg(long, default_value_t = 0, value_parser = super::ranges::count(super::ranges::LEVEL))]
    pub level: usize,
    /// Evaluated joints (default: all; 0..=10000, more than the model has means all).
    #[arg(long, value_parser = super::ranges::count(super::ranges::JOINTS))]
    pub joints: Option<usize>,
    /// Number of cycles (1..=10000).
    #[arg(long, default_value_t = 4, value_parser = super::ranges::count(super::ranges::CYCLES))]
    pub cycles: usize,
    /// Output frames per second (0 < fps <= 1000).
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
    let ext = args
        .output
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    if ext.as_deref() == Some("gltf") {
        bail!(
            "{}: glTF is written as binary .glb only; use a name ending in .glb",
            args.output.display()
        );
    }
    let glb = ext.as_deref() == Some("glb");
    let model = MotionModel::load(&args.model)
        .with_context(|| format!("reading {}", args.model.display()))?;
    let range = model.control_range();
    let height = args.height.unwrap_or(0.5 * (range[3].0 + range[3].1));
    let controls = Controls {
        dx: args.dx,
        dz: args.dz,
        turn: args.turn.to_radians(),
        height,
    };
    let names = Controls::NAMES;
    let ignored = model.ignored_controls();
    for (k, (&c, &(lo, hi))) in controls.to_array().iter().zip(&range).enumerate() {
        if !c.is_finite() {
            bail!("--{} is not a finite number", names[k]);
        }
        let constant = hi - lo <= f32::EPSILON * hi.abs().max(1.0);
        if constant && k == 3 {
            if args.height.is_some() && (c - lo).abs() > 1e-3 {
                eprintln!(
                    "warning: the training data has one height ({lo:.3} m); --height {c:.3} has no effect"
                );
            }
            continue;
        }
        if ignored[k] {
            // Dropped at build: the data's variation of this control is noise (see `info`).
            let given = k != 3 || args.height.is_some();
            if given && (c < lo || c > hi) {
                let (show, lo_s, hi_s) = if k == 2 {
                    (c.to_degrees(), lo.to_degrees(), hi.to_degrees())
                } else {
                    (c, lo, hi)
                };
                eprintln!(
                    "warning: --{} {show:.3} has no effect: the model ignores {} (the data's range \
                     [{lo_s:.3}, {hi_s:.3}] carries no signal; see `motion-lod info`)",
                    names[k], names[k]
                );
            }
            continue;
        }
        if c < lo || c > hi {
            let (show, lo_s, hi_s) = if k == 2 {
                (c.to_degrees(), lo.to_degrees(), hi.to_degrees())
            } else {
                (c, lo, hi)
            };
            let msg = format!(
                "--{} {show:.3} is outside the data's range [{lo_s:.3}, {hi_s:.3}]",
                names[k]
            );
            if args.strict {
                bail!("{msg} (--strict)");
            }
            eprintln!("warning: {msg}; clamped");
        }
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
    let walk = model
        .synthesize_walk(&req)
        .context("synthesizing the walk")?;
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
        println!(
            "wrote {}: {} cycles of {:.3} s, {frames} frames at {} fps (glTF 2.0; view it with \
             `motion-lod view {}`)",
            args.output.display(),
            args.cycles,
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
    println!(
        "wrote {}: {} cycles of {:.3} s, {} frames at {} fps",
        args.output.display(),
        args.cycles,
        walk.cycle_seconds,
        motion.frame_count(),
        args.fps
    );
    Ok(())
}
