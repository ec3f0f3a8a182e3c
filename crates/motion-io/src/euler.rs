//! Conversions between BVH Euler channels (degrees, any order) and quaternions.

use std::f64::consts::PI;

use glam::{DMat3, DQuat};

use crate::skeleton::{Channel, axis_rotation};

/// Quaternion of a joint's rotation channels: `R = R_first * R_second * R_third` in the listed
/// order (intrinsic), angles in degrees. Position channels in `channels` are skipped.
pub fn channels_to_quat(channels: &[Channel], values: &[f64]) -> DQuat {
    let mut r = DQuat::IDENTITY;
    for (c, &v) in channels.iter().zip(values) {
        if c.is_rotation() {
            r *= axis_rotation(c.axis(), v.to_radians());
        }
    }
    r
}

/// The rotation axes (0 = x, 1 = y, 2 = z) of a channel list, in order.
pub fn rotation_axes(channels: &[Channel]) -> Vec<usize> {
    channels
        .iter()
        .filter(|c| c.is_rotation())
        .map(|c| c.axis())
        .collect()
}

/// Completes a list of distinct rotation axes (0 to 3 of them) into a full order of 3 distinct axes,
/// appending the missing ones in x, y, z order.
fn full_order(axes: &[usize]) -> [usize; 3] {
    let mut out = [0usize; 3];
    let mut n = 0;
    for &a in axes.iter().take(3) {
        out[n] = a;
        n += 1;
    }
    for a in 0..3 {
        if n < 3 && !out[..n].contains(&a) {
            out[n] = a;
            n += 1;
        }
    }
    out
}

/// Euler angles (radians) of `q` in the intrinsic order `order = (i, j, k)` (distinct axes):
/// `R = R_i(a) R_j(b) R_k(c)` with `b` in `[-pi/2, pi/2]`, `a`, `c` in `(-pi, pi]`.
///
/// With `s = +1` for a cyclic order (xyz, yzx, zxy) and `-1` otherwise:
/// `b = asin(s R[i][k])`, `a = atan2(-s R[j][k], R[k][k])`, `c = atan2(-s R[i][j], R[i][i])`
/// (`R[row][col]`). At gimbal lock `c = 0` and `a` is read from `R R_j(b)^-1`.
///
/// # Panics
/// If `order` is not a permutation of `[0, 1, 2]` (a repeated or out-of-range axis has no Euler
/// decomposition).
pub fn quat_to_euler(q: DQuat, order: [usize; 3]) -> [f64; 3] {
    let [i, j, k] = order;
    assert!(
        i < 3 && j < 3 && k < 3 && i != j && j != k && i != k,
        "quat_to_euler: order {order:?} is not a permutation of the axes [0, 1, 2]"
    );
    let s = if (j + 3 - i) % 3 == 1 { 1.0 } else { -1.0 };
    let m = DMat3::from_quat(q.normalize());
    // glam matrices are column-major: m.col(c)[r] = R[r][c].
    let r = |row: usize, col: usize| m.col(col)[row];
    let sb = (s * r(i, k)).clamp(-1.0, 1.0);
    let b = sb.asin();
    if sb.abs() < 1.0 - 1e-10 {
        let a = (-s * r(j, k)).atan2(r(k, k));
        let c = (-s * r(i, j)).atan2(r(i, i));
        [a, b, c]
    } else {
        let rest = q * axis_rotation(j, -b);
        let v = [rest.x, rest.y, rest.z][i];
        let a = crate::expmap::wrap_angle(2.0 * v.atan2(rest.w));
        [a, b, 0.0]
    }
}

/// Writes the rotation channels of one joint for rotation `q`, choosing among the equivalent
/// Euler solutions `(a, b, c)`, `(a + pi, pi - b, c + pi)` and their shifts by 360 degrees the one
/// nearest `reference` (the joint's previous channel values, degrees) when given.
///
/// `channels`/`out` are the joint's channel list and its slice of a frame; position entries of
/// `out` are left untouched. With fewer than 3 rotation channels the missing axes are dropped (exact
/// only when the rotation has no component about them).
pub fn quat_to_channels(
    q: DQuat,
    channels: &[Channel],
    reference: Option<&[f64]>,
    out: &mut [f64],
) {
    let axes = rotation_axes(channels);
    let order = full_order(&axes);
    let e = quat_to_euler(q, order);
    let alt = [e[0] + PI, PI - e[1], e[2] + PI];
    let mut chosen = [e[0].to_degrees(), e[1].to_degrees(), e[2].to_degrees()];
    if let Some(refv) = reference {
        // Reference values in the same (order) slots.
        let mut rv = [0.0; 3];
        let mut slot = 0;
        for (c, &v) in channels.iter().zip(refv) {
            if c.is_rotation() && slot < 3 {
                rv[slot] = v;
                slot += 1;
            }
        }
        let near = |cand: [f64; 3]| -> ([f64; 3], f64) {
            let mut d = 0.0;
            let mut o = [0.0; 3];
            for t in 0..3 {
                let x = cand[t].to_degrees();
                let shifted = x + 360.0 * ((rv[t] - x) / 360.0).round();
                o[t] = shifted;
                d += (shifted - rv[t]).powi(2);
            }
            (o, d)
        };
        let (o1, d1) = near(e);
        let (o2, d2) = near(alt);
        chosen = if d2 < d1 { o2 } else { o1 };
    }
    let mut slot = 0;
    for (c, o) in channels.iter().zip(out.iter_mut()) {
        if c.is_rotation() && slot < 3 {
            *o = chosen[slot];
            slot += 1;
        }
    }
}
