//! hosvd-als's integration tests, one test binary: each file of this folder is a module (run one
//! with `cargo test -p hosvd-als --test integration FILE::`). One binary links once instead of 2
//! times (the workspace's first build, issue 36).

mod decomposition;
mod key_levels;
