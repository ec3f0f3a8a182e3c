//! xtask's integration tests, one test binary: each file of this folder is a module (run one with
//! `cargo test -p xtask --test integration FILE::`). One binary links once instead of 4 times (the
//! workspace's first build, issue 36).

mod imports;
mod motion_io_segmentation;
mod scaling;
mod tables_smoke;
mod walker_properties;
