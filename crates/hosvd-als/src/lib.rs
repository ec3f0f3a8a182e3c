//! Tucker decompositions for motion tensors: HOSVD, HOOI/ALS and the key-level search.
//!
//! This crate is for: the tensor mathematics of Mukai and Kuriyama sections 3.2 and 4.1-4.2 (HOSVD,
//! truncated HOSVD, HOOI/ALS at a rank triple, the greedy key-tensor search, hybrid truncation and
//! storage accounting). It is not for: interpolation over controls (see `kriging`) or runtime pose
//! evaluation (see `lod-policy`).
//!
//! Conventions (see `docs/architecture.md`): modes 0, 1, 2 = joint DOF, time, samples; factors
//! are `I_n x R_n` with orthonormal columns; every [`Tucker`] handed out has an *ordered* core
//! (all-orthogonal, mode-n singular values decreasing), so leading truncation is the reduction.
//! Errors: `mse = ||X - X~||^2 / (I_0 I_1 I_2)` (the paper's E) and `rel_error = ||X - X~|| / ||X||`,
//! computed from norms (`||X||^2 - ||Z||^2`) without forming `X~`. The large products (mode
//! products, Gram matrices, the sample factor's projections) run in parallel on the current rayon
//! pool with the bits of the single-threaded product ([`tensor_ops::par::matmul_blocked`]), and the
//! eigendecompositions single-threaded, so results are identical for any thread count.
//!
//! ```
//! use hosvd_als::{AlsOptions, KeySearchConfig, hooi, hosvd, hybrid_levels, key_levels};
//! use hosvd_als::storage::key_levels_bytes;
//! use tensor_ops::Tensor3;
//!
//! let x = Tensor3::from_fn([8, 9, 10], |i, j, k| {
//!     ((i + 1) as f64 * 0.3).sin() * ((j * k) as f64 * 0.1).cos() + 0.01 * ((i * j + k) % 7) as f64
//! }).unwrap();
//! let h = hosvd(&x, [3, 3, 3]).unwrap();
//! let (als, report) = hooi(&x, [3, 3, 3], &AlsOptions::default()).unwrap();
//! assert!(report.rel_error < 0.5);
//! assert_eq!(als.ranks(), h.ranks());
//! // Per-sample core K_i = Z x_2 u_{S,i} (paper eq. 7).
//! assert_eq!(als.sample_core(4).nrows(), 3);
//!
//! let cfg = KeySearchConfig { levels: 3, max_ranks: [5, 5, 5], min_ranks: [2, 2, 2], ..Default::default() };
//! let keys = key_levels(&x, &cfg).unwrap();
//! assert_eq!(keys.levels.len(), 3);
//! let acc = hybrid_levels(&keys, 7);
//! assert_eq!(acc.len(), 7);
//! let model = keys.model_at(&acc[1]).unwrap();
//! assert_eq!(model.ranks(), acc[1].ranks);
//! // Stored as f32 (4 bytes a value) against f64 (8 bytes).
//! assert!(key_levels_bytes(&keys, 4) < key_levels_bytes(&keys, 8));
//! ```

#![warn(missing_docs)]

mod eig;
mod error;
mod gram;
mod hooi;
mod hosvd;
mod hybrid;
mod keys;
mod project;
pub mod storage;
pub mod synthetic;
mod tucker;

pub use error::HosvdError;
pub use hooi::{AlsOptions, AlsReport, hooi, hooi_with_start};
pub use hosvd::{hosvd, hosvd_full};
pub use hybrid::{HybridLevel, MAX_ACCURACY_LEVELS, hybrid_levels};
pub use keys::{KeyLevel, KeyLevels, KeySearchConfig, key_levels};
pub use tucker::Tucker;
