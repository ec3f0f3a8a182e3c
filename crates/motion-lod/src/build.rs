//! `MotionModel::build`: from aligned gait cycles to the runtime multilinear model (sections 3-4).
//!
//! Steps, in order:
//! 1. leave out the joints that are static over the data, measure the visual importance of the others
//!    ([`crate::importance`]) and reorder the DOF rows (root and time increment first, then joints by
//!    decreasing importance, legs before arms and left/right counterparts adjacent);
//! 2. scale the time-increment row into frame units (so that it weighs like the other rows in the
//!    decomposition) and set the layout's rest rotations to the data's mean;
//! 3. the greedy key-level search with ALS (section 4.2) and the hybrid accuracy levels between keys;
//! 4. universal kriging of the samples over the controls (eq. 8, appendix A), variogram chosen by
//!    leave-one-out error; every varying control is kept unless leaving it out lowers the error of
//!    [`CONTROL_FOLDS`]-fold cross-validation by take by more than [`BuildConfig::control_margin`]
//!    ([`kriging::select_dims_by_folds`]; with fewer than 2 takes per fold, the leave-one-out rule
//!    of [`kriging::select_dims`]); one kriging system serves every level;
//! 5. per key level the runtime parts: `Q = [U_S^T; C] A^{-1}[:S, :]` and `V = U_S^T C^+`;
//! 6. the measured error of every accuracy level and every joint count ([`crate::metrics`]);
//! 7. the quality guard: when level 0 fails the motion-quality thresholds
//!    ([`LevelError::passes_quality`]) and the cross-validation kept controls that the
//!    leave-one-out rule drops, the model is rebuilt without them (each alone first, the one whose
//!    loss costs the cross-validation least first, then together) and the first whose level-0 walks
//!    pass is kept; its dropped controls read [`DimDecision::Overruled`] and the report keeps the
//!    level-0 quality that failed ([`crate::BuildReport::overruled_quality`]). Nothing of this runs
//!    when level 0 passes.
//!
//! Large sets (issue 35: ten thousand cycles in under two minutes on two cores, under 4 GB). Above
//! [`COMPRESS_VALUES_ABOVE`] samples the kriging stage works on the value columns compressed to
//! their leading directions (each group, scored and not, centred; [`VALUES_REL_ENERGY`] of its
//! squared norm left out), and above [`SELECT_MAX_SAMPLES`] the control selection and the quality
//! guard's leave-one-out rule decide on whole takes holding at most that many samples; the kriging
//! over the controls kept is fitted on every sample (its variogram search ranks on
//! [`kriging::search::SEARCH_SAMPLES`] of them). Cross-validation predicts each held-out fold with
//! one matrix product ([`kriging::Kriging::predict_rows`]). Up to those sizes nothing changes:
//! the shared sets' models are the same bytes.

use faer::Mat;
use hosvd_als::{AlsOptions, AlsReport, KeyLevels, KeySearchConfig, Tucker, hybrid_levels};
use kriging::{
    DimDecision, DimSelection, Kriging, KrigingConfig, SelectRule, select_dims,
    select_dims_by_folds,
};
use lod_policy::{
    AccuracyLevel, Controls, Detail, LevelError, LodModel, ModelParts, Ranks, RuntimeModel,
};
use motion_io::PoseLayout;
use rayon::prelude::*;
use tensor_ops::Tensor3;

pub use crate::config::{
    BuildConfig, COMPRESS_VALUES_ABOVE, CONTROL_DEFINED_ROWS, CONTROL_FOLDS, CONTROL_MARGIN,
    CONTROL_MIN_T, MIN_SAMPLES, PAPER_DOF, RowWeights, SELECT_MAX_SAMPLES, STYLE_FOLDS,
    STYLE_WEIGHTS, VALUES_REL_ENERGY,
};
pub use crate::dataset::TrainingSet;
use crate::importance::{
    JointImportance, LimbOrder, StaticJoint, dof_weights, joint_importance, limb_order,
    static_joints,
};
use crate::metrics::ErrorMeter;
use crate::model::{BuildReport, CONTROL_NAMES, KeyReport, MotionModel, TIME_ROW};
use crate::progress::Progress;
use crate::projection::{
    KeyFactors, VariogramConversionError, control_space, key_tensor, runtime_variogram,
    with_projection,
};
use crate::style::{StyleLabels, WeightTrial};

/// Why a model could not be built.
#[derive(Debug, thiserror::Error)]
pub enum BuildError {
    /// The training set is inconsistent or too small.
    #[error("training data: {0}")]
    Data(String),
    /// The decomposition failed.
    #[error("tensor decomposition: {0}")]
    Decomposition(#[from] hosvd_als::HosvdError),
    /// The kriging system could not be set up.
    #[error("kriging over the controls: {0}")]
    Kriging(#[from] kriging::KrigingError),
    /// The runtime model rejected the parts.
    #[error("runtime model: {0}")]
    Model(#[from] lod_policy::ModelError),
    /// The runtime model's parts do not fit together (a bug of the build).
    #[error("runtime model: {0}")]
    Invalid(#[from] lod_policy::InvalidModel),
    /// The fitted variogram cannot go into the runtime model.
    #[error("runtime model: {0}")]
    Variogram(#[from] VariogramConversionError),
    /// Evaluating the model while measuring its errors failed.
    #[error("measuring level errors: {0}")]
    Kernel(#[from] lod_policy::KernelError),
    /// The layout could not be reordered.
    #[error("pose layout: {0}")]
    Layout(#[from] motion_io::PoseError),
}

impl TrainingSet {
    /// Checks shapes and values: `P` matches the layout, one control row, one source and (with
    /// styles) one style label per sample, every label naming one of the distinct style names,
    /// finite controls and tensor values.
    ///
    /// # Errors
    /// [`BuildError::Data`] naming the first fault: a count that does not match `S`, a style index
    /// out of range or a repeated style name, the sample whose controls are not finite, or the DOF
    /// row, frame and sample of the first non-finite tensor value; and fewer than [`MIN_SAMPLES`]
    /// samples.
    pub fn validate(&self) -> Result<(), BuildError> {
        let [p, t, s] = self.tensor.dims();
        if p != self.layout.dof() {
            return Err(BuildError::Data(format!(
                "tensor has {p} DOF rows, the pose layout {}",
                self.layout.dof()
            )));
        }
        if t < 2 {
            return Err(BuildError::Data(format!(
                "{t} aligned frames: at least 2 are needed"
            )));
        }
        if self.controls.len() != s {
            return Err(BuildError::Data(format!(
                "{} control rows for {s} samples",
                self.controls.len()
            )));
        }
        if let Some(i) = self
            .controls
            .iter()
            .position(|c| c.iter().any(|v| !v.is_finite()))
        {
            return Err(BuildError::Data(format!(
                "controls of sample {i} are not finite: {:?}",
                self.controls[i]
            )));
        }
        if self.sources.len() != s {
            return Err(BuildError::Data(format!(
                "{} sources for {s} samples (one per sample)",
                self.sources.len()
            )));
        }
        if let Some(labels) = &self.styles {
            if labels.of_sample.len() != s {
                return Err(BuildError::Data(format!(
                    "style labels for {} samples, the tensor has {s}",
                    labels.of_sample.len()
                )));
            }
            if labels.names.is_empty() {
                return Err(BuildError::Data("style labels without style names".into()));
            }
            if let Some(i) =
                (1..labels.names.len()).find(|&i| labels.names[..i].contains(&labels.names[i]))
            {
                return Err(BuildError::Data(format!(
                    "style name {:?} appears twice (style {i})",
                    labels.names[i]
                )));
            }
            if let Some((i, &j)) = labels
                .of_sample
                .iter()
                .enumerate()
                .find(|(_, j)| **j >= labels.names.len())
            {
                return Err(BuildError::Data(format!(
                    "sample {i} has style {j}, but there are only {} style names",
                    labels.names.len()
                )));
            }
        }
        if let Some(i) = self.tensor.as_slice().iter().position(|v| !v.is_finite()) {
            let (row, frame, sample) = (i % p, (i / p) % t, i / (p * t));
            return Err(BuildError::Data(format!(
                "tensor value {} at DOF row {row}, frame {frame}, sample {sample} ({}) is not finite",
                self.tensor.as_slice()[i],
                self.sources[sample]
            )));
        }
        if s < MIN_SAMPLES {
            return Err(BuildError::Data(format!(
                "{s} samples: a model needs at least {MIN_SAMPLES} cycles (universal kriging over one \
                 control needs 3)"
            )));
        }
        Ok(())
    }

    /// A deterministic random subset of `n` samples (all when `n >= S`), in their original order.
    pub fn subset(&self, n: usize, seed: u64) -> TrainingSet {
        let s = self.tensor.dims()[2];
        if n >= s {
            return self.clone();
        }
        // Partial Fisher-Yates with splitmix64: the same (n, seed) always picks the same samples.
        let mut idx: Vec<usize> = (0..s).collect();
        let mut rng = lod_policy::SplitMix64::new(seed);
        for i in 0..n {
            let j = i + (rng.next_u64() % (s - i) as u64) as usize;
            idx.swap(i, j);
        }
        let mut pick = idx[..n].to_vec();
        pick.sort_unstable();
        self.select(&pick)
    }

    /// The samples at `indices` (each below `S`), in that order.
    ///
    /// # Panics
    /// When an index is out of range (a programming error: callers pass indices of this set).
    pub fn select(&self, indices: &[usize]) -> TrainingSet {
        let [p, t, _] = self.tensor.dims();
        let n = indices.len();
        let mut data = Vec::with_capacity(p * t * n);
        for &k in indices {
            data.extend_from_slice(self.tensor.sample(k));
        }
        TrainingSet {
            layout: self.layout.clone(),
            tensor: Tensor3::from_vec([p, t, n], data).expect("samples of a valid tensor"),
            controls: indices.iter().map(|&k| self.controls[k]).collect(),
            sources: indices.iter().map(|&k| self.sources[k].clone()).collect(),
            quality: self.quality.clone(),
            styles: self.styles.as_ref().map(|l| l.select(indices)),
            style_spec: self.style_spec.clone(),
            take_quality: self.take_quality.clone(),
        }
    }
}

/// Fits the kriging settings to the number of samples. Universal kriging over `d` varying controls
/// needs `d + 2` samples, and its leave-one-out (variogram choice, control selection, evaluation)
/// one more; with fewer samples the controls that vary least (standard deviation relative to the
/// mean step length for `dx`, `dz` and `height`, in radians for `turn`) are left out, down to one.
/// With `MIN_SAMPLES` samples (no leave-one-out possible) the variogram is chosen by its fit to the
/// empirical variogram. Returns the settings and the controls left out (sorted).
fn fit_to_sample_count(
    params: &Mat<f64>,
    config: &KrigingConfig,
) -> Result<(KrigingConfig, Vec<usize>), BuildError> {
    let s = params.nrows();
    let base = kriging::ParamScaling::from_choice(&config.scaling, params.as_ref())?;
    let varying: Vec<usize> = (0..base.dims()).filter(|&k| base.scale[k] != 0.0).collect();
    let allowed = s.saturating_sub(3).max(1);
    let mut out = config.clone();
    if s <= MIN_SAMPLES && matches!(out.model, kriging::ModelChoice::Auto(_)) {
        out.model = kriging::ModelChoice::Auto(kriging::Selection::BestFit);
    }
    if varying.len() <= allowed || config.method != kriging::Method::Regression {
        return Ok((out, Vec::new()));
    }
    let mean = |k: usize| params.col(k).iter().sum::<f64>() / s as f64;
    let std = |k: usize| {
        let m = mean(k);
        (params.col(k).iter().map(|v| (v - m).powi(2)).sum::<f64>() / s as f64).sqrt()
    };
    let step = mean(1).abs().max(1e-9);
    let spread = |k: usize| if k == 2 { std(k) } else { std(k) / step };
    let mut order = varying.clone();
    // Most varying first; ties by index, so the choice is deterministic.
    order.sort_by(|&a, &b| spread(b).total_cmp(&spread(a)).then(a.cmp(&b)));
    let mut dropped: Vec<usize> = order[allowed..].to_vec();
    dropped.sort_unstable();
    let mut scaling = base;
    for &k in &dropped {
        scaling.scale[k] = 0.0;
    }
    out.scaling = kriging::ScalingChoice::Given(scaling);
    Ok((out, dropped))
}

/// The style weight and the trials that chose it ([`Analysis::style_weight`]).
type StyleWeight = (f64, Vec<WeightTrial>);

/// The inputs of the kriging over the controls (step 4), shared by the control selection and the
/// quality guard.
struct ControlFit {
    /// The controls, `S x 4`.
    params: Mat<f64>,
    /// The samples with their rows weighted as in the decomposition, `S x PT`.
    values: Mat<f64>,
    /// The value columns the leave-one-out rule scores (not the rows the controls define).
    scored: Vec<bool>,
    /// The kriging settings for the sample count ([`fit_to_sample_count`]).
    kriging_config: KrigingConfig,
    /// Controls left out for the sample count.
    dropped_for_samples: Vec<usize>,
}

impl ControlFit {
    fn new(
        set: &TrainingSet,
        weighted: &Tensor3,
        config: &BuildConfig,
    ) -> Result<ControlFit, BuildError> {
        let [p, t, s] = weighted.dims();
        let params = control_matrix(&set.controls);
        // The rows weighted as in the decomposition: the variogram is chosen on what shows.
        let values = Mat::from_fn(s, p * t, |i, j| weighted.sample(i)[j]);
        // The controls measure the root's ground path and heading over the cycle: they predict those
        // rows by construction. The leave-one-out rule judges a control on the rest (pose, height,
        // lean, timing).
        let scored: Vec<bool> = (0..p * t)
            .map(|j| !CONTROL_DEFINED_ROWS.contains(&(j % p)))
            .collect();
        let (kriging_config, dropped_for_samples) = fit_to_sample_count(&params, &config.kriging)?;
        let (values, scored) = if s > COMPRESS_VALUES_ABOVE {
            compressed_values(values.as_ref(), &scored)
        } else {
            (values, scored)
        };
        Ok(ControlFit {
            params,
            values,
            scored,
            kriging_config,
            dropped_for_samples,
        })
    }

    /// The kriging over the controls and what the selection decided per control: by
    /// cross-validation by take when the data have at least 2 takes per fold ([`control_folds`]),
    /// else by leave-one-out; every varying control with `config.select_controls` off.
    fn select(
        &self,
        set: &TrainingSet,
        config: &BuildConfig,
    ) -> Result<(Kriging, Vec<DimDecision>), BuildError> {
        let Some(rows) = selection_rows(&set.sources) else {
            return self.select_on(&set.sources, config);
        };
        // Decided on whole takes, then the kriging over the controls kept fitted on every sample.
        let sources: Vec<String> = rows.iter().map(|&i| set.sources[i].clone()).collect();
        let (_, decisions) = self.rows(&rows).select_on(&sources, config)?;
        Ok((self.fit_kept(&decisions)?, decisions))
    }

    /// This fit restricted to the samples `rows` (same settings and scored columns).
    fn rows(&self, rows: &[usize]) -> ControlFit {
        ControlFit {
            params: select_rows(self.params.as_ref(), rows),
            values: select_rows(self.values.as_ref(), rows),
            scored: self.scored.clone(),
            kriging_config: self.kriging_config.clone(),
            dropped_for_samples: self.dropped_for_samples.clone(),
        }
    }

    /// [`ControlFit::select`] on every sample of this fit (`sources` one per sample).
    fn select_on(
        &self,
        sources: &[String],
        config: &BuildConfig,
    ) -> Result<(Kriging, Vec<DimDecision>), BuildError> {
        let s = self.params.nrows();
        // Leave-one-out needs a sample more than the fewest a model builds from.
        let select = config.select_controls && s > MIN_SAMPLES;
        let (kriging, mut decisions) = match control_folds(sources) {
            Some(fold) if select => {
                let selection = select_dims_by_folds(
                    self.params.as_ref(),
                    self.values.as_ref(),
                    &self.kriging_config,
                    config.control_margin,
                    &fold,
                    None,
                )?;
                (selection.kriging, selection.decisions)
            }
            None if select => {
                let selection = self.select_by_loo(config)?;
                (selection.kriging, selection.decisions)
            }
            _ => {
                let kriging = Kriging::fit(
                    self.params.as_ref(),
                    self.values.as_ref(),
                    &self.kriging_config,
                )?;
                let decisions = (0..CONTROL_NAMES.len())
                    .map(|k| {
                        if kriging.dropped_dims().contains(&k) {
                            DimDecision::Constant
                        } else {
                            DimDecision::Kept {
                                loo_with: f64::NAN,
                                loo_without: f64::NAN,
                                t: f64::NAN,
                            }
                        }
                    })
                    .collect();
                (kriging, decisions)
            }
        };
        for &k in &self.dropped_for_samples {
            decisions[k] = DimDecision::Constant;
        }
        Ok((kriging, decisions))
    }

    /// The leave-one-out rule's decisions ([`ControlFit::select_by_loo`]), on the whole takes of
    /// [`selection_rows`] when there are more samples than [`SELECT_MAX_SAMPLES`].
    fn loo_decisions(
        &self,
        sources: &[String],
        config: &BuildConfig,
    ) -> Result<Vec<DimDecision>, BuildError> {
        Ok(match selection_rows(sources) {
            Some(rows) => self.rows(&rows).select_by_loo(config)?.decisions,
            None => self.select_by_loo(config)?.decisions,
        })
    }

    /// The leave-one-out rule ([`kriging::select_dims`] over the scored columns).
    fn select_by_loo(&self, config: &BuildConfig) -> Result<DimSelection, BuildError> {
        Ok(select_dims(
            self.params.as_ref(),
            self.values.as_ref(),
            &self.kriging_config,
            SelectRule {
                margin: config.control_margin,
                min_t: config.control_min_t,
            },
            Some(&self.scored),
        )?)
    }

    /// `kriging` (over the controls kept) with the style code beside them for a set with styles
    /// ([`style_kriging`]), and the style weight with its trials; `kriging` itself without styles.
    fn with_styles(
        &self,
        kriging: Kriging,
        set: &TrainingSet,
        config: &BuildConfig,
        progress: &dyn Progress,
    ) -> Result<(Kriging, Option<StyleWeight>), BuildError> {
        let Some(labels) = &set.styles else {
            return Ok((kriging, None));
        };
        progress.stage("style weight (cross-validation by take)", 1);
        let (kriging, weight, trials) = style_kriging(
            &kriging,
            set,
            labels,
            self.values.as_ref(),
            &self.scored,
            config,
            &self.kriging_config,
        )?;
        progress.inc(1);
        Ok((kriging, Some((weight, trials))))
    }

    /// The kriging over the controls that `decisions` keep, its variogram chosen anew.
    fn fit_kept(&self, decisions: &[DimDecision]) -> Result<Kriging, BuildError> {
        let mut scaling =
            kriging::ParamScaling::from_choice(&self.kriging_config.scaling, self.params.as_ref())?;
        for (k, d) in decisions.iter().enumerate() {
            if d.dropped() {
                scaling.scale[k] = 0.0;
            }
        }
        let cfg = KrigingConfig {
            scaling: kriging::ScalingChoice::Given(scaling),
            ..self.kriging_config.clone()
        };
        Ok(Kriging::fit(
            self.params.as_ref(),
            self.values.as_ref(),
            &cfg,
        )?)
    }
}

/// The fold of every sample for the control selection by [`CONTROL_FOLDS`]-fold cross-validation
/// by take (`crate::folds::fold_of_samples`), or `None` when the data have fewer than 2 takes per
/// fold (the build then selects by leave-one-out).
pub fn control_folds(sources: &[String]) -> Option<Vec<usize>> {
    if crate::folds::distinct_takes(sources).len() < 2 * CONTROL_FOLDS {
        return None;
    }
    crate::folds::fold_of_samples(sources, CONTROL_FOLDS, crate::folds::FoldBy::Take).ok()
}

/// The values (S x D) with their scored and unscored columns each centred and compressed
/// ([`kriging::compress_columns`] at [`VALUES_REL_ENERGY`]), and the mask of the compressed
/// columns: the scored group first. Kriging is blind to a column's mean (its weights sum to one)
/// and to an orthogonal change of columns within a group, so every variogram, leave-one-out and
/// cross-validated error over either group is kept to that fraction of its squared norm.
fn compressed_values(values: faer::MatRef<'_, f64>, scored: &[bool]) -> (Mat<f64>, Vec<bool>) {
    let s = values.nrows();
    let group = |want: bool| -> Option<Mat<f64>> {
        let cols: Vec<usize> = (0..values.ncols()).filter(|&j| scored[j] == want).collect();
        if cols.is_empty() {
            return None;
        }
        let means: Vec<f64> = cols
            .iter()
            .map(|&j| values.col(j).iter().sum::<f64>() / s as f64)
            .collect();
        let centred = Mat::from_fn(s, cols.len(), |i, k| values[(i, cols[k])] - means[k]);
        Some(kriging::compress_columns(
            centred.as_ref(),
            VALUES_REL_ENERGY,
        ))
    };
    let (a, b) = (group(true), group(false));
    let (ka, kb) = (
        a.as_ref().map_or(0, |m| m.ncols()),
        b.as_ref().map_or(0, |m| m.ncols()),
    );
    let out = Mat::from_fn(s, ka + kb, |i, j| match (&a, &b) {
        (Some(a), _) if j < ka => a[(i, j)],
        (_, Some(b)) => b[(i, j - ka)],
        _ => 0.0,
    });
    let mask = (0..ka + kb).map(|j| j < ka).collect();
    (out, mask)
}

/// The samples the control selection decides on when there are more than
/// [`SELECT_MAX_SAMPLES`]: whole takes (in name order, every `k`-th, `k` the fewest that brings
/// the count to at most [`SELECT_MAX_SAMPLES`]), so that its refits of every fold and trial cost
/// what they cost for that many samples whatever the data's size; `None` (every sample) up to it.
/// The kriging over the controls kept is then fitted on every sample.
fn selection_rows(sources: &[String]) -> Option<Vec<usize>> {
    if sources.len() <= SELECT_MAX_SAMPLES {
        return None;
    }
    let takes = crate::folds::distinct_takes(sources);
    let take_of = |i: usize| {
        takes
            .binary_search(&crate::folds::take_of(&sources[i]))
            .unwrap_or(0)
    };
    let of: Vec<usize> = (0..sources.len()).map(take_of).collect();
    (2..=takes.len()).find_map(|k| {
        let rows: Vec<usize> = (0..sources.len()).filter(|&i| of[i] % k == 0).collect();
        (rows.len() <= SELECT_MAX_SAMPLES).then_some(rows)
    })
}

/// Controls as an `S x 4` matrix, one row per sample (the controls alone, without styles).
fn control_matrix(controls: &[[f64; 4]]) -> Mat<f64> {
    crate::dataset::control_matrix(controls, None)
}

/// The kriging over the controls kept (`base`, fitted by the control selection) and the style
/// code: the same scaling of the controls, each style's one-hot column scaled by the weight `w`,
/// and a variogram chosen anew ([`KrigingConfig::model`] of `kriging_config`). The weight is
/// [`BuildConfig::style_weight`], or the one of [`STYLE_WEIGHTS`] whose universal kriging predicts
/// held-out takes best: [`STYLE_FOLDS`] folds by take, each fold's cycles predicted by a kriging
/// refitted on the others (with the variogram chosen on every sample at that weight), the error
/// the root mean square over the held-out cycles of the scored value columns (ties: the smaller
/// weight). Returns the kriging, the weight and the trials.
fn style_kriging(
    base: &Kriging,
    set: &TrainingSet,
    labels: &StyleLabels,
    values: faer::MatRef<'_, f64>,
    scored: &[bool],
    config: &BuildConfig,
    kriging_config: &KrigingConfig,
) -> Result<(Kriging, f64, Vec<WeightTrial>), BuildError> {
    let params = crate::dataset::control_matrix(&set.controls, Some(labels));
    let n = labels.len();
    let scaling = |w: f64| {
        let mut sc = base.scaling().clone();
        sc.offset.extend(std::iter::repeat_n(0.0, n));
        sc.scale.extend(std::iter::repeat_n(w, n));
        kriging::ScalingChoice::Given(sc)
    };
    let fit_config = |w: f64| KrigingConfig {
        scaling: scaling(w),
        ..kriging_config.clone()
    };
    if let Some(w) = config.style_weight {
        if !(w.is_finite() && w > 0.0) {
            return Err(BuildError::Data(format!(
                "style weight {w}: it must be finite and positive"
            )));
        }
        let kriging = Kriging::fit(params.as_ref(), values, &fit_config(w))?;
        return Ok((kriging, w, Vec::new()));
    }
    let takes = crate::folds::distinct_takes(&set.sources);
    let folds = STYLE_FOLDS.min(takes.len());
    if folds < 2 {
        return Err(BuildError::Data(format!(
            "{} take(s): choosing the style weight needs at least 2 (give the weight)",
            takes.len()
        )));
    }
    let fold = crate::folds::fold_of_samples(&set.sources, folds, crate::folds::FoldBy::Take)
        .map_err(BuildError::Data)?;
    // Per weight: the kriging on every sample (its own variogram search), then each fold predicted
    // by a refit on the others with that variogram. Weights in parallel, results in weight order.
    let fits = STYLE_WEIGHTS
        .par_iter()
        .map(|&w| -> Result<(Kriging, WeightTrial), BuildError> {
            let full = Kriging::fit(params.as_ref(), values, &fit_config(w))?;
            let given = KrigingConfig {
                model: kriging::ModelChoice::Given(*full.variogram()),
                ..fit_config(w)
            };
            let (mut sq, mut count) = (0.0, 0);
            for f in 0..folds {
                let (e, n) = fold_squared_error(&params, values, scored, &given, &fold, f)?;
                sq += e;
                count += n;
            }
            let rmse = (sq / count.max(1) as f64).sqrt();
            Ok((full, WeightTrial { weight: w, rmse }))
        })
        .collect::<Result<Vec<_>, BuildError>>()?;
    let best = (0..fits.len())
        .filter(|&i| fits[i].1.rmse.is_finite())
        .min_by(|&a, &b| fits[a].1.rmse.total_cmp(&fits[b].1.rmse))
        .ok_or_else(|| BuildError::Data("no style weight could be cross-validated".into()))?;
    let trials: Vec<WeightTrial> = fits.iter().map(|f| f.1).collect();
    let weight = trials[best].weight;
    let kriging = fits.into_iter().nth(best).expect("best is an index").0;
    Ok((kriging, weight, trials))
}

/// The squared prediction error (scored columns, summed) of fold `f`'s samples by universal
/// kriging fitted with `config` on the other folds' samples, and the number of samples held out.
fn fold_squared_error(
    params: &Mat<f64>,
    values: faer::MatRef<'_, f64>,
    scored: &[bool],
    config: &KrigingConfig,
    fold: &[usize],
    f: usize,
) -> Result<(f64, usize), BuildError> {
    let (test, train): (Vec<usize>, Vec<usize>) = (0..fold.len()).partition(|&i| fold[i] == f);
    let k = Kriging::fit(
        select_rows(params.as_ref(), &train).as_ref(),
        select_rows(values, &train).as_ref(),
        config,
    )?;
    let pred = k.predict_rows(select_rows(params.as_ref(), &test).as_ref())?;
    let sq = kriging::held_out_squared_error(pred.as_ref(), values, &test, Some(scored));
    Ok((sq, test.len()))
}

/// The rows `rows` of `m`, in that order.
fn select_rows(m: faer::MatRef<'_, f64>, rows: &[usize]) -> Mat<f64> {
    Mat::from_fn(rows.len(), m.ncols(), |i, j| m[(rows[i], j)])
}

/// Column-major copy of a faer matrix.
fn col_major(m: faer::MatRef<'_, f64>) -> Vec<f64> {
    let mut v = Vec::with_capacity(m.nrows() * m.ncols());
    for j in 0..m.ncols() {
        for i in 0..m.nrows() {
            v.push(m[(i, j)]);
        }
    }
    v
}

/// Reorders the DOF rows of every pose: the first `7` rows stay, joint blocks follow `new`'s joint
/// order (a subset of `old`'s rotating joints: rows of joints `new` holds static are left out).
fn permute_rows(old: &PoseLayout, new: &PoseLayout, tensor: &Tensor3) -> Tensor3 {
    let [p_old, t, s] = tensor.dims();
    let p = new.dof();
    let mut map = (0..TIME_ROW + 1).collect::<Vec<usize>>();
    for &j in new.joint_order() {
        map.extend(old.joint_rows(j).expect("rotating joint"));
    }
    debug_assert_eq!(map.len(), p);
    let src = tensor.as_slice();
    let mut data = vec![0.0; p * t * s];
    for (dst_pose, src_pose) in data.chunks_exact_mut(p).zip(src.chunks_exact(p_old)) {
        for (d, &m) in dst_pose.iter_mut().zip(&map) {
            *d = src_pose[m];
        }
    }
    Tensor3::from_vec([p, t, s], data).expect("same shape")
}

/// Step 1 of the build: which joints are evaluated, in which order.
#[derive(Debug, Clone)]
pub struct JointLayout {
    /// The training layout without its static joints (held at their mean rotation), the others in
    /// evaluation order, every rest rotation the data's mean.
    pub layout: PoseLayout,
    /// The training tensor in that layout's rows (time row still in seconds).
    pub tensor: Tensor3,
    /// The joints left out as static.
    pub static_joints: Vec<StaticJoint>,
    /// The evaluation order with each joint's body part and measured importance.
    pub order: LimbOrder,
}

impl JointLayout {
    /// Measures the static joints ([`BuildConfig::static_rms_deg`]) and the importance of the others,
    /// and orders them legs before arms with counterparts adjacent ([`crate::importance`]).
    pub fn measure(set: &TrainingSet, config: &BuildConfig) -> Result<JointLayout, BuildError> {
        set.validate()?;
        if !(config.static_rms_deg.is_finite() && config.static_rms_deg >= 0.0) {
            return Err(BuildError::Data(format!(
                "static joint tolerance {} degrees must be finite and >= 0",
                config.static_rms_deg
            )));
        }
        let poses = set.tensor.as_slice();
        let static_joints = static_joints(&set.layout, poses, config.static_rms_deg);
        let mut moving = set.layout.clone();
        moving.set_rest_from_poses(poses)?;
        let frozen: Vec<usize> = static_joints.iter().map(|j| j.joint).collect();
        let moving = moving.freeze_joints(&frozen)?;
        let moving_tensor = permute_rows(&set.layout, &moving, &set.tensor);
        let measured = joint_importance(&moving, moving_tensor.as_slice(), config.importance_poses);
        let order = limb_order(&moving, &measured);
        let joints: Vec<usize> = order.joints.iter().map(|j| j.joint).collect();
        let layout = moving.clone().with_joint_order(joints)?;
        let tensor = permute_rows(&moving, &layout, &moving_tensor);
        Ok(JointLayout {
            layout,
            tensor,
            static_joints,
            order,
        })
    }
}

/// The offline analysis behind a model: the prepared tensor, the key-level decompositions (with their
/// sample factors `U_S`, which the runtime model does not keep) and the kriging fit. `eval` and the tables
/// use it to compare methods on exactly the data the model was built from.
#[derive(Debug, Clone)]
pub struct Analysis {
    /// Pose layout with joints in importance order and the data's mean as rest rotations.
    pub layout: PoseLayout,
    /// The motion tensor in that row order, time row multiplied by `time_scale`.
    pub tensor: Tensor3,
    /// Row [`TIME_ROW`] of `tensor` holds `time_scale` x seconds.
    pub time_scale: f64,
    /// Weight of every DOF row in the decomposition ([`RowWeights`]); the factors in `keys` are
    /// already divided by them, so they reconstruct `tensor` itself.
    pub row_weights: Vec<f64>,
    /// Joints in evaluation order: by decreasing measured importance, legs before arms, counterparts
    /// adjacent ([`crate::importance::limb_order`]).
    pub importance: Vec<JointImportance>,
    /// Joints of the training layout that are static over the data (held at their mean, no rows).
    pub static_joints: Vec<StaticJoint>,
    /// Why the legs-before-arms rule could not be applied, when it could not.
    pub order_note: Option<String>,
    /// What the control selection decided for each control ([`kriging::select_dims`]).
    pub control_decisions: Vec<DimDecision>,
    /// Controls that vary over the data but were left out because the samples are too few for a
    /// trend over all of them (see [`MIN_SAMPLES`]); their decision reads `Constant`.
    pub dropped_for_samples: Vec<usize>,
    /// The key levels (ALS), decomposed with the rows weighted (`mse` and `rel_error` are those of the
    /// weighted tensor, which the greedy search compares).
    pub keys: KeyLevels,
    /// The accuracy levels (distinct rank triples, each a truncation of a key).
    pub levels: Vec<hosvd_als::HybridLevel>,
    /// Universal kriging of the samples over the controls.
    pub kriging: Kriging,
    /// Raw controls per sample.
    pub controls: Vec<[f64; 4]>,
    /// Source of every sample.
    pub sources: Vec<String>,
    /// The style of every sample, for a model built with style labels: the kriging's parameters
    /// are then the four controls and the style's one-hot code ([`Analysis::control_matrix`]).
    pub styles: Option<StyleLabels>,
    /// The scale of the style code and how it was chosen (`None` without styles).
    pub style_weight: Option<(f64, Vec<WeightTrial>)>,
}

impl Analysis {
    /// Steps 1-4 of the module documentation.
    pub fn run(
        set: &TrainingSet,
        config: &BuildConfig,
        progress: &dyn Progress,
    ) -> Result<Analysis, BuildError> {
        set.validate()?;
        let [_, t, s] = set.tensor.dims();

        // 1. Static joints out; joint order by measured importance, legs before arms.
        progress.stage("joint importance", 1);
        let joints = JointLayout::measure(set, config)?;
        let JointLayout {
            layout,
            mut tensor,
            static_joints,
            order: limbs,
        } = joints;
        let importance = limbs.joints.clone();
        let p = layout.dof();
        progress.inc(1);

        // 2. Time increments in units of the mean increment.
        let mean_dt = tensor
            .as_slice()
            .chunks_exact(p)
            .map(|pose| pose[TIME_ROW])
            .sum::<f64>()
            / (t * s) as f64;
        if !mean_dt.is_finite() || mean_dt <= 0.0 {
            return Err(BuildError::Data(format!(
                "mean time increment {mean_dt} s: the time row ({TIME_ROW}) is not filled"
            )));
        }
        let time_scale = 1.0 / mean_dt;
        for pose in tensor.as_mut_slice().chunks_exact_mut(p) {
            pose[TIME_ROW] *= time_scale;
        }

        // 3. Key levels and hybrid accuracy levels.
        progress.stage("key levels (ALS)", 1);
        let row_weights = match config.row_weights {
            RowWeights::JointPosition => dof_weights(
                &layout,
                tensor.as_slice(),
                TIME_ROW,
                root_speed(&tensor, mean_dt) * mean_dt,
                config.importance_poses,
            ),
            RowWeights::Unit => vec![1.0; p],
        };
        if let Some((d, w)) = row_weights
            .iter()
            .enumerate()
            .find(|(_, w)| !(w.is_finite() && **w > 0.0))
        {
            return Err(BuildError::Data(format!(
                "weight {w} of DOF row {d} is not positive: the skeleton does not move with that row"
            )));
        }
        let weighted = weigh_rows(&tensor, &row_weights);
        let (max_ranks, min_ranks) = config.rank_bounds(p);
        let key_cfg = KeySearchConfig {
            levels: config.key_levels,
            max_ranks,
            min_ranks,
            als: config.als,
        };
        let mut keys: KeyLevels = hosvd_als::key_levels(&weighted, &key_cfg)?;
        for key in &mut keys.levels {
            unweigh_factor(&mut key.tucker, &row_weights);
        }
        let levels = distinct_levels(&hybrid_levels(&keys, config.accuracy_levels));
        progress.inc(1);

        // 4. Universal kriging of the samples over the controls.
        progress.stage("kriging", 1);
        let fit = ControlFit::new(set, &weighted, config)?;
        let (kriging, control_decisions) = fit.select(set, config)?;
        progress.inc(1);
        // 4b. The style code beside the controls kept.
        let (kriging, style_weight) = fit.with_styles(kriging, set, config, progress)?;
        Ok(Analysis {
            dropped_for_samples: fit.dropped_for_samples,
            layout,
            tensor,
            time_scale,
            row_weights,
            importance,
            static_joints,
            order_note: limbs.note,
            control_decisions,
            keys,
            levels,
            kriging,
            controls: set.controls.clone(),
            sources: set.sources.clone(),
            styles: set.styles.clone(),
            style_weight,
        })
    }

    /// Steps 1-4 and the quality guard of step 7 ([`crate::build`]): the analysis of the model
    /// that [`MotionModel::build`] builds from `set`, without measuring its level errors. When the
    /// cross-validation kept controls and `set` has the motion-quality reference, this measures
    /// level 0's motion quality on the quality grid (the guard's test), which [`Analysis::run`]
    /// does not. What `eval` compares, so that its figures are the model's.
    pub fn run_guarded(
        set: &TrainingSet,
        config: &BuildConfig,
        progress: &dyn Progress,
    ) -> Result<Analysis, BuildError> {
        let analysis = Analysis::run(set, config, progress)?;
        let cv_kept = analysis
            .control_decisions
            .iter()
            .any(|d| matches!(d, DimDecision::KeptByFolds { .. }));
        let Some(reference) = set.quality.as_ref().filter(|_| cv_kept) else {
            return Ok(analysis);
        };
        let model = MotionModel::prepared(&analysis, set, config, progress)?;
        let level0 = level0_quality(&model, reference, analysis.style_report(set).as_ref())?;
        Ok(
            match quality_guard(&analysis, level0, reference, set, config, progress)? {
                Some((guarded, _)) => guarded,
                None => analysis,
            },
        )
    }

    /// The style report of a model built from this analysis of `set` (`None` without styles).
    pub fn style_report(&self, set: &TrainingSet) -> Option<crate::style::StyleReport> {
        let (labels, (weight, trials)) = (self.styles.as_ref()?, self.style_weight.as_ref()?);
        Some(crate::style::StyleReport {
            spec: set.style_spec.clone()?,
            names: labels.names.clone(),
            cycles: labels.counts(),
            takes: crate::style::StyleReport::takes_per_style(labels, &self.sources),
            weight: *weight,
            trials: trials.clone(),
            posture: set.style_postures().unwrap_or_default(),
            quality: set.style_references().unwrap_or_default(),
        })
    }

    /// Brings an aligned tensor in the training layout (`set_layout`, rows as `motion-lod cycles` writes
    /// them) into this analysis's row order and time scale, for comparison with its samples.
    ///
    /// # Errors
    /// [`BuildError::Data`] when `tensor`'s rows are not `set_layout`'s DOF, or `set_layout` lacks
    /// a joint this analysis evaluates (it is not the layout the analysis was built from).
    pub fn prepare(
        &self,
        set_layout: &PoseLayout,
        tensor: &Tensor3,
    ) -> Result<Tensor3, BuildError> {
        let p = tensor.dims()[0];
        if p != set_layout.dof() {
            return Err(BuildError::Data(format!(
                "tensor to prepare has {p} DOF rows, its pose layout {}",
                set_layout.dof()
            )));
        }
        if let Some(&j) = self
            .layout
            .joint_order()
            .iter()
            .find(|&&j| set_layout.joint_rows(j).is_none_or(|r| r.end > p))
        {
            return Err(BuildError::Data(format!(
                "joint {j} of the analysis has no rows in the tensor's pose layout"
            )));
        }
        let mut out = permute_rows(set_layout, &self.layout, tensor);
        let p = out.dims()[0];
        for pose in out.as_mut_slice().chunks_exact_mut(p) {
            pose[TIME_ROW] *= self.time_scale;
        }
        Ok(out)
    }

    /// An ALS (HOOI) Tucker model of `tensor` at `ranks`, decomposed exactly as the key levels are (rows
    /// weighted, `U_P` divided by the weights afterwards); the report's errors are of the weighted tensor.
    pub fn decompose(
        &self,
        ranks: [usize; 3],
        als: &AlsOptions,
    ) -> Result<(Tucker, AlsReport), BuildError> {
        let (mut tucker, report) =
            hosvd_als::hooi(&weigh_rows(&self.tensor, &self.row_weights), ranks, als)?;
        unweigh_factor(&mut tucker, &self.row_weights);
        Ok((tucker, report))
    }

    /// The raw parameters as an `S x d` matrix (what the kriging was fitted on): the four
    /// controls, then the style's one-hot code for a model with styles.
    pub fn control_matrix(&self) -> Mat<f64> {
        crate::dataset::control_matrix(&self.controls, self.styles.as_ref())
    }

    /// Step 5: the runtime model (level errors not yet measured).
    pub fn runtime_model(
        &self,
        config: &BuildConfig,
        progress: &dyn Progress,
    ) -> Result<MotionModel, BuildError> {
        let [p, t, s] = self.tensor.dims();
        let krig = &self.kriging;
        progress.stage("runtime model", self.keys.levels.len() as u64);
        let mut key_tensors = Vec::with_capacity(self.keys.levels.len());
        let mut key_reports = Vec::with_capacity(self.keys.levels.len());
        for key in &self.keys.levels {
            let tk = &key.tucker;
            let [rp, rt, rs] = key.ranks;
            let u_p = col_major(tk.factors[0].as_ref());
            let u_t = col_major(tk.factors[1].as_ref());
            let u_s = col_major(tk.factors[2].as_ref());
            let factors = KeyFactors {
                ranks: Ranks::new(rp, rt, rs),
                core: tk.core.as_slice(),
                u_p: &u_p,
                u_t: &u_t,
                u_s: &u_s,
            };
            key_tensors.push(key_tensor(&factors, p, t, krig)?);
            key_reports.push(KeyReport {
                ranks: key.ranks,
                mse: key.mse,
                rel_error: key.rel_error,
                iterations: key.iterations,
                converged: key.converged,
            });
            progress.inc(1);
        }
        let scaling = krig.scaling();
        let params = self.control_matrix();
        let d = params.ncols();
        let raw: Vec<f32> = (0..d)
            .flat_map(|k| (0..s).map(move |i| (k, i)))
            .map(|(k, i)| params[(i, k)] as f32)
            .collect();
        let controls = control_space(
            runtime_variogram(krig.variogram())?,
            &raw,
            s,
            scaling.offset.iter().map(|&v| v as f32).collect(),
            scaling.scale.iter().map(|&v| v as f32).collect(),
        )?;
        let controls = with_projection(controls, krig)?;
        let mean_pose = mean_rows(&self.tensor, &self.layout);
        let parts = ModelParts {
            p,
            t,
            s,
            d,
            always_rows: lod_policy::ALWAYS_ROWS,
            rows_per_joint: lod_policy::ROWS_PER_JOINT,
            keys: key_tensors,
            levels: self.levels.iter().map(|&l| accuracy_level(l)).collect(),
            controls,
            time_scale: self.time_scale,
            mean_pose: mean_pose.iter().map(|&v| v as f32).collect(),
            level_errors: Vec::new(),
            joint_errors: Vec::new(),
        };
        let styles = self
            .styles
            .as_ref()
            .map_or_else(Vec::new, |l| l.names.clone());
        let runtime =
            RuntimeModel::with_styles(self.layout.rig().clone(), LodModel::new(parts)?, styles)?;
        Ok(MotionModel::new(
            runtime,
            self.layout.clone(),
            BuildReport {
                samples: s,
                dims: [p, t, s],
                sources: self.sources.clone(),
                importance: self.importance.clone(),
                row_weights: self.row_weights.clone(),
                keys: key_reports,
                c_e: self.keys.c_e,
                ranks_clamped: self.keys.clamped,
                variogram: *krig.variogram(),
                dropped_controls: krig.dropped_dims().to_vec(),
                control_decisions: self.control_decisions.clone(),
                dropped_for_samples: self.dropped_for_samples.clone(),
                static_joints: self.static_joints.clone(),
                order_note: self.order_note.clone(),
                kriging_loo_rmse: None,
                overruled_quality: None,
                quality: None,
                data: None,
                config: config.clone(),
            },
        )?)
    }
}

/// The runtime's form of a hybrid level: the same key, the ranks as [`Ranks`].
fn accuracy_level(l: hosvd_als::HybridLevel) -> AccuracyLevel {
    AccuracyLevel {
        key: l.key,
        ranks: Ranks::new(l.ranks[0], l.ranks[1], l.ranks[2]),
    }
}

impl MotionModel {
    /// Builds the hybrid multilinear model from aligned training data (offline; see the module docs).
    pub fn build(
        set: &TrainingSet,
        config: &BuildConfig,
        progress: &dyn Progress,
    ) -> Result<MotionModel, BuildError> {
        Ok(MotionModel::build_with_analysis(set, config, progress)?.0)
    }

    /// As [`MotionModel::build`], also returning the analysis it was built from.
    pub fn build_with_analysis(
        set: &TrainingSet,
        config: &BuildConfig,
        progress: &dyn Progress,
    ) -> Result<(MotionModel, Analysis), BuildError> {
        let analysis = Analysis::run(set, config, progress)?;
        let model = MotionModel::prepared(&analysis, set, config, progress)?;
        let model = model.measured(&analysis, set, config, progress)?;
        // 7. The quality guard (nothing to do when level 0 passes).
        let level0 = model.lod().level_errors().first().copied();
        if let (Some(level0), Some(reference)) = (level0, &model.report.quality) {
            if let Some((guarded, mut candidate)) =
                quality_guard(&analysis, level0, reference, set, config, progress)?
            {
                candidate.report.overruled_quality = Some(level0);
                let model = candidate.measured(&guarded, set, config, progress)?;
                return Ok((model, guarded));
            }
        }
        Ok((model, analysis))
    }

    /// Step 5 and the feet: the runtime model of `analysis` with the feet, the stature and the
    /// motion-quality reference of `set` (level errors not yet measured).
    fn prepared(
        analysis: &Analysis,
        set: &TrainingSet,
        config: &BuildConfig,
        progress: &dyn Progress,
    ) -> Result<MotionModel, BuildError> {
        let mut model = analysis.runtime_model(config, progress)?;
        // The decompositions' vector kernels may leave the AVX upper state dirty on every thread
        // they ran on, which slows this crate's SSE code (the runtime after a build in the same
        // process ran 2.5x slower): clear it everywhere before the runtime is used.
        rayon::broadcast(|_| lod_policy::offline::clear_avx_upper_state());
        lod_policy::offline::clear_avx_upper_state();
        model.report.quality = set.quality.clone();
        let feet = set
            .quality
            .as_ref()
            .and_then(|q| q.foot_rig(model.layout.rig()));
        let stature_m = set
            .quality
            .as_ref()
            .and_then(|q| q.stature_m)
            .map(|h| h as f32);
        let (runtime, layout, report) = model.into_parts();
        Ok(MotionModel {
            runtime: runtime.with_feet(feet)?.with_stature(stature_m)?,
            layout,
            report,
            style: None,
        })
    }

    /// Step 6 on a [`MotionModel::prepared`] model: the measured errors of every accuracy level and
    /// joint count, and the style report.
    fn measured(
        self,
        analysis: &Analysis,
        set: &TrainingSet,
        config: &BuildConfig,
        progress: &dyn Progress,
    ) -> Result<MotionModel, BuildError> {
        progress.stage("level errors", 1);
        let style = analysis.style_report(set);
        let (level_errors, joint_errors) = self.measure_lod_errors(
            &set.controls,
            set.styles.as_ref(),
            style.as_ref(),
            config.error_samples,
        )?;
        let (runtime, layout, report) = self.into_parts();
        let model = MotionModel {
            runtime: runtime.with_errors(level_errors, joint_errors)?,
            layout,
            report,
            style: None,
        }
        .with_style_report(style)?;
        progress.inc(1);
        Ok(model)
    }

    /// Error of every accuracy level (all joints) and of every joint count (level 0) relative to the
    /// full-detail synthesis at the same controls: pose errors over up to `max_samples` training
    /// controls (each with its sample's style when the set has `styles`), foot slide
    /// ([`foot_slide_cm`]) over those and the walks of the quality grid.
    fn measure_lod_errors(
        &self,
        controls: &[[f64; 4]],
        styles: Option<&StyleLabels>,
        styles_report: Option<&crate::style::StyleReport>,
        max_samples: usize,
    ) -> Result<(Vec<LevelError>, Vec<LevelError>), BuildError> {
        let lod = self.lod();
        let (p, t) = (lod.p(), lod.t());
        let stride = controls.len().div_ceil(max_samples.max(1)).max(1);
        let picked: Vec<Controls> = controls
            .iter()
            .enumerate()
            .step_by(stride)
            .map(|(i, &c)| {
                let style = styles.map_or(lod_policy::StyleMix::DATA_MIX, |l| {
                    lod_policy::StyleMix::one(l.of_sample[i])
                });
                Controls::from_f64(c).with_style(style)
            })
            .collect();
        let full = self.lod().full_detail();
        // Every synthesis and measurement below is independent of the others: they run in
        // parallel, each with its own arithmetic, collected in order (the same bits on any pool).
        let reference: Vec<Vec<f64>> = picked
            .par_iter()
            .map(|c| self.synthesize_aligned(c, full))
            .collect::<Result<_, _>>()?;
        // Foot slide needs the feet (the quality reference); without them it is 0. Measured over
        // the quality grid (the hull's corners, turns, sidesteps, slow and fast) and the picked
        // training controls: the largest over both.
        let walks = crate::walk_quality::walk_grid(self);
        let grid: Vec<Controls> = walks
            .iter()
            .map(|w| w.controls)
            .chain(picked.iter().copied())
            .collect();
        let slides_full: Option<Vec<f64>> = match &self.report.quality {
            Some(_) => Some(
                grid.par_iter()
                    .map(|c| foot_slide_cm(self, c, full))
                    .collect::<Result<_, _>>()?,
            ),
            None => None,
        };
        let measure = |detail: Detail, with_quality: bool| -> Result<LevelError, BuildError> {
            let mut meter = ErrorMeter::new(&self.layout);
            for (c, r) in picked.iter().zip(&reference) {
                let poses = self.synthesize_aligned(c, detail)?;
                meter.compare_sequences(r, &poses);
            }
            let e = meter.total();
            let slide_cm = match &slides_full {
                Some(full) => {
                    let mut worst = 0.0f64;
                    for (c, full) in grid.iter().zip(full) {
                        worst = worst.max(foot_slide_cm(self, c, detail)? - full);
                    }
                    worst as f32
                }
                None => 0.0,
            };
            let quality = match &self.report.quality {
                Some(reference) if with_quality => {
                    level_quality(self, reference, styles_report, &walks, detail)?
                }
                _ => LevelQuality::default(),
            };
            Ok(LevelError {
                mean_joint_cm: e.mean_joint_cm as f32,
                shell_cm: e.shell_cm as f32,
                slide_cm,
                pop_x: quality.pop_x,
                skate_x: quality.skate_x,
                floor_cm: quality.floor_cm,
                facing_out_deg: quality.facing_out_deg,
            })
        };
        debug_assert!(p > 0 && t > 0);
        let levels = (0..lod.levels().len())
            .into_par_iter()
            .map(|l| measure(Detail::new(l, lod.joints()), true))
            .collect::<Result<Vec<_>, _>>()?;
        let joints = (0..=lod.joints())
            .into_par_iter()
            .map(|j| measure(Detail::new(0, j), false))
            .collect::<Result<Vec<_>, _>>()?;
        Ok((levels, joints))
    }
}

/// Step 7 of the module documentation: when `level0` (the level-0 errors of the model of
/// `analysis`, with their motion quality against `reference`) fails the motion-quality thresholds
/// and the cross-validation kept controls that the leave-one-out rule drops, the analysis rebuilt
/// without the fewest of them whose level-0 walks pass, and its model ([`MotionModel::prepared`],
/// errors not yet measured); `None` when level 0 passes, when there is no such control, or when no
/// rebuild passes either (the controls are not what fails).
fn quality_guard(
    analysis: &Analysis,
    level0: LevelError,
    reference: &crate::quality::QualityReference,
    set: &TrainingSet,
    config: &BuildConfig,
    progress: &dyn Progress,
) -> Result<Option<(Analysis, MotionModel)>, BuildError> {
    let cv_kept: Vec<usize> = (0..analysis.control_decisions.len())
        .filter(|&k| {
            matches!(
                analysis.control_decisions[k],
                DimDecision::KeptByFolds { .. }
            )
        })
        .collect();
    if level0.passes_quality() || cv_kept.is_empty() {
        return Ok(None);
    }
    progress.stage("quality guard (controls kept by cross-validation)", 1);
    let fit = ControlFit::new(
        set,
        &weigh_rows(&analysis.tensor, &analysis.row_weights),
        config,
    )?;
    let loo_decisions = fit.loo_decisions(&set.sources, config)?;
    // What dropping a control costs the cross-validation.
    let cost = |k: usize| match analysis.control_decisions[k] {
        DimDecision::KeptByFolds {
            cv_with,
            cv_without,
            ..
        } => cv_without - cv_with,
        _ => f64::INFINITY,
    };
    let candidates: Vec<usize> = cv_kept
        .into_iter()
        .filter(|&k| loo_decisions[k].dropped())
        .collect();
    // Every non-empty subset: the fewest controls first, then the cheapest (ties: lowest indices).
    let mut subsets: Vec<Vec<usize>> = (1u32..1 << candidates.len())
        .map(|bits| {
            (0..candidates.len())
                .filter(|i| bits & (1 << i) != 0)
                .map(|i| candidates[i])
                .collect()
        })
        .collect();
    let total = |d: &[usize]| d.iter().map(|&k| cost(k)).sum::<f64>();
    subsets.sort_by(|a, b| {
        a.len()
            .cmp(&b.len())
            .then(total(a).total_cmp(&total(b)))
            .then(a.cmp(b))
    });
    for drop in subsets {
        let mut decisions = analysis.control_decisions.clone();
        for &k in &drop {
            if let DimDecision::KeptByFolds {
                cv_with,
                cv_without,
                folds,
            } = decisions[k]
            {
                decisions[k] = DimDecision::Overruled {
                    cv_with,
                    cv_without,
                    folds,
                };
            }
        }
        let kriging = fit.fit_kept(&decisions)?;
        let (kriging, style_weight) = fit.with_styles(kriging, set, config, progress)?;
        let guarded = Analysis {
            kriging,
            style_weight,
            control_decisions: decisions,
            ..analysis.clone()
        };
        let candidate = MotionModel::prepared(&guarded, set, config, progress)?;
        if level0_quality(&candidate, reference, guarded.style_report(set).as_ref())?
            .passes_quality()
        {
            progress.inc(1);
            return Ok(Some((guarded, candidate)));
        }
    }
    progress.inc(1);
    Ok(None)
}

/// The worst motion quality of one detail over the quality grid (the fields of [`LevelError`] of
/// the same names).
#[derive(Debug, Clone, Copy, Default)]
struct LevelQuality {
    pop_x: f32,
    skate_x: f32,
    floor_cm: f32,
    facing_out_deg: f32,
}

/// The motion quality of `model`'s level 0 over the quality grid ([`level_quality`]) as a
/// [`LevelError`] (its pose errors 0, as level 0's).
fn level0_quality(
    model: &MotionModel,
    reference: &crate::quality::QualityReference,
    styles: Option<&crate::style::StyleReport>,
) -> Result<LevelError, BuildError> {
    let walks = crate::walk_quality::walk_grid(model);
    let q = level_quality(model, reference, styles, &walks, model.lod().full_detail())?;
    Ok(LevelError {
        pop_x: q.pop_x,
        skate_x: q.skate_x,
        floor_cm: q.floor_cm,
        facing_out_deg: q.facing_out_deg,
        ..LevelError::default()
    })
}

/// The motion quality of `detail` over the quality grid's `walks` inside the data's hull
/// ([`crate::walk_quality::GridWalk::in_hull`]; each [`QUALITY_WALK_CYCLES`]
/// cycles at 30 fps, seams inertialized, the foot lock on: as the crowd plays a walker): the largest
/// pop and the largest skate over the walks, each a multiple of the data's at the walk's step
/// length ([`crate::quality::QualityReference::at_controls`]; the data: `pooled`, or for a walk of
/// one style in a model with styles that style's own takes, [`crate::style::StyleReport::reference_for`]),
/// the largest floor offset (cm, either side) and the largest facing against travel outside the
/// data's range (degrees): the figures of
/// `motion-lod quality` that [`LevelError::passes_quality`] holds to the near-character thresholds.
fn level_quality(
    model: &MotionModel,
    pooled: &crate::quality::QualityReference,
    styles: Option<&crate::style::StyleReport>,
    walks: &[crate::walk_quality::GridWalk],
    detail: Detail,
) -> Result<LevelQuality, BuildError> {
    let ratio = |v: f64, of: f64| (v / of.max(1e-9)).min(1e6) as f32;
    let mut worst = LevelQuality::default();
    // Inside the data's hull only: outside it the model extrapolates (and `synth` warns).
    for w in walks.iter().filter(|w| w.in_hull) {
        let fail = |e: &dyn std::fmt::Display| {
            BuildError::Data(format!("quality of `{}` at {detail:?}: {e}", w.name))
        };
        let walk = model
            .synthesize_walk(&crate::synth::WalkRequest {
                controls: w.controls,
                detail,
                cycles: QUALITY_WALK_CYCLES,
                fps: crate::quality::REFERENCE_FPS,
                blend: true,
                plant_feet: true,
            })
            .map_err(|e| fail(&e))?;
        let q = crate::walk_quality::measure_walk(model, &walk).map_err(|e| fail(&e))?;
        // A walk of one style (a corner of a model with styles) is held to that style's takes.
        let reference = styles
            .and_then(|st| st.reference_for(&w.controls.style, Some(pooled)))
            .unwrap_or(pooled);
        let (lo, hi) = reference.facing_range_deg;
        let data = reference.at_controls(&w.controls);
        worst.pop_x = worst.pop_x.max(ratio(q.pop_cm, data.pop_cm));
        worst.skate_x = worst.skate_x.max(ratio(q.skate_cm_s, data.skate_cm_s));
        worst.floor_cm = worst.floor_cm.max(q.floor_offset_cm.abs().min(1e6) as f32);
        let facing_out = (lo - q.facing_deg).max(q.facing_deg - hi).max(0.0);
        worst.facing_out_deg = worst.facing_out_deg.max(facing_out.min(1e6) as f32);
    }
    Ok(worst)
}

/// Cycles of each walk the build's per-level motion quality measures (as `motion-lod quality`).
pub const QUALITY_WALK_CYCLES: usize = 4;

/// Cycles of the walks [`foot_slide_cm`] measures.
pub const SLIDE_WALK_CYCLES: usize = 3;

/// How far a planted foot slides over one stance in a walk of [`SLIDE_WALK_CYCLES`] cycles at 30 fps
/// for `controls` at `detail` (cycles blended, the runtime foot lock on, as the crowd plays a
/// walker), in centimetres: the motion-quality meter's `skate x contact share x cycle duration`
/// (the distance the feet travel while on the floor, per foot and cycle). Needs the model's
/// quality reference.
pub fn foot_slide_cm(
    model: &MotionModel,
    controls: &Controls,
    detail: Detail,
) -> Result<f64, BuildError> {
    let walk = model
        .synthesize_walk(&crate::synth::WalkRequest {
            controls: *controls,
            detail,
            cycles: SLIDE_WALK_CYCLES,
            fps: crate::quality::REFERENCE_FPS,
            blend: true,
            plant_feet: true,
        })
        .map_err(|e| BuildError::Data(format!("foot slide of {controls:?} at {detail:?}: {e}")))?;
    let q = crate::walk_quality::measure_walk(model, &walk)
        .map_err(|e| BuildError::Data(format!("foot slide of {controls:?} at {detail:?}: {e}")))?;
    Ok(q.skate_cm_s * q.contact_share * walk.cycle_seconds)
}

/// `W X`: every DOF row of `x` times its weight.
fn weigh_rows(x: &Tensor3, weights: &[f64]) -> Tensor3 {
    let p = x.dims()[0];
    debug_assert_eq!(weights.len(), p);
    let mut out = x.clone();
    for pose in out.as_mut_slice().chunks_exact_mut(p) {
        for (v, w) in pose.iter_mut().zip(weights) {
            *v *= w;
        }
    }
    out
}

/// `U_P <- W^-1 U_P`: a model of the weighted tensor `W X` becomes a model of `X` (same core).
fn unweigh_factor(tucker: &mut Tucker, weights: &[f64]) {
    let u = &mut tucker.factors[0];
    debug_assert_eq!(u.nrows(), weights.len());
    for j in 0..u.ncols() {
        for (i, w) in weights.iter().enumerate() {
            u[(i, j)] /= w;
        }
    }
}

/// Mean speed of the root (m/s): path length of the root over all samples divided by their duration.
/// `tensor` has the time row in units of `mean_dt` seconds.
fn root_speed(tensor: &Tensor3, mean_dt: f64) -> f64 {
    let [p, t, s] = tensor.dims();
    let (mut path, mut time) = (0.0, 0.0);
    for k in 0..s {
        let sample = tensor.sample(k);
        for f in 1..t {
            let (a, b) = (&sample[(f - 1) * p..], &sample[f * p..]);
            path += ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2) + (b[2] - a[2]).powi(2)).sqrt();
            time += b[TIME_ROW] * mean_dt;
        }
    }
    if time > 0.0 { path / time } else { 0.0 }
}

/// Removes repeated rank triples from the hybrid schedule: when the rank range between two keys is too
/// narrow for the number of accuracy levels asked for, several levels get the same ranks. A truncation
/// whose ranks equal a later key's is dropped in favour of that key (ALS beats truncation at equal
/// size), and of consecutive equal levels the first is kept.
fn distinct_levels(levels: &[hosvd_als::HybridLevel]) -> Vec<hosvd_als::HybridLevel> {
    let mut out: Vec<hosvd_als::HybridLevel> = Vec::with_capacity(levels.len());
    for (i, level) in levels.iter().enumerate() {
        let later_same = levels[i + 1..]
            .iter()
            .any(|m| m.ranks == level.ranks && m.key != level.key);
        let repeats = out.last().is_some_and(|prev| prev.ranks == level.ranks);
        if !later_same && !repeats {
            out.push(*level);
        }
    }
    out
}

/// Mean of every row over all poses: root and (scaled) time rows arithmetic means, joint rows the
/// exp-map of the layout's rest (mean) rotation, so that rows which are not evaluated hold what the
/// runtime forward kinematics uses for inactive joints.
fn mean_rows(tensor: &Tensor3, layout: &PoseLayout) -> Vec<f64> {
    let [p, t, s] = tensor.dims();
    let mut mean = vec![0.0; p];
    for pose in tensor.as_slice().chunks_exact(p) {
        for (m, v) in mean.iter_mut().zip(pose) {
            *m += v;
        }
    }
    for m in &mut mean {
        *m /= (t * s) as f64;
    }
    let rest = layout.rest_pose();
    mean[TIME_ROW + 1..].copy_from_slice(&rest[TIME_ROW + 1..]);
    mean
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dof_ranks_scale_with_the_data() {
        let config = BuildConfig::default();
        assert_eq!(config.rank_bounds(PAPER_DOF), ([40, 40, 60], [7, 7, 9]));
        // Bandai: 67 DOF keep 40/94 of them at the first key, 7/94 at the last.
        assert_eq!(config.rank_bounds(67), ([29, 40, 60], [5, 7, 9]));
        // A tiny skeleton keeps at least one component.
        assert_eq!(config.rank_bounds(10), ([4, 40, 60], [1, 7, 9]));
        let as_given = BuildConfig {
            dof_rank_reference: None,
            ..BuildConfig::default()
        };
        assert_eq!(as_given.rank_bounds(67), ([40, 40, 60], [7, 7, 9]));
    }
}

#[cfg(test)]
mod selection_tests {
    use super::*;

    /// Sources as the training set writes them: `take_k.bvh [a..=b]`, `per` cycles per take.
    fn sources(takes: usize, per: usize) -> Vec<String> {
        (0..takes * per)
            .map(|i| {
                format!(
                    "take_{:04}.bvh [{}..={}]",
                    i / per,
                    i % per * 10,
                    i % per * 10 + 9
                )
            })
            .collect()
    }

    #[test]
    fn selection_decides_on_whole_takes_above_its_limit() {
        assert_eq!(
            selection_rows(&sources(100, 12)),
            None,
            "1,200 samples: all"
        );
        let src = sources(500, 7); // 3,500 samples
        let rows = selection_rows(&src).expect("a subsample above the limit");
        assert!(rows.len() <= SELECT_MAX_SAMPLES && rows.len() > SELECT_MAX_SAMPLES / 2);
        // Whole takes: every cycle of a picked take, none of the others.
        let picked: std::collections::BTreeSet<&str> = rows
            .iter()
            .map(|&i| crate::folds::take_of(&src[i]))
            .collect();
        for (i, s) in src.iter().enumerate() {
            assert_eq!(picked.contains(crate::folds::take_of(s)), rows.contains(&i));
        }
        assert!(
            picked.len() >= 2 * CONTROL_FOLDS,
            "enough takes for the folds"
        );
    }

    /// The compressed values keep each group's leave-one-out squared error (kriging ignores a
    /// column's mean and an orthogonal change of columns within a group), scored group first.
    #[test]
    fn compressed_values_keep_each_groups_errors() {
        let s = 80;
        let params = Mat::from_fn(s, 2, |i, k| {
            ((i * (k + 3)) % 17) as f64 / 17.0 + 0.01 * i as f64
        });
        let values = Mat::from_fn(s, 40, |i, j| {
            let (x, y) = (params[(i, 0)], params[(i, 1)]);
            5.0 + (j as f64 * 0.3).sin() * (2.0 * x).sin() + (j as f64 * 0.7).cos() * y * y
        });
        let scored: Vec<bool> = (0..40).map(|j| j % 5 != 0).collect();
        let (c, mask) = compressed_values(values.as_ref(), &scored);
        assert!(c.ncols() < 40);
        let k = mask.iter().filter(|&&m| m).count();
        assert!(mask[..k].iter().all(|&m| m) && mask[k..].iter().all(|&m| !m));
        let config = KrigingConfig {
            model: kriging::ModelChoice::Given(
                kriging::Variogram::new(kriging::VariogramModel::Gaussian, 1e-3, 1.0, 1.0, 1.0)
                    .unwrap(),
            ),
            ..KrigingConfig::default()
        };
        let sq = |v: &Mat<f64>, m: &[bool]| {
            let e = Kriging::fit(params.as_ref(), v.as_ref(), &config)
                .unwrap()
                .loo_errors()
                .unwrap();
            (0..e.ncols())
                .filter(|&j| m[j])
                .map(|j| e.col(j).iter().map(|x| x * x).sum::<f64>())
                .sum::<f64>()
        };
        let not = |m: &[bool]| m.iter().map(|b| !b).collect::<Vec<_>>();
        for (full, small) in [
            (sq(&values, &scored), sq(&c, &mask)),
            (sq(&values, &not(&scored)), sq(&c, &not(&mask))),
        ] {
            assert!((full - small).abs() <= 1e-4 * full, "{full} vs {small}");
        }
    }
}
