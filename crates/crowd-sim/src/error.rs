//! Error types of the crate: one enum for the simulation, one for rendering and file output.

use std::path::PathBuf;

/// What went wrong while building or stepping a crowd.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum CrowdError {
    /// `CrowdConfig::walkers` was zero.
    #[error("a crowd needs at least one walker (config.walkers = 0)")]
    NoWalkers,
    /// `CrowdConfig::walkers` is above [`MAX_WALKERS`](crate::MAX_WALKERS).
    #[error(
        "config.walkers = {walkers} is above the most walkers a crowd holds ({})",
        crate::MAX_WALKERS
    )]
    TooManyWalkers {
        /// The walkers asked for.
        walkers: usize,
    },
    /// The system refused the memory of a crowd's buffers (or their size does not fit in the
    /// address space): the crowd is too large for this machine.
    #[error("cannot allocate the {what} of {walkers} walkers: out of memory")]
    OutOfMemory {
        /// Which buffer.
        what: &'static str,
        /// Walkers of the crowd.
        walkers: usize,
    },
    /// The clip source reports no accuracy level or an empty pose vector.
    #[error(
        "clip source has no levels: accuracy_levels = {accuracy_levels}, pose_len = {pose_len}"
    )]
    NoLevels {
        /// Number of accuracy levels reported by the source.
        accuracy_levels: usize,
        /// Pose vector length reported by the source.
        pose_len: usize,
    },
    /// The clip source reports no clip size class, or more than the crowd keeps.
    #[error(
        "clip source reports {classes} clip size classes (1 to {} allowed)",
        crate::source::MAX_CLIP_CLASSES
    )]
    ClipClasses {
        /// What `ClipSource::clip_classes` returned.
        classes: usize,
    },
    /// The control range of the source is not finite, inverted, or allows no forward motion/turn.
    #[error("clip source control range is unusable: {what}")]
    BadControlRange {
        /// Which bound is wrong.
        what: &'static str,
    },
    /// A configuration value is out of range (not finite, zero, negative...).
    #[error("crowd config field `{field}` is invalid: {value}")]
    BadConfig {
        /// Name of the field in `CrowdConfig`.
        field: &'static str,
        /// Offending value.
        value: f64,
    },
    /// A configuration value is finite but above its limit (the field side above
    /// [`MAX_FIELD_M`](crate::MAX_FIELD_M)).
    #[error("crowd config field `{field}` = {value} is above its limit {max}")]
    AboveLimit {
        /// Name of the field in `CrowdConfig`.
        field: &'static str,
        /// Offending value.
        value: f64,
        /// The largest value accepted.
        max: f64,
    },
    /// The field, enlarged to fit the paths the source's turn range can follow (and
    /// `CrowdConfig::border_m`), is larger than a crowd places walkers on
    /// ([`MAX_FIELD_M`](crate::MAX_FIELD_M)).
    #[error(
        "paths need a field of {needed_m} m (turn range too narrow or border_m too large), above \
         the largest a crowd places walkers on ({} m)",
        crate::MAX_FIELD_M
    )]
    FieldTooLarge {
        /// The side length the paths need (m).
        needed_m: f32,
    },
    /// The field is too small for paths whose curvature the source's turn range can follow.
    #[error(
        "field of {field_m} m is too small: paths need at least {needed_m} m (turn range too narrow?)"
    )]
    FieldTooSmall {
        /// Configured field side length in metres.
        field_m: f32,
        /// Smallest side length that fits one path.
        needed_m: f32,
    },
    /// A camera parameter is NaN/infinite or degenerate.
    #[error("camera is invalid: {what}")]
    BadCamera {
        /// Which parameter is wrong.
        what: &'static str,
    },
    /// The time step is not finite, negative, or longer than the crowd steps in one frame
    /// (`crate::MAX_DT`).
    #[error("time step dt = {dt} s is not in [0, {}] s", crate::MAX_DT)]
    BadTimeStep {
        /// Offending time step in seconds.
        dt: f32,
    },
    /// The source built a clip whose duration is not finite or too short to play.
    #[error("walker {walker}: clip duration {duration} s is not a finite value >= 1 ms")]
    BadClipDuration {
        /// Index of the walker whose clip is wrong.
        walker: usize,
        /// Reported duration in seconds.
        duration: f32,
    },
    /// The source could not build a walker's first clip (there is no previous clip to keep).
    #[error("walker {walker}: first clip: {error}")]
    FirstClip {
        /// Index of the walker.
        walker: usize,
        /// The source's error.
        error: ClipError,
    },
    /// The policy asked for an accuracy level the source does not have.
    #[error("walker {walker}: policy asked for accuracy level {level}, source has {levels}")]
    BadLevel {
        /// Index of the walker.
        walker: usize,
        /// Requested accuracy level.
        level: usize,
        /// Number of accuracy levels of the source.
        levels: usize,
    },
    /// The policy asked for more active joints than the source has (at an accuracy level it has).
    #[error(
        "walker {walker}: policy asked for {active_joints} active joints (at accuracy level \
         {level}), source has {joints} joints"
    )]
    BadJoints {
        /// Index of the walker.
        walker: usize,
        /// Requested accuracy level (one the source has).
        level: usize,
        /// Requested active joints.
        active_joints: usize,
        /// Number of joints of the source (besides the root).
        joints: usize,
    },
}

/// Why a [`ClipSource`](crate::ClipSource) could not build a clip, in the source's words.
///
/// During a step the crowd does not stop on it: the walker keeps its previous clip and the fault
/// is counted in the frame's statistics ([`FrameStats::clip_faults`](crate::FrameStats)).
#[derive(Debug, thiserror::Error, Clone, PartialEq, Eq)]
#[error("{0}")]
pub struct ClipError(pub String);

/// What went wrong while rendering or writing images.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The output directory cannot be created or written.
    #[error("cannot write to directory {path}: {source}")]
    Dir {
        /// The directory.
        path: PathBuf,
        /// Underlying I/O error.
        source: std::io::Error,
    },
    /// Writing or renaming a file failed.
    #[error("cannot write {path}: {source}")]
    Io {
        /// The file being written.
        path: PathBuf,
        /// Underlying I/O error.
        source: std::io::Error,
    },
    /// The PNG encoder failed.
    #[error("PNG encoding of {path} failed: {message}")]
    Png {
        /// The file being written.
        path: PathBuf,
        /// Encoder message.
        message: String,
    },
    /// The GIF encoder failed.
    #[error("GIF encoding of {path} failed: {message}")]
    Gif {
        /// The file being written.
        path: PathBuf,
        /// Encoder message.
        message: String,
    },
    /// Image size is zero or too large for the format.
    #[error("image size {width}x{height} is not supported ({what})")]
    BadSize {
        /// Requested width in pixels.
        width: u32,
        /// Requested height in pixels.
        height: u32,
        /// Why it is refused.
        what: &'static str,
    },
    /// The camera used for rendering is invalid.
    #[error(transparent)]
    Camera(#[from] CrowdError),
}
