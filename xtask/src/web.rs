//! `cargo xtask web`: the viewer's built assets, reproducible from the repository.
//!
//! Two kinds of files under `viewer/` are built, not written by hand, and checked in so that
//! `motion-lod view` can embed them (an installed binary needs no checkout and no npm):
//! - `viewer/wasm/motion_lod.wasm`: the runtime's C ABI (`crates/motion-lod-ffi`) compiled for
//!   `wasm32-unknown-unknown` with SIMD128, in the `wasm` profile (LTO, one codegen unit), with
//!   the registry's, Cargo's and the checkout's paths remapped so the bytes do not depend on where
//!   it was built (nor on what the registry's index folder is called);
//!   `viewer/wasm/BUILD.txt` records the compiler that made it.
//! - `viewer/vendor/three/`: the three.js modules the pages import, copied from the npm package
//!   that `viewer/package-lock.json` pins (`npm ci` in `viewer/` installs it).
//!
//! `--check` rebuilds both into a scratch folder and fails when a checked-in file differs, so CI
//! catches a runtime change without a rebuilt wasm. With another compiler than the one recorded,
//! the bytes cannot be compared (the check says so and passes on the rest).

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context as _, Result, bail};

/// The three.js files the pages import, relative to the package's folder: the core, and the
/// add-ons with the add-ons they import in turn.
pub const THREE_FILES: [&str; 7] = [
    "LICENSE",
    "build/three.module.js",
    "build/three.core.js",
    "examples/jsm/controls/OrbitControls.js",
    "examples/jsm/loaders/GLTFLoader.js",
    "examples/jsm/utils/BufferGeometryUtils.js",
    "examples/jsm/utils/SkeletonUtils.js",
];

/// Where the checked-in wasm lives, relative to the workspace root.
pub const WASM_PATH: &str = "viewer/wasm/motion_lod.wasm";
/// The record of the compiler that built it.
pub const BUILD_RECORD: &str = "viewer/wasm/BUILD.txt";

/// `rustc -V`, e.g. `rustc 1.95.0 (59807616e 2026-04-14)`.
pub fn rustc_version() -> Result<String> {
    let out = Command::new(std::env::var_os("RUSTC").unwrap_or_else(|| "rustc".into()))
        .arg("-V")
        .output()
        .context("running rustc -V")?;
    Ok(String::from_utf8_lossy(&out.stdout).trim().to_string())
}

/// Builds the runtime for `wasm32-unknown-unknown` into `target_dir` and returns the module's
/// bytes.
pub fn build_wasm(root: &Path, target_dir: &Path) -> Result<Vec<u8>> {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let home = std::env::var_os("CARGO_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cargo")))
        .unwrap_or_default();
    // Flags for the wasm crates only (with --target, build scripts and proc macros get none). The
    // paths compiled into the module (panic locations) lose every machine-specific prefix: the
    // checkout, Cargo's home, and each registry's source folder whatever its index is called (rustc
    // applies the last matching remap, so the most specific come last).
    let mut flags = vec![
        "-Ctarget-feature=+simd128".to_string(),
        format!("--remap-path-prefix={}=/motion-lod", root.display()),
        format!("--remap-path-prefix={}=/cargo", home.display()),
    ];
    let sources = home.join("registry/src");
    let mut registries: Vec<PathBuf> = std::fs::read_dir(&sources)
        .map(|entries| entries.filter_map(|e| e.ok().map(|e| e.path())).collect())
        .unwrap_or_default();
    registries.sort();
    for dir in registries {
        flags.push(format!("--remap-path-prefix={}=/registry", dir.display()));
    }
    let flags = flags.join("\u{1f}");
    let status = Command::new(cargo)
        .current_dir(root)
        .args([
            "build",
            "--locked",
            "-p",
            "motion-lod-ffi",
            "--lib",
            "--target",
            "wasm32-unknown-unknown",
            "--profile",
            "wasm",
        ])
        .env("CARGO_TARGET_DIR", target_dir)
        .env("CARGO_ENCODED_RUSTFLAGS", flags)
        .env_remove("RUSTFLAGS")
        .status()
        .context("running cargo build for wasm32-unknown-unknown")?;
    if !status.success() {
        bail!(
            "building the wasm failed ({status}); is the target installed? \
             `rustup target add wasm32-unknown-unknown`"
        );
    }
    let built = target_dir.join("wasm32-unknown-unknown/wasm/motion_lod_ffi.wasm");
    std::fs::read(&built).with_context(|| format!("reading {}", built.display()))
}

/// The record written beside the wasm.
fn build_record(rustc: &str, size: usize) -> String {
    format!(
        "{WASM_PATH}: built by `cargo xtask web` with {rustc}\n\
         target wasm32-unknown-unknown, profile wasm, +simd128, {size} bytes\n"
    )
}

/// The compiler named in a record.
fn recorded_rustc(record: &str) -> Option<&str> {
    record.lines().next()?.split_once(" with ").map(|(_, v)| v)
}

/// What `cargo xtask web` does: build (or, with `check`, compare) the wasm and copy (or compare)
/// three.js. Returns a line per file.
pub fn run(root: &Path, check: bool) -> Result<Vec<String>> {
    let mut report = Vec::new();
    let mut stale = Vec::new();
    let rustc = rustc_version()?;
    let target_dir = root.join("target/wasm-build");
    let wasm = build_wasm(root, &target_dir)?;
    let wasm_path = root.join(WASM_PATH);
    let record_path = root.join(BUILD_RECORD);
    if check {
        let record = std::fs::read_to_string(&record_path).unwrap_or_default();
        let checked_in = std::fs::read(&wasm_path).unwrap_or_default();
        match recorded_rustc(&record) {
            Some(v) if v == rustc => {
                if checked_in == wasm {
                    report.push(format!("{WASM_PATH}: current ({} bytes)", wasm.len()));
                } else {
                    stale.push(format!(
                        "{WASM_PATH} differs from a build of the current source ({} bytes checked in, {} built)",
                        checked_in.len(),
                        wasm.len()
                    ));
                }
            }
            Some(v) => report.push(format!(
                "{WASM_PATH}: built with {v}, this machine has {rustc}: bytes not compared"
            )),
            None => stale.push(format!("{BUILD_RECORD} is missing or unreadable")),
        }
    } else {
        std::fs::create_dir_all(wasm_path.parent().unwrap_or(root))?;
        std::fs::write(&wasm_path, &wasm)
            .with_context(|| format!("writing {}", wasm_path.display()))?;
        std::fs::write(&record_path, build_record(&rustc, wasm.len()))?;
        report.push(format!("{WASM_PATH}: {} bytes", wasm.len()));
    }

    let package = root.join("viewer/node_modules/three");
    if !package.join("package.json").is_file() {
        bail!("three.js is not installed in viewer/node_modules: run `npm ci` in viewer/ first");
    }
    for file in THREE_FILES {
        let from = package.join(file);
        let to = root.join("viewer/vendor/three").join(file);
        let bytes = std::fs::read(&from).with_context(|| format!("reading {}", from.display()))?;
        if check {
            if std::fs::read(&to).ok().as_deref() != Some(&bytes[..]) {
                stale.push(format!("{} differs from the npm package", to.display()));
            }
        } else {
            std::fs::create_dir_all(to.parent().unwrap_or(root))?;
            std::fs::write(&to, &bytes).with_context(|| format!("writing {}", to.display()))?;
        }
    }
    report.push(format!(
        "viewer/vendor/three: {} files {}",
        THREE_FILES.len(),
        if check { "compared" } else { "copied" }
    ));
    if !stale.is_empty() {
        bail!(
            "the viewer's built assets are out of date (run `cargo xtask web`):\n  {}",
            stale.join("\n  ")
        );
    }
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_record_names_its_compiler() {
        let record = build_record("rustc 1.95.0 (59807616e 2026-04-14)", 10);
        assert_eq!(
            recorded_rustc(&record),
            Some("rustc 1.95.0 (59807616e 2026-04-14)")
        );
        assert_eq!(recorded_rustc(""), None);
    }
}
