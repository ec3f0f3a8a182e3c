//! [`MotionModel`]: the runtime multilinear model with its skeleton, the model file, and synthesis of
//! aligned cycles and of played-back walks.

use std::path::Path;

use kriging::Variogram;
use lod_policy::{ClipKernel, Detail, KernelScratch, LodModel};
use motion_io::PoseLayout;
use serde::{Deserialize, Serialize};

use crate::importance::JointImportance;
use crate::model_file::{self, ModelFileError};

/// Names and units of the control parameters, in the order of every control vector.
pub const CONTROL_NAMES: [&str; 4] = ["dx (m)", "dz (m)", "turn (rad)", "height (m)"];

/// Row of the pose vector that holds the time increment (docs/architecture.md).
pub const TIME_ROW: usize = 6;

/// One key level as built (for reports and tables).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct KeyReport {
    /// Ranks `(R_P, R_T, R_S)`.
    pub ranks: [usize; 3],
    /// The paper's mean squared tensor error `E` (section 4.2).
    pub mse: f64,
    /// `||M - M~|| / ||M||`.
    pub rel_error: f64,
    /// ALS sweeps.
    pub iterations: usize,
}

/// What the build measured and decided, stored with the model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BuildReport {
    /// Motion samples `S`.
    pub samples: usize,
    /// Tensor dimensions `(P, T, S)`.
    pub dims: [usize; 3],
    /// Source of every sample (file and frames).
    pub sources: Vec<String>,
    /// Joints by decreasing measured importance (the row order of the model).
    pub importance: Vec<JointImportance>,
    /// Weight of every DOF row in the decomposition (model row order; see
    /// [`RowWeights`](crate::build::RowWeights)).
    pub row_weights: Vec<f64>,
    /// Key levels as searched.
    pub keys: Vec<KeyReport>,
    /// The greedy search's error coefficient `C_E = E_N / (N E_1)`.
    pub c_e: f64,
    /// True when a requested rank exceeded a mode size and was clamped.
    pub ranks_clamped: bool,
    /// The fitted residual variogram.
    pub variogram: Variogram,
    /// Control dimensions dropped from kriging: constant over the data, or carrying no signal
    /// (see `control_decisions`). The runtime ignores them.
    pub dropped_controls: Vec<usize>,
    /// Per control, what the build's leave-one-out selection decided and measured
    /// ([`kriging::select_dims`]).
    pub control_decisions: Vec<kriging::DimDecision>,
    /// Rotating joints of the data that are static (held at their mean rotation, not counted).
    pub static_joints: Vec<crate::importance::StaticJoint>,
    /// Why the legs-before-arms order could not be applied, when it could not.
    pub order_note: Option<String>,
    /// Leave-one-out RMSE of the kriging fit, when measured.
    pub kriging_loo_rmse: Option<f64>,
    /// Wall-clock seconds of the build.
    pub seconds: f64,
    /// Where the training data came from (set by the command line; `None` for in-memory data).
    pub data: Option<crate::dataset::DataSpec>,
    /// The settings the model was built with.
    pub config: crate::build::BuildConfig,
}

/// The multilinear motion model with level-of-detail controls.
///
/// Built offline by [`MotionModel::build`](crate::build) from aligned gait cycles; immutable at
/// runtime, where clip kernels and poses are written into caller-owned buffers
/// ([`MotionModel::lod`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MotionModel {
    /// Skeleton and pose-vector layout (joint rows in the model's importance order).
    pub layout: PoseLayout,
    /// The runtime model at every accuracy level.
    pub lod: LodModel,
    /// What the build measured.
    pub report: BuildReport,
}

/// Everything needed to evaluate clips of one model without allocating.
#[derive(Debug, Clone)]
pub struct Evaluator {
    /// The clip kernel (refilled per clip).
    pub kernel: ClipKernel,
    /// Kernel scratch.
    pub scratch: KernelScratch,
    /// One f32 pose.
    pub pose: Vec<f32>,
}

impl Evaluator {
    /// Buffers sized for the largest level of `model`.
    pub fn new(model: &MotionModel) -> Evaluator {
        Evaluator {
            kernel: ClipKernel::new(&model.lod),
            scratch: KernelScratch::new(&model.lod),
            pose: vec![0.0; model.lod.p()],
        }
    }
}

impl MotionModel {
    /// Writes the model file atomically (see [`crate::model_file`]).
    pub fn save(&self, path: &Path) -> Result<(), ModelFileError> {
        model_file::save(self, path)
    }

    /// Reads and validates a model file.
    pub fn load(path: &Path) -> Result<MotionModel, ModelFileError> {
        let model: MotionModel = model_file::load(path)?;
        if model.layout.dof() != model.lod.p() {
            return Err(ModelFileError::Decode {
                path: path.to_path_buf(),
                message: format!(
                    "layout has {} DOF, the runtime model {}",
                    model.layout.dof(),
                    model.lod.p()
                ),
            });
        }
        Ok(model)
    }

    /// The synthesized cycle for `controls` at `detail`, at the `T` aligned frames, as `T x P` f64 pose
    /// vectors (row-major) with the time row back in seconds. Allocates; meant for offline work.
    pub fn synthesize_aligned(
        &self,
        controls: &[f32; 4],
        detail: Detail,
    ) -> Result<Vec<f64>, lod_policy::KernelError> {
        let mut ev = Evaluator::new(self);
        self.lod
            .build_kernel(controls, detail, &mut ev.scratch, &mut ev.kernel)?;
        let (p, t) = (self.lod.p(), self.lod.t());
        let time_scale = self.lod.parts().time_scale;
        let mut out = Vec::with_capacity(p * t);
        for tau in 0..t {
            self.lod.pose(&ev.kernel, tau as f32, &mut ev.pose)?;
            out.extend(ev.pose.iter().map(|&v| v as f64));
            out[tau * p + TIME_ROW] /= time_scale;
        }
        Ok(out)
    }

    /// For every control, whether the model ignores it (constant over the data, or dropped at build
    /// for carrying no signal; its scale in the control space is 0).
    pub fn ignored_controls(&self) -> [bool; 4] {
        let scale = &self.lod.controls().scale;
        std::array::from_fn(|k| scale.get(k).is_none_or(|&v| v == 0.0))
    }

    /// The range `[min, max]` of every control over the training data.
    pub fn control_range(&self) -> [(f32, f32); 4] {
        let c = self.lod.controls();
        std::array::from_fn(|k| (c.min[k], c.max[k]))
    }
}
