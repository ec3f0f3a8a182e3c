//! A skeleton's rest pose and one animation of it, from the project's pose vectors.

use std::sync::Arc;

use glam::{DQuat, DVec3};
use lod_policy::ALWAYS_ROWS;
use motion_io::expmap::exp_to_quat;
use motion_io::{PoseLayout, Transform};

use super::GltfError;

/// One joint node of a character: the rest (bind) pose's local transform.
#[derive(Debug, Clone, PartialEq)]
pub struct JointNode {
    /// The joint's name, as in the BVH.
    pub name: String,
    /// Its parent joint (`None` for a top joint).
    pub parent: Option<usize>,
    /// Rest translation relative to the parent, metres.
    pub translation: DVec3,
    /// Rest rotation relative to the parent (unit).
    pub rotation: DQuat,
    /// True for the motion root and the joints below it (those that carry the body).
    pub carries_body: bool,
    /// The joint's End Site relative to it, metres.
    pub end_site: Option<DVec3>,
}

/// The rest (and bind) pose of a layout's skeleton: one [`JointNode`] per joint.
#[derive(Debug, Clone, PartialEq)]
pub struct Rest {
    /// The joints in skeleton order (parents before children).
    pub joints: Vec<JointNode>,
    /// The motion root.
    pub root: usize,
    /// World transform of the motion root's parent (metres; identity when the root is a top joint).
    pub root_parent: Transform,
}

/// Local transforms of every joint in the layout's template frame, in metres.
fn template_locals(layout: &PoseLayout) -> Vec<Transform> {
    let sk = layout.skeleton();
    let units = layout.units_per_metre();
    let template = layout.template_frame();
    let starts = sk.channel_starts();
    sk.joints
        .iter()
        .enumerate()
        .map(|(j, joint)| {
            let s = starts[j];
            let t = sk.local_transform(j, &template[s..s + joint.channels.len()]);
            Transform {
                rotation: t.rotation.normalize(),
                position: t.position / units,
            }
        })
        .collect()
}

fn check_pose(pose: &[f64], dof: usize, what: &str) -> Result<(), GltfError> {
    if pose.len() != dof {
        return Err(GltfError::Poses(format!(
            "{what}: {} values for a pose of {dof}",
            pose.len()
        )));
    }
    if let Some(i) = pose.iter().position(|v| !v.is_finite()) {
        return Err(GltfError::Poses(format!("{what}: value {i} is not finite")));
    }
    Ok(())
}

impl Rest {
    /// The rest pose for `layout`: every joint at the layout's rest rotation (the data's mean
    /// rotation for the rotating joints, the template's for the static ones), joints above the
    /// motion root at their template transform, and the motion root standing at `(0, h, 0)` with
    /// the orientation it has in `reference` (a pose vector), `h` being `reference`'s root height.
    pub fn new(layout: &PoseLayout, reference: &[f64]) -> Result<Rest, GltfError> {
        Self::facing(layout, reference, None)
    }

    /// [`Rest::new`] with the root's orientation turned about +Y so that the ground direction
    /// `travel` (x, z) of the walk that starts at `reference` becomes +Z (when it is longer than
    /// 1 cm): the rest pose faces +Z as glTF asks.
    pub fn facing(
        layout: &PoseLayout,
        reference: &[f64],
        travel: Option<[f64; 2]>,
    ) -> Result<Rest, GltfError> {
        check_pose(reference, layout.dof(), "rest reference pose")?;
        let sk = layout.skeleton();
        let root = layout.root();
        let locals = template_locals(layout);
        let mut root_parent = Transform::IDENTITY;
        let mut chain = Vec::new();
        let mut a = sk.joints[root].parent;
        while let Some(p) = a {
            chain.push(p);
            a = sk.joints[p].parent;
        }
        for &p in chain.iter().rev() {
            root_parent = root_parent.mul(&locals[p]);
        }
        let q0 = exp_to_quat(DVec3::from_slice(&reference[3..6]));
        let yaw = match travel {
            Some([x, z]) if x.hypot(z) > 0.01 => x.atan2(z),
            _ => 0.0,
        };
        let root_world = Transform {
            rotation: (DQuat::from_rotation_y(-yaw) * q0).normalize(),
            position: DVec3::new(0.0, reference[1], 0.0),
        };
        let root_local = root_parent.inverse().mul(&root_world);
        let units = layout.units_per_metre();
        let joints = sk
            .joints
            .iter()
            .enumerate()
            .map(|(j, joint)| {
                let below = sk.is_ancestor_or_self(root, j);
                let (translation, rotation) = if j == root {
                    (root_local.position, root_local.rotation)
                } else if below {
                    (locals[j].position, layout.rest_rotation(j).normalize())
                } else {
                    (locals[j].position, locals[j].rotation)
                };
                JointNode {
                    name: joint.name.clone(),
                    parent: joint.parent,
                    translation,
                    rotation,
                    carries_body: below,
                    end_site: joint.end_site.map(|e| e / units),
                }
            })
            .collect();
        Ok(Rest {
            joints,
            root,
            root_parent,
        })
    }

    /// World transforms of the rest pose (metres).
    pub fn world(&self) -> Vec<Transform> {
        let mut out: Vec<Transform> = Vec::with_capacity(self.joints.len());
        for j in &self.joints {
            let local = Transform {
                rotation: j.rotation,
                position: j.translation,
            };
            let w = match j.parent {
                Some(p) => out[p].mul(&local),
                None => local,
            };
            out.push(w);
        }
        out
    }
}

/// A skeleton in its rest pose with one animation: the motion root's translation and the
/// rotations of the root and of every rotating joint, per frame.
#[derive(Debug, Clone)]
pub struct Character {
    /// The character's name (prefix of its nodes' names in crowds).
    pub name: String,
    /// The rest pose (shared by characters of one skeleton, so that they share their body mesh).
    pub rest: Arc<Rest>,
    /// Sample times (s), strictly increasing from 0.
    pub times: Vec<f32>,
    /// The motion root's local translation at every sample (metres).
    pub root_translation: Vec<[f32; 3]>,
    /// Animated joints and their local rotations `[x, y, z, w]` at every sample (unit,
    /// sign-continuous).
    pub rotations: Vec<(usize, Vec<[f32; 4]>)>,
    /// Free-form extras of the character's body node.
    pub extras: serde_json::Value,
}

impl Character {
    /// The animation of pose vectors `poses` (`frames x dof` of `layout`, world frame, metres)
    /// sampled every `frame_time` seconds, over the rest pose `rest` of the same layout.
    ///
    /// Local transforms follow the layout's forward kinematics, which the BVH writer inverts: a
    /// rotating joint's rotation is the exponential map of its rows, the root's world transform
    /// is rows 0..6 (expressed under its parent's static transform), every other joint keeps its
    /// rest transform.
    pub fn from_poses(
        layout: &PoseLayout,
        rest: &Arc<Rest>,
        poses: &[f64],
        frame_time: f64,
        name: &str,
    ) -> Result<Character, GltfError> {
        let p = layout.dof();
        if poses.is_empty() || poses.len() % p != 0 {
            return Err(GltfError::Poses(format!(
                "{} values are not whole poses of {p}",
                poses.len()
            )));
        }
        if !(frame_time.is_finite() && frame_time > 0.0) {
            return Err(GltfError::Poses(format!(
                "frame time {frame_time} is not a positive number of seconds"
            )));
        }
        if rest.joints.len() != layout.skeleton().joints.len() || rest.root != layout.root() {
            return Err(GltfError::Poses(
                "the rest pose is not of this layout's skeleton".into(),
            ));
        }
        let frames = poses.len() / p;
        let parent_inv = rest.root_parent.inverse();
        let order = layout.joint_order();
        let mut root_translation = Vec::with_capacity(frames);
        let mut root_rot = Vec::with_capacity(frames);
        let mut rots: Vec<Vec<[f32; 4]>> = vec![Vec::with_capacity(frames); order.len()];
        for (f, pose) in poses.chunks_exact(p).enumerate() {
            check_pose(pose, p, &format!("frame {f}"))?;
            let world = Transform {
                rotation: exp_to_quat(DVec3::from_slice(&pose[3..6])),
                position: DVec3::from_slice(&pose[0..3]),
            };
            let local = parent_inv.mul(&world);
            root_translation.push(local.position.as_vec3().to_array());
            push_continuous(&mut root_rot, local.rotation);
            for (k, track) in rots.iter_mut().enumerate() {
                let r = ALWAYS_ROWS + 3 * k;
                push_continuous(track, exp_to_quat(DVec3::from_slice(&pose[r..r + 3])));
            }
        }
        let mut rotations = vec![(rest.root, root_rot)];
        rotations.extend(order.iter().copied().zip(rots));
        let times = (0..frames)
            .map(|f| (f as f64 * frame_time) as f32)
            .collect();
        Ok(Character {
            name: name.to_string(),
            rest: Arc::clone(rest),
            times,
            root_translation,
            rotations,
            extras: serde_json::Value::Null,
        })
    }
}

/// Appends `q` as a unit f32 quaternion on the hemisphere of the track's last sample.
fn push_continuous(track: &mut Vec<[f32; 4]>, q: DQuat) {
    let mut q = q.normalize();
    if let Some(prev) = track.last() {
        let d = q.x * f64::from(prev[0])
            + q.y * f64::from(prev[1])
            + q.z * f64::from(prev[2])
            + q.w * f64::from(prev[3]);
        if d < 0.0 {
            q = -q;
        }
    }
    let v = q.as_quat().normalize();
    track.push([v.x, v.y, v.z, v.w]);
}
