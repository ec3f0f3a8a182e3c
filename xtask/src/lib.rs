//! Project tasks of the motion-lod workspace, as a library behind the `xtask` binary.
//!
//! This crate is for: generating the committed data in `fixtures/` with a procedural walker
//! (`cargo xtask fixtures`), and measuring the paper's tables and figures into `docs/tables.md` and
//! `docs/figures/` (`cargo xtask tables`, see [`tables`]). It is not for: anything the runtime or the model pipeline links
//! against (no other crate depends on it), nor for reading real motion capture (see `motion-io`).
//!
//! The walker is a parametric gait: per take a performer height, a steady speed and a turn rate
//! ([`gait::TakeSpec`]) give the root path and gait phase ([`gait::Trajectory`]), rolling foot
//! contacts at planted footholds ([`footsteps::FootPlanner`]), two-bone leg IK ([`leg_ik`]) and
//! a full-body pose per frame ([`walker::generate`]) on a 19-joint skeleton ([`rig::Rig`]). It is
//! deterministic: a fixed seed, a self-written SplitMix64 generator ([`rng`]) and frames printed
//! with 4 decimals ([`fixtures::bvh_text`]).
//!
//! ```
//! use xtask::gait::{Style, TakeSpec};
//! let spec = TakeSpec {
//!     height_m: 1.75,
//!     speed: 1.2,
//!     turn_rate_deg: 15.0,
//!     heading0_deg: 0.0,
//!     start_m: [0.0, 0.0],
//!     steady_cycles: 4,
//!     style: Style::default(),
//! };
//! let take = xtask::walker::generate(&spec)?;
//! assert_eq!(take.motion.skeleton.joint_count(), 19);
//! assert!((take.motion.fps() - 120.0).abs() < 1e-9);
//! let text = xtask::fixtures::bvh_text(&take.motion);
//! let back = motion_io::parse_bvh(&text)?;
//! assert_eq!(back.frame_count(), take.motion.frame_count());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![warn(missing_docs)]

pub mod euler;
pub mod fixtures;
pub mod footsteps;
pub mod gait;
pub mod imports;
pub mod leg_ik;
pub mod readme;
pub mod rig;
pub mod rng;
pub mod scaling;
pub mod tables;
pub mod variants;
pub mod walker;
pub mod web;
