//! Shared helpers for the criterion benchmarks in this folder. The benchmarks themselves are the
//! `*.rs` files declared as `[[bench]]` targets in `Cargo.toml`; run them with
//! `cargo bench -p motion-lod-benches`.
