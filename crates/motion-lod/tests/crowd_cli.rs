//! `motion-lod crowd --export` (issue 34): the clip records the camera (`--camera`) and the
//! level of detail (`--policy`, `--no-lod`) asked for. (`--camera overview` once wrote the ground
//! camera's bytes.)

use std::path::Path;
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_motion-lod");

/// Runs `crowd` on the embedded data with `extra` arguments, exporting to `out`; returns the
/// file's glTF JSON chunk.
fn export(out: &Path, extra: &[&str]) -> (Vec<u8>, serde_json::Value) {
    let mut args = vec![
        "crowd",
        "--walkers",
        "300",
        "--density",
        "0.01",
        "--seconds",
        "0.1",
        "--export-seconds",
        "0.5",
        "--json",
        "--export",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let run = Command::new(BIN)
        .args(&args)
        .output()
        .expect("the binary runs");
    assert!(
        run.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    let bytes = std::fs::read(out).expect("the export is written");
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let doc = serde_json::from_slice(&bytes[20..20 + json_len]).expect("glTF JSON");
    (bytes, doc)
}

/// Every exported walker's level bin at every frame.
fn levels(doc: &serde_json::Value) -> Vec<Vec<u64>> {
    doc["nodes"]
        .as_array()
        .expect("nodes")
        .iter()
        .filter_map(|n| serde_json::from_value(n["extras"]["motion_lod"]["levels"].clone()).ok())
        .collect()
}

#[test]
fn crowd_export_records_the_camera_and_the_detail_asked_for() {
    let dir = std::env::temp_dir().join(format!("mlod-crowd-export-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (ground, ground_doc) = export(&dir.join("ground.glb"), &["--camera", "ground"]);
    let (overview, overview_doc) = export(&dir.join("overview.glb"), &["--camera", "overview"]);
    assert!(ground != overview, "the two cameras write the same bytes");
    let height = |doc: &serde_json::Value| {
        doc["scenes"][0]["extras"]["motion_lod"]["camera"]["position"][1]
            .as_f64()
            .expect("the camera recorded")
    };
    let (g, o) = (height(&ground_doc), height(&overview_doc));
    assert!(
        g < 3.0 && o > 10.0 * g,
        "camera heights: ground {g} m, overview {o} m"
    );
    // Without levels of detail every exported walker is at full detail (bin 0) at every frame,
    // another clip than the distance policy's (which drops joints with distance).
    let (full_bytes, full_doc) = export(
        &dir.join("no-lod.glb"),
        &["--camera", "overview", "--no-lod"],
    );
    let full = levels(&full_doc);
    assert_eq!(full.len(), 24);
    assert!(full.iter().flatten().all(|&b| b == 0), "{full:?}");
    assert!(full_bytes != overview, "--no-lod writes the policy's clip");
    std::fs::remove_dir_all(&dir).ok();
}
