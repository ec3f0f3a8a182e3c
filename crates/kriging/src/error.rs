//! The error type of every fallible operation in this crate.

use crate::variogram::VariogramModel;

/// What went wrong, and where (sample index, dimension, matrix size).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum KrigingError {
    /// An input has the wrong length or shape.
    #[error("{what}: expected {expected}, got {got}")]
    ShapeMismatch {
        /// Which input (for example `"values rows"` or `"query length"`).
        what: &'static str,
        /// The size that was needed.
        expected: usize,
        /// The size that was given.
        got: usize,
    },
    /// An input holds NaN or an infinity.
    #[error("{what} is not finite at row {row}, column {col}")]
    NonFinite {
        /// Which input.
        what: &'static str,
        /// Row (sample) index.
        row: usize,
        /// Column (dimension) index.
        col: usize,
    },
    /// Not enough samples for the requested method.
    #[error("{what} needs at least {needed} samples, got {got}")]
    TooFewSamples {
        /// The method or step that needs them.
        what: &'static str,
        /// Minimum sample count.
        needed: usize,
        /// Sample count given.
        got: usize,
    },
    /// Two samples have the same parameters after scaling and nothing regularises the system.
    #[error(
        "samples {first} and {second} have the same scaled parameters: the {what} system is singular \
         (remove one, or fit a variogram with a nugget)"
    )]
    DuplicateParams {
        /// Which system (`"kriging"` or `"rbf"`).
        what: &'static str,
        /// The smaller sample index.
        first: usize,
        /// The larger sample index.
        second: usize,
    },
    /// All samples sit at the same point of the (scaled) parameter space.
    #[error("all {samples} samples have the same scaled parameters: no distances to work with")]
    NoSpread {
        /// Sample count.
        samples: usize,
    },
    /// A variogram model could not be fitted to the empirical variogram.
    #[error("cannot fit a {model:?} variogram: {reason}")]
    VariogramFit {
        /// The model that failed (`None` when the empirical variogram itself is unusable).
        model: Option<VariogramModel>,
        /// Why.
        reason: String,
    },
    /// Variogram parameters outside their domain.
    #[error("invalid {model:?} variogram: {reason}")]
    InvalidVariogram {
        /// The model.
        model: VariogramModel,
        /// Which parameter is wrong and why.
        reason: String,
    },
    /// A configuration value is out of range.
    #[error("invalid configuration: {0}")]
    InvalidConfig(String),
    /// Finite input whose intermediate results leave the range of double precision: values or
    /// coordinates so large (or so far apart) that their squares, variances or distances
    /// overflow, or so close together that their squared distances underflow to zero. Reported
    /// instead of the misleading consequence (values that seem not to vary, samples that seem to
    /// coincide, a dimension that seems constant, a NaN result). Rescale the input.
    #[error(
        "{what}: {reason} (too large or too small to compute with in double precision; rescale)"
    )]
    Overflow {
        /// What overflowed (for example `"values column 0"` or `"coordinates"`).
        what: String,
        /// What was computed and what it gave.
        reason: String,
    },
    /// A scaling is malformed (wrong length, negative or non-finite entries).
    #[error("invalid parameter scaling at dimension {dim}: {reason}")]
    InvalidScaling {
        /// The dimension.
        dim: usize,
        /// Why.
        reason: String,
    },
    /// The linear system is singular or too ill-conditioned to trust.
    #[error(
        "the {what} system ({size} x {size}) is singular or ill-conditioned \
         (smallest/largest pivot {pivot_ratio:.3e}, relative residual {residual:.3e})"
    )]
    Singular {
        /// Which system.
        what: &'static str,
        /// Its size.
        size: usize,
        /// Smallest over largest absolute LU pivot.
        pivot_ratio: f64,
        /// Relative residual of a probe solve.
        residual: f64,
    },
    /// Automatic model selection found no usable model.
    #[error("no variogram model could be used: {0}")]
    NoModel(String),
    /// The drift (trend) system of universal kriging is singular or too ill-conditioned: the drift
    /// terms are (nearly) linearly dependent over the samples, for example a linear drift on
    /// collinear samples or a quadratic drift on points along a curve.
    #[error(
        "the drift system ({terms} terms over {samples} samples) is ill-conditioned \
         (eigenvalue ratio {ratio:.3e}): the drift terms are (nearly) dependent over the samples; \
         use a lower-order drift"
    )]
    IllConditionedDrift {
        /// Number of drift terms.
        terms: usize,
        /// Number of samples in the system.
        samples: usize,
        /// Smallest over largest eigenvalue of `F^t C^-1 F`.
        ratio: f64,
    },
    /// A query point of a moving neighbourhood has too few samples within reach.
    #[error("query point {point} has {got} samples in its neighbourhood, needs at least {needed}")]
    QueryNeighbourhood {
        /// Index of the query point.
        point: usize,
        /// Samples needed (drift terms plus one).
        needed: usize,
        /// Samples found.
        got: usize,
    },
    /// Two conditioning data of a simulation sit at the same place: a realisation takes one value
    /// per site, so the data contradict each other (average or drop the duplicates).
    #[error(
        "data {first} and {second} sit at the same place: a realisation has one value per site \
         (average or drop the duplicates before simulating)"
    )]
    CoincidentData {
        /// The smaller data index.
        first: usize,
        /// The larger data index.
        second: usize,
    },
    /// A node of a sequential simulation ([`crate::Sgs`]) could not be simulated: its local
    /// kriging system failed (`source`: for example [`KrigingError::Singular`], or
    /// [`KrigingError::QueryNeighbourhood`] for ordinary kriging without neighbours).
    #[error(
        "sequential simulation at target {target}{}: {source}",
        realisation.map(|r| format!(" (realisation {r})")).unwrap_or_default()
    )]
    SimulationNode {
        /// The target (row of the target matrix) being simulated.
        target: usize,
        /// The realisation, when the failure depends on it (a path per realisation); `None` when
        /// the system is shared by every realisation ([`crate::SgsPath::Shared`]).
        realisation: Option<usize>,
        /// What went wrong with the node's kriging system.
        #[source]
        source: Box<KrigingError>,
    },
}
