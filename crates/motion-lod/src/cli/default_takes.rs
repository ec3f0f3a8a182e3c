//! The default data set, embedded in the binary (never in a library): the procedural walker's takes
//! in the workspace's `fixtures/` folder, written by `cargo xtask fixtures` and read into the binary
//! by the package's build script. Commands given no data folder use them.

/// The default takes: `(file name, BVH text)`, sorted by name.
pub const DEFAULT_TAKES: &[(&str, &str)] =
    include!(concat!(env!("OUT_DIR"), "/embedded_fixtures.rs"));
