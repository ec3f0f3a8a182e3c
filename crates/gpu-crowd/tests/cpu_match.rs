//! The GPU crowd against the CPU crowd (issue 32): for 1,000 walkers over 300 frames in both
//! scenes, with seam inertialization off and on, the same walkers in view, the same detail for
//! every walker and every joint within [`TOLERANCE_M`] of the CPU runtime's, on whatever adapter
//! there is (Mesa's lavapipe in CI).
//!
//! The CPU crowd is `crowd_sim::Crowd` over `motion_lod::LodSource` with the same config: seams off
//! (`seam_levels = 0`) in one run, on at every level (`usize::MAX`, the CPU crowd's default) in the
//! other, where the walker-frames inside a running seam transition are counted (they must be many,
//! or the run would not test the seams); the foot lock off in both (`foot_lock_levels = 0`: the
//! shaders do not do it yet). Without any adapter the test prints `skipped: no GPU adapter (...)`,
//! or fails when `MOTION_LOD_REQUIRE_GPU=1` (CI).

use crowd_sim::{Camera, Crowd, CrowdConfig, CrowdStyle, Culling, Scene};
use gpu_crowd::{Gpu, GpuCrowd, GpuOptions};
use lod_policy::DistancePolicy;
use motion_lod::dataset::DataSpec;
use motion_lod::progress::NoProgress;
use motion_lod::{BuildConfig, LodSource, MotionModel};

/// Largest distance (m) allowed between a GPU joint and the CPU's: 1e-4 m, as issue 32 asks.
/// Measured on lavapipe: 3.8e-6 m at worst over the 600 frames with seams off (2026-11-28), 6.2e-6 m
/// with seams on (2026-11-29: the seam's finite differences and quaternions in f32 on both sides),
/// not growing with time:
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

/// The config of both crowds, seams on or off: every field given here, none left to
/// `CrowdConfig::default()`.
fn config(seams: bool) -> CrowdConfig {
    let walkers = 1000;
    // A field of 70 m: walkers from 0 to 100 m from the camera, at the first two levels, with
    // joints dropped by distance, and root only.
    let density = 0.2;
    CrowdConfig {
        walkers,
        field_size_m: (walkers as f32 / density).sqrt(),
        seed: 7,
        fps: 30.0,
        seam_levels: if seams { usize::MAX } else { 0 },
        seam_halflife_s: lod_policy::DEFAULT_HALFLIFE_S,
        // Not done by the shaders yet: off in the CPU reference too.
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
/// their clocks differ in the last bit there (the seam's own jump, up to a few centimetres without
/// inertialization, or one frame's motion with it). On a software adapter (lavapipe, CI) the clocks are
/// the same and no such frame is allowed. A hardware GPU may fuse multiplies and adds in the clip's
/// f32 sums, which moves a clip's duration by an ulp: there such a frame is allowed, at most
/// [`SEAM_SIDE_M`] apart, at a frame where the CPU walker starts or ends a cycle, and at most once
/// in [`SEAM_FRAMES_PER`] walker-frames with joints.
const SEAM_SIDE_M: f32 = 0.05;

/// See [`SEAM_SIDE_M`].
const SEAM_FRAMES_PER: usize = 10_000;

/// What one comparison measured.
#[derive(Debug, Clone, Copy)]
struct Compared {
    /// The largest joint distance (m).
    worst: f32,
    /// The largest root distance (m).
    worst_root: f32,
    /// Walker-frames with joints (the seam frames left out of these three).
    with_joints: usize,
    /// Walker-frames inside a running seam transition (the CPU crowd's `in_transition`).
    in_transition: usize,
    /// Walker-frames that drew joints a seam fades out (more than their clip's).
    fading: usize,
    /// The GPU crowd's bytes of one joint slot and of all its buffers.
    slot_bytes: u64,
    gpu_bytes: u64,
}

/// Runs both crowds for `frames` frames in `scene`, with seams on or off; checks every frame that
/// both have the same walkers in view, the same detail for every walker and the same level
/// histogram, and every joint (the joints a seam fades out included) within [`TOLERANCE_M`] (or
/// [`SEAM_SIDE_M`] at a seam, on a hardware adapter).
fn compare(gpu: &Gpu, model: &MotionModel, scene: Scene, frames: usize, seams: bool) -> Compared {
    let config = config(seams);
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
    let (mut in_transition, mut fading) = (0usize, 0usize);
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
            in_transition += usize::from(cpu.in_transition(i));
            fading += usize::from(want.len() > 1 + w.detail.active_joints);
        }
        for (i, b) in before.iter_mut().enumerate() {
            *b = cpu.cycle_frame(i);
        }
        assert_eq!(
            gpu_stats.level_histogram, cpu_stats.level_histogram,
            "{scene:?} frame {f}: levels"
        );
        // A transition ends once its spring's weight is below 1e-4, which a hardware GPU's `exp`
        // may see a frame apart from the CPU's for a rare walker.
        let (g, c) = (gpu_stats.in_transition as usize, cpu_stats.in_transition);
        assert!(
            g == c || (seam_sides_allowed && g.abs_diff(c) <= 1 + c / 100),
            "{scene:?} frame {f}: {g} walkers in a seam transition on the GPU, {c} on the CPU"
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
    Compared {
        worst,
        worst_root,
        with_joints,
        in_transition,
        fading,
        slot_bytes: gpu_crowd.bytes_per_joint_slot(),
        gpu_bytes: gpu_crowd.gpu_bytes(),
    }
}

/// Both scenes with seams on or off: each joint within [`TOLERANCE_M`] (see [`compare`]), enough
/// walkers with joints, and with seams on, many walker-frames inside running transitions and
/// joints fading out (else the run would not test the seams).
fn both_scenes(seams: bool) {
    let Some(gpu) = Gpu::open_or_skip() else {
        return;
    };
    let model = fixture_model();
    let mut fading = 0;
    for scene in Scene::ALL {
        let c = compare(&gpu, &model, scene, 300, seams);
        println!(
            "{scene:?}, seams {}: 1000 walkers x 300 frames on {}: largest joint distance {:.3e} m \
             (roots {:.3e} m), {} walker-frames with joints, {} in a seam transition, {} fading \
             joints out; {} bytes a joint slot, {} in all",
            if seams { "on" } else { "off" },
            gpu.adapter_name(),
            c.worst,
            c.worst_root,
            c.with_joints,
            c.in_transition,
            c.fading,
            c.slot_bytes,
            c.gpu_bytes
        );
        fading += c.fading;
        assert!(
            c.with_joints > 1000,
            "{scene:?}: too few walkers with joints to compare"
        );
        if seams {
            assert!(
                c.in_transition > 1000,
                "{scene:?}: {} walker-frames in a seam transition, too few to test seams",
                c.in_transition
            );
        } else {
            assert_eq!(c.in_transition, 0, "{scene:?}: seams off");
        }
    }
    // Joints dropped at a seam fade out (the overview's far walkers drop joints at cycle ends).
    assert_eq!(
        fading > 100,
        seams,
        "walker-frames fading joints out: {fading}"
    );
}

#[test]
fn gpu_crowd_matches_the_cpu_crowd_in_both_scenes() {
    both_scenes(false);
}

/// Seam inertialization at every level (`seam_levels = usize::MAX`, the CPU crowd's default).
#[test]
fn gpu_crowd_matches_the_cpu_crowd_with_seams() {
    both_scenes(true);
}
