//! motion-io's integration tests, one test binary: each file of this folder is a module (run one
//! with `cargo test -p motion-io --test integration FILE::`). One binary links once instead of 6
//! times (the workspace's first build, issue 36).

mod api_defects;
mod bvh_io;
mod conventions;
mod hostile;
mod pose_vectors;
mod rest_at_origin;
mod shared_mocap;
