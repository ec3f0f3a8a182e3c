//! The motion-quality meter ([`crate::quality`]) applied to the model's own walks: the grid of
//! walks that covers the data's controls ([`walk_grid`]) and the measure of a synthesized walk
//! against the model's reference ([`measure_walk`]). Crowd tracks are measured by
//! [`crate::crowd::measure_track`].

use lod_policy::Controls;
use motion_io::PoseLayout;
use serde::{Deserialize, Serialize};

use crate::model::MotionModel;
use crate::quality::{MotionQuality, QualityError, QualityReference, measure};
use crate::synth::Walk;

/// A named walk of the quality grid: controls `(dx m, dz m, turn rad, height m)`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GridWalk {
    /// What the walk is (`straight`, `turn +30`, `corner +turn`, ...).
    pub name: String,
    /// Controls of every cycle.
    pub controls: Controls,
    /// Whether the controls lie inside the data's hull ([`crate::hull::ControlHull::contains`]).
    /// A walk outside it is measured and shown but held to no threshold: the model extrapolates
    /// there, and `synth` warns (the fixed turns and sidesteps can leave the hull: Bandai's turns of
    /// 30 degrees at the median step lie just beyond it).
    #[serde(default)]
    pub in_hull: bool,
}

/// The walks the `quality` command and the tables measure, covering the data's hull: straight at the
/// data's median step, turns of 30 degrees both ways and sidesteps of 0.3 m (each pulled inside the
/// data's range), slow and fast (the 10th and 90th percentile of dz), and the training samples that
/// reach furthest along each of the six control directions (`+-dx`, `+-dz`, `+-turn`, in units of each
/// control's range, at the sample's own height): the corners of the hull, inside it by
/// construction; and the hull's edges
/// ([`crate::hull::ControlHull::edge`]) from the median straight walk along turn and sidestep, each
/// way: the sharpest turn and the widest sidestep the data hold at the median step. Each walk says
/// whether it lies inside the hull ([`GridWalk::in_hull`]); the motion-quality thresholds hold
/// inside it.
pub fn walk_grid(model: &MotionModel) -> Vec<GridWalk> {
    let cs = model.lod().controls();
    let s = model.lod().s();
    let d = model.lod().d();
    let raw = |i: usize, k: usize| -> f32 {
        if cs.scale[k] > 0.0 {
            cs.samples[i + s * k] / cs.scale[k] + cs.offset[k]
        } else {
            cs.offset[k]
        }
    };
    let pct = |k: usize, q: f64| -> f32 {
        let mut v: Vec<f64> = (0..s).map(|i| f64::from(raw(i, k))).collect();
        v.sort_by(f64::total_cmp);
        v[((q * (s - 1) as f64).round() as usize).min(s - 1)] as f32
    };
    let height = 0.5 * (cs.min[3] + cs.max[3]);
    let n_styles = cs.style_count();
    let dz = pct(1, 0.5);
    let inside = |k: usize, v: f32| v.clamp(0.9 * cs.min[k], 0.9 * cs.max[k]);
    let mut grid: Vec<(String, [f32; 4], Option<lod_policy::StyleMix>)> = vec![
        ("straight".to_string(), [0.0, dz, 0.0, height], None),
        (
            "turn +30".into(),
            [0.0, dz, inside(2, 30f32.to_radians()), height],
            None,
        ),
        (
            "turn -30".into(),
            [0.0, dz, inside(2, -30f32.to_radians()), height],
            None,
        ),
        (
            "sidestep +0.3".into(),
            [inside(0, 0.3), dz, 0.0, height],
            None,
        ),
        (
            "sidestep -0.3".into(),
            [inside(0, -0.3), dz, 0.0, height],
            None,
        ),
        ("slow".into(), [0.0, pct(1, 0.1), 0.0, height], None),
        ("fast".into(), [0.0, pct(1, 0.9), 0.0, height], None),
    ];
    for (k, name) in lod_policy::Controls::NAMES.into_iter().enumerate().take(3) {
        if k >= d || cs.max[k] <= cs.min[k] {
            continue;
        }
        for sign in [1.0f32, -1.0] {
            let span = |k: usize| (cs.max[k] - cs.min[k]).max(f32::EPSILON);
            // The sample furthest along +-k, ties broken by the smallest other controls.
            let best = (0..s)
                .max_by(|&a, &b| {
                    let score = |i: usize| {
                        sign * (raw(i, k) - 0.5 * (cs.min[k] + cs.max[k])) / span(k)
                            - 0.25
                                * (0..3)
                                    .filter(|&o| o != k)
                                    .map(|o| {
                                        ((raw(i, o) - 0.5 * (cs.min[o] + cs.max[o])) / span(o))
                                            .abs()
                                    })
                                    .sum::<f32>()
                    };
                    score(a).total_cmp(&score(b)).then(b.cmp(&a))
                })
                .expect("a model has samples");
            // The sample's own controls, its height included (inside the hull: a training point),
            // and in a model with styles the sample's own style (the data's mix of styles at a
            // corner that one style holds is a walk the data never did).
            let c = [raw(best, 0), raw(best, 1), raw(best, 2), raw(best, 3)];
            let style = (n_styles > 0)
                .then(|| {
                    (0..n_styles)
                        .max_by(|&a, &b| raw(best, 4 + a).total_cmp(&raw(best, 4 + b)))
                        .map(lod_policy::StyleMix::one)
                })
                .flatten();
            let sign = if sign > 0.0 { '+' } else { '-' };
            grid.push((format!("corner {sign}{name}"), c, style));
        }
    }
    // The hull's edges from the median straight walk: the sharpest turn and the widest sidestep
    // the data hold at the median step, each way.
    let hull = crate::hull::ControlHull::of(model);
    let centre = Controls::from_array([0.0, dz, 0.0, height]);
    for (k, name) in [(2usize, "turn"), (0, "sidestep")] {
        if k >= d || cs.max[k] <= cs.min[k] {
            continue;
        }
        for (sign, mark) in [(1.0f32, '+'), (-1.0, '-')] {
            let span = cs.max[k] - cs.min[k];
            let edge = hull.edge(centre, k, sign, span);
            if edge != centre {
                grid.push((format!("{name} edge {mark}"), edge.to_array(), None));
            }
        }
    }
    grid.into_iter()
        .map(|(name, controls, style)| {
            let controls = Controls::from_array(controls);
            let controls = style.map_or(controls, |st| controls.with_style(st));
            GridWalk {
                name,
                controls,
                in_hull: hull.contains(&controls),
            }
        })
        .collect()
}

/// The model's motion-quality reference, or [`QualityError::NoReference`].
pub(crate) fn reference_of(model: &MotionModel) -> Result<&QualityReference, QualityError> {
    model
        .report
        .quality
        .as_ref()
        .ok_or(QualityError::NoReference)
}

/// The model's layout at a character's body `scale` (as the model draws it).
pub(crate) fn drawn_layout(model: &MotionModel, scale: f64) -> Result<PoseLayout, QualityError> {
    model.layout.scaled(scale).map_err(|_| QualityError::Bad {
        what: "body scale",
        value: scale,
    })
}

/// Measures a synthesized walk ([`measure`]) with its cycle seams, at the body scale it is drawn
/// at: its floating and window-rule figures against the data's floor
/// ([`QualityReference::floor_m`]); its contacts and skate from its own feet. Without the model's
/// reference, [`QualityError::NoReference`]; a frame time or cycle duration that is not finite and
/// positive, [`QualityError::Bad`] (before anything is allocated); otherwise [`measure`]'s errors.
pub fn measure_walk(model: &MotionModel, walk: &Walk) -> Result<MotionQuality, QualityError> {
    let reference = reference_of(model)?;
    for (what, value) in [
        ("frame time", walk.frame_time),
        ("cycle duration", walk.cycle_seconds),
    ] {
        if !(value.is_finite() && value > 0.0) {
            return Err(QualityError::Bad { what, value });
        }
    }
    let frames = walk.poses.len() / model.layout.dof().max(1);
    // A seam per whole cycle; never more seams than frames (a cycle shorter than a frame).
    let cycles =
        ((frames as f64 * walk.frame_time / walk.cycle_seconds).floor() as usize).min(frames);
    let seams: Vec<usize> = (1..=cycles)
        .map(|c| (c as f64 * walk.cycle_seconds / walk.frame_time).round() as usize)
        .collect();
    let layout = drawn_layout(model, walk.body_scale)?;
    measure(
        &layout,
        &reference.feet,
        &walk.poses,
        walk.frame_time,
        Some(reference.floor_m),
        walk.cycle_seconds,
        &seams,
    )
}

/// The posture of a synthesized walk, measured on the model's layout scaled to the walk's body
/// ([`crate::MotionModel::walk_layout`]); `None` when the model's skeleton has no clear knees or
/// head, or the walk cannot be measured.
pub fn walk_posture(
    model: &crate::MotionModel,
    walk: &crate::synth::Walk,
) -> Option<crate::posture::Posture> {
    let joints = crate::posture::PostureJoints::find(&model.layout)?;
    let layout = model.walk_layout(walk).ok()?;
    crate::posture::measure_posture(&layout, &walk.poses, &joints)
}
