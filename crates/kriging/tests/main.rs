//! The kriging crate's integration tests, one test binary: each file of this folder is a module
//! (run one with `cargo test -p kriging --test integration FILE::`, for example `meuse::`). One
//! binary links once instead of 15 times (the workspace's first build, issue 36).

mod common;

mod against_naive;
mod batched;
mod degenerate;
mod geostat;
mod measurement_error;
mod meuse;
mod meuse_variogram;
mod properties;
mod rbf_smoothing;
mod robustness;
mod search;
mod select;
mod select_folds;
mod simple;
mod simulation;
mod sphere;
mod variogram_fit;
