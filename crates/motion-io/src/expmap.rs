//! Exponential maps of rotations (Grassia 1998, the paper's reference \[13\]) and their branch
//! handling.
//!
//! A rotation by angle `theta` about unit axis `a` has exponential map `v = theta a`. The same
//! rotation is also `(theta + 2 pi k) a` for every integer `k`; the functions here pick the branch
//! nearest a reference vector so that a sequence of maps stays continuous (no jump at `|v| = pi`).

use std::f64::consts::{PI, TAU};

use glam::{DQuat, DVec3};

/// Logarithm of a unit quaternion: `v = theta a` with `q = (cos(theta/2), sin(theta/2) a)`,
/// `theta` in `[0, pi]` (the sign of `q` is chosen with `w >= 0`).
pub fn quat_to_exp(q: DQuat) -> DVec3 {
    let q = if q.w < 0.0 { -q } else { q };
    let v = DVec3::new(q.x, q.y, q.z);
    let s = v.length();
    if s < 1e-12 {
        // theta ~ 2 s; first-order series.
        return 2.0 * v;
    }
    let theta = 2.0 * s.atan2(q.w);
    v * (theta / s)
}

/// Exponential of a rotation vector: `q = (cos(|v|/2), sin(|v|/2) v/|v|)` (any `|v|`, including
/// maps beyond pi from an unwrapped sequence).
pub fn exp_to_quat(v: DVec3) -> DQuat {
    let theta = v.length();
    let half = 0.5 * theta;
    // sin(half)/theta with a Taylor series near zero.
    let k = if theta < 1e-6 {
        0.5 - theta * theta / 48.0
    } else {
        half.sin() / theta
    };
    DQuat::from_xyzw(v.x * k, v.y * k, v.z * k, half.cos())
}

/// Single-precision [`exp_to_quat`]: the runtime's ([`lod_policy::offline::exp_to_quat`]).
pub use lod_policy::offline::exp_to_quat as exp_to_quat_f32;

/// The branch of `v` (same rotation) nearest `reference`: among `v + 2 pi k v/|v|` for integer
/// `k` (which includes the opposite-axis form `-(2 pi - theta) a`), the one minimising the distance
/// to `reference`. When `v` is (near) zero, the axis is taken from `reference`.
pub fn nearest_branch(v: DVec3, reference: DVec3) -> DVec3 {
    let theta = v.length();
    let axis = if theta > 1e-9 {
        v / theta
    } else {
        let r = reference.length();
        if r < 1e-9 {
            return v;
        }
        reference / r
    };
    // Minimise |(theta + 2 pi k) a - r|: along the axis, t = theta + 2 pi k nearest a.r.
    let target = axis.dot(reference);
    let k = ((target - theta) / TAU).round();
    let mut best = axis * (theta + TAU * k);
    let mut best_d = (best - reference).length_squared();
    for dk in [-1.0, 1.0] {
        let c = axis * (theta + TAU * (k + dk));
        let d = (c - reference).length_squared();
        if d < best_d {
            best = c;
            best_d = d;
        }
    }
    best
}

/// Wraps an angle to `(-pi, pi]`.
pub fn wrap_angle(a: f64) -> f64 {
    let mut x = a.rem_euclid(TAU);
    if x > PI {
        x -= TAU;
    }
    x
}
