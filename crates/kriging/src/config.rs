//! Configuration of [`crate::Kriging::fit`] and the reports it produces.

use serde::{Deserialize, Serialize};

use crate::fit::FitWeights;
use crate::scaling::ScalingChoice;
use crate::variogram::{Variogram, VariogramModel};

/// Which kriging estimator [`crate::Kriging`] builds.
///
/// ```
/// use kriging::faer::Mat;
/// use kriging::{Kriging, KrigingConfig, Method, ModelChoice, ScalingChoice};
/// use kriging::{Variogram, VariogramModel};
///
/// // Samples of a plane over a 2-D parameter space.
/// let c: [[f64; 2]; 6] = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [0.3, 0.6], [0.7, 0.2]];
/// let plane = |p: [f64; 2]| 2.0 + p[0] - 3.0 * p[1];
/// let params = Mat::from_fn(6, 2, |i, k| c[i][k]);
/// let values = Mat::from_fn(6, 1, |i, _| plane(c[i]));
/// // Plane values leave nothing to fit a variogram to under regression kriging: give one.
/// let v = Variogram::new(VariogramModel::Spherical, 0.0, 1.0, 1.5, 1.0)?;
/// let fit = |method| {
///     let config = KrigingConfig {
///         method,
///         model: ModelChoice::Given(v),
///         scaling: ScalingChoice::None,
///         ..KrigingConfig::default()
///     };
///     Kriging::fit(params.as_ref(), values.as_ref(), &config)
/// };
/// let mut x = [0.0];
/// // Regression kriging: the least-squares trend carries the plane, even far from the samples.
/// fit(Method::Regression)?.predict(&[5.0, -4.0], &mut x)?;
/// assert!((x[0] - plane([5.0, -4.0])).abs() < 1e-9);
/// // Ordinary kriging falls back to a constant beyond the range.
/// fit(Method::Ordinary)?.predict(&[5.0, -4.0], &mut x)?;
/// assert!((x[0] - plane([5.0, -4.0])).abs() > 10.0);
/// # Ok::<(), kriging::KrigingError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum Method {
    /// Ordinary kriging of the values (appendix A system with the Lagrange multiplier).
    Ordinary,
    /// Regression kriging, the paper's "universal kriging" (eq. 8): an ordinary least-squares trend
    /// hyperplane `F = K C^+` over `[c; 1]`, then ordinary kriging of the residuals; the prediction
    /// is `F [c; 1] + sum_i b_i(c) r_i`. It is not the textbook universal kriging predictor (the
    /// best linear unbiased predictor with drift terms inside the kriging system, which estimates
    /// the trend by generalised least squares): for that, and for kriging variances, see
    /// [`crate::Krige`] with [`crate::Drift::Linear`]. Serialised as `"Regression"` (older
    /// `"Universal"` is read as this).
    #[default]
    #[serde(alias = "Universal")]
    Regression,
}

#[allow(non_upper_case_globals)]
impl Method {
    /// The old name of [`Method::Regression`] (the paper calls it universal kriging).
    #[deprecated(
        note = "this is regression kriging (OLS trend plus ordinary kriging of the residuals): use \
                Method::Regression, or kriging::Krige with a Drift for textbook universal kriging"
    )]
    pub const Universal: Method = Method::Regression;
}

/// How automatic model choice ranks the candidate variogram models.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum Selection {
    /// Smallest weighted squared error of the fit to the empirical variogram.
    BestFit,
    /// Smallest leave-one-out RMSE of the predictions (closed form, no refits).
    BestLoo,
    /// Smallest leave-one-out RMSE over the fitted models and a grid of ranges and nuggets
    /// ([`crate::search`]): the shape that predicts held-out samples best, fitted or not.
    #[default]
    LooSearch,
}

/// Which variogram the kriging system uses.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum ModelChoice {
    /// Fit every [`VariogramModel`] and keep the best by the given criterion.
    Auto(Selection),
    /// Fit this model.
    Fixed(VariogramModel),
    /// Use this variogram as it is (no fit; the empirical variogram is not computed).
    Given(Variogram),
}

impl Default for ModelChoice {
    fn default() -> Self {
        ModelChoice::Auto(Selection::LooSearch)
    }
}

/// Everything [`crate::Kriging::fit`] needs besides the data.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct KrigingConfig {
    /// Ordinary or regression kriging.
    pub method: Method,
    /// Variogram model choice.
    pub model: ModelChoice,
    /// Number of distance intervals `S_I` of the empirical variogram, at least 1 and at most
    /// [`crate::MAX_BINS`] (not used with [`ModelChoice::Given`]).
    pub bins: usize,
    /// Per-dimension scaling of the parameters.
    pub scaling: ScalingChoice,
    /// Fit a nugget (`>= 0`); when false the nugget is 0.
    pub nugget: bool,
    /// Interval weights of the variogram fit.
    pub fit_weights: FitWeights,
}

impl KrigingConfig {
    /// The preset of the motion model (Mukai and Kuriyama): the paper's regression kriging over
    /// standardised controls with the variogram chosen by leave-one-out search. The same as
    /// [`KrigingConfig::default`], named for what it is for; for maps see [`crate::Krige`].
    ///
    /// ```
    /// use kriging::faer::Mat;
    /// use kriging::{Kriging, KrigingConfig, Method, ModelChoice, ScalingChoice, Selection};
    ///
    /// let config = KrigingConfig::motion();
    /// assert_eq!(config, KrigingConfig::default());
    /// assert_eq!(config.method, Method::Regression); // trend over the controls, then kriging
    /// assert_eq!(config.model, ModelChoice::Auto(Selection::LooSearch));
    /// assert_eq!(config.scaling, ScalingChoice::Standardise);
    ///
    /// // Controls (dx, dz) of 12 cycles and one pose value each: a linear trend in the controls
    /// // plus a per-cycle wobble the controls do not explain (a performer's style).
    /// let controls = Mat::from_fn(12, 2, |i, k| if k == 0 { (i % 4) as f64 * 0.1 } else { 1.0 + (i / 4) as f64 * 0.2 });
    /// let values = Mat::from_fn(12, 1, |i, _| {
    ///     2.0 * controls[(i, 0)] - controls[(i, 1)] + 0.01 * (7.0 * i as f64).sin()
    /// });
    /// let k = Kriging::fit(controls.as_ref(), values.as_ref(), &config)?;
    /// let mut x = [0.0];
    /// k.predict(&[0.15, 1.3], &mut x)?;
    /// assert!((x[0] - (2.0 * 0.15 - 1.3)).abs() < 0.02); // the trend, within the wobble
    /// # Ok::<(), kriging::KrigingError>(())
    /// ```
    pub fn motion() -> Self {
        KrigingConfig::default()
    }
}

impl Default for KrigingConfig {
    /// Regression kriging (the paper's), model chosen by leave-one-out error, 20 intervals, standardised
    /// parameters, nugget fitted, pair-count weights.
    fn default() -> Self {
        KrigingConfig {
            method: Method::Regression,
            model: ModelChoice::default(),
            bins: 20,
            scaling: ScalingChoice::Standardise,
            nugget: true,
            fit_weights: FitWeights::PairCounts,
        }
    }
}

/// Leave-one-out cross validation: the prediction error at each sample when the model is built
/// from the other `S - 1` samples (same variogram and scaling; the trend is refitted).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LooReport {
    /// `sqrt(1/S sum_k |e_k|^2)` with `e_k` the error vector at sample `k`.
    pub rmse: f64,
    /// `|e_k|` (Euclidean norm over the value dimensions) per sample.
    pub per_sample: Vec<f64>,
}

impl LooReport {
    /// Builds the report from per-sample error norms.
    pub(crate) fn from_norms(per_sample: Vec<f64>) -> Self {
        let n = per_sample.len().max(1) as f64;
        let rmse = (per_sample.iter().map(|e| e * e).sum::<f64>() / n).sqrt();
        LooReport { rmse, per_sample }
    }
}

/// What automatic (or fixed) model choice found for one candidate model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CandidateReport {
    /// The candidate model.
    pub model: VariogramModel,
    /// The fitted variogram, when the fit succeeded.
    pub variogram: Option<Variogram>,
    /// Weighted squared error of the fit.
    pub wsse: Option<f64>,
    /// Leave-one-out RMSE (computed for [`Selection::BestLoo`]).
    pub loo_rmse: Option<f64>,
    /// Why the candidate was rejected, if it was.
    pub error: Option<String>,
    /// Which fitted parameters ended at a bound ([`crate::FitBounds`]); `None` when the
    /// candidate was not fitted (or in reports saved before this field existed).
    #[serde(default)]
    pub bounds: Option<crate::FitBounds>,
}
