//! Skeleton hierarchy, BVH channels and forward kinematics in the file's own units.

use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};

/// One BVH channel: a translation along, or a rotation about, one local axis.
///
/// Rotation values are Euler angles in degrees, as written in the file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Channel {
    /// Translation along local x.
    Xposition,
    /// Translation along local y.
    Yposition,
    /// Translation along local z.
    Zposition,
    /// Rotation about local x (degrees).
    Xrotation,
    /// Rotation about local y (degrees).
    Yrotation,
    /// Rotation about local z (degrees).
    Zrotation,
}

impl Channel {
    /// The channel's name as written in a BVH `CHANNELS` line.
    pub fn name(self) -> &'static str {
        match self {
            Channel::Xposition => "Xposition",
            Channel::Yposition => "Yposition",
            Channel::Zposition => "Zposition",
            Channel::Xrotation => "Xrotation",
            Channel::Yrotation => "Yrotation",
            Channel::Zrotation => "Zrotation",
        }
    }

    /// Parses a channel name (case-insensitive, as some exporters lower-case them).
    pub fn parse(name: &str) -> Option<Channel> {
        const ALL: [Channel; 6] = [
            Channel::Xposition,
            Channel::Yposition,
            Channel::Zposition,
            Channel::Xrotation,
            Channel::Yrotation,
            Channel::Zrotation,
        ];
        ALL.into_iter()
            .find(|c| c.name().eq_ignore_ascii_case(name))
    }

    /// True for the three translation channels.
    pub fn is_position(self) -> bool {
        matches!(
            self,
            Channel::Xposition | Channel::Yposition | Channel::Zposition
        )
    }

    /// True for the three rotation channels.
    pub fn is_rotation(self) -> bool {
        !self.is_position()
    }

    /// The axis index (0 = x, 1 = y, 2 = z).
    pub fn axis(self) -> usize {
        match self {
            Channel::Xposition | Channel::Xrotation => 0,
            Channel::Yposition | Channel::Yrotation => 1,
            Channel::Zposition | Channel::Zrotation => 2,
        }
    }
}

/// One joint of a BVH hierarchy.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Joint {
    /// Joint name as in the file.
    pub name: String,
    /// Index of the parent joint (`None` for the root). Parents come before children.
    pub parent: Option<usize>,
    /// Rest offset from the parent joint, file units.
    pub offset: DVec3,
    /// Channels in file order (0, 3 or 6 of them; any order).
    pub channels: Vec<Channel>,
    /// Offset of the `End Site` below this joint, if it has one.
    pub end_site: Option<DVec3>,
}

/// World (or parent-relative) rigid transform of one joint: rotation then translation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Transform {
    /// Orientation of the joint's frame.
    pub rotation: DQuat,
    /// Position of the joint, file units.
    pub position: DVec3,
}

impl Default for Transform {
    fn default() -> Self {
        Transform::IDENTITY
    }
}

impl Transform {
    /// The identity transform.
    pub const IDENTITY: Transform = Transform {
        rotation: DQuat::IDENTITY,
        position: DVec3::ZERO,
    };

    /// Composition `self * local`: the world transform of a child whose local transform is `local`.
    pub fn mul(&self, local: &Transform) -> Transform {
        Transform {
            rotation: (self.rotation * local.rotation).normalize(),
            position: self.position + self.rotation * local.position,
        }
    }

    /// The inverse transform.
    pub fn inverse(&self) -> Transform {
        let r = self.rotation.inverse();
        Transform {
            rotation: r,
            position: -(r * self.position),
        }
    }

    /// Applies the transform to a point.
    pub fn transform_point(&self, p: DVec3) -> DVec3 {
        self.position + self.rotation * p
    }
}

/// A hierarchy of joints, parents before children, index 0 = root.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Skeleton {
    /// The joints in file (depth-first) order.
    pub joints: Vec<Joint>,
}

/// Problems with a skeleton built by hand (the BVH reader never produces these).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SkeletonError {
    /// The skeleton has no joint.
    #[error("skeleton has no joints")]
    Empty,
    /// A joint's parent index is not smaller than its own index (or joint 0 has a parent).
    #[error(
        "joint {index} ({name}): parent {parent:?} must come before it (and only joint 0 is a root)"
    )]
    BadParent {
        /// Joint index.
        index: usize,
        /// Joint name.
        name: String,
        /// Its parent field.
        parent: Option<usize>,
    },
    /// A joint lists the same channel twice or more than 6 channels.
    #[error("joint {index} ({name}): invalid channel list {channels:?}")]
    BadChannels {
        /// Joint index.
        index: usize,
        /// Joint name.
        name: String,
        /// The channel list.
        channels: Vec<Channel>,
    },
    /// An offset is NaN or infinite.
    #[error("joint {index} ({name}): non-finite offset")]
    NonFinite {
        /// Joint index.
        index: usize,
        /// Joint name.
        name: String,
    },
}

impl Skeleton {
    /// Index of the joint called `name` (exact match).
    pub fn find(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }

    /// Total number of channels per frame.
    pub fn channel_count(&self) -> usize {
        self.joints.iter().map(|j| j.channels.len()).sum()
    }

    /// Number of joints.
    pub fn joint_count(&self) -> usize {
        self.joints.len()
    }

    /// Index of the first channel of every joint in a frame (length = joint count).
    pub fn channel_starts(&self) -> Vec<usize> {
        let mut start = 0;
        self.joints
            .iter()
            .map(|j| {
                let s = start;
                start += j.channels.len();
                s
            })
            .collect()
    }

    /// Children of joint `j`, in order.
    pub fn children(&self, j: usize) -> impl Iterator<Item = usize> + '_ {
        self.joints
            .iter()
            .enumerate()
            .filter(move |(_, c)| c.parent == Some(j))
            .map(|(i, _)| i)
    }

    /// True when `ancestor` is `j` or one of its ancestors.
    ///
    /// Follows at most one parent link per joint, so a hand-built skeleton whose parents form a
    /// cycle (which [`Skeleton::validate`] rejects) gets `false` instead of an endless loop; a
    /// parent index out of range ends the chain.
    pub fn is_ancestor_or_self(&self, ancestor: usize, mut j: usize) -> bool {
        // A valid chain has at most `len - 1` links, so `len + 1` checks always reach its top.
        for _ in 0..=self.joints.len() {
            if j == ancestor {
                return true;
            }
            match self.joints.get(j).and_then(|x| x.parent) {
                Some(p) => j = p,
                None => return false,
            }
        }
        false
    }

    /// True when every parent index is smaller than its joint's own index and only joint 0 is a
    /// root: the hierarchy part of [`Skeleton::validate`] (no cycles, no index out of range), what
    /// the forward kinematics needs. True for an empty skeleton.
    pub(crate) fn hierarchy_ok(&self) -> bool {
        self.joints.iter().enumerate().all(|(i, j)| match j.parent {
            None => i == 0,
            Some(p) => p < i,
        })
    }

    /// Checks the invariants the rest of the crate relies on: at least one joint, parents before
    /// children with a single root at index 0, at most one of each channel, finite offsets.
    pub fn validate(&self) -> Result<(), SkeletonError> {
        if self.joints.is_empty() {
            return Err(SkeletonError::Empty);
        }
        for (i, j) in self.joints.iter().enumerate() {
            let ok = match j.parent {
                None => i == 0,
                Some(p) => p < i,
            };
            if !ok {
                return Err(SkeletonError::BadParent {
                    index: i,
                    name: j.name.clone(),
                    parent: j.parent,
                });
            }
            let mut seen = [false; 6];
            for c in &j.channels {
                let k = *c as usize;
                if seen[k] {
                    return Err(SkeletonError::BadChannels {
                        index: i,
                        name: j.name.clone(),
                        channels: j.channels.clone(),
                    });
                }
                seen[k] = true;
            }
            if !j.offset.is_finite() || j.end_site.is_some_and(|e| !e.is_finite()) {
                return Err(SkeletonError::NonFinite {
                    index: i,
                    name: j.name.clone(),
                });
            }
        }
        Ok(())
    }

    /// Local transform of joint `j` from its channel values `values` (the joint's slice of a frame).
    ///
    /// Translation: the OFFSET, with each component replaced by its position channel when the joint
    /// has one (the convention of files with 6 channels on every joint, whose position channels
    /// repeat the offset). Rotation: `R = R_first * R_second * R_third`, each an axis rotation by the
    /// channel value in degrees, in the order the channels are listed (intrinsic rotations).
    pub fn local_transform(&self, j: usize, values: &[f64]) -> Transform {
        let joint = &self.joints[j];
        debug_assert_eq!(values.len(), joint.channels.len());
        let mut t = joint.offset.to_array();
        let mut r = DQuat::IDENTITY;
        for (c, &v) in joint.channels.iter().zip(values) {
            if c.is_position() {
                t[c.axis()] = v;
            } else {
                r *= axis_rotation(c.axis(), v.to_radians());
            }
        }
        Transform {
            rotation: r,
            position: DVec3::from_array(t),
        }
    }

    /// Forward kinematics of one frame: world rotation and position of every joint, file units.
    ///
    /// `world_j = world_parent(j) * local_j` with `local_j` from [`Skeleton::local_transform`].
    ///
    /// Expects parents before their children ([`Skeleton::validate`]; every skeleton the reader
    /// returns): a parent listed after its child reads that parent's transform before it is
    /// computed.
    ///
    /// # Panics
    /// If `frame.len() != self.channel_count()` or `out.len() != self.joints.len()` (a programming
    /// error, like an out-of-range slice index), or if a parent index is not a joint index (a
    /// hand-built skeleton that [`Skeleton::validate`] rejects).
    pub fn forward_kinematics(&self, frame: &[f64], out: &mut [Transform]) {
        assert_eq!(
            frame.len(),
            self.channel_count(),
            "frame length must equal the channel count"
        );
        assert_eq!(
            out.len(),
            self.joints.len(),
            "output length must equal the joint count"
        );
        let mut start = 0;
        for (j, joint) in self.joints.iter().enumerate() {
            let n = joint.channels.len();
            let local = self.local_transform(j, &frame[start..start + n]);
            start += n;
            out[j] = match joint.parent {
                Some(p) => out[p].mul(&local),
                None => local,
            };
        }
    }

    /// World positions of every joint for one frame (file units), allocating; see
    /// [`Skeleton::forward_kinematics`].
    ///
    /// # Panics
    /// As [`Skeleton::forward_kinematics`]: if `frame.len() != self.channel_count()` or a parent
    /// index is not a joint index.
    pub fn joint_positions(&self, frame: &[f64]) -> Vec<DVec3> {
        let mut t = vec![Transform::IDENTITY; self.joints.len()];
        self.forward_kinematics(frame, &mut t);
        t.iter().map(|x| x.position).collect()
    }

    /// Sum of bone lengths (|OFFSET|) along the path from `ancestor` (exclusive) down to `j`
    /// (inclusive). Zero when `ancestor == j` or `ancestor` is not an ancestor of `j` (see
    /// [`Skeleton::is_ancestor_or_self`]: a parent cycle or an index out of range ends the search).
    pub fn chain_length(&self, ancestor: usize, j: usize) -> f64 {
        if !self.is_ancestor_or_self(ancestor, j) {
            return 0.0;
        }
        let mut len = 0.0;
        let mut k = j;
        // The walk above reached `ancestor` within `len + 1` steps, along the same links.
        for _ in 0..=self.joints.len() {
            if k == ancestor {
                break;
            }
            len += self.joints[k].offset.length();
            match self.joints[k].parent {
                Some(p) => k = p,
                None => break,
            }
        }
        len
    }
}

/// Rotation by `angle` radians about coordinate axis `axis` (0 = x, 1 = y, 2 = z).
pub fn axis_rotation(axis: usize, angle: f64) -> DQuat {
    match axis {
        0 => DQuat::from_rotation_x(angle),
        1 => DQuat::from_rotation_y(angle),
        _ => DQuat::from_rotation_z(angle),
    }
}
