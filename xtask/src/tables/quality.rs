//! Section 7: the motion-quality meter ([`motion_lod::quality`]) per accuracy level over the grid of
//! walks covering the data's controls, as ratios to the data's own takes, and the figure of pop and
//! skate against the level and against the walk's step length.

use std::fmt::Write as _;

use anyhow::{Context as _, Result};
use lod_policy::Detail;
use motion_lod::MotionModel;
use motion_lod::quality::{self, GridWalk, MotionQuality, QualityReference};
use motion_lod::synth::WalkRequest;

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
    let grid = quality::walk_grid(model);
    let levels = model.lod.levels().len();
    progress.stage("motion quality per level", (levels * grid.len()) as u64);
    let mut points = Vec::with_capacity(levels * grid.len());
    for level in 0..levels {
        for walk in &grid {
            let req = WalkRequest {
                controls: lod_policy::Controls::from_array(walk.controls),
                detail: Detail::new(level, model.lod.joints()),
                cycles: CYCLES,
                fps: 30.0,
                blend: true,
                plant_feet: true,
            };
            let w = model
                .synthesize_walk(&req)
                .with_context(|| format!("synthesizing `{}` at level {level}", walk.name))?;
            let q = quality::measure_walk(model, &w)
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
    let m = &reference.median;
    let (lo, hi) = reference.facing_range_deg;
    let levels = points.iter().map(|p| p.level + 1).max().unwrap_or(0);
    (0..levels)
        .map(|l| {
            let at: Vec<&MotionQuality> = points
                .iter()
                .filter(|p| p.level == l)
                .map(|p| &p.quality)
                .collect();
            let (pop_w, pop_m) = worst_median(at.iter().map(|q| q.pop_cm / m.pop_cm).collect());
            let (sk_w, sk_m) =
                worst_median(at.iter().map(|q| q.skate_cm_s / m.skate_cm_s).collect());
            let (seam_w, _) = worst_median(at.iter().map(|q| q.seam_pop_cm / m.pop_cm).collect());
            let floor = at
                .iter()
                .map(|q| q.floor_offset_cm.abs())
                .fold(0.0, f64::max);
            let facing_out = at
                .iter()
                .filter(|q| q.facing_min_deg < lo || q.facing_max_deg > hi)
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
         sidesteps of +-0.3 m, slow, fast and the corners of the control hull), all {} joints, seams \
         inertialized and feet planted. Ratios are to the median of the data's own takes ({} takes: \
         pop {:.2} cm/frame² at 30 fps, skate {:.2} cm/s, facing range {:.1}..{:.1} deg). The issue's \
         thresholds for near characters: pop at most 1.25x, skate at most 1.5x, floor within 1 cm, \
         facing inside the data's range. The same command per walk: `motion-lod quality MODEL`.\n",
        model.lod.joints(),
        reference.takes,
        m.pop_cm,
        m.skate_cm_s,
        reference.facing_range_deg.0,
        reference.facing_range_deg.1
    );
    let _ = writeln!(
        doc,
        "| level | pop worst (x data) | pop median | seam pop worst | skate worst (x data) | skate median | largest floor offset (cm) | walks facing outside the data |\n\
         | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
    );
    for (l, pw, pm, sw, sm, seam, floor, out) in level_rows(reference, points) {
        let _ = writeln!(
            doc,
            "| {l} | {pw:.2} | {pm:.2} | {seam:.2} | {sw:.2} | {sm:.2} | {floor:.2} | {out} |"
        );
    }
    doc
}
