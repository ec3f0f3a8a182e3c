//! Crowds of walking characters over a field.
//!
//! This crate is for: walkers with paths, clip scheduling and transitions, a camera with frustum
//! culling over a bounding volume hierarchy, parallel per-frame updates, timings and PNG rendering.
//! It knows nothing of tensors: clips come from a `ClipSource` implementation. It is not for:
//! synthesising motion itself.
//!
//! Each walker follows a seeded closed path inside the field; every gait cycle asks the source
//! for a clip at controls taken from the path ahead (clamped to the source's
//! [`ControlBounds`]) and at the [`Detail`] a [`DetailPolicy`] picks from the walker's distance to
//! the camera and its visibility. Cycles chain through their root motion with the runtime's one
//! chaining routine ([`lod_policy::chain`]): changes of clip are inertialized at the first levels
//! (continuous in position and velocity) and switched as they are beyond. Each frame
//! culls walker boxes against the camera frustum through a BVH, then runs kernels, poses and
//! forward kinematics in parallel over walkers (rayon), with the same result for any thread
//! count, and reports per-stage timings and a level histogram. [`render`] draws stick figures
//! coloured by level (paper Figure 6), a top-down map and an animated GIF.
//!
//! ```
//! use crowd_sim::testing::{ProceduralSource, paper_distance_policy};
//! use crowd_sim::{Camera, ClipSource, Crowd, CrowdConfig};
//!
//! let source = ProceduralSource::new();
//! let policy = paper_distance_policy(source.levels());
//! let config = CrowdConfig { walkers: 200, field_size_m: 60.0, ..CrowdConfig::default() };
//! let mut crowd = Crowd::new(&source, config)?;
//! let camera = Camera::default();
//! let stats = crowd.step(&source, &policy, &camera, 1.0 / 30.0)?;
//! assert_eq!(stats.level_histogram.iter().sum::<u32>(), 200);
//! let head_of_first = crowd.joint_positions(0);
//! assert!(!head_of_first.is_empty());
//! # Ok::<(), crowd_sim::CrowdError>(())
//! ```

#![warn(missing_docs)]

pub mod camera;
pub mod controls;
mod crowd;
pub mod culling;
pub mod error;
pub mod path;
pub mod policy;
pub mod render;
pub mod rng;
pub mod source;
pub mod stats;
pub mod testing;
mod walker;

pub use camera::{Bounds, Camera, CameraPath, Frustum, Scene};
pub use controls::{ControlBounds, Controls, Detail, LevelTable, RootMotion};
pub use crowd::{Crowd, CrowdConfig};
pub use error::{CrowdError, RenderError};
pub use policy::DetailPolicy;
pub use source::ClipSource;
pub use stats::{CrowdReport, FrameStats, StageTimings};
