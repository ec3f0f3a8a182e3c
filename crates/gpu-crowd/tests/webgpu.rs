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

/// Walker fields the browser check reads (`CrowdWalker` of `DRAW_WGSL`, 4-byte words): the root,
/// the joints shown, the clip's accuracy level and joints, the joint slot; and the words a walker.
const ROOT: usize = 4;
const SHOWN: usize = 35;
const CUR_ACC: usize = 36;
const CUR_JOINTS: usize = 37;
const SLOT: usize = 41;
const WORDS: usize = 44;
/// Frames the browser runs, walkers and joint slots (fewer than the walkers that want joints, so
/// that the slot grant decides).
const FRAMES: usize = 60;
const WALKERS: usize = 300;
const SLOTS: usize = 40;

/// Each walker's detail and positions from a page's raw walker and joint buffers, read with the
/// field indices above (as `viewer/checks/webgpu.mjs` reads the browser's).
fn from_raw(walkers: &[u8], joints: &[u8], slots: usize) -> Vec<(u32, u32, Vec<f32>)> {
    let w: &[u32] = bytemuck::cast_slice(walkers);
    let j: &[f32] = bytemuck::cast_slice(joints);
    w.chunks_exact(WORDS)
        .map(|f| {
            let mut p: Vec<f32> = f[ROOT..ROOT + 3]
                .iter()
                .map(|&b| f32::from_bits(b))
                .collect();
            if f[CUR_JOINTS] > 0 && f[SLOT] != u32::MAX {
                for k in 0..f[SHOWN] as usize {
                    for c in 0..3 {
                        p.push(j[(3 * k + c) * slots + f[SLOT] as usize]);
                    }
                }
            }
            (f[CUR_ACC], f[CUR_JOINTS], p)
        })
        .collect()
}

/// A crowd handed over for the browser to run (`GpuCrowd::host_state`): its buffers after `new`,
/// the frame uniforms of 60 frames along the ground camera's path under the distance policy, and
/// what this crowd gives after them, into `target/web-ref/gpu-run/`. `viewer/checks/webgpu.mjs`
/// runs the frames with the same shaders in headless Chromium and compares every walker's detail
/// and positions. Skipped without an adapter (fails with `MOTION_LOD_REQUIRE_GPU=1`, as in CI).
#[test]
fn a_crowd_is_handed_over_for_the_browser_to_run() {
    let Some(gpu) = common::gpu() else {
        return;
    };
    let options = gpu_crowd::GpuOptions {
        joint_slots: Some(SLOTS),
        ..Default::default()
    };
    let config = CrowdConfig::with_density(WALKERS, 0.2);
    let mut crowd = gpu_crowd::GpuCrowd::new(gpu, model(), config, options).expect("crowd");
    let state = crowd.host_state().expect("state");
    assert_eq!(state.pages.len(), 1);
    let field = crowd.config().field_size_m;
    let scene = crowd_sim::Scene::Ground;
    let (path, lens) = (
        scene.path(field),
        scene.lens(crowd_sim::Camera::default(), field),
    );
    let policy = lod_policy::DistancePolicy::for_model(model().lod());
    let dt = 1.0 / 30.0;
    let mut uniforms = Vec::new();
    let mut faults = 0;
    for f in 0..FRAMES {
        let cam = path.camera_at(f as f32 * dt, &lens);
        uniforms.extend(
            crowd
                .frame_uniforms(&policy, &cam, dt)
                .expect("uniform")
                .remove(0),
        );
        faults += crowd.step(&policy, &cam, dt).expect("frame").slot_faults;
    }
    assert!(
        faults > 0,
        "the slots must be scarce for the grant to decide"
    );
    // The field indices read the crowd as `read_walkers` does.
    let end = crowd.host_state().expect("state");
    let raw = |s: &gpu_crowd::HostState, b: u32| s.pages[0].buffers[b as usize].bytes.clone();
    let walkers = crowd.read_walkers().expect("walkers");
    let ns = SLOTS;
    let decoded = from_raw(&raw(&end, 2), &raw(&end, 9), ns);
    assert_eq!(decoded.len(), walkers.len());
    for (i, (d, w)) in decoded.iter().zip(&walkers).enumerate() {
        assert_eq!(
            (d.0 as usize, d.1 as usize),
            (w.detail.accuracy, w.detail.active_joints),
            "walker {i}"
        );
        let p: Vec<f32> = w.positions.iter().flat_map(|v| v.to_array()).collect();
        assert_eq!(d.2, p, "walker {i}");
    }
    let dir = out_dir().join("gpu-run");
    std::fs::create_dir_all(&dir).expect("folder");
    let page = &state.pages[0];
    let mut buffers = Vec::new();
    for b in &page.buffers {
        std::fs::write(dir.join(format!("binding{}.bin", b.binding)), &b.bytes).expect("writes");
        buffers.push(format!(
            "{{\"binding\": {}, \"kind\": \"{:?}\"}}",
            b.binding, b.kind
        ));
    }
    std::fs::write(dir.join("uniforms.bin"), &uniforms).expect("writes");
    std::fs::write(dir.join("expected-walkers.bin"), raw(&end, 2)).expect("writes");
    std::fs::write(dir.join("expected-joints.bin"), raw(&end, 9)).expect("writes");
    std::fs::write(dir.join("crowd.wgsl"), &state.wgsl).expect("writes");
    let passes: Vec<String> = state
        .passes
        .iter()
        .map(|(e, d)| format!("[\"{e}\", \"{d:?}\"]"))
        .collect();
    let resets: Vec<String> = state
        .counter_resets
        .iter()
        .map(|(o, v)| format!("[{o}, {v:?}]"))
        .collect();
    let meta = format!(
        "{{\"frames\": {FRAMES}, \"walkers\": {}, \"slots\": {ns}, \"workgroups\": {:?}, \
         \"uniform_bytes\": {}, \"buffers\": [{}], \"passes\": [{}], \"resets\": [{}], \
         \"fields\": {{\"root\": {ROOT}, \"shown\": {SHOWN}, \"cur_acc\": {CUR_ACC}, \
         \"cur_joints\": {CUR_JOINTS}, \"slot\": {SLOT}, \"words\": {WORDS}}}}}",
        page.walkers,
        page.workgroups,
        uniforms.len() / FRAMES,
        buffers.join(", "),
        passes.join(", "),
        resets.join(", ")
    );
    std::fs::write(dir.join("run.json"), meta).expect("writes");
}
