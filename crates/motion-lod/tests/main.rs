//! motion-lod's integration tests, one test binary: each file of this folder is a module (run one
//! with `cargo test -p motion-lod --test integration FILE::`, for example `quality::`).
//!
//! One binary instead of one per file (issue 36, the first build): the tests link once instead of
//! 22 times, the models the files share ([`common::built`]) are built once per run, and the test
//! threads stay busy across files instead of waiting for each file's slowest test.

mod common;
mod fk_probe;

mod acceptance;
mod api_defects;
mod cli;
mod crowd_cli;
mod crowd_paths;
mod crowd_start;
mod dataset;
mod explain_terms;
#[path = "gltf.rs"]
mod gltf_export;
mod gpu_cli;
mod hostile_model;
mod joints_and_controls;
mod model;
mod naive_threads;
mod pca;
mod posture;
mod quality;
mod quality_meter;
mod readme_examples;
mod runtime_model;
mod section_layout;
mod skeleton_variants;
mod storage;
mod style;
