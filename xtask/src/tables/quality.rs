//! Section 7: the motion-quality meter ([`motion_lod::quality`]) per accuracy level over the grid of
//! walks covering the data's controls, as ratios to the data's own takes, and the figure of pop and
//! skate against the level and against the walk's step length.

use std::fmt::Write as _;

use anyhow::{Context as _, Result};
use lod_policy::Detail;
use motion_lod::MotionModel;
use motion_lod::quality::{self, MotionQuality, QualityReference};
use motion_lod::synth::WalkRequest;
use motion_lod::walk_quality::{self, GridWalk};

/// Cycles per measured walk (as `motion-lod quality`).
pub const CYCLES: usize = 4;

/// One walk of the grid measured at one level.
#[derive(Debug, Clone)]
pub struct QualityPoint {
    /// The grid walk.
    pub walk: GridWalk,
    /// Accuracy level.
    pub level: usize,
    /// The meter's figures.
    pub quality: MotionQuality,
}

/// The grid at every accuracy level, all joints, seams inertialized and feet planted (what near
/// characters show). `None` when the model has no quality reference (feet not found).
pub fn measure(
    model: &MotionModel,
    progress: &dyn motion_lod::progress::Progress,
) -> Result<Option<(QualityReference, Vec<QualityPoint>)>> {
    let Some(reference) = model.report.quality.clone() else {
        return Ok(None);
    };
    let grid = walk_quality::walk_grid(model);
    let levels = model.lod().levels().len();
    progress.stage("motion quality per level", (levels * grid.len()) as u64);
    let mut points = Vec::with_capacity(levels * grid.len());
    for level in 0..levels {
        for walk in &grid {
            let req = WalkRequest {
                controls: walk.controls,
                detail: Detail::new(level, model.lod().joints()),
                cycles: CYCLES,
                fps: 30.0,
                blend: true,
                plant_feet: true,
            };
            let w = model
                .synthesize_walk(&req)
                .with_context(|| format!("synthesizing `{}` at level {level}", walk.name))?;
            let q = walk_quality::measure_walk(model, &w)
                .with_context(|| format!("measuring `{}` at level {level}", walk.name))?;
            points.push(QualityPoint {
                walk: walk.clone(),
                level,
                quality: q,
            });
            progress.inc(1);
        }
    }
    Ok(Some((reference, points)))
}

/// Worst and median of `v` (NaN for none).
fn worst_median(mut v: Vec<f64>) -> (f64, f64) {
    if v.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let worst = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    (worst, quality::median(&mut v))
}

/// Per level: `(level, worst pop ratio, median pop ratio, worst skate ratio, median skate ratio,
/// worst seam pop ratio, largest |floor offset| cm, walks facing outside the data's range)`.
pub type LevelRow = (usize, f64, f64, f64, f64, f64, f64, usize);

/// The per-level summary rows of `points`.
pub fn level_rows(reference: &QualityReference, points: &[QualityPoint]) -> Vec<LevelRow> {
    let (lo, hi) = reference.facing_range_deg;
    let levels = points.iter().map(|p| p.level + 1).max().unwrap_or(0);
    (0..levels)
        .map(|l| {
            // Each walk against the data's takes of similar step length.
            let at: Vec<(&MotionQuality, MotionQuality)> = points
                .iter()
                .filter(|p| p.level == l)
                .map(|p| (&p.quality, reference.at_controls(&p.walk.controls)))
                .collect();
            let (pop_w, pop_m) =
                worst_median(at.iter().map(|(q, d)| q.pop_cm / d.pop_cm).collect());
            let (sk_w, sk_m) = worst_median(
                at.iter()
                    .map(|(q, d)| q.skate_cm_s / d.skate_cm_s)
                    .collect(),
            );
            let (seam_w, _) =
                worst_median(at.iter().map(|(q, d)| q.seam_pop_cm / d.pop_cm).collect());
            let floor = at
                .iter()
                .map(|(q, _)| q.floor_offset_cm.abs())
                .fold(0.0, f64::max);
            let facing_out = at
                .iter()
                .filter(|(q, _)| q.facing_min_deg < lo || q.facing_max_deg > hi)
                .count();
            (l, pop_w, pop_m, sk_w, sk_m, seam_w, floor, facing_out)
        })
        .collect()
}

/// The markdown section (`figure_link`: the figure's path relative to the document).
pub fn section(
    model: &MotionModel,
    reference: &QualityReference,
    points: &[QualityPoint],
    figure_link: &str,
) -> String {
    let m = &reference.median;
    let walks = points.iter().filter(|p| p.level == 0).count();
    let mut doc = String::new();
    let _ = writeln!(
        doc,
        "\n## 7. Motion quality per accuracy level\n\n![Motion quality]({figure_link})\n\n\
         The motion-quality meter (`motion_lod::quality`, by forward kinematics) over {walks} walks of \
         {CYCLES} cycles at 30 fps covering the data's controls (straight, turns of +-30 degrees, \
         sidesteps of +-0.3 m, slow, fast, the corners of the control hull and its edges along turn \
         and sidestep from the median straight walk), all {} joints, seams inertialized and feet \
         planted. Ratios are to the data's own takes of similar step length (the median of the takes \
         whose mean step is within 10% of the walk's, the 9 nearest when fewer: the data's pop and \
         skate grow with the step; all {} takes: pop {:.2} cm/frame² at 30 fps, skate {:.2} cm/s, \
         facing range {:.1}..{:.1} deg). The issue's thresholds for near \
         characters: pop at most 1.25x, skate at most 1.5x, floor within 1 cm, facing inside the \
         data's range. *Used*: whether the policies give the level to walkers with joints (level 0, \
         or a level within the pop, skate and floor thresholds as the build measured it: \
         `motion-lod info`'s `used` column). The same command per walk: `motion-lod quality MODEL`.\n",
        model.lod().joints(),
        reference.takes,
        m.pop_cm,
        m.skate_cm_s,
        reference.facing_range_deg.0,
        reference.facing_range_deg.1
    );
    let _ = writeln!(
        doc,
        "| level | pop worst (x data) | pop median | seam pop worst | skate worst (x data) | skate median | largest floor offset (cm) | walks facing outside the data | used |\n\
         | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |"
    );
    for (l, pw, pm, sw, sm, seam, floor, out) in level_rows(reference, points) {
        let used = model.lod().level_serves_joints(l);
        let used = if used { "yes" } else { "no" };
        let _ = writeln!(
            doc,
            "| {l} | {pw:.2} | {pm:.2} | {seam:.2} | {sw:.2} | {sm:.2} | {floor:.2} | {out} | {used} |"
        );
    }
    doc
}

/// Walkers and simulated seconds of the crowd measurement (the `motion-lod quality --crowd`
/// defaults).
pub const CROWD_WALKERS: usize = 200;
/// Walkers per square metre of the crowd measurement.
pub const CROWD_DENSITY: f32 = 0.01;
/// Simulated seconds of the crowd measurement.
pub const CROWD_SECONDS: f32 = 10.0;

/// Crowd walkers measured as the crowd plays them, per scene (ground, overview):
/// [`motion_lod::crowd::crowd_quality`] under the distance policy.
pub fn measure_crowd(
    model: &MotionModel,
    progress: &dyn motion_lod::progress::Progress,
) -> Result<Vec<(&'static str, Vec<motion_lod::crowd::WalkerQuality>)>> {
    use motion_lod::crowd_sim::{CrowdConfig, Scene};
    progress.stage("motion quality of crowd walkers", 2);
    let policy = lod_policy::DistancePolicy::for_model(model.lod());
    let mut out = Vec::new();
    for (name, scene) in [("ground", Scene::Ground), ("overview", Scene::Overview)] {
        let config = CrowdConfig::with_density(CROWD_WALKERS, CROWD_DENSITY);
        let walkers =
            motion_lod::crowd::crowd_quality(model, config, scene, &policy, CROWD_SECONDS)
                .with_context(|| format!("measuring the crowd walkers ({name} camera)"))?;
        out.push((name, walkers));
        progress.inc(1);
    }
    Ok(out)
}

/// The joint count from which both legs (thigh, knee and ankle of each foot) are evaluated, the
/// joints the foot lock needs; the model's joint count without feet.
pub fn leg_joints(model: &MotionModel) -> usize {
    let order = model.layout.joint_order();
    let sk = model.layout.skeleton();
    let Some(feet) = model.feet() else {
        return order.len();
    };
    let mut needed = 0;
    for foot in [feet.left, feet.right] {
        let mut j = Some(foot.ankle);
        for _ in 0..3 {
            let Some(k) = j else { break };
            if let Some(at) = order.iter().position(|&o| o == k) {
                needed = needed.max(at + 1);
            }
            j = sk.joints[k].parent;
        }
    }
    needed
}

/// The markdown subsection of the crowd measurement: per scene, the walkers with both legs
/// evaluated and those with fewer joints, each group with the levels its walkers showed.
pub fn crowd_section(
    model: &MotionModel,
    reference: &QualityReference,
    scenes: &[(&'static str, Vec<motion_lod::crowd::WalkerQuality>)],
) -> String {
    let m = &reference.median;
    let legs = leg_joints(model);
    let mut doc = String::new();
    let _ = writeln!(
        doc,
        "\n### Crowd walkers as the crowd plays them\n\n\
         {CROWD_WALKERS} walkers at {CROWD_DENSITY} per m² for {CROWD_SECONDS} s at 30 fps under the distance \
         policy, each measured over its longest stretch drawn (in view, with joints; after its first seam, at \
         least two cycles): controls change every cycle along the walkers' paths and levels change \
         with distance. Every walker with joints inertializes its seams and plants its feet (the \
         runtime foot lock), at whatever level; the policies give walkers with joints only the \
         levels that pass the quality grid (section 7's last column). *Legs evaluated*: the walker \
         showed at least the {legs} joints that evaluate both legs (the foot lock's); with fewer, the \
         legs hold their mean rotation, where the policies keep the slide under a pixel. *Levels*: \
         the accuracy levels the group's walkers showed. *Floor worst*: the largest floor offset (cm, \
         + = above). The same command: `motion-lod quality MODEL --crowd --camera ground|overview`.\n\n\
         | camera | walkers | group | levels | pop worst (x data) | pop median | seam pop worst | skate worst (x data) | skate median | floor worst |\n\
         | --- | ---: | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |"
    );
    for (scene, walkers) in scenes {
        for (group, with_legs) in [("legs evaluated", true), ("fewer joints", false)] {
            let at: Vec<&motion_lod::crowd::WalkerQuality> = walkers
                .iter()
                .filter(|w| (w.joints.0 >= legs) == with_legs)
                .collect();
            if at.is_empty() {
                continue;
            }
            let lo = at.iter().map(|w| w.levels.0).min().unwrap_or(0);
            let hi = at.iter().map(|w| w.levels.1).max().unwrap_or(0);
            let q: Vec<&MotionQuality> = at.iter().map(|w| &w.quality).collect();
            let (pw, pm) = worst_median(q.iter().map(|q| q.pop_cm / m.pop_cm).collect());
            let (seam, _) = worst_median(q.iter().map(|q| q.seam_pop_cm / m.pop_cm).collect());
            let (sw, sm) = worst_median(q.iter().map(|q| q.skate_cm_s / m.skate_cm_s).collect());
            let floor = q
                .iter()
                .map(|q| q.floor_offset_cm)
                .fold(0.0f64, |a, b| if b.abs() > a.abs() { b } else { a });
            let levels = if lo == hi {
                format!("{lo}")
            } else {
                format!("{lo}-{hi}")
            };
            let _ = writeln!(
                doc,
                "| {scene} | {} | {group} | {levels} | {pw:.2} | {pm:.2} | {seam:.2} | {sw:.2} | {sm:.2} | {floor:.2} |",
                q.len()
            );
        }
    }
    doc
}
