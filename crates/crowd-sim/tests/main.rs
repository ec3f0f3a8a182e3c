//! crowd-sim's integration tests, one test binary: each file of this folder is a module (run one
//! with `cargo test -p crowd-sim --test integration FILE::`). One binary links once instead of 2
//! times (the workspace's first build, issue 36).

mod altered;
mod crowd;
mod render;
mod robustness;
