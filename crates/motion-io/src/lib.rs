//! Motion capture input and output: BVH files, skeletons, forward kinematics, gait cycles.
//!
//! This crate is for: reading and writing Biovision BVH, forward kinematics with glam, pose vectors
//! built from exponential maps, canonicalisation, foot contacts and the segmentation of takes into
//! two-step gait cycles with their control parameters. It is not for: time alignment (see `timewarp`)
//! or statistics over many cycles.
//!
//! Modules: [`bvh`] (reader, writer, errors with line numbers), [`Skeleton`] / [`Motion`] (hierarchy,
//! frames, FK in file units), [`units`] (units per metre), [`normalize`] (any exporter's units, up axis, root semantics, feet
//! and reference frames brought into the project's conventions), [`euler`] and [`expmap`] (rotation
//! conversions), [`pose`] (pose vectors of the paper's section 3 and their FK in metres),
//! [`contacts`] (feet, leg length, contacts) and [`cycles`] (segmentation, canonicalisation,
//! controls).
//!
//! ```
//! use motion_io::{parse_bvh, PoseLayout, to_bvh_string};
//!
//! let text = "HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n JOINT Spine\n {\n  OFFSET 0 20 0\n  CHANNELS 3 Zrotation Xrotation Yrotation\n  End Site\n  {\n   OFFSET 0 30 0\n  }\n }\n}\nMOTION\nFrames: 2\nFrame Time: 0.0333333\n0 90 0 0 0 170 10 0 0\n0 90 5 0 0 -170 12 0 0\n";
//! let motion = parse_bvh(text)?;
//! // Centimetres; the root is the first joint whose position channels vary.
//! let layout = PoseLayout::from_motions(&[&motion], 100.0)?;
//! let poses = layout.poses_from_motion(&motion)?; // frames x dof, exp-maps unwrapped over time
//! assert_eq!(layout.dof(), 7 + 3);
//! assert!((poses[1] - 0.9).abs() < 1e-12); // root height in metres
//! // The root turned from 170 to -170 degrees about y: no jump in the exp-map.
//! assert!((poses[layout.dof() + 4] - poses[4]).abs() < 0.4);
//! // Back to BVH channels and text.
//! let written = layout.motion_from_poses(&poses, motion.frame_time)?;
//! let again = parse_bvh(&to_bvh_string(&written))?;
//! assert_eq!(again.frame_count(), 2);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![warn(missing_docs)]

pub mod bvh;
pub mod contacts;
pub mod cycles;
pub mod euler;
pub mod expmap;
mod folder;
mod motion;
pub mod normalize;
pub mod pose;
mod skeleton;
pub mod test_data;
pub mod units;

pub use bvh::{
    BvhError, BvhErrorKind, parse_bvh, read_bvh, to_bvh_string, to_bvh_string_checked,
    with_rest_at_origin, write_bvh,
};
pub use contacts::{
    CycleError, Feet, FootNames, feet_by_hierarchy, find_feet, mirrored_names, name_words, side_of,
    standing_height,
};
pub use cycles::{
    CycleConfig, CycleReport, DropReason, DroppedCycle, GaitCycle, MeasuredControls,
    segment_cycles, segment_take,
};
pub use folder::{FolderReport, read_folder};
pub use motion::Motion;
pub use normalize::{
    Conventions, NormalizeOptions, NormalizedTake, RootPositions, SignedAxis, SkipReason,
    SkippedFrames, Units, normalize_take,
};
pub use pose::{
    PoseError, PoseLayout, PoseLayoutParts, align_exp_maps, align_sequence, unwrap_exp_maps,
};
pub use skeleton::{Channel, Joint, Skeleton, SkeletonError, Transform, axis_rotation};
pub use units::{detect_units_per_metre, motion_root, to_metres};
