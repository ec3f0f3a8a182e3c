//! `cargo xtask fixtures`: the deterministic synthetic gait set in `fixtures/`.
//!
//! Three performers (1.60, 1.75 and 1.90 m) each walk [`TAKES_PER_PERFORMER`] takes; speeds are
//! stratified over 0.8..1.6 m/s and the turn rates -30, -15, 0, 15, 30 deg/s (jittered, straight
//! takes exactly straight) are shuffled across them. All choices come from one SplitMix64 stream
//! with a fixed seed, and the frames are written with 4 decimals, so the files are the same bytes
//! on every run.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use motion_io::Motion;

use crate::gait::{Style, TakeSpec, cycle_frequency, stride_length};
use crate::rng::SplitMix64;
use crate::walker::{self, FPS, Take};

/// Seed of the fixture plan ("motionlo" in ASCII).
pub const SEED: u64 = 0x6D6F_7469_6F6E_6C6F;
/// Standing heights of the three performers, metres.
pub const PERFORMER_HEIGHTS: [f64; 3] = [1.60, 1.75, 1.90];
/// Takes per performer.
pub const TAKES_PER_PERFORMER: usize = 5;
/// Steady cycles per take (after the first, accelerating cycle).
pub const STEADY_CYCLES: usize = 4;
/// Steady speed range, m/s.
pub const SPEED_RANGE: (f64, f64) = (0.8, 1.6);
/// Nominal turn rates, deg/s (positive = left); each performer walks each once.
pub const TURN_RATES: [f64; 5] = [-30.0, -15.0, 0.0, 15.0, 30.0];

/// One planned take: its file name, performer label and generating parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct PlannedTake {
    /// File name inside the fixtures folder, e.g. `walk_p175_t03.bvh`.
    pub file: String,
    /// Performer label, e.g. `p175`.
    pub performer: String,
    /// Generating parameters.
    pub spec: TakeSpec,
}

/// The performer label of a height in metres: `p` and the height in centimetres.
fn performer_label(height_m: f64) -> String {
    format!("p{:.0}", height_m * 100.0)
}

/// The fixture plan: every take's parameters, drawn from the SplitMix64 stream seeded with `seed`.
pub fn plan(seed: u64) -> Vec<PlannedTake> {
    let mut rng = SplitMix64::new(seed);
    let mut takes = Vec::new();
    for &height in &PERFORMER_HEIGHTS {
        let style = Style {
            arm_swing_deg: rng.uniform(14.0, 22.0),
            elbow_deg: rng.uniform(12.0, 24.0),
            step_width: rng.uniform(0.05, 0.07),
            toe_out_deg: rng.uniform(3.0, 9.0),
            bob_scale: rng.uniform(0.85, 1.15),
            trunk_lean_deg: rng.uniform(2.0, 6.0),
        };
        let n = TAKES_PER_PERFORMER;
        let mut speeds: Vec<f64> = (0..n)
            .map(|i| {
                let (lo, hi) = SPEED_RANGE;
                lo + (hi - lo) * (i as f64 + rng.uniform(0.1, 0.9)) / n as f64
            })
            .collect();
        rng.shuffle(&mut speeds);
        let mut turns: Vec<f64> = TURN_RATES.iter().copied().cycle().take(n).collect();
        rng.shuffle(&mut turns);
        let performer = performer_label(height);
        for (i, (&speed, &turn)) in speeds.iter().zip(&turns).enumerate() {
            let turn_rate_deg = if turn == 0.0 {
                0.0
            } else {
                turn + rng.uniform(-3.0, 3.0)
            };
            let spec = TakeSpec {
                height_m: height,
                speed: round_to(speed, 3),
                turn_rate_deg: round_to(turn_rate_deg, 2),
                heading0_deg: round_to(rng.uniform(-90.0, 90.0), 1),
                start_m: [
                    round_to(rng.uniform(-2.0, 2.0), 2),
                    round_to(rng.uniform(-2.0, 2.0), 2),
                ],
                steady_cycles: STEADY_CYCLES,
                style,
            };
            takes.push(PlannedTake {
                file: format!("walk_{performer}_t{:02}.bvh", i + 1),
                performer: performer.clone(),
                spec,
            });
        }
    }
    takes
}

/// Rounds to `decimals` places, so that `controls.csv` lists the exact generating values.
fn round_to(x: f64, decimals: i32) -> f64 {
    let s = 10f64.powi(decimals);
    (x * s).round() / s + 0.0 // + 0.0 turns -0.0 into 0.0
}

/// BVH text of a motion with every frame value rounded to 4 decimals, trailing zeros dropped
/// (motion-io's writer uses 6; 4 keep the set small and are far below capture precision:
/// 1e-4 cm and 1e-4 degrees).
///
/// The HIERARCHY section is motion-io's own (`to_bvh_string` of the frameless motion).
pub fn bvh_text(motion: &Motion) -> String {
    bvh_text_with(motion, 4)
}

/// [`bvh_text`] with `decimals` decimals (4 or 6).
pub fn bvh_text_with(motion: &Motion, decimals: usize) -> String {
    let frameless = Motion {
        skeleton: motion.skeleton.clone(),
        frame_time: motion.frame_time,
        frames: Vec::new(),
    };
    let header = motion_io::to_bvh_string(&frameless);
    let cut = header.find("MOTION").unwrap_or(header.len());
    let nch = motion.skeleton.channel_count();
    let nf = motion.frame_count();
    let mut s = String::with_capacity(cut + 64 + nf * nch * 9);
    s.push_str(&header[..cut]);
    let _ = write!(
        s,
        "MOTION\nFrames: {nf}\nFrame Time: {:.7}\n",
        motion.frame_time
    );
    for f in 0..nf {
        for (k, &v) in motion.frame(f).iter().enumerate() {
            if k > 0 {
                s.push(' ');
            }
            push_decimals(&mut s, v, decimals);
        }
        s.push('\n');
    }
    s
}

/// Appends `v` rounded to `decimals` decimals without trailing zeros (`1.5`, `-0.0012`, `0`; never
/// `-0`).
fn push_decimals(s: &mut String, v: f64, decimals: usize) {
    if v.abs() < 0.5 * 10f64.powi(-(decimals as i32)) {
        s.push('0');
        return;
    }
    let start = s.len();
    let _ = write!(s, "{v:.decimals$}");
    let trimmed = s[start..].trim_end_matches('0').trim_end_matches('.').len();
    s.truncate(start + trimmed);
}

/// One generated file: name and content.
#[derive(Debug, Clone, PartialEq)]
pub struct FixtureFile {
    /// File name inside the fixtures folder.
    pub name: String,
    /// Full content.
    pub content: String,
}

/// Generates every fixture file in memory: the takes, `controls.csv` and `README.md`.
pub fn generate_all(seed: u64) -> Result<Vec<FixtureFile>> {
    let planned = plan(seed);
    let mut files = Vec::with_capacity(planned.len() + 2);
    let mut controls = String::from(
        "file,performer,height_m,speed_mps,turn_rate_dps,heading0_deg,start_x_m,start_z_m,frames,duration_s,steady_start_s,stride_m,cycle_s\n",
    );
    let mut bases = Vec::new();
    for p in &planned {
        let take: Take =
            walker::generate(&p.spec).with_context(|| format!("generating {}", p.file))?;
        let m = &take.motion;
        if let Some(i) = m.frames.iter().position(|v| !v.is_finite()) {
            let n = m.skeleton.channel_count();
            bail!(
                "{}: non-finite value at frame {}, channel {}",
                p.file,
                i / n,
                i % n
            );
        }
        let s = &p.spec;
        let leg = take.trajectory.leg;
        let _ = writeln!(
            controls,
            "{},{},{:.2},{:.3},{:.2},{:.1},{:.2},{:.2},{},{:.4},{:.4},{:.4},{:.4}",
            p.file,
            p.performer,
            s.height_m,
            s.speed,
            s.turn_rate_deg,
            s.heading0_deg,
            s.start_m[0],
            s.start_m[1],
            m.frame_count(),
            m.frame_count() as f64 / FPS,
            take.trajectory.steady_start,
            stride_length(s.speed, leg),
            1.0 / cycle_frequency(s.speed, leg),
        );
        let content = bvh_text(m);
        if crate::variants::VARIANT_TAKES.contains(&p.file.as_str()) {
            // Variants rewrite the take as written (4 decimals), not the unrounded motion.
            let written = motion_io::parse_bvh(&content)
                .with_context(|| format!("reading back {}", p.file))?;
            bases.push((p.file.clone(), written));
        }
        files.push(FixtureFile {
            name: p.file.clone(),
            content,
        });
    }
    files.extend(crate::variants::variant_files(&bases));
    files.push(FixtureFile {
        name: "controls.csv".into(),
        content: controls,
    });
    files.push(FixtureFile {
        name: "README.md".into(),
        content: readme(&planned),
    });
    Ok(files)
}

/// The generated `README.md` of the fixtures folder.
fn readme(planned: &[PlannedTake]) -> String {
    let mut s = String::new();
    let _ = write!(
        s,
        "# fixtures: a synthetic gait set from the procedural walker\n\n\
         Generated by `cargo xtask fixtures` (source: `xtask/src/`); do not edit by hand.\n\
         `cargo xtask fixtures` rewrites every file here from a fixed seed (0x{SEED:016X}), and\n\
         `cargo xtask fixtures --check` fails if any file differs from what the generator produces.\n\
         This is the default data set of the demo: it lets the whole pipeline run on a fresh\n\
         checkout without the real motion capture in `../shared/mocap`.\n\n\
         ## What is here\n\
         - {} BVH takes `walk_<performer>_tNN.bvh`: {} performers ({}) x {} takes each, {} Hz.\n\
         - `controls.csv`: per take the generating parameters (performer, height, steady speed, turn\n  \
           rate, start heading and position) and the resulting frame count, duration, start of the\n  \
           steady cycles, stride length and cycle duration.\n\n\
         ## The takes\n\
         - Each take starts from a standstill-like first cycle (speed ramping from 30 % of the steady\n  \
           speed, short slow steps) that ends with a left heel strike, then walks {} steady two-step cycles\n  \
           (left heel strike to left heel strike) on a circular arc with the take's turn rate\n  \
           (positive = turning left) or a straight line, and goes on walking for about half a cycle\n  \
           after the last one (so that a window of one cycle centred on its closing heel strike, over\n  \
           which `motion_io` measures the heading, lies inside the take).\n\
         - Steady speeds are stratified over 0.8..1.6 m/s per performer; turn rates -30, -15, 0, +15,\n  \
           +30 deg/s, one of each per performer (jittered by up to 3 deg/s, straight takes exactly\n  \
           straight). Start heading and position vary per take.\n\
         - Stride length follows Alexander's relation `2.5 L (v^2 / g L)^0.3` (L = hip height), the\n  \
           duty factor falls from 0.64 to 0.58 with speed; heel strike, foot flat, heel rise and toe\n  \
           off are modelled as rolling contacts, so stance feet do not slide. Legs are solved with\n  \
           two-bone IK towards the planted feet; the pelvis bobs, sways, rolls and rotates; the trunk\n  \
           counter-rotates; the arms swing against the legs; the body leans into turns.\n\n\
         ## Skeleton and units\n\
         - 19 joints: Hips (root), Spine, Chest, Neck, Head, UpperArm/LowerArm/Hand _L/_R,\n  \
           UpperLeg/LowerLeg/Foot/Toes _L/_R, with End Sites on Head, Hands and Toes (names as in\n  \
           the Bandai-Namco data set). Segment lengths are fixed fractions of the standing height.\n\
         - Centimetres, Y up, floor at y = 0, rest pose facing +Z (left = +X) with the arms down.\n\
         - Root channels `Xposition Yposition Zposition Zrotation Xrotation Yrotation`, other joints\n  \
           `Zrotation Xrotation Yrotation` (local rotation Rz * Rx * Ry), degrees with 4 decimals;\n  \
           Euler channels are continuous (a turning heading grows past 180 degrees). Values are rounded to\n  \
           4 decimals with trailing zeros dropped.\n\n\
         ## Determinism\n\
         The plan comes from a self-written SplitMix64 generator and the frames are printed with 4\n\
         decimals: repeated runs give the same bytes. The trigonometry comes from the platform's math\n\
         library, so another platform could differ in a rare last digit; `--check` tells.\n\n\
         ## Takes\n\n\
         | file | performer | height m | speed m/s | turn deg/s |\n|---|---|---|---|---|\n",
        planned.len(),
        PERFORMER_HEIGHTS.len(),
        PERFORMER_HEIGHTS
            .iter()
            .map(|h| format!("{h:.2} m"))
            .collect::<Vec<_>>()
            .join(", "),
        TAKES_PER_PERFORMER,
        FPS,
        STEADY_CYCLES,
    );
    for p in planned {
        let _ = writeln!(
            s,
            "| {} | {} | {:.2} | {:.3} | {:.2} |",
            p.file, p.performer, p.spec.height_m, p.spec.speed, p.spec.turn_rate_deg
        );
    }
    s
}

/// Default output folder: `fixtures/` at the workspace root.
pub fn default_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("fixtures")
}

/// Writes the fixture files into `dir` (created if missing) and removes stale `walk_*.bvh` files
/// that the plan no longer contains. Returns the number of bytes written.
pub fn write(dir: &Path, files: &[FixtureFile]) -> Result<u64> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let mut total = 0;
    for f in files {
        let path = dir.join(&f.name);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent)
                .with_context(|| format!("creating {}", parent.display()))?;
        }
        std::fs::write(&path, f.content.as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
        total += f.content.len() as u64;
    }
    for entry in std::fs::read_dir(dir).with_context(|| format!("listing {}", dir.display()))? {
        let entry = entry?;
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.starts_with("walk_")
            && name.ends_with(".bvh")
            && !files.iter().any(|f| f.name == name)
        {
            std::fs::remove_file(entry.path()).with_context(|| format!("removing stale {name}"))?;
        }
    }
    // Stale variant takes and folders.
    let variants = dir.join("variants");
    if let Ok(folders) = std::fs::read_dir(&variants) {
        for folder in folders {
            let folder = folder?.path();
            if !folder.is_dir() {
                continue;
            }
            for entry in std::fs::read_dir(&folder)
                .with_context(|| format!("listing {}", folder.display()))?
            {
                let path = entry?.path();
                let rel = path
                    .strip_prefix(dir)
                    .map(|p| p.to_string_lossy().replace('\\', "/"))
                    .unwrap_or_default();
                if !files.iter().any(|f| f.name == rel) {
                    std::fs::remove_file(&path)
                        .with_context(|| format!("removing stale {}", path.display()))?;
                }
            }
            if std::fs::read_dir(&folder)?.next().is_none() {
                std::fs::remove_dir(&folder)
                    .with_context(|| format!("removing {}", folder.display()))?;
            }
        }
    }
    Ok(total)
}

/// Compares the files in `dir` with `files`; returns the names that are missing or differ.
pub fn check(dir: &Path, files: &[FixtureFile]) -> Vec<String> {
    files
        .iter()
        .filter(|f| std::fs::read(dir.join(&f.name)).map_or(true, |b| b != f.content.as_bytes()))
        .map(|f| f.name.clone())
        .collect()
}
