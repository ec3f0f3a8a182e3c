//! Multilinear motion synthesis with level-of-detail controls (Mukai and Kuriyama).
//!
//! This facade crate is for: the whole build pipeline from BVH folders to a `MotionModel`, the model
//! file, and the `motion-lod` command line. It re-exports the runtime crates so that an engine can
//! depend on this one crate. It is not for: the mathematics itself, which lives in the crates below.
//!
//! The dataset stage ([`dataset`]): BVH folders to gait cycles on one skeleton, then to the
//! aligned `P x T x S` motion tensor with the time increment at row 6.
//!
//! ```no_run
//! use motion_lod::dataset::{DatasetConfig, align_cycles, load_cycles};
//! use timewarp::{AlignMethod, DtwConfig};
//!
//! let dirs = vec![std::path::PathBuf::from("fixtures")];
//! let set = load_cycles(&dirs, &DatasetConfig::default(), &|_, _| {})?;
//! let aligned = align_cycles(&set, None, AlignMethod::Dtw(DtwConfig::default()))?;
//! let [p, t, s] = aligned.tensor.dims();
//! println!("{} cycles kept: P = {p}, T = {t}, S = {s}", set.cycles.len());
//! # Ok::<(), motion_lod::dataset::DatasetError>(())
//! ```

#![warn(missing_docs)]

//! At runtime an engine loads a model once and, per character and cycle, builds a clip kernel for its
//! controls and level of detail, then evaluates poses into buffers it owns (no allocation per frame).
//! The runtime is [`lod_policy`] (an engine that only animates can depend on it alone); this
//! example compiles against this crate alone, as `examples/engine` in the workspace does, which
//! runs it. Units are metres, seconds and radians everywhere in the library (the command line takes
//! turns in degrees).
//!
//! ```no_run
//! use motion_lod::glam::{DVec3, Quat, Vec3};
//! use motion_lod::lod_policy::{
//!     ClipKernel, Controls, CycleFrame, DistancePolicy, KernelScratch, LevelPolicy, RuntimeModel,
//!     ViewParams,
//! };
//!
//! let model = RuntimeModel::load("walk.mlod".as_ref())?;
//! let (lod, rig) = (model.lod(), model.rig());
//! // Once per character: buffers for the largest level.
//! let (mut kernel, mut scratch) = (ClipKernel::new(lod), KernelScratch::new(lod));
//! let mut pose = vec![0.0f32; lod.p()];
//! let mut local = vec![Quat::IDENTITY; rig.joint_count()];
//! // One gait cycle (two steps): metres, radians, metres.
//! let controls = Controls::from_array([0.0, 1.3, 0.2, 1.75]); // dx, dz, turn, height
//! // The policy answers with a detail of its model (a level it has, at most its joints).
//! let detail = DistancePolicy::for_model(lod).detail(12.0, true, &ViewParams::default()); // 12 m
//! lod.build_kernel(&controls, detail, &mut scratch, &mut kernel)?;
//! let mut cycle_frame = CycleFrame::default(); // the first cycle starts at the origin, facing +z
//! let mut t = 0.0f64; // seconds into the current cycle
//! for _frame in 0..600 {
//!     if t >= kernel.duration() {
//!         // Chain the next cycle where this one's root went.
//!         t -= kernel.duration();
//!         cycle_frame = cycle_frame.next(&kernel.root_motion());
//!         lod.build_kernel(&controls, detail, &mut scratch, &mut kernel)?;
//!     }
//!     lod.pose(&kernel, kernel.phase_at(t), &mut pose)?;
//!     // For skinning: each joint's rotation relative to its parent, and the root in the world.
//!     rig.local_rotations(&pose, detail.active_joints, &mut local)?;
//!     // The frame is in double precision, and so is the world position it gives.
//!     let root_world: DVec3 = cycle_frame.to_world(Vec3::new(pose[0], pose[1], pose[2]));
//!     let root_rotation: Quat = cycle_frame.rotation() * local[rig.root()];
//!     # let _ = (root_world, root_rotation);
//!     t += 1.0 / 60.0;
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

//! The paper's baselines are crowd clip sources too, over the samples the model was built from:
//! [`NaiveSource`] (kriging of the raw samples) and [`PcaSource`] (the samples reduced to their leading
//! principal DOF directions, fewer components per accuracy level):
//!
//! ```no_run
//! use motion_lod::{BuildConfig, MotionModel, PcaSource};
//! use motion_lod::crowd_sim::ClipSource;
//! use motion_lod::dataset::DataSpec;
//! use motion_lod::progress::NoProgress;
//!
//! let spec = DataSpec { dirs: vec!["fixtures".into()], ..DataSpec::default() };
//! let data = spec.load(&|_, _| {})?;
//! let (model, analysis) =
//!     MotionModel::build_with_analysis(&data.training, &BuildConfig::default(), &NoProgress)?;
//! let pca = PcaSource::new(&model, &analysis, 40)?; // R_P,max = 40 as in the paper
//! println!("components per level {:?}, {} levels", pca.level_ranks(), pca.levels().accuracy_levels);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

//! Style as a control: label each take's style (here from the file names; a folder per style or a
//! CSV table work too, [`style::StyleSpec`]), build, and ask for one style or a blend; the kernel
//! normalises the weights, and all zero is the data's own mix ([`lod_policy::StyleMix`]):
//!
//! ```no_run
//! use motion_lod::dataset::DataSpec;
//! use motion_lod::lod_policy::Controls;
//! use motion_lod::progress::NoProgress;
//! use motion_lod::style::{StyleSpec, parse_style_mix};
//! use motion_lod::{BuildConfig, MotionModel};
//!
//! let spec = DataSpec { dirs: vec!["takes".into()], ..DataSpec::default() };
//! let labels = StyleSpec::Name(r"_([a-z]+)_\d+\.bvh$".into()); // walk_elderly_001.bvh: elderly
//! let set = spec.load(&|_, _| {})?.training.with_styles(Some(&labels))?;
//! let model = MotionModel::build(&set, &BuildConfig::default(), &NoProgress)?;
//! println!("styles {:?}, shares {:?}", model.styles(), model.runtime().data_style_mix());
//! let style = parse_style_mix(model.styles(), "elderly=0.5,youthful=0.5")?;
//! let controls = Controls::from_array([0.0, 0.9, 0.0, 1.7]).with_style(style); // dx, dz, turn, height
//! # let _ = controls;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod build;
pub mod config;
pub mod crowd;
pub mod dataset;
pub mod eval;
pub mod folds;
pub mod footlock;
pub mod gltf;
pub mod hull;
pub mod importance;
pub mod info;
pub mod metrics;
pub mod model;
pub mod model_file;
pub mod naive;
pub mod pca;
pub mod posture;
pub mod progress;
pub mod projection;
pub mod quality;
pub mod recording;
mod sample_weights;
pub mod source;
pub mod storage;
pub mod style;
pub mod synth;
pub mod track;
pub mod walk_quality;

pub use build::{Analysis, BuildConfig, BuildError, TrainingSet};
pub use model::{BuildReport, CONTROL_NAMES, Evaluator, MotionModel, TIME_ROW};
pub use naive::NaiveSource;
pub use pca::PcaSource;
pub use source::LodSource;

/// The math types of the runtime's API (`Vec3`, `Quat`), the same version as the runtime's.
pub use lod_policy::glam;
/// The crates below, re-exported so that a tool can depend on this crate alone (an engine that only
/// animates needs just `lod_policy`, the runtime).
pub use {crowd_sim, hosvd_als, kriging, lod_policy, motion_io, tensor_ops, timewarp};
