//! `motion-lod crowd --gpu` without a usable adapter: one clear error naming what is missing, and
//! a non-zero exit. The backends are restricted to Metal (`WGPU_BACKEND=metal`), which this build
//! does not compile in, so no adapter exists whatever the machine has.

#![cfg(feature = "gpu")]

use std::process::Command;

#[test]
fn crowd_gpu_without_an_adapter_is_one_clear_error() {
    let out = Command::new(env!("CARGO_BIN_EXE_motion-lod"))
        .args(["crowd", "--gpu", "--walkers", "10", "--seconds", "0.1"])
        .env("WGPU_BACKEND", "metal")
        .output()
        .expect("run motion-lod");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "exit status {:?}", out.status);
    assert!(stderr.contains("no GPU adapter"), "{stderr}");
    assert!(
        stderr.contains("VK_ICD_FILENAMES") && stderr.contains("libvulkan1"),
        "{stderr}"
    );
    assert_eq!(stderr.matches("error:").count(), 1, "{stderr}");
}
