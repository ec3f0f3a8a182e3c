//! tensor-ops's integration tests, one test binary: each file of this folder is a module (run one
//! with `cargo test -p tensor-ops --test integration FILE::`). One binary links once instead of 3
//! times (the workspace's first build, issue 36).

mod hostile_npy;
mod npy;
mod tensor;
