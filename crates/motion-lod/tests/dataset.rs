//! The dataset pipeline and `motion-lod cycles` on `fixtures/` (when generated) and on the Bandai
//! folder of `../shared/mocap` (when present).

use std::path::{Path, PathBuf};
use std::process::Command;

use motion_lod::dataset::{AlignedSet, CycleSet, DatasetConfig, align_cycles, load_cycles};
use timewarp::{AlignMethod, DtwConfig};

const FIXTURES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures");

/// Folders under `root` (and `root` itself) that hold at least one `.bvh` file.
fn bvh_folders(root: &Path) -> Vec<PathBuf> {
    let has_bvh = |d: &Path| {
        std::fs::read_dir(d).is_ok_and(|it| {
            it.flatten().any(|e| {
                e.path()
                    .extension()
                    .is_some_and(|x| x.eq_ignore_ascii_case("bvh"))
            })
        })
    };
    let mut out = Vec::new();
    if has_bvh(root) {
        out.push(root.to_path_buf());
    }
    if let Ok(it) = std::fs::read_dir(root) {
        let mut subs: Vec<PathBuf> = it
            .flatten()
            .map(|e| e.path())
            .filter(|p| p.is_dir())
            .collect();
        subs.sort();
        out.extend(subs.into_iter().filter(|d| has_bvh(d)));
    }
    out
}

/// Checks the invariants of a loaded and aligned set; returns (turn min, turn max).
fn check_set(set: &CycleSet, aligned: &AlignedSet) -> (f64, f64) {
    let s = set.cycles.len();
    let p = set.layout.dof();
    let [tp, tt, ts] = aligned.tensor.dims();
    assert_eq!((tp, ts), (p, s));
    assert_eq!(tt, set.median_length().max(2));
    assert_eq!(aligned.controls.len(), s);
    assert_eq!(aligned.sources.len(), s);
    assert!(aligned.reference < s);
    assert!(aligned.tensor.as_slice().iter().all(|v| v.is_finite()));
    for (k, c) in set.cycles.iter().enumerate() {
        // Row 6 integrates to the cycle's duration.
        let total: f64 = (0..tt).map(|j| aligned.tensor.get(6, j, k)).sum();
        assert!(
            (total - c.duration()).abs() < 1e-9,
            "cycle {k}: {total} vs {}",
            c.duration()
        );
        // The first aligned pose is the cycle's first pose (row 6 excepted).
        let first = c.pose(0, p);
        for (i, &v) in first.iter().enumerate().filter(|&(i, _)| i != 6) {
            assert!((aligned.tensor.get(i, 0, k) - v).abs() < 1e-9, "row {i}");
        }
    }
    let turns = aligned.controls.iter().map(|c| c.turn);
    (
        turns.clone().fold(f64::INFINITY, f64::min),
        turns.fold(f64::NEG_INFINITY, f64::max),
    )
}

/// Runs the binary and returns its stdout; panics with stderr on failure.
fn run_cli(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_motion-lod"))
        .args(args)
        .output()
        .expect("run motion-lod");
    assert!(
        out.status.success(),
        "motion-lod {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("utf-8 output")
}

/// Checks the `--json` line, the NPY shape and the CSV of `motion-lod cycles` on `dir`.
fn check_cli(dir: &Path, set: &CycleSet, aligned: &AlignedSet, extra: &[&str]) {
    // One folder per data set: the tests calling this run in parallel in one process.
    let tag = dir
        .file_name()
        .map_or("data".into(), |n| n.to_string_lossy().into_owned());
    let tmp = std::env::temp_dir().join(format!(
        "motion-lod-dataset-test-{}-{tag}",
        std::process::id()
    ));
    std::fs::create_dir_all(&tmp).unwrap();
    let npy = tmp.join("tensor.npy");
    let csv = tmp.join("controls.csv");
    let dir_s = dir.to_str().unwrap();
    let mut args = vec![
        "cycles",
        dir_s,
        "--json",
        "--tensor",
        npy.to_str().unwrap(),
        "--controls",
        csv.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let stdout = run_cli(&args);
    assert_eq!(stdout.lines().count(), 1, "{stdout}");
    let v: serde_json::Value = serde_json::from_str(stdout.trim()).expect("JSON line");
    let [p, t, s] = aligned.tensor.dims();
    assert_eq!(v["files"], set.files);
    assert_eq!(v["failed_files"], set.failed.len());
    assert_eq!(v["cycles"], set.cycles.len());
    assert_eq!(v["dropped"], set.dropped.len());
    assert_eq!(
        (v["P"].as_u64(), v["T"].as_u64(), v["S"].as_u64()),
        (Some(p as u64), Some(t as u64), Some(s as u64))
    );
    let back = tensor_ops::npy::read_tensor(&npy).expect("NPY reads back");
    assert_eq!(back.dims(), [p, t, s]);
    assert_eq!(back.as_slice(), aligned.tensor.as_slice());
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("source,first_frame,last_frame,dx_m,dz_m,turn_rad,height_m")
    );
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), s);
    let last: Vec<&str> = rows[s - 1].rsplitn(7, ',').collect();
    let turn: f64 = last[1].parse().unwrap();
    assert!((turn - aligned.controls[s - 1].turn).abs() < 1e-12);
    std::fs::remove_dir_all(&tmp).ok();
}

#[test]
fn fixtures_load_align_and_report() {
    let dirs = bvh_folders(Path::new(FIXTURES));
    let Some(dir) = dirs.first() else {
        motion_io::test_data::missing("fixtures/ has no .bvh yet");
        return;
    };
    let set = match load_cycles(
        std::slice::from_ref(dir),
        &DatasetConfig::default(),
        &|_, _| {},
    ) {
        Ok(set) => set,
        Err(e) => panic!("fixtures in {}: {e}", dir.display()),
    };
    assert!(set.files >= 1);
    assert!(!set.cycles.is_empty());
    let aligned = align_cycles(&set, None, AlignMethod::Dtw(DtwConfig::default())).unwrap();
    let (lo, hi) = check_set(&set, &aligned);
    println!(
        "fixtures {}: {} files, {} cycles, {} dropped, P x T x S = {:?}, turn [{lo:.3}, {hi:.3}] rad",
        dir.display(),
        set.files,
        set.cycles.len(),
        set.dropped.len(),
        aligned.tensor.dims()
    );
    // Same result whatever the thread count.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let again = pool.install(|| {
        let set = load_cycles(
            std::slice::from_ref(dir),
            &DatasetConfig::default(),
            &|_, _| {},
        )
        .unwrap();
        align_cycles(&set, None, AlignMethod::Dtw(DtwConfig::default())).unwrap()
    });
    assert_eq!(again.tensor.as_slice(), aligned.tensor.as_slice());
    check_cli(dir, &set, &aligned, &[]);
    let (better, dtw_mean, uniform_mean) = dtw_versus_uniform(&set);
    println!(
        "fixtures: DTW lowers the distance to the reference for {better} of {} cycles \
         (mean {dtw_mean:.5} vs uniform {uniform_mean:.5})",
        set.cycles.len()
    );
    assert!(dtw_mean <= uniform_mean);
}

#[test]
fn bandai_counts_ranges_and_cli() {
    let Some(dir) =
        motion_io::test_data::shared_mocap(env!("CARGO_MANIFEST_DIR"), "bandai-namco-2-walk")
    else {
        return;
    };
    let set = load_cycles(
        std::slice::from_ref(&dir),
        &DatasetConfig::default(),
        &|_, _| {},
    )
    .unwrap();
    let aligned = align_cycles(&set, None, AlignMethod::Uniform).unwrap();
    let (lo, hi) = check_set(&set, &aligned);
    let range = |f: fn(&motion_io::MeasuredControls) -> f64| {
        let v: Vec<f64> = aligned.controls.iter().map(f).collect();
        (
            v.iter().copied().fold(f64::INFINITY, f64::min),
            v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        )
    };
    println!(
        "bandai: {} files, {} failed, {} cycles, {} dropped {:?}, P x T x S = {:?}, lengths median {}",
        set.files,
        set.failed.len(),
        set.cycles.len(),
        set.dropped.len(),
        set.dropped_by_reason(),
        aligned.tensor.dims(),
        set.median_length()
    );
    println!(
        "bandai controls: dx {:?} m, dz {:?} m, turn [{:.1}, {:.1}] deg, height {:?} m",
        range(|c| c.dx),
        range(|c| c.dz),
        lo.to_degrees(),
        hi.to_degrees(),
        range(|c| c.height)
    );
    assert_eq!(set.files, 168);
    assert!(set.failed.is_empty(), "{:?}", set.failed);
    assert!(set.cycles.len() > 400, "{} cycles", set.cycles.len());
    // Both turn directions are covered.
    assert!(lo < -0.2 && hi > 0.2, "turn range [{lo}, {hi}]");
    check_cli(&dir, &set, &aligned, &["--align", "uniform"]);
    let (better, dtw_mean, uniform_mean) = dtw_versus_uniform(&set);
    println!(
        "bandai: DTW lowers the distance to the reference for {better} of {} cycles \
         (mean {dtw_mean:.4} vs uniform {uniform_mean:.4} m^2 per frame)",
        set.cycles.len()
    );
    assert!(dtw_mean < uniform_mean);
}

/// Aligns the cycles' features (joint positions in the root frame) to the same reference by DTW
/// and by uniform scaling; returns how many cycles DTW brings closer to the reference and the two
/// mean squared distances per aligned frame.
fn dtw_versus_uniform(set: &CycleSet) -> (usize, f64, f64) {
    use timewarp::{AlignConfig, FrameSeq, align};
    let feats: Vec<FrameSeq> = set
        .cycles
        .iter()
        .map(|c| {
            let f = c.features(&set.layout);
            FrameSeq::new(f.len() / c.frame_count(), f).unwrap()
        })
        .collect();
    let ft: Vec<f64> = set.cycles.iter().map(|c| c.frame_time).collect();
    let mut cfg = AlignConfig::for_data(&feats, AlignMethod::Dtw(DtwConfig::default()));
    let warped = align(&feats, &feats, &ft, &cfg).unwrap();
    cfg.reference = Some(warped.reference);
    cfg.method = AlignMethod::Uniform;
    let uniform = align(&feats, &feats, &ft, &cfg).unwrap();
    let dist = |a: &FrameSeq, b: &FrameSeq, skip: usize| -> f64 {
        let mut sum = 0.0;
        for k in 0..a.len() {
            for c in (0..a.dim).filter(|&c| c != skip) {
                sum += (a.frame(k)[c] - b.frame(k)[c]).powi(2);
            }
        }
        sum / a.len() as f64
    };
    let r = warped.reference;
    let (mut better, mut dw, mut du) = (0, 0.0, 0.0);
    for s in 0..feats.len() {
        let w = dist(&warped.aligned[s], &warped.aligned[r], warped.increment_col);
        let u = dist(
            &uniform.aligned[s],
            &uniform.aligned[r],
            uniform.increment_col,
        );
        better += usize::from(w < u);
        dw += w;
        du += u;
    }
    (better, dw / feats.len() as f64, du / feats.len() as f64)
}

#[test]
fn bad_inputs_are_clear_errors() {
    let missing = PathBuf::from("/nonexistent/motion-lod-folder");
    let err = load_cycles(&[missing], &DatasetConfig::default(), &|_, _| {}).unwrap_err();
    assert!(
        err.to_string().contains("/nonexistent/motion-lod-folder"),
        "{err}"
    );
    assert!(load_cycles(&[], &DatasetConfig::default(), &|_, _| {}).is_err());
    let tmp = std::env::temp_dir().join(format!("motion-lod-bad-{}", std::process::id()));
    std::fs::create_dir_all(&tmp).unwrap();
    let err = load_cycles(
        std::slice::from_ref(&tmp),
        &DatasetConfig::default(),
        &|_, _| {},
    )
    .unwrap_err();
    assert!(err.to_string().contains("no .bvh file"), "{err}");
    std::fs::write(
        tmp.join("broken.bvh"),
        "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0\n",
    )
    .unwrap();
    let err = load_cycles(
        std::slice::from_ref(&tmp),
        &DatasetConfig::default(),
        &|_, _| {},
    )
    .unwrap_err();
    assert!(err.to_string().contains("broken.bvh"), "{err}");
    std::fs::remove_dir_all(&tmp).ok();
    let out = Command::new(env!("CARGO_BIN_EXE_motion-lod"))
        .args(["cycles", "/nonexistent/motion-lod-folder", "--json"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("nonexistent"));
}

/// A user error (a missing folder) prints `error: ` with what and where and each cause once, and no
/// backtrace even when `RUST_BACKTRACE` asks for one (issue 19); the exit status is 1.
#[test]
fn user_errors_print_each_cause_once_and_no_backtrace() {
    let model = std::env::temp_dir().join(format!("motion-lod-no-{}.mlod", std::process::id()));
    let model = model.to_str().unwrap();
    for args in [
        vec!["cycles", "/nonexistent/motion-lod-folder"],
        vec!["build", "/nonexistent/motion-lod-folder", "-o", model],
    ] {
        let command = args[0];
        let out = Command::new(env!("CARGO_BIN_EXE_motion-lod"))
            .args(&args)
            .env("RUST_BACKTRACE", "1")
            .env("RUST_LIB_BACKTRACE", "1")
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{command}: {stderr}");
        assert!(stderr.starts_with("error: "), "{command}: {stderr}");
        assert!(
            stderr.contains("/nonexistent/motion-lod-folder"),
            "{command}: {stderr}"
        );
        assert!(
            !stderr.to_lowercase().contains("backtrace"),
            "{command}: {stderr}"
        );
        let lines: Vec<&str> = stderr.lines().collect();
        for (i, a) in lines.iter().enumerate() {
            let cause = a.trim_start_matches("  caused by: ");
            assert!(
                !lines[..i].iter().any(|b| b.contains(cause)),
                "{command}: {cause:?} repeats an earlier line:\n{stderr}"
            );
        }
    }
}

/// Negative numbers are values in every subcommand (issue 19): `--fps -30` reaches the range check
/// instead of being read as a flag `-3`.
#[test]
fn negative_numbers_parse_as_values() {
    let out = Command::new(env!("CARGO_BIN_EXE_motion-lod"))
        .args([
            "synth", "m.mlod", "--dx", "-0.3", "--dz", "1.2", "--turn", "-30",
        ])
        .args(["--fps", "-30", "-o", "walk.bvh"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.contains("-30 is not in [1, 1000]") && !stderr.contains("unexpected argument"),
        "{stderr}"
    );
}

/// A folder given twice, under two names, is refused before any take is read: each take was read
/// twice, and the build kept controls by a leave-one-out that left each sample's twin in (found
/// 2026-11-28).
#[test]
fn a_folder_given_twice_is_refused() {
    let dir = std::env::temp_dir().join(format!("mlod-twice-{}", std::process::id()));
    let sub = dir.join("takes");
    std::fs::create_dir_all(&sub).unwrap();
    std::fs::write(sub.join("a.bvh"), "HIERARCHY\n").unwrap();
    let again = dir.join("takes/../takes");
    let e = load_cycles(
        &[sub.clone(), again.clone()],
        &DatasetConfig::default(),
        &|_, _| {},
    )
    .unwrap_err();
    assert!(
        matches!(&e, motion_lod::dataset::DatasetError::SameFolder { first, second } if *first == sub && *second == again),
        "{e}"
    );
    assert!(e.to_string().contains("same folder"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `text` (a BVH) with the first number of the first OFFSET after `JOINT Spine` (its x) replaced
/// by what `replace` makes of it.
fn with_spine_offset_x(text: &str, replace: impl Fn(&str) -> String) -> String {
    let spine = text.find("JOINT Spine").unwrap();
    let at = spine + text[spine..].find("OFFSET ").unwrap() + "OFFSET ".len();
    let end = at + text[at..].find(char::is_whitespace).unwrap();
    format!("{}{}{}", &text[..at], replace(&text[at..end]), &text[end..])
}

/// A take whose numbers no walk has (the Spine's OFFSET at 1e300, which measured an infinite
/// height) is refused by name with the reason, and the other take is kept: `cycles` printed
/// `height [1.35, inf] m` and `build` failed on "controls of sample 0" (found 2026-11-28).
#[test]
fn a_take_measuring_infinite_controls_is_refused_by_name() {
    let Some(bandai) =
        motion_io::test_data::shared_mocap(env!("CARGO_MANIFEST_DIR"), "bandai-namco-2-walk")
    else {
        return;
    };
    let good = bandai.join("dataset-2_walk_normal_001.bvh");
    let text = std::fs::read_to_string(&good).unwrap();
    let dir = std::env::temp_dir().join(format!("mlod-inf-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("a_good.bvh"), &text).unwrap();
    let huge = with_spine_offset_x(&text, |_| "1e300".into());
    let bad = dir.join("b_huge.bvh");
    std::fs::write(&bad, huge).unwrap();
    let set = load_cycles(
        std::slice::from_ref(&dir),
        &DatasetConfig::default(),
        &|_, _| {},
    )
    .unwrap();
    assert!(!set.cycles.is_empty());
    assert!(
        set.cycles
            .iter()
            .all(|c| c.controls.to_array().iter().all(|v| v.is_finite()))
    );
    let refused = set
        .takes
        .iter()
        .find(|t| t.path == bad)
        .expect("the take is listed");
    assert_eq!(refused.cycles, 0);
    let reason = refused.reason.as_deref().unwrap_or_default();
    assert!(reason.contains("not finite"), "{reason}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A take whose `Frame Time` is no capture rate of a walk (milliseconds written for seconds) and a
/// take whose skeleton stands 10 km tall (an OFFSET a million times too long) are each refused by
/// name with their own reason, and the good take is kept. Both used to be read: the first said "no
/// cycle candidate ... the feet or up axis are wrong", the second printed `height [1.3, 10001] m`
/// and failed the build at its very end on the runtime's stature (found 2026-11-28).
#[test]
fn a_take_with_no_capture_rate_or_no_body_height_is_refused_by_name() {
    let good = Path::new(FIXTURES).join("walk_p160_t01.bvh");
    let text = std::fs::read_to_string(&good).expect("fixtures are in the repository");
    let dir = std::env::temp_dir().join(format!("mlod-rate-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("a_good.bvh"), &text).unwrap();
    let line = text.lines().find(|l| l.starts_with("Frame Time:")).unwrap();
    let seconds: f64 = line["Frame Time:".len()..].trim().parse().unwrap();
    let ms = text.replace(line, &format!("Frame Time: {}", seconds * 1000.0));
    let (slow, tall) = (dir.join("b_ms.bvh"), dir.join("c_tall.bvh"));
    std::fs::write(&slow, ms).unwrap();
    // The Spine's x offset a million times longer (1e6 where it is 0).
    let tall_text = with_spine_offset_x(&text, |x| {
        let x: f64 = x.parse().unwrap();
        format!("{}", if x == 0.0 { 1e6 } else { x * 1e6 })
    });
    std::fs::write(&tall, tall_text).unwrap();
    let set = load_cycles(
        std::slice::from_ref(&dir),
        &DatasetConfig::default(),
        &|_, _| {},
    )
    .unwrap();
    assert!(!set.cycles.is_empty());
    for (path, says) in [
        (&slow, "read as milliseconds it would be"),
        (&tall, "standing height"),
    ] {
        let take = set.takes.iter().find(|t| t.path == *path).unwrap();
        assert_eq!(take.cycles, 0, "{}", path.display());
        let reason = take.reason.as_deref().unwrap_or_default();
        assert!(reason.contains(says), "{}: {reason}", path.display());
    }
    let kept = set.takes.iter().find(|t| t.path.ends_with("a_good.bvh"));
    assert!(kept.is_some_and(|t| t.cycles > 0));
    let _ = std::fs::remove_dir_all(&dir);
}
