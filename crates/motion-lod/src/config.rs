//! [`BuildConfig`]: the settings of the offline build (`MotionModel::build`, [`crate::build`]),
//! with their defaults (the paper's section 5.1) and bounds. Plain data that the model's report
//! records, so it sits below the build and the model.

use hosvd_als::AlsOptions;
use kriging::KrigingConfig;
use serde::{Deserialize, Serialize};

use crate::importance::STATIC_RMS_DEG;

/// Settings of [`MotionModel::build`](crate::MotionModel::build); the defaults are the paper's section 5.1.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BuildConfig {
    /// Key levels `N`.
    pub key_levels: usize,
    /// Accuracy levels `N_A` (at least `N`); the levels between keys are truncations.
    pub accuracy_levels: usize,
    /// Ranks `(R_P, R_T, R_S)` of the first key level (clamped to the data).
    pub max_ranks: [usize; 3],
    /// Ranks of the last key level (clamped to the data).
    pub min_ranks: [usize; 3],
    /// The DOF count `max_ranks` and `min_ranks` are meant for: their `R_P` is scaled by
    /// `P / dof_rank_reference` (rounded, at least 1), so that the DOF mode keeps the same share of the
    /// joint DOF on any skeleton. The default is the paper's `P = 94`; `None` uses the ranks as given.
    pub dof_rank_reference: Option<usize>,
    /// How the DOF rows are weighted in the decomposition.
    pub row_weights: RowWeights,
    /// ALS stopping rule.
    pub als: AlsOptions,
    /// Kriging settings (universal kriging, variogram chosen by leave-one-out error by default).
    pub kriging: KrigingConfig,
    /// Poses used to measure joint importance (evenly strided over the data).
    pub importance_poses: usize,
    /// Samples at whose controls the level errors are measured (evenly strided).
    pub error_samples: usize,
    /// A rotating joint whose rotation stays within this RMS angle (degrees) about its mean over the
    /// training poses is static: it holds its mean rotation and is not counted nor evaluated
    /// ([`crate::importance::static_joints`]).
    pub static_rms_deg: f64,
    /// A varying control stays in the kriging (trend and distances) unless leaving it out lowers
    /// the RMSE of [`CONTROL_FOLDS`]-fold cross-validation by take by more than this fraction
    /// ([`kriging::select_dims_by_folds`]). With fewer than 2 takes per fold the build falls back
    /// to the leave-one-out rule: a control stays only when leaving it out raises the
    /// leave-one-out RMSE by more than this fraction ([`kriging::select_dims`]).
    pub control_margin: f64,
    /// For the leave-one-out rule only: the rise must also be beyond noise, its paired t statistic
    /// over the samples reaching this value ([`kriging::select_dims`]).
    pub control_min_t: f64,
    /// Select the controls as above (a control kept by the cross-validation whose level-0 walks
    /// fail the motion-quality thresholds is dropped again: [`crate::build`]'s quality guard);
    /// when false every non-constant control is kept (the paper).
    pub select_controls: bool,
    /// For a training set with style labels: the scale of each style's one-hot code in the
    /// kriging's standardised control space; `None` (the default) chooses it among
    /// [`STYLE_WEIGHTS`] by cross-validation by take ([`crate::build`]). Recorded in the model's
    /// style section, not in this report (so that a model without styles is unchanged).
    #[serde(skip)]
    pub style_weight: Option<f64>,
}

/// The style weights the build tries when none is given ([`BuildConfig::style_weight`]): a
/// one-hot code at weight `w` puts two styles `w sqrt(2)` apart in the standardised control space,
/// where one standard deviation of a control is 1.
pub const STYLE_WEIGHTS: [f64; 5] = [0.25, 0.5, 1.0, 2.0, 4.0];

/// Folds of the build's cross-validation of the style weight (by take; fewer when the data have
/// fewer takes).
pub const STYLE_FOLDS: usize = 5;

/// Above this many samples the build's kriging stage (control selection, style weight, variogram
/// search, quality guard) works on the value columns compressed to their leading directions
/// ([`kriging::compress_columns`], keeping all but [`VALUES_REL_ENERGY`] of the centred values'
/// squared norm): what it measures (squared distances between samples, squared prediction errors)
/// is kept to that fraction, and its products shrink from `P T` columns to a few hundred. Up to
/// it the values are used as they are (the models of the shared sets are unchanged).
pub const COMPRESS_VALUES_ABOVE: usize = 1000;

/// The share of the centred values' squared norm that [`COMPRESS_VALUES_ABOVE`]'s compression may
/// leave out.
pub const VALUES_REL_ENERGY: f64 = 1e-6;

/// Above this many samples the build's control selection (and the quality guard's leave-one-out
/// rule) decides on whole takes holding at most this many samples (`crate::build`'s
/// `selection_rows`); the kriging over the controls kept is fitted on every sample.
pub const SELECT_MAX_SAMPLES: usize = 1200;

/// Folds of the build's control selection by cross-validation by take
/// ([`BuildConfig::control_margin`]); it needs at least 2 takes per fold, else the build selects
/// by leave-one-out.
pub const CONTROL_FOLDS: usize = 5;

impl Default for BuildConfig {
    fn default() -> Self {
        BuildConfig {
            key_levels: 10,
            accuracy_levels: 28,
            max_ranks: [40, 40, 60],
            min_ranks: [7, 7, 9],
            dof_rank_reference: Some(PAPER_DOF),
            row_weights: RowWeights::JointPosition,
            als: AlsOptions::default(),
            kriging: KrigingConfig::default(),
            importance_poses: 4000,
            error_samples: 48,
            static_rms_deg: STATIC_RMS_DEG,
            control_margin: CONTROL_MARGIN,
            control_min_t: CONTROL_MIN_T,
            select_controls: true,
            style_weight: None,
        }
    }
}

/// Default [`BuildConfig::control_margin`]: a control must lower the leave-one-out error by more than
/// 1% to stay in the model.
pub const CONTROL_MARGIN: f64 = 0.01;
/// Default [`BuildConfig::control_min_t`]: the rise must be at least one standard error (about 84%
/// one-sided). The paired t of per-sample squared errors is heavy-tailed: on the embedded walker a
/// control that lowers the leave-one-out error by 36% reaches only t = 1.5 over 60 samples, while the
/// noise-only controls of the CMU set make the error worse (t < 0).
pub const CONTROL_MIN_T: f64 = 1.0;

/// Pose rows that the controls measure by construction (root ground position x and z, and the root
/// exp-map's yaw component): left out of the leave-one-out error that decides which controls carry
/// signal ([`BuildConfig::control_margin`]).
pub const CONTROL_DEFINED_ROWS: [usize; 3] = [0, 2, 4];

/// The paper's joint DOF count `P` (section 5.1), which its ranks `(40, 40, 60)` to `(7, 7, 9)` are for.
pub const PAPER_DOF: usize = 94;

/// How the DOF rows of the motion tensor are weighted in the decomposition (beyond the paper).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum RowWeights {
    /// Each row by how far it moves the joints ([`crate::importance::dof_weights`]): the squared tensor error that ALS
    /// minimises and the greedy search compares approximates the squared joint position error, so the
    /// ranks are spent on what shows. The runtime cost is nil (the weights are folded into `U_P`).
    JointPosition,
    /// No weights, as the paper: root position in metres, rotations in radians, the time increment in
    /// units of its mean.
    Unit,
}

impl BuildConfig {
    /// The rank bounds `(max, min)` of the key search for `p` DOF rows, `R_P` scaled by
    /// [`BuildConfig::dof_rank_reference`] (before clamping to the data). A product `R_P * p` past
    /// `usize::MAX` is scaled in floating point and saturates at `usize::MAX` (then clamped to the
    /// data) instead of wrapping.
    pub fn rank_bounds(&self, p: usize) -> ([usize; 3], [usize; 3]) {
        let scale = |r: usize| match self.dof_rank_reference {
            Some(reference) if reference > 0 => {
                // Exact as the integer product whenever that fits (it is then the same value).
                let product = r.checked_mul(p).map_or(r as f64 * p as f64, |rp| rp as f64);
                ((product / reference as f64).round() as usize).max(1)
            }
            _ => r,
        };
        let [mp, mt, ms] = self.max_ranks;
        let [np, nt, ns] = self.min_ranks;
        ([scale(mp), mt, ms], [scale(np), nt, ns])
    }
}

/// The fewest samples a model builds from: universal kriging over one control needs 3.
pub const MIN_SAMPLES: usize = 3;
