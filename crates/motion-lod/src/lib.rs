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
//! controls and level of detail, then evaluates poses into buffers it owns (no allocation per frame):
//!
//! ```no_run
//! use motion_lod::{Evaluator, MotionModel};
//! use motion_lod::lod_policy::Detail;
//!
//! let model = MotionModel::load("walk.mlod".as_ref())?;
//! let mut ev = Evaluator::new(&model); // kernel, scratch and pose buffers, allocated once
//! let controls = [0.0, 1.3, 0.2, 1.75]; // dx, dz (m), turn (rad), height (m) of one two-step cycle
//! model.lod.build_kernel(&controls, Detail::new(3, 12), &mut ev.scratch, &mut ev.kernel)?;
//! let mut joints = vec![glam::Vec3::ZERO; model.layout.skeleton().joints.len()];
//! for frame in 0..60 {
//!     let t = frame as f64 / 60.0; // seconds into the cycle
//!     model.lod.pose(&ev.kernel, ev.kernel.phase_at(t), &mut ev.pose)?;
//!     model.layout.joint_positions(&ev.pose, 12, &mut joints); // metres, cycle frame
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

pub mod build;
pub mod crowd;
pub mod dataset;
pub mod eval;
pub mod footlock;
pub mod gltf;
pub mod importance;
pub mod info;
pub mod metrics;
pub mod model;
pub mod model_file;
pub mod naive;
pub mod pca;
pub mod progress;
pub mod projection;
pub mod quality;
mod sample_weights;
pub mod source;
pub mod storage;
pub mod synth;

pub use build::{Analysis, BuildConfig, BuildError, TrainingSet};
pub use model::{BuildReport, CONTROL_NAMES, Evaluator, MotionModel, TIME_ROW};
pub use naive::NaiveSource;
pub use pca::PcaSource;
pub use source::LodSource;

/// The runtime crates, re-exported so that an engine can depend on this crate alone.
pub use {crowd_sim, hosvd_als, kriging, lod_policy, motion_io, tensor_ops, timewarp};
