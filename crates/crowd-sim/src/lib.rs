//! Crowds of walking characters over a field.
//!
//! This crate is for: walkers with paths, clip scheduling and transitions, a camera with frustum
//! culling (a scan of every walker box, or a bounding volume hierarchy), parallel per-frame
//! updates, timings and PNG rendering.
//! It knows nothing of tensors: clips come from a `ClipSource` implementation. It is not for:
//! synthesising motion itself.
//!
//! It speaks the runtime's vocabulary (`lod_policy`): [`Controls`](lod_policy::Controls),
//! [`Detail`](lod_policy::Detail), [`RootMotion`](lod_policy::RootMotion) and the one policy trait
//! [`LevelPolicy`](lod_policy::LevelPolicy).
//!
//! Each walker follows a seeded closed path inside the field; every gait cycle asks the source
//! for a clip at controls taken from the path ahead (clamped to the source's
//! [`ControlRange`](lod_policy::ControlRange)) and at the detail a policy picks from the walker's
//! distance to the camera and its visibility (checked against the source's [`LevelTable`]). A new
//! crowd's walkers hold root-only clips at random phases and take their detail over their first
//! cycle ([`CrowdConfig::spread_first_builds`]), unless the crowd is primed before its first frame
//! ([`Crowd::prime`]: every walker starts mid-stride at its detail, as recordings and exports do). A
//! clip the source cannot build is counted in the frame's statistics
//! ([`FrameStats::clip_faults`]) and the walker keeps its previous clip. Cycles chain through their root motion with the runtime's one
//! chaining routine ([`lod_policy::SeamTransition`]): changes of clip are inertialized at the first levels
//! (continuous in position and velocity) and switched as they are beyond. Each frame
//! culls walker boxes against the camera frustum ([`Culling`]: a scan of every box inside the
//! frame's parallel pass, or an AABB tree, [`culling`]), then runs kernels, poses and forward
//! kinematics in parallel over walkers (rayon), with the same result for any thread
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
mod crowd;
pub mod culling;
pub mod error;
pub mod levels;
pub mod path;
pub mod render;
pub mod source;
pub mod stats;
mod stock;
pub mod testing;
mod walker;

pub use camera::{Bounds, Camera, CameraPath, Frustum, Scene};
pub use crowd::{Crowd, CrowdConfig, CrowdStyle, Culling, MAX_DT, MAX_FIELD_M, MAX_WALKERS};
pub use error::{ClipError, CrowdError, RenderError};
pub use levels::{LevelTable, check_control_range};
pub use source::{ClipSource, MAX_CLIP_CLASSES};
pub use stats::{ClipFaults, CrowdReport, FrameStats, FrameTimes, StageTimings};
