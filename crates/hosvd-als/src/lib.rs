//! Tucker decompositions for motion tensors: HOSVD, HOOI/ALS and the key-level search.
//!
//! This crate is for: the tensor mathematics of Mukai and Kuriyama sections 3.2 and 4.1-4.2 (HOSVD,
//! truncated HOSVD, HOOI/ALS at a rank triple, the greedy key-tensor search, hybrid truncation and
//! storage accounting). It is not for: interpolation over controls (see `kriging`) or runtime pose
//! evaluation (see `lod-policy`).
