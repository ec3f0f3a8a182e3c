//! [`PolicyTable`]: a level-of-detail policy tabulated over distance for the shaders.
//!
//! The crowd's policies ([`lod_policy::LevelPolicy`]) map `(distance, visible, view)` to a detail
//! and are piecewise constant in the distance for a given view. The host finds every distance at
//! which the detail changes, to the exact `f32` (a bisection over the bit patterns of positive
//! floats, which are ordered like the floats), so that a walker at distance `d` reads the very
//! detail the policy gives at `d`. The sweep visits 0 to 100 m every centimetre, then every 10 cm
//! to 1 km, every metre to 10 km, every 10 m to 100 km and every km to 1000 km; a policy whose
//! detail changes and changes back inside one step of that sweep is not tabulated exactly (the
//! runtime's policies change at most once per level or joint over metres).

use lod_policy::{Detail, LevelPolicy, ViewParams};

use crate::error::GpuError;
use crate::tables::POLICY_MAX;

/// The details a policy gives, as `(first distance, detail)` runs: visible walkers, then hidden.
///
/// Made by [`PolicyTable::new`] only (the fields are private), so that both run lists hold at
/// least one run, the first at distance 0, in increasing distance:
///
/// ```compile_fail
/// let empty = gpu_crowd::PolicyTable { visible: vec![], hidden: vec![] };
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct PolicyTable {
    /// Runs for walkers in view: the detail of entry `k` holds from its distance (m) up to the
    /// next entry's; the first starts at 0.
    visible: Vec<(f32, Detail)>,
    /// Runs for walkers out of view.
    hidden: Vec<(f32, Detail)>,
}

/// The distances of the sweep (see the module documentation), increasing from 0.
fn sweep() -> impl Iterator<Item = f32> {
    let bands: [(f32, f32, f32); 5] = [
        (0.0, 100.0, 0.01),
        (100.0, 1000.0, 0.1),
        (1000.0, 10_000.0, 1.0),
        (10_000.0, 100_000.0, 10.0),
        (100_000.0, 1_000_000.0, 1000.0),
    ];
    bands.into_iter().flat_map(|(lo, hi, step)| {
        let n = ((hi - lo) / step).round() as usize;
        (0..n).map(move |k| lo + k as f32 * step)
    })
}

/// The runs of `f` over the sweep, or `None` once there are more than `cap` (a policy whose
/// detail changes at nearly every distance, or one that answers differently each time it is
/// asked, would otherwise grow the list without bound).
fn runs(f: impl Fn(f32) -> Detail, cap: usize) -> Option<Vec<(f32, Detail)>> {
    let mut out = vec![(0.0f32, f(0.0))];
    let mut prev = 0.0f32;
    for x in sweep().skip(1).chain([f32::MAX]) {
        // Every change between `prev` and `x`, each at its first f32.
        while f(x) != out.last().expect("one run").1 {
            if out.len() >= cap {
                return None;
            }
            let cur = out.last().expect("one run").1;
            let (mut lo, mut hi) = (prev.to_bits(), x.to_bits());
            while hi - lo > 1 {
                let mid = lo + (hi - lo) / 2;
                if f(f32::from_bits(mid)) == cur {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let at = f32::from_bits(hi);
            out.push((at, f(at)));
            prev = at;
        }
        prev = x;
    }
    Some(out)
}

/// Every this many points of the sweep [`PolicyTable::matches`] asks the policy again.
const PROBE_EVERY: usize = 97;

impl PolicyTable {
    /// Tabulates `policy` for `view`, each detail checked against a model of `levels` accuracy
    /// levels and `joints` joints ([`Detail::fits`]).
    ///
    /// Errors: [`GpuError::Policy`] for a detail the model does not have (with the distance it
    /// was given at); [`GpuError::Config`] for a policy whose detail changes more than the GPU
    /// crowd tabulates (256 runs, visible and hidden together), found as soon as it does: a
    /// policy that changes at nearly every distance, or answers differently each time it is
    /// asked, costs bounded time and memory.
    pub fn new<P: LevelPolicy + ?Sized>(
        policy: &P,
        view: &ViewParams,
        levels: usize,
        joints: usize,
    ) -> Result<PolicyTable, GpuError> {
        let too_many = || {
            GpuError::Config(format!(
                "the level-of-detail policy changes detail more than {POLICY_MAX} times over \
                 distance (or gives a different detail each time it is asked); the GPU crowd \
                 tabulates at most {POLICY_MAX}"
            ))
        };
        // (The hidden runs take at least one entry.)
        let visible =
            runs(|d| policy.detail(d, true, view), POLICY_MAX - 1).ok_or_else(too_many)?;
        let hidden = runs(
            |d| policy.detail(d, false, view),
            POLICY_MAX - visible.len(),
        )
        .ok_or_else(too_many)?;
        let table = PolicyTable { visible, hidden };
        for &(distance_m, d) in table.visible.iter().chain(&table.hidden) {
            if !d.fits(levels, joints) {
                return Err(GpuError::Policy {
                    accuracy: d.accuracy,
                    joints: d.active_joints,
                    distance_m,
                    levels,
                    max_joints: joints,
                });
            }
        }
        Ok(table)
    }

    /// Whether `policy` still gives this table's details for `view`: at every run's first
    /// distance and the `f32` below it, and at every [`PROBE_EVERY`]-th point of the sweep. A
    /// policy that changed (another policy, or the same one with other settings) is caught
    /// unless its changes all fall between those points.
    pub(crate) fn matches<P: LevelPolicy + ?Sized>(&self, policy: &P, view: &ViewParams) -> bool {
        [(true, &self.visible), (false, &self.hidden)]
            .into_iter()
            .all(|(visible, runs)| {
                let at = |d: f32| policy.detail(d, visible, view) == self.detail(d, visible);
                runs.iter().all(|&(start, _)| {
                    at(start) && (start == 0.0 || at(f32::from_bits(start.to_bits() - 1)))
                }) && sweep().step_by(PROBE_EVERY).all(at)
            })
    }

    /// Runs for walkers in view: the detail of entry `k` holds from its distance (m) up to the
    /// next entry's; the first starts at 0 (never empty).
    pub fn visible(&self) -> &[(f32, Detail)] {
        &self.visible
    }

    /// Runs for walkers out of view, as [`PolicyTable::visible`] (never empty).
    pub fn hidden(&self) -> &[(f32, Detail)] {
        &self.hidden
    }

    /// The detail at `distance_m` (what the shaders look up; the first run's below 0 or at NaN).
    pub fn detail(&self, distance_m: f32, visible: bool) -> Detail {
        let runs = if visible { &self.visible } else { &self.hidden };
        runs.iter()
            .take_while(|(start, _)| *start <= distance_m)
            .last()
            .map_or(runs[0].1, |r| r.1)
    }

    /// The table as the shaders' uniform entries `(start bits, accuracy, joints, 0)`.
    pub(crate) fn entries(&self) -> Vec<[u32; 4]> {
        self.visible
            .iter()
            .chain(&self.hidden)
            .map(|(s, d)| [s.to_bits(), d.accuracy as u32, d.active_joints as u32, 0])
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tabulated_policy_gives_the_policy_detail_at_its_boundaries() {
        let policy = |d: f32, visible: bool, _: &ViewParams| {
            if !visible || d >= 95.3 {
                Detail::new(3, 0)
            } else if d < 30.0 {
                Detail::new(0, 10)
            } else {
                Detail::new(1, 10 - ((d - 30.0) / 10.0).floor().min(9.0) as usize)
            }
        };
        let view = ViewParams::default();
        let table = PolicyTable::new(&policy, &view, 4, 10).unwrap();
        assert_eq!(table.hidden.len(), 1);
        for d in [
            0.0, 29.999998, 30.0, 31.0, 39.99999, 40.0, 95.29999, 95.3, 1e4, 3e38,
        ] {
            assert_eq!(table.detail(d, true), policy(d, true, &view), "at {d}");
        }
        let boundary = table
            .visible
            .iter()
            .find(|r| r.1 == Detail::new(3, 0))
            .unwrap()
            .0;
        assert_eq!(boundary, 95.3);
        // The accessors give the runs, never empty; below 0 and at NaN the first run holds.
        assert_eq!(table.visible(), &table.visible[..]);
        assert_eq!(table.hidden(), &[(0.0, Detail::new(3, 0))][..]);
        assert_eq!(table.visible()[0], (0.0, Detail::new(0, 10)));
        for d in [-1.0, f32::NAN, f32::NEG_INFINITY] {
            assert_eq!(table.detail(d, true), Detail::new(0, 10));
            assert_eq!(table.detail(d, false), Detail::new(3, 0));
        }
        let bad = |_: f32, _: bool, _: &ViewParams| Detail::new(9, 0);
        assert!(matches!(
            PolicyTable::new(&bad, &view, 4, 10),
            Err(GpuError::Policy { accuracy: 9, .. })
        ));
    }
}
