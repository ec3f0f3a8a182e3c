//! The runtime multilinear motion model and the level-of-detail policies.
//!
//! This crate is for: evaluating poses from a compressed motion model at any accuracy level (clip
//! kernels and per-frame poses into caller-owned buffers) and for choosing a level per character from
//! its distance or projected size. It is not for: building models (see `motion-lod`) or simulating
//! crowds (see `crowd-sim`).
//!
//! The pieces (Mukai and Kuriyama, sections 3.2-4.3):
//! - [`model`]: [`LodModel`], validated from plain-data [`ModelParts`]: key tensors (ordered Tucker
//!   models with their universal-kriging projections), accuracy levels (leading sub-block
//!   truncations of a key), the control space, the mean pose, measured error tables, storage.
//! - [`projection`]: offline helpers that compute a key's kriging projection `Q` and trend
//!   projection `V` from `U_S`, the kriging matrix inverse and the sample controls.
//! - [`kernel`]: per clip, [`LodModel::build_kernel`] computes the kriging weights, the blended
//!   core `K(c) = Z x_3 w` (eq. 8), `G(c) = U_P K(c)` for the active rows and the clip's time
//!   table; per frame, [`LodModel::pose`] evaluates `G w_T` (eq. 4-5). Neither allocates.
//! - [`policy`]: the paper's [`DistancePolicy`] and a [`ScreenSpacePolicy`] with a pixel budget,
//!   both behind the [`LevelPolicy`] trait.
//! - The one vocabulary: [`Controls`] (with their names, units and [`ControlRange`] clamp),
//!   [`Detail`], [`RootMotion`], the angle wrap and ease curve ([`math`]) and the seeded generator
//!   ([`rng`]).
//!
//! ```
//! use lod_policy::{Detail, DistancePolicy, LevelPolicy, LodModel, ViewParams};
//!
//! fn animate(model: &LodModel, controls: &lod_policy::Controls, distance_m: f32) -> Result<Vec<f32>, Box<dyn std::error::Error>> {
//!     // Once per model: preallocated buffers.
//!     let mut scratch = lod_policy::KernelScratch::new(model);
//!     let mut kernel = lod_policy::ClipKernel::new(model);
//!     let mut pose = vec![0.0f32; model.p()];
//!     // Once per clip: the level from the policy, then the kernel.
//!     let policy = DistancePolicy::for_model(model);
//!     let detail: Detail = policy.detail(distance_m, true, &ViewParams::default());
//!     model.build_kernel(&controls.to_array(), detail, &mut scratch, &mut kernel)?;
//!     // Per frame: playback time -> aligned phase -> pose vector.
//!     let phase = kernel.phase_at(0.5 * kernel.duration());
//!     model.pose(&kernel, phase, &mut pose)?;
//!     Ok(pose)
//! }
//! # let _ = animate;
//! ```

#![warn(missing_docs)]

pub mod chain;
pub mod controls;
pub mod detail;
pub mod error;
pub mod kernel;
pub mod math;
pub mod model;
pub mod policy;
pub mod projection;
pub mod rng;

pub use chain::{CycleFrame, PoseState, RootMotion, SeamScratch, SeamTransition};
pub use controls::{ControlRange, Controls, clamp_control};
pub use detail::Detail;
pub use error::{KernelError, ModelError};
pub use kernel::{ClipKernel, KernelScratch, TURN_CONTROL};
pub use math::{ease_in_out, wrap_angle};
pub use model::{
    ALWAYS_ROWS, AccuracyLevel, ControlSpace, KeyTensor, LevelError, LodModel, ModelParts,
    Precision, ROWS_PER_JOINT, Ranks, TIME_ROW, Variogram, VariogramModel,
};
pub use policy::{
    DistanceConfig, DistancePolicy, ERROR_MARGIN, ErrorMetric, FullDetail, LevelPolicy,
    PolicyError, ScreenConfig, ScreenSpacePolicy, ViewParams,
};
pub use projection::KeyFactors;
