//! The runtime multilinear model: key tensors, accuracy levels, control space, validation and
//! storage accounting.
//!
//! A [`LodModel`] holds, for every KEY level `k`, an ordered Tucker model of the motion tensor
//! (core `Z_k`, factors `U_P`, `U_T`) together with the precomputed universal-kriging projection of
//! its sample factor `U_S` (section 3.3, eq. 8), and a table of ACCURACY levels, each a leading
//! sub-block truncation of one key (section 4.2). All arrays are plain `Vec<f32>`, column-major,
//! with their dimensions stored beside them; [`LodModel::new`] validates every shape and value.

use serde::{Deserialize, Serialize};

use crate::chain::RootMotion;
use crate::controls::{Controls, MAX_STYLES, clamp_unchecked};

/// The longest raw control vector of a walk model: the four controls and [`MAX_STYLES`] style
/// weights ([`LodModel::control_vector`]).
pub const CONTROL_VALUES: usize = Controls::COUNT + MAX_STYLES;
use crate::detail::Detail;

use crate::error::{KernelError, ModelError};

pub use crate::variogram::{Variogram, VariogramModel};

/// Rows 0..7 of the pose vector are always evaluated: root position (0..3), root exp-map (3..6)
/// and the time increment (6).
pub const ALWAYS_ROWS: usize = 7;
/// DOF rows per joint (one exponential map).
pub const ROWS_PER_JOINT: usize = 3;
/// Row of the pose vector holding the time increment to the next aligned frame (seconds).
pub const TIME_ROW: usize = 6;

/// A rank triple `(R_P, R_T, R_S)` of a Tucker model (modes joint DOF, time, samples).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Ranks {
    /// Rank of the joint-DOF mode `R_P`.
    pub p: usize,
    /// Rank of the time mode `R_T`.
    pub t: usize,
    /// Rank of the sample mode `R_S`.
    pub s: usize,
}

impl Ranks {
    /// Builds a rank triple.
    pub fn new(p: usize, t: usize, s: usize) -> Self {
        Self { p, t, s }
    }

    /// Number of core elements `R_P R_T R_S`.
    pub fn core_len(&self) -> usize {
        self.p * self.t * self.s
    }

    /// True when every rank is at most the corresponding rank of `other`.
    pub fn fits_in(&self, other: &Ranks) -> bool {
        self.p <= other.p && self.t <= other.t && self.s <= other.s
    }
}

/// One key tensor: an ordered Tucker model with its kriging projection (section 3.3).
///
/// Layouts (all column-major, first index fastest):
/// - `core`: `Z` of size `R_P x R_T x R_S`, element `(i, j, l)` at `i + R_P (j + R_T l)`;
/// - `u_p`: `U_P` of size `P x R_P`; `u_t`: `U_T` of size `T x R_T`;
/// - `projection`: `Q = U_S^T A^{-1}[:S, :]` of size `R_S x (S + 1)`, where `A = [Gamma 1; 1^T 0]`
///   is the kriging matrix (appendix A); its companion `C A^{-1}[:S, :]`, the same for every key, is
///   [`ControlSpace::projection`];
/// - `trend`: `V = U_S^T C^+` of size `R_S x (d + 1)`, so that the trend of eq. 8 is
///   `F = Z_(12) V` (`F = K C^+` with `K = Z_(12) U_S^T`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct KeyTensor {
    /// Ranks `(R_P, R_T, R_S)` of this key.
    pub ranks: Ranks,
    /// Core tensor `Z`, `R_P R_T R_S` values.
    pub core: Vec<f32>,
    /// Joint-DOF factor `U_P`, `P x R_P`.
    pub u_p: Vec<f32>,
    /// Time factor `U_T`, `T x R_T`.
    pub u_t: Vec<f32>,
    /// Kriging projection `Q = U_S^T A^{-1}[:S, :]`, `R_S x (S + 1)`.
    pub projection: Vec<f32>,
    /// Trend projection `V = U_S^T C^+`, `R_S x (d + 1)`.
    pub trend: Vec<f32>,
}

/// One accuracy level: a leading sub-block truncation of key `key` to `ranks` (section 4.2).
///
/// A key level itself is the accuracy level whose ranks equal its key's ranks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct AccuracyLevel {
    /// Index of the key tensor this level truncates.
    pub key: usize,
    /// Ranks kept, each at most the key's rank.
    pub ranks: Ranks,
}

/// Index of the control that is the character's standing height (m), the last of
/// [`crate::Controls`]' four.
pub const HEIGHT_CONTROL: usize = 3;

/// The control space of the kriging interpolation.
///
/// A raw control `c` (length `d`) is clamped to `[min, max]` per dimension and scaled as
/// `c'_k = (c_k - offset_k) * scale_k`; distances, the kriging system and the trend all use scaled
/// controls. A dimension that is constant over the data has `scale_k = 0` (it is then ignored).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ControlSpace {
    /// Variogram `gamma(h)` of the residuals (fitted offline, evaluated here).
    pub variogram: Variogram,
    /// Per-dimension offset (length `d`).
    pub offset: Vec<f32>,
    /// Per-dimension scale, finite and non-negative (length `d`).
    pub scale: Vec<f32>,
    /// Scaled sample controls, `S x d` column-major (sample `i`, dimension `k` at `i + S k`).
    pub samples: Vec<f32>,
    /// Per-dimension minimum of the raw sample controls (length `d`).
    pub min: Vec<f32>,
    /// Per-dimension maximum of the raw sample controls (length `d`).
    pub max: Vec<f32>,
    /// `C A^{-1}[:S, :]`, `(d + 1) x (S + 1)` column-major, with `C` the `(d + 1) x S` matrix of
    /// columns `[c_i; 1]` (scaled controls) and `A` the kriging matrix: `C b(c)` for the trend of
    /// eq. 8. Shared by every key (stored once, not per key).
    pub projection: Vec<f32>,
    /// What the data imply for the dimensions the kriging ignores (`scale_k = 0`), as a linear
    /// function of the raw controls: row `k` (`d + 1` values, rows stored one after another) holds
    /// `beta` with `c_k ~ beta[..d] . c + beta[d]`, the least-squares fit of the samples' `c_k` on
    /// the dimensions kept (zero weights elsewhere); a kept dimension's row is the identity. Read by
    /// [`ControlSpace::implied`]: e.g. the travel turn of a clip when turn is not a control of the
    /// model. Empty when not computed (ignored dimensions then read as their data midpoint).
    #[serde(default)]
    pub implied: Vec<f32>,
}

impl ControlSpace {
    /// Root motion of a clip built for `controls` whose first and last poses are `start` and
    /// `end` (rows 0-5: root position and exponential map): the root's ground displacement, and
    /// the travel turn, the turn control as [`ControlSpace::implied`] reads it (the pelvis's yaw
    /// change for a control space without a turn dimension). The one rule every clip source
    /// chains by ([`crate::CycleFrame::next`]). `start` and `end` need at least 6 rows; with fewer,
    /// or a hand-built control space whose vectors disagree in length, the motion is zero.
    pub fn root_motion(&self, controls: &Controls, start: &[f32], end: &[f32]) -> RootMotion {
        let (values, d) = self.values_lossy(controls);
        self.root_motion_of(&values[..d], start, end)
    }

    /// The number of styles of this control space: its dimensions after the walk's four
    /// ([`Controls::COUNT`]), 0 when it has none or is not the walk's.
    pub fn style_count(&self) -> usize {
        let d = self.scale.len();
        if (Controls::COUNT..=Controls::COUNT + MAX_STYLES).contains(&d) {
            d - Controls::COUNT
        } else {
            0
        }
    }

    /// The raw control vector of `c` in this control space, into `out[..d]` (returns `d`): the
    /// four controls, then the style weights normalised to sum 1 ([`crate::StyleMix::normalised`];
    /// the data's mix `data_mix` when they are all 0). The one place [`Controls`] become the
    /// kernel's control vector. Errors: a control space that is not the walk's (fewer than four or
    /// more than `4 + MAX_STYLES` dimensions), a style weight NaN, infinite or negative.
    pub(crate) fn values_into(
        &self,
        c: &Controls,
        data_mix: &[f32],
        out: &mut [f32; CONTROL_VALUES],
    ) -> Result<usize, KernelError> {
        let d = self.scale.len();
        if !(Controls::COUNT..=CONTROL_VALUES).contains(&d) {
            return Err(KernelError::ControlLength {
                expected: d,
                found: Controls::COUNT,
            });
        }
        out[..Controls::COUNT].copy_from_slice(&c.to_array());
        let n = d - Controls::COUNT;
        if c.style
            .normalised(n, data_mix, &mut out[Controls::COUNT..])
            .is_none()
        {
            let (index, value) = c.style.weights[..n]
                .iter()
                .enumerate()
                .find(|(_, w)| !(w.is_finite() && **w >= 0.0))
                .map_or((0, f32::NAN), |(j, w)| (j, *w));
            return Err(KernelError::Style { index, value });
        }
        Ok(d)
    }

    /// [`ControlSpace::values_into`] for the infallible readers (root motion, body scale,
    /// implied controls): a style that is not valid reads as the data's mix, a control space that
    /// is not the walk's as the four controls alone.
    fn values_lossy(&self, c: &Controls) -> ([f32; CONTROL_VALUES], usize) {
        let mut out = [0.0f32; CONTROL_VALUES];
        // The data's mix (a pass over the samples) only when the controls ask for it.
        let mix = if c.style.is_data_mix() {
            self.data_style_mix()
        } else {
            [0.0; MAX_STYLES]
        };
        match self.values_into(c, &mix, &mut out) {
            Ok(d) => (out, d),
            Err(_) => {
                let d = match self.values_into(
                    &c.with_style(crate::StyleMix::DATA_MIX),
                    &self.data_style_mix(),
                    &mut out,
                ) {
                    Ok(d) => d,
                    Err(_) => {
                        out[..Controls::COUNT].copy_from_slice(&c.to_array());
                        Controls::COUNT
                    }
                };
                (out, d)
            }
        }
    }

    /// Whether the vectors of this control space agree in length (`offset`, `min` and `max` of
    /// `scale`'s `d`, `samples` a multiple of `d`, `implied` empty or `d (d + 1)`), as
    /// [`LodModel::new`] checks them: the readers of a hand-built control space that fails this
    /// return their neutral values instead of indexing out of range.
    fn lengths_agree(&self) -> bool {
        let d = self.scale.len();
        self.offset.len() == d
            && self.min.len() == d
            && self.max.len() == d
            && (d == 0 || self.samples.len() % d == 0)
            && (self.implied.is_empty() || Some(self.implied.len()) == d.checked_mul(d + 1))
    }

    /// The data's mix of styles: each style dimension's raw sample mean (`scaled / scale + offset`,
    /// each style's share of the samples), zeros beyond [`ControlSpace::style_count`] (all zeros for
    /// a hand-built control space whose vectors disagree in length).
    pub fn data_style_mix(&self) -> [f32; MAX_STYLES] {
        let mut mix = [0.0f32; MAX_STYLES];
        let n = self.style_count();
        let d = self.scale.len();
        if n == 0 || self.samples.is_empty() || !self.lengths_agree() {
            return mix;
        }
        let s = self.samples.len() / d;
        for (j, m) in mix.iter_mut().enumerate().take(n) {
            let k = Controls::COUNT + j;
            let (offset, scale) = (f64::from(self.offset[k]), f64::from(self.scale[k]));
            if scale == 0.0 {
                *m = self.min[k];
                continue;
            }
            let sum: f64 = self.samples[s * k..s * (k + 1)]
                .iter()
                .map(|&v| f64::from(v) / scale + offset)
                .sum();
            *m = (sum / s as f64) as f32;
        }
        mix
    }

    /// [`ControlSpace::root_motion`] for a raw control vector of length `d`.
    pub(crate) fn root_motion_of(
        &self,
        controls: &[f32],
        start: &[f32],
        end: &[f32],
    ) -> RootMotion {
        use crate::kernel::{TURN_CONTROL, yaw_of_exp_map};
        if start.len() < 6 || end.len() < 6 || !self.lengths_agree() {
            return RootMotion::default();
        }
        let turn = if self.scale.len() > TURN_CONTROL && controls.len() > TURN_CONTROL {
            self.implied_of(TURN_CONTROL, controls)
        } else {
            crate::math::wrap_angle(yaw_of_exp_map(&end[3..6]) - yaw_of_exp_map(&start[3..6]))
        };
        RootMotion {
            dx: end[0] - start[0],
            dz: end[2] - start[2],
            turn,
        }
    }

    /// The body scale of a character with controls `c`: the standing height the
    /// controls give ([`ControlSpace::implied`] of [`HEIGHT_CONTROL`]: the height control clamped
    /// to the data's range, or the height the data imply from the other controls when the kriging
    /// ignores it) over `stature_m`, the rig's standing height measured the same way. The bones
    /// below the root then have the length of a performer of that height (the root's position is
    /// the pose's, kriged in metres). Exactly 1 when the data hold one height (the rig is theirs),
    /// the control space has no height dimension, `stature_m` is `None`, the ratio is not finite
    /// and positive, or a hand-built control space's vectors disagree in length.
    pub fn body_scale(&self, stature_m: Option<f32>, c: &Controls) -> f32 {
        let (values, d) = self.values_lossy(c);
        self.body_scale_of(stature_m, &values[..d])
    }

    /// [`ControlSpace::body_scale`] for a raw control vector of length `d`.
    pub(crate) fn body_scale_of(&self, stature_m: Option<f32>, c: &[f32]) -> f32 {
        let k = HEIGHT_CONTROL;
        let Some(stature) = stature_m else {
            return 1.0;
        };
        if self.scale.len() <= k
            || c.len() < self.scale.len()
            || !self.lengths_agree()
            || self.min[k] == self.max[k]
        {
            return 1.0;
        }
        let s = self.implied_of(k, c) / stature;
        if s.is_finite() && s > 0.0 { s } else { 1.0 }
    }

    /// The value of dimension `k` that the controls `c` (each clamped to the data's range here)
    /// imply: `c_k` itself for a kept dimension, else the least-squares prediction from the kept
    /// ones ([`ControlSpace::implied`] field), clamped to the data's range of `c_k`. `k` is a
    /// dimension of the control space, which is the walk's: for a `k` beyond its dimensions, or a
    /// hand-built control space whose vectors disagree in length, the result is 0.
    pub fn implied(&self, k: usize, c: &Controls) -> f32 {
        let (values, d) = self.values_lossy(c);
        self.implied_of(k, &values[..d])
    }

    /// [`ControlSpace::implied`] for a raw control vector of length `d` (any `d`; the tests of
    /// other control spaces use it, feature `reference`).
    #[cfg(feature = "reference")]
    pub fn implied_values(&self, k: usize, c: &[f32]) -> f32 {
        self.implied_of(k, c)
    }

    pub(crate) fn implied_of(&self, k: usize, c: &[f32]) -> f32 {
        let d = self.scale.len();
        if k >= d || c.len() < d || !self.lengths_agree() {
            return 0.0;
        }
        let clamp = |j: usize| clamp_unchecked(c[j], self.min[j], self.max[j]);
        if self.scale[k] > 0.0 {
            return clamp(k);
        }
        if self.implied.len() != d * (d + 1) {
            return 0.5 * (self.min[k] + self.max[k]);
        }
        let beta = &self.implied[k * (d + 1)..(k + 1) * (d + 1)];
        let v = (0..d).fold(beta[d], |acc, j| {
            if beta[j] == 0.0 {
                acc
            } else {
                acc + beta[j] * clamp(j)
            }
        });
        clamp_unchecked(v, self.min[k], self.max[k])
    }
}

/// Measured error of one accuracy level (or of one joint count) against full detail at the same
/// controls, filled by the model builder.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct LevelError {
    /// Mean joint position error after forward kinematics, in centimetres.
    pub mean_joint_cm: f32,
    /// Shell error: largest displacement of virtual vertices 3 cm from each joint, in centimetres.
    pub shell_cm: f32,
    /// Foot slide: how far a planted foot slides over one stance beyond what full detail slides
    /// (largest over the measured walks, with the runtime foot lock on, as the crowd plays them),
    /// in centimetres; 0 when the model's feet are unknown. The slide of a walk is
    /// `skate x contact share x cycle duration` of the motion-quality meter
    /// (`motion_lod::quality`), the distance a foot travels while on the floor per cycle.
    pub slide_cm: f32,
    /// Motion quality of an accuracy level (every joint, seams inertialized, feet locked): the
    /// largest pop (joint acceleration) over the walks of the quality grid, each as a multiple of
    /// the data's pop at the walk's step length (the trend of the takes' pop over their steps); 0
    /// when not measured (a joint count's entry, or a model without feet).
    pub pop_x: f32,
    /// Likewise the largest foot skate over the grid's walks as a multiple of the data's skate at
    /// the walk's step length; 0 when not measured.
    pub skate_x: f32,
    /// Likewise the largest distance between a walk's feet and the data's floor (the meter's floor
    /// offset, above or below), in centimetres; 0 when not measured.
    pub floor_cm: f32,
    /// Likewise how far the grid's walks face against their travel outside the data's own range
    /// (the meter's mean facing beyond the 2nd..98th percentile of the takes' one-cycle means), in
    /// degrees: 0 when every walk lies inside it, or when not measured.
    pub facing_out_deg: f32,
}

/// Largest pop (as a multiple of the data's at the walk's step) that an accuracy level may show on the quality
/// grid and still be used by the policies ([`LevelError::passes_quality`]): the motion-quality
/// threshold for near characters.
pub const QUALITY_POP_LIMIT: f32 = 1.25;

/// Largest foot skate (as a multiple of the data's at the walk's step) that an accuracy level may show on the
/// quality grid and still be used by the policies.
pub const QUALITY_SKATE_LIMIT: f32 = 1.5;

/// Largest floor offset (cm, above or below the data's floor) that an accuracy level may show on
/// the quality grid and still be used by the policies.
pub const QUALITY_FLOOR_CM: f32 = 1.0;

/// Largest facing against travel outside the data's range (degrees) that an accuracy level may show
/// on the quality grid and still be used by the policies: none (a walker must not crab more than
/// the data do).
pub const QUALITY_FACING_OUT_DEG: f32 = 0.0;

/// One motion-quality figure of a [`LevelError`] ([`LevelError::quality_figures`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum QualityFigure {
    /// [`LevelError::pop_x`] against [`QUALITY_POP_LIMIT`].
    Pop,
    /// [`LevelError::skate_x`] against [`QUALITY_SKATE_LIMIT`].
    Skate,
    /// [`LevelError::floor_cm`] against [`QUALITY_FLOOR_CM`].
    Floor,
    /// [`LevelError::facing_out_deg`] against [`QUALITY_FACING_OUT_DEG`].
    Facing,
}

impl LevelError {
    /// Each motion-quality figure with its measured value and its threshold, `(figure, value,
    /// limit)`: the one list [`LevelError::passes_quality`] and the reports read.
    pub fn quality_figures(&self) -> [(QualityFigure, f32, f32); 4] {
        [
            (QualityFigure::Pop, self.pop_x, QUALITY_POP_LIMIT),
            (QualityFigure::Skate, self.skate_x, QUALITY_SKATE_LIMIT),
            (QualityFigure::Floor, self.floor_cm, QUALITY_FLOOR_CM),
            (
                QualityFigure::Facing,
                self.facing_out_deg,
                QUALITY_FACING_OUT_DEG,
            ),
        ]
    }

    /// Whether the measured motion quality is within [`QUALITY_POP_LIMIT`],
    /// [`QUALITY_SKATE_LIMIT`], [`QUALITY_FLOOR_CM`] and [`QUALITY_FACING_OUT_DEG`] (true when not
    /// measured: every figure 0): the policies use an accuracy level with joints only when it
    /// passes; coarser levels that pop, skate, leave the floor or crab stay for root-only walkers.
    pub fn passes_quality(&self) -> bool {
        self.quality_figures()
            .iter()
            .all(|&(_, value, limit)| value <= limit)
    }

    /// The larger of the chosen pose error and the foot slide, in metres: what a policy projects to
    /// the screen (both must stay under its pixel budget).
    pub fn visible_m(&self, shell: bool) -> f32 {
        let pose = if shell {
            self.shell_cm
        } else {
            self.mean_joint_cm
        };
        0.01 * pose.max(self.slide_cm)
    }
}

/// Storage precision for [`LodModel::bytes`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Precision {
    /// 4 bytes per value (the runtime model and the model file).
    F32,
    /// 8 bytes per value (the analysis).
    F64,
}

impl Precision {
    /// Bytes per stored value.
    pub fn value_bytes(self) -> usize {
        match self {
            Precision::F32 => 4,
            Precision::F64 => 8,
        }
    }
}

/// Plain-data parts of a [`LodModel`], as produced by the model builder or read from a file.
///
/// Nothing here is validated; [`LodModel::new`] does that.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModelParts {
    /// Joint DOF `P` (rows of the pose vector).
    pub p: usize,
    /// Aligned frames per cycle `T`.
    pub t: usize,
    /// Motion samples `S`.
    pub s: usize,
    /// Control dimension `d`.
    pub d: usize,
    /// Rows always evaluated ([`ALWAYS_ROWS`] = 7: root and time increment).
    pub always_rows: usize,
    /// Rows per joint ([`ROWS_PER_JOINT`] = 3).
    pub rows_per_joint: usize,
    /// Key tensors, largest first.
    pub keys: Vec<KeyTensor>,
    /// Accuracy levels, most accurate (most expensive) first.
    pub levels: Vec<AccuracyLevel>,
    /// Control space (variogram, scaling, samples, bounds).
    pub controls: ControlSpace,
    /// Row [`TIME_ROW`] holds `time_scale` times the time increment in seconds (the builder scales
    /// the row so that it weighs like the other rows in the decomposition; 1 = seconds).
    pub time_scale: f64,
    /// Mean pose (length `P`), written for rows that are not evaluated.
    pub mean_pose: Vec<f32>,
    /// Measured error per accuracy level (empty, or one per level).
    pub level_errors: Vec<LevelError>,
    /// Measured error when only `j` joints are evaluated at level 0, indexed by `j`
    /// (empty, or `joints + 1` entries; the last is normally zero).
    pub joint_errors: Vec<LevelError>,
}

/// The validated runtime model (see the module documentation).
///
/// Serialises as [`ModelParts`]; deserialisation runs the same validation as [`LodModel::new`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "ModelParts", into = "ModelParts")]
pub struct LodModel {
    parts: ModelParts,
    /// Largest ranks over all keys, per mode (for preallocation).
    max_ranks: Ranks,
    /// The kriging weights' projection with the trend folded in, row-major f64, for the kernels'
    /// dot products (derived from `parts` by [`LodModel::new`]; not stored in the model file).
    folded: FoldedProjections,
    /// Each key's `U_T` row-major (`T x R_T`, row `i` at `[i R_T..(i + 1) R_T]`, then eight zeros):
    /// the two rows a pose blends are contiguous runs (derived by [`LodModel::new`]; not stored in
    /// the model file).
    time_rows: Vec<Vec<f32>>,
    /// Each key's largest `|U_T|` entry: with it [`LodModel::build_kernel`] bounds the poses a
    /// clip's `G(c)` can give (derived by [`LodModel::new`]; not stored in the model file).
    u_t_max: Vec<f32>,
    /// The data's mix of styles: the mean of the samples' raw style dimensions (dimensions
    /// `Controls::COUNT..d`), each style's share of the samples; zeros beyond the model's styles
    /// (derived by [`LodModel::new`]; not stored in the model file).
    data_style_mix: [f32; MAX_STYLES],
}

/// Each key's kriging projection with the trend folded in, row-major in f64: row `l` of key `k` is
/// `a[k][l (S + 1)..(l + 1) (S + 1)]`, with
///
/// `A = Q_top - V P_C` (`Q_top` the key's `R_S x (S + 1)` part of `Q`, `V` its trend, `P_C` the
/// control space's `(d + 1) x (S + 1)` projection),
///
/// so that the sample-mode weights of module `kernel`, `w = Q_top x + V ([c' ; 1] - P_C x)`, are
/// `w = A x + V [c' ; 1]`: `r_S` dot products over the samples instead of `r_S + d + 1`, each one
/// contiguous run of f64 (no conversion in the loop). Truncating to the first `r_S` rows of `Q_top`
/// and `V` truncates `A` the same way. The fold is exact up to the rounding of `d + 1` products per
/// entry.
#[derive(Debug, Clone, PartialEq, Default)]
pub(crate) struct FoldedProjections {
    pub a: Vec<Vec<f64>>,
}

/// `A = Q_top - V P_C` row-major (see [`FoldedProjections`]) for one key of `R_S` rows.
fn fold_projection(key: &KeyTensor, pc: &[f32], s: usize, d: usize) -> Vec<f64> {
    let r_s = key.ranks.s;
    let n = s + 1;
    let mut a = vec![0.0f64; r_s * n];
    for l in 0..r_s {
        let row = &mut a[l * n..(l + 1) * n];
        for (j, v) in row.iter_mut().enumerate() {
            let mut acc = f64::from(key.projection[l + r_s * j]);
            for m in 0..=d {
                acc -= f64::from(key.trend[l + r_s * m]) * f64::from(pc[m + (d + 1) * j]);
            }
            *v = acc;
        }
    }
    a
}

impl TryFrom<ModelParts> for LodModel {
    type Error = ModelError;
    fn try_from(parts: ModelParts) -> Result<Self, ModelError> {
        LodModel::new(parts)
    }
}

impl From<LodModel> for ModelParts {
    fn from(model: LodModel) -> Self {
        model.parts
    }
}

fn check_len(what: impl FnOnce() -> String, v: &[f32], expected: usize) -> Result<(), ModelError> {
    if v.len() != expected {
        return Err(ModelError::Length {
            what: what(),
            expected,
            found: v.len(),
        });
    }
    Ok(())
}

fn check_finite(what: impl FnOnce() -> String, v: &[f32]) -> Result<(), ModelError> {
    if let Some(index) = v.iter().position(|x| !x.is_finite()) {
        return Err(ModelError::NonFinite {
            what: what(),
            index,
        });
    }
    Ok(())
}

fn check_array(what: &str, v: &[f32], expected: usize) -> Result<(), ModelError> {
    check_len(|| what.to_string(), v, expected)?;
    check_finite(|| what.to_string(), v)
}

/// `a * b`, or an error naming `what` when the product does not fit in memory sizes (a hostile
/// file can claim any dimensions).
fn product(what: impl FnOnce() -> String, a: usize, b: usize) -> Result<usize, ModelError> {
    a.checked_mul(b)
        .ok_or_else(|| ModelError::TooLarge { what: what() })
}

fn positive(what: &str, v: usize) -> Result<(), ModelError> {
    if v == 0 {
        return Err(ModelError::ZeroSize {
            what: what.to_string(),
        });
    }
    Ok(())
}

fn rank_limit(what: String, rank: usize, limit: usize) -> Result<(), ModelError> {
    if rank == 0 {
        return Err(ModelError::ZeroSize { what });
    }
    if rank > limit {
        return Err(ModelError::Rank { what, rank, limit });
    }
    Ok(())
}

impl LodModel {
    /// Validates `parts` and builds the model.
    ///
    /// Checks: positive sizes; `6 < always_rows <= P` and `(P - always_rows)` divisible by
    /// `rows_per_joint`; every key's ranks within `(P, T, S)` and within the previous key's (keys
    /// go from the largest down), and every array's length against its dimensions (sizes whose
    /// product overflows are an error, not a panic); accuracy levels naming an existing key with
    /// ranks within it, in key order; a valid variogram ([`Variogram::validate`]); control bounds
    /// `min <= max`, scales `>= 0`; error tables of the right length and non-negative; and every
    /// value finite (the variogram is also evaluated at `h = 0` and at the sample spread).
    pub fn new(parts: ModelParts) -> Result<LodModel, ModelError> {
        let ModelParts {
            p,
            t,
            s,
            d,
            always_rows,
            rows_per_joint,
            ..
        } = parts;
        positive("P", p)?;
        positive("T", t)?;
        positive("S", s)?;
        positive("d", d)?;
        positive("rows_per_joint", rows_per_joint)?;
        if always_rows <= TIME_ROW || always_rows > p {
            return Err(ModelError::RowLayout(format!(
                "always_rows = {always_rows} must hold the time row {TIME_ROW} and be at most P = {p}"
            )));
        }
        if (p - always_rows) % rows_per_joint != 0 {
            return Err(ModelError::RowLayout(format!(
                "P - always_rows = {} is not a multiple of rows_per_joint = {rows_per_joint}",
                p - always_rows
            )));
        }
        if parts.keys.is_empty() {
            return Err(ModelError::ZeroSize {
                what: "number of key tensors".into(),
            });
        }
        if parts.levels.is_empty() {
            return Err(ModelError::ZeroSize {
                what: "number of accuracy levels".into(),
            });
        }
        let mut max_ranks = Ranks::new(0, 0, 0);
        for (k, key) in parts.keys.iter().enumerate() {
            let r = key.ranks;
            rank_limit(format!("key {k} R_P"), r.p, p)?;
            rank_limit(format!("key {k} R_T"), r.t, t)?;
            rank_limit(format!("key {k} R_S"), r.s, s)?;
            if let Some(prev) = k.checked_sub(1).map(|j| parts.keys[j].ranks) {
                // Keys go from the largest down.
                let j = k - 1;
                rank_limit(format!("key {k} R_P (keys shrink: key {j}'s)"), r.p, prev.p)?;
                rank_limit(format!("key {k} R_T (keys shrink: key {j}'s)"), r.t, prev.t)?;
                rank_limit(format!("key {k} R_S (keys shrink: key {j}'s)"), r.s, prev.s)?;
            }
            let name = |a: &'static str| move || format!("key {k} {a}");
            let core_len = product(name("core"), product(name("core"), r.p, r.t)?, r.s)?;
            check_array(&format!("key {k} core"), &key.core, core_len)?;
            check_array(
                &format!("key {k} u_p"),
                &key.u_p,
                product(name("u_p"), p, r.p)?,
            )?;
            check_array(
                &format!("key {k} u_t"),
                &key.u_t,
                product(name("u_t"), t, r.t)?,
            )?;
            check_array(
                &format!("key {k} projection"),
                &key.projection,
                product(name("projection"), r.s, s.saturating_add(1))?,
            )?;
            check_array(
                &format!("key {k} trend"),
                &key.trend,
                product(name("trend"), r.s, d.saturating_add(1))?,
            )?;
            max_ranks.p = max_ranks.p.max(r.p);
            max_ranks.t = max_ranks.t.max(r.t);
            max_ranks.s = max_ranks.s.max(r.s);
        }
        for (l, level) in parts.levels.iter().enumerate() {
            let key = parts.keys.get(level.key).ok_or(ModelError::KeyIndex {
                level: l,
                key: level.key,
                keys: parts.keys.len(),
            })?;
            rank_limit(format!("level {l} r_P"), level.ranks.p, key.ranks.p)?;
            rank_limit(format!("level {l} r_T"), level.ranks.t, key.ranks.t)?;
            rank_limit(format!("level {l} r_S"), level.ranks.s, key.ranks.s)?;
            if let Some(prev) = l.checked_sub(1).map(|m| parts.levels[m].key)
                && level.key < prev
            {
                return Err(ModelError::KeyOrder {
                    level: l,
                    key: level.key,
                    previous: prev,
                });
            }
        }
        if !(parts.time_scale.is_finite() && parts.time_scale > 0.0) {
            return Err(ModelError::NonFinite {
                what: "time_scale (must be positive)".into(),
                index: 0,
            });
        }
        check_array("mean_pose", &parts.mean_pose, p)?;
        Self::check_controls(&parts.controls, s, d)?;
        let joints = (p - always_rows) / rows_per_joint;
        Self::check_errors("level_errors", &parts.level_errors, parts.levels.len())?;
        Self::check_errors("joint_errors", &parts.joint_errors, joints + 1)?;
        let folded = FoldedProjections {
            a: parts
                .keys
                .iter()
                .map(|k| fold_projection(k, &parts.controls.projection, s, d))
                .collect(),
        };
        let time_rows = parts
            .keys
            .iter()
            .map(|k| {
                let r_t = k.ranks.t;
                // Eight entries of padding: eight-wide loads from any row's start stay inside.
                let mut rows = vec![0.0f32; t * r_t + 8];
                for (i, row) in rows[..t * r_t].chunks_exact_mut(r_t).enumerate() {
                    for (b, v) in row.iter_mut().enumerate() {
                        *v = k.u_t[i + t * b];
                    }
                }
                rows
            })
            .collect();
        let u_t_max = parts
            .keys
            .iter()
            .map(|k| k.u_t.iter().fold(0.0f32, |m, &v| m.max(v.abs())))
            .collect();
        let data_style_mix = parts.controls.data_style_mix();
        Ok(LodModel {
            parts,
            max_ranks,
            folded,
            time_rows,
            u_t_max,
            data_style_mix,
        })
    }

    fn check_controls(c: &ControlSpace, s: usize, d: usize) -> Result<(), ModelError> {
        c.variogram
            .validate()
            .map_err(|e| ModelError::Controls(format!("variogram: {e}")))?;
        check_array("controls offset", &c.offset, d)?;
        check_array("controls scale", &c.scale, d)?;
        check_array("controls min", &c.min, d)?;
        check_array("controls max", &c.max, d)?;
        let samples = product(|| "controls samples".into(), s, d)?;
        check_array("controls samples", &c.samples, samples)?;
        let projection = product(
            || "controls projection".into(),
            d.saturating_add(1),
            s.saturating_add(1),
        )?;
        check_array("controls projection", &c.projection, projection)?;
        if !c.implied.is_empty() {
            check_array("controls implied", &c.implied, d * (d + 1))?;
        }
        for k in 0..d {
            if c.scale[k] < 0.0 {
                return Err(ModelError::Controls(format!(
                    "scale of dimension {k} is negative ({})",
                    c.scale[k]
                )));
            }
            if c.min[k] > c.max[k] {
                return Err(ModelError::Controls(format!(
                    "dimension {k}: min {} exceeds max {}",
                    c.min[k], c.max[k]
                )));
            }
        }
        // Largest scaled distance between samples is at most the bounding-box diagonal.
        let mut diag2 = 0.0f64;
        for k in 0..d {
            let col = &c.samples[k * s..(k + 1) * s];
            let lo = col.iter().copied().fold(f32::INFINITY, f32::min);
            let hi = col.iter().copied().fold(f32::NEG_INFINITY, f32::max);
            diag2 += f64::from(hi - lo).powi(2);
        }
        for h in [0.0, 0.5 * diag2.sqrt(), diag2.sqrt()] {
            let g = c.variogram.eval(h);
            if !g.is_finite() {
                return Err(ModelError::Controls(format!(
                    "variogram is not finite at h = {h}"
                )));
            }
        }
        Ok(())
    }

    fn check_errors(what: &str, table: &[LevelError], expected: usize) -> Result<(), ModelError> {
        if table.is_empty() {
            return Ok(());
        }
        if table.len() != expected {
            return Err(ModelError::ErrorTable(format!(
                "{what}: expected {expected} entries, found {}",
                table.len()
            )));
        }
        for (i, e) in table.iter().enumerate() {
            for v in [
                e.mean_joint_cm,
                e.shell_cm,
                e.slide_cm,
                e.pop_x,
                e.skate_x,
                e.floor_cm,
                e.facing_out_deg,
            ] {
                if !v.is_finite() || v < 0.0 {
                    return Err(ModelError::ErrorTable(format!(
                        "{what}: entry {i} holds {v} (must be finite and >= 0)"
                    )));
                }
            }
        }
        Ok(())
    }

    /// The validated parts.
    pub fn parts(&self) -> &ModelParts {
        &self.parts
    }
    /// Returns the parts (for editing and revalidating with [`LodModel::new`]).
    pub fn into_parts(self) -> ModelParts {
        self.parts
    }
    /// Joint DOF `P`.
    pub fn p(&self) -> usize {
        self.parts.p
    }
    /// Aligned frames per cycle `T`.
    pub fn t(&self) -> usize {
        self.parts.t
    }
    /// Number of samples `S`.
    pub fn s(&self) -> usize {
        self.parts.s
    }
    /// Control dimension `d`.
    pub fn d(&self) -> usize {
        self.parts.d
    }

    /// Number of styles the model conditions on: the control dimensions after the walk's four
    /// ([`Controls::COUNT`]), each a style's one-hot code ([`crate::StyleMix`]); 0 for a model
    /// without style labels (or a control space that is not the walk's).
    pub fn style_count(&self) -> usize {
        self.parts.controls.style_count()
    }

    /// The data's mix of styles: each style's share of the training samples (the first
    /// [`LodModel::style_count`] entries; they sum to 1), what [`crate::StyleMix::DATA_MIX`] asks for.
    pub fn data_style_mix(&self) -> &[f32] {
        &self.data_style_mix[..self.style_count()]
    }

    /// The raw control vector of `controls` in this model's control space into `out[..d]`
    /// (returns `d`): the four controls of [`Controls::NAMES`], then the style weights normalised
    /// to sum 1, or the data's mix ([`LodModel::data_style_mix`]) when they are all 0. What the
    /// kernel interpolates over, and what another interpolator over the same samples (a baseline)
    /// must take to agree with it. Errors: a control space that is not a walk's
    /// ([`KernelError::ControlLength`]), a style weight NaN, infinite or negative
    /// ([`KernelError::Style`]).
    pub fn control_vector(
        &self,
        controls: &Controls,
        out: &mut [f32; CONTROL_VALUES],
    ) -> Result<usize, KernelError> {
        self.control_values(controls, out)
    }

    /// [`LodModel::control_vector`]: [`ControlSpace::values_into`] with the cached data mix.
    pub(crate) fn control_values(
        &self,
        controls: &Controls,
        out: &mut [f32; CONTROL_VALUES],
    ) -> Result<usize, KernelError> {
        self.parts
            .controls
            .values_into(controls, &self.data_style_mix, out)
    }
    /// Rows always evaluated (root and time increment).
    pub fn always_rows(&self) -> usize {
        self.parts.always_rows
    }
    /// Rows per joint.
    pub fn rows_per_joint(&self) -> usize {
        self.parts.rows_per_joint
    }
    /// Number of joints `(P - always_rows) / rows_per_joint`.
    pub fn joints(&self) -> usize {
        (self.parts.p - self.parts.always_rows) / self.parts.rows_per_joint
    }
    /// Full detail: the most accurate level and every joint.
    pub fn full_detail(&self) -> Detail {
        Detail::new(0, self.joints())
    }

    /// Root only: rows `0..7` (root position, root orientation, time increment) at the smallest
    /// (last) accuracy level, the cheapest clip; every other row takes the mean pose.
    pub fn root_only(&self) -> Detail {
        Detail::new(self.levels().len() - 1, 0)
    }

    /// The detail a clip source evaluates for `detail`: a root-only detail (no joints) at the
    /// smallest level, [`LodModel::root_only`], whatever level the policy gave it (every root-only
    /// clip is then the same, and the cheapest); any other detail as it is.
    pub fn evaluated(&self, detail: Detail) -> Detail {
        if detail.is_root_only() {
            self.root_only()
        } else {
            detail
        }
    }

    /// `detail`, checked to exist in this model ([`Detail::fits`]): its level among the accuracy
    /// levels and its joints at most [`LodModel::joints`].
    pub fn check_detail(&self, detail: Detail) -> Result<Detail, KernelError> {
        if detail.accuracy >= self.levels().len() {
            return Err(KernelError::Level {
                level: detail.accuracy,
                levels: self.levels().len(),
            });
        }
        if detail.active_joints > self.joints() {
            return Err(KernelError::Joints {
                joints: detail.active_joints,
                max: self.joints(),
            });
        }
        Ok(detail)
    }

    /// Evaluated rows `P' = always_rows + rows_per_joint * active_joints`.
    pub fn active_rows(&self, active_joints: usize) -> usize {
        self.parts.always_rows + self.parts.rows_per_joint * active_joints.min(self.joints())
    }
    /// `G(c)` entries a kernel built at `detail` holds: `P' x r_T` of the detail it evaluates
    /// ([`LodModel::evaluated`]; `P'` the rows of its joints), or `P x max R_T` for an accuracy
    /// level the model does not have. What a [`crate::ClipKernel::compact_holding`] kernel must
    /// hold for that build not to allocate.
    pub fn kernel_entries(&self, detail: Detail) -> usize {
        let d = self.evaluated(detail);
        match self.levels().get(d.accuracy) {
            Some(level) => self.active_rows(d.active_joints) * level.ranks.t,
            None => self.p() * self.max_ranks().t,
        }
    }
    /// Key tensors, largest first.
    pub fn keys(&self) -> &[KeyTensor] {
        &self.parts.keys
    }
    /// Accuracy levels, most accurate first.
    pub fn levels(&self) -> &[AccuracyLevel] {
        &self.parts.levels
    }
    /// The control space.
    pub fn controls(&self) -> &ControlSpace {
        &self.parts.controls
    }
    /// Mean pose (length `P`).
    pub fn mean_pose(&self) -> &[f32] {
        &self.parts.mean_pose
    }
    /// Whether the level-of-detail policies give accuracy level `level` to characters with
    /// joints: level 0 always; a coarser level when its measured motion quality passes
    /// ([`LevelError::passes_quality`], true when not measured); never a level the model lacks.
    /// The others serve only root-only characters.
    pub fn level_serves_joints(&self, level: usize) -> bool {
        level == 0
            || (level < self.parts.levels.len()
                && self
                    .parts
                    .level_errors
                    .get(level)
                    .is_none_or(LevelError::passes_quality))
    }
    /// Measured error per accuracy level (empty if not measured).
    pub fn level_errors(&self) -> &[LevelError] {
        &self.parts.level_errors
    }
    /// Measured error per active joint count (empty if not measured).
    pub fn joint_errors(&self) -> &[LevelError] {
        &self.parts.joint_errors
    }
    /// Replaces the per-level and per-joint-count error tables (validated as in [`LodModel::new`]).
    pub fn set_errors(
        &mut self,
        level_errors: Vec<LevelError>,
        joint_errors: Vec<LevelError>,
    ) -> Result<(), ModelError> {
        Self::check_errors("level_errors", &level_errors, self.parts.levels.len())?;
        Self::check_errors("joint_errors", &joint_errors, self.joints() + 1)?;
        self.parts.level_errors = level_errors;
        self.parts.joint_errors = joint_errors;
        Ok(())
    }
    /// The kriging projections with the trend folded in (derived by [`LodModel::new`]).
    pub(crate) fn folded(&self) -> &FoldedProjections {
        &self.folded
    }

    /// `U_T` of key `k` row-major, `T x R_T`, then eight zeros (derived by [`LodModel::new`]).
    pub(crate) fn time_rows(&self, k: usize) -> &[f32] {
        &self.time_rows[k]
    }
    /// Key `k`'s largest `|U_T|` entry.
    pub(crate) fn u_t_max(&self, k: usize) -> f32 {
        self.u_t_max[k]
    }

    /// Largest ranks over all keys, per mode.
    pub fn max_ranks(&self) -> Ranks {
        self.max_ranks
    }

    /// Multiply-adds to build a clip kernel at `detail` for its `P'` evaluated rows:
    /// `(r_S + d + 1)(S + 1) + r_S (d + 1)` for the kriging weights, `r_P r_T r_S` for `K(c)`,
    /// `P' r_P r_T` for `G(c)` and `T r_T` for the time table; `None` for a level the model lacks.
    pub fn kernel_cost(&self, detail: Detail) -> Option<usize> {
        self.kernel_cost_rows(detail.accuracy, self.active_rows(detail.active_joints))
    }

    /// Multiply-adds per evaluated pose at `detail`: `P' r_T` for its `P'` evaluated rows; `None`
    /// for a level the model lacks.
    pub fn pose_cost(&self, detail: Detail) -> Option<usize> {
        self.pose_cost_rows(detail.accuracy, self.active_rows(detail.active_joints))
    }

    /// Multiply-adds to build a clip kernel at `level` for `rows` evaluated rows:
    /// `(r_S + d + 1)(S + 1) + r_S (d + 1)` for the kriging weights, `r_P r_T r_S` for `K(c)`,
    /// `rows r_P r_T` for `G(c)` and `T r_T` for the time table; `None` for a bad level.
    pub(crate) fn kernel_cost_rows(&self, level: usize, rows: usize) -> Option<usize> {
        let lv = self.parts.levels.get(level)?;
        let r = lv.ranks;
        let (s, d, t) = (self.parts.s, self.parts.d, self.parts.t);
        Some((r.s + d + 1) * (s + 1) + r.s * (d + 1) + r.core_len() + rows * r.p * r.t + t * r.t)
    }

    /// Multiply-adds per evaluated pose at `level` for `rows` rows: `rows r_T`.
    pub(crate) fn pose_cost_rows(&self, level: usize, rows: usize) -> Option<usize> {
        Some(self.parts.levels.get(level)?.ranks.t * rows)
    }

    /// Bytes needed to store the model at `precision`: every key tensor (core, `U_P`, `U_T`,
    /// projection, trend), the control space (samples, offset, scale, bounds, kriging rows, implied
    /// controls) and the mean pose. Accuracy levels and error tables are a few numbers each and are
    /// counted too, the error tables at the size a built model holds (3 values per accuracy level and
    /// per joint count) whether or not they are measured yet, so that a model counts the same before
    /// and after its errors are measured (`eval` and `info` agree).
    pub fn bytes(&self, precision: Precision) -> usize {
        let b = precision.value_bytes();
        let keys: usize = (0..self.parts.keys.len())
            .map(|k| self.key_bytes(k, precision))
            .sum();
        let c = &self.parts.controls;
        let controls = (c.samples.len()
            + c.offset.len()
            + c.scale.len()
            + c.min.len()
            + c.max.len()
            + c.projection.len()
            + c.implied.len())
            * b;
        let tables = self.parts.levels.len() * 4 * std::mem::size_of::<u32>()
            + (self.parts.levels.len() + self.joints() + 1) * 3 * b;
        keys + controls + self.parts.mean_pose.len() * b + tables
    }

    /// Bytes of key tensor `k` at `precision` (0 for a bad index).
    pub fn key_bytes(&self, k: usize, precision: Precision) -> usize {
        self.parts.keys.get(k).map_or(0, |key| {
            (key.core.len()
                + key.u_p.len()
                + key.u_t.len()
                + key.projection.len()
                + key.trend.len())
                * precision.value_bytes()
        })
    }
}
