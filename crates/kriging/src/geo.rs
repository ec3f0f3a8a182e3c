//! Geostatistics front end: simple, ordinary, universal and external-drift kriging of a scalar
//! field over 1-, 2- or 3-D coordinates, with kriging variances, leave-one-out diagnostics,
//! geometric anisotropy and an optional moving neighbourhood.
//!
//! # The estimator
//!
//! With covariance `C(h) = K - gamma(h)` (`K` the total sill of a bounded variogram; for unbounded
//! variograms any `K` large enough for a positive definite sample matrix, which leaves the predictor
//! and its variance unchanged because the weights sum to one), drift basis `f(x)` (p terms: the
//! constant, then the coordinates for a linear drift, their products for a quadratic drift, then the
//! external variables), sample covariances `C` (n x n), drift matrix `F` (n x p) and data `z`, the
//! universal kriging weights `lambda` and Lagrange multipliers `mu` at `x` solve
//!
//! ```text
//! [ C   F ] [lambda]   [c(x)]
//! [ F^t 0 ] [  mu  ] = [f(x)]      (c_i(x) = C(|x - x_i|), C(0) = K: exact at the samples)
//! ```
//!
//! which gives the prediction `z*(x) = f(x)^t beta + c(x)^t alpha` with the generalised
//! least-squares drift `beta = (F^t C^-1 F)^-1 F^t C^-1 z` and `alpha = C^-1 (z - F beta)`, and the
//! kriging variance
//!
//! ```text
//! sigma^2(x) = K - c^t C^-1 c + (f - F^t C^-1 c)^t (F^t C^-1 F)^-1 (f - F^t C^-1 c)
//!            = sum_i lambda_i gamma(x, x_i) + sum_k mu_k f_k(x)      (semivariogram form)
//! ```
//!
//! Ordinary kriging is the case `f = 1`. This is the textbook best linear unbiased predictor (the
//! drift is estimated jointly with the weights), not the regression kriging of [`crate::Kriging`]
//! (an ordinary least-squares trend, then ordinary kriging of its residuals).
//!
//! # Simple kriging
//!
//! With a known constant mean `m` ([`Krige::simple`]) there is no drift to estimate (p = 0, no
//! Lagrange row): the weights solve the covariance system alone, and
//!
//! ```text
//! C lambda = c(x)                                   (C(h) = K - gamma(h), K = nugget + sill)
//! z*(x)      = m + lambda^t (z - m) = m + c(x)^t C^-1 (z - m)
//! sigma^2(x) = C(0) - lambda^t c(x) = K - c(x)^t C^-1 c(x)
//! ```
//!
//! Here `K` must be the total sill: the covariance is only defined for a bounded (sill-reaching)
//! variogram, so the linear and power models are refused ([`KrigingError::InvalidVariogram`]).
//! Beyond the range `c(x) = 0`: the prediction is the mean and the variance the total sill.
//!
//! # Measurement error
//!
//! By default the nugget is microscale variation and kriging is exact: `c_i(x_i) = C(0) = K`, so a
//! prediction at a sample is its value with variance 0. With [`Krige::measurement_error`] the
//! nugget `c0` is the variance of independent measurement errors, `z_i = S(x_i) + e_i`, and the
//! target is the error-free signal `S` (GSTools' `exact=False` with `cond_err="nugget"`). The
//! kriging matrix is unchanged (`C_ii = K = c0 + sill`, `C_ij = K - c0 - gamma_s(h_ij)` for
//! `i != j`, duplicates included), but the right-hand side is the signal covariance at every
//! distance, the origin included:
//!
//! ```text
//! c_i(x) = K - c0 - gamma_s(|x - x_i|)        (gamma_s = gamma - c0, continuous, 0 at 0)
//! [ C   F ] [lambda]   [c(x)]
//! [ F^t 0 ] [  mu  ] = [f(x)]                  z*(x) = lambda^t z   (simple: m + lambda^t (z - m))
//! sigma^2(x) = K - c^t C^-1 c + (f - F^t C^-1 c)^t (F^t C^-1 F)^-1 (f - F^t C^-1 c)
//!            = sum_i lambda_i gamma_me(x - x_i) + sum_k mu_k f_k(x)   (semivariogram form, drift)
//! ```
//!
//! where `gamma_me(h) = c0 + gamma_s(h)` is the variogram without its drop to 0 at the origin (the
//! semivariogram form needs `sum_i lambda_i = 1`, i.e. a drift; it has the sign of `mu` of the
//! semivariogram system, as in the exact case above).
//!
//! The reported variance follows GSTools (`krige_var = sill - k^t A^-1 k` with `sill` the *total*
//! sill `nugget + var`): it is `E[(Z_new(x) - z*(x))^2]`, the mean squared error of predicting a new
//! measurement at `x` with its own independent error. The variance of the error-free signal,
//! `E[(S(x) - z*(x))^2]`, is that minus the nugget `c0`; subtract it where that is wanted. With
//! measurement error the predictions are smoothed at the samples and the variance there is at
//! least the nugget. Coinciding samples are allowed with a positive nugget (the matrix stays
//! regular: `C_ii - C_ij = c0`), and a pure-nugget variogram (no structure, `c0 > 0`) is allowed:
//! `c(x) = 0`, so the prediction is the (generalised least-squares) drift everywhere. Without a
//! nugget the two forms coincide. Leave-one-out is the same closed form in both modes, since the
//! right-hand side at a held-out sample is its column of `C` (which already carries the signal
//! covariance off the diagonal).
//!
//! Numerics: `C = L L^t` (Cholesky), `F_w = L^-1 F`, `F^t C^-1 F = F_w^t F_w = R R^t`; a query costs
//! one triangular solve `v = L^-1 c(x)` (n^2 multiply-adds) for the variance and `O(n p)` for the
//! prediction. Coordinates are centred on their mean and the drift terms are built from coordinates
//! divided by their largest extent (and external variables standardised), so that the drift system
//! is well conditioned whatever the units; the variogram and every result stay in the user's units.
//! An ill-conditioned drift system (for example a quadratic drift on collinear samples) is an error
//! ([`KrigingError::IllConditionedDrift`]); a merely poor one is reported in
//! [`KrigeModel::warnings`].

use faer::{Mat, MatRef, Par};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::anisotropy::Anisotropy;
use crate::config::CandidateReport;
use crate::empirical::{Binning, EmpiricalVariogram};
use crate::error::KrigingError;
use crate::fit::{FitOptions, FitWeights, fit_variogram};
use crate::kdtree::KdTree;
use crate::linalg::{matmul, sym_eigen, sym_pinv};
use crate::nested::NestedVariogram;
use crate::variogram::VariogramModel;

/// Points per block of a batch prediction: blocks are fixed by position, so the results do not
/// depend on the number of threads.
const BLOCK: usize = 64;
/// Smallest eigenvalue ratio of the drift system `F^t C^-1 F` accepted.
const DRIFT_RATIO_MIN: f64 = 1e-12;
/// Below this eigenvalue ratio a warning is recorded.
const DRIFT_RATIO_WARN: f64 = 1e-8;
/// Smallest `(min L_kk / max L_kk)^2` of the covariance Cholesky factor accepted.
const PIVOT_RATIO_MIN: f64 = 1e-14;
/// Largest global system built without a neighbourhood (bytes of the n x n covariance factor).
const GLOBAL_MAX_BYTES: usize = 4 << 30;

/// The deterministic part of the model (the drift) of universal kriging; external drift variables
/// come on top through [`Krige::fit_with_external`].
///
/// Universal kriging reproduces its drift exactly: samples of a plane are predicted without error
/// with a linear drift, even far outside the samples, whatever the variogram.
///
/// ```
/// use kriging::faer::Mat;
/// use kriging::{Drift, Krige, NestedVariogram, VariogramModel};
///
/// let plane = |x: f64, y: f64| 3.0 + 0.5 * x - 0.25 * y;
/// let xy = [[0.0, 0.0], [10.0, 0.0], [0.0, 10.0], [10.0, 10.0], [3.0, 7.0], [6.0, 2.0]];
/// let coords = Mat::from_fn(6, 2, |i, k| xy[i][k]);
/// let z: Vec<f64> = xy.iter().map(|p| plane(p[0], p[1])).collect();
/// let v = NestedVariogram::single(VariogramModel::Gaussian, 0.0, 1.0, 8.0)?;
/// let uk = Krige::new().drift(Drift::Linear).variogram(v.clone()).fit(coords.as_ref(), &z)?;
/// let far = uk.predict(&[40.0, -25.0])?;
/// assert!((far.value - plane(40.0, -25.0)).abs() < 1e-8);
/// assert!(far.variance > 0.0);
/// assert_eq!(uk.drift_coefficients().map(|b| b.len()), Some(Drift::Linear.n_terms(2)));
/// // Ordinary kriging (constant drift) reverts to the mean far away instead.
/// let ok = Krige::new().variogram(v).fit(coords.as_ref(), &z)?;
/// let mean = z.iter().sum::<f64>() / 6.0;
/// assert!((ok.predict(&[40.0, -25.0])?.value - plane(40.0, -25.0)).abs() > 5.0);
/// assert!((ok.predict(&[400.0, -250.0])?.value - mean).abs() < 1.0);
/// # Ok::<(), kriging::KrigingError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum Drift {
    /// An unknown constant mean: ordinary kriging.
    #[default]
    Constant,
    /// `1, x_1, ..., x_d`: universal kriging with a linear drift.
    Linear,
    /// `1, x_k, x_k x_l (k <= l)`: universal kriging with a quadratic drift.
    Quadratic,
}

impl Drift {
    /// Number of drift terms in `d` dimensions (without external variables); saturates at
    /// `usize::MAX` for a `d` so large that the count does not fit.
    pub fn n_terms(self, d: usize) -> usize {
        match self {
            Drift::Constant => 1,
            Drift::Linear => d.saturating_add(1),
            Drift::Quadratic => {
                // In 128 bits: d (d + 1) / 2 overflows usize from d = 2^32 on.
                let d = d as u128;
                usize::try_from(1 + d + d * (d + 1) / 2).unwrap_or(usize::MAX)
            }
        }
    }
}

/// Which samples enter the kriging system of a query.
///
/// ```
/// use kriging::faer::Mat;
/// use kriging::{Krige, KrigingError, Neighbourhood, NestedVariogram, VariogramModel};
///
/// // 40 samples along a line, 1 m apart.
/// let coords = Mat::from_fn(40, 1, |i, _| i as f64);
/// let z: Vec<f64> = (0..40).map(|i| (i as f64 / 5.0).sin()).collect();
/// let v = NestedVariogram::single(VariogramModel::Exponential, 0.0, 1.0, 6.0)?;
/// let krige = Krige::new().variogram(v);
/// let global = krige.clone().fit(coords.as_ref(), &z)?;
///
/// // k = n nearest neighbours is the global system.
/// let all = krige.clone().neighbourhood(Neighbourhood::Nearest { k: 40 }).fit(coords.as_ref(), &z)?;
/// let (a, b) = (global.predict(&[12.5])?, all.predict(&[12.5])?);
/// assert!((a.value - b.value).abs() < 1e-10 && (a.variance - b.variance).abs() < 1e-10);
///
/// // A few neighbours: a local system per query (with its own local mean), still exact at the
/// // samples, and close to the global answer inside the data (the near samples screen the far).
/// let local = krige.clone().neighbourhood(Neighbourhood::Nearest { k: 6 }).fit(coords.as_ref(), &z)?;
/// assert!((local.predict(&[12.5])?.value - a.value).abs() < 0.05);
/// assert!((local.predict(&[7.0])?.value - z[7]).abs() < 1e-12);
///
/// // A radius: a query with too few samples inside it is an error naming the query.
/// let radius = krige.neighbourhood(Neighbourhood::Radius { radius: 3.0, max: 8 });
/// let model = radius.fit(coords.as_ref(), &z)?;
/// assert!(model.predict(&[20.2])?.variance > 0.0);
/// let far = Mat::from_fn(2, 1, |i, _| [20.2, 100.0][i]);
/// assert!(matches!(model.predict_many(far.as_ref()), Err(KrigingError::QueryNeighbourhood { .. })));
/// # Ok::<(), kriging::KrigingError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub enum Neighbourhood {
    /// Every sample: one system factorised at fit time (memory `8 n^2` bytes).
    #[default]
    Global,
    /// The `k` samples nearest to the query (after anisotropy), found with a k-d tree; a small
    /// system is solved per query (memory `O(n)` plus `O(k^2)` per thread).
    Nearest {
        /// Number of neighbours, at least the number of drift terms plus one.
        k: usize,
    },
    /// The samples within `radius` of the query, at most `max` of them (the nearest); a query with
    /// fewer neighbours than drift terms plus one is an error.
    Radius {
        /// Search radius in the coordinates' units (along the major axis under anisotropy).
        radius: f64,
        /// Largest number of neighbours used.
        max: usize,
    },
}

/// Where the variogram of [`Krige::fit`] comes from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum VariogramChoice {
    /// Use this variogram (no fit).
    Given(NestedVariogram),
    /// Fit this model to the empirical variogram (of the ordinary least-squares drift residuals for
    /// universal kriging).
    Fit(VariogramModel),
    /// Fit each of these models and keep the one with the smallest weighted squared error.
    BestFit(Vec<VariogramModel>),
}

/// The settings of a geostatistical kriging model, as a builder; [`Krige::fit`] makes the model.
///
/// Defaults suit maps: ordinary kriging, isotropic, global neighbourhood, the best of a spherical,
/// exponential and gaussian fit (nugget fitted) by weighted least squares with Cressie's weights on
/// 15 bins up to a third of the bounding-box diagonal. For the motion model of Mukai and Kuriyama
/// use [`crate::KrigingConfig::motion`] with [`crate::Kriging`] instead.
///
/// ```
/// use kriging::faer::Mat;
/// use kriging::{Drift, Krige, NestedVariogram, VariogramModel};
///
/// // A few samples of a field over 2-D map coordinates (metres).
/// let xy = [[0.0, 0.0], [100.0, 0.0], [0.0, 100.0], [100.0, 100.0], [40.0, 70.0], [70.0, 20.0]];
/// let z = [1.0, 2.0, 1.5, 3.0, 2.0, 2.2];
/// let coords = Mat::from_fn(6, 2, |i, k| xy[i][k]);
/// let v = NestedVariogram::single(VariogramModel::Spherical, 0.01, 0.5, 150.0)?;
/// let model = Krige::new().drift(Drift::Linear).variogram(v).fit(coords.as_ref(), &z)?;
/// let p = model.predict(&[50.0, 50.0])?;
/// assert!(p.variance > 0.0);
/// let at_sample = model.predict(&[100.0, 0.0])?; // exact at the samples
/// assert!((at_sample.value - 2.0).abs() < 1e-9 && at_sample.variance.abs() < 1e-9);
/// let loo = model.leave_one_out()?;
/// assert_eq!(loo.errors.len(), 6);
/// # Ok::<(), kriging::KrigingError>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Krige {
    /// The drift (default: constant, i.e. ordinary kriging).
    pub drift: Drift,
    /// The variogram, given or fitted.
    pub variogram: VariogramChoice,
    /// Geometric anisotropy (default: isotropic).
    pub anisotropy: Anisotropy,
    /// Which samples each query uses (default: all).
    pub neighbourhood: Neighbourhood,
    /// Binning of the empirical variogram (fit only).
    pub binning: Binning,
    /// Weights of the variogram fit (fit only).
    pub fit_weights: FitWeights,
    /// Whether the fit estimates a nugget (otherwise 0).
    pub fit_nugget: bool,
    /// `Some(m)`: simple kriging with the known mean `m` (see [`Krige::simple`]); `None` (the
    /// default): the mean or drift is estimated (ordinary, universal or external-drift kriging).
    #[serde(default)]
    pub known_mean: Option<f64>,
    /// `true`: the nugget is measurement error (non-exact kriging, see
    /// [`Krige::measurement_error`]); `false` (the default): it is microscale variation and
    /// kriging interpolates the data.
    #[serde(default)]
    pub measurement_error: bool,
}

impl Default for Krige {
    fn default() -> Self {
        Krige {
            drift: Drift::Constant,
            variogram: VariogramChoice::BestFit(vec![
                VariogramModel::Spherical,
                VariogramModel::Exponential,
                VariogramModel::Gaussian,
            ]),
            anisotropy: Anisotropy::Isotropic,
            neighbourhood: Neighbourhood::Global,
            binning: Binning::default(),
            fit_weights: FitWeights::Cressie,
            fit_nugget: true,
            known_mean: None,
            measurement_error: false,
        }
    }
}

/// A prediction and its kriging variance `sigma^2` (see the [module docs](crate::geo)).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Prediction {
    /// `z*(x)`.
    pub value: f64,
    /// `sigma^2(x) >= 0` (0 at a sample; at least the nugget with
    /// [`Krige::measurement_error`]).
    pub variance: f64,
}

/// Predictions at many points, in the order of the points.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Predictions {
    /// `z*(x_q)` per point.
    pub values: Vec<f64>,
    /// `sigma^2(x_q)` per point (empty when variances were not requested).
    pub variances: Vec<f64>,
}

/// Leave-one-out cross validation of a [`KrigeModel`] (variogram fixed, drift re-estimated).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LooStats {
    /// `e_k = z_k - z*_{-k}(x_k)` per sample.
    pub errors: Vec<f64>,
    /// Kriging variance `sigma^2_{-k}(x_k)` of each held-out prediction.
    pub variances: Vec<f64>,
    /// Standardised errors `e_k / sigma_{-k}(x_k)` (about N(0, 1) if the model is right).
    pub standardised: Vec<f64>,
    /// Root mean squared error.
    pub rmse: f64,
    /// Mean error (bias).
    pub mean_error: f64,
    /// Mean squared standardised error (about 1 if the variances are right).
    pub msse: f64,
}

/// How the variogram of a [`KrigeModel`] was obtained by fitting.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct VariogramFitReport {
    /// The empirical variogram (lags in the coordinates' units, along the major axis).
    pub empirical: EmpiricalVariogram,
    /// Every model tried, with its fit or the reason it failed.
    pub candidates: Vec<CandidateReport>,
}

/// What a fitted model is made of (what it serialises to).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct ModelData {
    dim: usize,
    /// Row-major n x dim, as given.
    coords: Vec<f64>,
    values: Vec<f64>,
    n_ext: usize,
    /// Row-major n x n_ext.
    external: Vec<f64>,
    variogram: NestedVariogram,
    drift: Drift,
    anisotropy: Anisotropy,
    neighbourhood: Neighbourhood,
    fit: Option<VariogramFitReport>,
    /// Simple kriging's known mean (absent in models saved before simple kriging existed).
    #[serde(default)]
    known_mean: Option<f64>,
    /// The nugget is measurement error (absent in models saved before the option existed).
    #[serde(default)]
    measurement_error: bool,
}

/// A kriging system over a set of samples (all of them, or one query's neighbours).
#[derive(Debug, Clone)]
struct System {
    idx: Vec<usize>,
    /// Lower Cholesky factor of the covariance matrix (upper part unused).
    l: Mat<f64>,
    /// `L^-1 F` (n x p).
    fw: Mat<f64>,
    /// Lower Cholesky factor of `F_w^t F_w` (p x p).
    r: Mat<f64>,
    beta: Vec<f64>,
    alpha: Vec<f64>,
}

/// Derived state, rebuilt from [`ModelData`].
#[derive(Debug, Clone)]
struct State {
    centre: Vec<f64>,
    /// Row-major d x d anisotropy map.
    amat: Vec<f64>,
    /// Largest extent of the transformed samples (drift terms use coordinates over it).
    scale: f64,
    /// Row-major n x d transformed sample coordinates (user units, centred, anisotropy applied).
    pts: Vec<f64>,
    ext_mean: Vec<f64>,
    ext_sd: Vec<f64>,
    /// Row-major n x p drift basis at the samples.
    fmat: Vec<f64>,
    p: usize,
    /// Covariance shift `K`.
    shift: f64,
    tree: Option<KdTree>,
    global: Option<System>,
    warnings: Vec<String>,
}

/// A fitted geostatistical kriging model (see [`Krige`]).
///
/// Serialises (serde) to its data and settings; deserialising refactorises the system. The
/// reloaded model predicts the same bits as the original when the format reads every `f64` back
/// exactly: binary formats such as bincode, and serde_json built with its `float_roundtrip`
/// feature. serde_json's default float parser can be one ulp off (its documentation says so), and
/// the predictions of a model reloaded through it then differ in their last few bits; enable
/// `serde_json = { version = "1", features = ["float_roundtrip"] }` where bits matter.
///
/// ```
/// use kriging::faer::Mat;
/// use kriging::{Krige, KrigeModel, NestedVariogram, VariogramModel};
///
/// let xy = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [0.3, 0.6]];
/// let coords = Mat::from_fn(5, 2, |i, k| xy[i][k] * 1234.567);
/// let z = [0.1, 0.7, 0.3, 1.1, 1.0 / 3.0];
/// let v = NestedVariogram::single(VariogramModel::Exponential, 0.0, 0.2, 2000.0)?;
/// let model = Krige::new().variogram(v).fit(coords.as_ref(), &z)?;
/// let q = Mat::from_fn(20, 2, |i, k| 100.0 * (i as f64) * [0.61, 0.37][k]);
/// let bits = |m: &KrigeModel| -> Vec<u64> {
///     let p = m.predict_many(q.as_ref()).unwrap();
///     p.values.iter().chain(&p.variances).map(|x| x.to_bits()).collect()
/// };
///
/// let cfg = bincode::config::standard();
/// let bytes = bincode::serde::encode_to_vec(&model, cfg).unwrap();
/// let (back, _): (KrigeModel, usize) = bincode::serde::decode_from_slice(&bytes, cfg).unwrap();
/// assert_eq!(bits(&back), bits(&model));
///
/// // This crate's tests build serde_json with `float_roundtrip`: exact too.
/// let json = serde_json::to_string(&model).unwrap();
/// let back: KrigeModel = serde_json::from_str(&json).unwrap();
/// assert_eq!(bits(&back), bits(&model));
/// # Ok::<(), kriging::KrigingError>(())
/// ```
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(try_from = "ModelData", into = "ModelData")]
pub struct KrigeModel {
    data: ModelData,
    st: State,
}

impl From<KrigeModel> for ModelData {
    fn from(m: KrigeModel) -> Self {
        m.data
    }
}

impl TryFrom<ModelData> for KrigeModel {
    type Error = KrigingError;
    fn try_from(data: ModelData) -> Result<Self, KrigingError> {
        KrigeModel::build(data)
    }
}

impl Krige {
    /// The map defaults (see [`Krige`]).
    pub fn new() -> Self {
        Krige::default()
    }

    /// Sets the drift ([`Drift::Constant`] is ordinary kriging).
    pub fn drift(mut self, drift: Drift) -> Self {
        self.drift = drift;
        self
    }

    /// Simple kriging with the known constant mean `mean`: weights from the covariance system alone
    /// (no Lagrange row), `z*(x) = m + c(x)^t C^-1 (z - m)` and
    /// `sigma^2(x) = C(0) - c(x)^t C^-1 c(x)` (see the [module docs](crate::geo#simple-kriging)).
    ///
    /// Needs a bounded variogram (nugget plus sill-reaching structures: not linear or power), a
    /// finite mean, the constant drift and no external drift; [`Krige::fit`] refuses anything else.
    /// Works with every [`Neighbourhood`] (a local system per query, with the same global mean:
    /// at least one neighbour per query), [`Anisotropy`] and [`KrigeModel::leave_one_out`].
    ///
    /// ```
    /// use kriging::faer::Mat;
    /// use kriging::{Krige, KrigingError, NestedVariogram, VariogramModel};
    ///
    /// let coords = Mat::from_fn(4, 1, |i, _| [0.0, 1.0, 3.0, 4.5][i]);
    /// let z = [1.2, 0.8, 1.5, 1.1];
    /// // Exponential variogram, nugget 0, partial sill 0.5, practical range 2: K = C(0) = 0.5.
    /// let v = NestedVariogram::single(VariogramModel::Exponential, 0.0, 0.5, 2.0)?;
    /// let sk = Krige::new().simple(1.0).variogram(v).fit(coords.as_ref(), &z)?;
    /// assert_eq!(sk.known_mean(), Some(1.0));
    /// let at = sk.predict(&[3.0])?; // exact at a sample, variance 0
    /// assert!((at.value - 1.5).abs() < 1e-12 && at.variance.abs() < 1e-12);
    /// let far = sk.predict(&[500.0])?; // beyond the range: the mean and the total sill
    /// assert!((far.value - 1.0).abs() < 1e-12 && (far.variance - 0.5).abs() < 1e-12);
    /// // An unbounded variogram has no covariance: refused, naming the model.
    /// let power = NestedVariogram::single(VariogramModel::Power, 0.0, 0.5, 1.0)?;
    /// let err = Krige::new().simple(1.0).variogram(power).fit(coords.as_ref(), &z).unwrap_err();
    /// assert!(matches!(err, KrigingError::InvalidVariogram { model: VariogramModel::Power, .. }));
    /// # Ok::<(), kriging::KrigingError>(())
    /// ```
    pub fn simple(mut self, mean: f64) -> Self {
        self.known_mean = Some(mean);
        self
    }

    /// `true`: the nugget is measurement error, not microscale variation (non-exact kriging, as
    /// GSTools' `exact=False`): the kriging matrix keeps the nugget on its diagonal, but the
    /// right-hand side is the covariance of the error-free signal, `c_i(x) = C(0) - nugget -
    /// gamma_s(|x - x_i|)` (`gamma_s` the structured part, without the jump at the origin) even
    /// where `x` is a sample, so predictions at the samples are smoothed towards the drift instead
    /// of reproducing the data. See the [module docs](crate::geo#measurement-error) for the
    /// formulas and the variance reported (GSTools' convention: the total sill `K` minus the
    /// kriging reduction, i.e. the error variance of predicting a *new measurement* at `x`; the
    /// variance of the error-free signal there is that minus the nugget).
    ///
    /// With the option, samples at the same place are accepted when the nugget is positive (their
    /// errors are independent), and a pure-nugget variogram (`NestedVariogram { nugget, structures:
    /// vec![] }`, nugget > 0) is allowed: it predicts the (drift) mean everywhere. Leave-one-out
    /// keeps its closed form (the held-out sample is not in the system, so the right-hand side at
    /// it is a column of the kriging matrix either way). Works with every drift, simple kriging,
    /// neighbourhood and anisotropy. Without a nugget the option changes nothing.
    ///
    /// ```
    /// use kriging::faer::Mat;
    /// use kriging::{Krige, NestedVariogram, VariogramModel};
    ///
    /// // The same site measured twice (2 and 5), and a third sample.
    /// let coords = Mat::from_fn(3, 1, |i, _| [0.0, 0.0, 4.0][i]);
    /// let z = [2.0, 5.0, 3.0];
    /// let v = NestedVariogram::single(VariogramModel::Exponential, 0.5, 1.0, 6.0)?;
    /// let me = Krige::new().measurement_error(true).variogram(v).fit(coords.as_ref(), &z)?;
    /// let p = me.predict(&[0.0])?; // smoothed: between the two measurements
    /// assert!(p.value > 2.0 && p.value < 5.0 && p.variance > 0.5);
    /// // Pure nugget: the data are noise around the mean; ordinary kriging predicts their mean.
    /// let noise = NestedVariogram { nugget: 0.5, structures: vec![] };
    /// let pn = Krige::new().measurement_error(true).variogram(noise).fit(coords.as_ref(), &z)?;
    /// assert!((pn.predict(&[4.0])?.value - 10.0 / 3.0).abs() < 1e-12);
    /// // Variance: the nugget (a new measurement's error) plus the mean's, 0.5 / 3.
    /// assert!((pn.predict(&[4.0])?.variance - 0.5 * (1.0 + 1.0 / 3.0)).abs() < 1e-12);
    /// # Ok::<(), kriging::KrigingError>(())
    /// ```
    pub fn measurement_error(mut self, on: bool) -> Self {
        self.measurement_error = on;
        self
    }

    /// Uses this variogram as given (a [`crate::Variogram`] or a [`NestedVariogram`]).
    pub fn variogram(mut self, v: impl Into<NestedVariogram>) -> Self {
        self.variogram = VariogramChoice::Given(v.into());
        self
    }

    /// Fits this variogram model.
    pub fn fit_model(mut self, model: VariogramModel) -> Self {
        self.variogram = VariogramChoice::Fit(model);
        self
    }

    /// Sets the geometric anisotropy.
    pub fn anisotropy(mut self, a: Anisotropy) -> Self {
        self.anisotropy = a;
        self
    }

    /// Sets the neighbourhood.
    pub fn neighbourhood(mut self, n: Neighbourhood) -> Self {
        self.neighbourhood = n;
        self
    }

    /// Sets the binning of the empirical variogram.
    pub fn binning(mut self, b: Binning) -> Self {
        self.binning = b;
        self
    }

    /// Sets the weights of the variogram fit.
    pub fn fit_weights(mut self, w: FitWeights) -> Self {
        self.fit_weights = w;
        self
    }

    /// Fits the model to `coords` (n x d, one sample per row, d = 1, 2 or 3 with anisotropy, any d
    /// otherwise) and `values` (n).
    ///
    /// Errors: shapes, NaN or infinity (naming row and column), fewer samples than drift terms plus
    /// one, coinciding samples without a nugget ([`KrigingError::DuplicateParams`] with both
    /// indices; with a nugget they are accepted, best read with [`Krige::measurement_error`]), a
    /// pure-nugget variogram (no structure) unless [`Krige::measurement_error`] is set, a variogram that cannot be fitted, a covariance matrix that is not positive
    /// definite, an ill-conditioned drift system, a global system above 4 GiB (use a
    /// [`Neighbourhood`]); for simple kriging also a non-finite mean or a non-constant drift
    /// ([`KrigingError::InvalidConfig`]) and an unbounded variogram
    /// ([`KrigingError::InvalidVariogram`] naming the model).
    pub fn fit(&self, coords: MatRef<'_, f64>, values: &[f64]) -> Result<KrigeModel, KrigingError> {
        self.fit_inner(coords, values, None)
    }

    /// As [`Krige::fit`] with external drift variables (n x m: one row per sample, one column per
    /// variable): kriging with external drift. Queries then need the m variables too
    /// ([`KrigeModel::predict_external`], [`KrigeModel::predict_many_with`]).
    ///
    /// ```
    /// use kriging::faer::Mat;
    /// use kriging::{Krige, NestedVariogram, VariogramModel};
    ///
    /// // The field follows an external variable (say, elevation) linearly: 1 + 3 e.
    /// let xy = [[0.0, 0.0], [50.0, 0.0], [0.0, 50.0], [50.0, 50.0], [20.0, 30.0], [35.0, 10.0]];
    /// let elevation = [2.0, 5.0, 1.0, 4.0, 3.5, 0.5];
    /// let z: Vec<f64> = elevation.iter().map(|e| 1.0 + 3.0 * e).collect();
    /// let coords = Mat::from_fn(6, 2, |i, k| xy[i][k]);
    /// let ext = Mat::from_fn(6, 1, |i, _| elevation[i]);
    /// let v = NestedVariogram::single(VariogramModel::Exponential, 0.0, 1.0, 40.0)?;
    /// let model = Krige::new().variogram(v).fit_with_external(coords.as_ref(), &z, ext.as_ref())?;
    /// assert_eq!(model.n_external(), 1);
    /// // Anywhere, with the variable known there, the prediction follows it exactly.
    /// let p = model.predict_external(&[300.0, -80.0], &[10.0])?;
    /// assert!((p.value - 31.0).abs() < 1e-9 && p.variance > 0.0);
    /// // Queries without the variable are an error.
    /// assert!(model.predict(&[10.0, 10.0]).is_err());
    /// # Ok::<(), kriging::KrigingError>(())
    /// ```
    pub fn fit_with_external(
        &self,
        coords: MatRef<'_, f64>,
        values: &[f64],
        external: MatRef<'_, f64>,
    ) -> Result<KrigeModel, KrigingError> {
        self.fit_inner(coords, values, Some(external))
    }

    fn fit_inner(
        &self,
        coords: MatRef<'_, f64>,
        values: &[f64],
        external: Option<MatRef<'_, f64>>,
    ) -> Result<KrigeModel, KrigingError> {
        let (n, d) = coords.shape();
        if values.len() != n {
            return Err(KrigingError::ShapeMismatch {
                what: "values length vs coordinate rows",
                expected: n,
                got: values.len(),
            });
        }
        if d == 0 {
            return Err(KrigingError::ShapeMismatch {
                what: "coordinate dimensions (need at least one)",
                expected: 1,
                got: 0,
            });
        }
        if let Some(m) = self.known_mean {
            check_simple(m, self.drift, external.map_or(0, |e| e.ncols()), None)?;
        }
        crate::check_finite("coordinates", coords)?;
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(KrigingError::NonFinite {
                what: "values",
                row: i,
                col: 0,
            });
        }
        let (n_ext, ext_rows) = match external {
            None => (0, Vec::new()),
            Some(e) => {
                if e.nrows() != n {
                    return Err(KrigingError::ShapeMismatch {
                        what: "external drift rows vs coordinate rows",
                        expected: n,
                        got: e.nrows(),
                    });
                }
                crate::check_finite("external drift", e)?;
                (e.ncols(), rows_of(e))
            }
        };
        let mut data = ModelData {
            dim: d,
            coords: rows_of(coords),
            values: values.to_vec(),
            n_ext,
            external: ext_rows,
            variogram: NestedVariogram {
                nugget: 0.0,
                structures: Vec::new(),
            },
            drift: self.drift,
            anisotropy: self.anisotropy,
            neighbourhood: self.neighbourhood,
            fit: None,
            known_mean: self.known_mean,
            measurement_error: self.measurement_error,
        };
        match &self.variogram {
            VariogramChoice::Given(v) => {
                validate_variogram(v, self.measurement_error)?;
                data.variogram = v.clone();
            }
            VariogramChoice::Fit(m) => self.fit_variogram(&mut data, &[*m])?,
            VariogramChoice::BestFit(ms) => self.fit_variogram(&mut data, ms)?,
        }
        KrigeModel::build(data)
    }

    /// Fits the variogram to the residuals of an ordinary least-squares fit of the drift.
    fn fit_variogram(
        &self,
        data: &mut ModelData,
        models: &[VariogramModel],
    ) -> Result<(), KrigingError> {
        if models.is_empty() {
            return Err(KrigingError::InvalidConfig(
                "no variogram model to fit".into(),
            ));
        }
        let geom = Geometry::new(data)?;
        let n = data.values.len();
        let p = geom.p;
        let fmat = geom.drift_rows(data);
        // OLS residuals: beta = (F^t F)^+ F^t z.
        // Simple kriging (p = 0): the residuals from the known mean.
        let resid = if let (0, Some(m0)) = (p, data.known_mean) {
            Mat::from_fn(n, 1, |i, _| data.values[i] - m0)
        } else {
            let f = Mat::from_fn(n, p, |i, k| fmat[i * p + k]);
            let z = Mat::from_fn(n, 1, |i, _| data.values[i]);
            let (gp, _) = sym_pinv(matmul(f.transpose(), f.as_ref()).as_ref());
            let beta = matmul(gp.as_ref(), matmul(f.transpose(), z.as_ref()).as_ref());
            let fitted = matmul(f.as_ref(), beta.as_ref());
            Mat::from_fn(n, 1, |i, _| data.values[i] - fitted[(i, 0)])
        };
        let pts = Mat::from_fn(n, data.dim, |i, k| geom.pts[i * data.dim + k]);
        let emp = EmpiricalVariogram::compute_binned(pts.as_ref(), resid.as_ref(), &self.binning)?;
        let opts = FitOptions {
            nugget: self.fit_nugget,
            weights: self.fit_weights,
        };
        let mut candidates = Vec::new();
        let mut best: Option<(f64, crate::Variogram)> = None;
        for &m in models {
            let mut rep = CandidateReport {
                model: m,
                variogram: None,
                wsse: None,
                loo_rmse: None,
                error: None,
                bounds: None,
            };
            match fit_variogram(&emp, m, &opts) {
                Ok(fv) => {
                    rep.variogram = Some(fv.variogram);
                    rep.wsse = Some(fv.wsse);
                    rep.bounds = Some(fv.bounds);
                    if best.is_none_or(|b| fv.wsse < b.0) {
                        best = Some((fv.wsse, fv.variogram));
                    }
                }
                Err(e) => rep.error = Some(e.to_string()),
            }
            candidates.push(rep);
        }
        let Some((_, v)) = best else {
            let why = candidates
                .iter()
                .map(|r| format!("{}: {}", r.model.name(), r.error.as_deref().unwrap_or("?")))
                .collect::<Vec<_>>()
                .join("; ");
            return Err(KrigingError::NoModel(why));
        };
        data.variogram = v.into();
        data.fit = Some(VariogramFitReport {
            empirical: emp,
            candidates,
        });
        Ok(())
    }
}

/// Row-major copy of a matrix.
fn rows_of(m: MatRef<'_, f64>) -> Vec<f64> {
    let (r, c) = m.shape();
    let mut out = Vec::with_capacity(r * c);
    for i in 0..r {
        for k in 0..c {
            out.push(m[(i, k)]);
        }
    }
    out
}

/// Coordinate transform and drift basis of a model.
struct Geometry {
    centre: Vec<f64>,
    amat: Vec<f64>,
    scale: f64,
    pts: Vec<f64>,
    ext_mean: Vec<f64>,
    ext_sd: Vec<f64>,
    p: usize,
}

impl Geometry {
    fn new(data: &ModelData) -> Result<Self, KrigingError> {
        let d = data.dim;
        let n = data.values.len();
        // Simple kriging has no drift terms.
        let p = if data.known_mean.is_some() {
            0
        } else {
            data.drift.n_terms(d) + data.n_ext
        };
        if n < p + 1 || n < 2 {
            return Err(KrigingError::TooFewSamples {
                what: if p == 0 {
                    "simple kriging (at least two samples)"
                } else {
                    "kriging with this drift (drift terms plus one)"
                },
                needed: (p + 1).max(2),
                got: n,
            });
        }
        let amat = data.anisotropy.matrix(d)?;
        let mut centre = vec![0.0; d];
        for (k, c) in centre.iter_mut().enumerate() {
            *c = (0..n).map(|i| data.coords[i * d + k]).sum::<f64>() / n as f64;
        }
        let mut pts = vec![0.0; n * d];
        let mut scale = 0.0f64;
        for i in 0..n {
            transform(
                &amat,
                &centre,
                &data.coords[i * d..(i + 1) * d],
                &mut pts[i * d..(i + 1) * d],
            );
            for &u in &pts[i * d..(i + 1) * d] {
                scale = scale.max(u.abs());
            }
        }
        if scale.is_nan() || scale <= 0.0 {
            return Err(KrigingError::NoSpread { samples: n });
        }
        // Squared distances must be representable, or far-apart samples would read as duplicates
        // (an infinite tolerance) and close ones too (squares that underflow to 0). Neither bound
        // binds below coordinates of about 1e153 or spreads above about 1e-142.
        let extent2 = (2.0 * scale) * (2.0 * scale) * d as f64;
        let tol = 1e-12 * scale;
        if !extent2.is_finite() || tol * tol == 0.0 {
            return Err(KrigingError::Overflow {
                what: "coordinates".into(),
                reason: format!(
                    "their squared distances {} (largest centred coordinate {scale:e}, after the \
                     anisotropy)",
                    if extent2.is_finite() {
                        "underflow to 0"
                    } else {
                        "overflow"
                    }
                ),
            });
        }
        let m = data.n_ext;
        let mut ext_mean = vec![0.0; m];
        let mut ext_sd = vec![1.0; m];
        for k in 0..m {
            let mean = (0..n).map(|i| data.external[i * m + k]).sum::<f64>() / n as f64;
            let var = (0..n)
                .map(|i| (data.external[i * m + k] - mean).powi(2))
                .sum::<f64>()
                / n as f64;
            ext_mean[k] = mean;
            ext_sd[k] = if var > 0.0 { var.sqrt() } else { 1.0 };
        }
        Ok(Geometry {
            centre,
            amat,
            scale,
            pts,
            ext_mean,
            ext_sd,
            p,
        })
    }

    /// Row-major n x p drift basis at the samples.
    fn drift_rows(&self, data: &ModelData) -> Vec<f64> {
        let (d, n, m) = (data.dim, data.values.len(), data.n_ext);
        let mut out = vec![0.0; n * self.p];
        for i in 0..n {
            drift_terms(
                data.drift,
                &self.pts[i * d..(i + 1) * d],
                self.scale,
                &data.external[i * m..(i + 1) * m],
                &self.ext_mean,
                &self.ext_sd,
                &mut out[i * self.p..(i + 1) * self.p],
            );
        }
        out
    }
}

/// `u = A (x - centre)`.
#[inline]
fn transform(amat: &[f64], centre: &[f64], x: &[f64], u: &mut [f64]) {
    let d = centre.len();
    for (r, ur) in u.iter_mut().enumerate() {
        let mut s = 0.0;
        for k in 0..d {
            s += amat[r * d + k] * (x[k] - centre[k]);
        }
        *ur = s;
    }
}

/// The drift basis at transformed point `u`: `1`, `u_k / scale`, `(u_k / scale)(u_l / scale)`,
/// standardised external variables.
#[inline]
fn drift_terms(
    drift: Drift,
    u: &[f64],
    scale: f64,
    ext: &[f64],
    ext_mean: &[f64],
    ext_sd: &[f64],
    out: &mut [f64],
) {
    if out.is_empty() {
        return; // simple kriging: no drift terms
    }
    let d = u.len();
    out[0] = 1.0;
    let mut j = 1;
    if drift != Drift::Constant {
        for &uk in u {
            out[j] = uk / scale;
            j += 1;
        }
    }
    if drift == Drift::Quadratic {
        for k in 0..d {
            for l in k..d {
                out[j] = (u[k] / scale) * (u[l] / scale);
                j += 1;
            }
        }
    }
    for (k, &e) in ext.iter().enumerate() {
        out[j] = (e - ext_mean[k]) / ext_sd[k];
        j += 1;
    }
}

#[inline]
fn dist(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt()
}

/// Lower Cholesky factor in place (single-threaded); `Err(index)` at a non-positive pivot.
fn cholesky(a: &mut Mat<f64>) -> Result<(), usize> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::cholesky::llt::factor;
    let n = a.nrows();
    let mut mem = MemBuffer::new(factor::cholesky_in_place_scratch::<f64>(
        n,
        Par::Seq,
        Default::default(),
    ));
    factor::cholesky_in_place(
        a.as_mut(),
        Default::default(),
        Par::Seq,
        MemStack::new(&mut mem),
        Default::default(),
    )
    .map(|_| ())
    .map_err(|e| match e {
        factor::LltError::NonPositivePivot { index } => index,
    })
}

fn solve_lower(l: MatRef<'_, f64>, rhs: faer::MatMut<'_, f64>) {
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(l, rhs, Par::Seq);
}

fn solve_lower_t(l: MatRef<'_, f64>, rhs: faer::MatMut<'_, f64>) {
    faer::linalg::triangular_solve::solve_upper_triangular_in_place(l.transpose(), rhs, Par::Seq);
}

impl KrigeModel {
    fn build(data: ModelData) -> Result<Self, KrigingError> {
        validate_variogram(&data.variogram, data.measurement_error)?;
        let d = data.dim;
        let n = data.values.len();
        if data.coords.len() != n * d || data.external.len() != n * data.n_ext {
            return Err(KrigingError::ShapeMismatch {
                what: "stored model coordinates",
                expected: n * d,
                got: data.coords.len(),
            });
        }
        if let Some(m) = data.known_mean {
            check_simple(m, data.drift, data.n_ext, Some(&data.variogram))?;
        }
        let geom = Geometry::new(&data)?;
        let fmat = geom.drift_rows(&data);
        let v = &data.variogram;
        let shift = if v.is_bounded() {
            v.total_sill()
        } else {
            // Any constant large enough: the diameter of the samples is at most 2 sqrt(d) scale.
            let diam = 2.0 * (d as f64).sqrt() * geom.scale;
            v.nugget + v.structured(4.0 * diam)
        };
        let p = geom.p;
        match data.neighbourhood {
            Neighbourhood::Global => {
                if n.saturating_mul(n).saturating_mul(8) > GLOBAL_MAX_BYTES {
                    return Err(KrigingError::InvalidConfig(format!(
                        "a global kriging system over {n} samples needs {:.1} GiB; use a moving \
                         neighbourhood (Neighbourhood::Nearest)",
                        (n * n * 8) as f64 / (1u64 << 30) as f64
                    )));
                }
            }
            Neighbourhood::Nearest { k } => {
                if k < p + 1 {
                    return Err(KrigingError::InvalidConfig(format!(
                        "a moving neighbourhood of {k} samples is too small for {p} drift terms \
                         (need at least {})",
                        p + 1
                    )));
                }
            }
            Neighbourhood::Radius { radius, max } => {
                if !(radius.is_finite() && radius > 0.0) || max < p + 1 {
                    return Err(KrigingError::InvalidConfig(format!(
                        "neighbourhood radius {radius} must be finite and > 0 and at most {max} \
                         neighbours at least {} (drift terms plus one)",
                        p + 1
                    )));
                }
            }
        }
        let tree = KdTree::new(&geom.pts, d);
        // Coinciding samples: singular without a nugget.
        if v.nugget == 0.0 {
            let tol = 1e-12 * geom.scale;
            let mut nb = Vec::new();
            for i in 0..n {
                tree.nearest(
                    &geom.pts,
                    &geom.pts[i * d..(i + 1) * d],
                    1,
                    tol * tol,
                    Some(i),
                    &mut nb,
                );
                if let Some(&(_, j)) = nb.first() {
                    return Err(KrigingError::DuplicateParams {
                        what: "kriging",
                        first: i.min(j),
                        second: i.max(j),
                    });
                }
            }
        }
        let mut st = State {
            centre: geom.centre,
            amat: geom.amat,
            scale: geom.scale,
            pts: geom.pts,
            ext_mean: geom.ext_mean,
            ext_sd: geom.ext_sd,
            fmat,
            p,
            shift,
            tree: None,
            global: None,
            warnings: Vec::new(),
        };
        let mut model = KrigeModel {
            data,
            st: st.clone(),
        };
        if model.data.neighbourhood == Neighbourhood::Global {
            let (sys, warn) = model.system((0..n).collect(), "the global kriging system")?;
            st.global = Some(sys);
            st.warnings.extend(warn);
        } else {
            st.tree = Some(tree);
        }
        model.st = st;
        Ok(model)
    }

    /// Builds and factorises the system over the samples `idx`.
    fn system(
        &self,
        idx: Vec<usize>,
        what: &'static str,
    ) -> Result<(System, Option<String>), KrigingError> {
        let st = &self.st;
        let d = self.data.dim;
        let n = idx.len();
        let p = st.p;
        let v = &self.data.variogram;
        let mut c = Mat::from_fn(n, n, |i, j| {
            if i == j {
                st.shift
            } else if i > j {
                let (a, b) = (idx[i], idx[j]);
                // Distinct samples: the nugget applies even at distance 0 (duplicates), as
                // independent noise, which keeps the matrix regular.
                let h = dist(&st.pts[a * d..(a + 1) * d], &st.pts[b * d..(b + 1) * d]);
                st.shift - (v.nugget + v.structured(h))
            } else {
                0.0
            }
        });
        let not_pd = |pivot_ratio: f64| KrigingError::Singular {
            what,
            size: n,
            pivot_ratio,
            residual: f64::NAN,
        };
        if cholesky(&mut c).is_err() {
            return Err(not_pd(0.0));
        }
        let (mut lmin, mut lmax) = (f64::INFINITY, 0.0f64);
        for k in 0..n {
            lmin = lmin.min(c[(k, k)]);
            lmax = lmax.max(c[(k, k)]);
        }
        let ratio = (lmin / lmax).powi(2);
        if ratio.is_nan() || ratio < PIVOT_RATIO_MIN {
            return Err(not_pd(ratio));
        }
        // Simple kriging: alpha = C^-1 (z - m), no drift system.
        let m0 = self.data.known_mean.unwrap_or(0.0);
        if p == 0 {
            let mut alpha = Mat::from_fn(n, 1, |i, _| self.data.values[idx[i]] - m0);
            solve_lower(c.as_ref(), alpha.as_mut());
            solve_lower_t(c.as_ref(), alpha.as_mut());
            return Ok((
                System {
                    idx,
                    l: c,
                    fw: Mat::zeros(n, 0),
                    r: Mat::zeros(0, 0),
                    beta: Vec::new(),
                    alpha: (0..n).map(|i| alpha[(i, 0)]).collect(),
                },
                None,
            ));
        }
        let mut fw = Mat::from_fn(n, p, |i, k| st.fmat[idx[i] * p + k]);
        solve_lower(c.as_ref(), fw.as_mut());
        let m = matmul(fw.transpose(), fw.as_ref());
        let (eig, _) = sym_eigen(m.as_ref());
        let emax = eig.iter().fold(0.0f64, |a, &b| a.max(b));
        let emin = eig.iter().fold(f64::INFINITY, |a, &b| a.min(b));
        let dratio = emin / emax;
        let mut warning = None;
        if dratio.is_nan() || dratio < DRIFT_RATIO_MIN {
            return Err(KrigingError::IllConditionedDrift {
                terms: p,
                samples: n,
                ratio: dratio,
            });
        }
        if dratio < DRIFT_RATIO_WARN {
            warning = Some(format!(
                "{what}: the drift system is poorly conditioned (eigenvalue ratio {dratio:.2e}); \
                 the drift coefficients are uncertain"
            ));
        }
        let mut r = m;
        if cholesky(&mut r).is_err() {
            return Err(KrigingError::IllConditionedDrift {
                terms: p,
                samples: n,
                ratio: dratio,
            });
        }
        let mut zw = Mat::from_fn(n, 1, |i, _| self.data.values[idx[i]]);
        solve_lower(c.as_ref(), zw.as_mut());
        // beta = M^-1 F_w^t z_w
        let mut beta = matmul(fw.transpose(), zw.as_ref());
        solve_lower(r.as_ref(), beta.as_mut());
        solve_lower_t(r.as_ref(), beta.as_mut());
        let fb = matmul(fw.as_ref(), beta.as_ref());
        let mut alpha = Mat::from_fn(n, 1, |i, _| zw[(i, 0)] - fb[(i, 0)]);
        solve_lower_t(c.as_ref(), alpha.as_mut());
        Ok((
            System {
                idx,
                l: c,
                fw,
                r,
                beta: (0..p).map(|k| beta[(k, 0)]).collect(),
                alpha: (0..n).map(|i| alpha[(i, 0)]).collect(),
            },
            warning,
        ))
    }

    /// Predictions (and variances into `var` when it is not empty) of `sys` at transformed points
    /// `q` (row-major B x d) with drift rows `fq` (row-major B x p).
    fn solve_block(&self, sys: &System, q: &[f64], fq: &[f64], val: &mut [f64], var: &mut [f64]) {
        let st = &self.st;
        let d = self.data.dim;
        let p = st.p;
        let b = val.len();
        let n = sys.idx.len();
        let v = &self.data.variogram;
        let me = self.data.measurement_error;
        let mut cq = Mat::from_fn(n, b, |i, j| {
            let a = sys.idx[i];
            let h = dist(&st.pts[a * d..(a + 1) * d], &q[j * d..(j + 1) * d]);
            if me {
                // Measurement error: the covariance of the error-free signal, also at h = 0.
                st.shift - (v.nugget + v.structured(h))
            } else {
                st.shift - v.eval(h)
            }
        });
        // The known mean of simple kriging (p = 0); 0 otherwise, where the drift carries the mean.
        let m0 = self.data.known_mean.unwrap_or(0.0);
        for j in 0..b {
            let mut s = m0;
            for k in 0..p {
                s += sys.beta[k] * fq[j * p + k];
            }
            let col = cq.col_as_slice(j);
            for (a, c) in sys.alpha.iter().zip(col) {
                s += a * c;
            }
            val[j] = s;
        }
        if var.is_empty() {
            return;
        }
        solve_lower(sys.l.as_ref(), cq.as_mut());
        let ftv = matmul(sys.fw.transpose(), cq.as_ref()); // p x B
        let mut w = Mat::from_fn(p, b, |k, j| fq[j * p + k] - ftv[(k, j)]);
        if p > 0 {
            solve_lower(sys.r.as_ref(), w.as_mut());
        }
        for (j, vj) in var.iter_mut().enumerate() {
            let vv: f64 = cq.col_as_slice(j).iter().map(|x| x * x).sum();
            let ww: f64 = w.col_as_slice(j).iter().map(|x| x * x).sum();
            *vj = (st.shift - vv + ww).max(0.0);
        }
    }

    /// The neighbours of transformed point `u` (sorted by index), excluding `exclude`.
    fn neighbours(
        &self,
        u: &[f64],
        exclude: Option<usize>,
        buf: &mut Vec<(f64, usize)>,
    ) -> Result<Vec<usize>, KrigingError> {
        let tree = self.st.tree.as_ref().expect("local models have a tree");
        let (k, r2) = match self.data.neighbourhood {
            Neighbourhood::Nearest { k } => (k, f64::INFINITY),
            Neighbourhood::Radius { radius, max } => (max, radius * radius),
            Neighbourhood::Global => unreachable!("global models have no tree"),
        };
        tree.nearest(&self.st.pts, u, k, r2, exclude, buf);
        if buf.len() < self.st.p + 1 {
            return Err(KrigingError::TooFewSamples {
                what: "the moving neighbourhood of a query point",
                needed: self.st.p + 1,
                got: buf.len(),
            });
        }
        let mut idx: Vec<usize> = buf.iter().map(|e| e.1).collect();
        idx.sort_unstable();
        Ok(idx)
    }

    /// Checks a query point and its external variables; returns the transformed point and drift row.
    fn prepare(
        &self,
        x: &[f64],
        ext: &[f64],
        u: &mut [f64],
        f: &mut [f64],
    ) -> Result<(), KrigingError> {
        let d = self.data.dim;
        if x.len() != d {
            return Err(KrigingError::ShapeMismatch {
                what: "query point length",
                expected: d,
                got: x.len(),
            });
        }
        if ext.len() != self.data.n_ext {
            return Err(KrigingError::ShapeMismatch {
                what: "external drift variables of a query",
                expected: self.data.n_ext,
                got: ext.len(),
            });
        }
        if let Some(k) = x.iter().position(|v| !v.is_finite()) {
            return Err(KrigingError::NonFinite {
                what: "query point",
                row: 0,
                col: k,
            });
        }
        if let Some(k) = ext.iter().position(|v| !v.is_finite()) {
            return Err(KrigingError::NonFinite {
                what: "query external drift",
                row: 0,
                col: k,
            });
        }
        let st = &self.st;
        transform(&st.amat, &st.centre, x, u);
        drift_terms(
            self.data.drift,
            u,
            st.scale,
            ext,
            &st.ext_mean,
            &st.ext_sd,
            f,
        );
        Ok(())
    }

    /// The prediction and kriging variance at `x` (a model without external drift).
    pub fn predict(&self, x: &[f64]) -> Result<Prediction, KrigingError> {
        self.predict_external(x, &[])
    }

    /// The prediction and kriging variance at `x` with the external drift variables `ext` there.
    pub fn predict_external(&self, x: &[f64], ext: &[f64]) -> Result<Prediction, KrigingError> {
        let mut u = vec![0.0; self.data.dim];
        let mut f = vec![0.0; self.st.p];
        self.prepare(x, ext, &mut u, &mut f)?;
        let (mut val, mut var) = ([0.0], [0.0]);
        match &self.st.global {
            Some(sys) => self.solve_block(sys, &u, &f, &mut val, &mut var),
            None => {
                let idx = self.neighbours(&u, None, &mut Vec::new())?;
                let (sys, _) = self.system(idx, "a moving-neighbourhood kriging system")?;
                self.solve_block(&sys, &u, &f, &mut val, &mut var);
            }
        }
        check_prediction(&val, &var, None)?;
        Ok(Prediction {
            value: val[0],
            variance: var[0],
        })
    }

    /// Predictions and variances at every row of `points` (m x d), in parallel (rayon) over fixed
    /// blocks of 64 points: the same bits whatever the number of threads.
    ///
    /// ```
    /// use kriging::faer::Mat;
    /// use kriging::{Krige, NestedVariogram, VariogramModel};
    ///
    /// let xy = [[0.0, 0.0], [4.0, 0.0], [0.0, 4.0], [4.0, 4.0], [1.0, 3.0]];
    /// let z = [1.0, 2.0, 3.0, 4.0, 2.5];
    /// let coords = Mat::from_fn(5, 2, |i, k| xy[i][k]);
    /// let v = NestedVariogram::single(VariogramModel::Spherical, 0.1, 1.0, 6.0)?;
    /// let model = Krige::new().variogram(v).fit(coords.as_ref(), &z)?;
    ///
    /// // 200 query points (m x 2): the last one is the sample (4, 4).
    /// let q = Mat::from_fn(200, 2, |i, k| if i == 199 { 4.0 } else { 0.02 * i as f64 * [1.0, 0.5][k] });
    /// let p = model.predict_many(q.as_ref())?;
    /// assert_eq!((p.values.len(), p.variances.len()), (200, 200));
    /// for i in [0, 63, 64, 150] {
    ///     let one = model.predict(&[q[(i, 0)], q[(i, 1)]])?;
    ///     assert!((p.values[i] - one.value).abs() < 1e-12);
    ///     assert!((p.variances[i] - one.variance).abs() < 1e-12);
    /// }
    /// // Exact at a sample, where the variance is 0; away from the samples it is at least the nugget.
    /// assert!((p.values[199] - 4.0).abs() < 1e-12 && p.variances[199].abs() < 1e-12);
    /// assert!(p.variances[100] >= 0.1);
    /// // Values alone (no variances) are the same numbers.
    /// let v_only = model.predict_many_with(q.as_ref(), None, false)?;
    /// assert!(v_only.variances.is_empty());
    /// assert!(v_only.values.iter().zip(&p.values).all(|(a, b)| (a - b).abs() < 1e-12));
    /// # Ok::<(), kriging::KrigingError>(())
    /// ```
    pub fn predict_many(&self, points: MatRef<'_, f64>) -> Result<Predictions, KrigingError> {
        self.predict_many_with(points, None, true)
    }

    /// As [`KrigeModel::predict_many`], with the external drift variables at the points (m x
    /// n_ext) and the choice of computing variances (predictions alone cost `O(n)` per point in a
    /// global model, variances `O(n^2)`).
    pub fn predict_many_with(
        &self,
        points: MatRef<'_, f64>,
        external: Option<MatRef<'_, f64>>,
        variance: bool,
    ) -> Result<Predictions, KrigingError> {
        let (m, d) = points.shape();
        if d != self.data.dim {
            return Err(KrigingError::ShapeMismatch {
                what: "query point columns",
                expected: self.data.dim,
                got: d,
            });
        }
        let n_ext = self.data.n_ext;
        match external {
            Some(e) if e.nrows() != m || e.ncols() != n_ext => {
                return Err(KrigingError::ShapeMismatch {
                    what: "external drift at the query points (rows x columns)",
                    expected: m * n_ext,
                    got: e.nrows() * e.ncols(),
                });
            }
            None if n_ext > 0 => {
                return Err(KrigingError::ShapeMismatch {
                    what: "external drift columns at the query points",
                    expected: n_ext,
                    got: 0,
                });
            }
            _ => {}
        }
        let x = rows_of(points);
        let e = external.map(rows_of).unwrap_or_default();
        self.predict_rows(&x, &e, m, variance)
    }

    /// Predictions and variances on the grid `xs` x `ys` (2-D models), row-major with `x`
    /// fastest: entry `j * xs.len() + i` is at `(xs[i], ys[j])` (PyKrige's `"grid"` layout).
    pub fn predict_grid(&self, xs: &[f64], ys: &[f64]) -> Result<Predictions, KrigingError> {
        if self.data.dim != 2 {
            return Err(KrigingError::ShapeMismatch {
                what: "grid prediction needs 2-D coordinates",
                expected: 2,
                got: self.data.dim,
            });
        }
        let m = xs.len() * ys.len();
        let mut x = Vec::with_capacity(2 * m);
        for &y in ys {
            for &xv in xs {
                x.push(xv);
                x.push(y);
            }
        }
        self.predict_rows(&x, &[], m, true)
    }

    fn predict_rows(
        &self,
        x: &[f64],
        e: &[f64],
        m: usize,
        variance: bool,
    ) -> Result<Predictions, KrigingError> {
        let d = self.data.dim;
        let p = self.st.p;
        let n_ext = self.data.n_ext;
        let mut values = vec![0.0; m];
        let mut variances = if variance { vec![0.0; m] } else { Vec::new() };
        let nblocks = m.div_ceil(BLOCK);
        let results: Vec<Result<(), KrigingError>> = values
            .par_chunks_mut(BLOCK)
            .zip(if variance {
                variances
                    .par_chunks_mut(BLOCK)
                    .map(Some)
                    .collect::<Vec<_>>()
            } else {
                (0..nblocks).map(|_| None).collect::<Vec<_>>()
            })
            .enumerate()
            .map(|(blk, (val, var))| {
                let start = blk * BLOCK;
                let b = val.len();
                let mut u = vec![0.0; b * d];
                let mut f = vec![0.0; b * p];
                for j in 0..b {
                    let q = start + j;
                    self.prepare(
                        &x[q * d..(q + 1) * d],
                        &e[q * n_ext..(q + 1) * n_ext],
                        &mut u[j * d..(j + 1) * d],
                        &mut f[j * p..(j + 1) * p],
                    )
                    .map_err(|err| at_point(err, q))?;
                }
                let mut empty: [f64; 0] = [];
                let var: &mut [f64] = var.unwrap_or(&mut empty);
                match &self.st.global {
                    Some(sys) => self.solve_block(sys, &u, &f, val, var),
                    None => {
                        let mut buf = Vec::new();
                        for j in 0..b {
                            let uj = &u[j * d..(j + 1) * d];
                            let idx = self
                                .neighbours(uj, None, &mut buf)
                                .map_err(|err| at_point(err, start + j))?;
                            let (sys, _) = self
                                .system(idx, "a moving-neighbourhood kriging system")
                                .map_err(|err| at_point(err, start + j))?;
                            let vj: &mut [f64] = if var.is_empty() {
                                &mut []
                            } else {
                                &mut var[j..j + 1]
                            };
                            self.solve_block(
                                &sys,
                                uj,
                                &f[j * p..(j + 1) * p],
                                &mut val[j..j + 1],
                                vj,
                            );
                        }
                    }
                }
                Ok(())
            })
            .collect();
        for r in results {
            r?;
        }
        check_prediction(&values, &variances, Some(0))?;
        Ok(Predictions { values, variances })
    }

    /// Leave-one-out cross validation with the variogram fixed and the drift re-estimated (simple
    /// kriging: the mean stays the known one).
    ///
    /// Global neighbourhood, closed form (Dubrule 1983) from the inverse of the kriging matrix
    /// `A = [C F; F^t 0]`: with `B = A^-1`, `e_k = (B [z; 0])_k / B_kk` and
    /// `sigma^2_{-k}(x_k) = 1 / B_kk`, where `B_kk = (C^-1)_kk - g_k^t (F^t C^-1 F)^-1 g_k`,
    /// `g_k = (F^t C^-1)_{:, k}` (cost: one `L^-1`, `n^3 / 3`). Simple kriging is the same closed
    /// form without drift (`B = C^-1`): `e_k = (C^-1 (z - m))_k / (C^-1)_kk`,
    /// `sigma^2_{-k}(x_k) = 1 / (C^-1)_kk`. With [`Krige::measurement_error`] the same closed form
    /// holds (the held-out sample is not in the system, and the right-hand side at it is its
    /// column of `C`, which off the diagonal is the error-free covariance already; the variance is
    /// that of predicting the held-out measurement, GSTools' convention). Moving neighbourhood: each sample is predicted from its
    /// own neighbours without it.
    ///
    /// ```
    /// use kriging::faer::Mat;
    /// use kriging::{Drift, Krige, NestedVariogram, VariogramModel};
    ///
    /// let xy = [[0.0, 0.0], [9.0, 1.0], [1.0, 8.0], [10.0, 10.0], [4.0, 6.0], [7.0, 3.0], [2.0, 3.0]];
    /// let z = [1.0, 2.5, 1.8, 3.9, 2.2, 2.6, 1.1];
    /// let coords = Mat::from_fn(7, 2, |i, k| xy[i][k]);
    /// let v = NestedVariogram::single(VariogramModel::Spherical, 0.05, 1.0, 12.0)?;
    /// let krige = Krige::new().drift(Drift::Linear).variogram(v);
    /// let loo = krige.fit(coords.as_ref(), &z)?.leave_one_out()?;
    /// // The closed form is the refit without the sample.
    /// let k = 4;
    /// let rest: Vec<usize> = (0..7).filter(|&i| i != k).collect();
    /// let without = Mat::from_fn(6, 2, |i, c| xy[rest[i]][c]);
    /// let z_without: Vec<f64> = rest.iter().map(|&i| z[i]).collect();
    /// let p = krige.fit(without.as_ref(), &z_without)?.predict(&xy[k])?;
    /// assert!((loo.errors[k] - (z[k] - p.value)).abs() < 1e-10);
    /// assert!((loo.variances[k] - p.variance).abs() < 1e-10);
    /// assert!((loo.standardised[k] - loo.errors[k] / p.variance.sqrt()).abs() < 1e-9);
    /// let mse = loo.errors.iter().map(|e| e * e).sum::<f64>() / 7.0;
    /// assert!((loo.rmse - mse.sqrt()).abs() < 1e-12);
    /// # Ok::<(), kriging::KrigingError>(())
    /// ```
    pub fn leave_one_out(&self) -> Result<LooStats, KrigingError> {
        let n = self.data.values.len();
        let d = self.data.dim;
        let p = self.st.p;
        let mut errors = vec![0.0; n];
        let mut variances = vec![0.0; n];
        if let Some(sys) = &self.st.global {
            // L^-1, then G = C^-1 F = L^-t F_w.
            let mut linv = Mat::<f64>::identity(n, n);
            solve_lower(sys.l.as_ref(), linv.as_mut());
            let mut g = sys.fw.clone();
            solve_lower_t(sys.l.as_ref(), g.as_mut());
            let mut gt = g.transpose().to_owned(); // p x n (0 x n for simple kriging)
            if p > 0 {
                solve_lower(sys.r.as_ref(), gt.as_mut());
            }
            for k in 0..n {
                let cinv_kk: f64 = (k..n).map(|i| linv[(i, k)] * linv[(i, k)]).sum();
                let corr: f64 = gt.col_as_slice(k).iter().map(|x| x * x).sum();
                let bkk = cinv_kk - corr;
                if !(bkk > 0.0 && bkk.is_finite()) {
                    return Err(KrigingError::Singular {
                        what: "leave-one-out",
                        size: n,
                        pivot_ratio: 0.0,
                        residual: bkk,
                    });
                }
                errors[k] = sys.alpha[k] / bkk;
                variances[k] = 1.0 / bkk;
            }
        } else {
            let per: Vec<Result<(f64, f64), KrigingError>> = (0..n)
                .into_par_iter()
                .map(|k| {
                    let u = &self.st.pts[k * d..(k + 1) * d];
                    let idx = self
                        .neighbours(u, Some(k), &mut Vec::new())
                        .map_err(|e| at_point(e, k))?;
                    let (sys, _) = self.system(idx, "a leave-one-out neighbourhood system")?;
                    let (mut val, mut var) = ([0.0], [0.0]);
                    self.solve_block(
                        &sys,
                        u,
                        &self.st.fmat[k * p..(k + 1) * p],
                        &mut val,
                        &mut var,
                    );
                    Ok((self.data.values[k] - val[0], var[0]))
                })
                .collect();
            for (k, r) in per.into_iter().enumerate() {
                let (e, v) = r?;
                errors[k] = e;
                variances[k] = v;
            }
        }
        let standardised: Vec<f64> = errors
            .iter()
            .zip(&variances)
            .map(|(e, v)| if *v > 0.0 { e / v.sqrt() } else { f64::NAN })
            .collect();
        let nf = n as f64;
        Ok(LooStats {
            rmse: (errors.iter().map(|e| e * e).sum::<f64>() / nf).sqrt(),
            mean_error: errors.iter().sum::<f64>() / nf,
            msse: standardised.iter().map(|s| s * s).sum::<f64>() / nf,
            errors,
            variances,
            standardised,
        })
    }

    /// The variogram used (fitted or given), in the coordinates' units (ranges along the major
    /// axis under anisotropy).
    pub fn variogram(&self) -> &NestedVariogram {
        &self.data.variogram
    }

    /// The empirical variogram and candidate fits, when the variogram was fitted.
    pub fn fit_report(&self) -> Option<&VariogramFitReport> {
        self.data.fit.as_ref()
    }

    /// The drift ([`Drift::Constant`] for simple kriging; its mean: [`KrigeModel::known_mean`]).
    pub fn drift(&self) -> Drift {
        self.data.drift
    }

    /// The known mean of a simple-kriging model ([`Krige::simple`]); `None` otherwise.
    pub fn known_mean(&self) -> Option<f64> {
        self.data.known_mean
    }

    /// Whether the nugget is measurement error ([`Krige::measurement_error`]).
    pub fn measurement_error(&self) -> bool {
        self.data.measurement_error
    }

    /// The neighbourhood.
    pub fn neighbourhood(&self) -> Neighbourhood {
        self.data.neighbourhood
    }

    /// The anisotropy.
    pub fn anisotropy(&self) -> Anisotropy {
        self.data.anisotropy
    }

    /// Number of samples.
    pub fn n_samples(&self) -> usize {
        self.data.values.len()
    }

    /// Coordinate dimensions.
    pub fn dim(&self) -> usize {
        self.data.dim
    }

    /// Number of external drift variables.
    pub fn n_external(&self) -> usize {
        self.data.n_ext
    }

    /// Generalised least-squares drift coefficients of a global model, on the internal basis
    /// (`1`, centred coordinates over their largest extent, their products, standardised external
    /// variables); `None` for a moving neighbourhood (each query has its own); empty for simple
    /// kriging (no drift is estimated).
    pub fn drift_coefficients(&self) -> Option<&[f64]> {
        self.st.global.as_ref().map(|s| s.beta.as_slice())
    }

    /// Conditioning warnings recorded at fit time (empty when all is well).
    pub fn warnings(&self) -> &[String] {
        &self.st.warnings
    }
}

/// The conditions of simple kriging: a finite mean, the constant drift without external variables,
/// and (once known) a bounded variogram.
fn check_simple(
    mean: f64,
    drift: Drift,
    n_ext: usize,
    variogram: Option<&NestedVariogram>,
) -> Result<(), KrigingError> {
    if !mean.is_finite() {
        return Err(KrigingError::InvalidConfig(format!(
            "the mean of simple kriging must be finite, got {mean}"
        )));
    }
    if drift != Drift::Constant || n_ext > 0 {
        return Err(KrigingError::InvalidConfig(format!(
            "simple kriging (known mean) takes no drift to estimate: got {drift:?} drift and {n_ext} \
             external drift variables (use Drift::Constant without external variables, or drop \
             Krige::simple for universal kriging)"
        )));
    }
    let unbounded = variogram.and_then(|v| v.structures.iter().find(|s| !s.model.has_range()));
    if let Some(s) = unbounded {
        return Err(KrigingError::InvalidVariogram {
            model: s.model,
            reason: format!(
                "simple kriging needs a bounded variogram (one that reaches a sill, so that the \
                 covariance C(h) = sill - gamma(h) exists); the {} model is unbounded: use a \
                 bounded model or ordinary kriging",
                s.model.name()
            ),
        });
    }
    Ok(())
}

/// [`NestedVariogram::validate`], and under measurement error also a pure nugget (no structure,
/// nugget finite and > 0).
fn validate_variogram(v: &NestedVariogram, measurement_error: bool) -> Result<(), KrigingError> {
    if measurement_error && v.structures.is_empty() {
        if v.nugget.is_finite() && v.nugget > 0.0 {
            return Ok(());
        }
        return Err(KrigingError::InvalidConfig(format!(
            "a pure-nugget variogram needs a finite nugget > 0, got {}",
            v.nugget
        )));
    }
    v.validate()
}

/// `Ok` when every prediction and variance is finite, else [`KrigingError::Overflow`] naming the
/// first query point whose result is not (`first`: the index of `values[0]` among the query
/// points, `None` for a single query): a point so far from the samples, or data so large, that
/// the variogram or the drift overflows.
fn check_prediction(
    values: &[f64],
    variances: &[f64],
    first: Option<usize>,
) -> Result<(), KrigingError> {
    let bad = values
        .iter()
        .position(|v| !v.is_finite())
        .into_iter()
        .chain(variances.iter().position(|v| !v.is_finite()))
        .min();
    match bad {
        None => Ok(()),
        Some(q) => Err(KrigingError::Overflow {
            what: match first {
                Some(f) => format!("the prediction at query point {}", f + q),
                None => "the prediction at the query point".into(),
            },
            reason: format!(
                "value {} and variance {} (the point is too far from the samples)",
                values[q],
                variances.get(q).copied().unwrap_or(0.0)
            ),
        }),
    }
}

/// Adds the query index to an error about a query point.
fn at_point(err: KrigingError, q: usize) -> KrigingError {
    match err {
        KrigingError::NonFinite { what, col, .. } => KrigingError::NonFinite { what, row: q, col },
        KrigingError::TooFewSamples { needed, got, .. } => KrigingError::QueryNeighbourhood {
            point: q,
            needed,
            got,
        },
        other => other,
    }
}
