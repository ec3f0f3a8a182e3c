//! `examples/crowd.c`, compiled by the system's C compiler against the checked-in header and this
//! crate's static library, walks 1,000 characters for 120 frames through the C ABI alone: details
//! from the camera, cycles chained by the library with controls that change every cycle, the foot
//! lock, local rotations and joint transforms. Every value it prints (all values of a subset of
//! walkers and frames, and a checksum of every value of every frame of every walker) equals the
//! same walk computed here through the Rust runtime API (`lod_policy`, as `examples/engine` walks),
//! bit for bit.

use std::path::{Path, PathBuf};
use std::process::Command;

use lod_policy::glam::{DVec3, Quat, Vec3};
use lod_policy::{
    ClipKernel, Controls, CycleFrame, DEFAULT_HALFLIFE_S, Detail, DistancePolicy, FootLock,
    JointTransform, KernelError, KernelScratch, LevelPolicy, RuntimeModel, SeamScratch,
    SeamTransition, ViewParams, wrap_angle_f64,
};
use motion_lod::dataset::DataSpec;
use motion_lod::progress::NoProgress;
use motion_lod::{BuildConfig, MotionModel};

// The constants of `examples/crowd.c`.
const WALKERS: usize = 1000;
const COLUMNS: usize = 40;
const FRAMES: usize = 120;
const DUMP_EVERY_WALKER: usize = 97;
const DUMP_EVERY_FRAME: usize = 29;
const FPS: f64 = 30.0;
const SPACING_M: f32 = 4.0;
const RADIUS_M: f32 = 1.2;

/// The camera of `examples/crowd.c`.
struct Camera {
    position: DVec3,
    direction: Vec3,
    fov_y: f32,
    aspect: f32,
    image_height_px: f32,
    near_m: f32,
    far_m: f32,
}

const CAMERA: Camera = Camera {
    position: DVec3::new(0.0, 1.7, -8.0),
    direction: Vec3::Z,
    fov_y: std::f32::consts::FRAC_PI_3, // 1.0471976f in crowd.c, the same float
    aspect: 16.0 / 9.0,
    image_height_px: 1080.0,
    near_m: 0.1,
    far_m: 90.0,
};

/// The folder holding this test binary's build artifacts (`target/<profile>`).
fn profile_dir() -> PathBuf {
    let exe = std::env::current_exe().expect("test binary path");
    // target/<profile>/deps/c_example-<hash>
    exe.parent()
        .and_then(Path::parent)
        .expect("target/<profile>")
        .to_path_buf()
}

/// The static library cargo built for this test: `target/<profile>/libmotion_lod_ffi.a`, or the
/// newest `deps/libmotion_lod_ffi-*.a`.
fn static_library() -> PathBuf {
    let dir = profile_dir();
    let uplifted = dir.join("libmotion_lod_ffi.a");
    let mut candidates: Vec<PathBuf> = std::fs::read_dir(dir.join("deps"))
        .expect("deps folder")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("libmotion_lod_ffi") && n.ends_with(".a"))
        })
        .collect();
    candidates.push(uplifted);
    candidates
        .into_iter()
        .filter(|p| p.exists())
        .max_by_key(|p| p.metadata().and_then(|m| m.modified()).ok())
        .expect("cargo builds the staticlib with the tests")
}

/// Builds the default-data model and writes it to `path`.
fn write_model(path: &Path) {
    let data = DataSpec::default()
        .load_with_default(motion_io::test_data::fixture_takes(), &|_, _| {})
        .expect("default data loads");
    let model = MotionModel::build(&data.training, &BuildConfig::default(), &NoProgress)
        .expect("model builds");
    model.save(path).expect("model saves");
}

/// `controls_for` of `examples/crowd.c`: walker `i`'s controls for its cycle `k`.
fn controls_for(lo: &[f32], hi: &[f32], i: usize, k: u64) -> Controls {
    let u = ((i as i64 * 7 + k as i64 * 3) % 11) as f32 / 10.0;
    let v = ((i as i64 * 5 + k as i64 * 2) % 7) as f32 / 6.0;
    Controls::from_array([
        lo[0] + (hi[0] - lo[0]) * (0.25 + 0.5 * v),
        lo[1] + (hi[1] - lo[1]) * u,
        lo[2] + (hi[2] - lo[2]) * (1.0 - u),
        lo[3] + (hi[3] - lo[3]) * v,
    ])
}

/// Whether a sphere of `radius` around `p` is in the camera's view: the cone through the image's
/// corners, between the near and far distances along the view direction (as `MlodCamera`
/// documents it).
fn in_view(c: &Camera, p: DVec3, radius: f32) -> (f32, bool) {
    let offset = (p - c.position).as_vec3();
    let distance = offset.length();
    let along = offset.dot(c.direction);
    let before_near = c.near_m > 0.0 && along + radius < c.near_m;
    let beyond_far = c.far_m > 0.0 && along - radius > c.far_m;
    let visible = if before_near || beyond_far {
        false
    } else if distance <= radius {
        true
    } else {
        let half = ((0.5 * c.fov_y).tan() * (1.0 + c.aspect * c.aspect).sqrt()).atan();
        let reach = half + (radius / distance).asin();
        reach >= std::f32::consts::PI || (along / distance).clamp(-1.0, 1.0).acos() <= reach
    };
    (distance, visible)
}

/// The detail the distance policy gives a sphere of `RADIUS_M` around `p` seen by the camera,
/// root only at the smallest level when it has no joints, and whether it is in view.
fn camera_detail(model: &RuntimeModel, policy: &DistancePolicy, p: DVec3) -> (Detail, bool) {
    let (distance, visible) = in_view(&CAMERA, p, RADIUS_M);
    let view = ViewParams {
        fov_y_radians: CAMERA.fov_y,
        image_height_px: CAMERA.image_height_px,
    };
    let lod = model.lod();
    let detail = lod
        .check_detail(lod.evaluated(policy.detail(distance, visible, &view)))
        .expect("policy level");
    (detail, visible)
}

/// FNV-1a over 32-bit words, as `examples/crowd.c` mixes them.
fn mix(h: u64, word: u32) -> u64 {
    (h ^ u64::from(word)).wrapping_mul(0x100000001b3)
}

fn hex(words: &[u32]) -> String {
    words.iter().map(|w| format!(" {w:08x}")).collect()
}

fn float_words(values: impl IntoIterator<Item = f32>) -> Vec<u32> {
    values.into_iter().map(f32::to_bits).collect()
}

/// Doubles as `examples/crowd.c` splits them: low word, then high.
fn double_words(values: impl IntoIterator<Item = f64>) -> Vec<u32> {
    values
        .into_iter()
        .flat_map(|v| {
            let b = v.to_bits();
            [b as u32, (b >> 32) as u32]
        })
        .collect()
}

/// What `crowd.c --dump` prints, computed through the Rust runtime API, and how many walker-frames
/// had their feet locked.
fn rust_dump(model: &RuntimeModel) -> (String, usize) {
    let (lod, rig) = (model.lod(), model.rig());
    let feet = model.feet().expect("the embedded model knows its feet");
    let policy = DistancePolicy::for_model(lod);
    let joints = rig.joint_count();
    let c = lod.controls();
    let (lo, hi) = (&c.min, &c.max);
    let dt = 1.0 / FPS;
    let mut kernel = ClipKernel::new(lod);
    let mut scratch = KernelScratch::new(lod);
    let mut pose = vec![0.0f32; lod.p()];
    let mut locals = vec![Quat::IDENTITY; joints];
    let mut transforms = vec![JointTransform::default(); joints];
    // (frame, walker, line): the C program prints frame by frame.
    let mut lines: Vec<(usize, usize, String)> = Vec::new();
    let mut sums = Vec::with_capacity(WALKERS);
    let mut locked_frames = 0;
    for i in 0..WALKERS {
        // Walker i starts on the grid, its detail from the camera at its start position.
        let x = ((i % COLUMNS) as f32 - 19.5) * SPACING_M;
        let z = ((i / COLUMNS) as f32 - 5.0) * SPACING_M;
        // 0.39269908f in crowd.c, the same float.
        let heading = (i % 16) as f32 * std::f32::consts::FRAC_PI_8 - 3.0;
        let (mut detail, mut visible) =
            camera_detail(model, &policy, DVec3::new(f64::from(x), 1.0, f64::from(z)));
        let mut controls = controls_for(lo, hi, i, 0);
        lod.build_kernel(&controls, detail, &mut scratch, &mut kernel)
            .expect("kernel");
        let mut body_scale = model.body_scale(&controls);
        let mut cycle_detail = detail;
        let mut frame = CycleFrame {
            x: f64::from(x),
            z: f64::from(z),
            heading: wrap_angle_f64(f64::from(heading)),
        };
        let mut lock = FootLock::new();
        // The inertialized seams between cycles that both animate joints.
        let mut seam = SeamTransition::new(lod.p(), DEFAULT_HALFLIFE_S);
        let mut seam_scratch = SeamScratch::new(lod.p());
        let mut seam_start = 0.0f32;
        let mut t = 0.0f64;
        let mut cycle = 0u64;
        let mut root = DVec3::ZERO;
        let mut h: u64 = 0xcbf29ce484222325;
        for f in 0..FRAMES {
            let mut begun = 0u32;
            if f > 0 {
                // The next cycle's detail from where the walker is, and its controls; used when
                // the current cycle ends (the engine example's chaining).
                (detail, visible) = camera_detail(model, &policy, root);
                controls = controls_for(lo, hi, i, cycle + 1);
                t += dt;
                while t >= kernel.duration() {
                    let ending = kernel.duration();
                    t -= ending;
                    let motion = kernel.root_motion();
                    let blend = kernel.detail().active_joints > 0
                        && lod.evaluated(detail).active_joints > 0;
                    if blend {
                        // The outgoing side: the pose shown at the clip's end (its seam applied).
                        let (k, s, st) = (&kernel, &seam, seam_start);
                        seam_scratch
                            .capture(ending as f32, ending as f32, Some(&motion), |tt, out| {
                                lod.pose(k, k.phase_at(f64::from(tt)), out)?;
                                let rows = k.rows().min(out.len());
                                s.apply(tt - st, &mut out[..rows]);
                                Ok::<usize, KernelError>(rows)
                            })
                            .expect("capture");
                    }
                    frame = frame.next(&motion);
                    seam.clear();
                    lod.build_kernel(&controls, detail, &mut scratch, &mut kernel)
                        .expect("kernel");
                    if blend && kernel.detail().active_joints > 0 {
                        let k = &kernel;
                        seam_scratch
                            .start(
                                t as f32,
                                k.duration() as f32,
                                |tt, out| {
                                    lod.pose(k, k.phase_at(f64::from(tt)), out)?;
                                    Ok::<usize, KernelError>(k.rows().min(out.len()))
                                },
                                &mut seam,
                            )
                            .expect("seam");
                        seam_start = t as f32;
                    }
                    body_scale = model.body_scale(&controls);
                    cycle_detail = detail;
                    cycle += 1;
                    begun += 1;
                }
            }
            let active = cycle_detail.active_joints;
            lod.pose(&kernel, kernel.phase_at(t), &mut pose)
                .expect("pose");
            if seam.is_active() {
                let since = t as f32 - seam_start;
                let rows = kernel.rows().min(pose.len());
                seam.apply(since, &mut pose[..rows]);
                seam.finish_after(since);
            }
            lock.apply(rig, feet, &frame, active, body_scale, dt as f32, &mut pose)
                .expect("foot lock");
            locked_frames += 1;
            rig.local_rotations(&pose, active, &mut locals)
                .expect("local rotations");
            root = frame.to_world(Vec3::new(pose[0], pose[1], pose[2]));
            let root_rotation = frame.rotation() * locals[rig.root()];
            rig.joint_transforms_scaled(&pose, active, body_scale, &mut transforms)
                .expect("transforms");

            let (t_bits, d_bits) = (t.to_bits(), kernel.duration().to_bits());
            let mut state = vec![
                t_bits as u32,
                (t_bits >> 32) as u32,
                d_bits as u32,
                (d_bits >> 32) as u32,
                cycle as u32,
                (cycle >> 32) as u32,
            ];
            state.extend(double_words(root.to_array()));
            state.extend(double_words([frame.x, frame.z, frame.heading]));
            state.extend(float_words(root_rotation.to_array()));
            state.extend(float_words([body_scale]));
            state.extend([
                cycle_detail.accuracy as u32,
                cycle_detail.active_joints as u32,
                begun,
                1, // feet locked
            ]);
            let local_words = float_words(locals.iter().flat_map(|q| q.to_array()));
            let joint_words = float_words(transforms.iter().flat_map(|t| {
                let (r, p) = (t.rotation.to_array(), t.position.to_array());
                [r[0], r[1], r[2], r[3], p[0], p[1], p[2]]
            }));
            let head = [
                f as u32,
                detail.accuracy as u32,
                detail.active_joints as u32,
                u32::from(visible),
            ];
            for w in head
                .iter()
                .chain(&state)
                .chain(&local_words)
                .chain(&joint_words)
            {
                h = mix(h, *w);
            }
            if i % DUMP_EVERY_WALKER == 0 && (f % DUMP_EVERY_FRAME == 0 || f == FRAMES - 1) {
                let (level, active, vis) = (head[1], head[2], head[3]);
                let text = format!(
                    "D {i} {f} {level} {active} {vis}\nS {i} {f}{}\nL {i} {f}{}\nJ {i} {f}{}",
                    hex(&state),
                    hex(&local_words),
                    hex(&joint_words)
                );
                lines.push((f, i, text));
            }
        }
        let t_bits = t.to_bits();
        for w in [
            cycle as u32,
            (cycle >> 32) as u32,
            t_bits as u32,
            (t_bits >> 32) as u32,
        ] {
            h = mix(h, w);
        }
        sums.push(format!("H {i} {cycle} {h:016x}"));
    }
    lines.sort_by_key(|(f, i, _)| (*f, *i));
    let mut out: Vec<String> = lines.into_iter().map(|(_, _, l)| l).collect();
    out.extend(sums);
    (out.join("\n") + "\n", locked_frames)
}

#[test]
fn c_crowd_matches_the_rust_api_bit_for_bit() {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let work = std::env::temp_dir().join(format!("motion-lod-ffi-{}", std::process::id()));
    std::fs::create_dir_all(&work).expect("temporary folder");
    let model_path = work.join("walk.mlod");
    write_model(&model_path);

    let exe = work.join("crowd");
    let status = Command::new(std::env::var("CC").unwrap_or_else(|_| "cc".into()))
        .arg("-std=c11")
        .arg("-Wall")
        .arg("-Wextra")
        .arg("-Werror")
        .arg("-ffp-contract=off")
        .arg(crate_dir.join("examples/crowd.c"))
        .arg("-I")
        .arg(crate_dir.join("include"))
        .arg(static_library())
        .args(["-lm", "-lpthread", "-ldl", "-o"])
        .arg(&exe)
        .status()
        .expect("the C compiler runs (cc)");
    assert!(status.success(), "examples/crowd.c compiles and links");

    let summary = Command::new(&exe).arg(&model_path).output().expect("runs");
    let text = String::from_utf8_lossy(&summary.stdout);
    assert!(
        summary.status.success(),
        "crowd failed: {}{}",
        text,
        String::from_utf8_lossy(&summary.stderr)
    );
    println!("{text}");
    assert!(
        text.contains(&format!("walkers: {WALKERS} for {FRAMES} frames")),
        "{text}"
    );
    assert!(
        text.contains(&format!(
            "motion-lod {} (ABI {})",
            env!("CARGO_PKG_VERSION"),
            motion_lod_ffi::MLOD_ABI_VERSION
        )),
        "{text}"
    );
    assert!(text.contains("garbage bytes refused"), "{text}");

    let dump = Command::new(&exe)
        .arg(&model_path)
        .arg("--dump")
        .output()
        .expect("runs");
    assert!(
        dump.status.success(),
        "{}",
        String::from_utf8_lossy(&dump.stderr)
    );
    let c_lines = String::from_utf8(dump.stdout).expect("ASCII");
    let model = RuntimeModel::load(&model_path).expect("the runtime loads the model");
    let (rust_lines, locked) = rust_dump(&model);
    assert_eq!(locked, WALKERS * FRAMES, "the reference locks every frame");
    assert_eq!(c_lines.lines().count(), rust_lines.lines().count());
    for (c, r) in c_lines.lines().zip(rust_lines.lines()) {
        assert_eq!(c, r, "the C example differs from the Rust API");
    }
    // Every walker's checksum was compared; the walk crossed several cycles, with and without the
    // camera's view and at several levels of detail, feet locked (the state's last word).
    let checksums: Vec<&str> = c_lines.lines().filter(|l| l.starts_with("H ")).collect();
    assert_eq!(checksums.len(), WALKERS);
    let fewest_cycles = checksums
        .iter()
        .map(|l| {
            l.split(' ')
                .nth(2)
                .and_then(|c| c.parse::<u64>().ok())
                .expect("cycle")
        })
        .min()
        .expect("walkers");
    assert!(
        fewest_cycles >= 3,
        "every walker chains at least three cycles: {fewest_cycles}"
    );
    let details: std::collections::BTreeSet<&str> = c_lines
        .lines()
        .filter(|l| l.starts_with("D "))
        .map(|l| l.splitn(4, ' ').nth(3).unwrap_or(""))
        .collect();
    assert!(details.len() >= 4, "details used: {details:?}");
    assert!(details.iter().any(|d| d.ends_with(" 0")), "{details:?}");
    assert!(details.iter().any(|d| d.ends_with(" 1")), "{details:?}");
    assert!(
        c_lines
            .lines()
            .filter(|l| l.starts_with("S "))
            .all(|l| l.ends_with(" 00000001")),
        "the foot lock ran on every frame"
    );
    let _ = std::fs::remove_dir_all(&work);
}
