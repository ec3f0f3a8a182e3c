//! The level of detail of one clip ([`Detail`]): the one type the policies return, the crowd
//! schedules and the clip sources build.

use serde::{Deserialize, Serialize};

/// Level of detail of one clip: an accuracy level and the number of evaluated joints, both
/// concrete for the model they were made for (no sentinels).
///
/// The policies resolve a character's detail once, against their model's levels and joints
/// ([`crate::LevelPolicy::detail`]); [`crate::LodModel::full_detail`] and
/// [`crate::LodModel::root_only`] give the two ends, and [`Detail::fits`] checks a detail made
/// elsewhere against a table of levels and joints. A clip build refuses a detail its model does not
/// have ([`crate::KernelError::Level`], [`crate::KernelError::Joints`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
pub struct Detail {
    /// Index into the model's accuracy levels (0 = most accurate).
    pub accuracy: usize,
    /// Joints evaluated after the always-evaluated root rows (0 = root only), at most the model's
    /// joint count.
    pub active_joints: usize,
}

impl Detail {
    /// Builds a detail.
    pub const fn new(accuracy: usize, active_joints: usize) -> Detail {
        Detail {
            accuracy,
            active_joints,
        }
    }

    /// True when this detail exists in a table of `levels` accuracy levels and `joints` joints:
    /// `accuracy < levels` and `active_joints <= joints`.
    pub fn fits(&self, levels: usize, joints: usize) -> bool {
        self.accuracy < levels && self.active_joints <= joints
    }

    /// True when the detail evaluates the root alone (no joints).
    pub fn is_root_only(&self) -> bool {
        self.active_joints == 0
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
    fn fits_checks_level_and_joints() {
        assert!(Detail::new(3, 0).fits(4, 9));
        assert!(Detail::new(0, 9).fits(4, 9));
        assert!(!Detail::new(4, 5).fits(4, 9));
        assert!(!Detail::new(0, 10).fits(4, 9));
        assert!(!Detail::new(0, 0).fits(0, 9));
    }

    #[test]
    fn finer_compares_level_and_joints() {
        let held = Detail::new(2, 5);
        assert!(Detail::new(1, 5).is_finer_than(&held));
        assert!(Detail::new(2, 6).is_finer_than(&held));
        assert!(!Detail::new(3, 5).is_finer_than(&held));
        assert!(!held.is_finer_than(&held));
    }
}
