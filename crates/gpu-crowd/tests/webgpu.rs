//! The shaders as they compile, written for the WebGPU check of `.ci/web-checks`
//! (`viewer/checks/webgpu.mjs` compiles them in headless Chromium, whose WGSL compiler, Tint, is
//! stricter than wgpu's naga in places): `gpu-crowd.wgsl` (a crowd of the fixture model with the
//! CPU crowd's defaults, seams and the foot lock at every level) and `gpu-preview.wgsl`, in
//! `target/web-ref/` (or `$MOTION_LOD_WEB_REF`). No adapter needed.

use std::path::PathBuf;

use crowd_sim::CrowdConfig;
use gpu_crowd::Preview;

mod common;
use common::model;

/// The compute passes the crowd runs (`GpuCrowd`'s pipelines), which the check makes from the
/// source one by one.
const CROWD_ENTRIES: [&str; 8] = [
    "advance",
    "build_args",
    "grant",
    "seam_capture",
    "build",
    "seam_start",
    "fix_free",
    "pose_fk",
];

fn out_dir() -> PathBuf {
    let dir = std::env::var_os("MOTION_LOD_WEB_REF").map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../target/web-ref"),
        PathBuf::from,
    );
    std::fs::create_dir_all(&dir).expect("output folder");
    dir
}

#[test]
fn the_shaders_are_written_for_the_webgpu_check() {
    let crowd = gpu_crowd::crowd_wgsl(model(), &CrowdConfig::with_density(1000, 0.2))
        .expect("the crowd's shaders");
    for entry in CROWD_ENTRIES {
        assert!(crowd.contains(&format!("fn {entry}(")), "{entry}");
    }
    // Tint refuses a literal beyond the largest f32, which the shortest decimal of f32::MAX is.
    assert!(!crowd.contains("3.4028235e38"));
    let preview = Preview::wgsl();
    for entry in ["walker_vs", "grid_vs", "fs"] {
        assert!(preview.contains(&format!("fn {entry}(")), "{entry}");
    }
    let dir = out_dir();
    std::fs::write(dir.join("gpu-crowd.wgsl"), &crowd).expect("writes");
    std::fs::write(dir.join("gpu-preview.wgsl"), &preview).expect("writes");
    std::fs::write(
        dir.join("gpu-entries.json"),
        format!(
            "{{\"compute\": {:?}, \"vertex\": [\"walker_vs\", \"grid_vs\"], \"fragment\": [\"fs\"]}}",
            CROWD_ENTRIES
        ),
    )
    .expect("writes");
}
