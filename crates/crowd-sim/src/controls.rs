//! The small value types exchanged with a [`ClipSource`](crate::ClipSource): controls, control
//! bounds, the detail of a clip, the source's level table and a clip's root motion.
//!
//! Conventions (same as `docs/architecture.md`): metres and radians, y up, +z forward, +x to the
//! character's left, positive turn = turn left (a positive rotation about +y).

use crate::error::CrowdError;

/// Control parameters of one gait cycle, `c = (dx, dz, turn, height)`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Controls {
    /// Root displacement to the left over the cycle, in the start heading frame (m).
    pub dx: f32,
    /// Root displacement forward over the cycle, in the start heading frame (m).
    pub dz: f32,
    /// Heading change over the cycle (rad, positive = left).
    pub turn: f32,
    /// Standing height of the character (m).
    pub height: f32,
}

/// Per-dimension range of controls the source covers; controls outside are clamped into it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControlBounds {
    /// Smallest value of each control.
    pub min: Controls,
    /// Largest value of each control.
    pub max: Controls,
}

impl ControlBounds {
    /// Clamps each control into `[min, max]` (NaN controls become the range's midpoint).
    pub fn clamp(&self, c: &Controls) -> Controls {
        fn cl(v: f32, lo: f32, hi: f32) -> f32 {
            if v.is_nan() {
                0.5 * (lo + hi)
            } else {
                v.clamp(lo, hi)
            }
        }
        Controls {
            dx: cl(c.dx, self.min.dx, self.max.dx),
            dz: cl(c.dz, self.min.dz, self.max.dz),
            turn: cl(c.turn, self.min.turn, self.max.turn),
            height: cl(c.height, self.min.height, self.max.height),
        }
    }

    /// Checks that every bound is finite, `min <= max`, walkers can move forward (`max.dz > 0`),
    /// turn both ways (`min.turn < 0 < max.turn`) and have a positive height.
    pub fn validate(&self) -> Result<(), CrowdError> {
        let all = [
            self.min.dx,
            self.min.dz,
            self.min.turn,
            self.min.height,
            self.max.dx,
            self.max.dz,
            self.max.turn,
            self.max.height,
        ];
        let bad = |what| Err(CrowdError::BadControlBounds { what });
        if all.iter().any(|v| !v.is_finite()) {
            return bad("a bound is NaN or infinite");
        }
        if self.min.dx > self.max.dx
            || self.min.dz > self.max.dz
            || self.min.turn > self.max.turn
            || self.min.height > self.max.height
        {
            return bad("min > max");
        }
        if self.max.dz <= 0.0 {
            return bad("max.dz <= 0: walkers cannot move forward");
        }
        if !(self.min.turn < 0.0 && self.max.turn > 0.0) {
            return bad("turn range must contain both left and right turns");
        }
        if self.min.height <= 0.0 {
            return bad("min.height <= 0");
        }
        Ok(())
    }
}

/// How much of a clip to compute: an accuracy level and how many joints beyond the root.
///
/// `accuracy` 0 is the finest level; `active_joints` 0 means root only (position and orientation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Detail {
    /// Accuracy level, 0 = most accurate, `LevelTable::accuracy_levels - 1` = coarsest.
    pub accuracy: usize,
    /// Number of joints other than the root whose rotations are evaluated.
    pub active_joints: usize,
}

impl Detail {
    /// Root-only detail at the coarsest accuracy of a source with `levels` accuracy levels.
    pub fn root_only(levels: &LevelTable) -> Self {
        Self {
            accuracy: levels.accuracy_levels.saturating_sub(1),
            active_joints: 0,
        }
    }

    /// True when `self` asks for more than `held` provides (finer accuracy or more joints).
    pub fn is_finer_than(&self, held: &Detail) -> bool {
        self.accuracy < held.accuracy || self.active_joints > held.active_joints
    }
}

/// What a source offers: accuracy levels, joints and pose vector length.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LevelTable {
    /// Number of accuracy levels (at least 1).
    pub accuracy_levels: usize,
    /// Number of joints besides the root that can be active; joint position buffers hold
    /// `1 + joints` entries (root at index 0).
    pub joints: usize,
    /// Length of a full pose vector (rows written by `ClipSource::pose` at full detail).
    pub pose_len: usize,
}

impl LevelTable {
    /// Number of bins of a level histogram: one per accuracy level, plus one (the last) for
    /// root-only walkers.
    pub fn histogram_bins(&self) -> usize {
        self.accuracy_levels + 1
    }

    /// Histogram bin of a detail: its accuracy level, or the last bin when root-only.
    pub fn bin(&self, d: &Detail) -> usize {
        if d.active_joints == 0 {
            self.accuracy_levels
        } else {
            d.accuracy.min(self.accuracy_levels - 1)
        }
    }
}

/// Motion of the root over a whole clip, in the clip's start cycle frame: the runtime's
/// [`lod_policy::RootMotion`] (ground displacement and travel turn).
pub use lod_policy::RootMotion;

#[cfg(test)]
mod tests {
    use super::*;

    fn bounds() -> ControlBounds {
        ControlBounds {
            min: Controls {
                dx: -0.3,
                dz: 0.5,
                turn: -1.0,
                height: 1.5,
            },
            max: Controls {
                dx: 0.3,
                dz: 1.8,
                turn: 1.0,
                height: 1.9,
            },
        }
    }

    #[test]
    fn clamp_limits_each_dimension_and_replaces_nan() {
        let b = bounds();
        let c = b.clamp(&Controls {
            dx: 5.0,
            dz: -1.0,
            turn: f32::NAN,
            height: 1.7,
        });
        assert_eq!(
            c,
            Controls {
                dx: 0.3,
                dz: 0.5,
                turn: 0.0,
                height: 1.7
            }
        );
    }

    #[test]
    fn validate_rejects_bad_bounds() {
        assert!(bounds().validate().is_ok());
        let mut b = bounds();
        b.max.turn = f32::NAN;
        assert!(b.validate().is_err());
        let mut b = bounds();
        b.min.dz = 3.0;
        assert!(b.validate().is_err());
        let mut b = bounds();
        b.min.turn = 0.1;
        assert!(b.validate().is_err());
    }

    #[test]
    fn histogram_bin_puts_root_only_last() {
        let t = LevelTable {
            accuracy_levels: 4,
            joints: 10,
            pose_len: 37,
        };
        assert_eq!(
            t.bin(&Detail {
                accuracy: 2,
                active_joints: 3
            }),
            2
        );
        assert_eq!(
            t.bin(&Detail {
                accuracy: 2,
                active_joints: 0
            }),
            4
        );
        assert_eq!(t.histogram_bins(), 5);
    }
}
