//! Length units of a take: detection and conversion to metres.

use crate::motion::Motion;

/// Index of the motion root: the first joint whose position channels vary over the take (by more
/// than `1e-6` units), or joint 0 when none does.
pub fn motion_root(motion: &Motion) -> usize {
    let sk = &motion.skeleton;
    let n = sk.channel_count();
    let starts = sk.channel_starts();
    let nf = motion.frame_count();
    if nf == 0 {
        return 0;
    }
    for (j, joint) in sk.joints.iter().enumerate() {
        for (c, ch) in joint.channels.iter().enumerate() {
            if !ch.is_position() {
                continue;
            }
            let k = starts[j] + c;
            let first = motion.frames[k];
            if motion.frames[k..]
                .iter()
                .step_by(n)
                .any(|v| (v - first).abs() > 1e-6)
            {
                return j;
            }
        }
    }
    0
}

/// Guesses the file's units per metre from the median height (y) of the motion root over the
/// take: above 20 units means centimetres (100), otherwise metres (1). A walking person's hips are
/// 0.7-1.1 m high, i.e. 70-110 in centimetres. Returns 100 for an empty take, and for a skeleton
/// whose parents are not all listed before their children (a hand-built one that
/// [`crate::Skeleton::validate`] rejects: no forward kinematics).
pub fn detect_units_per_metre(motion: &Motion) -> f64 {
    let nf = motion.frame_count();
    if nf == 0 || !motion.skeleton.hierarchy_ok() {
        return 100.0;
    }
    let root = motion_root(motion);
    let mut t = vec![crate::Transform::IDENTITY; motion.skeleton.joints.len()];
    let mut ys: Vec<f64> = (0..nf)
        .step_by((nf / 64).max(1))
        .map(|f| {
            motion.skeleton.forward_kinematics(motion.frame(f), &mut t);
            t[root].position.y
        })
        .filter(|y| y.is_finite())
        .collect();
    if ys.is_empty() {
        return 100.0;
    }
    ys.sort_by(f64::total_cmp);
    if ys[ys.len() / 2].abs() > 20.0 {
        100.0
    } else {
        1.0
    }
}

/// Converts a length in file units to metres.
pub fn to_metres(value: f64, units_per_metre: f64) -> f64 {
    value / units_per_metre
}
