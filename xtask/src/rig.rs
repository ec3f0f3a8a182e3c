//! The humanoid skeleton of the procedural walker, scaled to a performer's standing height.
//!
//! 19 joints, centimetres, Y up, facing +Z (left = +X), every bone of the rest pose along a
//! coordinate axis: legs and arms hang straight down, spine and neck point up, feet point forward.
//! The root `Hips` has six channels `Xposition Yposition Zposition Zrotation Xrotation Yrotation`,
//! every other joint three `Zrotation Xrotation Yrotation` (the order of the Bandai-Namco files;
//! local rotation `R = Rz * Rx * Ry`). Joint names follow the Bandai-Namco data set so that tools
//! written for that data find the feet and toes by name.

use glam::DVec3;
use motion_io::{Channel, Joint, Skeleton};

/// Index of the root joint `Hips` (pelvis centre).
pub const HIPS: usize = 0;
/// Index of `Spine` (lumbar).
pub const SPINE: usize = 1;
/// Index of `Chest` (thorax).
pub const CHEST: usize = 2;
/// Index of `Neck`.
pub const NECK: usize = 3;
/// Index of `Head`.
pub const HEAD: usize = 4;
/// Index of `UpperArm_L` (left shoulder joint).
pub const UPPER_ARM_L: usize = 5;
/// Index of `LowerArm_L` (left elbow).
pub const LOWER_ARM_L: usize = 6;
/// Index of `Hand_L` (left wrist).
pub const HAND_L: usize = 7;
/// Index of `UpperArm_R`.
pub const UPPER_ARM_R: usize = 8;
/// Index of `LowerArm_R`.
pub const LOWER_ARM_R: usize = 9;
/// Index of `Hand_R`.
pub const HAND_R: usize = 10;
/// Index of `UpperLeg_L` (left hip joint).
pub const UPPER_LEG_L: usize = 11;
/// Index of `LowerLeg_L` (left knee).
pub const LOWER_LEG_L: usize = 12;
/// Index of `Foot_L` (left ankle).
pub const FOOT_L: usize = 13;
/// Index of `Toes_L` (left ball of the foot).
pub const TOES_L: usize = 14;
/// Index of `UpperLeg_R`.
pub const UPPER_LEG_R: usize = 15;
/// Index of `LowerLeg_R`.
pub const LOWER_LEG_R: usize = 16;
/// Index of `Foot_R`.
pub const FOOT_R: usize = 17;
/// Index of `Toes_R`.
pub const TOES_R: usize = 18;
/// Number of joints.
pub const JOINT_COUNT: usize = 19;
/// Channels per frame: 6 for the root, 3 for each other joint.
pub const CHANNEL_COUNT: usize = 6 + 3 * (JOINT_COUNT - 1);

/// Segment dimensions of one performer in centimetres (all proportional to the standing height).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rig {
    /// Standing height (floor to the top of the head), cm.
    pub height: f64,
    /// Thigh length (hip joint to knee), cm.
    pub thigh: f64,
    /// Shank length (knee to ankle), cm.
    pub shank: f64,
    /// Ankle height above the floor with the foot flat, cm.
    pub ankle_height: f64,
    /// Hip joint below the pelvis centre, cm.
    pub hip_drop: f64,
    /// Hip joint to the side of the pelvis centre, cm.
    pub hip_half_width: f64,
    /// Heel contact point behind the ankle, cm (on the floor when the foot is flat).
    pub heel_back: f64,
    /// Ball of the foot (`Toes` joint) in front of the ankle, cm.
    pub ball_forward: f64,
    /// Height of the ball joint above the floor with the foot flat, cm.
    pub ball_height: f64,
    /// Toe length (ball to tip), cm.
    pub toe_length: f64,
}

/// One joint of the rig: name, parent, rest offset (cm) and End Site offset.
struct JointSpec {
    name: &'static str,
    parent: Option<usize>,
    offset: DVec3,
    end_site: Option<DVec3>,
}

impl Rig {
    /// The rig of a performer `height_m` metres tall; segment lengths are fixed fractions of the
    /// height (close to Winter's anthropometric table: hip joint at 0.530 H, knee at 0.285 H,
    /// ankle at 0.040 H, shoulder at 0.818 H).
    pub fn new(height_m: f64) -> Rig {
        let h = height_m * 100.0;
        Rig {
            height: h,
            thigh: 0.245 * h,
            shank: 0.245 * h,
            ankle_height: 0.040 * h,
            hip_drop: 0.030 * h,
            hip_half_width: 0.050 * h,
            heel_back: 0.030 * h,
            ball_forward: 0.080 * h,
            ball_height: 0.011 * h,
            toe_length: 0.032 * h,
        }
    }

    /// Height of the hip joints above the floor in the rest pose, cm.
    pub fn hip_height(&self) -> f64 {
        self.ankle_height + self.shank + self.thigh
    }

    /// Offset of the left (`side = 1`) or right (`side = -1`) hip joint from the pelvis centre.
    pub fn hip_offset(&self, side: f64) -> DVec3 {
        DVec3::new(side * self.hip_half_width, -self.hip_drop, 0.0)
    }

    /// Heel contact point relative to the ankle, in the foot's frame.
    pub fn heel_local(&self) -> DVec3 {
        DVec3::new(0.0, -self.ankle_height, -self.heel_back)
    }

    /// Ball joint (`Toes`) relative to the ankle, in the foot's frame.
    pub fn ball_local(&self) -> DVec3 {
        DVec3::new(0.0, self.ball_height - self.ankle_height, self.ball_forward)
    }

    fn joint_specs(&self) -> [JointSpec; JOINT_COUNT] {
        let h = self.height;
        let v = DVec3::new;
        let spec = |name, parent: Option<usize>, offset, end_site| JointSpec {
            name,
            parent,
            offset,
            end_site,
        };
        let toe_end = Some(v(0.0, -0.007 * h, self.toe_length));
        [
            spec("Hips", None, DVec3::ZERO, None),
            spec("Spine", Some(HIPS), v(0.0, 0.060 * h, 0.0), None),
            spec("Chest", Some(SPINE), v(0.0, 0.100 * h, 0.0), None),
            spec("Neck", Some(CHEST), v(0.0, 0.125 * h, 0.0), None),
            spec(
                "Head",
                Some(NECK),
                v(0.0, 0.055 * h, 0.008 * h),
                Some(v(0.0, 0.100 * h, 0.0)),
            ),
            spec(
                "UpperArm_L",
                Some(CHEST),
                v(0.125 * h, 0.098 * h, 0.0),
                None,
            ),
            spec(
                "LowerArm_L",
                Some(UPPER_ARM_L),
                v(0.0, -0.186 * h, 0.0),
                None,
            ),
            spec(
                "Hand_L",
                Some(LOWER_ARM_L),
                v(0.0, -0.146 * h, 0.0),
                Some(v(0.0, -0.100 * h, 0.0)),
            ),
            spec(
                "UpperArm_R",
                Some(CHEST),
                v(-0.125 * h, 0.098 * h, 0.0),
                None,
            ),
            spec(
                "LowerArm_R",
                Some(UPPER_ARM_R),
                v(0.0, -0.186 * h, 0.0),
                None,
            ),
            spec(
                "Hand_R",
                Some(LOWER_ARM_R),
                v(0.0, -0.146 * h, 0.0),
                Some(v(0.0, -0.100 * h, 0.0)),
            ),
            spec("UpperLeg_L", Some(HIPS), self.hip_offset(1.0), None),
            spec(
                "LowerLeg_L",
                Some(UPPER_LEG_L),
                v(0.0, -self.thigh, 0.0),
                None,
            ),
            spec("Foot_L", Some(LOWER_LEG_L), v(0.0, -self.shank, 0.0), None),
            spec("Toes_L", Some(FOOT_L), self.ball_local(), toe_end),
            spec("UpperLeg_R", Some(HIPS), self.hip_offset(-1.0), None),
            spec(
                "LowerLeg_R",
                Some(UPPER_LEG_R),
                v(0.0, -self.thigh, 0.0),
                None,
            ),
            spec("Foot_R", Some(LOWER_LEG_R), v(0.0, -self.shank, 0.0), None),
            spec("Toes_R", Some(FOOT_R), self.ball_local(), toe_end),
        ]
    }

    /// The rig as a `motion_io` skeleton (joints depth-first, channels as described in the module
    /// documentation).
    pub fn skeleton(&self) -> Skeleton {
        use Channel::*;
        let joints = self
            .joint_specs()
            .into_iter()
            .map(|s| Joint {
                name: s.name.to_string(),
                parent: s.parent,
                offset: s.offset,
                channels: if s.parent.is_none() {
                    vec![
                        Xposition, Yposition, Zposition, Zrotation, Xrotation, Yrotation,
                    ]
                } else {
                    vec![Zrotation, Xrotation, Yrotation]
                },
                end_site: s.end_site,
            })
            .collect();
        Skeleton { joints }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn skeleton_is_valid_and_depth_first() {
        let sk = Rig::new(1.75).skeleton();
        sk.validate().unwrap();
        assert_eq!(sk.joint_count(), JOINT_COUNT);
        assert_eq!(sk.channel_count(), CHANNEL_COUNT);
        assert_eq!(sk.find("Toes_R"), Some(TOES_R));
        assert_eq!(sk.find("Hand_L"), Some(HAND_L));
        // Depth-first: every joint's subtree is contiguous, i.e. a joint's parent is the nearest
        // earlier joint on the path back to the root.
        for (i, j) in sk.joints.iter().enumerate().skip(1) {
            let p = j.parent.unwrap();
            for k in p + 1..i {
                assert!(
                    sk.is_ancestor_or_self(p, k),
                    "joint {k} between {p} and its child {i}"
                );
            }
        }
    }

    #[test]
    fn rest_pose_matches_the_standing_height() {
        for h in [1.6, 1.75, 1.9] {
            let rig = Rig::new(h);
            let sk = rig.skeleton();
            let mut frame = vec![0.0; CHANNEL_COUNT];
            frame[1] = rig.hip_height() + rig.hip_drop;
            let pos = sk.joint_positions(&frame);
            let head_top = pos[HEAD] + sk.joints[HEAD].end_site.unwrap();
            assert!(
                (head_top.y - rig.height).abs() < 1e-9,
                "head top at {}",
                head_top.y
            );
            assert!((pos[FOOT_L].y - rig.ankle_height).abs() < 1e-9);
            assert!((pos[TOES_R].y - rig.ball_height).abs() < 1e-9);
            let toe_tip = pos[TOES_L] + sk.joints[TOES_L].end_site.unwrap();
            assert!(toe_tip.y > 0.0 && toe_tip.y < 0.01 * rig.height);
            assert!(pos[UPPER_LEG_L].x > 0.0, "left is +X");
        }
    }
}
