//! The motion-lod runtime: the one crate an engine links to animate characters from a model file.
//!
//! This crate is for: loading a model file ([`RuntimeModel::load`], [`RuntimeModel::from_bytes`]:
//! framing, checksum, version, validation), evaluating poses from the compressed multilinear model at
//! any accuracy level (clip kernels and per-frame poses into caller-owned buffers), turning poses into
//! joint positions and transforms in f32 ([`Rig`]), chaining clips into a walk, and choosing a level
//! per character from its distance or projected size. Its dependencies are serde, bincode, glam,
//! thiserror and crc32fast only. It is not for: building models (the offline `motion-lod` crate
//! fits the decomposition, the kriging and the variogram, and writes the file with this crate's
//! framing), reading motion capture, or simulating crowds (see `crowd-sim`).
//!
//! The pieces (Mukai and Kuriyama, sections 3.2-4.3):
//! - [`runtime`]: [`RuntimeModel`], a model file's [`Rig`] and [`LodModel`]; [`file`](mod@file): the file
//!   framing and its errors ([`FileError`]), shared with the offline writer.
//! - [`model`]: [`LodModel`], validated from plain-data [`ModelParts`]: key tensors (ordered Tucker
//!   models with their universal-kriging projections), accuracy levels (leading sub-block
//!   truncations of a key), the control space with its [`Variogram`], the mean pose, measured error
//!   tables, storage.
//! - [`kernel`]: per clip, [`LodModel::build_kernel`] computes the kriging weights, the blended
//!   core `K(c) = Z x_3 w` (eq. 8), `G(c) = U_P K(c)` for the active rows and the clip's
//!   [`TimeTable`]; per frame, [`LodModel::pose`] evaluates `G w_T` (eq. 4-5). Neither allocates.
//! - [`rig`]: [`Rig`], forward kinematics of f32 poses for the active joints.
//! - [`footlock`]: [`FootLock`], planted feet frame by frame (a causal foot lock with two-bone IK)
//!   for the model file's [`FootRig`].
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
//!
//! From a file to joint positions:
//!
//! ```no_run
//! use lod_policy::{ClipKernel, Detail, KernelScratch, RuntimeModel};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let model = RuntimeModel::load(std::path::Path::new("walk.mlod"))?;
//! let (lod, rig) = (model.lod(), model.rig());
//! let (mut scratch, mut kernel) = (KernelScratch::new(lod), ClipKernel::new(lod));
//! let mut pose = vec![0.0f32; lod.p()];
//! let mut joints = vec![glam::Vec3::ZERO; rig.joint_count()];
//! lod.build_kernel(&[0.0, 1.4, 0.0, 1.7], Detail::full(), &mut scratch, &mut kernel)?;
//! lod.pose(&kernel, kernel.phase_at(0.25), &mut pose)?;
//! rig.joint_positions(&pose, kernel.detail().active_joints, &mut joints)?; // metres, cycle frame
//! # Ok(())
//! # }
//! ```

#![warn(missing_docs)]

pub mod chain;
pub mod controls;
pub mod detail;
pub mod error;
pub mod file;
pub mod footlock;
pub mod kernel;
pub mod math;
pub mod model;
pub mod policy;
pub mod rig;
pub mod rng;
pub mod runtime;
pub mod time_table;
pub mod variogram;

pub use chain::{CycleFrame, PoseState, RootMotion, SeamScratch, SeamTransition};
pub use controls::{ControlRange, Controls, clamp_control};
pub use detail::Detail;
pub use error::{KernelError, ModelError, RigError, VariogramError};
pub use file::{FileError, InvalidModel};
pub use footlock::{Foot, FootLock, FootLockError, FootRig};
/// The math types of the runtime API (`Vec3`, `Quat`), so an engine uses the same version.
pub use glam;
pub use kernel::{ClipKernel, KernelScratch, TURN_CONTROL};
pub use math::{
    clear_avx_upper_state, ease_in_out, prefetch, prefetch_bytes, prefetch_slice, wrap_angle,
};
pub use model::{
    ALWAYS_ROWS, AccuracyLevel, ControlSpace, HEIGHT_CONTROL, KeyTensor, LevelError, LodModel,
    ModelParts, Precision, ROWS_PER_JOINT, Ranks, TIME_ROW, Variogram, VariogramModel,
};
pub use policy::{
    DistanceConfig, DistancePolicy, ERROR_MARGIN, ErrorMetric, FullDetail, LevelPolicy,
    PolicyError, ScreenConfig, ScreenSpacePolicy, ViewParams,
};
pub use rig::{JointRole, JointTransform, Rig, RigJoint};
pub use runtime::RuntimeModel;
pub use time_table::{MIN_INCREMENT, TimeTable};
