//! Any skeleton in (issue 13): every exporter variant of the walker's takes in
//! `fixtures/variants/` gives the same cycles and controls as the base takes; a joint map; files
//! that all fail are listed with their reasons; a 5-cycle set builds, evaluates and synthesizes;
//! a model's data folders are relative to the model file; the shared data keep their conventions.

use std::path::{Path, PathBuf};
use std::process::Command;

use motion_io::{RootPositions, SignedAxis, SkipReason, Units};
use motion_lod::dataset::{
    CycleSet, DataSpec, DatasetConfig, DatasetError, joint_map_from_toml, load_cycles,
};

const FIXTURES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures");
const BIN: &str = env!("CARGO_BIN_EXE_motion-lod");

fn variants() -> PathBuf {
    Path::new(FIXTURES).join("variants")
}

fn file_name(p: &Path) -> String {
    p.file_name()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_default()
}

fn load(dir: &Path, config: &DatasetConfig) -> CycleSet {
    load_cycles(&[dir.to_path_buf()], config, &|_, _| {})
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
}

/// The base takes' cycles, from the whole fixtures folder.
fn base() -> CycleSet {
    load(Path::new(FIXTURES), &DatasetConfig::default())
}

/// Every variant's cycles match the base takes' in count, frames (shifted by `shift`) and controls
/// in metres (1 mm, 0.1 degree).
fn assert_same_cycles(base: &CycleSet, variant: &CycleSet, shift: usize, what: &str) {
    let takes: Vec<String> = variant
        .cycles
        .iter()
        .map(|c| file_name(&c.source))
        .collect::<std::collections::BTreeSet<_>>()
        .into_iter()
        .collect();
    assert_eq!(takes.len(), 2, "{what}: takes with cycles {takes:?}");
    for take in &takes {
        let a: Vec<_> = base
            .cycles
            .iter()
            .filter(|c| &file_name(&c.source) == take)
            .collect();
        let b: Vec<_> = variant
            .cycles
            .iter()
            .filter(|c| &file_name(&c.source) == take)
            .collect();
        assert_eq!(a.len(), b.len(), "{what} {take}: cycle count");
        assert!(!a.is_empty(), "{what} {take}: no cycle");
        for (x, y) in a.iter().zip(&b) {
            assert_eq!(x.first_frame + shift, y.first_frame, "{what} {take}");
            assert_eq!(x.last_frame + shift, y.last_frame, "{what} {take}");
            let (cx, cy) = (x.controls, y.controls);
            for (name, u, v) in [
                ("dx", cx.dx, cy.dx),
                ("dz", cx.dz, cy.dz),
                ("height", cx.height, cy.height),
            ] {
                assert!(
                    (u - v).abs() < 1e-3,
                    "{what} {take} frame {}: {name} {u} vs {v} m",
                    x.first_frame
                );
            }
            let dt = (cx.turn - cy.turn).to_degrees().abs();
            assert!(dt < 0.1, "{what} {take}: turn differs by {dt} deg");
        }
    }
}

fn variant(name: &str) -> Option<PathBuf> {
    let dir = variants().join(name);
    motion_io::test_data::require_dir(&dir, "fixtures/variants (run `cargo xtask fixtures`)")
}

#[test]
fn every_variant_gives_the_base_cycles_and_controls() {
    let Some(root) = motion_io::test_data::require_dir(&variants(), "fixtures/variants") else {
        return;
    };
    let base = base();
    let base_conv = base.conventions.clone().expect("conventions");
    assert_eq!(base_conv.units, Units::Centimetres);
    assert_eq!(base_conv.up, SignedAxis::Y);
    assert_eq!(base_conv.forward, Some(SignedAxis::Z));
    let mut seen = 0;
    let mut folders: Vec<PathBuf> = std::fs::read_dir(&root)
        .expect("variants folder")
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.is_dir())
        .collect();
    folders.sort();
    for dir in folders {
        let name = file_name(&dir);
        let set = load(&dir, &DatasetConfig::default());
        let c = set.conventions.clone().expect("conventions");
        let shift = usize::from(name == "t-pose-first");
        assert_same_cycles(&base, &set, shift, &name);
        assert!(set.failed.is_empty(), "{name}: {:?}", set.failed);
        let expected_units = match name.as_str() {
            "metres" => Units::Metres,
            "millimetres" => Units::Millimetres,
            "inches" => Units::Inches,
            _ => Units::Centimetres,
        };
        assert_eq!(c.units, expected_units, "{name}");
        assert!(c.units_detected && c.up_detected, "{name}");
        let up = if name == "z-up" {
            SignedAxis::Z
        } else {
            SignedAxis::Y
        };
        assert_eq!(c.up, up, "{name}");
        assert_eq!(c.feet_by_hierarchy, name == "anonymous-names", "{name}");
        let roots = if name == "root-offset" {
            RootPositions::Relative
        } else {
            RootPositions::Same
        };
        assert_eq!(c.root_positions, roots, "{name}");
        let skipped: Vec<_> = set.takes.iter().flat_map(|t| t.skipped.clone()).collect();
        if name == "t-pose-first" {
            assert_eq!(skipped.len(), 2, "{name}: {skipped:?}");
            for s in &skipped {
                assert_eq!((s.first, s.last), (0, 0));
                assert!(matches!(s.reason, SkipReason::Jump { metres } if metres > 2.5));
            }
        } else {
            assert!(skipped.is_empty(), "{name}: {skipped:?}");
        }
        // The layout's units convert to the same metres: the pose vectors' root heights agree.
        let h: f64 = set.cycles[0].poses[1];
        let take = file_name(&set.cycles[0].source);
        let b = base
            .cycles
            .iter()
            .find(|x| file_name(&x.source) == take)
            .expect("base cycle");
        assert!(
            (h - b.poses[1]).abs() < 1e-3,
            "{name}: root height {h} vs {}",
            b.poses[1]
        );
        seen += 1;
    }
    assert_eq!(seen, 10, "variant folders");
}

#[test]
fn forced_up_and_units_override_detection() {
    let (Some(zup), Some(metres)) = (variant("z-up"), variant("metres")) else {
        return;
    };
    let base = base();
    let set = load(
        &zup,
        &DatasetConfig {
            up: Some(SignedAxis::Z),
            ..DatasetConfig::default()
        },
    );
    assert!(!set.conventions.as_ref().expect("conventions").up_detected);
    assert_same_cycles(&base, &set, 0, "z-up forced");
    // Metres read as centimetres: a 1.7 m person of 1.7 cm walks steps of a centimetre; the
    // controls scale by 100 exactly, so forcing is obeyed.
    let set = load(
        &metres,
        &DatasetConfig {
            units: Some(Units::Centimetres),
            ..DatasetConfig::default()
        },
    );
    let c = set.conventions.as_ref().expect("conventions");
    assert_eq!(c.units, Units::Centimetres);
    assert!(!c.units_detected);
    assert!(set.cycles.iter().all(|c| c.controls.dz < 0.05));
}

#[test]
fn a_joint_map_names_the_feet_of_anonymous_joints() {
    let Some(dir) = variant("anonymous-names") else {
        return;
    };
    // The walker's joint indices of the feet, read from a base take.
    let base_take =
        motion_io::read_bvh(Path::new(FIXTURES).join("walk_p160_t01.bvh")).expect("base take");
    let index = |n: &str| base_take.skeleton.find(n).expect("joint");
    let toml = format!(
        "left_foot = \"j{:02}\"\nright_foot = \"j{:02}\"\nleft_toe = \"j{:02}\"\nright_toe = \"j{:02}\"\n",
        index("Foot_L"),
        index("Foot_R"),
        index("Toes_L"),
        index("Toes_R")
    );
    let feet = joint_map_from_toml(&toml).expect("map parses");
    let mut config = DatasetConfig::default();
    config.cycle.feet = feet.clone();
    let set = load(&dir, &config);
    let c = set.conventions.as_ref().expect("conventions");
    assert!(!c.feet_by_hierarchy);
    // The map's feet, and the head (not in the map) from the hierarchy: the highest joint.
    let expected = motion_io::FootNames {
        head: Some(format!("j{:02}", index("Head"))),
        ..feet.clone()
    };
    assert_eq!(c.feet, expected);
    assert_same_cycles(&base(), &set, 0, "joint map");
    // Unknown keys and a wrong type are errors that say where.
    let err = joint_map_from_toml("left_fot = \"x\"\n")
        .unwrap_err()
        .to_string();
    assert!(err.contains("left_fot"), "{err}");
    assert!(joint_map_from_toml("left_foot = 3\n").is_err());
    // A map naming a joint that does not exist fails every file, each with its reason.
    let mut config = DatasetConfig::default();
    config.cycle.feet.left_foot = Some("no_such_joint".into());
    match load_cycles(std::slice::from_ref(&dir), &config, &|_, _| {}) {
        Err(DatasetError::NoCycles { reasons, .. }) => {
            assert_eq!(reasons.len(), 2);
            for r in reasons {
                assert!(r.error.contains("no_such_joint"), "{}", r.error);
            }
        }
        other => panic!("expected NoCycles, got {other:?}"),
    }
}

/// A temporary folder under the target directory, emptied first.
fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir
}

#[test]
fn a_folder_of_failing_files_lists_every_file_and_exits_non_zero() {
    let dir = scratch("all-failing");
    std::fs::write(dir.join("a_garbage.bvh"), "not a bvh file\n").expect("write");
    let base =
        std::fs::read_to_string(Path::new(FIXTURES).join("walk_p160_t01.bvh")).expect("base take");
    // A take of 20 frames: it reads, but holds no cycle.
    let cut = base.find("Frames:").expect("MOTION");
    let header = &base[..cut];
    let frames: Vec<&str> = base[cut..].lines().skip(2).take(20).collect();
    let short = format!(
        "{header}Frames: 20\nFrame Time: 0.0083333\n{}\n",
        frames.join("\n")
    );
    std::fs::write(dir.join("b_short.bvh"), short).expect("write");
    // No frames at all.
    std::fs::write(
        dir.join("c_empty.bvh"),
        format!("{header}Frames: 0\nFrame Time: 0.0083333\n"),
    )
    .expect("write");
    let err = load_cycles(
        std::slice::from_ref(&dir),
        &DatasetConfig::default(),
        &|_, _| {},
    )
    .unwrap_err();
    let text = err.to_string();
    for f in ["a_garbage.bvh", "b_short.bvh", "c_empty.bvh"] {
        assert!(text.contains(f), "{f} missing from: {text}");
    }
    let out = Command::new(BIN)
        .args(["cycles", "--json"])
        .arg(&dir)
        .output()
        .expect("runs");
    assert!(!out.status.success());
    let line = String::from_utf8_lossy(&out.stdout);
    let v: serde_json::Value = serde_json::from_str(line.trim()).expect("one JSON line");
    let files = v["files"].as_array().expect("files");
    assert_eq!(files.len(), 3, "{v}");
    for f in files {
        assert!(!f["error"].as_str().unwrap_or("").is_empty(), "{f}");
    }
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("b_short.bvh"), "{stderr}");
}

#[test]
fn five_cycles_build_evaluate_and_synthesize_and_eval_runs_from_anywhere() {
    let Some(dir) = variant("mixamo-names") else {
        return;
    };
    let work = scratch("five-cycles");
    let model = work.join("models").join("five.mlod");
    std::fs::create_dir_all(model.parent().expect("parent")).expect("models folder");
    // Built from the fixtures folder with a relative data folder.
    assert!(dir.ends_with("variants/mixamo-names"));
    let out = Command::new(BIN)
        .current_dir(FIXTURES)
        .args(["build", "--samples", "5", "--json", "-o"])
        .arg(&model)
        .arg("variants/mixamo-names")
        .output()
        .expect("runs");
    assert!(
        out.status.success(),
        "build: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("5 samples are too few"), "{stderr}");
    // The recorded folder is relative to the model file.
    let loaded = motion_lod::MotionModel::load(&model).expect("model loads");
    let spec: &DataSpec = loaded.report.data.as_ref().expect("data recorded");
    // Stored relative to the model file, read back joined to the model's folder.
    let models = model.parent().expect("parent");
    assert!(
        spec.dirs[0].starts_with(models),
        "{}",
        spec.dirs[0].display()
    );
    assert!(spec.dirs[0].is_dir(), "{}", spec.dirs[0].display());
    assert_eq!(loaded.report.samples, 5);
    let used = 4 - loaded.report.dropped_controls.len();
    assert!((1..=2).contains(&used), "controls used: {used}");
    // eval from another working directory, by the model alone.
    let elsewhere = scratch("five-cycles-elsewhere");
    let eval = Command::new(BIN)
        .current_dir(&elsewhere)
        .args(["eval", "--json"])
        .arg(&model)
        .output()
        .expect("runs");
    assert!(
        eval.status.success(),
        "eval: {}",
        String::from_utf8_lossy(&eval.stderr)
    );
    let v: serde_json::Value =
        serde_json::from_slice(&eval.stdout).expect("eval prints one JSON line");
    assert_eq!(v["evaluated"], 5);
    // --data overrides the recorded folders (here the same takes under other names).
    let other = variant("iclone-names").expect("variant");
    let eval = Command::new(BIN)
        .current_dir(&elsewhere)
        .args(["eval", "--json"])
        .arg(&model)
        .arg("--data")
        .arg(&other)
        .output()
        .expect("runs");
    assert!(
        eval.status.success(),
        "eval --data: {}",
        String::from_utf8_lossy(&eval.stderr)
    );
    // Synthesis.
    let walk = work.join("walk.bvh");
    let synth = Command::new(BIN)
        .current_dir(&elsewhere)
        .args([
            "synth", "--dx", "0", "--dz", "1.3", "--turn", "0", "--cycles", "2", "-o",
        ])
        .arg(&walk)
        .arg(&model)
        .output()
        .expect("runs");
    assert!(
        synth.status.success(),
        "synth: {}",
        String::from_utf8_lossy(&synth.stderr)
    );
    let m = motion_io::read_bvh(&walk).expect("synthesized walk reads");
    assert!(m.frame_count() > 10);
    assert!(m.frames.iter().all(|v| v.is_finite()));
}

#[test]
fn three_cycles_build_and_two_are_refused_with_a_count_of_cycles() {
    let Some(dir) = variant("cgspeed-names") else {
        return;
    };
    let spec = DataSpec {
        dirs: vec![dir],
        samples: Some(3),
        ..DataSpec::default()
    };
    let loaded = spec
        .load_with_default(motion_io::test_data::fixture_takes(), &|_, _| {})
        .expect("loads");
    let config = motion_lod::BuildConfig::default();
    let model = motion_lod::MotionModel::build(
        &loaded.training,
        &config,
        &motion_lod::progress::NoProgress,
    )
    .expect("3 cycles build");
    assert_eq!(model.report.samples, 3);
    assert_eq!(4 - model.report.dropped_controls.len(), 1);
    assert!(!model.report.warnings().is_empty());
    let two = loaded.training.subset(2, 1);
    let err = motion_lod::MotionModel::build(&two, &config, &motion_lod::progress::NoProgress)
        .unwrap_err()
        .to_string();
    assert!(err.contains("at least 3 cycles"), "{err}");
}

#[test]
fn shared_data_keep_their_conventions() {
    for (name, preset) in [
        ("bandai-namco-2-walk", motion_lod::dataset::Preset::Default),
        ("cmu-daz-walk-s07-s08", motion_lod::dataset::Preset::Cmu),
    ] {
        let Some(dir) = motion_io::test_data::shared_mocap(env!("CARGO_MANIFEST_DIR"), name) else {
            return;
        };
        let config = DatasetConfig {
            cycle: preset.cycle_config(),
            ..DatasetConfig::default()
        };
        let set = load(&dir, &config);
        let c = set.conventions.as_ref().expect("conventions");
        assert_eq!(c.units, Units::Centimetres, "{name}");
        assert_eq!(c.up, SignedAxis::Y, "{name}");
        assert!(!c.feet_by_hierarchy, "{name}");
        // Bandai takes start mid-walk; some CMU takes hold a reference pose in frame 0 (or 0 and 1),
        // a jump of 0.3-0.4 m to the next frame: skipped, and nothing else.
        for t in &set.takes {
            for s in &t.skipped {
                assert!(
                    name.starts_with("cmu")
                        && s.last <= 1
                        && matches!(s.reason, SkipReason::Jump { .. }),
                    "{name}: {} skipped {s}",
                    t.path.display()
                );
            }
        }
        let expected = if name.starts_with("bandai") { 800 } else { 33 };
        assert_eq!(set.cycles.len(), expected, "{name}");
    }
}

#[test]
fn a_crowd_of_a_model_of_straight_walks_fits_its_field_instead_of_refusing() {
    use crowd_sim::{Camera, CrowdConfig};
    use lod_policy::DistancePolicy;
    use motion_lod::crowd::{CrowdRun, run_crowd};
    let loaded = DataSpec::default()
        .load_with_default(motion_io::test_data::fixture_takes(), &|_, _| {})
        .expect("embedded data");
    let straight: Vec<usize> = (0..loaded.training.controls.len())
        .filter(|&k| loaded.training.controls[k][2].abs() < 0.5f64.to_radians())
        .collect();
    assert!(straight.len() >= 3, "straight cycles: {}", straight.len());
    let set = loaded.training.select(&straight);
    let model = motion_lod::MotionModel::build(
        &set,
        &motion_lod::BuildConfig::default(),
        &motion_lod::progress::NoProgress,
    )
    .expect("model of straight walks builds");
    let run = CrowdRun {
        config: CrowdConfig {
            seed: 5,
            ..CrowdConfig::with_density(40, 0.05)
        },
        seconds: 1.0,
        lens: Camera::default(),
        scene: motion_lod::crowd_sim::Scene::Ground,
        render: None,
    };
    let lod = model.lod();
    let source = motion_lod::LodSource::new(&model);
    let policy = DistancePolicy::for_model(lod);
    let outcome = run_crowd(&source, &policy, &run).expect("the crowd runs");
    let asked = run.config.field_size_m;
    assert_eq!(outcome.field_enlarged_from, Some(asked));
    assert!(outcome.field_m > asked, "{} vs {asked}", outcome.field_m);
    assert_eq!(outcome.last.level_histogram.iter().sum::<u32>(), 40);
}
