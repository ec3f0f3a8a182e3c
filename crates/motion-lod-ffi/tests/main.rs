//! The C ABI's integration tests, one test binary: each file of this folder is a module (run one
//! with `cargo test -p motion-lod-ffi --test integration FILE::`). One binary links once instead of
//! 7 times (the workspace's first build, issue 36).

mod common;

mod c_example;
mod errors;
mod far_from_origin;
mod header;
mod layouts;
mod shown_pose;
mod styles;
mod threads;
mod web_reference;
