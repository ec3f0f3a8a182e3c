//! Euler and exponential-map conversions, pose vectors and their inverse, layout FK.

use std::f64::consts::PI;

use glam::{DQuat, DVec3, Vec3};
use motion_io::euler::{channels_to_quat, quat_to_channels, quat_to_euler};
use motion_io::expmap::{exp_to_quat, nearest_branch, quat_to_exp};
use motion_io::pose::{ALWAYS_ROWS, PoseError};
use motion_io::{
    Channel, Joint, Motion, PoseLayout, Skeleton, Transform, align_exp_maps, unwrap_exp_maps,
};
use proptest::prelude::*;

const ORDERS: [[Channel; 3]; 6] = {
    use Channel::*;
    [
        [Xrotation, Yrotation, Zrotation],
        [Xrotation, Zrotation, Yrotation],
        [Yrotation, Xrotation, Zrotation],
        [Yrotation, Zrotation, Xrotation],
        [Zrotation, Xrotation, Yrotation],
        [Zrotation, Yrotation, Xrotation],
    ]
};

fn same_rotation(a: DQuat, b: DQuat, tol: f64) -> bool {
    a.dot(b).abs() > 1.0 - tol
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn euler_decomposition_inverts_every_order(o in 0..6usize, a in -179.0..179.0f64, b in -89.0..89.0f64, c in -179.0..179.0f64) {
        let ch = ORDERS[o];
        let q = channels_to_quat(&ch, &[a, b, c]);
        let mut out = [0.0; 3];
        quat_to_channels(q, &ch, None, &mut out);
        prop_assert!((out[0] - a).abs() < 1e-7 && (out[1] - b).abs() < 1e-7 && (out[2] - c).abs() < 1e-7, "{:?} vs {:?}", out, [a, b, c]);
        // Any angles (other branch, wrapped): the rotation is reproduced, and with the source values
        // as reference the source values come back.
        let src = [a + 360.0, 180.0 - b, c - 180.0];
        let q2 = channels_to_quat(&ch, &src);
        quat_to_channels(q2, &ch, Some(&src), &mut out);
        prop_assert!(same_rotation(channels_to_quat(&ch, &out), q2, 1e-12));
        for k in 0..3 { prop_assert!((out[k] - src[k]).abs() < 1e-6, "{:?} vs {:?}", out, src); }
    }

    #[test]
    fn exp_map_round_trip(x in -1.0..1.0f64, y in -1.0..1.0f64, z in -1.0..1.0f64, t in 0.0..3.1f64) {
        let axis = DVec3::new(x, y, z);
        prop_assume!(axis.length() > 1e-3);
        let v = axis.normalize() * t;
        let q = exp_to_quat(v);
        prop_assert!((quat_to_exp(q) - v).length() < 1e-9);
        // Branches represent the same rotation and the nearest branch is continuous.
        let r = v + axis.normalize() * 2.0 * PI;
        let w = nearest_branch(v, r);
        prop_assert!(same_rotation(exp_to_quat(w), q, 1e-12));
        prop_assert!((w - r).length() < 1e-9);
    }
}

#[test]
fn gimbal_lock_still_reproduces_the_rotation() {
    for ch in ORDERS {
        for b in [90.0, -90.0] {
            let q = channels_to_quat(&ch, &[25.0, b, -40.0]);
            let e = quat_to_euler(q, [ch[0].axis(), ch[1].axis(), ch[2].axis()]);
            let back = channels_to_quat(&ch, &e.map(f64::to_degrees));
            assert!(same_rotation(back, q, 1e-9), "{ch:?}");
        }
    }
}

#[test]
fn unwrapping_removes_jumps_at_pi() {
    // A rotation about y sweeping through 180 degrees: principal logs jump from +pi to -pi.
    let dof = ALWAYS_ROWS + 3;
    let n = 40;
    let mut poses = vec![0.0; n * dof];
    for f in 0..n {
        let ang = 2.6 + 0.03 * f as f64;
        let v = quat_to_exp(DQuat::from_rotation_y(ang));
        poses[f * dof + ALWAYS_ROWS..f * dof + ALWAYS_ROWS + 3].copy_from_slice(&v.to_array());
        let r = quat_to_exp(DQuat::from_rotation_x(-ang));
        poses[f * dof + 3..f * dof + 6].copy_from_slice(&r.to_array());
    }
    let jumps = |p: &[f64]| {
        (1..n)
            .map(|f| (p[f * dof + ALWAYS_ROWS + 1] - p[(f - 1) * dof + ALWAYS_ROWS + 1]).abs())
            .fold(0.0, f64::max)
    };
    assert!(jumps(&poses) > 6.0);
    unwrap_exp_maps(&mut poses, dof).unwrap();
    assert!(jumps(&poses) < 0.031);
    for f in 1..n {
        assert!((poses[f * dof + 3] - poses[(f - 1) * dof + 3]).abs() < 0.031);
        let want = DQuat::from_rotation_y(2.6 + 0.03 * f as f64);
        assert!(same_rotation(
            exp_to_quat(DVec3::from_slice(&poses[f * dof + ALWAYS_ROWS..])),
            want,
            1e-12
        ));
    }
    // Alignment across samples: a principal-branch pose moves next to the reference.
    let mut one = poses[(n - 1) * dof..].to_vec();
    let last = one.clone();
    let v = quat_to_exp(exp_to_quat(DVec3::from_slice(&one[ALWAYS_ROWS..])));
    one[ALWAYS_ROWS..ALWAYS_ROWS + 3].copy_from_slice(&v.to_array());
    align_exp_maps(&mut one, &last).unwrap();
    assert!((one[ALWAYS_ROWS + 1] - last[ALWAYS_ROWS + 1]).abs() < 1e-9);
    assert!(matches!(
        unwrap_exp_maps(&mut poses[..9], 8),
        Err(PoseError::BadShape { .. })
    ));
}

/// Static joint above the root (like Bandai's joint_Root), a 6-channel root, a static joint and
/// rotating joints with different orders.
fn test_motion() -> Motion {
    use Channel::*;
    let six = vec![
        Xposition, Yposition, Zposition, Zrotation, Xrotation, Yrotation,
    ];
    let j = |name: &str, parent, offset, channels: Vec<Channel>| Joint {
        name: name.into(),
        parent,
        offset,
        channels,
        end_site: None,
    };
    let sk = Skeleton {
        joints: vec![
            j("top", None, DVec3::ZERO, six.clone()),
            j("pelvis", Some(0), DVec3::new(0.0, 90.0, 0.0), six.clone()),
            j(
                "thigh",
                Some(1),
                DVec3::new(10.0, 0.0, 0.0),
                vec![Zrotation, Xrotation, Yrotation],
            ),
            j(
                "shin",
                Some(2),
                DVec3::new(0.0, -40.0, 0.0),
                vec![Xrotation, Yrotation, Zrotation],
            ),
            j(
                "finger",
                Some(3),
                DVec3::new(0.0, -5.0, 1.0),
                vec![Yrotation, Xrotation, Zrotation],
            ),
            j("spine", Some(1), DVec3::new(0.0, 20.0, 0.0), six.clone()),
        ],
    };
    let nch = sk.channel_count();
    let nf = 30;
    let mut frames = vec![0.0; nf * nch];
    for f in 0..nf {
        let t = f as f64 / 10.0;
        let fr = &mut frames[f * nch..(f + 1) * nch];
        // top: static, but not identity.
        fr[0..6].copy_from_slice(&[1.0, 0.0, 2.0, 0.0, 0.0, 10.0]);
        // pelvis: moves and turns through +-180 on its y channel.
        fr[6..12].copy_from_slice(&[
            3.0 * t,
            90.0 + t.sin(),
            100.0 * t,
            5.0 * t.sin(),
            3.0,
            150.0 + 30.0 * t,
        ]);
        fr[12..15].copy_from_slice(&[175.0 + 10.0 * t, 20.0 * t.cos(), -5.0]);
        fr[15..18].copy_from_slice(&[40.0 * t.sin(), 3.0, 100.0 + 40.0 * t]);
        fr[18..21].copy_from_slice(&[0.0, 12.0, 0.0]); // finger static
        fr[21..27].copy_from_slice(&[0.0, 20.0, 0.0, 5.0 * t, -4.0, 2.0]);
    }
    Motion {
        skeleton: sk,
        frame_time: 1.0 / 30.0,
        frames,
    }
}

#[test]
fn layout_detects_root_and_rotating_joints() {
    let m = test_motion();
    let layout = PoseLayout::from_motions(&[&m], 100.0).unwrap();
    assert_eq!(layout.root(), 1);
    assert_eq!(layout.joint_order(), &[2, 3, 5]);
    assert_eq!(layout.dof(), 7 + 9);
    assert_eq!(layout.joint_rows(3), Some(10..13));
    assert_eq!(layout.joint_rows(4), None);
    assert_eq!(layout.row_names()[10], "shin.rx");
    let swapped = layout.clone().with_joint_order(vec![5, 2, 3]).unwrap();
    assert_eq!(swapped.joint_rows(5), Some(7..10));
    assert!(matches!(
        layout.clone().with_joint_order(vec![2, 3]),
        Err(PoseError::BadJointOrder(_))
    ));
    assert!(matches!(
        PoseLayout::from_motions(&[], 100.0),
        Err(PoseError::NoMotions)
    ));
    assert!(matches!(
        PoseLayout::new(&m.skeleton, 0.0),
        Err(PoseError::BadUnits(_))
    ));
}

#[test]
fn pose_to_channels_round_trip_and_fk_agree() {
    let m = test_motion();
    let layout = PoseLayout::from_motions(&[&m], 100.0)
        .unwrap()
        .with_joint_order(vec![5, 3, 2])
        .unwrap();
    let poses = layout.poses_from_motion(&m).unwrap();
    let p = layout.dof();
    let nch = m.skeleton.channel_count();
    let nj = m.skeleton.joints.len();
    let mut ch = vec![0.0; nch];
    let mut src_t = vec![Transform::IDENTITY; nj];
    let mut back_t = vec![Transform::IDENTITY; nj];
    let mut pos = vec![DVec3::ZERO; nj];
    let mut pos32 = vec![Vec3::ZERO; nj];
    for f in 0..m.frame_count() {
        let pose = &poses[f * p..(f + 1) * p];
        // Exact channels back with the source frame as Euler reference.
        layout
            .frame_from_pose_near(pose, m.frame(f), &mut ch)
            .unwrap();
        for (a, b) in ch.iter().zip(m.frame(f)) {
            assert!((a - b).abs() < 1e-6, "frame {f}: {a} vs {b}");
        }
        // Principal-branch channels give the same FK.
        layout.frame_from_pose(pose, &mut ch).unwrap();
        m.skeleton.forward_kinematics(m.frame(f), &mut src_t);
        m.skeleton.forward_kinematics(&ch, &mut back_t);
        for (a, b) in src_t.iter().zip(&back_t) {
            assert!((a.position - b.position).length() < 1e-8);
            assert!(same_rotation(a.rotation, b.rotation, 1e-12));
        }
        // Pose FK (f64 and f32) in metres equals the skeleton FK below the root.
        layout.joint_positions_f64(pose, &mut pos);
        let pose32: Vec<f32> = pose.iter().map(|&x| x as f32).collect();
        layout.joint_positions(&pose32, layout.joint_count(), &mut pos32);
        for j in 1..nj {
            let want = src_t[j].position / 100.0;
            assert!((pos[j] - want).length() < 1e-9, "joint {j}");
            assert!(
                (pos32[j].as_dvec3() - want).length() < 1e-4,
                "joint {j} f32"
            );
        }
    }
    // Unwrapped: no exp-map jumps although the pelvis y channel crosses 180 degrees.
    for f in 1..m.frame_count() {
        for r in 3..p {
            if r != 6 {
                assert!(
                    (poses[f * p + r] - poses[(f - 1) * p + r]).abs() < 0.5,
                    "row {r} frame {f}"
                );
            }
        }
    }
    // Continuous writing: motion_from_poses gives channels without 360-degree jumps.
    let written = layout.motion_from_poses(&poses, m.frame_time).unwrap();
    for f in 1..written.frame_count() {
        for k in 0..nch {
            assert!((written.frame(f)[k] - written.frame(f - 1)[k]).abs() < 60.0);
        }
    }
}

#[test]
fn inactive_joints_use_the_rest_rotation() {
    let m = test_motion();
    let layout = PoseLayout::from_motions(&[&m], 100.0).unwrap();
    let p = layout.dof();
    let poses = layout.poses_from_motion(&m).unwrap();
    let pose32: Vec<f32> = poses[5 * p..6 * p].iter().map(|&x| x as f32).collect();
    let mut full = vec![Vec3::ZERO; 6];
    let mut cut = vec![Vec3::ZERO; 6];
    layout.joint_positions(&pose32, 3, &mut full);
    // One active joint (thigh) and a truncated pose vector of 7 + 3 rows.
    layout.joint_positions(&pose32[..10], 1, &mut cut);
    assert!((full[2] - cut[2]).length() < 1e-6);
    // shin is inactive: its child (finger) moves to the rest-rotation position.
    let rest = layout.rest_pose();
    let mut with_rest = pose32.clone();
    for r in 10..13 {
        with_rest[r] = rest[r] as f32;
    }
    let mut expect = vec![Vec3::ZERO; 6];
    layout.joint_positions(&with_rest, 3, &mut expect);
    assert!((cut[4] - expect[4]).length() < 1e-5);
    assert!((cut[4] - full[4]).length() > 1e-3);
}

#[test]
fn conversions_reject_bad_input() {
    let m = test_motion();
    let layout = PoseLayout::from_motions(&[&m], 100.0).unwrap();
    let mut out = vec![0.0; layout.dof()];
    assert!(matches!(
        layout.pose_from_frame(&m, 99, &mut out),
        Err(PoseError::FrameOutOfRange { frame: 99, .. })
    ));
    assert!(matches!(
        layout.pose_from_frame(&m, 0, &mut out[..3]),
        Err(PoseError::Length { .. })
    ));
    let mut ch = vec![0.0; m.skeleton.channel_count()];
    out[4] = f64::NAN;
    assert!(matches!(
        layout.frame_from_pose(&out, &mut ch),
        Err(PoseError::NonFinite { index: 4, .. })
    ));
    let mut other = m.clone();
    other.skeleton.joints.pop();
    other.frames.truncate(other.skeleton.channel_count() * 2);
    assert!(matches!(
        layout.pose_from_frame(&other, 0, &mut vec![0.0; layout.dof()]),
        Err(PoseError::SkeletonMismatch { .. })
    ));
}

#[test]
fn frozen_joints_leave_the_pose_and_hold_their_rest_rotation() {
    let m = test_motion();
    let layout = PoseLayout::from_motions(&[&m], 100.0).unwrap();
    let poses = layout.poses_from_motion(&m).unwrap();
    let p = layout.dof();
    // Freeze the shin (joint 3): the thigh and spine keep their relative order.
    let frozen = layout.clone().freeze_joints(&[3]).unwrap();
    assert_eq!(frozen.joint_order(), &[2, 5]);
    assert_eq!(frozen.dof(), p - 3);
    assert_eq!(frozen.joint_rows(3), None);
    assert_eq!(frozen.joint_rows(5), Some(10..13));
    // FK of the frozen layout = FK of the full layout with the shin at its rest rotation.
    let rest = layout.rest_pose();
    let shin = layout.joint_rows(3).unwrap();
    let nj = m.skeleton.joints.len();
    let (mut a, mut b) = (vec![DVec3::ZERO; nj], vec![DVec3::ZERO; nj]);
    for pose in poses.chunks_exact(p).step_by(7) {
        let mut held = pose.to_vec();
        held[shin.clone()].copy_from_slice(&rest[shin.clone()]);
        let short: Vec<f64> = (0..p)
            .filter(|r| !shin.contains(r))
            .map(|r| pose[r])
            .collect();
        layout.joint_positions_f64(&held, &mut a);
        frozen.joint_positions_f64(&short, &mut b);
        for (x, y) in a.iter().zip(&b) {
            assert!((*x - *y).length() < 1e-12, "{x} vs {y}");
        }
        // Written BVH channels carry the rest rotation of the frozen joint.
        let mut ch = vec![0.0; m.skeleton.channel_count()];
        frozen.frame_from_pose(&short, &mut ch).unwrap();
        let s = m.skeleton.channel_starts()[3];
        let q = channels_to_quat(&m.skeleton.joints[3].channels, &ch[s..s + 3]);
        assert!(same_rotation(q, layout.rest_rotation(3), 1e-12));
    }
    // Only rotating joints can be frozen.
    assert!(matches!(
        layout.clone().freeze_joints(&[4]),
        Err(PoseError::BadJointOrder(_))
    ));
    assert!(matches!(
        layout.freeze_joints(&[99]),
        Err(PoseError::BadJointOrder(_))
    ));
}

#[test]
fn mirrored_names_swap_one_side_marker() {
    use motion_io::{mirrored_names, side_of};
    let cases = [
        ("LeftUpLeg", "RightUpLeg"),
        ("UpperLeg_L", "UpperLeg_R"),
        ("rShldr", "lShldr"),
        ("l_knee", "r_knee"),
        ("foot.R", "foot.L"),
        ("leftEye", "rightEye"),
    ];
    for (a, b) in cases {
        assert!(mirrored_names(a).contains(&b.to_string()), "{a}");
        assert!(mirrored_names(b).contains(&a.to_string()), "{b}");
        assert_eq!(side_of(a), side_of(b).map(|s| !s), "{a} vs {b}");
    }
    assert!(mirrored_names("Spine").is_empty());
    assert!(mirrored_names("abdomen").is_empty());
}
