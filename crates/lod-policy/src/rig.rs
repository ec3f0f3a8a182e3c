//! [`Rig`]: the model's skeleton as the runtime needs it, and forward kinematics in f32 into
//! caller-owned slices.
//!
//! A rig lists the joints of the model's skeleton, parents before children (the skeleton's own
//! order, so one pass evaluates it), each with its parent, its offset from the parent in metres,
//! its rest rotation and what drives it ([`JointRole`]): the root rows of the pose vector, three
//! rows of it (the rotating joints, in the model's row order), or nothing (a static joint keeps its
//! rest rotation). Pose rows are those of docs/architecture.md: `0..3` root position, `3..6` root
//! exponential map, `6` time increment, then 3 rows per rotating joint.
//!
//! `world_j = world_parent(j) * (offset_j, local_j)`, with `local_j` the exponential map of the
//! joint's rows for the first `active_joints` rotating joints and the rest rotation otherwise.
//! Joints that are not below the motion root are placed on the ground under it.

use std::ops::Range;

use glam::{Quat, Vec3};
use serde::{Deserialize, Serialize};

use crate::error::RigError;
use crate::model::{ALWAYS_ROWS, ROWS_PER_JOINT};

/// Rigs up to this many joints run forward kinematics without any allocation (larger ones
/// allocate one scratch buffer per [`Rig::joint_positions`] call).
pub const STACK_JOINTS: usize = 128;

/// Largest `| |q| - 1 |` accepted for a rest rotation.
const UNIT_TOLERANCE: f32 = 1e-4;

/// The rotation of an exponential map `v` (rotation vector, any length):
/// `q = (sin(|v|/2) v/|v|, cos(|v|/2))`, with a Taylor series of `sin(|v|/2)/|v|` below `1e-3`, for
/// forward kinematics (smooth through 0, no division by a tiny `|v|`).
///
/// The chaining code's `exp_map_to_quat` is the same rotation by `Quat::from_axis_angle` for the
/// root's heading in cycle chaining and root motion; they can differ in the last bits and each
/// one's rounding is part of results checked bit for bit (joint positions here, chained paths
/// there), so both stay.
#[inline]
pub fn exp_to_quat(v: Vec3) -> Quat {
    let theta = v.length();
    let half = 0.5 * theta;
    let k = if theta < 1e-3 {
        0.5 - theta * theta / 48.0
    } else {
        half.sin() / theta
    };
    Quat::from_xyzw(v.x * k, v.y * k, v.z * k, half.cos())
}

/// What drives a joint of a [`Rig`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum JointRole {
    /// Not below the motion root: static, placed on the ground under the root.
    Outside,
    /// The motion root: position rows `0..3`, rotation rows `3..6`.
    Root,
    /// Rotating joint number `k` of the row order: rows `7 + 3k .. 7 + 3k + 3` (an exponential
    /// map of its local rotation).
    Rotating(usize),
    /// Below the root with a constant local rotation (its rest rotation).
    Static,
}

/// Largest length of a joint's offset [`Rig::new`] accepts, in metres (a thousand kilometres: no
/// body's bone comes near it, and any chain of such bones stays far inside single precision).
pub const MAX_OFFSET_M: f32 = 1e6;

/// Largest magnitude of a pose row forward kinematics reads (root position in metres, exponential
/// maps in radians): far beyond any pose, and small enough that a rotation's length and the joint
/// positions stay finite in single precision.
pub const MAX_POSE_VALUE: f32 = 1e18;

/// A body scale must be finite and positive.
fn check_scale(scale: f32) -> Result<(), RigError> {
    if scale.is_finite() && scale > 0.0 {
        Ok(())
    } else {
        Err(RigError::Scale(scale))
    }
}

/// One joint of a [`Rig`] (stored as is in the model file's runtime section).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RigJoint {
    /// The joint's name in the source data.
    pub name: String,
    /// Index of the parent joint in the rig (smaller than this joint's), `None` for the skeleton's
    /// top joint.
    pub parent: Option<usize>,
    /// Translation from the parent, in metres.
    pub offset: Vec3,
    /// Local rotation used when the pose does not drive the joint (static joints; rotating joints
    /// beyond the active count: the data's mean rotation). A unit quaternion.
    pub rest: Quat,
    /// What drives the joint.
    pub role: JointRole,
}

/// A joint's rotation and position in the cycle frame (metres), as [`Rig::joint_transforms`]
/// writes them.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct JointTransform {
    /// Orientation of the joint's frame.
    pub rotation: Quat,
    /// Position of the joint, metres.
    pub position: Vec3,
}

/// The model's joints and forward kinematics (see the module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct Rig {
    joints: Vec<RigJoint>,
    /// The longest chain of offsets from the root to a joint (metres, the sum of their lengths):
    /// with it a forward-kinematics call bounds every position (derived by [`Rig::new`]).
    reach_m: f64,
    root: usize,
    /// Rig index of rotating joint `k` of the row order.
    rotating: Vec<usize>,
}

/// Where forward kinematics writes: positions alone (with rotation scratch) or whole transforms.
trait FkOut {
    fn get(&self, j: usize) -> (Vec3, Quat);
    fn set(&mut self, j: usize, position: Vec3, rotation: Quat);
}

struct Split<'a> {
    positions: &'a mut [Vec3],
    rotations: &'a mut [Quat],
}

impl FkOut for Split<'_> {
    #[inline]
    fn get(&self, j: usize) -> (Vec3, Quat) {
        (self.positions[j], self.rotations[j])
    }
    #[inline]
    fn set(&mut self, j: usize, position: Vec3, rotation: Quat) {
        self.positions[j] = position;
        self.rotations[j] = rotation;
    }
}

impl FkOut for [JointTransform] {
    #[inline]
    fn get(&self, j: usize) -> (Vec3, Quat) {
        (self[j].position, self[j].rotation)
    }
    #[inline]
    fn set(&mut self, j: usize, position: Vec3, rotation: Quat) {
        self[j] = JointTransform { rotation, position };
    }
}

impl Rig {
    /// A validated rig: at least one joint and exactly one [`JointRole::Root`]; every joint's parent
    /// before it, and present for rotating and static joints; rotating joints numbered `0..n`, each
    /// number once; finite offsets no longer than [`MAX_OFFSET_M`] and unit rest rotations (within
    /// `1e-4`). Each failure names the joint.
    pub fn new(joints: Vec<RigJoint>) -> Result<Rig, RigError> {
        if joints.is_empty() {
            return Err(RigError::Structure("no joints".into()));
        }
        let bad = |j: usize, reason: String| RigError::Joint {
            joint: j,
            name: joints[j].name.clone(),
            reason,
        };
        let mut root = None;
        let mut slots: Vec<Option<usize>> = vec![None; joints.len()];
        for (j, joint) in joints.iter().enumerate() {
            if let Some(p) = joint.parent
                && p >= j
            {
                return Err(bad(j, format!("parent {p} does not come before the joint")));
            }
            match joint.role {
                JointRole::Root => {
                    if let Some(r) = root {
                        return Err(bad(j, format!("a second root (the first is joint {r})")));
                    }
                    root = Some(j);
                }
                JointRole::Rotating(k) => {
                    let slot = slots.get_mut(k).ok_or_else(|| {
                        bad(
                            j,
                            format!("rotating joint number {k} of only {} joints", joints.len()),
                        )
                    })?;
                    if let Some(other) = slot.replace(j) {
                        return Err(bad(
                            j,
                            format!("rotating joint number {k} is also joint {other}'s"),
                        ));
                    }
                }
                JointRole::Static | JointRole::Outside => {}
            }
            if matches!(joint.role, JointRole::Rotating(_) | JointRole::Static)
                && joint.parent.is_none()
            {
                return Err(bad(j, "a joint below the root needs a parent".into()));
            }
            if !joint.offset.is_finite() {
                return Err(bad(j, format!("offset {} is not finite", joint.offset)));
            }
            if joint.offset.length() > MAX_OFFSET_M {
                return Err(bad(
                    j,
                    format!("offset {} is longer than {MAX_OFFSET_M} m", joint.offset),
                ));
            }
            let q = joint.rest;
            if !q.is_finite() || (q.length() - 1.0).abs() > UNIT_TOLERANCE {
                return Err(bad(
                    j,
                    format!("rest rotation {q} is not a unit quaternion"),
                ));
            }
        }
        let root = root.ok_or_else(|| RigError::Structure("no root joint".into()))?;
        let n = slots.iter().take_while(|s| s.is_some()).count();
        if let Some(k) = slots[n..].iter().position(Option::is_some) {
            return Err(RigError::Structure(format!(
                "rotating joint number {n} is missing (number {} is used)",
                n + k
            )));
        }
        let rotating = slots[..n].iter().flatten().copied().collect();
        // Parents come first: each joint's chain length from its parent's.
        let mut chain = vec![0.0f64; joints.len()];
        for (j, joint) in joints.iter().enumerate() {
            let up = joint.parent.map_or(0.0, |p| chain[p]);
            chain[j] = up + f64::from(joint.offset.length());
        }
        let reach_m = chain.iter().copied().fold(0.0, f64::max);
        Ok(Rig {
            joints,
            reach_m,
            root,
            rotating,
        })
    }

    /// The joints, parents before children.
    pub fn joints(&self) -> &[RigJoint] {
        &self.joints
    }

    /// Number of joints (the length [`Rig::joint_positions`] writes).
    pub fn joint_count(&self) -> usize {
        self.joints.len()
    }

    /// Index of the motion root.
    pub fn root(&self) -> usize {
        self.root
    }

    /// Rig indices of the rotating joints in row order (entry `k` is driven by rows
    /// `7 + 3k .. 7 + 3k + 3`).
    pub fn rotating_joints(&self) -> &[usize] {
        &self.rotating
    }

    /// Pose rows the rig reads: `7 + 3 * rotating joints` (the model's `P`).
    pub fn dof(&self) -> usize {
        ALWAYS_ROWS + ROWS_PER_JOINT * self.rotating.len()
    }

    /// Pose rows that drive joint `j` (`0..6` for the root, three rows for a rotating joint,
    /// `None` otherwise or for an index out of range).
    pub fn rows(&self, j: usize) -> Option<Range<usize>> {
        match self.joints.get(j)?.role {
            JointRole::Root => Some(0..6),
            JointRole::Rotating(k) => {
                let r = ALWAYS_ROWS + ROWS_PER_JOINT * k;
                Some(r..r + ROWS_PER_JOINT)
            }
            JointRole::Outside | JointRole::Static => None,
        }
    }

    /// Index of the joint called `name` (exact match).
    pub fn find(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }

    /// Checks the slices of a forward-kinematics call; returns the number of active joints.
    fn check(&self, pose: &[f32], active_joints: usize, out: usize) -> Result<usize, RigError> {
        let active = active_joints.min(self.rotating.len());
        let needed = if active == 0 {
            6
        } else {
            ALWAYS_ROWS + ROWS_PER_JOINT * active
        };
        if pose.len() < needed {
            return Err(RigError::PoseLength {
                active,
                needed,
                found: pose.len(),
            });
        }
        if out < self.joints.len() {
            return Err(RigError::OutputLength {
                joints: self.joints.len(),
                found: out,
            });
        }
        check_rows(&pose[..needed])?;
        Ok(active)
    }

    /// [`Rig::check`] for a call that places joints at `scale`: the root's position plus the
    /// longest chain of bones at that scale must stay well inside single precision.
    fn check_reach(&self, pose: &[f32], scale: f32) -> Result<(), RigError> {
        let root = (0..3).fold(0.0f64, |m, i| m.max(f64::from(pose[i].abs())));
        let reach = root + self.reach_m * f64::from(scale);
        if reach <= 0.25 * f64::from(f32::MAX) {
            Ok(())
        } else {
            Err(RigError::Overflow {
                scale,
                reach_m: reach,
            })
        }
    }

    /// Checks that `pose` suits forward kinematics for `active_joints` (its length and its values,
    /// as every forward-kinematics call checks them), without running it.
    pub(crate) fn check_pose(&self, pose: &[f32], active_joints: usize) -> Result<(), RigError> {
        self.check(pose, active_joints, self.joints.len())
            .map(|_| ())
    }

    /// World positions in metres (the cycle frame of the pose) of every joint, into `out[..joint_count]`.
    ///
    /// Only the first `active_joints` rotating joints are read from `pose` (which may be truncated
    /// to `7 + 3 * active_joints` rows, a level's `P'`; 6 rows with no active joint); the others
    /// take their rest rotation. No allocation for rigs of up to 128 joints (`STACK_JOINTS`). Errors: a
    /// pose shorter than the active joints' rows, a row it reads that is not finite or larger than
    /// [`MAX_POSE_VALUE`] ([`RigError::PoseValue`]), an output shorter than the joint count, a
    /// root and bones so far out that a position could overflow ([`RigError::Overflow`]).
    pub fn joint_positions(
        &self,
        pose: &[f32],
        active_joints: usize,
        out: &mut [Vec3],
    ) -> Result<(), RigError> {
        self.joint_positions_scaled(pose, active_joints, 1.0, out)
    }

    /// [`Rig::joint_positions`] of a body `scale` times the rig's size: every bone below the root
    /// (each joint's [`RigJoint::offset`]) is multiplied by `scale`, the root's position and every
    /// rotation are the pose's. A character whose standing height is `scale` times the rig's (see
    /// [`crate::ControlSpace::body_scale`]); `scale = 1` gives [`Rig::joint_positions`] bit for bit.
    /// Errors as [`Rig::joint_positions`], and a `scale` that is not finite and positive.
    pub fn joint_positions_scaled(
        &self,
        pose: &[f32],
        active_joints: usize,
        scale: f32,
        out: &mut [Vec3],
    ) -> Result<(), RigError> {
        check_scale(scale)?;
        let active = self.check(pose, active_joints, out.len())?;
        self.check_reach(pose, scale)?;
        let nj = self.joints.len();
        let mut stack = [Quat::IDENTITY; STACK_JOINTS];
        let mut heap = Vec::new();
        let rotations: &mut [Quat] = if nj <= STACK_JOINTS {
            &mut stack[..nj]
        } else {
            heap.resize(nj, Quat::IDENTITY);
            &mut heap
        };
        let mut split = Split {
            positions: out,
            rotations,
        };
        self.forward(pose, active, scale, &mut split, |_| true);
        Ok(())
    }

    /// World rotation and position (metres, the cycle frame of the pose) of every joint, into
    /// `out[..joint_count]`; positions are those of [`Rig::joint_positions`], bit for bit. Never
    /// allocates. Errors as [`Rig::joint_positions`].
    pub fn joint_transforms(
        &self,
        pose: &[f32],
        active_joints: usize,
        out: &mut [JointTransform],
    ) -> Result<(), RigError> {
        self.joint_transforms_scaled(pose, active_joints, 1.0, out)
    }

    /// [`Rig::joint_transforms`] of a body `scale` times the rig's size (as
    /// [`Rig::joint_positions_scaled`]; positions are its, bit for bit). Never allocates.
    pub fn joint_transforms_scaled(
        &self,
        pose: &[f32],
        active_joints: usize,
        scale: f32,
        out: &mut [JointTransform],
    ) -> Result<(), RigError> {
        check_scale(scale)?;
        let active = self.check(pose, active_joints, out.len())?;
        self.check_reach(pose, scale)?;
        self.forward(pose, active, scale, out, |_| true);
        Ok(())
    }

    /// [`Rig::joint_transforms_scaled`] for the joints `needed` marks only (a marked joint's parent
    /// must be marked too; `needed.len() >= joint_count`); the other slots of `out` are left as
    /// they are. The marked transforms are those of [`Rig::joint_transforms_scaled`], bit for bit.
    pub(crate) fn joint_transforms_of(
        &self,
        pose: &[f32],
        active_joints: usize,
        scale: f32,
        needed: &[bool],
        out: &mut [JointTransform],
    ) -> Result<(), RigError> {
        check_scale(scale)?;
        let active = self.check(pose, active_joints, out.len())?;
        self.check_reach(pose, scale)?;
        self.forward(pose, active, scale, out, |j| needed[j]);
        Ok(())
    }

    /// Local rotation of every joint relative to its parent, into `out[..joint_count]`: what a
    /// skinned mesh's bones take (with the joints' [`RigJoint::offset`]s as local translations, and
    /// the root's translation from pose rows `0..3`). The root's is its orientation in the cycle
    /// frame, a joint not below the root has none (identity), a rotating joint beyond
    /// `active_joints` and a static joint their rest rotation. Never allocates. Errors as
    /// [`Rig::joint_positions`].
    pub fn local_rotations(
        &self,
        pose: &[f32],
        active_joints: usize,
        out: &mut [Quat],
    ) -> Result<(), RigError> {
        let active = self.check(pose, active_joints, out.len())?;
        for (j, q) in out[..self.joints.len()].iter_mut().enumerate() {
            *q = self.local_rotation(j, pose, active);
        }
        Ok(())
    }

    /// Joint `j`'s local rotation (see [`Rig::local_rotations`]); `pose` is checked.
    #[inline]
    fn local_rotation(&self, j: usize, pose: &[f32], active: usize) -> Quat {
        let joint = &self.joints[j];
        match joint.role {
            JointRole::Outside => Quat::IDENTITY,
            JointRole::Root => exp_to_quat(Vec3::new(pose[3], pose[4], pose[5])),
            JointRole::Rotating(k) if k < active => {
                let r = ALWAYS_ROWS + ROWS_PER_JOINT * k;
                exp_to_quat(Vec3::new(pose[r], pose[r + 1], pose[r + 2]))
            }
            _ => joint.rest,
        }
    }

    fn forward<O: FkOut + ?Sized>(
        &self,
        pose: &[f32],
        active: usize,
        scale: f32,
        out: &mut O,
        keep: impl Fn(usize) -> bool,
    ) {
        let root_pos = Vec3::new(pose[0], pose[1], pose[2]);
        let ground = Vec3::new(root_pos.x, 0.0, root_pos.z);
        for (j, joint) in self.joints.iter().enumerate() {
            if !keep(j) {
                continue;
            }
            match joint.role {
                JointRole::Outside => out.set(j, ground, Quat::IDENTITY),
                JointRole::Root => out.set(j, root_pos, self.local_rotation(j, pose, active)),
                _ => {
                    let (parent_pos, parent_rot) = out.get(joint.parent.unwrap_or(0));
                    let local = self.local_rotation(j, pose, active);
                    out.set(
                        j,
                        parent_pos + parent_rot * (joint.offset * scale),
                        parent_rot * local,
                    );
                }
            }
        }
    }
}

/// The rows forward kinematics reads: each finite and at most [`MAX_POSE_VALUE`] in magnitude.
fn check_rows(rows: &[f32]) -> Result<(), RigError> {
    match rows
        .iter()
        .position(|v| v.is_nan() || v.abs() > MAX_POSE_VALUE)
    {
        None => Ok(()),
        Some(row) => Err(RigError::PoseValue {
            row,
            value: rows[row],
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn joint(name: &str, parent: Option<usize>, offset: [f32; 3], role: JointRole) -> RigJoint {
        RigJoint {
            name: name.into(),
            parent,
            offset: Vec3::from_array(offset),
            rest: Quat::IDENTITY,
            role,
        }
    }

    /// Ground (outside) -> hips (root) -> spine (rotating 1) -> head (static); hips -> leg
    /// (rotating 0).
    fn rig() -> Rig {
        Rig::new(vec![
            joint("ground", None, [0.0; 3], JointRole::Outside),
            joint("hips", Some(0), [0.0; 3], JointRole::Root),
            joint("spine", Some(1), [0.0, 0.5, 0.0], JointRole::Rotating(1)),
            joint("head", Some(2), [0.0, 0.3, 0.0], JointRole::Static),
            joint("leg", Some(1), [0.1, -0.5, 0.0], JointRole::Rotating(0)),
        ])
        .unwrap()
    }

    /// A scaled body: every joint below the root moves away from the root by the scale (the root
    /// and the ground joint stay where the pose puts them); scale 1 is the plain forward kinematics
    /// bit for bit; a scale that is not finite and positive is refused.
    #[test]
    fn a_scaled_body_stretches_every_bone_below_the_root() {
        let rig = rig();
        let mut pose = vec![0.0f32; rig.dof()];
        pose[..6].copy_from_slice(&[0.3, 0.9, -0.2, 0.1, 0.7, -0.2]);
        pose[7..13].copy_from_slice(&[0.4, -0.1, 0.2, -0.3, 0.2, 0.5]);
        let fk = |scale: f32| {
            let mut out = vec![Vec3::ZERO; rig.joint_count()];
            rig.joint_positions_scaled(&pose, 2, scale, &mut out)
                .unwrap();
            let mut tr = vec![JointTransform::default(); rig.joint_count()];
            rig.joint_transforms_scaled(&pose, 2, scale, &mut tr)
                .unwrap();
            assert!(out.iter().zip(&tr).all(|(p, t)| *p == t.position));
            out
        };
        let mut plain = vec![Vec3::ZERO; rig.joint_count()];
        rig.joint_positions(&pose, 2, &mut plain).unwrap();
        assert_eq!(fk(1.0), plain);
        let big = fk(1.25);
        let root = plain[1];
        assert_eq!(big[0], plain[0]);
        assert_eq!(big[1], root);
        for j in 2..rig.joint_count() {
            let expected = root + 1.25 * (plain[j] - root);
            assert!(big[j].distance(expected) < 1e-6, "joint {j}");
        }
        let mut out = vec![Vec3::ZERO; rig.joint_count()];
        for bad in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            assert!(matches!(
                rig.joint_positions_scaled(&pose, 2, bad, &mut out),
                Err(RigError::Scale(_))
            ));
        }
    }

    #[test]
    fn forward_kinematics_follows_the_rows() {
        let rig = rig();
        assert_eq!(rig.dof(), 13);
        assert_eq!(rig.rotating_joints(), &[4, 2]);
        assert_eq!(rig.rows(2), Some(10..13));
        assert_eq!(rig.rows(3), None);
        // Root at (1, 0.9, 2) turned 90 degrees about y; spine bent 90 degrees about z.
        let h = std::f32::consts::FRAC_PI_2;
        let mut pose = [0.0f32; 13];
        pose[..6].copy_from_slice(&[1.0, 0.9, 2.0, 0.0, h, 0.0]);
        pose[12] = h;
        let mut pos = [Vec3::ZERO; 5];
        rig.joint_positions(&pose, 2, &mut pos).unwrap();
        assert_eq!(pos[0], Vec3::new(1.0, 0.0, 2.0));
        assert_eq!(pos[1], Vec3::new(1.0, 0.9, 2.0));
        assert!(pos[2].abs_diff_eq(Vec3::new(1.0, 1.4, 2.0), 1e-6));
        // The head sits 0.3 m along the spine's bent y axis: -x in the spine frame, then the root's
        // quarter turn about y takes -x to +z.
        assert!(
            pos[3].abs_diff_eq(Vec3::new(1.0, 1.4, 2.3), 1e-6),
            "{}",
            pos[3]
        );
        assert!(
            pos[4].abs_diff_eq(Vec3::new(1.0, 0.4, 1.9), 1e-6),
            "{}",
            pos[4]
        );
        // One active joint: the spine takes its rest rotation and may be cut from the pose.
        rig.joint_positions(&pose[..10], 1, &mut pos).unwrap();
        assert!(
            pos[3].abs_diff_eq(Vec3::new(1.0, 1.7, 2.0), 1e-6),
            "{}",
            pos[3]
        );
        // Transforms agree with positions bit for bit.
        let mut tr = [JointTransform::default(); 5];
        rig.joint_transforms(&pose, 2, &mut tr).unwrap();
        rig.joint_positions(&pose, 2, &mut pos).unwrap();
        for (t, p) in tr.iter().zip(&pos) {
            assert_eq!(t.position, *p);
        }
    }

    #[test]
    fn short_slices_and_bad_rigs_are_errors() {
        let rig = rig();
        let mut pos = [Vec3::ZERO; 5];
        let e = rig.joint_positions(&[0.0; 9], 1, &mut pos).unwrap_err();
        assert_eq!(
            e,
            RigError::PoseLength {
                active: 1,
                needed: 10,
                found: 9
            }
        );
        assert!(rig.joint_positions(&[0.0; 6], 0, &mut pos).is_ok());
        let e = rig
            .joint_positions(&[0.0; 13], 2, &mut pos[..4])
            .unwrap_err();
        assert!(e.to_string().contains("4 slots for 5 joints"), "{e}");

        let mut joints = rig.joints().to_vec();
        joints[3].parent = Some(4);
        let e = Rig::new(joints).unwrap_err();
        assert!(e.to_string().contains("head"), "{e}");
        let mut joints = rig.joints().to_vec();
        joints[4].role = JointRole::Rotating(1);
        assert!(Rig::new(joints).is_err());
        let mut joints = rig.joints().to_vec();
        joints[4].role = JointRole::Rotating(2);
        assert!(Rig::new(joints).is_err());
        let mut joints = rig.joints().to_vec();
        joints[2].rest = Quat::from_xyzw(0.0, 0.0, 0.0, 2.0);
        assert!(Rig::new(joints).is_err());
        let mut joints = rig.joints().to_vec();
        joints[1].role = JointRole::Static;
        assert!(matches!(Rig::new(joints), Err(RigError::Structure(_))));
        assert!(Rig::new(Vec::new()).is_err());
    }

    #[test]
    fn exp_map_is_a_rotation_about_its_axis() {
        let q = exp_to_quat(Vec3::new(0.0, 0.0, std::f32::consts::PI));
        assert!((q * Vec3::X).abs_diff_eq(-Vec3::X, 1e-6));
        assert_eq!(exp_to_quat(Vec3::ZERO), Quat::IDENTITY);
    }
}
