//! The error type of every fallible function in this crate.

use thiserror::Error;

/// What went wrong, and where (sequence index, frame, column, lengths).
///
/// Sequence indices refer to the position in the slice the caller passed in; for the two-sequence
/// [`dtw`](crate::dtw) the first argument is sequence 0 and the second is sequence 1.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum TimewarpError {
    /// No sequences were given where at least one is needed.
    #[error("no sequences given")]
    NoSequences,
    /// A sequence has zero columns per frame.
    #[error("sequence {index}: frame dimension is 0")]
    ZeroDim {
        /// Index of the sequence.
        index: usize,
    },
    /// A sequence's buffer length is not a multiple of its frame dimension.
    #[error("sequence {index}: {len} values is not a whole number of frames of dimension {dim}")]
    RaggedFrames {
        /// Index of the sequence.
        index: usize,
        /// Length of the flat buffer.
        len: usize,
        /// Declared frame dimension.
        dim: usize,
    },
    /// A sequence has fewer frames than the operation needs.
    #[error("sequence {index}: {frames} frames, at least {needed} needed")]
    TooShort {
        /// Index of the sequence.
        index: usize,
        /// Number of frames it has.
        frames: usize,
        /// Number of frames needed.
        needed: usize,
    },
    /// Two sequences that must share a frame dimension do not.
    #[error("sequence {index}: frame dimension {found}, expected {expected}")]
    DimMismatch {
        /// Index of the offending sequence.
        index: usize,
        /// The dimension of the first sequence of the set.
        expected: usize,
        /// The dimension found.
        found: usize,
    },
    /// A value is NaN or infinite.
    #[error("sequence {index}, frame {frame}, column {column}: value {value} is not finite")]
    NonFinite {
        /// Index of the sequence.
        index: usize,
        /// Frame within the sequence.
        frame: usize,
        /// Column within the frame.
        column: usize,
        /// The offending value.
        value: f64,
    },
    /// The feature and value slices hold different numbers of sequences.
    #[error("{features} feature sequences but {values} value sequences")]
    CountMismatch {
        /// Number of feature sequences.
        features: usize,
        /// Number of value sequences (or frame times).
        values: usize,
    },
    /// A feature sequence and its value sequence have different numbers of frames.
    #[error("sequence {index}: {features} feature frames but {values} value frames")]
    FrameCountMismatch {
        /// Index of the sequence.
        index: usize,
        /// Frames in the feature sequence.
        features: usize,
        /// Frames in the value sequence.
        values: usize,
    },
    /// A frame time (seconds per source frame) is not finite and positive.
    #[error("sequence {index}: frame time {value} s is not finite and positive")]
    BadFrameTime {
        /// Index of the sequence.
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// The requested reference sequence does not exist.
    #[error("reference {reference} out of range for {count} sequences")]
    ReferenceOutOfRange {
        /// Requested reference index.
        reference: usize,
        /// Number of sequences.
        count: usize,
    },
    /// A configuration value is out of its valid range.
    #[error("invalid configuration: {what} = {value} ({reason})")]
    InvalidConfig {
        /// Name of the parameter.
        what: &'static str,
        /// Its value, formatted.
        value: String,
        /// Why it is rejected.
        reason: &'static str,
    },
    /// Band and slope constraints leave no warping path between two sequences.
    #[error(
        "no warping path between sequences of {len_a} and {len_b} frames within band {band} \
         and at most {max_slope} consecutive steps along one axis"
    )]
    NoPath {
        /// Frames of the first sequence.
        len_a: usize,
        /// Frames of the second sequence.
        len_b: usize,
        /// Band of the configuration.
        band: f64,
        /// Slope limit of the configuration.
        max_slope: usize,
    },
    /// The DTW cost of two sequences is not finite although the constraints admit a path: the
    /// squared distances of their feature values (or their sum along the path) overflow `f64`.
    /// The features are too large (around `1e154` and above); scale them down.
    #[error(
        "the DTW cost between sequences of {len_a} and {len_b} frames is not finite: the squared \
         distances of the feature values overflow (the values are too large; scale them down)"
    )]
    NonFiniteCost {
        /// Frames of the first sequence.
        len_a: usize,
        /// Frames of the second sequence.
        len_b: usize,
    },
    /// A buffer that the inputs ask for exceeds this crate's documented limit
    /// ([`MAX_BUFFER_VALUES`](crate::MAX_BUFFER_VALUES) values,
    /// [`MAX_PLAYBACK_FRAMES`](crate::MAX_PLAYBACK_FRAMES) frames): the memory it needs could
    /// not be allocated (or would be absurd).
    #[error("{what}: {requested} exceeds the limit of {limit}")]
    TooLarge {
        /// What would be allocated, e.g. "DTW table values".
        what: &'static str,
        /// The size asked for, formatted (it may not fit a `usize`).
        requested: String,
        /// The limit.
        limit: usize,
    },
    /// A sequence's duration, `(frames - 1) * frame_time`, overflows `f64`.
    #[error("sequence {index}: {frames} frames of {frame_time} s overflow the duration")]
    DurationOverflow {
        /// Index of the sequence.
        index: usize,
        /// Frames of the sequence.
        frames: usize,
        /// Its frame time in seconds.
        frame_time: f64,
    },
    /// The cumulative playback times ([`fill_times`](crate::fill_times)) of an aligned sequence
    /// are not finite or stop increasing: its increments are so large that the sum overflows or
    /// absorbs the next increment (durations around `1e10` s and above).
    #[error(
        "playback time {time} s at aligned frame {frame} is not finite or does not increase \
         (the time increments are too large)"
    )]
    PlaybackTimes {
        /// The aligned frame whose time is bad.
        frame: usize,
        /// Its cumulative time in seconds.
        time: f64,
    },
    /// DTW failed between the reference and one sequence of a set.
    #[error("sequence {index} against reference {reference}: {source}")]
    Pair {
        /// Index of the sequence.
        index: usize,
        /// Index of the reference.
        reference: usize,
        /// The underlying error.
        #[source]
        source: Box<TimewarpError>,
    },
}
