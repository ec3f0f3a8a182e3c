//! Leave-one-out evaluation of the multilinear model against the alternatives (paper section 5.1).
//!
//! Every method predicts a held-out sample as a linear blend of the other samples' representations, so
//! each is a leave-one-out weight matrix `W` (S x S, zero diagonal, row `i` = the weights that predict
//! sample `i` from the others) applied to a representation of the samples:
//!
//! | method | `W` | samples blended |
//! |---|---|---|
//! | `multilinear` (per key level) | universal kriging (eq. 8), trend refitted without `i` | the level's Tucker reconstruction, `Z x1 U_P x2 U_T x3 (W U_S)` |
//! | `naive-kriging` | the same | the raw aligned samples |
//! | `pca` | the same | the samples projected on the first `R_P` principal DOF directions |
//! | `rbf` | RBF with a linear polynomial (Rose et al.), refitted without `i` | the raw aligned samples |
//! | `rbf-smoothed` | the same with a smoothing term chosen by leave-one-out error (see below) | the raw aligned samples |
//! | `nearest` | 1 at the nearest other sample in scaled control space | the raw aligned samples |
//!
//! The RBF baseline interpolates exactly, as in Rose et al. and the paper; on cycles with nearly equal
//! controls that system is ill-conditioned (167 cm leave-one-out error on the embedded data).
//! `rbf-smoothed` adds a ridge term `Phi + lambda I`, `lambda` chosen by its own leave-one-out error on
//! the samples (`kriging::RbfSmoothing::Loo`): the stronger competitor.
//!
//! The kriging variogram and the control scaling stay those fitted on all samples (closed-form
//! leave-one-out, see `kriging::Kriging::loo_errors`). The error of a prediction is the project's metric
//! ([`crate::metrics`]): mean joint position error in cm over the `T` aligned frames, against the held-out
//! sample.

use faer::{Mat, MatRef};
use hosvd_als::Tucker;
use kriging::{
    Kriging, KrigingConfig, ModelChoice, ParamScaling, Rbf, RbfConfig, RbfSmoothing, ScalingChoice,
};
use serde::{Deserialize, Serialize};
use tensor_ops::Tensor3;

use crate::build::{Analysis, BuildError};
use crate::metrics::ErrorMeter;
use crate::progress::Progress;
use rayon::prelude::*;

/// Settings of [`leave_one_out`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct EvalConfig {
    /// Principal DOF directions kept by the PCA baseline (the paper: 40), clamped to `P`.
    pub pca_rank: usize,
    /// Evaluate at most this many held-out samples (evenly strided); all when `None`. `Some(0)` is
    /// refused ([`BuildError::Data`]).
    pub max_samples: Option<usize>,
}

impl EvalConfig {
    /// Refuses `max_samples: Some(0)` (checked before any work by every evaluation).
    fn check(&self) -> Result<(), BuildError> {
        if self.max_samples == Some(0) {
            return Err(BuildError::Data(
                "max_samples = 0: evaluate at least 1 sample (None evaluates all)".into(),
            ));
        }
        Ok(())
    }
}

impl Default for EvalConfig {
    fn default() -> Self {
        EvalConfig {
            pca_rank: 40,
            max_samples: None,
        }
    }
}

/// The error of one method.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MethodError {
    /// `multilinear`, `naive-kriging`, `rbf`, `rbf-smoothed`, `pca` or `nearest`.
    pub name: String,
    /// Accuracy level (multilinear only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub level: Option<usize>,
    /// Ranks `(R_P, R_T, R_S)` of that level (multilinear only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ranks: Option<[usize; 3]>,
    /// Mean joint position error over the held-out samples (cm).
    pub error_cm: f64,
    /// Largest shell error over the held-out samples (cm).
    pub shell_cm: f64,
    /// Bytes the method keeps to synthesize, in f64.
    pub bytes: usize,
}

/// The result of [`leave_one_out`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EvalReport {
    /// Samples `S`.
    pub samples: usize,
    /// Held-out samples evaluated.
    pub evaluated: usize,
    /// The aligned samples in f64, `P T S x 8`.
    pub raw_bytes: usize,
    /// Everything the hybrid model keeps, in f64.
    pub model_bytes: usize,
    /// One entry per method (multilinear once per key level).
    pub methods: Vec<MethodError>,
    /// For a model with styles: the error of each style's held-out cycles at level 0 and by the
    /// best of the baselines (left out of the JSON without styles).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub styles: Vec<StyleError>,
}

/// The error of one style's held-out cycles ([`EvalReport::styles`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StyleError {
    /// The style.
    pub style: String,
    /// Its held-out cycles evaluated.
    pub evaluated: usize,
    /// Mean joint position error of the multilinear model's level 0 (first key) (cm).
    pub level0_cm: f64,
    /// Mean joint position error of naive kriging of the raw samples (cm).
    pub naive_cm: f64,
}

/// `W = I - E(I)`: leave-one-out weights from the leave-one-out errors of the identity values.
fn loo_weights_from_errors(errors: MatRef<'_, f64>) -> Mat<f64> {
    let s = errors.nrows();
    Mat::from_fn(s, s, |i, j| if i == j { 0.0 } else { -errors[(i, j)] })
}

/// The RBF baseline's smoothing `lambda`, chosen by its closed-form leave-one-out error on the samples
/// themselves (rows weighted as the decomposition weighs them, so that the choice follows the joint
/// position error): the weights below are then fitted to identity values with that `lambda` fixed.
fn rbf_smoothing(analysis: &Analysis) -> Result<f64, BuildError> {
    let x = &analysis.tensor;
    let [p, t, s] = x.dims();
    let w = &analysis.row_weights;
    let values = Mat::from_fn(s, p * t, |i, j| x.sample(i)[j] * w[j % p]);
    let config = RbfConfig {
        scaling: rbf_scaling(analysis)?,
        smoothing: RbfSmoothing::Loo,
        ..RbfConfig::default()
    };
    Ok(Rbf::fit(analysis.control_matrix().as_ref(), values.as_ref(), &config)?.smoothing())
}

/// The control scaling of the RBF baselines: the kriging's, with the controls that the build's
/// selection dropped for carrying no signal put back (standardised). Rose et al. interpolate over
/// every control that varies, and an exact RBF over fewer controls is singular wherever cycles share
/// the kept ones (several cycles of one take).
fn rbf_scaling(analysis: &Analysis) -> Result<ScalingChoice, BuildError> {
    let params = analysis.control_matrix();
    let all = ParamScaling::standardise(params.as_ref())?;
    let mut scaling = analysis.kriging.scaling().clone();
    for k in 0..scaling.scale.len() {
        if scaling.scale[k] == 0.0 && all.scale[k] > 0.0 {
            scaling.scale[k] = all.scale[k];
            scaling.offset[k] = all.offset[k];
        }
    }
    Ok(ScalingChoice::Given(scaling))
}

/// Leave-one-out weights of universal kriging (`rbf` `None`) or of the RBF baseline (`rbf` its
/// smoothing), both
/// with the analysis's control scaling (kriging also with its variogram): the methods fitted to the
/// identity values, so that their leave-one-out errors are `I - W`.
fn loo_weights(analysis: &Analysis, rbf: Option<f64>) -> Result<Mat<f64>, BuildError> {
    let k = &analysis.kriging;
    let s = k.n_samples();
    let params = analysis.control_matrix();
    let identity = Mat::<f64>::identity(s, s);
    let scaling = ScalingChoice::Given(k.scaling().clone());
    let errors = if let Some(lambda) = rbf {
        let config = RbfConfig {
            scaling: rbf_scaling(analysis)?,
            smoothing: RbfSmoothing::Fixed(lambda),
            ..RbfConfig::default()
        };
        Rbf::fit(params.as_ref(), identity.as_ref(), &config)?.loo_errors()?
    } else {
        let config = KrigingConfig {
            model: ModelChoice::Given(*k.variogram()),
            scaling,
            ..KrigingConfig::default()
        };
        Kriging::fit(params.as_ref(), identity.as_ref(), &config)?.loo_errors()?
    };
    Ok(loo_weights_from_errors(errors.as_ref()))
}

/// Sample weights of universal kriging (`rbf` `None`) or RBF (`rbf` its smoothing) at new `controls`: the method
/// fitted to the identity values predicts exactly its weights on the samples (H x S).
fn prediction_weights(
    analysis: &Analysis,
    controls: &[Vec<f64>],
    rbf: Option<f64>,
) -> Result<Mat<f64>, BuildError> {
    let k = &analysis.kriging;
    let s = k.n_samples();
    let params = analysis.control_matrix();
    let identity = Mat::<f64>::identity(s, s);
    let scaling = ScalingChoice::Given(k.scaling().clone());
    let mut w = Mat::zeros(controls.len(), s);
    let mut row = vec![0.0; s];
    if let Some(lambda) = rbf {
        let config = RbfConfig {
            scaling: rbf_scaling(analysis)?,
            smoothing: RbfSmoothing::Fixed(lambda),
            ..RbfConfig::default()
        };
        let fit = Rbf::fit(params.as_ref(), identity.as_ref(), &config)?;
        for (h, c) in controls.iter().enumerate() {
            fit.predict(c, &mut row)?;
            (0..s).for_each(|j| w[(h, j)] = row[j]);
        }
    } else {
        let config = KrigingConfig {
            model: ModelChoice::Given(*k.variogram()),
            scaling,
            ..KrigingConfig::default()
        };
        let fit = Kriging::fit(params.as_ref(), identity.as_ref(), &config)?;
        for (h, c) in controls.iter().enumerate() {
            fit.predict(c, &mut row)?;
            (0..s).for_each(|j| w[(h, j)] = row[j]);
        }
    }
    Ok(w)
}

/// Weight 1 on the training sample nearest each of `controls` in scaled control space.
fn nearest_to(analysis: &Analysis, controls: &[Vec<f64>]) -> Mat<f64> {
    let k = &analysis.kriging;
    let c = k.scaled_params();
    let mut w = Mat::zeros(controls.len(), c.nrows());
    let mut q = vec![0.0; c.ncols()];
    for (h, ctl) in controls.iter().enumerate() {
        k.scaling().apply(ctl, &mut q);
        let nearest = (0..c.nrows())
            .map(|j| {
                (0..c.ncols())
                    .map(|d| (c[(j, d)] - q[d]).powi(2))
                    .sum::<f64>()
            })
            .enumerate()
            .fold(
                (0, f64::INFINITY),
                |best, (j, d)| if d < best.1 { (j, d) } else { best },
            );
        w[(h, nearest.0)] = 1.0;
    }
    w
}

/// Nearest other sample in scaled control space (ties: the lower index).
fn nearest_weights(analysis: &Analysis) -> Mat<f64> {
    let c = analysis.kriging.scaled_params();
    let s = c.nrows();
    let mut w = Mat::zeros(s, s);
    for i in 0..s {
        let mut best = (f64::INFINITY, i);
        for j in (0..s).filter(|&j| j != i) {
            let d: f64 = (0..c.ncols())
                .map(|k| (c[(i, k)] - c[(j, k)]).powi(2))
                .sum();
            if d < best.0 {
                best = (d, j);
            }
        }
        if best.1 != i {
            w[(i, best.1)] = 1.0;
        }
    }
    w
}

/// `X x3 W` for a `P x T x S` tensor seen as the `(P T) x S` matrix of its samples: sample `i` of the
/// result is `sum_j W[i, j] X_j`.
fn blend_samples(x: &Tensor3, w: MatRef<'_, f64>) -> Tensor3 {
    x.mode_product(2, w)
}

/// The samples projected on the first `rank` principal directions of the DOF mode (PCA of the mode-0
/// unfolding, without centring, as the paper's matrix SVD).
fn pca_projection(x: &Tensor3, rank: usize) -> Result<Tensor3, BuildError> {
    let u = crate::pca::pca_basis(x, rank)?;
    let proj = u.as_ref() * u.transpose();
    Ok(x.mode_product(0, proj.as_ref()))
}

/// Mean joint and largest shell error of the predicted samples (every `stride`-th) against `targets`.
fn score(analysis: &Analysis, targets: &Tensor3, predicted: &Tensor3, stride: usize) -> (f64, f64) {
    let mut meter = ErrorMeter::new(&analysis.layout);
    for i in (0..targets.dims()[2]).step_by(stride) {
        meter.compare_sequences(targets.sample(i), predicted.sample(i));
    }
    let e = meter.total();
    (e.mean_joint_cm, e.shell_cm)
}

/// Mean joint error of the predicted samples (every `stride`-th) that `keep` selects.
fn score_where(
    analysis: &Analysis,
    targets: &Tensor3,
    predicted: &Tensor3,
    stride: usize,
    keep: &dyn Fn(usize) -> bool,
) -> f64 {
    let mut meter = ErrorMeter::new(&analysis.layout);
    for i in (0..targets.dims()[2]).step_by(stride).filter(|&i| keep(i)) {
        meter.compare_sequences(targets.sample(i), predicted.sample(i));
    }
    meter.total().mean_joint_cm
}

/// Reconstruction of every predicted sample at a multilinear level from sample weights `W` (one row per
/// prediction): `Z x1 U_P x2 U_T x3 (W U_S)`.
fn multilinear_prediction(tucker: &Tucker, w: MatRef<'_, f64>) -> Tensor3 {
    let u_s = w * tucker.factors[2].as_ref();
    tensor_ops::reconstruct(
        &tucker.core,
        [
            tucker.factors[0].as_ref(),
            tucker.factors[1].as_ref(),
            u_s.as_ref(),
        ],
    )
}

/// The sample weights of each method, one row per predicted cycle (H x S).
struct Weights {
    kriging: Mat<f64>,
    rbf: Mat<f64>,
    rbf_smoothed: Mat<f64>,
    nearest: Mat<f64>,
}

/// Every method's error when predicting `targets` (P x T x H, in the analysis's layout) with `weights`;
/// with `styles` (each target's style, an index into the analysis's style names), also each style's.
#[allow(clippy::too_many_arguments)]
fn compare(
    analysis: &Analysis,
    weights: &Weights,
    targets: &Tensor3,
    styles: Option<&[usize]>,
    model_bytes: usize,
    key_bytes: &[usize],
    config: &EvalConfig,
    progress: &dyn Progress,
) -> Result<EvalReport, BuildError> {
    let x = &analysis.tensor;
    let [p, t, s] = x.dims();
    let h = targets.dims()[2];
    let raw_bytes = p * t * s * 8;
    let stride = config
        .max_samples
        .map_or(1, |m| h.div_ceil(m.max(1)).max(1));
    let evaluated = (0..h).step_by(stride).count();
    let keys = &analysis.keys.levels;
    let mut per_style = Vec::new();
    if let (Some(labels), Some(of)) = (&analysis.styles, styles) {
        let level0 = keys
            .first()
            .map(|k| multilinear_prediction(&k.tucker, weights.kriging.as_ref()));
        let naive = blend_samples(x, weights.kriging.as_ref());
        for (j, name) in labels.names.iter().enumerate() {
            let keep = |i: usize| of.get(i) == Some(&j);
            let n = (0..h).step_by(stride).filter(|&i| keep(i)).count();
            if n == 0 {
                continue;
            }
            per_style.push(StyleError {
                style: name.clone(),
                evaluated: n,
                level0_cm: level0.as_ref().map_or(f64::NAN, |p| {
                    score_where(analysis, targets, p, stride, &keep)
                }),
                naive_cm: score_where(analysis, targets, &naive, stride, &keep),
            });
        }
    }
    progress.stage("evaluation", (keys.len() + 5) as u64);
    let w_krig = weights.kriging.as_ref();
    let mut methods = Vec::new();
    let mut push = |name: &str, level, ranks, predicted: &Tensor3, bytes| {
        let (error_cm, shell_cm) = score(analysis, targets, predicted, stride);
        methods.push(MethodError {
            name: name.into(),
            level,
            ranks,
            error_cm,
            shell_cm,
            bytes,
        });
        progress.inc(1);
    };
    for (k, key) in keys.iter().enumerate() {
        let level = analysis
            .levels
            .iter()
            .position(|l| l.key == k && l.ranks == key.ranks);
        let bytes = key_bytes.get(k).copied().unwrap_or(0);
        let predicted = multilinear_prediction(&key.tucker, w_krig);
        push("multilinear", level, Some(key.ranks), &predicted, bytes);
    }
    push(
        "naive-kriging",
        None,
        None,
        &blend_samples(x, w_krig),
        raw_bytes,
    );
    push(
        "rbf",
        None,
        None,
        &blend_samples(x, weights.rbf.as_ref()),
        raw_bytes,
    );
    push(
        "rbf-smoothed",
        None,
        None,
        &blend_samples(x, weights.rbf_smoothed.as_ref()),
        raw_bytes,
    );
    let r_pca = config.pca_rank.clamp(1, p);
    let pca = blend_samples(&pca_projection(x, r_pca)?, w_krig);
    push(
        "pca",
        None,
        Some([r_pca, t, s]),
        &pca,
        (r_pca * t * s + p * r_pca) * 8,
    );
    push(
        "nearest",
        None,
        None,
        &blend_samples(x, weights.nearest.as_ref()),
        raw_bytes,
    );
    Ok(EvalReport {
        samples: s,
        evaluated,
        raw_bytes,
        model_bytes,
        methods,
        styles: per_style,
    })
}

/// Leave-one-out errors of every method on the analysis's samples (see the module documentation).
pub fn leave_one_out(
    analysis: &Analysis,
    model_bytes: usize,
    key_bytes: &[usize],
    config: &EvalConfig,
    progress: &dyn Progress,
) -> Result<EvalReport, BuildError> {
    config.check()?;
    let weights = Weights {
        kriging: loo_weights(analysis, None)?,
        rbf: loo_weights(analysis, Some(0.0))?,
        rbf_smoothed: loo_weights(analysis, Some(rbf_smoothing(analysis)?))?,
        nearest: nearest_weights(analysis),
    };
    let styles = analysis.styles.as_ref().map(|l| l.of_sample.clone());
    compare(
        analysis,
        &weights,
        &analysis.tensor,
        styles.as_deref(),
        model_bytes,
        key_bytes,
        config,
        progress,
    )
}

/// Errors of every method on held-out cycles: `targets` (P x T x H, prepared with
/// [`Analysis::prepare`]) predicted from all training samples at their `controls` and, for an
/// analysis with styles, their `styles` (each an index into the analysis's style names).
#[allow(clippy::too_many_arguments)]
pub fn held_out(
    analysis: &Analysis,
    targets: &Tensor3,
    controls: &[[f64; 4]],
    styles: Option<&[usize]>,
    model_bytes: usize,
    key_bytes: &[usize],
    config: &EvalConfig,
    progress: &dyn Progress,
) -> Result<EvalReport, BuildError> {
    config.check()?;
    if targets.dims()[2] != controls.len() || targets.dims()[..2] != analysis.tensor.dims()[..2] {
        return Err(BuildError::Data(format!(
            "held-out tensor {:?} with {} control rows does not fit the model's {:?}",
            targets.dims(),
            controls.len(),
            analysis.tensor.dims()
        )));
    }
    // Each held-out cycle's parameters as the analysis's samples have them
    // ([`crate::dataset::control_matrix`]: the controls, then the style's one-hot code).
    let held_labels = match (&analysis.styles, styles) {
        (None, _) => None,
        (Some(labels), Some(st))
            if st.len() == controls.len() && st.iter().all(|&j| j < labels.len()) =>
        {
            Some(crate::style::StyleLabels {
                names: labels.names.clone(),
                of_sample: st.to_vec(),
            })
        }
        (Some(labels), st) => {
            return Err(BuildError::Data(format!(
                "the model has {} styles: every held-out cycle needs one of them ({} given for {} cycles)",
                labels.len(),
                st.map_or(0, <[usize]>::len),
                controls.len()
            )));
        }
    };
    let params = crate::dataset::control_matrix(controls, held_labels.as_ref());
    let controls: Vec<Vec<f64>> = (0..params.nrows())
        .map(|i| (0..params.ncols()).map(|k| params[(i, k)]).collect())
        .collect();
    let controls = controls.as_slice();
    let weights = Weights {
        kriging: prediction_weights(analysis, controls, None)?,
        rbf: prediction_weights(analysis, controls, Some(0.0))?,
        rbf_smoothed: prediction_weights(analysis, controls, Some(rbf_smoothing(analysis)?))?,
        nearest: nearest_to(analysis, controls),
    };
    compare(
        analysis,
        &weights,
        targets,
        styles,
        model_bytes,
        key_bytes,
        config,
        progress,
    )
}

pub use crate::folds::FoldBy;

/// The fold of every sample: by take, the distinct takes in name order dealt round-robin to the
/// `folds` folds; by sample, `i mod folds` ([`crate::folds::fold_of_samples`]). Errors when there
/// are fewer takes (or samples) than folds.
pub fn fold_of_samples(
    sources: &[String],
    folds: usize,
    by: FoldBy,
) -> Result<Vec<usize>, BuildError> {
    crate::folds::fold_of_samples(sources, folds, by).map_err(BuildError::Data)
}

/// The result of [`k_fold`]: every method's error over all held-out cycles, each predicted by a
/// model refitted on the other folds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FoldReport {
    /// Folds `K`.
    pub folds: usize,
    /// How the samples were split.
    pub by: FoldBy,
    /// Held-out samples per fold.
    pub fold_sizes: Vec<usize>,
    /// The pooled result: `samples` is the whole set, `evaluated` the held-out cycles scored over
    /// all folds, `error_cm` their mean and `shell_cm` their largest; ranks and bytes are the first
    /// fold's model's.
    pub pooled: EvalReport,
}

/// K-fold cross-validation by refitting: for each fold, the whole pipeline ([`Analysis::run_guarded`]:
/// joint order, row weights, key levels, the variogram chosen by leave-one-out on the training
/// folds, and in the comparison the RBF smoothing and the PCA basis) is fitted on the other folds
/// with `build`, and every method predicts the fold's cycles at their own controls
/// ([`held_out`]). Nothing of a held-out cycle enters its prediction except through the time
/// alignment of the data set (the reference cycle and `T`), which is fixed before the split. The
/// folds are refitted in parallel and pooled in fold order: the same report on any thread count.
pub fn k_fold(
    set: &crate::build::TrainingSet,
    build: &crate::build::BuildConfig,
    folds: usize,
    by: FoldBy,
    config: &EvalConfig,
    progress: &dyn Progress,
) -> Result<FoldReport, BuildError> {
    set.validate()?;
    config.check()?;
    let fold = fold_of_samples(&set.sources, folds, by)?;
    // The folds are independent refits: they run in parallel and are pooled in fold order, so the
    // report is the same for any pool size.
    progress.stage("folds (each a refit of the model)", folds as u64);
    let reports: Vec<Result<(usize, EvalReport), BuildError>> = (0..folds)
        .into_par_iter()
        .map(|f| {
            let (test, train): (Vec<usize>, Vec<usize>) =
                (0..fold.len()).partition(|&i| fold[i] == f);
            let training = set.select(&train);
            let held = set.select(&test);
            let quiet = crate::progress::NoProgress;
            let analysis = Analysis::run_guarded(&training, build, &quiet)?;
            let model = analysis.runtime_model(build, &quiet)?;
            let key_bytes: Vec<usize> = (0..model.lod().keys().len())
                .map(|k| model.lod().key_bytes(k, lod_policy::Precision::F64))
                .collect();
            let model_bytes = crate::storage::Storage::of(&model).model_f64;
            let targets = analysis.prepare(&set.layout, &held.tensor)?;
            let report = held_out(
                &analysis,
                &targets,
                &held.controls,
                held.styles.as_ref().map(|l| l.of_sample.as_slice()),
                model_bytes,
                &key_bytes,
                config,
                &quiet,
            )?;
            progress.inc(1);
            Ok((test.len(), report))
        })
        .collect();
    let mut pooled: Option<EvalReport> = None;
    let mut weights: Vec<f64> = Vec::new();
    let mut fold_sizes = Vec::with_capacity(folds);
    for (f, result) in reports.into_iter().enumerate() {
        let (size, report) = result?;
        fold_sizes.push(size);
        let n = report.evaluated as f64;
        match &mut pooled {
            None => {
                weights = vec![n; report.methods.len()];
                pooled = Some(EvalReport {
                    samples: set.tensor.dims()[2],
                    ..report
                });
            }
            Some(p) => {
                if p.methods.len() != report.methods.len()
                    || p.methods
                        .iter()
                        .zip(&report.methods)
                        .any(|(a, b)| a.name != b.name)
                {
                    return Err(BuildError::Data(format!(
                        "fold {f} built a different set of key levels than fold 0; \
                         use fewer key levels or more data per fold"
                    )));
                }
                p.evaluated += report.evaluated;
                for r in &report.styles {
                    match p.styles.iter_mut().find(|q| q.style == r.style) {
                        Some(q) => {
                            let (a, b) = (q.evaluated as f64, r.evaluated as f64);
                            q.level0_cm = (q.level0_cm * a + r.level0_cm * b) / (a + b);
                            q.naive_cm = (q.naive_cm * a + r.naive_cm * b) / (a + b);
                            q.evaluated += r.evaluated;
                        }
                        None => p.styles.push(r.clone()),
                    }
                }
                for ((m, w), r) in p.methods.iter_mut().zip(&mut weights).zip(&report.methods) {
                    m.error_cm = (m.error_cm * *w + r.error_cm * n) / (*w + n);
                    m.shell_cm = m.shell_cm.max(r.shell_cm);
                    *w += n;
                }
            }
        }
    }
    Ok(FoldReport {
        folds,
        by,
        fold_sizes,
        pooled: pooled.expect("at least two folds"),
    })
}
