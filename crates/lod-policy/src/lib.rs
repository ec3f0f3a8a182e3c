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
//! The jobs an engine runs, in call order (Mukai and Kuriyama, sections 3.2-4.3), each a small call
//! over buffers the caller owns, none allocating after its buffers exist:
//! 1. **Load** the model once: [`RuntimeModel::load`] or [`RuntimeModel::from_bytes`] read the
//!    runtime's own section of a model file ([`file`](mod@file): sections, checksums, versions,
//!    [`FileError`]) into the one model type: the [`Rig`], the multilinear model at every accuracy
//!    level ([`LodModel`]: key tensors with their universal-kriging projections, accuracy levels,
//!    the control space with its [`Variogram`], the mean pose, measured error tables), the
//!    [`FootRig`] and the stature.
//! 2. **Per character, once**: a [`ClipKernel`], a [`KernelScratch`] (shared by the characters of a
//!    thread), a pose vector, a [`FootLock`].
//! 3. **Per cycle**: the [`LevelPolicy`] ([`DistancePolicy`], the paper's, or
//!    [`ScreenSpacePolicy`] with a pixel budget) gives the [`Detail`] from the camera; then
//!    [`LodModel::build_kernel`] builds the clip for the [`Controls`]: the kriging weights, the
//!    blended core `K(c) = Z x_3 w` (eq. 8), `G(c) = U_P K(c)` for the active rows, the clip's
//!    [`TimeTable`] and its [`RootMotion`].
//! 4. **Per frame**: [`LodModel::pose`] evaluates `G w_T` (eq. 4-5) at [`ClipKernel::phase_at`];
//!    [`FootLock::apply`] holds planted feet; [`Rig::local_rotations`] (local space, for skinning)
//!    or [`Rig::joint_transforms`] (model space) turn the pose into joints.
//! 5. **At a cycle's end**: [`CycleFrame::next`] moves the character's frame by the clip's root
//!    motion, and the next clip is built (step 3); a [`SeamTransition`] inertializes the change.
//!
//! The vocabulary is one type per concept ([`Controls`], [`Detail`], [`ClipKernel`],
//! [`RuntimeModel`]); `docs/architecture.md` has the glossary. The [`offline`] module holds what the
//! offline crates share with the runtime to get its bits; an engine needs none of it. The baseline
//! and reference kernels exist only with the feature `reference`, for tests and benchmarks.
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
//!     model.build_kernel(controls, detail, &mut scratch, &mut kernel)?;
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
//! lod.build_kernel(&lod_policy::Controls::from_array([0.0, 1.4, 0.0, 1.7]), lod.full_detail(), &mut scratch, &mut kernel)?;
//! lod.pose(&kernel, kernel.phase_at(0.25), &mut pose)?;
//! rig.joint_positions(&pose, kernel.detail().active_joints, &mut joints)?; // metres, cycle frame
//! # Ok(())
//! # }
//! ```

#![warn(missing_docs)]

mod chain;
mod controls;
mod detail;
mod error;
pub mod file;
mod footlock;
mod kernel;
mod math;
mod model;
pub mod offline;
mod policy;
mod rig;
mod rng;
mod runtime;
mod time_table;
mod variogram;

// The jobs an engine runs, in call order (docs/architecture.md, "How an engine uses it").

// 1. Load: the one model type, read from its section of a model file.
pub use runtime::{RuntimeModel, STYLE_PREFIX, check_stature, style_name_problem};

// 2. Per character, once: the buffers every job writes into.
pub use kernel::{ClipKernel, KernelScratch};

// 3. Per cycle: the policy chooses the detail, then the clip is built for the controls.
pub use policy::{
    DistanceConfig, DistancePolicy, ERROR_MARGIN, ErrorMetric, FullDetail, LevelPolicy,
    PolicyError, ScreenConfig, ScreenSpacePolicy, ViewParams,
};

// 4. Per frame: the pose at the clip's phase (`LodModel::pose`), then local rotations or model-space
//    transforms (`Rig`), and the foot lock on the pose.
pub use footlock::{Foot, FootLock, FootLockError, FootRig};
pub use rig::{JointRole, JointTransform, MAX_OFFSET_M, MAX_POSE_VALUE, Rig, RigJoint};

// 5. At a cycle's end: chain to the next cycle (the cycle frame moves by the clip's root motion),
//    optionally with an inertialized seam.
pub use chain::{
    CycleFrame, DEFAULT_HALFLIFE_S, PoseState, RootMotion, SEAM_STEP_S, SeamScratch, SeamTransition,
};

// The one vocabulary: controls, detail, the pose rows, time, errors.
pub use controls::{ControlRange, Controls, MAX_STYLES, StyleMix, clamp_control};
pub use detail::Detail;
pub use error::{KernelError, ModelError, RigError, VariogramError};
pub use file::{FileError, InvalidModel};
/// The math types of the runtime API (`Vec3`, `Quat`), so an engine uses the same version.
pub use glam;
pub use kernel::TURN_CONTROL;
pub use math::{ease_in_out, wrap_angle, wrap_angle_f64};
pub use model::{
    ALWAYS_ROWS, CONTROL_VALUES, HEIGHT_CONTROL, QUALITY_FACING_OUT_DEG, QUALITY_FLOOR_CM,
    QUALITY_POP_LIMIT, QUALITY_SKATE_LIMIT, QualityFigure, ROWS_PER_JOINT, TIME_ROW,
};
pub use rng::SplitMix64;
pub use time_table::{MIN_INCREMENT, TimeTable};

// The model's data: what the offline builder fills and a reader may inspect (ranks, levels,
// errors, storage).
pub use model::{
    AccuracyLevel, ControlSpace, KeyTensor, LevelError, LodModel, ModelParts, Precision, Ranks,
    Variogram, VariogramModel,
};
