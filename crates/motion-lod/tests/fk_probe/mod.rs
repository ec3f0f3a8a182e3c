//! An independent forward-kinematics probe of foot skate, to check the motion-quality meter
//! (`motion_lod::quality`) against: it shares none of the meter's code. It reads BVH motions (the
//! data's files as read, or a walk as `synth` writes it), places the joints with the BVH reader's
//! own Euler-channel forward kinematics (`motion_io::Skeleton::joint_positions`, not the pose
//! layout's exp-map one the meter uses), finds the feet by name, and applies the textbook rule:
//!
//! - per foot, the lower of its ankle and toe at each frame; the foot's floor in each gait cycle is
//!   the 10th percentile of that height over the cycle (the motion cut into consecutive stretches one
//!   cycle long, the last one taking the remainder; the meter slides a one-cycle window instead), so
//!   that a walk whose stance height changes from cycle to cycle is followed;
//! - speed: horizontal displacement of that point from the frame before to the frame after, over the
//!   frame step nearest 1/30 s;
//! - contact: within 2 cm of the floor and slower than 1 m/s; skate: the mean speed over contacts.

use glam::DVec3;
use motion_io::{FootNames, Motion, find_feet};

/// What the probe read.
#[derive(Debug, Clone, Copy)]
pub struct Probe {
    /// Mean horizontal speed of the lowest foot point over contacts, cm/s.
    pub skate_cm_s: f64,
    /// Share of (foot, frame) pairs in contact.
    pub contact_share: f64,
}

/// Joint positions (metres) of frames `frames` of `motion`, whose lengths are in units of
/// `1 / units_per_metre` metres, by the BVH reader's forward kinematics.
pub fn positions(
    motion: &Motion,
    units_per_metre: f64,
    frames: std::ops::Range<usize>,
) -> Vec<Vec<DVec3>> {
    frames
        .map(|f| {
            motion
                .skeleton
                .joint_positions(motion.frame(f))
                .into_iter()
                .map(|p| p / units_per_metre)
                .collect()
        })
        .collect()
}

/// The probe on positions `x` (frames x joints, metres, y up) of `motion`'s skeleton, frames `dt`
/// seconds apart, gait cycles `cycle_s` seconds long.
pub fn skate(motion: &Motion, x: &[Vec<DVec3>], dt: f64, cycle_s: f64) -> Probe {
    let feet = find_feet(&motion.skeleton, &FootNames::default()).expect("feet by name");
    let left: Vec<usize> = [Some(feet.left_foot), feet.left_toe]
        .into_iter()
        .flatten()
        .collect();
    let right: Vec<usize> = [Some(feet.right_foot), feet.right_toe]
        .into_iter()
        .flatten()
        .collect();
    let n = x.len();
    let k = ((1.0 / (30.0 * dt)).round() as usize).max(1);
    assert!(n > 2 * k + 10, "{n} frames");
    let (mut sum, mut contacts) = (0.0, 0usize);
    for points in [&left, &right] {
        let lowest = |f: usize| {
            points
                .iter()
                .copied()
                .min_by(|&a, &b| x[f][a].y.partial_cmp(&x[f][b].y).unwrap())
                .unwrap()
        };
        let heights: Vec<f64> = (0..n).map(|f| x[f][lowest(f)].y).collect();
        let cycle = ((cycle_s / dt).round() as usize).clamp(1, n);
        let cycles = n / cycle;
        let floors: Vec<f64> = (0..cycles)
            .map(|c| {
                let end = if c + 1 == cycles { n } else { (c + 1) * cycle };
                let mut h = heights[c * cycle..end].to_vec();
                h.sort_by(|a, b| a.partial_cmp(b).unwrap());
                h[(0.1 * (h.len() - 1) as f64).round() as usize]
            })
            .collect();
        for f in k..n - k {
            let j = lowest(f);
            let floor = floors[(f / cycle).min(cycles - 1)];
            let d = x[f + k][j] - x[f - k][j];
            let speed = (d.x * d.x + d.z * d.z).sqrt() / (2.0 * k as f64 * dt);
            if heights[f] - floor < 0.02 && speed < 1.0 {
                sum += speed;
                contacts += 1;
            }
        }
    }
    Probe {
        skate_cm_s: if contacts > 0 {
            100.0 * sum / contacts as f64
        } else {
            0.0
        },
        contact_share: contacts as f64 / (2 * (n - 2 * k)) as f64,
    }
}

/// Median of `v` (0 when empty).
pub fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(|a, b| a.partial_cmp(b).unwrap());
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}
