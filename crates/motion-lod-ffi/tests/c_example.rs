//! `examples/crowd.c`, compiled by the system's C compiler against the checked-in header and this
//! crate's static library, animates a small crowd; its poses, joint transforms and root positions
//! equal the Rust API's bit for bit, computed here the same way.

use std::path::{Path, PathBuf};
use std::process::Command;

use lod_policy::{
    ClipKernel, DistancePolicy, JointTransform, KernelScratch, LevelPolicy, RuntimeModel,
    ViewParams,
};
use motion_lod::dataset::DataSpec;
use motion_lod::progress::NoProgress;
use motion_lod::{BuildConfig, MotionModel};

const WALKERS: usize = 6;
const FRAMES: usize = 45;
const FPS: f64 = 30.0;

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

fn hex(values: &[f32]) -> String {
    values
        .iter()
        .map(|v| format!(" {:08x}", v.to_bits()))
        .collect()
}

/// What `crowd.c --dump` prints, computed through the Rust API.
fn rust_dump(model: &RuntimeModel) -> String {
    let lod = model.lod();
    let policy = DistancePolicy::for_model(lod);
    let joints = model.rig().joint_count();
    let animated = model.rig().rotating_joints().len();
    let c = lod.controls();
    let (lo, hi) = (&c.min, &c.max);
    let mut out = String::new();
    let mut kernel = ClipKernel::new(lod);
    let mut scratch = KernelScratch::new(lod);
    let mut pose = vec![0.0f32; lod.p()];
    let mut transforms = vec![JointTransform::default(); joints];
    for i in 0..WALKERS {
        let distance = 3.0f32 * 4.0f32.powf(i as f32);
        let u = i as f32 / (WALKERS - 1) as f32;
        let controls = [
            lo[0] + (hi[0] - lo[0]) * 0.5,
            lo[1] + (hi[1] - lo[1]) * u,
            lo[2] + (hi[2] - lo[2]) * (1.0 - u),
            lo[3] + (hi[3] - lo[3]) * 0.5,
        ];
        let detail = policy
            .detail(distance, true, &ViewParams::default())
            .resolve(lod.levels().len(), animated)
            .expect("policy level");
        let (level, active) = (detail.accuracy, detail.active_joints);
        lod.build_kernel(&controls, detail, &mut scratch, &mut kernel)
            .expect("kernel");
        let mut root = [0.0f32; 3];
        let mut t = 0.0f64;
        for f in 0..FRAMES {
            while t >= kernel.duration() {
                t -= kernel.duration();
                let motion = kernel.root_motion();
                let (s, co) = (root[2].sin(), root[2].cos());
                root[0] += co * motion.dx + s * motion.dz;
                root[1] += -s * motion.dx + co * motion.dz;
                root[2] += motion.turn;
                lod.build_kernel(&controls, detail, &mut scratch, &mut kernel)
                    .expect("kernel");
            }
            lod.pose(&kernel, kernel.phase_at(t), &mut pose)
                .expect("pose");
            let scale = model.body_scale(&lod_policy::Controls::from_array(controls));
            model
                .rig()
                .joint_transforms_scaled(&pose, active, scale, &mut transforms)
                .expect("transforms");
            let flat: Vec<f32> = transforms
                .iter()
                .flat_map(|t| {
                    let r = t.rotation.to_array();
                    let p = t.position.to_array();
                    [r[0], r[1], r[2], r[3], p[0], p[1], p[2]]
                })
                .collect();
            out.push_str(&format!("D {i} {f} {level} {active}\n"));
            out.push_str(&format!("P {i} {f}{}\n", hex(&pose)));
            out.push_str(&format!("J {i} {f}{}\n", hex(&flat)));
            out.push_str(&format!("R {i} {f}{}\n", hex(&root)));
            t += 1.0 / FPS;
        }
    }
    out
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
    assert_eq!(text.matches("walker ").count(), WALKERS, "{text}");
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
    let rust_lines = rust_dump(&model);
    assert_eq!(c_lines.lines().count(), rust_lines.lines().count());
    for (c, r) in c_lines.lines().zip(rust_lines.lines()) {
        assert_eq!(c, r, "the C example differs from the Rust API");
    }
    // The crowd uses more than one level of detail, so the comparison covers several.
    let details: std::collections::BTreeSet<&str> = c_lines
        .lines()
        .filter(|l| l.starts_with("D "))
        .map(|l| l.splitn(4, ' ').nth(3).unwrap_or(""))
        .collect();
    assert!(details.len() >= 3, "details used: {details:?}");
    let _ = std::fs::remove_dir_all(&work);
}
