//! Dense three-mode tensors for multilinear analysis.
//!
//! This crate is for: a real (f64) `P x T x S` tensor stored contiguously, its mode-n unfoldings and
//! foldings as de Lathauwer et al. define them, n-mode products with matrices and vectors, leading
//! sub-tensor truncation, Frobenius norms, Tucker reconstruction and NPY exchange with numpy.
//! It is not for: decompositions (see `hosvd-als`), general N-mode tensors, or sparse data.
//!
//! Large products run in parallel on the current rayon pool with the bits of the single-threaded
//! product ([`par::matmul_blocked`]), so every result is the same for any thread count.
//!
//! Layout: element `(i, j, k)` of an `I x J x K` [`Tensor3`] is stored at `i + I * (j + J * k)`
//! (numpy's Fortran order), so each mode-2 slice ([`Tensor3::sample`]) is a contiguous
//! column-major `I x J` block. Modes are numbered 0, 1, 2 (the paper's 1, 2, 3).
//!
//! ```
//! use tensor_ops::{Tensor3, reconstruct};
//! use faer::Mat;
//!
//! let x = Tensor3::from_fn([2, 3, 4], |i, j, k| (i + 2 * j + 6 * k) as f64).unwrap();
//! // Mode-1 product with a 5 x 3 matrix: the time mode grows to 5.
//! let a = Mat::<f64>::from_fn(5, 3, |r, c| (r + c) as f64);
//! assert_eq!(x.mode_product(1, a.as_ref()).dims(), [2, 5, 4]);
//! // fold(unfold(X)) = X in every mode.
//! for mode in 0..3 {
//!     let m = x.unfold(mode);
//!     assert_eq!(Tensor3::fold(mode, m.as_ref(), x.dims()).unwrap(), x);
//! }
//! // Identity factors reconstruct the core itself.
//! let eye = |n: usize| Mat::<f64>::identity(n, n);
//! let (e0, e1, e2) = (eye(2), eye(3), eye(4));
//! let y = reconstruct(&x, [e0.as_ref(), e1.as_ref(), e2.as_ref()]);
//! assert!((y.frobenius_norm() - x.frobenius_norm()).abs() < 1e-12);
//! ```

#![warn(missing_docs)]

mod error;
pub mod npy;
pub mod par;
mod product;
mod tensor;
mod unfold;

pub use error::TensorError;
pub use product::{
    mode_product_into, mode_vec_product_into, product_dims, reconstruct, try_reconstruct,
};
pub use tensor::{Tensor3, check_ranks, squared_norm};
pub use unfold::cyclic_others;
