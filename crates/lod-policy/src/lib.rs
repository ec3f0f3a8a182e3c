//! The runtime multilinear motion model and the level-of-detail policies.
//!
//! This crate is for: evaluating poses from a compressed motion model at any accuracy level (clip
//! kernels and per-frame poses into caller-owned buffers) and for choosing a level per character from
//! its distance or projected size. It is not for: building models (see `motion-lod`) or simulating
//! crowds (see `crowd-sim`).
