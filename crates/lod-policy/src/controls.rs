//! The runtime's controls: what a gait cycle is asked to do, `c = (dx, dz, turn, height)`.
//!
//! Mukai and Kuriyama parameterise each sample of the motion tensor by the controls of one gait
//! cycle (two steps): where the root goes over the cycle, how much the heading turns, and the
//! character's body height. Every runtime consumer (clip kernels, the crowd, `synth`, the CLI)
//! speaks [`Controls`]; the offline cycle analysis measures them in `f64`
//! (`motion_io::MeasuredControls`), and [`Controls::from_f64`] is the one conversion.
//!
//! Conventions (`docs/architecture.md`): metres and radians, y up, +z forward, +x to the
//! character's left, positive turn = turn left (a positive rotation about +y). The model's own
//! scaling of the control space (offsets, scales, variogram) is [`ControlSpace`], a different
//! thing: plain data of the kriging, not a request.

use serde::{Deserialize, Serialize};

use crate::model::ControlSpace;

/// Controls of one gait cycle (two steps), the paper's `c`; the model's control dimensions in this
/// order ([`Controls::NAMES`]).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Controls {
    /// Root displacement to the character's left over the cycle, in the start heading frame (m).
    pub dx: f32,
    /// Root displacement forward over the cycle, in the start heading frame (m).
    pub dz: f32,
    /// Heading change of the direction of travel over the cycle (rad, positive = left).
    pub turn: f32,
    /// Standing height of the character's skeleton (m).
    pub height: f32,
}

impl Controls {
    /// Number of control dimensions.
    pub const COUNT: usize = 4;
    /// Name of each dimension, in array order.
    pub const NAMES: [&'static str; 4] = ["dx", "dz", "turn", "height"];
    /// Unit of each dimension, in array order.
    pub const UNITS: [&'static str; 4] = ["m", "m", "rad", "m"];
    /// `name (unit)` of each dimension, in array order, for tables and reports.
    pub const LABELS: [&'static str; 4] = ["dx (m)", "dz (m)", "turn (rad)", "height (m)"];

    /// Controls from `[dx, dz, turn, height]`.
    pub const fn from_array(a: [f32; 4]) -> Controls {
        Controls {
            dx: a[0],
            dz: a[1],
            turn: a[2],
            height: a[3],
        }
    }

    /// Controls from `[dx, dz, turn, height]` in `f64`, as the offline analysis measures them
    /// (`motion_io::MeasuredControls::to_array`, `motion_lod::Analysis::controls`), rounded to `f32`: the
    /// one conversion from measured to runtime controls.
    pub fn from_f64(a: [f64; 4]) -> Controls {
        Controls::from_array(a.map(|v| v as f32))
    }

    /// `[dx, dz, turn, height]`: the raw control vector the kernel takes
    /// ([`LodModel::build_kernel`](crate::LodModel::build_kernel)).
    pub const fn to_array(&self) -> [f32; 4] {
        [self.dx, self.dz, self.turn, self.height]
    }
}

/// Clamps one control value into `[lo, hi]`; NaN becomes the midpoint. The one clamp of controls
/// into a model's range ([`ControlRange::clamp`]).
pub fn clamp_control(v: f32, lo: f32, hi: f32) -> f32 {
    if v.is_nan() {
        0.5 * (lo + hi)
    } else {
        v.clamp(lo, hi)
    }
}

/// A per-dimension range of controls, e.g. what a model's training data cover.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct ControlRange {
    /// Smallest value of each control.
    pub min: Controls,
    /// Largest value of each control.
    pub max: Controls,
}

impl ControlRange {
    /// Each control clamped into `[min, max]` ([`clamp_control`]: NaN becomes the midpoint).
    pub fn clamp(&self, c: &Controls) -> Controls {
        let (v, lo, hi) = (c.to_array(), self.min.to_array(), self.max.to_array());
        Controls::from_array(std::array::from_fn(|k| clamp_control(v[k], lo[k], hi[k])))
    }

    /// Whether every control lies in `[min, max]` (false for NaN).
    pub fn contains(&self, c: &Controls) -> bool {
        let (v, lo, hi) = (c.to_array(), self.min.to_array(), self.max.to_array());
        (0..Controls::COUNT).all(|k| lo[k] <= v[k] && v[k] <= hi[k])
    }

    /// The first problem of the range as a phrase, if any: a non-finite bound or `min > max`.
    pub fn problem(&self) -> Option<&'static str> {
        let (lo, hi) = (self.min.to_array(), self.max.to_array());
        if lo.iter().chain(&hi).any(|v| !v.is_finite()) {
            Some("a bound is NaN or infinite")
        } else if (0..Controls::COUNT).any(|k| lo[k] > hi[k]) {
            Some("min > max")
        } else {
            None
        }
    }
}

impl ControlSpace {
    /// The range of the raw sample controls as [`Controls`], or `None` when the model does not
    /// have the four control dimensions of [`Controls::NAMES`].
    pub fn range(&self) -> Option<ControlRange> {
        let (lo, hi) = (
            <[f32; 4]>::try_from(self.min.as_slice()).ok()?,
            <[f32; 4]>::try_from(self.max.as_slice()).ok()?,
        );
        Some(ControlRange {
            min: Controls::from_array(lo),
            max: Controls::from_array(hi),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn range() -> ControlRange {
        ControlRange {
            min: Controls::from_array([-0.3, 0.5, -1.0, 1.5]),
            max: Controls::from_array([0.3, 1.8, 1.0, 1.9]),
        }
    }

    #[test]
    fn array_round_trip_keeps_the_named_order() {
        let c = Controls::from_array([0.1, 1.2, -0.3, 1.7]);
        assert_eq!((c.dx, c.dz, c.turn, c.height), (0.1, 1.2, -0.3, 1.7));
        assert_eq!(c.to_array(), [0.1, 1.2, -0.3, 1.7]);
        for (k, label) in Controls::LABELS.iter().enumerate() {
            assert_eq!(
                *label,
                format!("{} ({})", Controls::NAMES[k], Controls::UNITS[k])
            );
        }
    }

    #[test]
    fn clamp_limits_each_dimension_and_replaces_nan() {
        let r = range();
        let c = r.clamp(&Controls::from_array([5.0, -1.0, f32::NAN, 1.7]));
        assert_eq!(c, Controls::from_array([0.3, 0.5, 0.0, 1.7]));
        assert!(r.contains(&c));
        assert!(!r.contains(&Controls::from_array([0.0, 1.0, f32::NAN, 1.7])));
    }

    #[test]
    fn problem_names_bad_ranges() {
        assert_eq!(range().problem(), None);
        let mut r = range();
        r.max.turn = f32::INFINITY;
        assert!(r.problem().is_some());
        let mut r = range();
        r.min.dz = 3.0;
        assert_eq!(r.problem(), Some("min > max"));
    }
}
