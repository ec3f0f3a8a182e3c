//! Planted feet: a foot on the floor stays where it landed (offline, on a played-back walk).
//!
//! Interpolated walks slide their feet: the root's path and the leg rotations are blended separately,
//! so the stance foot drifts (the motion-quality meter's foot skate, [`crate::quality`]). Per foot:
//!
//! 1. **Contacts**: frames where the foot's lowest point (ankle or toe) is within
//!    [`LOCK_HEIGHT_M`] of the floor and slower than [`LOCK_SPEED_M_S`], with runs shorter than
//!    [`MIN_RUN_S`] removed.
//! 2. **Correction**: within a contact run, the horizontal motion of the foot's pivot (its lowest point,
//!    which may pass from heel to toe) is cancelled frame by frame, `d(f) = d(f - 1) - (x_j(f) - x_j(f - 1))`
//!    for the pivot `j` of frame `f`, then centred (minus its mean over the run) so the foot rests where
//!    it is on average, and raised or lowered so the run's lowest pivot height is the floor. Before and after the run the correction eases in and out
//!    (`3u^2 - 2u^3`) over up to [`BLEND_S`], while the foot is in the air.
//!    A swing foot (faster than the lock speed) that passes lower than the lock height scuffs the floor;
//!    it is lifted to that height, the lift eased over [`CLEARANCE_S`] each side.
//! 3. **Two-bone IK**: the ankle is moved by the correction with the hip fixed: the knee stays in the
//!    leg's current bend plane, the thigh and shin keep their lengths, and the foot keeps its world
//!    orientation (so the toe moves with the ankle). Near full extension the reach is softened
//!    ("soft IK"): beyond [`SOFT_REACH`] of the leg's length the ankle approaches the target along
//!    `d_s + (L - d_s)(1 - exp(-(r - d_s) / (L - d_s)))`, so a target at or past full length bends
//!    the knee a little less each frame instead of snapping it straight (a planted foot may slide
//!    by the shortfall, a few millimetres, rather than the knee popping).
//!
//! Only the rotations of the thigh, knee and ankle joints change; the root does not move.
//!
//! The runtime's foot lock ([`lod_policy::FootLock`]) is the causal counterpart for characters
//! played frame by frame (crowds, engines): it cannot centre a contact it has not seen the end of,
//! so it holds the foot where it landed and releases it with a decay. The thresholds are the same
//! numbers (checked by a test); the arithmetic here is f64 over a whole walk.

use glam::{DQuat, DVec3};
use motion_io::expmap::{nearest_branch, quat_to_exp};
use motion_io::{PoseLayout, Transform};

use crate::quality::FootJoints;

/// A foot point counts as planted within this height above the floor (the meter's 2 cm and a margin).
pub const LOCK_HEIGHT_M: f64 = 0.03;
/// A foot point counts as planted below this horizontal speed (m/s); a swing foot passes faster.
pub const LOCK_SPEED_M_S: f64 = 0.8;
/// Contact runs shorter than this (s) are not locked.
pub const MIN_RUN_S: f64 = 0.1;
/// A swing foot's lift toward the lock height spreads over this many seconds each side.
pub const CLEARANCE_S: f64 = 0.1;
/// Longest ease of the correction before and after a contact run (s).
pub const BLEND_S: f64 = 0.2;
/// Share of the leg's length (thigh plus shin) beyond which the IK reach is softened.
pub const SOFT_REACH: f64 = 0.97;

/// One leg: hip (thigh) joint, knee, ankle, and the foot's points (ankle first).
struct Leg {
    hip: usize,
    knee: usize,
    ankle: usize,
    points: Vec<usize>,
}

fn leg(layout: &PoseLayout, points: &[usize]) -> Option<Leg> {
    let sk = layout.skeleton();
    let ankle = *points.first()?;
    let knee = sk.joints.get(ankle)?.parent?;
    let hip = sk.joints[knee].parent?;
    let rotating = |j: usize| layout.joint_rows(j).is_some();
    (rotating(hip) && rotating(knee) && rotating(ankle)).then(|| Leg {
        hip,
        knee,
        ankle,
        points: points.to_vec(),
    })
}

/// Holds planted feet in place (module documentation). `poses`: `frames x dof` world-frame pose
/// vectors of `layout` (metres, y up), changed in place; `floor_m`: the data's floor.
pub fn plant_feet(
    layout: &PoseLayout,
    feet: &FootJoints,
    floor_m: f64,
    poses: &mut [f64],
    dt: f64,
) {
    let dof = layout.dof();
    let nj = layout.skeleton().joints.len();
    if dof == 0 || poses.len() % dof != 0 || !feet.fits(nj) || dt.is_nan() || dt <= 0.0 {
        return;
    }
    let n = poses.len() / dof;
    let mut world = vec![Transform::default(); n * nj];
    for (pose, out) in poses.chunks_exact(dof).zip(world.chunks_exact_mut(nj)) {
        layout.joint_transforms_f64(pose, out);
    }
    let mut corrections = Vec::new();
    for points in [&feet.left, &feet.right] {
        let Some(leg) = leg(layout, points) else {
            continue;
        };
        let d = correction(&world, nj, &leg.points, floor_m, dt);
        corrections.push((leg, d));
    }
    let parent = |j: usize| layout.skeleton().joints[j].parent;
    for f in 0..n {
        let t = &world[f * nj..(f + 1) * nj];
        let pose = &mut poses[f * dof..(f + 1) * dof];
        for (leg, d) in &corrections {
            if d[f].length_squared() < 1e-12 {
                continue;
            }
            let parent_rot = parent(leg.hip).map_or(DQuat::IDENTITY, |p| t[p].rotation);
            let (hip, knee, ankle) = (t[leg.hip], t[leg.knee], t[leg.ankle]);
            // The character's forward (its root's heading): where a straight leg's knee points.
            let ahead = t[layout.root()].rotation * DVec3::Z;
            let pole = DVec3::new(ahead.x, 0.0, ahead.z).normalize_or(DVec3::Z);
            let (r_hip, r_knee) = two_bone(
                hip.position,
                knee.position,
                ankle.position,
                ankle.position + d[f],
                pole,
            );
            let hip_rot = r_hip * hip.rotation;
            let knee_rot = r_knee * r_hip * knee.rotation;
            let locals = [
                (leg.hip, parent_rot.inverse() * hip_rot),
                (leg.knee, hip_rot.inverse() * knee_rot),
                (leg.ankle, knee_rot.inverse() * ankle.rotation),
            ];
            for (j, q) in locals {
                if let Some(rows) = layout.joint_rows(j) {
                    let old = DVec3::from_slice(&pose[rows.clone()]);
                    let v = nearest_branch(quat_to_exp(q.normalize()), old);
                    pose[rows].copy_from_slice(&v.to_array());
                }
            }
        }
    }
}

/// The correction of one foot at every frame: horizontal for planted runs, vertical for clearance (module documentation, step 2).
fn correction(world: &[Transform], nj: usize, points: &[usize], floor: f64, dt: f64) -> Vec<DVec3> {
    let n = world.len() / nj;
    let at = |f: usize, j: usize| world[f * nj + j].position;
    let pivot = |f: usize| {
        *points
            .iter()
            .min_by(|&&a, &&b| at(f, a).y.total_cmp(&at(f, b).y))
            .expect("a foot has points")
    };
    // Low and slow: a swing foot may pass low over the floor, but fast.
    let speed = |f: usize| {
        let (a, b) = (f.saturating_sub(1), (f + 1).min(n - 1));
        let j = pivot(f);
        let v = at(b, j) - at(a, j);
        DVec3::new(v.x, 0.0, v.z).length() / ((b - a).max(1) as f64 * dt)
    };
    let planted: Vec<bool> = (0..n)
        .map(|f| at(f, pivot(f)).y - floor < LOCK_HEIGHT_M && speed(f) < LOCK_SPEED_M_S)
        .collect();
    let min_run = ((MIN_RUN_S / dt).round() as usize).max(2);
    let mut runs = Vec::new();
    let mut f = 0;
    while f < n {
        if !planted[f] {
            f += 1;
            continue;
        }
        let s = f;
        while f < n && planted[f] {
            f += 1;
        }
        if f - s >= min_run {
            runs.push((s, f - 1));
        }
    }
    let mut d = vec![DVec3::ZERO; n];
    let flat = |v: DVec3| DVec3::new(v.x, 0.0, v.z);
    let blend = ((BLEND_S / dt).round() as usize).max(1);
    for (i, &(s, e)) in runs.iter().enumerate() {
        for f in s + 1..=e {
            let j = pivot(f);
            d[f] = d[f - 1] - flat(at(f, j) - at(f - 1, j));
        }
        let mean = d[s..=e].iter().copied().sum::<DVec3>() / (e - s + 1) as f64;
        // On the floor: the run's lowest pivot height is brought to the floor.
        let low = (s..=e)
            .map(|f| at(f, pivot(f)).y)
            .fold(f64::INFINITY, f64::min);
        let onto_floor = DVec3::new(0.0, floor - low, 0.0);
        d[s..=e].iter_mut().for_each(|v| *v += onto_floor - mean);
        // Ease in before the run and out after it, within half the gap to the neighbouring runs.
        let before = i.checked_sub(1).map_or(s, |k| (s - runs[k].1) / 2);
        let after = runs.get(i + 1).map_or(n - 1 - e, |r| (r.0 - e) / 2);
        let (bi, bo) = (blend.min(before), blend.min(after));
        for k in 1..=bi {
            let w = lod_policy::ease_in_out(1.0 - k as f32 / (bi + 1) as f32);
            d[s - k] = d[s] * f64::from(w);
        }
        for k in 1..=bo {
            let w = lod_policy::ease_in_out(1.0 - k as f32 / (bo + 1) as f32);
            d[e + k] = d[e] * f64::from(w);
        }
    }
    // Clearance: a swing foot (fast) that passes lower than the lock height is lifted to it, the lift
    // spread over +-CLEARANCE_S with the ease curve (the larger of overlapping bumps).
    let lift: Vec<f64> = (0..n)
        .map(|f| {
            if speed(f) < LOCK_SPEED_M_S || runs.iter().any(|&(s, e)| (s..=e).contains(&f)) {
                0.0
            } else {
                (floor + LOCK_HEIGHT_M - at(f, pivot(f)).y).max(0.0)
            }
        })
        .collect();
    let spread = ((CLEARANCE_S / dt).round() as usize).max(1);
    for (f, df) in d.iter_mut().enumerate() {
        let mut y: f64 = 0.0;
        for (g, &l) in lift
            .iter()
            .enumerate()
            .take((f + spread + 1).min(n))
            .skip(f.saturating_sub(spread))
        {
            let u = 1.0 - f.abs_diff(g) as f32 / (spread + 1) as f32;
            y = y.max(l * f64::from(lod_policy::ease_in_out(u)));
        }
        df.y += y;
    }
    d
}

/// The reach the IK uses for a target `reach` away from the hip with a leg of length `len` whose
/// ankle is `current` away now: itself up to `max(SOFT_REACH len, current)`, then easing toward `len`
/// (C1 at the joint), at most `max(0.9999 len, current)` (the runtime's rule,
/// [`lod_policy::offline::soft_reach`]: no correction, no change).
fn soft_reach(reach: f64, current: f64, len: f64) -> f64 {
    let start = (SOFT_REACH * len).max(current);
    if reach <= start {
        return reach;
    }
    let span = len - start;
    if span <= 0.0 {
        return start;
    }
    // Capped just short of full length, where the slope is already below 0.004, so that far
    // targets never straighten the leg exactly (a degenerate knee plane).
    (start + span * (1.0 - (-(reach - start) / span).exp())).min((MAX_REACH * len).max(current))
}

/// The IK never straightens the leg beyond this share of its length.
const MAX_REACH: f64 = 0.9999;

/// Two-bone IK with the hip fixed: the world rotations to apply to the thigh (`r_hip`, about the hip)
/// and then to the shin (`r_knee`, about the moved knee) so that the ankle reaches `target`, the knee
/// staying on the side it bends to now; a nearly straight leg bends toward `pole` (the runtime's
/// rule, [`lod_policy::offline::two_bone`], with its [`lod_policy::offline::POLE_WEIGHT`]).
fn two_bone(hip: DVec3, knee: DVec3, ankle: DVec3, target: DVec3, pole: DVec3) -> (DQuat, DQuat) {
    let (l1, l2) = ((knee - hip).length(), (ankle - knee).length());
    let to_target = target - hip;
    let reach = to_target.length();
    if l1 < 1e-6 || l2 < 1e-6 || reach < 1e-6 {
        return (DQuat::IDENTITY, DQuat::IDENTITY);
    }
    let d = soft_reach(reach, (ankle - hip).length(), l1 + l2).max((l1 - l2).abs() + 1e-4);
    let u = to_target / reach;
    // The bend direction: the current knee's offset from the hip-target line, leaning toward the
    // pole (decisive only when the leg is nearly straight).
    let kh = knee - hip;
    let side = kh + f64::from(lod_policy::offline::POLE_WEIGHT) * l1 * pole;
    let mut w = side - side.dot(u) * u;
    if w.length_squared() < 1e-12 {
        w = (ankle - hip).cross(DVec3::Y).cross(u);
    }
    let w = w.normalize_or_zero();
    let cos_a = ((l1 * l1 + d * d - l2 * l2) / (2.0 * l1 * d)).clamp(-1.0, 1.0);
    let new_knee = hip + l1 * (cos_a * u + (1.0 - cos_a * cos_a).sqrt() * w);
    let r_hip = DQuat::from_rotation_arc(kh / l1, (new_knee - hip) / l1);
    let shin = r_hip * (ankle - knee);
    let goal = hip + d * u - new_knee;
    let r_knee = DQuat::from_rotation_arc(shin.normalize(), goal.normalize());
    (r_hip, r_knee)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thresholds_are_the_runtime_locks() {
        use lod_policy::offline as runtime;
        assert_eq!(LOCK_HEIGHT_M as f32, runtime::LOCK_HEIGHT_M);
        assert_eq!(LOCK_SPEED_M_S as f32, runtime::LOCK_SPEED_M_S);
        assert_eq!(SOFT_REACH as f32, runtime::SOFT_REACH);
        assert_eq!(MAX_REACH as f32, runtime::MAX_REACH);
    }

    #[test]
    fn two_bone_reaches_the_target_and_keeps_lengths() {
        let hip = DVec3::new(0.1, 0.9, 0.0);
        let knee = DVec3::new(0.1, 0.5, 0.05);
        let ankle = DVec3::new(0.1, 0.1, 0.0);
        // Within the unsoftened reach (0.94 of the leg's length).
        let target = ankle + DVec3::new(0.0, 0.05, -0.08);
        let (r_hip, r_knee) = two_bone(hip, knee, ankle, target, DVec3::Z);
        let new_knee = hip + r_hip * (knee - hip);
        let new_ankle = new_knee + r_knee * (r_hip * (ankle - knee));
        assert!(new_ankle.distance(target) < 1e-6, "{new_ankle}");
        assert!(((new_knee - hip).length() - (knee - hip).length()).abs() < 1e-9);
        // The knee still bends forward (+z).
        assert!(new_knee.z > hip.z.min(target.z));
    }

    #[test]
    fn soft_reach_is_smooth_and_below_full_length() {
        let len = 0.9;
        let mut prev = (0.0, 1.0);
        for i in 0..=2000 {
            let r = i as f64 * 0.001;
            let s = soft_reach(r, 0.5, len);
            assert!(s < len, "{r}: {s}");
            assert!(s <= r + 1e-15, "{r}: {s} beyond the target");
            let slope = (s - prev.0) / 0.001;
            // Non-decreasing reach, and the slope never jumps (continuous derivative: it changes
            // by at most step / (len - SOFT_REACH len) = 0.037 per 1 mm step; a hard clamp at the
            // target's reach would jump by 1).
            assert!(
                slope >= 0.0 && (i <= 1 || (slope - prev.1).abs() < 0.04),
                "{r}: {slope}"
            );
            prev = (s, slope);
        }
        assert_eq!(soft_reach(0.5, 0.5, len), 0.5);
        // A leg the data straighten beyond the soft start keeps its reach without a correction,
        // and a longer target eases on from there.
        let straight = 0.995 * len;
        assert_eq!(soft_reach(straight, straight, len), straight);
        let further = soft_reach(straight + 0.01, straight, len);
        assert!(further > straight && further < len, "{further}");
    }

    #[test]
    fn a_target_past_full_length_bends_the_knee_less_without_snapping() {
        let hip = DVec3::new(0.0, 0.9, 0.0);
        let knee = DVec3::new(0.0, 0.5, 0.05);
        let ankle = DVec3::new(0.0, 0.1, 0.0);
        let len = (knee - hip).length() + (ankle - knee).length();
        // Targets moving back past full length, 2 mm a frame: the knee moves a little each frame.
        let mut prev: Option<DVec3> = None;
        for i in 0..60 {
            let target = ankle + DVec3::new(0.0, 0.0, -0.002 * i as f64);
            let (r_hip, _) = two_bone(hip, knee, ankle, target, DVec3::Z);
            let new_knee = hip + r_hip * (knee - hip);
            assert!((target - hip).length() < len || i > 20);
            if let Some(p) = prev {
                assert!(
                    new_knee.distance(p) < 0.01,
                    "frame {i}: knee jumps {}",
                    new_knee.distance(p)
                );
            }
            prev = Some(new_knee);
        }
    }
}
