//! Geostatistical interpolation: variograms and kriging of scattered samples, for maps and for any
//! parameter space.
//!
//! This crate is for: variogram analysis (binned empirical variograms with a maximum lag,
//! directional and robust ones: Matheron, Cressie-Hawkins, Dowd; anisotropy estimation; weighted
//! least-squares fits of seven shapes, Matérn's smoothness included, and of nested sums, with
//! parameters that end at a bound reported); ordinary, universal (linear or quadratic drift inside
//! the kriging system), external-drift and simple (known mean) kriging of a scalar field over 1-3-D
//! coordinates with kriging variances, leave-one-out diagnostics, geometric anisotropy and a moving
//! neighbourhood ([`Krige`], module [`geo`]; checked against PyKrige and GSTools on the Meuse data);
//! conditional simulation by sequential Gaussian simulation ([`Sgs`], module [`simulate`]); and the
//! vector-valued regression kriging of Mukai and Kuriyama's motion model ([`Kriging`], eq. 8 and
//! appendix A) with its precomputed hot-path projection and an RBF baseline. It is not for: space-time
//! or multivariate (co-)kriging, indicator or disjunctive kriging, other simulation methods
//! (turning bands, spectral, indicator), block kriging, or sparse/approximate methods for millions
//! of points; nor for tensors or motion data themselves. Latitude/longitude data are kriged on the
//! sphere through [`latlon_to_xyz`] (chordal distances, as GSTools' `latlon=True`; module [`sphere`]).
//!
//! Two front ends:
//! - [`Krige`] (builder) -> [`KrigeModel`]: maps and other geostatistics. Defaults suit maps:
//!   ordinary kriging, a variogram fitted by Cressie's weighted least squares on 15 bins up to a
//!   third of the bounding-box diagonal, every result in the input's units (coordinates are centred
//!   and scaled inside for conditioning only). Batch prediction runs in parallel (rayon) with the
//!   same bits for any thread count; the fitted model serialises with serde.
//! - [`Kriging`] with [`KrigingConfig`]: vector values over a parameter space, per-axis scaling, the
//!   paper's regression kriging ([`Method::Regression`]: an ordinary least-squares trend plus
//!   ordinary kriging of its residuals; *not* textbook universal kriging) and a variogram chosen by
//!   leave-one-out search; [`KrigingConfig::motion`] is the motion model's preset.
//!
//! Pieces:
//! - [`EmpiricalVariogram`]: the binned semi-variance of appendix A ([`EmpiricalVariogram::compute`],
//!   bins up to the largest distance) or with a chosen maximum lag ([`Binning`], [`MaxLag`]);
//! - [`Variogram`] / [`VariogramModel`]: linear, power, spherical, exponential, gaussian, Matérn and
//!   cardinal-sine (wave; formerly called hole-effect) models with nugget, partial sill and range, fitted by weighted least squares
//!   ([`fit_variogram`], pair-count or Cressie weights; Matérn's `nu` fitted too; parameters at a
//!   bound in [`FitBounds`]); [`NestedVariogram`]: sums of them, fitted by [`fit_nested`];
//! - [`EmpiricalVariogram::estimate`]: directional ([`Direction`]) and robust ([`Estimator`])
//!   empirical variograms, also with great-circle distances; [`estimate_anisotropy`]: angle and
//!   ratio of a 2-D geometric anisotropy from directional variograms;
//! - [`Krige`] / [`KrigeModel`]: simple ([`Krige::simple`]), ordinary, universal and external-drift
//!   kriging with variances,
//!   [`Anisotropy`], [`Neighbourhood`], [`LooStats`] (see [`geo`] for the formulas);
//! - [`Sgs`] / [`Realisations`]: sequential Gaussian simulation honouring the data (a random path,
//!   simple or ordinary kriging from the nearest data and earlier nodes, a normal draw per node;
//!   deterministic for a seed on any number of threads; see [`simulate`] for the formulas);
//! - [`Kriging`]: ordinary kriging and the paper's regression kriging (trend `F = K C^+` over
//!   `[c; 1]`, kriging of the residuals), with automatic model choice by fit or leave-one-out error,
//!   by default over the fitted models and a grid of ranges and nuggets ([`search`]: the nugget smooths
//!   noisy samples instead of interpolating them), closed-form leave-one-out
//!   ([`Kriging::leave_one_out`]) and allocation-free queries;
//! - [`ProjectedQuery`]: `L b(c)` for a fixed `L` in `R (S+1)` multiply-adds (runtime hot path);
//! - [`ParamScaling`]: per-dimension scaling (none, standardise, given); constant dimensions dropped;
//! - [`select_dims`]: drops the dimensions that carry no signal (forward selection by
//!   leave-one-out error); [`select_dims_by_folds`]: keeps every dimension unless dropping it
//!   lowers the error of a cross-validation over given folds (backward elimination);
//! - [`Rbf`]: the radial-basis baseline of Rose et al. with the same `fit/weights/predict/loo` shape,
//!   exact or with a smoothing term chosen by leave-one-out error ([`RbfSmoothing`]).
//!
//! Degenerate input: NaN/inf, wrong shapes, too few samples (regression kriging needs `d' + 2`
//! with `d'` the non-constant dimensions), all-equal parameters and values that do not vary are
//! errors ([`KrigingError`]). Duplicate parameter points are an error naming both samples unless the
//! variogram has a nugget, which then regularises the system (it acts as independent noise between
//! distinct samples). Constant dimensions get scale 0 under standardisation and are reported by
//! [`Kriging::dropped_dims`]; constant or collinear dimensions in the trend go through a
//! pseudo-inverse. A singular or ill-conditioned system (pivot ratio below 1e-13) is an error,
//! and automatic model choice skips such candidates.
//!
//! All results are deterministic: the linear algebra runs single-threaded, the pairwise value
//! distances reduce in a fixed order, and the variogram search scores its candidates independently.
//!
//! ```
//! use faer::Mat;
//! use kriging::{Kriging, KrigingConfig, Method, ModelChoice, ScalingChoice, VariogramModel};
//!
//! // Five samples over a 2-D parameter space, 2-D values.
//! let c: [[f64; 2]; 5] = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [0.4, 0.7]];
//! let params = Mat::from_fn(5, 2, |i, k| c[i][k]);
//! let values = Mat::from_fn(5, 2, |i, j| if j == 0 { c[i][0] + 2.0 * c[i][1] } else { c[i][0] * c[i][1] });
//! let config = KrigingConfig {
//!     method: Method::Ordinary,
//!     model: ModelChoice::Fixed(VariogramModel::Linear),
//!     scaling: ScalingChoice::None,
//!     bins: 4,
//!     ..KrigingConfig::default()
//! };
//! let k = Kriging::fit(params.as_ref(), values.as_ref(), &config)?;
//! let mut b = vec![0.0; 5];
//! k.weights(&[0.5, 0.5], &mut b)?;
//! assert!((b.iter().sum::<f64>() - 1.0).abs() < 1e-12);
//! let mut x = vec![0.0; 2];
//! k.predict(&[1.0, 0.0], &mut x)?; // exact at a sample
//! assert!((x[0] - 1.0).abs() < 1e-9);
//! let loo = k.leave_one_out()?;
//! assert_eq!(loo.per_sample.len(), 5);
//! # Ok::<(), kriging::KrigingError>(())
//! ```

#![warn(missing_docs)]

// The README's Rust snippets run as doc tests (`cargo test --doc -p kriging`).
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
mod readme {}

mod anisotropy;
mod config;
mod empirical;
mod error;
mod estimator;
mod fit;
pub mod geo;
mod kdtree;
mod kriging;
mod linalg;
mod nested;
mod projected;
mod rbf;
mod scaling;
pub mod search;
mod select;
pub mod simulate;
mod special;
pub mod sphere;
mod variogram;

/// The linear-algebra crate whose matrix types ([`faer::MatRef`], [`faer::Mat`]) this crate takes
/// and returns, re-exported so that users need not depend on the same version themselves.
pub use faer;

pub use anisotropy::Anisotropy;
pub use config::{CandidateReport, KrigingConfig, LooReport, Method, ModelChoice, Selection};
pub use empirical::{Binning, EmpiricalVariogram, MAX_BINS, MaxLag};
pub use error::KrigingError;
pub use estimator::{
    AnisotropyEstimate, AnisotropyOptions, Direction, DirectionalRange, EstimateOptions, Estimator,
    estimate_anisotropy,
};
pub use fit::{
    FitBounds, FitOptions, FitWeights, FittedVariogram, MATERN_NU_BOUNDS, MATERN_NUS, NestedFit,
    fit_nested, fit_variogram,
};
pub use geo::{
    Drift, Krige, KrigeModel, LooStats, Neighbourhood, Prediction, Predictions, VariogramChoice,
    VariogramFitReport,
};
pub use kriging::{EAGER_INVERSE_MAX_SAMPLES, Kriging, augmented_params, variogram_column};
pub use linalg::{PINV_RTOL, compress_columns, sym_pinv};
pub use nested::{NestedVariogram, Structure};
pub use projected::ProjectedQuery;
pub use rbf::{RBF_SMOOTHING_GRID, Rbf, RbfConfig, RbfKernel, RbfSmoothing, SmoothingCandidate};
pub use scaling::{ParamScaling, ScalingChoice};
pub use select::{
    DimDecision, DimSelection, SelectRule, TRIAL_SEARCH_MAX_SAMPLES, held_out_squared_error,
    select_dims, select_dims_by_folds,
};
pub use simulate::{MAX_SIMULATED_VALUES, Realisations, Sgs, SgsMean, SgsPath};
pub use sphere::{chord_distance, great_circle_distance, latlon_to_xyz};
pub use variogram::{Variogram, VariogramModel, shape};

/// Fails with [`KrigingError::NonFinite`] at the first NaN or infinity of `m` (column by column).
pub(crate) fn check_finite(
    what: &'static str,
    m: faer::MatRef<'_, f64>,
) -> Result<(), KrigingError> {
    for j in 0..m.ncols() {
        for i in 0..m.nrows() {
            if !m[(i, j)].is_finite() {
                return Err(KrigingError::NonFinite {
                    what,
                    row: i,
                    col: j,
                });
            }
        }
    }
    Ok(())
}
