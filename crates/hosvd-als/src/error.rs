//! Errors of the decompositions and the key-level search.

use tensor_ops::TensorError;

/// Everything that can go wrong in this crate, naming what and where.
#[derive(Debug, thiserror::Error)]
pub enum HosvdError {
    /// A tensor-level problem: bad rank triple (mode, rank, size), NaN/inf (with its index),
    /// shape mismatch.
    #[error(transparent)]
    Tensor(#[from] TensorError),
    /// The tensor has a zero dimension.
    #[error("cannot decompose an empty tensor of dims {dims:?}")]
    EmptyTensor {
        /// The tensor's dims.
        dims: [usize; 3],
    },
    /// The symmetric eigensolver failed to converge on a Gram matrix.
    #[error(
        "eigen-decomposition of the mode-{mode} Gram matrix ({size} x {size}) did not converge"
    )]
    Eigen {
        /// The mode whose Gram matrix failed.
        mode: usize,
        /// The Gram matrix size.
        size: usize,
    },
    /// A Gram matrix `X_(n) X_(n)^T` (or one of the projected tensor's) has entries that
    /// overflowed to infinity: the data are finite but too large (squares around `1e308`, values
    /// around `1e154` and above). Scale the tensor down before decomposing it.
    #[error(
        "the mode-{mode} Gram matrix ({size} x {size}) overflowed to a non-finite value: the data \
         are too large (scale the tensor down)"
    )]
    GramOverflow {
        /// The mode whose Gram matrix overflowed.
        mode: usize,
        /// The Gram matrix size.
        size: usize,
    },
    /// An ALS option is out of range.
    #[error("invalid ALS option {field} = {value}: {reason}")]
    BadOption {
        /// The field name.
        field: &'static str,
        /// Its value, printed.
        value: String,
        /// What is required.
        reason: &'static str,
    },
    /// The key-level search configuration is inconsistent.
    #[error("invalid key search configuration: {0}")]
    BadKeyConfig(String),
    /// A starting factor for warm-started ALS has the wrong shape.
    #[error("start factor {mode} is {rows} x {cols}, expected {expected_rows} x {expected_cols}")]
    BadStart {
        /// The mode.
        mode: usize,
        /// Rows found.
        rows: usize,
        /// Columns found.
        cols: usize,
        /// Rows required (the mode size).
        expected_rows: usize,
        /// Columns required (the rank).
        expected_cols: usize,
    },
}
