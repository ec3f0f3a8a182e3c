//! Multilinear motion synthesis with level-of-detail controls (Mukai and Kuriyama).
//!
//! This facade crate is for: the whole build pipeline from BVH folders to a `MotionModel`, the model
//! file, and the `motion-lod` command line. It re-exports the runtime crates so that an engine can
//! depend on this one crate. It is not for: the mathematics itself, which lives in the crates below.
