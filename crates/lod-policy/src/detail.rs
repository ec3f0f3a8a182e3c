//! The level of detail of one clip ([`Detail`]): the one type the policies return, the crowd
//! schedules and the clip sources build.

use serde::{Deserialize, Serialize};

use crate::model::LodModel;

/// Level of detail of one clip: an accuracy level and the number of evaluated joints.
///
/// A policy may answer with [`Detail::SMALLEST`] and with more joints than a model has (e.g.
/// [`Detail::full`]); [`Detail::resolve`] turns that into a concrete level and joint count for a
/// table of `levels` accuracy levels and `joints` joints, the one place both are resolved.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
pub struct Detail {
    /// Index into the model's accuracy levels (0 = most accurate), or [`Detail::SMALLEST`].
    pub accuracy: usize,
    /// Joints evaluated after the always-evaluated root rows (0 = root only); values above the
    /// model's joint count mean all joints.
    pub active_joints: usize,
}

impl Detail {
    /// Sentinel accuracy index selecting the model's smallest (last) accuracy level.
    pub const SMALLEST: usize = usize::MAX;

    /// Full detail: the most accurate level and every joint.
    pub const fn full() -> Detail {
        Detail {
            accuracy: 0,
            active_joints: usize::MAX,
        }
    }

    /// Root only: rows `0..7` (root position, root orientation, time increment) at the smallest
    /// accuracy level; every other row takes the mean pose.
    pub const fn root_only() -> Detail {
        Detail {
            accuracy: Detail::SMALLEST,
            active_joints: 0,
        }
    }

    /// Builds a detail.
    pub const fn new(accuracy: usize, active_joints: usize) -> Detail {
        Detail {
            accuracy,
            active_joints,
        }
    }

    /// This detail for a table of `levels` accuracy levels and `joints` joints:
    /// [`Detail::SMALLEST`] becomes `levels - 1` and the joint count is clamped to `joints`.
    /// `None` when the accuracy level is out of range (or there are no levels).
    pub fn resolve(&self, levels: usize, joints: usize) -> Option<Detail> {
        let accuracy = if self.accuracy == Detail::SMALLEST {
            levels.checked_sub(1)?
        } else if self.accuracy < levels {
            self.accuracy
        } else {
            return None;
        };
        Some(Detail {
            accuracy,
            active_joints: self.active_joints.min(joints),
        })
    }

    /// The accuracy level index this detail selects in `model` ([`Detail::resolve`]), or `None`
    /// when it is out of range.
    pub fn level_in(&self, model: &LodModel) -> Option<usize> {
        self.resolve(model.levels().len(), model.joints())
            .map(|d| d.accuracy)
    }

    /// The detail a clip source evaluates for this one: a root-only detail (no joints) at the
    /// smallest level, [`Detail::root_only`], whatever level the policy gave it (every root-only
    /// clip is then the same, and the cheapest); any other detail as it is.
    pub fn evaluated(&self) -> Detail {
        if self.active_joints == 0 {
            Detail::root_only()
        } else {
            *self
        }
    }

    /// True when `self` asks for more than `held` provides (a finer accuracy level or more joints).
    pub fn is_finer_than(&self, held: &Detail) -> bool {
        self.accuracy < held.accuracy || self.active_joints > held.active_joints
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resolve_maps_the_sentinel_and_clamps_joints() {
        assert_eq!(Detail::root_only().resolve(4, 9), Some(Detail::new(3, 0)));
        assert_eq!(Detail::full().resolve(4, 9), Some(Detail::new(0, 9)));
        assert_eq!(Detail::new(2, 5).resolve(4, 9), Some(Detail::new(2, 5)));
        assert_eq!(Detail::new(4, 5).resolve(4, 9), None);
        assert_eq!(Detail::root_only().resolve(0, 9), None);
    }

    #[test]
    fn finer_compares_level_and_joints() {
        let held = Detail::new(2, 5);
        assert!(Detail::new(1, 5).is_finer_than(&held));
        assert!(Detail::new(2, 6).is_finer_than(&held));
        assert!(!Detail::new(3, 5).is_finer_than(&held));
        assert!(!held.is_finer_than(&held));
    }

    #[test]
    fn root_only_details_evaluate_at_the_smallest_level() {
        assert_eq!(Detail::new(2, 0).evaluated(), Detail::root_only());
        assert_eq!(Detail::new(2, 1).evaluated(), Detail::new(2, 1));
    }
}
