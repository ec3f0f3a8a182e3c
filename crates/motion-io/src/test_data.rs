//! Test support: where the tests find data that lives outside the repository, and what they do
//! when it is absent.
//!
//! Locally a test that needs `../shared/mocap` (or the generated `fixtures/`) prints
//! `skipped: <test>: ... not found` and passes. The line goes straight to the process's standard
//! error, past the test harness's output capture, so that `cargo test` shows it (and `.ci/run`
//! counts such lines in its summary). Under `MOTION_LOD_REQUIRE_DATA=1` (set by `.ci/run`,
//! because CI always has the data) a missing folder fails the test instead, so that a broken path
//! in CI cannot turn the acceptance tests into silent passes.

use std::path::{Path, PathBuf};

/// The environment variable that turns a missing data folder into a test failure.
pub const REQUIRE_DATA_VAR: &str = "MOTION_LOD_REQUIRE_DATA";

/// True when [`REQUIRE_DATA_VAR`] is set to anything but empty or `0`.
pub fn data_required() -> bool {
    std::env::var_os(REQUIRE_DATA_VAR).is_some_and(|v| !v.is_empty() && v != "0")
}

/// `dir` when it is a folder. Otherwise prints `skipped: {what} not found ({dir})` and returns
/// `None`, or, when [`data_required`], panics with the same message (this is for tests: the
/// panic is the test failure).
pub fn require_dir(dir: &Path, what: &str) -> Option<PathBuf> {
    if dir.is_dir() {
        return Some(dir.to_path_buf());
    }
    missing(&format!("{what} not found ({})", dir.display()));
    None
}

/// Reports data a test needs but cannot find: prints `skipped: {message}`, or, when
/// [`data_required`], panics with it (the test then fails). The caller returns after it.
pub fn missing(message: &str) {
    if data_required() {
        panic!("{message}, and {REQUIRE_DATA_VAR} is set: the data must be present");
    }
    use std::io::Write as _;
    let test = std::thread::current()
        .name()
        .map_or(String::new(), |n| format!("{n}: "));
    // Not `eprintln!`: the test harness captures that and shows it only for failing tests.
    let _ = writeln!(std::io::stderr(), "skipped: {test}{message}");
}

/// [`require_dir`] for `../shared/mocap/{name}` seen from a crate's manifest folder
/// (`crates/<crate>`, three levels below the folder that holds the checkout and `shared/`).
pub fn shared_mocap(manifest_dir: &str, name: &str) -> Option<PathBuf> {
    let dir = Path::new(manifest_dir)
        .join("../../../shared/mocap")
        .join(name);
    require_dir(&dir, "../shared/mocap")
}

/// The workspace's default data set, read from its `fixtures/` folder (written by
/// `cargo xtask fixtures` and committed): `(file name, BVH text)` for every `.bvh` file, sorted by
/// name, read once per process. This is what the `motion-lod` binary embeds; tests, benches and
/// `xtask` read it from the checkout instead, since no library embeds it.
///
/// # Panics
/// When the folder cannot be read: it is part of the checkout, so that is a broken checkout.
pub fn fixture_takes() -> &'static [(&'static str, &'static str)] {
    static TAKES: std::sync::OnceLock<Vec<(&'static str, &'static str)>> =
        std::sync::OnceLock::new();
    TAKES.get_or_init(|| {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures");
        let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
            .unwrap_or_else(|e| panic!("cannot list {}: {e}", dir.display()))
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("bvh")))
            .collect();
        files.sort();
        assert!(!files.is_empty(), "no .bvh file in {}", dir.display());
        files
            .iter()
            .map(|f| {
                let text = std::fs::read_to_string(f)
                    .unwrap_or_else(|e| panic!("cannot read {}: {e}", f.display()));
                let name = f
                    .file_name()
                    .map_or(String::new(), |n| n.to_string_lossy().into_owned());
                (&*String::leak(name), &*String::leak(text))
            })
            .collect()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn present_folder_is_returned_and_missing_one_skips_or_fails() {
        let here = Path::new(env!("CARGO_MANIFEST_DIR"));
        assert_eq!(require_dir(here, "crate").as_deref(), Some(here));
        let missing = here.join("no-such-folder-xyz");
        if data_required() {
            let caught = std::panic::catch_unwind(|| require_dir(&missing, "test data"));
            assert!(
                caught.is_err(),
                "a missing folder must fail under {REQUIRE_DATA_VAR}"
            );
        } else {
            assert_eq!(require_dir(&missing, "test data"), None);
        }
    }
}
