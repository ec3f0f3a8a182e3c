//! The pose kernel through the C ABI, timed natively: the counterpart of `benchPose` in
//! `viewer/crowd.js`, which times the same calls in the runtime compiled to WebAssembly.
//! `viewer/checks/bench.mjs` runs both in one run and prints their ratio.
//!
//! Usage: `cargo run --release -p motion-lod-ffi --example pose_bench -- MODEL.mlod LEVEL`
//! (prints one JSON line: the median nanoseconds of `mlod_walker_pose`, alone and followed by
//! `mlod_walker_joint_transforms`; and of `mlod_walkers_step` per walker for a crowd of 2,000 on a
//! grid 2 m apart, with the camera facing away, every walker root only, and facing the crowd).

use std::time::Instant;

use motion_lod_ffi::*;

const BATCH: usize = 20000;
const SAMPLES: usize = 15;

fn ok(status: MlodStatus, what: &str) {
    if status != MlodStatus::Ok {
        // SAFETY: the library's message for this thread.
        let message = unsafe { std::ffi::CStr::from_ptr(mlod_last_error()) };
        eprintln!("{what}: {}", message.to_string_lossy());
        std::process::exit(1);
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(path), Some(level)) = (args.first(), args.get(1).and_then(|l| l.parse().ok())) else {
        eprintln!("usage: pose_bench MODEL.mlod LEVEL");
        std::process::exit(2);
    };
    let bytes = std::fs::read(path).unwrap_or_else(|e| {
        eprintln!("reading {path}: {e}");
        std::process::exit(1);
    });
    let mut model: *mut MlodModel = std::ptr::null_mut();
    // SAFETY: valid bytes and out pointers throughout; every object is live while used.
    unsafe {
        ok(
            mlod_model_from_bytes(bytes.as_ptr(), bytes.len(), &mut model),
            "load",
        );
        let (mut joints, mut animated) = (0usize, 0usize);
        ok(
            mlod_model_sizes(
                model,
                std::ptr::null_mut(),
                &mut joints,
                &mut animated,
                std::ptr::null_mut(),
            ),
            "sizes",
        );
        let (mut lo, mut hi) = (MlodControls::default(), MlodControls::default());
        ok(mlod_model_control_range(model, &mut lo, &mut hi), "range");
        let controls = MlodControls {
            dx: 0.5 * (lo.dx + hi.dx),
            dz: 0.5 * (lo.dz + hi.dz),
            turn: 0.5 * (lo.turn + hi.turn),
            height: 0.5 * (lo.height + hi.height),
            ..MlodControls::default()
        };
        let detail = MlodDetail {
            level,
            joints: animated as u32,
        };
        let mut walker: *mut MlodWalker = std::ptr::null_mut();
        ok(mlod_walker_new(model, &mut walker), "walker");
        let mut cycle = MlodCycle::default();
        ok(
            mlod_walker_prepare(walker, model, &controls, detail, &mut cycle),
            "prepare",
        );
        let mut transforms = vec![MlodJointTransform::default(); joints];
        let mut time = |fk: bool| {
            let mut per = Vec::new();
            for s in 0..SAMPLES + 2 {
                let t0 = Instant::now();
                for i in 0..BATCH {
                    let t = cycle.duration_s * i as f64 / BATCH as f64;
                    ok(
                        mlod_walker_pose(walker, model, t, std::ptr::null_mut(), 0),
                        "pose",
                    );
                    if fk {
                        ok(
                            mlod_walker_joint_transforms(
                                walker,
                                model,
                                transforms.as_mut_ptr(),
                                joints,
                            ),
                            "transforms",
                        );
                    }
                }
                if s >= 2 {
                    per.push(t0.elapsed().as_nanos() as f64 / BATCH as f64);
                }
            }
            per.sort_by(f64::total_cmp);
            per[per.len() / 2]
        };
        let pose_ns = time(false);
        let pose_fk_ns = time(true);
        let away_ns = crowd_step(model, &controls, animated, -1.0);
        let facing_ns = crowd_step(model, &controls, animated, 1.0);
        println!(
            "{{\"poseNs\": {pose_ns:.1}, \"poseFkNs\": {pose_fk_ns:.1}, \"stepAwayNs\": {away_ns:.1}, \"stepFacingNs\": {facing_ns:.1}}}"
        );
        mlod_walker_free(walker);
        mlod_model_free(model);
    }
}

/// Walkers of the crowd step measurement, on a grid of `CROWD_COLUMNS`, 2 m apart.
const CROWD: usize = 2000;
const CROWD_COLUMNS: usize = 50;

/// The median nanoseconds a walker of `mlod_walkers_step` for a crowd of `CROWD` walking with
/// `controls`, the camera at the grid's near edge looking along `direction_z` (+1: over the crowd,
/// -1: away from it, every walker root only once its first cycle has ended).
///
/// # Safety
/// `model` is live.
unsafe fn crowd_step(
    model: *mut MlodModel,
    controls: &MlodControls,
    animated: usize,
    direction_z: f32,
) -> f64 {
    let camera = MlodCamera {
        position: [0.0, 1.7, -8.0],
        direction: [0.0, 0.0, direction_z],
        fov_y: std::f32::consts::FRAC_PI_3,
        aspect: 16.0 / 9.0,
        image_height_px: 1080.0,
        near_m: 0.1,
        far_m: 0.0,
    };
    let detail = MlodDetail {
        level: 0,
        joints: animated as u32,
    };
    let mut walkers = vec![std::ptr::null_mut::<MlodWalker>(); CROWD];
    // SAFETY: live model; every walker created here.
    unsafe {
        for (i, w) in walkers.iter_mut().enumerate() {
            ok(mlod_walker_new(model, w), "walker");
            let x = ((i % CROWD_COLUMNS) as f64 - 24.5) * 2.0;
            let z = (i / CROWD_COLUMNS) as f64 * 2.0;
            ok(
                mlod_walker_start(*w, model, controls, detail, x, z, 0.0, std::ptr::null_mut()),
                "start",
            );
        }
        let next = vec![*controls; CROWD];
        let mut states = vec![MlodWalkerState::default(); CROWD];
        let mut per = Vec::new();
        // 90 steps of 1/60 s (more than a cycle) warm up: every walker then walks at the
        // detail the camera gives it.
        for s in 0..SAMPLES + 90 {
            let t0 = Instant::now();
            ok(
                mlod_walkers_step(
                    walkers.as_ptr(),
                    CROWD,
                    model,
                    &camera,
                    1.2,
                    1.0 / 60.0,
                    next.as_ptr(),
                    states.as_mut_ptr(),
                    std::ptr::null_mut(),
                ),
                "step",
            );
            if s >= 90 {
                per.push(t0.elapsed().as_nanos() as f64 / CROWD as f64);
            }
        }
        for w in walkers {
            mlod_walker_free(w);
        }
        per.sort_by(f64::total_cmp);
        per[per.len() / 2]
    }
}
