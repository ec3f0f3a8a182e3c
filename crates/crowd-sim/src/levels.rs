//! What the crowd asks of a [`ClipSource`](crate::ClipSource) besides the runtime's vocabulary
//! (`lod_policy`'s [`Controls`](lod_policy::Controls), [`ControlRange`], [`Detail`] and
//! [`RootMotion`](lod_policy::RootMotion)): the source's level table and the conditions its control
//! range must meet for walkers to follow paths.

use crate::error::CrowdError;
use lod_policy::{ControlRange, Detail};

/// Checks that a source's control range is usable by walkers: every bound finite with
/// `min <= max` ([`ControlRange::problem`]), walkers can move forward (`max.dz > 0`), turn both
/// ways (`min.turn < 0 < max.turn`) and have a positive height.
pub fn check_control_range(r: &ControlRange) -> Result<(), CrowdError> {
    let bad = |what| Err(CrowdError::BadControlRange { what });
    if let Some(what) = r.problem() {
        return bad(what);
    }
    if r.max.dz <= 0.0 {
        return bad("max.dz <= 0: walkers cannot move forward");
    }
    if !(r.min.turn < 0.0 && r.max.turn > 0.0) {
        return bad("turn range must contain both left and right turns");
    }
    if r.min.height <= 0.0 {
        return bad("min.height <= 0");
    }
    Ok(())
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
    /// A policy's `detail`, checked to exist in this table ([`Detail::fits`]); `None` for a level or
    /// a joint count the source does not have.
    pub fn check(&self, detail: &Detail) -> Option<Detail> {
        detail
            .fits(self.accuracy_levels, self.joints)
            .then_some(*detail)
    }

    /// Root only at the smallest (last) level; `None` for a table without levels.
    pub fn root_only(&self) -> Option<Detail> {
        Some(Detail::new(self.accuracy_levels.checked_sub(1)?, 0))
    }

    /// Number of bins of a level histogram: one per accuracy level, plus one (the last) for
    /// root-only walkers.
    pub fn histogram_bins(&self) -> usize {
        self.accuracy_levels.saturating_add(1)
    }

    /// Histogram bin of a detail: its accuracy level (at most the last level), or the last bin
    /// when root-only. Always below [`LevelTable::histogram_bins`]: a table without levels has
    /// one bin, 0.
    pub fn bin(&self, d: &Detail) -> usize {
        if d.active_joints == 0 {
            self.accuracy_levels
        } else {
            d.accuracy.min(self.accuracy_levels.saturating_sub(1))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ClipSource;

    fn range() -> ControlRange {
        crate::testing::ProceduralSource.control_range()
    }

    #[test]
    fn check_rejects_unusable_ranges() {
        assert!(check_control_range(&range()).is_ok());
        let mut r = range();
        r.max.turn = f32::NAN;
        assert!(check_control_range(&r).is_err());
        let mut r = range();
        r.min.dz = 3.0;
        assert!(check_control_range(&r).is_err());
        let mut r = range();
        r.min.turn = 0.1;
        assert!(check_control_range(&r).is_err());
        let mut r = range();
        r.min.height = 0.0;
        assert!(check_control_range(&r).is_err());
    }

    #[test]
    fn histogram_bin_puts_root_only_last() {
        let t = LevelTable {
            accuracy_levels: 4,
            joints: 10,
            pose_len: 37,
        };
        assert_eq!(t.bin(&Detail::new(2, 3)), 2);
        assert_eq!(t.bin(&Detail::new(2, 0)), 4);
        assert_eq!(t.histogram_bins(), 5);
        assert_eq!(t.root_only(), Some(Detail::new(3, 0)));
        assert_eq!(t.check(&Detail::new(0, 10)), Some(Detail::new(0, 10)));
        assert_eq!(t.check(&Detail::new(0, 11)), None);
        assert_eq!(t.check(&Detail::new(4, 1)), None);
        let empty = LevelTable {
            accuracy_levels: 0,
            ..t
        };
        assert_eq!(empty.root_only(), None);
    }
}
