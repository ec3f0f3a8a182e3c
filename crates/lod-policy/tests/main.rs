//! The runtime (lod-policy)'s integration tests, one test binary: each file of this folder is a
//! module (run one with `cargo test -p lod-policy --test integration FILE::`). One binary links
//! once instead of 3 times (the workspace's first build, issue 36).

mod common;

mod kernel;
mod model;
mod policy;
mod robustness;
