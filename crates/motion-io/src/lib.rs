//! Motion capture input and output: BVH files, skeletons, forward kinematics, gait cycles.
//!
//! This crate is for: reading and writing Biovision BVH, forward kinematics with glam, pose vectors
//! built from exponential maps, canonicalisation, foot contacts and the segmentation of takes into
//! two-step gait cycles with their control parameters. It is not for: time alignment (see `timewarp`)
//! or statistics over many cycles.
