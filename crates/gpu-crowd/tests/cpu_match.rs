//! The GPU crowd against the CPU crowd (issue 32): for 1,000 walkers over 300 frames in both
//! scenes, the same walkers in view, the same detail for every walker and every joint within
//! [`TOLERANCE_M`] of the CPU runtime's, on whatever adapter there is (Mesa's lavapipe in CI).
//!
//! The CPU crowd is `crowd_sim::Crowd` over `motion_lod::LodSource` with the same config, with
//! seam inertialization and the foot lock turned off explicitly (`seam_levels = 0`,
//! `foot_lock_levels = 0`): the shaders do neither yet. Without any adapter the test prints
//! `skipped: no GPU adapter (...)`, or fails when `MOTION_LOD_REQUIRE_GPU=1` (CI).

use crowd_sim::{Camera, Crowd, CrowdConfig, CrowdStyle, Culling, Scene};
use gpu_crowd::{Gpu, GpuCrowd, GpuOptions};
use lod_policy::DistancePolicy;
use motion_lod::dataset::DataSpec;
use motion_lod::progress::NoProgress;
use motion_lod::{BuildConfig, LodSource, MotionModel};

/// Largest distance (m) allowed between a GPU joint and the CPU's: 1e-4 m, as issue 32 asks.
/// Measured on lavapipe: 3.8e-6 m at worst over the 600 frames (2026-11-28), not growing with time:
/// the walkers' cycle frames, path parameters and path controller are computed in double-float
/// arithmetic (`df.wgsl`) as the CPU's in f64 and rounded once, so both crowds steer by the same
/// controls, clip durations and clocks; what remains is the f32 sums of the clip and the pose in
/// another order. (Before, the controller in f32 drifted the two apart by 2.5e-4 m in ten seconds,
/// the shader compiler having also folded every double-float error term to zero.)
const TOLERANCE_M: f32 = 1e-4;

fn fixture_model() -> MotionModel {
    let loaded = DataSpec::default()
        .load_with_default(motion_io::test_data::fixture_takes(), &|_, _| {})
        .expect("fixture takes");
    MotionModel::build(&loaded.training, &BuildConfig::default(), &NoProgress).expect("model")
}

/// The config of both crowds: every field given here, none left to `CrowdConfig::default()`.
fn config() -> CrowdConfig {
    let walkers = 1000;
    // A field of 70 m: walkers from 0 to 100 m from the camera, at the first two levels, with
    // joints dropped by distance, and root only.
    let density = 0.2;
    CrowdConfig {
        walkers,
        field_size_m: (walkers as f32 / density).sqrt(),
        seed: 7,
        fps: 30.0,
        // Not done by the shaders yet: off in the CPU reference too.
        seam_levels: 0,
        seam_halflife_s: lod_policy::DEFAULT_HALFLIFE_S,
        foot_lock_levels: 0,
        border_m: 2.0,
        cull_margin_m: 0.25,
        culling: Culling::Scan,
        tree_rebuild_interval: 240,
        spread_first_builds: true,
        style: CrowdStyle::DataMix,
    }
}

/// At a walker's cycle seam the two crowds could show the two sides of it for one frame, when
/// their clocks differ in the last bit there (the seam's own jump, up to a few centimetres, since
/// seams are not inertialized in this test). On a software adapter (lavapipe, CI) the clocks are
/// the same and no such frame is allowed. A hardware GPU may fuse multiplies and adds in the clip's
/// f32 sums, which moves a clip's duration by an ulp: there such a frame is allowed, at most
/// [`SEAM_SIDE_M`] apart, at a frame where the CPU walker starts or ends a cycle, and at most once
/// in [`SEAM_FRAMES_PER`] walker-frames with joints.
const SEAM_SIDE_M: f32 = 0.05;

/// See [`SEAM_SIDE_M`].
const SEAM_FRAMES_PER: usize = 10_000;

/// Runs both crowds for `frames` frames in `scene`; checks every frame that both have the same
/// walkers in view, the same detail for every walker and the same level histogram, and every joint
/// within [`TOLERANCE_M`] (or [`SEAM_SIDE_M`] at a seam, on a hardware adapter). Returns the
/// largest joint distance, the largest root distance and the walker-frames with joints (the seam
/// frames left out of both).
fn compare(gpu: &Gpu, model: &MotionModel, scene: Scene, frames: usize) -> (f32, f32, usize) {
    let config = config();
    let source = LodSource::new(model);
    let policy = DistancePolicy::for_model(model.lod());
    let mut cpu = Crowd::new(&source, config).expect("CPU crowd");
    let mut gpu_crowd =
        GpuCrowd::new(gpu, model.runtime(), config, GpuOptions::default()).expect("GPU crowd");
    assert_eq!(cpu.config().field_size_m, gpu_crowd.config().field_size_m);
    let field = cpu.config().field_size_m;
    let path = scene.path(field);
    let lens = scene.lens(Camera::default(), field);
    let dt = 1.0 / config.fps;
    let seam_sides_allowed = !gpu.is_software();
    let (mut worst, mut worst_root, mut with_joints) = (0.0f32, 0.0f32, 0usize);
    // The CPU walkers' cycle frames at the frame before, and the walker-frames beyond the
    // tolerance, judged once the next frame shows whether they were at a seam: (frame, walker,
    // distance, whether a cycle began at that frame).
    let mut before: Vec<lod_policy::CycleFrame> =
        (0..cpu.len()).map(|i| cpu.cycle_frame(i)).collect();
    let mut pending: Vec<(usize, usize, f32, bool)> = Vec::new();
    let mut seam_sides = 0usize;
    for f in 0..frames {
        let camera = path.camera_at(f as f32 * dt, &lens);
        let cpu_stats = cpu.step(&source, &policy, &camera, dt).expect("CPU step");
        // A walker over the tolerance last frame must have been at a seam: a cycle began then, or
        // begins now.
        for (pf, i, d, began) in pending.drain(..) {
            let at_seam = began || cpu.cycle_frame(i) != before[i];
            assert!(
                seam_sides_allowed && at_seam && d <= SEAM_SIDE_M,
                "{scene:?} frame {pf} walker {i}: {d} m apart, more than {TOLERANCE_M} m (at a \
                 seam: {at_seam}; allowed there on a hardware adapter: {SEAM_SIDE_M} m)"
            );
            seam_sides += 1;
        }
        let gpu_stats = gpu_crowd.step(&policy, &camera, dt).expect("GPU step");
        assert_eq!(
            gpu_stats.visible as usize, cpu_stats.visible,
            "{scene:?} frame {f}: walkers in view"
        );
        let walkers = gpu_crowd.read_walkers().expect("read back");
        for (i, w) in walkers.iter().enumerate() {
            assert_eq!(
                w.detail,
                cpu.detail(i),
                "{scene:?} frame {f} walker {i}: detail"
            );
            let want = cpu.joint_positions(i);
            assert_eq!(
                w.positions.len(),
                want.len(),
                "{scene:?} frame {f} walker {i}: joints"
            );
            let far = w
                .positions
                .iter()
                .zip(want)
                .map(|(g, c)| g.distance(*c))
                .fold(0.0f32, f32::max);
            if far > TOLERANCE_M {
                pending.push((f, i, far, before[i] != cpu.cycle_frame(i)));
                continue;
            }
            for (k, (g, c)) in w.positions.iter().zip(want).enumerate() {
                let d = g.distance(*c);
                worst = worst.max(d);
                if k == 0 {
                    worst_root = worst_root.max(d);
                }
            }
            with_joints += usize::from(w.detail.active_joints > 0);
        }
        for (i, b) in before.iter_mut().enumerate() {
            *b = cpu.cycle_frame(i);
        }
        assert_eq!(
            gpu_stats.level_histogram, cpu_stats.level_histogram,
            "{scene:?} frame {f}: levels"
        );
    }
    assert!(
        pending.iter().all(|p| seam_sides_allowed && p.3),
        "{scene:?}: walkers over the tolerance at the last frame: {pending:?}"
    );
    seam_sides += pending.len();
    assert!(
        seam_sides * SEAM_FRAMES_PER <= with_joints.max(1),
        "{scene:?}: {seam_sides} walker-frames showed two sides of a seam in {with_joints}"
    );
    if seam_sides > 0 {
        eprintln!("{scene:?}: {seam_sides} walker-frame(s) at a seam showed its two sides");
    }
    (worst, worst_root, with_joints)
}

#[test]
fn gpu_crowd_matches_the_cpu_crowd_in_both_scenes() {
    let Some(gpu) = Gpu::open_or_skip() else {
        return;
    };
    let model = fixture_model();
    for scene in Scene::ALL {
        let (worst, worst_root, with_joints) = compare(&gpu, &model, scene, 300);
        println!(
            "{scene:?}: 1000 walkers x 300 frames on {}: largest joint distance {worst:.3e} m \
             (roots {worst_root:.3e} m), {with_joints} walker-frames with joints",
            gpu.adapter_name()
        );
        assert!(
            with_joints > 1000,
            "{scene:?}: too few walkers with joints to compare"
        );
    }
}
