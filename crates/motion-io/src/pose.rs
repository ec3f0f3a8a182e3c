//! Pose vectors (paper section 3: root position, root orientation and joint rotations as
//! exponential maps) and the layout that maps them to and from BVH channels.
//!
//! Rows (docs/architecture.md): `0..3` root position in metres, `3..6` root orientation
//! (exp-map), `6` time increment (left 0 here), then 3 rows per rotating joint in the layout's
//! joint order.

use std::ops::Range;

use glam::{DQuat, DVec3, Vec3};
use lod_policy::{JointRole, Rig, RigJoint};
use serde::{Deserialize, Serialize};

use crate::euler::{channels_to_quat, quat_to_channels};
use crate::expmap::{exp_to_quat, nearest_branch, quat_to_exp};
use crate::motion::Motion;
use crate::skeleton::{Skeleton, SkeletonError, Transform};

/// Rows before the first joint: root position (3), root orientation (3), time increment (1): the
/// runtime's constant, one name for it everywhere.
pub use lod_policy::ALWAYS_ROWS;
/// Row of the time increment (the runtime's constant).
pub use lod_policy::TIME_ROW;

/// Errors of pose-vector construction and conversion.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PoseError {
    /// No motion was given where at least one is needed.
    #[error("no motions given")]
    NoMotions,
    /// The skeleton is invalid.
    #[error("invalid skeleton: {0}")]
    Skeleton(#[from] SkeletonError),
    /// A motion's skeleton differs from the layout's (joint names or channels).
    #[error("motion {motion}: skeleton differs from the layout's at joint {joint} ({what})")]
    SkeletonMismatch {
        /// Index of the motion in the list given (0 for single-motion calls).
        motion: usize,
        /// Joint index.
        joint: usize,
        /// What differs.
        what: String,
    },
    /// A frame index beyond the motion.
    #[error("frame {frame} out of range (motion has {count} frames)")]
    FrameOutOfRange {
        /// Requested frame.
        frame: usize,
        /// Frames in the motion.
        count: usize,
    },
    /// A slice of the wrong length.
    #[error("{what}: expected length {expected}, found {found}")]
    Length {
        /// Which slice.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Actual length.
        found: usize,
    },
    /// A pose-vector length that is not `7 + 3 n`, or a buffer that is not whole poses.
    #[error(
        "pose dimension {dof} with buffer length {len}: need dof = 7 + 3 n and len a multiple of dof"
    )]
    BadShape {
        /// The pose dimension given.
        dof: usize,
        /// The buffer length.
        len: usize,
    },
    /// A joint order that is not a permutation of the layout's rotating joints.
    #[error("joint order is not a permutation of the rotating joints: {0}")]
    BadJointOrder(String),
    /// Units per metre must be positive and finite.
    #[error("units per metre must be positive and finite, found {0}")]
    BadUnits(f64),
    /// A NaN or infinite value in the input.
    #[error("non-finite value in {what} at index {index}")]
    NonFinite {
        /// Which input.
        what: &'static str,
        /// Index of the value.
        index: usize,
    },
    /// Stored layout parts that do not describe a layout of their skeleton
    /// ([`PoseLayout::from_parts`]).
    #[error("invalid pose layout: {0}")]
    BadLayout(String),
    /// A frame time that is not positive and finite ([`PoseLayout::motion_from_poses`]).
    #[error("frame time must be positive and finite, found {0}")]
    BadFrameTime(f64),
}

/// How a joint is evaluated by the layout's forward kinematics.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
enum Role {
    /// Not below the motion root: static, placed on the ground under the root by the pose FK.
    Outside,
    /// The motion root.
    Root,
    /// Rotating joint at position `k` of the joint order.
    Rotating(usize),
    /// Static joint below the root (constant rotation).
    Static,
}

/// Maps between BVH frames and pose vectors for one skeleton, and evaluates pose vectors.
///
/// The motion root is the first joint whose position channels vary (joints above it are static:
/// in the Bandai files `joint_Root` is all zero and `Hips` carries the root motion). Rotating
/// joints are the joints below the root whose rotation channels vary; the others keep the constant
/// rotation of a template frame. Joint translations are the OFFSETs, or for joints with position
/// channels the template frame's values.
///
/// Serialises as [`PoseLayoutParts`] (what it is built from); deserialisation validates them and
/// derives the rest, as [`PoseLayout::from_parts`] does.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "PoseLayoutParts", into = "PoseLayoutParts")]
pub struct PoseLayout {
    skeleton: Skeleton,
    units_per_metre: f64,
    root: usize,
    order: Vec<usize>,
    role: Vec<Role>,
    /// Channel values used for everything the pose vector does not hold.
    template: Vec<f64>,
    channel_starts: Vec<usize>,
    /// World transform of the root's parent in the template frame (identity when the root is 0).
    root_parent_world: Transform,
    /// The root and its ancestors, top (joint 0) first: the joints whose local transforms make the
    /// root's world transform ([`PoseLayout::pose_from_frame`]).
    root_chain: Vec<usize>,
    /// Local rotation of every joint used when it is not evaluated from the pose (static joints:
    /// the template's; rotating joints beyond the active count: the mean rotation).
    rest: Vec<DQuat>,
    offset_m: Vec<DVec3>,
    /// The runtime's rig of this layout (f32 offsets and rest rotations, roles): the f32 forward
    /// kinematics ([`PoseLayout::joint_positions`]) is the runtime's.
    rig: Rig,
}

/// What a [`PoseLayout`] is made of, as stored in files: everything else is derived from these.
///
/// Nothing here is validated; [`PoseLayout::from_parts`] does that.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PoseLayoutParts {
    /// The skeleton.
    pub skeleton: Skeleton,
    /// File units per metre (positive, finite).
    pub units_per_metre: f64,
    /// Skeleton index of the motion root.
    pub root: usize,
    /// Rotating joints (skeleton indices below the root, each with rotation channels) in row order.
    pub joint_order: Vec<usize>,
    /// Channel values used for everything the pose vector does not hold (one per channel).
    pub template: Vec<f64>,
    /// Rest local rotation of every joint (unit quaternions, one per joint).
    pub rest: Vec<DQuat>,
}

impl TryFrom<PoseLayoutParts> for PoseLayout {
    type Error = PoseError;
    fn try_from(parts: PoseLayoutParts) -> Result<PoseLayout, PoseError> {
        PoseLayout::from_parts(parts)
    }
}

impl From<PoseLayout> for PoseLayoutParts {
    fn from(layout: PoseLayout) -> PoseLayoutParts {
        PoseLayoutParts {
            skeleton: layout.skeleton,
            units_per_metre: layout.units_per_metre,
            root: layout.root,
            joint_order: layout.order,
            template: layout.template,
            rest: layout.rest,
        }
    }
}

/// Largest `| |q| - 1 |` accepted for a stored rest rotation.
const UNIT_TOLERANCE: f64 = 1e-6;

/// Rotation channels of joint `j` vary more than `tol` degrees over the motions.
fn channel_ranges(motions: &[&Motion]) -> (Vec<f64>, Vec<f64>) {
    let n = motions[0].skeleton.channel_count();
    let mut lo = vec![f64::INFINITY; n];
    let mut hi = vec![f64::NEG_INFINITY; n];
    for m in motions {
        for f in m.frames.chunks_exact(n) {
            for ((l, h), &v) in lo.iter_mut().zip(hi.iter_mut()).zip(f) {
                *l = l.min(v);
                *h = h.max(v);
            }
        }
    }
    (lo, hi)
}

fn check_same_skeleton(a: &Skeleton, b: &Skeleton, motion: usize) -> Result<(), PoseError> {
    if a.joints.len() != b.joints.len() {
        return Err(PoseError::SkeletonMismatch {
            motion,
            joint: a.joints.len().min(b.joints.len()),
            what: format!("{} vs {} joints", a.joints.len(), b.joints.len()),
        });
    }
    for (i, (x, y)) in a.joints.iter().zip(&b.joints).enumerate() {
        if x.name != y.name || x.parent != y.parent || x.channels != y.channels {
            return Err(PoseError::SkeletonMismatch {
                motion,
                joint: i,
                what: format!("`{}` vs `{}` (name, parent or channels)", x.name, y.name),
            });
        }
    }
    Ok(())
}

impl PoseLayout {
    /// Layout from a skeleton alone: the root is the first joint with position channels (joint 0
    /// when none has), every joint below it with rotation channels rotates, the template frame has
    /// OFFSETs in position channels and zero rotations, and the rest rotation is the identity.
    /// Use [`PoseLayout::from_motions`] for data with static joints (CMU's fingers) or a static
    /// joint above the root (Bandai's `joint_Root`).
    pub fn new(skeleton: &Skeleton, units_per_metre: f64) -> Result<PoseLayout, PoseError> {
        skeleton.validate()?;
        let root = skeleton
            .joints
            .iter()
            .position(|j| j.channels.iter().any(|c| c.is_position()))
            .unwrap_or(0);
        let mut template = Vec::with_capacity(skeleton.channel_count());
        for j in &skeleton.joints {
            for c in &j.channels {
                template.push(if c.is_position() {
                    j.offset[c.axis()]
                } else {
                    0.0
                });
            }
        }
        let rotating: Vec<bool> = skeleton
            .joints
            .iter()
            .map(|j| j.channels.iter().any(|c| c.is_rotation()))
            .collect();
        Self::build(
            skeleton.clone(),
            units_per_metre,
            root,
            &rotating,
            template,
            None,
        )
    }

    /// Layout detected from a set of takes of one skeleton (same joint names, parents and channels;
    /// offsets are taken from the first take): the root is the first joint whose position channels
    /// vary by more than `1e-6` units, rotating joints are those below it whose rotation channels
    /// vary by more than `1e-4` degrees, the template is the first frame of the first take, and
    /// the rest rotation of every rotating joint is its mean rotation over all frames
    /// (sign-aligned quaternion average).
    pub fn from_motions(
        motions: &[&Motion],
        units_per_metre: f64,
    ) -> Result<PoseLayout, PoseError> {
        let first = *motions.first().ok_or(PoseError::NoMotions)?;
        let sk = &first.skeleton;
        sk.validate()?;
        for (i, m) in motions.iter().enumerate() {
            check_same_skeleton(sk, &m.skeleton, i)?;
            if m.frame_count() == 0 {
                return Err(PoseError::FrameOutOfRange { frame: 0, count: 0 });
            }
            if let Some(k) = m.frames.iter().position(|v| !v.is_finite()) {
                return Err(PoseError::NonFinite {
                    what: "motion frames",
                    index: k,
                });
            }
        }
        let (lo, hi) = channel_ranges(motions);
        let starts = sk.channel_starts();
        let varies = |j: usize, pos: bool, tol: f64| {
            sk.joints[j].channels.iter().enumerate().any(|(c, ch)| {
                ch.is_position() == pos && hi[starts[j] + c] - lo[starts[j] + c] > tol
            })
        };
        let root = (0..sk.joints.len())
            .find(|&j| varies(j, true, 1e-6))
            .unwrap_or(0);
        let rotating: Vec<bool> = (0..sk.joints.len())
            .map(|j| varies(j, false, 1e-4))
            .collect();
        let template = first.frame(0).to_vec();
        let mut layout = Self::build(sk.clone(), units_per_metre, root, &rotating, template, None)?;
        // Mean local rotation of each rotating joint over every frame.
        let mut sums = vec![glam::DVec4::ZERO; sk.joints.len()];
        let mut refq: Vec<Option<DQuat>> = vec![None; sk.joints.len()];
        for m in motions {
            for f in 0..m.frame_count() {
                let fr = m.frame(f);
                for &j in &layout.order {
                    let ch = &sk.joints[j].channels;
                    let q = channels_to_quat(ch, &fr[starts[j]..starts[j] + ch.len()]);
                    let r = *refq[j].get_or_insert(q);
                    let q = if q.dot(r) < 0.0 { -q } else { q };
                    sums[j] += glam::DVec4::from(q);
                }
            }
        }
        for &j in &layout.order.clone() {
            let s = sums[j];
            if s.length() > 1e-12 {
                layout.rest[j] = DQuat::from_vec4(s).normalize();
            }
        }
        layout.refresh_rig()?;
        Ok(layout)
    }

    /// Validates stored parts and derives the layout from them (the inverse of
    /// `PoseLayoutParts::from`): a valid skeleton ([`Skeleton::validate`]: one root, parents in
    /// range and before their children, finite offsets); positive finite units; the root one of
    /// its joints; a finite template with one value per channel; a joint order of distinct joints
    /// below the root, each with rotation channels; and one unit rest rotation per joint. Each
    /// failure names the joint or value concerned.
    pub fn from_parts(parts: PoseLayoutParts) -> Result<PoseLayout, PoseError> {
        let PoseLayoutParts {
            skeleton,
            units_per_metre,
            root,
            joint_order,
            template,
            rest,
        } = parts;
        skeleton.validate()?;
        let nj = skeleton.joints.len();
        let bad = |m: String| Err(PoseError::BadLayout(m));
        if root >= nj {
            return bad(format!(
                "root joint {root} is not one of the skeleton's {nj} joints"
            ));
        }
        let channels = skeleton.channel_count();
        if template.len() != channels {
            return Err(PoseError::Length {
                what: "template frame (one value per channel)",
                expected: channels,
                found: template.len(),
            });
        }
        if let Some(index) = template.iter().position(|v| !v.is_finite()) {
            return Err(PoseError::NonFinite {
                what: "template frame",
                index,
            });
        }
        let mut seen = vec![false; nj];
        for (k, &j) in joint_order.iter().enumerate() {
            if j >= nj {
                return bad(format!(
                    "joint order entry {k} names joint {j}; the skeleton has {nj} joints"
                ));
            }
            let name = &skeleton.joints[j].name;
            if j == root || !skeleton.is_ancestor_or_self(root, j) {
                return bad(format!(
                    "joint order entry {k}: joint {j} ({name}) is not below the root joint {root}"
                ));
            }
            if std::mem::replace(&mut seen[j], true) {
                return bad(format!(
                    "joint order entry {k}: joint {j} ({name}) is listed twice"
                ));
            }
            if !skeleton.joints[j].channels.iter().any(|c| c.is_rotation()) {
                return bad(format!(
                    "joint order entry {k}: joint {j} ({name}) has no rotation channels"
                ));
            }
        }
        if rest.len() != nj {
            return Err(PoseError::Length {
                what: "rest rotations (one per joint)",
                expected: nj,
                found: rest.len(),
            });
        }
        for (j, q) in rest.iter().enumerate() {
            if !q.is_finite() || (q.length() - 1.0).abs() > UNIT_TOLERANCE {
                return bad(format!(
                    "rest rotation of joint {j} ({}) is not a unit quaternion: {q:?}",
                    skeleton.joints[j].name
                ));
            }
        }
        let mut layout = Self::build(
            skeleton,
            units_per_metre,
            root,
            &[],
            template,
            Some(joint_order),
        )?;
        layout.rest = rest;
        layout.refresh_rig()?;
        Ok(layout)
    }

    fn build(
        skeleton: Skeleton,
        units_per_metre: f64,
        root: usize,
        rotating: &[bool],
        template: Vec<f64>,
        order: Option<Vec<usize>>,
    ) -> Result<PoseLayout, PoseError> {
        if !(units_per_metre.is_finite() && units_per_metre > 0.0) {
            return Err(PoseError::BadUnits(units_per_metre));
        }
        let nj = skeleton.joints.len();
        let order = order.unwrap_or_else(|| {
            (0..nj)
                .filter(|&j| j != root && rotating[j] && skeleton.is_ancestor_or_self(root, j))
                .collect()
        });
        let mut role = vec![Role::Outside; nj];
        for (j, r) in role.iter_mut().enumerate() {
            if j == root {
                *r = Role::Root;
            } else if skeleton.is_ancestor_or_self(root, j) {
                *r = Role::Static;
            }
        }
        for (k, &j) in order.iter().enumerate() {
            role[j] = Role::Rotating(k);
        }
        let channel_starts = skeleton.channel_starts();
        let mut world = vec![Transform::IDENTITY; nj];
        skeleton.forward_kinematics(&template, &mut world);
        let root_parent_world = skeleton.joints[root]
            .parent
            .map_or(Transform::IDENTITY, |p| world[p]);
        // The skeleton is valid (parents before children): the chain ends within `nj` links.
        let mut root_chain = Vec::new();
        let mut j = Some(root);
        while let Some(k) = j {
            root_chain.push(k);
            j = skeleton.joints[k].parent;
        }
        root_chain.reverse();
        let mut rest = Vec::with_capacity(nj);
        let mut offset_m = Vec::with_capacity(nj);
        for (j, joint) in skeleton.joints.iter().enumerate() {
            let s = channel_starts[j];
            let local = skeleton.local_transform(j, &template[s..s + joint.channels.len()]);
            rest.push(local.rotation);
            offset_m.push(local.position / units_per_metre);
        }
        let rig = make_rig(&skeleton, &role, &rest, &offset_m)?;
        Ok(PoseLayout {
            skeleton,
            units_per_metre,
            root,
            order,
            role,
            template,
            channel_starts,
            root_parent_world,
            root_chain,
            rest,
            offset_m,
            rig,
        })
    }

    /// Rebuilds the runtime rig after the roles or rest rotations changed.
    fn refresh_rig(&mut self) -> Result<(), PoseError> {
        self.rig = make_rig(&self.skeleton, &self.role, &self.rest, &self.offset_m)?;
        Ok(())
    }

    /// The runtime's rig of this layout: its joints (skeleton order), f32 offsets in metres and
    /// rest rotations, and which rows drive each joint. [`PoseLayout::joint_positions`] runs its
    /// forward kinematics.
    pub fn rig(&self) -> &Rig {
        &self.rig
    }

    /// The same layout with the rotating joints in a new order (skeleton joint indices, a
    /// permutation of [`PoseLayout::joint_order`]); rows follow the new order.
    pub fn with_joint_order(mut self, order: Vec<usize>) -> Result<PoseLayout, PoseError> {
        let mut a = order.clone();
        let mut b = self.order.clone();
        a.sort_unstable();
        b.sort_unstable();
        if a != b {
            return Err(PoseError::BadJointOrder(format!(
                "{order:?} vs joints {b:?}"
            )));
        }
        for (k, &j) in order.iter().enumerate() {
            self.role[j] = Role::Rotating(k);
        }
        self.order = order;
        self.refresh_rig()?;
        Ok(self)
    }

    /// The same layout with the rotating joints `joints` (skeleton indices) made static: they leave
    /// the joint order (and the pose vector, whose remaining joint rows keep their relative order),
    /// and hold their current rest rotation ([`PoseLayout::rest_rotation`], e.g. the data's mean after
    /// [`PoseLayout::set_rest_from_poses`]) in the forward kinematics and in written BVH frames (the
    /// template frame's channels of those joints are set to it).
    ///
    /// Fails when a listed joint is not a rotating joint of this layout.
    pub fn freeze_joints(mut self, joints: &[usize]) -> Result<PoseLayout, PoseError> {
        for &j in joints {
            if !matches!(self.role.get(j), Some(Role::Rotating(_))) {
                return Err(PoseError::BadJointOrder(format!(
                    "joint {j} to freeze is not a rotating joint of the layout"
                )));
            }
        }
        for &j in joints {
            self.role[j] = Role::Static;
            let s = self.channel_starts[j];
            let ch = &self.skeleton.joints[j].channels;
            let reference = self.template[s..s + ch.len()].to_vec();
            quat_to_channels(
                self.rest[j],
                ch,
                Some(&reference),
                &mut self.template[s..s + ch.len()],
            );
        }
        let order: Vec<usize> = self
            .order
            .iter()
            .copied()
            .filter(|j| !joints.contains(j))
            .collect();
        for (k, &j) in order.iter().enumerate() {
            self.role[j] = Role::Rotating(k);
        }
        self.order = order;
        self.refresh_rig()?;
        Ok(self)
    }

    /// The same layout with a body `scale` times as large: every bone below the root (OFFSETs, End
    /// Sites and the template's position channels of those joints) is multiplied by `scale`; the root
    /// and what lies above it are unchanged, and so are the rows (the root position stays the pose's).
    /// The offline form of the runtime's scaled forward kinematics
    /// ([`Rig::joint_positions_scaled`]): a character whose standing height is `scale` times the
    /// skeleton's. `scale == 1` is a plain copy.
    ///
    /// Fails when `scale` is not finite and positive.
    pub fn scaled(&self, scale: f64) -> Result<PoseLayout, PoseError> {
        if !(scale.is_finite() && scale > 0.0) {
            return Err(PoseError::BadLayout(format!(
                "body scale {scale} is not a finite positive number"
            )));
        }
        let mut out = self.clone();
        if scale == 1.0 {
            return Ok(out);
        }
        for j in 0..out.skeleton.joints.len() {
            if j == out.root || !out.skeleton.is_ancestor_or_self(out.root, j) {
                continue;
            }
            let start = out.channel_starts[j];
            let joint = &mut out.skeleton.joints[j];
            joint.offset *= scale;
            if let Some(e) = joint.end_site.as_mut() {
                *e *= scale;
            }
            for (c, ch) in joint.channels.iter().enumerate() {
                if ch.is_position() {
                    out.template[start + c] *= scale;
                }
            }
            out.offset_m[j] *= scale;
        }
        if let Some(e) = out.skeleton.joints[out.root].end_site.as_mut() {
            *e *= scale;
        }
        out.refresh_rig()?;
        Ok(out)
    }

    /// The skeleton this layout was built for.
    pub fn skeleton(&self) -> &Skeleton {
        &self.skeleton
    }

    /// File units per metre (100 for centimetres).
    pub fn units_per_metre(&self) -> f64 {
        self.units_per_metre
    }

    /// Skeleton index of the motion root.
    pub fn root(&self) -> usize {
        self.root
    }

    /// Rotating joints (skeleton indices) in row order.
    pub fn joint_order(&self) -> &[usize] {
        &self.order
    }

    /// Number of rotating joints.
    pub fn joint_count(&self) -> usize {
        self.order.len()
    }

    /// Pose dimension `P = 7 + 3 * rotating joints`.
    pub fn dof(&self) -> usize {
        ALWAYS_ROWS + 3 * self.order.len()
    }

    /// Rows of skeleton joint `j` (`None` unless it is a rotating joint).
    pub fn joint_rows(&self, j: usize) -> Option<Range<usize>> {
        match self.role.get(j) {
            Some(Role::Rotating(k)) => Some(ALWAYS_ROWS + 3 * k..ALWAYS_ROWS + 3 * k + 3),
            _ => None,
        }
    }

    /// A name for every row: `root.px`, `root.py`, `root.pz`, `root.rx`, `root.ry`, `root.rz`,
    /// `dt`, then `<joint>.rx`, `<joint>.ry`, `<joint>.rz` per rotating joint.
    pub fn row_names(&self) -> Vec<String> {
        let mut v: Vec<String> = [
            "root.px", "root.py", "root.pz", "root.rx", "root.ry", "root.rz", "dt",
        ]
        .map(String::from)
        .into();
        for &j in &self.order {
            let n = &self.skeleton.joints[j].name;
            v.extend([format!("{n}.rx"), format!("{n}.ry"), format!("{n}.rz")]);
        }
        v
    }

    /// The channel values used for the channels a pose vector does not hold.
    pub fn template_frame(&self) -> &[f64] {
        &self.template
    }

    /// Rest (mean or template) local rotation of skeleton joint `j`.
    ///
    /// # Panics
    /// If `j` is not a joint of the layout's skeleton (`j >= skeleton().joint_count()`).
    pub fn rest_rotation(&self, j: usize) -> DQuat {
        self.rest[j]
    }

    /// A pose vector with the root at the origin (identity orientation), `dt = 0` and every
    /// rotating joint at its rest rotation: the `rest` argument of the runtime FK.
    pub fn rest_pose(&self) -> Vec<f64> {
        let mut p = vec![0.0; self.dof()];
        for (k, &j) in self.order.iter().enumerate() {
            let e = quat_to_exp(self.rest[j]);
            p[ALWAYS_ROWS + 3 * k..ALWAYS_ROWS + 3 * k + 3].copy_from_slice(&e.to_array());
        }
        p
    }

    /// Sets the rest rotation of each rotating joint to its mean over the pose vectors `poses`
    /// (`frames x dof`, sign-aligned quaternion average of the exp-maps).
    ///
    /// Errors: a shape that is not whole poses ([`PoseError::BadShape`]) or an exp-map row that is
    /// not finite ([`PoseError::NonFinite`], `what: "exp-map"`, the index into `poses`); the rest
    /// rotations are then unchanged.
    pub fn set_rest_from_poses(&mut self, poses: &[f64]) -> Result<(), PoseError> {
        let p = self.dof();
        if poses.is_empty() || poses.len() % p != 0 {
            return Err(PoseError::BadShape {
                dof: p,
                len: poses.len(),
            });
        }
        for (f, pose) in poses.chunks_exact(p).enumerate() {
            check_exp_maps(pose, f * p)?;
        }
        for (k, &j) in self.order.iter().enumerate() {
            let mut sum = glam::DVec4::ZERO;
            let mut r: Option<DQuat> = None;
            for pose in poses.chunks_exact(p) {
                let v = DVec3::from_slice(&pose[ALWAYS_ROWS + 3 * k..]);
                let q = exp_to_quat(v);
                let rr = *r.get_or_insert(q);
                sum += glam::DVec4::from(if q.dot(rr) < 0.0 { -q } else { q });
            }
            if sum.length() > 1e-12 && sum.is_finite() {
                self.rest[j] = DQuat::from_vec4(sum).normalize();
            }
        }
        self.refresh_rig()
    }

    /// The motion's skeleton has this layout's joint and channel counts, and its frame buffer is
    /// whole frames.
    fn check_motion(&self, motion: &Motion) -> Result<(), PoseError> {
        let a = &self.skeleton;
        let b = &motion.skeleton;
        let nch = b.channel_count();
        if a.joints.len() != b.joints.len() || a.channel_count() != nch {
            return check_same_skeleton(a, b, 0).and(Err(PoseError::SkeletonMismatch {
                motion: 0,
                joint: 0,
                what: "channel count".into(),
            }));
        }
        let len = motion.frames.len();
        if nch > 0 && len % nch != 0 {
            return Err(PoseError::Length {
                what: "motion frames (whole frames of every channel)",
                expected: len / nch * nch,
                found: len,
            });
        }
        Ok(())
    }

    /// Pose vector of frame `frame_idx` of `motion` (world frame, not canonicalised), written into
    /// `out` (length [`PoseLayout::dof`]): root position `p / units_per_metre`, root orientation
    /// `log(q_root_world)`, `dt = 0`, joint rotations `log(q_local)` on the principal branch
    /// (`|v| <= pi`; see [`unwrap_exp_maps`] for continuity over frames).
    ///
    /// Errors: a skeleton with other joint or channel counts, a frame buffer that is not whole
    /// frames ([`PoseError::Length`]), a frame out of range, an output of the wrong length, a
    /// non-finite value in the frame (`what: "motion frames"`, `index` into `motion.frames`) or a
    /// pose that overflows (huge offsets or positions).
    pub fn pose_from_frame(
        &self,
        motion: &Motion,
        frame_idx: usize,
        out: &mut [f64],
    ) -> Result<(), PoseError> {
        self.check_motion(motion)?;
        let count = motion.frame_count();
        if frame_idx >= count {
            return Err(PoseError::FrameOutOfRange {
                frame: frame_idx,
                count,
            });
        }
        if out.len() != self.dof() {
            return Err(PoseError::Length {
                what: "pose output",
                expected: self.dof(),
                found: out.len(),
            });
        }
        let fr = motion.frame(frame_idx);
        if let Some(k) = fr.iter().position(|v| !v.is_finite()) {
            return Err(PoseError::NonFinite {
                what: "motion frames",
                index: frame_idx * fr.len() + k,
            });
        }
        let sk = &motion.skeleton;
        // World transform of the root: compose its ancestor chain (the layout's, any depth) from
        // the top down.
        let mut world = Transform::IDENTITY;
        for &k in &self.root_chain {
            let s = self.channel_starts[k];
            world = world.mul(&sk.local_transform(k, &fr[s..s + sk.joints[k].channels.len()]));
        }
        let p = world.position / self.units_per_metre;
        out[0..3].copy_from_slice(&p.to_array());
        out[3..6].copy_from_slice(&quat_to_exp(world.rotation).to_array());
        out[TIME_ROW] = 0.0;
        for (k, &j) in self.order.iter().enumerate() {
            let s = self.channel_starts[j];
            let ch = &sk.joints[j].channels;
            let q = channels_to_quat(ch, &fr[s..s + ch.len()]);
            out[ALWAYS_ROWS + 3 * k..ALWAYS_ROWS + 3 * k + 3]
                .copy_from_slice(&quat_to_exp(q).to_array());
        }
        if let Some(index) = out.iter().position(|v| !v.is_finite()) {
            return Err(PoseError::NonFinite {
                what: "pose computed from the motion frame (overflow)",
                index,
            });
        }
        Ok(())
    }

    /// Pose vectors of every frame of `motion` (`frames x dof`, row-major), exp-maps unwrapped
    /// over time.
    ///
    /// Errors: those of [`PoseLayout::pose_from_frame`] (a frame buffer that is not whole frames
    /// is refused even when it holds no whole frame).
    pub fn poses_from_motion(&self, motion: &Motion) -> Result<Vec<f64>, PoseError> {
        self.check_motion(motion)?;
        let p = self.dof();
        let n = motion.frame_count();
        let mut out = vec![0.0; n * p];
        for (f, row) in out.chunks_exact_mut(p).enumerate() {
            self.pose_from_frame(motion, f, row)?;
        }
        unwrap_exp_maps(&mut out, p)?;
        Ok(out)
    }

    /// Inverse of [`PoseLayout::pose_from_frame`]: BVH channel values (the file's own channel
    /// orders, degrees) for `pose`. Channels the pose does not hold come from the template frame.
    /// Euler angles are on the principal branch; see [`PoseLayout::frame_from_pose_near`].
    ///
    /// Errors: a pose or output of the wrong length, a non-finite pose value, or a pose whose
    /// channels are not finite numbers (an exp-map or position so large that it overflows);
    /// `out_channels` is then partly written.
    pub fn frame_from_pose(&self, pose: &[f64], out_channels: &mut [f64]) -> Result<(), PoseError> {
        self.frame_from_pose_impl(pose, None, out_channels)
    }

    /// Like [`PoseLayout::frame_from_pose`], choosing for every joint the Euler solution (and
    /// 360-degree shift) nearest `reference` (e.g. the previous written frame, or the source frame),
    /// so that written channels stay continuous.
    ///
    /// Errors: as [`PoseLayout::frame_from_pose`], and a reference of the wrong length or with a
    /// non-finite value.
    pub fn frame_from_pose_near(
        &self,
        pose: &[f64],
        reference: &[f64],
        out_channels: &mut [f64],
    ) -> Result<(), PoseError> {
        if reference.len() != self.template.len() {
            return Err(PoseError::Length {
                what: "reference frame",
                expected: self.template.len(),
                found: reference.len(),
            });
        }
        if let Some(index) = reference.iter().position(|v| !v.is_finite()) {
            return Err(PoseError::NonFinite {
                what: "reference frame",
                index,
            });
        }
        self.frame_from_pose_impl(pose, Some(reference), out_channels)
    }

    fn frame_from_pose_impl(
        &self,
        pose: &[f64],
        reference: Option<&[f64]>,
        out: &mut [f64],
    ) -> Result<(), PoseError> {
        if pose.len() != self.dof() {
            return Err(PoseError::Length {
                what: "pose",
                expected: self.dof(),
                found: pose.len(),
            });
        }
        if out.len() != self.template.len() {
            return Err(PoseError::Length {
                what: "channel output",
                expected: self.template.len(),
                found: out.len(),
            });
        }
        if let Some(i) = pose.iter().position(|v| !v.is_finite()) {
            return Err(PoseError::NonFinite {
                what: "pose",
                index: i,
            });
        }
        out.copy_from_slice(&self.template);
        let sk = &self.skeleton;
        let world = Transform {
            rotation: exp_to_quat(DVec3::from_slice(&pose[3..6])),
            position: DVec3::from_slice(&pose[0..3]) * self.units_per_metre,
        };
        let local = self.root_parent_world.inverse().mul(&world);
        let r = self.root;
        let s = self.channel_starts[r];
        let ch = &sk.joints[r].channels;
        let seg = &mut out[s..s + ch.len()];
        for (c, o) in ch.iter().zip(seg.iter_mut()) {
            if c.is_position() {
                *o = local.position[c.axis()];
            }
        }
        quat_to_channels(
            local.rotation,
            ch,
            reference.map(|x| &x[s..s + ch.len()]),
            seg,
        );
        for (k, &j) in self.order.iter().enumerate() {
            let s = self.channel_starts[j];
            let ch = &sk.joints[j].channels;
            let q = exp_to_quat(DVec3::from_slice(&pose[ALWAYS_ROWS + 3 * k..]));
            quat_to_channels(
                q,
                ch,
                reference.map(|x| &x[s..s + ch.len()]),
                &mut out[s..s + ch.len()],
            );
        }
        if let Some(index) = out.iter().position(|v| !v.is_finite()) {
            return Err(PoseError::NonFinite {
                what: "channels computed from the pose (overflow)",
                index,
            });
        }
        Ok(())
    }

    /// A motion (this layout's skeleton) from pose vectors `poses` (`frames x dof`), every frame's
    /// Euler angles chosen nearest the previous frame's so the written channels are continuous.
    ///
    /// Errors: a frame time that is not positive and finite ([`PoseError::BadFrameTime`]), a
    /// buffer that is not whole poses, and the errors of [`PoseLayout::frame_from_pose`].
    pub fn motion_from_poses(&self, poses: &[f64], frame_time: f64) -> Result<Motion, PoseError> {
        if !(frame_time.is_finite() && frame_time > 0.0) {
            return Err(PoseError::BadFrameTime(frame_time));
        }
        let p = self.dof();
        if poses.is_empty() || poses.len() % p != 0 {
            return Err(PoseError::BadShape {
                dof: p,
                len: poses.len(),
            });
        }
        let nch = self.template.len();
        let nf = poses.len() / p;
        let mut frames = vec![0.0; nf * nch];
        for f in 0..nf {
            let (before, rest) = frames.split_at_mut(f * nch);
            let out = &mut rest[..nch];
            if f == 0 {
                self.frame_from_pose(&poses[..p], out)?;
            } else {
                self.frame_from_pose_near(
                    &poses[f * p..(f + 1) * p],
                    &before[(f - 1) * nch..],
                    out,
                )?;
            }
        }
        Ok(Motion {
            skeleton: self.skeleton.clone(),
            frame_time,
            frames,
        })
    }

    /// Forward kinematics of a full-precision pose vector: world position (metres) of every
    /// skeleton joint into `out` (length = skeleton joint count). Joints that are not below the
    /// motion root are placed on the ground under the root. Allocation-free.
    ///
    /// # Panics
    /// If `pose.len() != dof()` or `out.len()` differs from the joint count.
    pub fn joint_positions_f64(&self, pose: &[f64], out: &mut [DVec3]) {
        assert_eq!(pose.len(), self.dof(), "pose length must equal dof");
        assert_eq!(
            out.len(),
            self.skeleton.joints.len(),
            "output length must equal the joint count"
        );
        self.fk_f64(pose, out, &mut None);
    }

    /// World transforms (rotation, position in metres) of every joint of a full-precision pose.
    ///
    /// # Panics
    /// As [`PoseLayout::joint_positions_f64`].
    pub fn joint_transforms_f64(&self, pose: &[f64], out: &mut [Transform]) {
        assert_eq!(pose.len(), self.dof(), "pose length must equal dof");
        assert_eq!(
            out.len(),
            self.skeleton.joints.len(),
            "output length must equal the joint count"
        );
        let mut pos = vec![DVec3::ZERO; out.len()];
        let mut rots = Some(vec![DQuat::IDENTITY; out.len()]);
        self.fk_f64(pose, &mut pos, &mut rots);
        for ((o, p), r) in out.iter_mut().zip(pos).zip(rots.unwrap_or_default()) {
            *o = Transform {
                rotation: r,
                position: p,
            };
        }
    }

    fn fk_f64(&self, pose: &[f64], out: &mut [DVec3], rots_out: &mut Option<Vec<DQuat>>) {
        let nj = self.skeleton.joints.len();
        let root_pos = DVec3::from_slice(&pose[0..3]);
        let root_rot = exp_to_quat(DVec3::from_slice(&pose[3..6]));
        let ground = DVec3::new(root_pos.x, 0.0, root_pos.z);
        // Small fixed scratch; heap only for very large skeletons.
        let mut stack = [DQuat::IDENTITY; 128];
        let mut heap = Vec::new();
        let rot: &mut [DQuat] = if nj <= stack.len() {
            &mut stack[..nj]
        } else {
            heap.resize(nj, DQuat::IDENTITY);
            &mut heap
        };
        for j in 0..nj {
            match self.role[j] {
                Role::Outside => {
                    out[j] = ground;
                    rot[j] = DQuat::IDENTITY;
                }
                Role::Root => {
                    out[j] = root_pos;
                    rot[j] = root_rot;
                }
                role => {
                    let p = self.skeleton.joints[j].parent.unwrap_or(0);
                    let local = match role {
                        Role::Rotating(k) => {
                            exp_to_quat(DVec3::from_slice(&pose[ALWAYS_ROWS + 3 * k..]))
                        }
                        _ => self.rest[j],
                    };
                    out[j] = out[p] + rot[p] * self.offset_m[j];
                    rot[j] = rot[p] * local;
                }
            }
        }
        if let Some(r) = rots_out {
            r.copy_from_slice(rot);
        }
    }

    /// Runtime forward kinematics (paper section 3.2's last step): world positions in metres of
    /// every skeleton joint for an f32 pose vector, into `out` (length = skeleton joint count), by
    /// the runtime's [`Rig::joint_positions`] ([`PoseLayout::rig`]).
    ///
    /// Only the first `active_joints` joints of the order are read from `pose` (which may be
    /// truncated to `7 + 3 * active_joints` rows, the level's `P'`); the others use the layout's
    /// rest rotation (the mean, see [`PoseLayout::from_motions`], [`PoseLayout::set_rest_from_poses`]).
    /// `world_j = world_parent * (offset_j, exp(v_j))`. Joints not below the motion root are placed
    /// on the ground under it. No allocation for skeletons up to 128 joints.
    ///
    /// # Panics
    /// If `pose` has fewer than `7 + 3 * min(active_joints, joint_count())` rows or `out` is shorter
    /// than the skeleton's joint count.
    pub fn joint_positions(&self, pose: &[f32], active_joints: usize, out: &mut [Vec3]) {
        if let Err(e) = self.rig.joint_positions(pose, active_joints, out) {
            panic!("joint positions: {e}");
        }
    }
}

/// The runtime rig of a layout: the skeleton's joints with their f32 offsets (metres) and rest
/// rotations, and their roles.
fn make_rig(
    skeleton: &Skeleton,
    role: &[Role],
    rest: &[DQuat],
    offset_m: &[DVec3],
) -> Result<Rig, PoseError> {
    let joints = skeleton
        .joints
        .iter()
        .enumerate()
        .map(|(j, joint)| RigJoint {
            name: joint.name.clone(),
            parent: joint.parent,
            offset: offset_m[j].as_vec3(),
            rest: rest[j].as_quat(),
            role: match role[j] {
                Role::Outside => JointRole::Outside,
                Role::Root => JointRole::Root,
                Role::Rotating(k) => JointRole::Rotating(k),
                Role::Static => JointRole::Static,
            },
        })
        .collect();
    Rig::new(joints).map_err(|e| PoseError::BadLayout(format!("runtime rig: {e}")))
}

fn check_shape(len: usize, dof: usize) -> Result<(), PoseError> {
    if dof < ALWAYS_ROWS || (dof - ALWAYS_ROWS) % 3 != 0 || len % dof != 0 {
        return Err(PoseError::BadShape { dof, len });
    }
    Ok(())
}

/// The exp-map triples of a pose of dimension `dof`: rows `3..6`, then `7 + 3k ..`.
fn exp_triples(dof: usize) -> impl Iterator<Item = usize> {
    std::iter::once(3).chain((ALWAYS_ROWS..dof).step_by(3))
}

/// Makes every exp-map of a sequence of pose vectors (`frames x dof`, row-major) continuous over
/// frames: frame `f`'s map is replaced by its branch nearest frame `f - 1`'s (already unwrapped)
/// map, so there is no jump at `|v| = pi`.
///
/// Errors: a shape that is not whole poses of `7 + 3 n` rows ([`PoseError::BadShape`]), or an
/// exp-map that is not finite, in the input or once unwrapped (a map so large that its length
/// overflows, `|v| > ~1e154`): [`PoseError::NonFinite`] with the index into `poses`, which is
/// then partly unwrapped.
pub fn unwrap_exp_maps(poses: &mut [f64], dof: usize) -> Result<(), PoseError> {
    check_shape(poses.len(), dof)?;
    let n = poses.len() / dof;
    if n > 0 {
        check_exp_maps(&poses[..dof], 0)?;
    }
    for f in 1..n {
        let (prev, cur) = poses.split_at_mut(f * dof);
        let prev = &prev[(f - 1) * dof..];
        let cur = &mut cur[..dof];
        for r in exp_triples(dof) {
            let v = nearest_branch(DVec3::from_slice(&cur[r..]), DVec3::from_slice(&prev[r..]));
            cur[r..r + 3].copy_from_slice(&v.to_array());
        }
        check_exp_maps(cur, f * dof)?;
    }
    Ok(())
}

/// The exp-map rows of one pose are finite, else [`PoseError::NonFinite`] at `base` + the row.
fn check_exp_maps(pose: &[f64], base: usize) -> Result<(), PoseError> {
    for r in exp_triples(pose.len()) {
        if let Some(k) = pose[r..r + 3].iter().position(|v| !v.is_finite()) {
            return Err(PoseError::NonFinite {
                what: "exp-map",
                index: base + r + k,
            });
        }
    }
    Ok(())
}

/// Brings every exp-map of one pose onto the branch nearest the same map in `reference` (continuity
/// across samples, e.g. to the first cycle's first frame or a mean pose).
///
/// Errors: shapes that differ or are not `7 + 3 n` rows, or an exp-map of the result that is not
/// finite ([`PoseError::NonFinite`], as [`unwrap_exp_maps`]).
pub fn align_exp_maps(pose: &mut [f64], reference: &[f64]) -> Result<(), PoseError> {
    let dof = reference.len();
    check_shape(pose.len(), dof)?;
    if pose.len() != dof {
        return Err(PoseError::Length {
            what: "pose",
            expected: dof,
            found: pose.len(),
        });
    }
    for r in exp_triples(dof) {
        let v = nearest_branch(
            DVec3::from_slice(&pose[r..]),
            DVec3::from_slice(&reference[r..]),
        );
        pose[r..r + 3].copy_from_slice(&v.to_array());
    }
    check_exp_maps(pose, 0)
}

/// Brings a whole sequence (`frames x dof`) onto the branch nearest `reference` as one block:
/// every exp-map of the first frame is aligned to `reference`, and the same `2 pi k` shift of each
/// map is then carried through the sequence by [`unwrap_exp_maps`].
pub fn align_sequence(poses: &mut [f64], reference: &[f64]) -> Result<(), PoseError> {
    let dof = reference.len();
    check_shape(poses.len(), dof)?;
    if poses.is_empty() {
        return Ok(());
    }
    align_exp_maps(&mut poses[..dof], reference)?;
    unwrap_exp_maps(poses, dof)
}
