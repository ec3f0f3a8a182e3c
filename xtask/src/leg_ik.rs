//! Analytic two-bone inverse kinematics for a leg (hip, knee, ankle).

use glam::{DMat3, DQuat, DVec3};

/// A solved leg: the knee position and the world orientations of thigh and shank.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LegPose {
    /// Knee position.
    pub knee: DVec3,
    /// Thigh orientation: its local -Y points from hip to knee, its local X is the knee axis.
    pub thigh: DQuat,
    /// Shank orientation: local -Y from knee to ankle, same local X as the thigh (a pure hinge).
    pub shank: DQuat,
    /// Whether the target was out of reach (the ankle then stops short of it along the same line).
    pub clamped: bool,
}

/// Places the knee for a hip at `hip`, an ankle target `ankle`, segment lengths `l1` (thigh) and
/// `l2` (shank), bending towards `forward` (the knee points that way).
///
/// With `d = |ankle - hip|` and `u = (ankle - hip) / d`, the angle `alpha` between thigh and `u`
/// obeys the law of cosines `cos alpha = (l1^2 + d^2 - l2^2) / (2 l1 d)`, and
/// `knee = hip + l1 (cos alpha u + sin alpha n)` with `n` the part of `forward` orthogonal to `u`.
/// `d` is clamped to `[|l1 - l2| + eps, l1 + l2 - eps]`.
pub fn solve_leg(hip: DVec3, ankle: DVec3, l1: f64, l2: f64, forward: DVec3) -> LegPose {
    let to = ankle - hip;
    let d_raw = to.length();
    let u = if d_raw > 1e-9 {
        to / d_raw
    } else {
        DVec3::NEG_Y
    };
    let lo = (l1 - l2).abs() + 1e-6;
    let hi = (l1 + l2) * (1.0 - 1e-9);
    let d = d_raw.clamp(lo, hi);
    let clamped = d_raw > hi;
    let mut n = forward - u * forward.dot(u);
    if n.length_squared() < 1e-12 {
        n = DVec3::Z - u * u.z;
    }
    let n = n.normalize();
    let cos_a = ((l1 * l1 + d * d - l2 * l2) / (2.0 * l1 * d)).clamp(-1.0, 1.0);
    let sin_a = (1.0 - cos_a * cos_a).sqrt();
    let knee = hip + l1 * (cos_a * u + sin_a * n);
    let end = hip + d * u;
    let y_thigh = (hip - knee).normalize();
    let x = y_thigh.cross(n).normalize();
    let thigh = frame(x, y_thigh);
    let y_shank = (knee - end).normalize();
    let x_shank = (x - y_shank * x.dot(y_shank)).normalize();
    let shank = frame(x_shank, y_shank);
    LegPose {
        knee,
        thigh,
        shank,
        clamped,
    }
}

/// Orientation with local X along `x` and local Y along `y` (orthonormal), Z = X x Y.
fn frame(x: DVec3, y: DVec3) -> DQuat {
    DQuat::from_mat3(&DMat3::from_cols(x, y, x.cross(y))).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reaches_target_and_bends_forward() {
        let hip = DVec3::new(8.0, 90.0, 0.0);
        let ankle = DVec3::new(6.0, 12.0, 20.0);
        let p = solve_leg(hip, ankle, 42.0, 43.0, DVec3::Z);
        assert!(!p.clamped);
        assert!(((p.knee - hip).length() - 42.0).abs() < 1e-9);
        assert!(((ankle - p.knee).length() - 43.0).abs() < 1e-9);
        // Bone directions match the orientations.
        assert!((p.thigh * DVec3::NEG_Y * 42.0 - (p.knee - hip)).length() < 1e-9);
        assert!((p.shank * DVec3::NEG_Y * 43.0 - (ankle - p.knee)).length() < 1e-9);
        // Knee ahead of the hip-ankle line.
        let mid = (hip + ankle) * 0.5;
        assert!(p.knee.z > mid.z);
        // The knee is a hinge about local X.
        let local = p.thigh.inverse() * p.shank;
        let (axis, angle) = local.to_axis_angle();
        assert!(angle > 0.1 && axis.x.abs() > 1.0 - 1e-9, "{axis} {angle}");
        assert!(
            axis.x * angle > 0.0,
            "knee flexion is a positive X rotation"
        );
    }

    #[test]
    fn out_of_reach_is_clamped_not_nan() {
        let p = solve_leg(
            DVec3::ZERO,
            DVec3::new(0.0, -200.0, 0.0),
            40.0,
            40.0,
            DVec3::Z,
        );
        assert!(p.clamped && p.knee.is_finite() && p.thigh.is_finite());
        let p = solve_leg(DVec3::ZERO, DVec3::ZERO, 40.0, 40.0, DVec3::Z);
        assert!(p.knee.is_finite() && p.shank.is_finite());
    }
}
