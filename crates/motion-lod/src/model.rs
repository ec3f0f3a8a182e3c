//! [`MotionModel`]: the runtime multilinear model with its skeleton, the model file, and synthesis of
//! aligned cycles and of played-back walks.

use crate::style::StyleReport;
use kriging::Variogram;
use lod_policy::{ClipKernel, Detail, KernelScratch, LodModel, Rig, RuntimeModel};
use motion_io::PoseLayout;
use serde::{Deserialize, Serialize};

use crate::importance::JointImportance;

/// Names and units of the control parameters, in the order of every control vector.
pub const CONTROL_NAMES: [&str; 4] = lod_policy::Controls::LABELS;

/// Row of the pose vector that holds the time increment (docs/architecture.md; the runtime's
/// constant).
pub use lod_policy::TIME_ROW;

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
    /// True when ALS met its tolerance; false when it stopped at the iteration cap (a warning of
    /// the build report, [`BuildReport::warnings`]).
    pub converged: bool,
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
    /// [`RowWeights`](crate::config::RowWeights)).
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
    /// Controls that vary over the data but were left out because the samples are too few for a
    /// trend over all of them ([`crate::config::MIN_SAMPLES`]).
    pub dropped_for_samples: Vec<usize>,
    /// Rotating joints of the data that are static (held at their mean rotation, not counted).
    pub static_joints: Vec<crate::importance::StaticJoint>,
    /// Why the legs-before-arms order could not be applied, when it could not.
    pub order_note: Option<String>,
    /// Leave-one-out RMSE of the kriging fit, when measured.
    pub kriging_loo_rmse: Option<f64>,
    /// The level-0 motion quality of the model with every control the cross-validation kept, when
    /// it failed the thresholds and the build's quality guard dropped the controls whose decision
    /// reads [`kriging::DimDecision::Overruled`] ([`crate::build`], step 7); `None` otherwise.
    pub overruled_quality: Option<lod_policy::LevelError>,
    /// The motion-quality meter on the training takes (the reference of [`crate::quality`]).
    pub quality: Option<crate::quality::QualityReference>,
    /// Where the training data came from (set by the command line; `None` for in-memory data).
    pub data: Option<crate::dataset::DataSpec>,
    /// The settings the model was built with.
    pub config: crate::config::BuildConfig,
}

impl BuildReport {
    /// What the build should be warned about: key levels whose ALS stopped at the iteration cap
    /// before meeting its tolerance. Empty when all is well.
    ///
    /// The report holds only what the data, the settings and the seed determine (no timings), so
    /// that the same build writes the same bytes.
    pub fn warnings(&self) -> Vec<String> {
        let mut out = Vec::new();
        if !self.dropped_for_samples.is_empty() {
            let used = crate::CONTROL_NAMES.len() - self.dropped_controls.len();
            let names: Vec<&str> = self
                .dropped_for_samples
                .iter()
                .filter_map(|&k| crate::CONTROL_NAMES.get(k).copied())
                .collect();
            out.push(format!(
                "{} samples are too few for a trend over every varying control (universal kriging \
                 over d controls needs d + 2, and leave-one-out one more): left out the least varying \
                 ({}), kriging over {used} control{}",
                self.samples,
                names.join(", "),
                if used == 1 { "" } else { "s" }
            ));
        }
        for (k, key) in self.keys.iter().enumerate() {
            if !key.converged {
                out.push(format!(
                    "key level {k} {:?}: ALS stopped at the iteration cap ({} sweeps) before its \
                     tolerance {:e}; raise the cap or accept a less accurate key",
                    key.ranks, key.iterations, self.config.als.tol
                ));
            }
        }
        out
    }
}

/// What is wrong with a decoded model whose parts do not fit together
/// ([`MotionModel::validate`]; the runtime's type, shared by the file errors).
pub use lod_policy::InvalidModel;

/// The multilinear motion model with level-of-detail controls, as the offline side holds it: the
/// runtime's one model type ([`RuntimeModel`]: rig, multilinear model, feet, stature) with what
/// the workshop adds (the pose layout with its BVH channels, and the build report).
///
/// Built offline by [`MotionModel::build`](crate::build) from aligned gait cycles; immutable at
/// runtime, where clip kernels and poses are written into caller-owned buffers
/// ([`MotionModel::lod`]). The model file holds the runtime's section, then the report's
/// ([`crate::model_file`]); an engine reads the first alone ([`RuntimeModel::load`]).
#[derive(Debug, Clone, PartialEq)]
pub struct MotionModel {
    /// What playback needs: the runtime model.
    pub(crate) runtime: RuntimeModel,
    /// Skeleton and pose-vector layout (joint rows in the model's importance order): how BVH
    /// frames become pose vectors and back. Its rig is the runtime model's.
    pub layout: PoseLayout,
    /// What the build measured.
    pub report: BuildReport,
    /// For a model built with style labels: where they came from, the styles and the weight of
    /// their code (the model file's style section); `None` without styles.
    pub style: Option<StyleReport>,
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
            kernel: ClipKernel::new(model.lod()),
            scratch: KernelScratch::new(model.lod()),
            pose: vec![0.0; model.lod().p()],
        }
    }
}

impl MotionModel {
    /// A model from its parts, checked by [`MotionModel::validate`].
    pub fn new(
        runtime: RuntimeModel,
        layout: PoseLayout,
        report: BuildReport,
    ) -> Result<MotionModel, InvalidModel> {
        let model = MotionModel {
            runtime,
            layout,
            report,
            style: None,
        };
        model.validate()?;
        Ok(model)
    }

    /// The model with its style report: `Some` exactly when the runtime model has styles, with
    /// the same names in the same order.
    pub fn with_style_report(
        mut self,
        style: Option<StyleReport>,
    ) -> Result<MotionModel, InvalidModel> {
        let names = self.runtime.styles();
        match &style {
            None if !names.is_empty() => {
                return Err(InvalidModel(format!(
                    "the model has styles ({}) but no style report",
                    names.join(", ")
                )));
            }
            Some(r) if r.names != names => {
                return Err(InvalidModel(format!(
                    "the style report names {:?}; the runtime model's styles are {names:?}",
                    r.names
                )));
            }
            Some(r) if r.cycles.len() != names.len() || r.takes.len() != names.len() => {
                return Err(InvalidModel(format!(
                    "the style report counts {} and {} styles for {}",
                    r.cycles.len(),
                    r.takes.len(),
                    names.len()
                )));
            }
            Some(r) if !(r.weight.is_finite() && r.weight > 0.0) => {
                return Err(InvalidModel(format!(
                    "style weight {} is not finite and positive",
                    r.weight
                )));
            }
            _ => {}
        }
        self.style = style;
        Ok(self)
    }

    /// The styles the model conditions on (the runtime model's), in [`lod_policy::StyleMix`]
    /// order; empty without style labels.
    pub fn styles(&self) -> &[String] {
        self.runtime.styles()
    }

    /// The runtime model: what [`RuntimeModel::load`] reads from this model's file.
    pub fn runtime(&self) -> &RuntimeModel {
        &self.runtime
    }

    /// The multilinear model at every accuracy level (the runtime model's).
    pub fn lod(&self) -> &LodModel {
        self.runtime.lod()
    }

    /// The skeleton's feet and the data's floor, for the runtime foot lock
    /// ([`lod_policy::FootLock`]); `None` when the build found no feet.
    pub fn feet(&self) -> Option<&lod_policy::FootRig> {
        self.runtime.feet()
    }

    /// Standing height (m) of the skeleton, measured as the height control measures the data's
    /// performers ([`MotionModel::body_scale`]); `None` when the build found no feet.
    pub fn stature_m(&self) -> Option<f32> {
        self.runtime.stature_m()
    }

    /// This model with its multilinear model replaced by `lod` (the same skeleton, feet, stature and
    /// report), for comparing decomposition schemes on the same data; `lod` must fit the skeleton
    /// ([`RuntimeModel::new`]). The report is not checked against `lod`: it describes the model
    /// that was built.
    pub fn with_lod(&self, lod: LodModel) -> Result<MotionModel, InvalidModel> {
        let runtime = RuntimeModel::with_styles(self.rig().clone(), lod, self.styles().to_vec())?
            .with_feet(self.feet().copied())?
            .with_stature(self.stature_m())?;
        Ok(MotionModel {
            runtime,
            layout: self.layout.clone(),
            report: self.report.clone(),
            style: self.style.clone(),
        })
    }

    /// The parts: the runtime model, the pose layout and the report (the style report, if any, is
    /// dropped: take it first).
    pub fn into_parts(self) -> (RuntimeModel, PoseLayout, BuildReport) {
        (self.runtime, self.layout, self.report)
    }

    /// The body scale of a character with `controls`: the height they give over the skeleton's
    /// stature ([`lod_policy::ControlSpace::body_scale`]); 1 when the data hold one height. The
    /// runtime's [`RuntimeModel::body_scale`].
    pub fn body_scale(&self, controls: &lod_policy::Controls) -> f32 {
        self.runtime.body_scale(controls)
    }

    /// The skeleton and its f32 forward kinematics, as the runtime evaluates them.
    pub fn rig(&self) -> &Rig {
        self.runtime.rig()
    }

    /// Checks that the parts fit together (each part validates itself when it is built or
    /// decoded, the runtime model its rig, rows, controls, feet and stature): the pose layout's rig
    /// is the runtime model's; the build report describes this model (samples, dimensions, one
    /// source per sample, the importance order equal to the layout's joint order, one positive row
    /// weight per DOF row, one key report per key with its ranks, dropped controls among the 4)
    /// and holds finite numbers.
    pub fn validate(&self) -> Result<(), InvalidModel> {
        let bad = |what: String| Err(InvalidModel(what));
        let lod = self.lod();
        let (p, t, s) = (lod.p(), lod.t(), lod.s());
        if self.layout.dof() != p {
            return bad(format!(
                "the pose layout has {} DOF rows, the runtime model {p}",
                self.layout.dof()
            ));
        }
        if self.layout.rig() != self.runtime.rig() {
            return bad("the pose layout's rig differs from the runtime model's".into());
        }
        let r = &self.report;
        if r.samples != s || r.dims != [p, t, s] {
            return bad(format!(
                "the build report describes {} samples of dimensions {:?}, the model has {:?}",
                r.samples,
                r.dims,
                [p, t, s]
            ));
        }
        if r.sources.len() != s {
            return bad(format!(
                "the build report names {} sources for {s} samples",
                r.sources.len()
            ));
        }
        let order = self.layout.joint_order();
        if r.importance.len() != order.len()
            || r.importance.iter().zip(order).any(|(i, &j)| i.joint != j)
        {
            return bad(
                "the build report's joint importance order differs from the pose layout's joint order"
                    .into(),
            );
        }
        if let Some(i) = r.importance.iter().position(|i| !i.error_cm.is_finite()) {
            return bad(format!(
                "the build report's importance of joint {} is not finite",
                r.importance[i].joint
            ));
        }
        if r.row_weights.len() != p {
            return bad(format!(
                "the build report has {} row weights for {p} DOF rows",
                r.row_weights.len()
            ));
        }
        if let Some(i) = r
            .row_weights
            .iter()
            .position(|w| !(w.is_finite() && *w > 0.0))
        {
            return bad(format!(
                "row weight {i} is {} (must be positive and finite)",
                r.row_weights[i]
            ));
        }
        if r.keys.len() != lod.keys().len() {
            return bad(format!(
                "the build report describes {} key levels, the model holds {}",
                r.keys.len(),
                lod.keys().len()
            ));
        }
        for (k, (kr, key)) in r.keys.iter().zip(lod.keys()).enumerate() {
            let ranks = [key.ranks.p, key.ranks.t, key.ranks.s];
            if kr.ranks != ranks {
                return bad(format!(
                    "key {k}: the build report has ranks {:?}, the model {ranks:?}",
                    kr.ranks
                ));
            }
            if !(kr.mse.is_finite() && kr.rel_error.is_finite()) {
                return bad(format!("key {k}: the build report's errors are not finite"));
            }
        }
        if r.c_e.is_nan() {
            return bad("the build report's error coefficient C_E is NaN".into());
        }
        if let Some(k) = r
            .dropped_controls
            .iter()
            .find(|&&k| k >= CONTROL_NAMES.len())
        {
            return bad(format!(
                "the build report drops control {k}; there are {}",
                CONTROL_NAMES.len()
            ));
        }
        if r.kriging_loo_rmse.is_some_and(|v| !v.is_finite()) {
            return bad("the build report's kriging leave-one-out error is not finite".into());
        }
        Ok(())
    }

    /// The synthesized cycle for `controls` at `detail`, at the `T` aligned frames, as `T x P` f64 pose
    /// vectors (row-major) with the time row back in seconds. Allocates; meant for offline work.
    pub fn synthesize_aligned(
        &self,
        controls: &lod_policy::Controls,
        detail: Detail,
    ) -> Result<Vec<f64>, lod_policy::KernelError> {
        let mut ev = Evaluator::new(self);
        self.lod()
            .build_kernel(controls, detail, &mut ev.scratch, &mut ev.kernel)?;
        let (p, t) = (self.lod().p(), self.lod().t());
        let time_scale = self.lod().parts().time_scale;
        let mut out = Vec::with_capacity(p * t);
        for tau in 0..t {
            self.lod().pose(&ev.kernel, tau as f32, &mut ev.pose)?;
            out.extend(ev.pose.iter().map(|&v| v as f64));
            out[tau * p + TIME_ROW] /= time_scale;
        }
        Ok(out)
    }

    /// For every control, whether the model ignores it (constant over the data, or dropped at build
    /// by the control selection or its quality guard; its scale in the control space is 0).
    pub fn ignored_controls(&self) -> [bool; 4] {
        let scale = &self.lod().controls().scale;
        std::array::from_fn(|k| scale.get(k).is_none_or(|&v| v == 0.0))
    }

    /// Why the build left control `k` (of [`lod_policy::Controls::NAMES`]) out of the model, as
    /// a phrase with the figures that decided it ([`kriging::DimDecision`]); `None` when the
    /// model uses it.
    pub fn why_ignored(&self, k: usize) -> Option<String> {
        use kriging::DimDecision;
        if !self.ignored_controls().get(k).copied().unwrap_or(false) {
            return None;
        }
        let r = &self.report;
        Some(match r.control_decisions.get(k) {
            Some(DimDecision::Constant) if r.dropped_for_samples.contains(&k) => {
                format!("too few samples ({}) for a trend over it too", r.samples)
            }
            Some(DimDecision::NoSignal { loo_with, .. }) if !loo_with.is_finite() => {
                "dropped at build: the kriging with it added could not be fitted".to_string()
            }
            Some(DimDecision::NoSignal {
                loo_with,
                loo_without,
                t,
            }) => format!(
                "dropped at build as no signal: leave-one-out RMSE {loo_with:.4} with it, \
                    {loo_without:.4} without, t = {t:.2} (kept only above {:.1}% and t >= {})",
                100.0 * r.config.control_margin,
                r.config.control_min_t
            ),
            Some(DimDecision::DroppedByFolds {
                cv_with,
                cv_without,
                folds,
            }) => format!(
                "dropped at build: leaving it out lowers the error of {folds}-fold \
                 cross-validation by take (RMSE {cv_with:.4} with it, {cv_without:.4} without; \
                 kept unless more than {:.1}% lower)",
                100.0 * r.config.control_margin
            ),
            Some(DimDecision::Overruled {
                cv_with,
                cv_without,
                folds,
            }) => format!(
                "dropped at build by the quality guard: kept by {folds}-fold cross-validation by \
                 take (RMSE {cv_with:.4} with it, {cv_without:.4} without) but level-0 walks with \
                 it fail the motion-quality thresholds ({})",
                r.overruled_quality
                    .as_ref()
                    .map_or_else(|| "figures not kept".to_string(), quality_failures)
            ),
            _ => {
                let (lo, _) = self.control_range()[k];
                format!("constant over the data ({lo:.3})")
            }
        })
    }

    /// The range `[min, max]` of every control over the training data.
    pub fn control_range(&self) -> [(f32, f32); 4] {
        let c = self.lod().controls();
        std::array::from_fn(|k| (c.min[k], c.max[k]))
    }
}

/// The motion-quality figures of `e` beyond the near-character thresholds
/// ([`lod_policy::LevelError::passes_quality`]), e.g. `pop 1.65x (at most 1.25x), floor 2.24 cm
/// (at most 1 cm)`; `passes` when none is.
pub fn quality_failures(e: &lod_policy::LevelError) -> String {
    use lod_policy::QualityFigure;
    let out: Vec<String> = e
        .quality_figures()
        .into_iter()
        .filter(|&(_, value, limit)| value > limit || value.is_nan())
        .map(|(figure, value, limit)| match figure {
            QualityFigure::Pop => format!("pop {value:.2}x (at most {limit}x)"),
            QualityFigure::Skate => format!("skate {value:.2}x (at most {limit}x)"),
            QualityFigure::Floor => format!("floor {value:.2} cm (at most {limit} cm)"),
            QualityFigure::Facing => format!("facing {value:.1} deg beyond the data's range"),
        })
        .collect();
    if out.is_empty() {
        "passes".to_string()
    } else {
        out.join(", ")
    }
}
