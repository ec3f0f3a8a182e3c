//! Rotations to BVH Euler channels (`Zrotation Xrotation Yrotation`, degrees) and back.

use glam::{DMat3, DQuat};

/// Euler angles `(z, x, y)` in degrees with `R = Rz(z) * Rx(x) * Ry(y)` (intrinsic ZXY, the BVH
/// convention for channels listed `Zrotation Xrotation Yrotation`).
///
/// With `R = Rz(a) Rx(b) Ry(c)`: `R21 = sin b`, `R01 = -sin a cos b`, `R11 = cos a cos b`,
/// `R20 = -cos b sin c`, `R22 = cos b cos c`, hence `b = asin R21`, `a = atan2(-R01, R11)`,
/// `c = atan2(-R20, R22)`; `b` lies in `[-90, 90]`.
pub fn quat_to_zxy_degrees(q: DQuat) -> [f64; 3] {
    let m = DMat3::from_quat(q.normalize());
    // glam matrices are column-major: R_ij = m.col(j)[i].
    let r21 = m.y_axis.z;
    let r01 = m.y_axis.x;
    let r11 = m.y_axis.y;
    let r20 = m.x_axis.z;
    let r22 = m.z_axis.z;
    let b = r21.clamp(-1.0, 1.0).asin();
    let a = (-r01).atan2(r11);
    let c = (-r20).atan2(r22);
    [a.to_degrees(), b.to_degrees(), c.to_degrees()]
}

/// The rotation `Rz(z) * Rx(x) * Ry(y)` from angles in degrees (inverse of [`quat_to_zxy_degrees`]).
pub fn zxy_degrees_to_quat(zxy: [f64; 3]) -> DQuat {
    DQuat::from_rotation_z(zxy[0].to_radians())
        * DQuat::from_rotation_x(zxy[1].to_radians())
        * DQuat::from_rotation_y(zxy[2].to_radians())
}

/// Adds the multiple of 360 degrees to `angle` that brings it closest to `previous`, so that a
/// channel never jumps by a full turn between frames (the heading of a turning walker grows past
/// 180 degrees instead of wrapping).
pub fn unwrap_degrees(angle: f64, previous: f64) -> f64 {
    angle - 360.0 * ((angle - previous) / 360.0).round()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zxy_round_trip() {
        for &(a, b, c) in &[
            (10.0, -20.0, 30.0),
            (-170.0, 45.0, 179.0),
            (0.0, 89.0, -5.0),
            (90.0, -60.0, -120.0),
        ] {
            let q = zxy_degrees_to_quat([a, b, c]);
            let e = quat_to_zxy_degrees(q);
            assert!(
                (e[0] - a).abs() < 1e-6 && (e[1] - b).abs() < 1e-6 && (e[2] - c).abs() < 1e-6,
                "{e:?}"
            );
        }
    }

    #[test]
    fn matches_motion_io_channel_composition() {
        // motion-io composes R = R_first * R_second * R_third in listed channel order.
        let q = DQuat::from_rotation_y(0.3)
            * DQuat::from_rotation_z(-0.2)
            * DQuat::from_rotation_x(0.7);
        let e = quat_to_zxy_degrees(q);
        let r = motion_io::axis_rotation(2, e[0].to_radians())
            * motion_io::axis_rotation(0, e[1].to_radians())
            * motion_io::axis_rotation(1, e[2].to_radians());
        assert!(r.dot(q).abs() > 1.0 - 1e-12);
    }

    #[test]
    fn unwrap_follows_previous_value() {
        assert!((unwrap_degrees(-179.0, 179.0) - 181.0).abs() < 1e-12);
        assert!((unwrap_degrees(179.0, -179.0) + 181.0).abs() < 1e-12);
        assert!((unwrap_degrees(10.0, 725.0) - 730.0).abs() < 1e-12);
    }
}
