//! Error types of the runtime model: shape and value validation, kernel evaluation, variogram
//! parameters and rigs (the model file's errors are [`crate::file::FileError`]).

use thiserror::Error;

/// Why a [`crate::model::LodModel`] (or one of its parts) was rejected.
///
/// Every variant names the part (`what`), and where relevant the key or level index and the
/// offending dimension or element, so a malformed model file can be traced to its producer.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ModelError {
    /// A size that must be positive is zero (`P`, `T`, `S`, a rank, the number of keys or levels).
    #[error("{what} must be positive")]
    ZeroSize {
        /// Which size.
        what: String,
    },
    /// An array has the wrong number of elements.
    #[error("{what}: expected {expected} values, found {found}")]
    Length {
        /// Which array (for example `key 2 core`).
        what: String,
        /// Number of elements its dimensions imply.
        expected: usize,
        /// Number of elements present.
        found: usize,
    },
    /// A value is NaN or infinite.
    #[error("{what}: non-finite value at element {index}")]
    NonFinite {
        /// Which array.
        what: String,
        /// Flat index of the first bad element.
        index: usize,
    },
    /// A rank exceeds the mode size, or an accuracy level's rank exceeds its key's rank.
    #[error("{what}: rank {rank} exceeds the limit {limit}")]
    Rank {
        /// Which rank (for example `level 3 r_T`).
        what: String,
        /// The rank given.
        rank: usize,
        /// Largest allowed value.
        limit: usize,
    },
    /// An accuracy level refers to a key tensor that does not exist.
    #[error("accuracy level {level} refers to key {key}, but the model has {keys} keys")]
    KeyIndex {
        /// Accuracy level index.
        level: usize,
        /// Key index it names.
        key: usize,
        /// Number of key tensors.
        keys: usize,
    },
    /// Accuracy levels are out of key order (a level truncates an earlier key than the level
    /// before it).
    #[error(
        "accuracy level {level} truncates key {key}, after a level of key {previous}: levels go from key 0 down"
    )]
    KeyOrder {
        /// Accuracy level index.
        level: usize,
        /// Key it truncates.
        key: usize,
        /// Key of the level before it.
        previous: usize,
    },
    /// Dimensions whose product (an array's size) overflows the address space.
    #[error("{what}: its dimensions are too large to hold in memory")]
    TooLarge {
        /// Which array.
        what: String,
    },
    /// The DOF row layout is inconsistent (`always_rows`, `rows_per_joint` and `P`).
    #[error("row layout: {0}")]
    RowLayout(String),
    /// The control space is inconsistent (bounds, scales).
    #[error("control space: {0}")]
    Controls(String),
    /// The per-level error table does not have one entry per accuracy level, or holds a bad value.
    #[error("error table: {0}")]
    ErrorTable(String),
    /// A small dense linear system met while building a projection was singular.
    #[error("{what}: singular matrix (pivot {pivot} at column {column})")]
    Singular {
        /// Which system.
        what: String,
        /// Column where elimination failed.
        column: usize,
        /// Magnitude of the best pivot found.
        pivot: f64,
    },
}

/// Why a clip kernel could not be built.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum KernelError {
    /// The control vector has the wrong length.
    #[error("controls: expected {expected} values, found {found}")]
    ControlLength {
        /// Model's control dimension `d`.
        expected: usize,
        /// Length given.
        found: usize,
    },
    /// A style weight of [`crate::StyleMix`] is NaN, infinite or negative.
    #[error("style weight {index} is {value}: style weights are finite and >= 0")]
    Style {
        /// Style index.
        index: usize,
        /// The weight given.
        value: f32,
    },
    /// A control value is NaN or infinite.
    #[error("control {index} is not finite ({value})")]
    NonFiniteControl {
        /// Control dimension.
        index: usize,
        /// The value given.
        value: f32,
    },
    /// [`crate::LodModel::kriging_weights`]: the key is out of range, or the number of weights is not
    /// in `1..=R_S` of that key.
    #[error("key {key} with {r_s} sample weights: the model has {keys} keys, that key R_S = {max}")]
    Key {
        /// The key asked for.
        key: usize,
        /// The number of weights asked for.
        r_s: usize,
        /// Keys in the model.
        keys: usize,
        /// `R_S` of the key (0 when it does not exist).
        max: usize,
    },
    /// The requested accuracy level does not exist.
    #[error("accuracy level {level} out of range (model has {levels})")]
    Level {
        /// Level requested.
        level: usize,
        /// Number of levels.
        levels: usize,
    },
    /// The requested detail evaluates more joints than the model has.
    #[error("{joints} joints requested; the model animates {max}")]
    Joints {
        /// Joints requested.
        joints: usize,
        /// Joints of the model.
        max: usize,
    },
    /// The pose output slice has the wrong length.
    #[error("pose output: expected {expected} values, found {found}")]
    OutputLength {
        /// Model's `P`.
        expected: usize,
        /// Length given.
        found: usize,
    },
    /// The phase is NaN or infinite.
    #[error("phase is not finite ({phase})")]
    NonFinitePhase {
        /// The phase given.
        phase: f32,
    },
    /// The kernel or scratch was preallocated for a different (smaller) model, or the kernel
    /// was built by another model (its ranks or rows exceed those of this model's level).
    #[error("{what} was allocated for a different model ({detail})")]
    Capacity {
        /// `kernel` or `scratch`.
        what: &'static str,
        /// Which size does not fit.
        detail: String,
    },
    /// [`crate::LodModel::build_kernel`]: the model's values are so large that the clip for these
    /// controls overflows (a kriging weight, an entry of `G(c)` that could make a pose infinite,
    /// the clip's duration or its root motion is not finite). The model passed validation but
    /// cannot animate these controls; the kernel is left unbuilt (it reads as
    /// [`crate::ClipKernel::new`]'s does).
    #[error(
        "clip overflows: {what} at element {index} is {value} (the model's values are too large)"
    )]
    Overflow {
        /// What overflowed: `kriging weights`, `G(c)`, `duration` or `root motion`.
        what: &'static str,
        /// Index of the first bad element.
        index: usize,
        /// Its value.
        value: f64,
    },
}

/// A variogram parameter outside its domain ([`crate::Variogram::validate`]).
#[derive(Debug, Clone, PartialEq, Error)]
#[error("invalid {model} variogram: {reason}")]
pub struct VariogramError {
    /// The model's name ([`crate::VariogramModel::name`]).
    pub model: &'static str,
    /// Which parameter is wrong, with its value.
    pub reason: String,
}

/// Why a [`crate::Rig`] could not be built, or forward kinematics could not run on the buffers
/// given.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum RigError {
    /// A joint (or the rig as a whole) does not fit the rig's rules.
    #[error("joint {joint} ({name}): {reason}")]
    Joint {
        /// Index of the joint in the rig.
        joint: usize,
        /// Its name.
        name: String,
        /// What is wrong.
        reason: String,
    },
    /// The rig has no joint, or no root joint.
    #[error("rig: {0}")]
    Structure(String),
    /// The pose is shorter than the rows the active joints read.
    #[error("pose: {found} rows, the {active} active joints read {needed}")]
    PoseLength {
        /// Joints read from the pose.
        active: usize,
        /// Rows they need.
        needed: usize,
        /// Rows given.
        found: usize,
    },
    /// The output slice is shorter than the rig's joint count.
    #[error("output: {found} slots for {joints} joints")]
    OutputLength {
        /// Joints of the rig.
        joints: usize,
        /// Slots given.
        found: usize,
    },
    /// The body scale is not a finite positive number.
    #[error("body scale {0} is not a finite positive number")]
    Scale(f32),
    /// A pose row forward kinematics reads is NaN, infinite or larger in magnitude than
    /// [`crate::MAX_POSE_VALUE`].
    #[error(
        "pose row {row} is {value}: the rows forward kinematics reads must be finite and at most 1e18 in magnitude"
    )]
    PoseValue {
        /// The row.
        row: usize,
        /// Its value.
        value: f32,
    },
    /// The root's distance from the origin plus the rig's longest chain of bones at the body
    /// scale is so large that joint positions could overflow single precision.
    #[error(
        "root and bones reach {reach_m} m at body scale {scale}: joint positions would overflow"
    )]
    Overflow {
        /// The body scale.
        scale: f32,
        /// The root's largest coordinate plus the longest chain of bones at `scale`, in metres.
        reach_m: f64,
    },
}
