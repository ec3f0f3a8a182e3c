//! Dense three-mode tensors for multilinear analysis.
//!
//! This crate is for: a real (f64) `P x T x S` tensor stored contiguously, its mode-n unfoldings and
//! foldings as de Lathauwer et al. define them, n-mode products with matrices and vectors, leading
//! sub-tensor truncation, Frobenius norms, Tucker reconstruction and NPY exchange with numpy.
//! It is not for: decompositions (see `hosvd-als`), general N-mode tensors, or sparse data.
