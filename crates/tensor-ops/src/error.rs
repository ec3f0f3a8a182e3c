//! Errors of tensor construction, shape checks and NPY exchange.

use std::path::PathBuf;

/// Everything that can go wrong with a [`crate::Tensor3`] or an NPY file. Each variant names what
/// failed and where (index, dimension, byte offset, file).
#[derive(Debug, thiserror::Error)]
pub enum TensorError {
    /// `dims` asks for more elements than `usize` can count, or (for an empty tensor) the product
    /// of its nonzero dimensions overflows.
    #[error("tensor dims {dims:?} overflow usize")]
    DimsOverflow {
        /// The requested dimensions.
        dims: [usize; 3],
    },
    /// The data length does not match the product of the dimensions.
    #[error("tensor dims {dims:?} need {expected} values, got {found}")]
    SizeMismatch {
        /// The requested dimensions.
        dims: [usize; 3],
        /// `dims[0] * dims[1] * dims[2]`.
        expected: usize,
        /// Length of the supplied data.
        found: usize,
    },
    /// A value is NaN or infinite.
    #[error("non-finite value {value} at index ({i}, {j}, {k})")]
    NonFinite {
        /// Mode-0 index.
        i: usize,
        /// Mode-1 index.
        j: usize,
        /// Mode-2 index.
        k: usize,
        /// The offending value.
        value: f64,
    },
    /// A mode number outside `0..3`.
    #[error("mode {mode} out of range (a 3-mode tensor has modes 0, 1, 2)")]
    BadMode {
        /// The requested mode.
        mode: usize,
    },
    /// A matrix or vector operand has the wrong shape for the requested operation.
    #[error("shape mismatch in {what}: expected {expected}, found {found}")]
    ShapeMismatch {
        /// The operation and operand, e.g. "mode_product(1) matrix columns".
        what: &'static str,
        /// The size required by the tensor.
        expected: usize,
        /// The size supplied.
        found: usize,
    },
    /// A truncation rank is zero or larger than the mode size.
    #[error("rank {rank} invalid for mode {mode} of size {size} (need 1..={size})")]
    BadRank {
        /// The mode.
        mode: usize,
        /// The requested rank.
        rank: usize,
        /// The mode size.
        size: usize,
    },
    /// Reading or writing a file failed.
    #[error("I/O error on {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The bytes are not a valid NPY file.
    #[error("malformed NPY{}: {reason}", location(.path, *.offset))]
    NpyMalformed {
        /// The file, when reading from a file.
        path: Option<PathBuf>,
        /// Byte offset of the problem.
        offset: usize,
        /// What is wrong.
        reason: String,
    },
    /// A valid NPY file whose content this crate does not handle (dtype, version).
    #[error("unsupported NPY{}: {reason}", location(.path, *.offset))]
    NpyUnsupported {
        /// The file, when reading from a file.
        path: Option<PathBuf>,
        /// Byte offset of the header field.
        offset: usize,
        /// What is unsupported.
        reason: String,
    },
    /// An NPY array has the wrong number of dimensions for the requested conversion.
    #[error("NPY array has shape {shape:?}, expected a {expected}-D array")]
    NpyRank {
        /// The array's shape.
        shape: Vec<usize>,
        /// The required number of dimensions.
        expected: usize,
    },
    /// The NPY array has no elements (a zero in its shape), so it is no matrix or tensor; its other
    /// dimensions may be absurdly large without costing any data.
    #[error("NPY array of shape {shape:?} has no elements")]
    NpyEmpty {
        /// The shape read from the header.
        shape: Vec<usize>,
    },
}

fn location(path: &Option<PathBuf>, offset: usize) -> String {
    match path {
        Some(p) => format!(" ({}, byte {offset})", p.display()),
        None => format!(" (byte {offset})"),
    }
}
