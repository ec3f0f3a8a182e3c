//! glTF 2.0 binary (`.glb`) export: synthesized walks and crowd clips for any engine or browser.
//!
//! Conventions are glTF's, which are the project's pose vectors' own: metres, Y up, a character
//! facing +Z (+X on its left). A character is
//!
//! - one node per skeleton joint, in the data's hierarchy and with the BVH's joint names; the joint
//!   translations are the skeleton's OFFSETs in metres;
//! - a skin over those nodes whose inverse bind matrices are the rest pose's world transforms;
//! - a generated body: one box per bone (parent joint to child joint or End Site) and a head block,
//!   each rigidly skinned to the bone's parent joint, so that every viewer draws something;
//! - an animation: the motion root's translation and the rotation of every joint that moves
//!   (unit quaternions, sign-continuous), sampled at the walk's frame times in seconds, `LINEAR`.
//!
//! The rest (and bind) pose is the data's mean pose (the layout's rest rotations) standing with the
//! hips above the origin, facing +Z: what a viewer shows without the animation, and what an engine
//! imports as the bind pose. Joints above the motion root (the Bandai files' `joint_Root`) keep
//! their static transform, so that world joint positions equal the BVH's forward kinematics.
//!
//! [`Scene`] gathers characters, materials and extras and writes the `.glb` bytes
//! deterministically (same input, same bytes); [`export_walk`] is one walk,
//! [`crowd::export_crowd`] a crowd clip with one character per walker coloured by its level of
//! detail (the paper's Figure 6 as a 3D file).

mod body;
mod character;
pub mod crowd;
mod glb;

use std::path::{Path, PathBuf};

pub use character::{Character, JointNode, Rest};
pub use glb::{Material, Scene};

use crate::model::MotionModel;
use crate::synth::Walk;

/// Why a glTF file could not be made or written.
#[derive(Debug, thiserror::Error)]
pub enum GltfError {
    /// Pose vectors of the wrong shape or with non-finite values.
    #[error("poses: {0}")]
    Poses(String),
    /// The layout refused a pose.
    #[error("pose: {0}")]
    Pose(#[from] motion_io::PoseError),
    /// The crowd could not be run.
    #[error("crowd: {0}")]
    Crowd(#[from] crowd_sim::CrowdError),
    /// The crowd's walkers could not be followed (an internal inconsistency, reported rather than
    /// written as a wrong file).
    #[error("crowd recording: {0}")]
    Recording(String),
    /// The binary buffer or the JSON would exceed the 4 GiB a GLB chunk can hold.
    #[error("the glTF would be larger than the 4 GiB a .glb can hold")]
    TooLarge,
    /// The file could not be written.
    #[error("writing {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The error.
        source: std::io::Error,
    },
}

/// Linear RGB (glTF's `baseColorFactor`) of an 8-bit sRGB colour.
pub fn srgb_to_linear(c: [u8; 3]) -> [f64; 3] {
    c.map(|v| {
        let s = f64::from(v) / 255.0;
        if s <= 0.04045 {
            s / 12.92
        } else {
            ((s + 0.055) / 1.055).powf(2.4)
        }
    })
}

/// The colour of accuracy level `level` (or root only, `level >= accuracy_levels`) in the crowd's
/// PNG renderer, used for the same level everywhere.
pub fn level_color(level: usize, accuracy_levels: usize) -> [u8; 3] {
    crowd_sim::render::RenderStyle::default().color_of_bin(level, accuracy_levels)
}

/// The name of a level histogram bin: `level L` or `root only`.
pub fn level_label(level: usize, accuracy_levels: usize) -> String {
    if level >= accuracy_levels {
        "root only".into()
    } else if level == 0 {
        "level 0 (full detail)".into()
    } else {
        format!("level {level}")
    }
}

/// One synthesized walk as a `.glb` scene: the model's skeleton (scaled by the walk's body scale,
/// [`MotionModel::walk_layout`]), its rest pose from the walk's
/// first frame (hips over the origin, facing +Z), the body, and the walk as the animation `walk`,
/// coloured as its accuracy level `level` is in the crowd renderer.
pub fn export_walk(
    model: &MotionModel,
    walk: &Walk,
    level: usize,
    name: &str,
) -> Result<Scene, GltfError> {
    let layout = &model
        .walk_layout(walk)
        .map_err(|e| GltfError::Poses(e.to_string()))?;
    let p = layout.dof();
    if walk.poses.len() < p {
        return Err(GltfError::Poses("the walk has no frame".into()));
    }
    let rest = std::sync::Arc::new(walk_rest(layout, walk)?);
    let character = Character::from_poses(layout, &rest, &walk.poses, walk.frame_time, name)?;
    let levels = model.lod().levels().len();
    let mut scene = Scene::new();
    let color = level_color(level, levels);
    let label = level_label(level, levels);
    let material = scene.add_material(&label, color);
    scene.add_character(character, material, serde_json::Value::Null);
    scene.set_extras(serde_json::json!({
        "motion_lod": {
            "kind": "walk",
            "legend": [{ "label": label, "color": color }],
            "frame_time": walk.frame_time,
            "cycle_seconds": walk.cycle_seconds,
        }
    }));
    Ok(scene)
}

/// The rest pose of a walk: its first frame's root orientation and height, turned to face +Z along
/// the ground direction the walk travels over its first cycle ([`Rest::facing`]).
pub fn walk_rest(layout: &motion_io::PoseLayout, walk: &Walk) -> Result<Rest, GltfError> {
    let p = layout.dof();
    let frames = walk.poses.len() / p;
    if frames == 0 {
        return Err(GltfError::Poses("the walk has no frame".into()));
    }
    let cycle = ((walk.cycle_seconds / walk.frame_time).round() as usize).clamp(0, frames - 1);
    let (a, b) = (&walk.poses[..p], &walk.poses[cycle * p..(cycle + 1) * p]);
    let travel = [b[0] - a[0], b[2] - a[2]];
    Rest::facing(layout, a, Some(travel))
}

/// Writes `bytes` to `path` atomically ([`lod_policy::file::write_atomic`]).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), GltfError> {
    lod_policy::file::write_atomic(path, bytes).map_err(|source| GltfError::Io {
        path: path.to_path_buf(),
        source,
    })
}
