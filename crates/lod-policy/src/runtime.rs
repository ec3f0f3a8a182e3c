//! [`RuntimeModel`]: what an engine loads from a model file: the [`Rig`] and the [`LodModel`].
//!
//! A model file's payload is the offline `MotionModel`: the pose layout (`motion_io::PoseLayout`,
//! stored as what it is built from), the runtime model, the feet for the foot lock, the rig's
//! stature, then the build report. The runtime decodes the first four and ignores the rest. The layout's stored form is mirrored here field for field
//! (private types with the same serde shape), so the runtime reads files without the offline crates.

use std::path::Path;

use glam::{DQuat, DVec3};
use serde::Deserialize;

use crate::controls::Controls;
use crate::file::{self, FileError, InvalidModel};
use crate::footlock::FootRig;
use crate::model::{ALWAYS_ROWS, LodModel, ROWS_PER_JOINT};
use crate::rig::{JointRole, Rig, RigJoint};

/// The runtime form of a model file: the skeleton with its forward kinematics, the
/// multilinear model at every accuracy level, the feet for the foot lock, and the rig's stature
/// for the body scale of each character.
#[derive(Debug, Clone, PartialEq)]
pub struct RuntimeModel {
    rig: Rig,
    lod: LodModel,
    feet: Option<FootRig>,
    stature_m: Option<f32>,
}

impl RuntimeModel {
    /// A runtime model from its parts, checking that they fit: the rig drives the model's pose
    /// rows (`7 + 3 n` rows for its `n` rotating joints, the model's `P`, with the model's 7 always
    /// evaluated rows and 3 rows per joint).
    pub fn new(rig: Rig, lod: LodModel) -> Result<RuntimeModel, InvalidModel> {
        if lod.always_rows() != ALWAYS_ROWS || lod.rows_per_joint() != ROWS_PER_JOINT {
            return Err(InvalidModel(format!(
                "the runtime model has {} root rows and {} rows per joint; pose vectors have {ALWAYS_ROWS} and {ROWS_PER_JOINT}",
                lod.always_rows(),
                lod.rows_per_joint(),
            )));
        }
        if rig.dof() != lod.p() {
            return Err(InvalidModel(format!(
                "the pose layout has {} DOF rows, the runtime model {}",
                rig.dof(),
                lod.p()
            )));
        }
        Ok(RuntimeModel {
            rig,
            lod,
            feet: None,
            stature_m: None,
        })
    }

    /// The model with its rig's stature: the standing height (m) of the rig's skeleton, measured as
    /// the height control measures the data's performers ([`crate::ControlSpace::body_scale`]). Must be
    /// finite and positive; `None` draws every character at the rig's size.
    pub fn with_stature(mut self, stature_m: Option<f32>) -> Result<RuntimeModel, InvalidModel> {
        if let Some(h) = stature_m {
            check_stature(h).map_err(InvalidModel)?;
        }
        self.stature_m = stature_m;
        Ok(self)
    }

    /// The model with the feet of its rig for the foot lock ([`FootRig::check`]ed against the rig).
    pub fn with_feet(mut self, feet: Option<FootRig>) -> Result<RuntimeModel, InvalidModel> {
        if let Some(f) = &feet {
            f.check(&self.rig).map_err(InvalidModel)?;
        }
        self.feet = feet;
        Ok(self)
    }

    /// Decodes the bytes of a model file (framing and checksum as [`file::unframe`] checks them,
    /// then the pose layout, the runtime model and the feet; the build report after them is not
    /// read).
    pub fn from_bytes(bytes: &[u8]) -> Result<RuntimeModel, FileError> {
        Self::decode_at(bytes, Path::new("<model bytes>"))
    }

    /// Reads a model file (see [`RuntimeModel::from_bytes`]); errors name the path.
    pub fn load(path: &Path) -> Result<RuntimeModel, FileError> {
        Self::decode_at(&file::read(path)?, path)
    }

    fn decode_at(bytes: &[u8], path: &Path) -> Result<RuntimeModel, FileError> {
        let payload = file::unframe(bytes, path)?;
        type Prefix = (LayoutParts, LodModel, Option<FootRig>, Option<f32>);
        let ((layout, lod, feet, stature), _): (Prefix, usize) =
            file::decode_prefix(payload, path)?;
        let invalid = |source: InvalidModel| FileError::Invalid {
            path: path.to_path_buf(),
            source,
        };
        let rig = layout
            .rig()
            .map_err(|e| invalid(InvalidModel(format!("pose layout: {e}"))))?;
        RuntimeModel::new(rig, lod)
            .and_then(|m| m.with_feet(feet))
            .and_then(|m| m.with_stature(stature))
            .map_err(invalid)
    }

    /// The skeleton and its forward kinematics.
    pub fn rig(&self) -> &Rig {
        &self.rig
    }

    /// The multilinear model at every accuracy level.
    pub fn lod(&self) -> &LodModel {
        &self.lod
    }

    /// The feet and floor the foot lock needs ([`crate::FootLock`]); `None` when the model's build
    /// found no feet.
    pub fn feet(&self) -> Option<&FootRig> {
        self.feet.as_ref()
    }

    /// The standing height (m) of the rig's skeleton, as the height control measures it; `None`
    /// when the build could not measure it (no feet or head found).
    pub fn stature_m(&self) -> Option<f32> {
        self.stature_m
    }

    /// The body scale of a character with `controls`: its height over the rig's stature
    /// ([`crate::ControlSpace::body_scale`]); what [`Rig::joint_positions_scaled`],
    /// [`Rig::joint_transforms_scaled`] and [`crate::FootLock::apply`] take, and what an engine
    /// scales the skeleton's bone translations by. 1 when the data hold one height.
    pub fn body_scale(&self, controls: &Controls) -> f32 {
        self.lod
            .controls()
            .body_scale(self.stature_m, &controls.to_array())
    }

    /// The parts.
    pub fn into_parts(self) -> (Rig, LodModel, Option<FootRig>) {
        (self.rig, self.lod, self.feet)
    }
}

/// Checks a stature (the standing height of a model's skeleton, m): a finite height between 1 cm and
/// 100 m. The one check the runtime and the offline model use.
pub fn check_stature(h: f32) -> Result<(), String> {
    if h.is_finite() && (0.01..=100.0).contains(&h) {
        Ok(())
    } else {
        Err(format!(
            "stature {h} m is not a standing height (finite, 0.01 to 100 m)"
        ))
    }
}

/// `motion_io::Channel` as stored (variant order is the file format).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
enum Channel {
    Xposition,
    Yposition,
    Zposition,
    Xrotation,
    Yrotation,
    Zrotation,
}

impl Channel {
    /// The axis of a position channel, `None` for a rotation channel.
    fn position_axis(self) -> Option<usize> {
        match self {
            Channel::Xposition => Some(0),
            Channel::Yposition => Some(1),
            Channel::Zposition => Some(2),
            _ => None,
        }
    }
}

/// `motion_io::Joint` as stored.
#[derive(Debug, Clone, Deserialize)]
struct Joint {
    name: String,
    parent: Option<usize>,
    offset: DVec3,
    channels: Vec<Channel>,
    end_site: Option<DVec3>,
}

/// `motion_io::Skeleton` as stored.
#[derive(Debug, Clone, Deserialize)]
struct Skeleton {
    joints: Vec<Joint>,
}

/// `motion_io::PoseLayoutParts`, the stored form of a `PoseLayout`.
#[derive(Debug, Clone, Deserialize)]
struct LayoutParts {
    skeleton: Skeleton,
    units_per_metre: f64,
    root: usize,
    joint_order: Vec<usize>,
    template: Vec<f64>,
    rest: Vec<DQuat>,
}

/// Largest `| |q| - 1 |` accepted for a stored rest rotation (the layout's own tolerance).
const UNIT_TOLERANCE: f64 = 1e-6;

impl LayoutParts {
    /// The rig the layout's f32 forward kinematics evaluates, after the checks the layout makes
    /// when it is decoded (skeleton order and channels, units, root, template, joint order, rest
    /// rotations). Offsets are the joints' OFFSETs with position channels taken from the template
    /// frame, divided by the units per metre, then rounded to f32.
    fn rig(&self) -> Result<Rig, String> {
        let joints = &self.skeleton.joints;
        let nj = joints.len();
        if nj == 0 {
            return Err("the skeleton has no joints".into());
        }
        let name = |j: usize| &joints[j].name;
        for (i, j) in joints.iter().enumerate() {
            let ok = match j.parent {
                None => i == 0,
                Some(p) => p < i,
            };
            if !ok {
                return Err(format!(
                    "joint {i} ({}): parent {:?} must come before it (and only joint 0 is a root)",
                    j.name, j.parent
                ));
            }
            let mut seen = [false; 6];
            for &c in &j.channels {
                if std::mem::replace(&mut seen[c as usize], true) {
                    return Err(format!("joint {i} ({}): channel {c:?} twice", j.name));
                }
            }
            if !j.offset.is_finite() || j.end_site.is_some_and(|e| !e.is_finite()) {
                return Err(format!("joint {i} ({}): non-finite offset", j.name));
            }
        }
        let units = self.units_per_metre;
        if !(units.is_finite() && units > 0.0) {
            return Err(format!(
                "units per metre must be positive and finite, found {units}"
            ));
        }
        let root = self.root;
        if root >= nj {
            return Err(format!(
                "root joint {root} is not one of the skeleton's {nj} joints"
            ));
        }
        let channels: usize = joints.iter().map(|j| j.channels.len()).sum();
        if self.template.len() != channels {
            return Err(format!(
                "template frame: expected {channels} values (one per channel), found {}",
                self.template.len()
            ));
        }
        if let Some(i) = self.template.iter().position(|v| !v.is_finite()) {
            return Err(format!("template frame: non-finite value at index {i}"));
        }
        let below_root = |mut j: usize| loop {
            if j == root {
                return true;
            }
            match joints[j].parent {
                Some(p) => j = p,
                None => return false,
            }
        };
        let mut role: Vec<JointRole> = (0..nj)
            .map(|j| {
                if j == root {
                    JointRole::Root
                } else if below_root(j) {
                    JointRole::Static
                } else {
                    JointRole::Outside
                }
            })
            .collect();
        for (k, &j) in self.joint_order.iter().enumerate() {
            if j >= nj {
                return Err(format!(
                    "joint order entry {k} names joint {j}; the skeleton has {nj} joints"
                ));
            }
            match role[j] {
                JointRole::Static => {}
                JointRole::Rotating(_) => {
                    return Err(format!(
                        "joint order entry {k}: joint {j} ({}) is listed twice",
                        name(j)
                    ));
                }
                JointRole::Root | JointRole::Outside => {
                    return Err(format!(
                        "joint order entry {k}: joint {j} ({}) is not below the root joint {root}",
                        name(j)
                    ));
                }
            }
            if joints[j]
                .channels
                .iter()
                .all(|c| c.position_axis().is_some())
            {
                return Err(format!(
                    "joint order entry {k}: joint {j} ({}) has no rotation channels",
                    name(j)
                ));
            }
            role[j] = JointRole::Rotating(k);
        }
        if self.rest.len() != nj {
            return Err(format!(
                "rest rotations: expected {nj} (one per joint), found {}",
                self.rest.len()
            ));
        }
        let mut start = 0;
        let mut rig = Vec::with_capacity(nj);
        for (j, joint) in joints.iter().enumerate() {
            let q = self.rest[j];
            if !q.is_finite() || (q.length() - 1.0).abs() > UNIT_TOLERANCE {
                return Err(format!(
                    "rest rotation of joint {j} ({}) is not a unit quaternion: {q:?}",
                    joint.name
                ));
            }
            let mut t = joint.offset.to_array();
            let values = &self.template[start..start + joint.channels.len()];
            start += joint.channels.len();
            for (c, &v) in joint.channels.iter().zip(values) {
                if let Some(axis) = c.position_axis() {
                    t[axis] = v;
                }
            }
            rig.push(RigJoint {
                name: joint.name.clone(),
                parent: joint.parent,
                offset: (DVec3::from_array(t) / units).as_vec3(),
                rest: q.as_quat(),
                role: role[j],
            });
        }
        Rig::new(rig).map_err(|e| e.to_string())
    }
}
