//! The command line as a newcomer meets it: the help's promises hold, and values the data cannot
//! honour are an error or a stated adjustment, never silent.

use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_motion-lod");

fn run(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(BIN)
        .args(args)
        .output()
        .expect("the binary runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn cycles_without_a_folder_reads_the_embedded_data_as_its_help_says() {
    let (_, help, _) = run(&["cycles", "--help"]);
    assert!(
        help.contains("without any, the embedded default data set"),
        "{help}"
    );
    let (ok, stdout, stderr) = run(&["cycles", "--json"]);
    assert!(ok, "{stderr}");
    let line: serde_json::Value = serde_json::from_str(stdout.trim()).expect("one JSON line");
    assert_eq!(line["cycles"].as_u64(), Some(60), "{line}");
}

#[test]
fn more_samples_than_cycles_is_an_error_and_writes_nothing() {
    let dir = std::env::temp_dir().join(format!("motion-lod-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("too-many.mlod");
    let (ok, _, stderr) = run(&["build", "--samples", "5000", "-o", out.to_str().unwrap()]);
    assert!(!ok, "5000 samples of 60 cycles must fail");
    assert!(
        stderr.contains("5000 samples asked for, but the data has 60 usable cycles"),
        "{stderr}"
    );
    assert!(!out.exists(), "nothing is written");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn fewer_accuracy_levels_than_key_levels_is_a_stated_adjustment() {
    let dir = std::env::temp_dir().join(format!("motion-lod-cli-levels-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("small.mlod");
    let (ok, _, stderr) = run(&[
        "build",
        "--samples",
        "12",
        "--levels",
        "3",
        "--accuracy-levels",
        "2",
        "--json",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    assert!(
        stderr.contains(
            "note: --accuracy-levels 2: the model has 3 accuracy levels (every one of the 3 key levels is an accuracy level)"
        ),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn every_column_header_of_info_eval_and_quality_is_explained() {
    let (_, help, _) = run(&["--help"]);
    assert!(help.contains("motion-lod explain TERM"), "{help}");
    // The words the reports print as headers or units of their numbers.
    for term in [
        "key level",
        "acc.level",
        "accuracy level",
        "ranks",
        "joint error",
        "shell error",
        "foot slide",
        "1 px from",
        "rel.error",
        "MSE",
        "sweeps",
        "pop",
        "seam",
        "skate",
        "contact",
        "floating",
        "floor",
        "float",
        "facing",
        "cycle/data",
        "walker",
        "frames",
        "levels",
        "seams",
        "--joints",
        "leave-one-out",
        "stature",
        "body scale",
        "variogram",
        "naive-kriging",
        "rbf-smoothed",
        "hybrid model",
        "row weights",
        "turn",
    ] {
        let (ok, stdout, stderr) = run(&["explain", term]);
        assert!(ok, "`explain {term}` fails: {stderr}");
        assert!(
            stdout.len() > 60,
            "`explain {term}` says too little: {stdout}"
        );
    }
    let (ok, _, stderr) = run(&["explain", "frobnication"]);
    assert!(!ok);
    assert!(stderr.contains("no entry for `frobnication`"), "{stderr}");
    let (ok, list, _) = run(&["explain"]);
    assert!(
        ok && list.contains("accuracy level") && list.contains("shell error"),
        "{list}"
    );
}

#[test]
fn the_crowd_says_which_scene_it_timed() {
    let (ok, stdout, stderr) = run(&[
        "crowd",
        "--walkers",
        "50",
        "--seconds",
        "0.5",
        "--camera",
        "overview",
    ]);
    assert!(ok, "{stderr}");
    assert!(
        stdout.contains("scene: camera circling above the field, 0.05 walkers per square metre, seed 1, distance policy"),
        "{stdout}"
    );
    assert!(
        stdout.contains("`cargo xtask tables` (section 4) times another scene"),
        "{stdout}"
    );
}

#[test]
fn eval_names_both_of_its_inputs_and_refuses_a_take_with_a_hint() {
    let (_, help, _) = run(&["eval", "--help"]);
    assert!(
        help.contains("motion-lod eval [OPTIONS] MODEL.mlod"),
        "{help}"
    );
    let take =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/walk_p160_t01.bvh");
    let (ok, _, stderr) = run(&["eval", take.to_str().unwrap()]);
    assert!(!ok);
    assert!(
        stderr.contains(
            "is a BVH take; eval reads a model file (.mlod) or folders of takes: pass its folder"
        ),
        "{stderr}"
    );
}

/// `quality --crowd`: crowd walkers measured as the crowd plays them, each over a stretch drawn
/// with joints of at least two cycles, with the levels it showed; a bad duration is refused.
#[test]
fn quality_measures_crowd_walkers_as_the_crowd_plays_them() {
    let dir = std::env::temp_dir().join(format!("mlod-cli-crowd-quality-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let model = dir.join("m.mlod");
    let (ok, _, stderr) = run(&["build", "-o", model.to_str().unwrap()]);
    assert!(ok, "{stderr}");
    let m = model.to_str().unwrap();
    let (ok, stdout, stderr) = run(&[
        "quality",
        m,
        "--crowd",
        "--walkers",
        "30",
        "--seconds",
        "4",
        "--camera",
        "ground",
        "--json",
    ]);
    assert!(ok, "{stderr}");
    let doc: serde_json::Value = serde_json::from_str(&stdout).expect("one JSON document");
    let walkers = doc["walkers"].as_array().expect("walkers");
    assert!(!walkers.is_empty(), "{stdout}");
    for w in walkers {
        // 4 s at 30 fps, from the first seam on: at least two cycles of frames were drawn.
        let frames = w["frames"].as_u64().unwrap();
        assert!((40..=120).contains(&frames), "{w}");
        let (lo, hi) = (
            w["levels"][0].as_u64().unwrap(),
            w["levels"][1].as_u64().unwrap(),
        );
        assert!(lo <= hi, "{w}");
        for k in ["pop_cm", "seam_pop_cm", "skate_cm_s", "floor_offset_cm"] {
            assert!(
                w["quality"][k].as_f64().is_some_and(f64::is_finite),
                "{k}: {w}"
            );
        }
    }
    let (ok, table, _) = run(&["quality", m, "--crowd", "--walkers", "30", "--seconds", "4"]);
    assert!(
        ok && table.contains("scene: 30 walkers") && table.contains("levels"),
        "{table}"
    );
    let (ok, _, stderr) = run(&["quality", m, "--crowd", "--seconds", "0"]);
    assert!(!ok && stderr.contains("[0.001, 3600]"), "{stderr}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Issue 36's noise list, each item as it can fail: a default build says nothing about accuracy
/// levels it was not asked for; an unwritable output is refused before the build; a load error
/// names the data, not the alignment settings; `info | head -1` ends quietly; the top-level help
/// describes the command, not the library crate.
#[test]
fn the_output_says_only_what_was_asked_or_must_be_known() {
    let dir = std::env::temp_dir().join(format!("motion-lod-cli-quiet-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let model = dir.join("m.mlod");
    let (ok, _, stderr) = run(&[
        "build",
        "--samples",
        "12",
        "--json",
        "-o",
        model.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    assert!(!stderr.contains("--accuracy-levels"), "{stderr}");

    // A folder that does not exist: refused before the build, naming the path.
    let missing = dir.join("no-such-folder/m.mlod");
    let (ok, _, stderr) = run(&["build", "-o", missing.to_str().unwrap()]);
    assert!(!ok);
    assert!(
        stderr.contains("cannot write") && stderr.contains("no-such-folder"),
        "{stderr}"
    );
    assert!(!stderr.contains("building the model"), "{stderr}");

    let (ok, _, stderr) = run(&["build", "/nonexistent/takes", "-o", model.to_str().unwrap()]);
    assert!(!ok);
    assert!(stderr.contains("loading /nonexistent/takes"), "{stderr}");
    assert!(!stderr.contains("dtw (band"), "{stderr}");

    // An output that cannot be written is refused before the work, naming the flag and the path.
    let nowhere = |name: &str| {
        dir.join("no-such-folder")
            .join(name)
            .to_str()
            .unwrap()
            .to_string()
    };
    let m = model.to_str().unwrap();
    for (args, flag) in [
        (
            vec![
                "crowd",
                m,
                "--walkers",
                "20",
                "--seconds",
                "1",
                "--export",
                &nowhere("c.glb"),
            ],
            "--export",
        ),
        (vec!["cycles", "--tensor", &nowhere("t.npy")], "--tensor"),
        (
            vec!["cycles", "--controls", &nowhere("c.csv")],
            "--controls",
        ),
        (
            vec![
                "synth",
                m,
                "--dx",
                "0",
                "--dz",
                "1",
                "--turn",
                "0",
                "-o",
                &nowhere("w.bvh"),
            ],
            "cannot write",
        ),
    ] {
        let (ok, stdout, stderr) = run(&args);
        assert!(!ok, "{args:?}");
        assert!(
            stderr.contains(flag) && stderr.contains("no-such-folder"),
            "{args:?}: {stderr}"
        );
        assert!(stdout.is_empty(), "{args:?}: ran before refusing: {stdout}");
    }

    // Controls far outside the data's range are clamped, and the hull warning then names the
    // clamped controls it measured, not the values given (it printed dx 1e30 beside "each control
    // is in its range").
    let (ok, _, stderr) = run(&[
        "synth",
        model.to_str().unwrap(),
        "--dx",
        "1e30",
        "--dz",
        "-1e30",
        "--turn",
        "0",
        "-o",
        dir.join("far.bvh").to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    let hull = stderr
        .lines()
        .find(|l| l.contains("outside the data's hull"))
        .unwrap_or_else(|| panic!("a hull warning for the clamped corner: {stderr}"));
    assert!(
        hull.contains("once clamped") && !hull.contains("e30") && !hull.contains("000000000"),
        "{hull}"
    );

    // `info m.mlod | head -1`, as a reader that goes away at once (`true` reads nothing): every
    // write of the report then meets a closed pipe.
    let out = Command::new("bash")
        .arg("-c")
        .arg(format!(
            "set -o pipefail; '{BIN}' info '{}' | true",
            model.display()
        ))
        .output()
        .expect("bash runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(!stderr.contains("Broken pipe"), "{stderr}");

    // The conventions line says in words what was done with the root's positions (it printed the
    // variant's name, `Same`, which `explain` did not know).
    let (ok, stdout, stderr) = run(&["cycles"]);
    assert!(ok, "{stderr}");
    let line = stdout
        .lines()
        .find(|l| l.starts_with("conventions:"))
        .unwrap_or_else(|| panic!("a conventions line: {stdout}"));
    let roots = line
        .split("root positions ")
        .nth(1)
        .expect("root positions");
    assert!(
        !["Same", "Absolute", "Relative"]
            .iter()
            .any(|v| roots.starts_with(v)),
        "{line}"
    );

    // Every number states its range in the help, and a value outside it is refused.
    let (_, help, _) = run(&["demo", "--help"]);
    assert!(
        help.contains("1..=1000000") && help.contains("(0.001 to 3600)"),
        "{help}"
    );
    let (_, help, _) = run(&["quality", "--help"]);
    assert!(help.matches("0..=10000").count() >= 2, "{help}");
    let (ok, _, stderr) = run(&["quality", model.to_str().unwrap(), "--level", "20000"]);
    assert!(!ok && stderr.contains("--level"), "{stderr}");

    let (_, help, _) = run(&["--help"]);
    assert!(
        help.starts_with("Walking characters from motion capture"),
        "{help}"
    );
    assert!(!help.contains("re-exporting the runtime"), "{help}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `crowd --json` reports frame-time percentiles after the first second (issue 35's meter): the
/// median, the 99th percentile and the worst frame, in order, over the frames after the warm-up.
#[test]
fn the_crowd_reports_frame_time_percentiles_after_its_warm_up() {
    let (ok, stdout, stderr) = run(&[
        "crowd",
        "--walkers",
        "300",
        "--seconds",
        "2",
        "--fps",
        "30",
        "--json",
    ]);
    assert!(ok, "{stderr}");
    let line: serde_json::Value = serde_json::from_str(stdout.trim()).expect("one JSON line");
    let t = &line["frame_ms"];
    let (p50, p99, worst) = (
        t["p50"].as_f64().unwrap(),
        t["p99"].as_f64().unwrap(),
        t["worst"].as_f64().unwrap(),
    );
    assert!(0.0 < p50 && p50 <= p99 && p99 <= worst, "{t}");
    assert_eq!(t["after_s"].as_f64(), Some(1.0), "{t}");
    assert_eq!(
        t["frames"].as_u64(),
        Some(line["frames"].as_u64().unwrap() - 30),
        "{line}"
    );
    // The worst frame of the whole run (warm-up included) is at least the worst after it.
    let fps_worst = line["fps"]["worst"].as_f64().unwrap();
    assert!(1e3 / fps_worst >= worst - 1e-9, "{line}");
    let (ok, stdout, _) = run(&["crowd", "--walkers", "300", "--seconds", "2"]);
    assert!(ok);
    assert!(
        stdout.contains("frame times after the first 1 s (30 frames): median"),
        "{stdout}"
    );
    let (ok, text, _) = run(&["explain", "p99"]);
    assert!(ok && text.starts_with("frame times:"), "{text}");
}

/// Issue 33 on the command line: styles from the file names (the embedded walker's performers),
/// reported by `cycles` and `info`, a walk per style or blend, a track, a crowd of one style; and
/// on a model without styles, a style is refused and a control the model ignores is said with
/// the figures that dropped it.
#[test]
fn styles_tracks_and_ignored_controls_on_the_command_line() {
    let dir = std::env::temp_dir().join(format!("motion-lod-cli-style-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let pattern = r"walk_(p\d+)_";

    let (ok, stdout, stderr) = run(&["cycles", "--style-from-name", pattern, "--json"]);
    assert!(ok, "{stderr}");
    let v: serde_json::Value = serde_json::from_str(stdout.trim()).unwrap();
    let styles = v["styles"].as_array().expect("styles in cycles --json");
    assert_eq!(styles.len(), 3);
    assert_eq!(styles[0]["name"], "p160");
    assert_eq!(styles[0]["cycles"], 20);
    assert_eq!(styles[0]["takes"], 5);
    let (ok, stdout, _) = run(&["cycles", "--json"]);
    assert!(
        ok && !stdout.contains("\"styles\""),
        "no styles without labels"
    );

    let styled = path("styled.mlod");
    let (ok, _, stderr) = run(&["build", "--style-from-name", pattern, "-o", &styled]);
    assert!(ok, "{stderr}");
    let (ok, stdout, _) = run(&["info", &styled]);
    assert!(ok);
    assert!(
        stdout.contains("styles (3, from file names matching")
            && stdout.contains("p175 20 cycles/5 takes")
            && stdout.contains("style weight"),
        "{stdout}"
    );
    let (ok, stdout, _) = run(&["info", &styled, "--json"]);
    assert!(ok && stdout.contains("\"style_weight\""), "{stdout}");

    let walk = |style: &str, out: &str| {
        run(&[
            "synth",
            &styled,
            "--dx",
            "0",
            "--dz",
            "1.3",
            "--turn",
            "0",
            "--style",
            style,
            "-o",
            &path(out),
        ])
    };
    for (style, out) in [
        ("p160", "a.bvh"),
        ("p190", "b.bvh"),
        ("p160=0.5,p190=0.5", "ab.bvh"),
    ] {
        let (ok, _, stderr) = walk(style, out);
        assert!(ok, "{style}: {stderr}");
    }
    let (a, b) = (
        std::fs::read(path("a.bvh")).unwrap(),
        std::fs::read(path("b.bvh")).unwrap(),
    );
    assert_ne!(a, b, "two styles, two walks");
    let (ok, _, stderr) = walk("p999", "x.bvh");
    assert!(
        !ok && stderr.contains("its styles are p160, p175, p190"),
        "{stderr}"
    );
    assert!(
        !dir.join("x.bvh").exists(),
        "nothing written on a refused style"
    );

    std::fs::write(
        dir.join("track.csv"),
        "time,dx,dz,turn,style\n0,0,1.1,0,p160\n2.5,0,1.5,0,p190\n",
    )
    .unwrap();
    let (ok, stdout, stderr) = run(&[
        "synth",
        &styled,
        "--track",
        &path("track.csv"),
        "-o",
        &path("track.glb"),
    ]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("cycles of"), "{stdout}");
    std::fs::write(
        dir.join("bad.csv"),
        "time,dx,dz,turn\n0,0,1.1,0\n0,0,1.2,0\n",
    )
    .unwrap();
    let (ok, _, stderr) = run(&[
        "synth",
        &styled,
        "--track",
        &path("bad.csv"),
        "-o",
        &path("bad.bvh"),
    ]);
    assert!(
        !ok && stderr.contains("line 3") && stderr.contains("must increase"),
        "{stderr}"
    );

    let (ok, stdout, stderr) = run(&[
        "crowd",
        &styled,
        "--walkers",
        "60",
        "--seconds",
        "1",
        "--style",
        "p175",
        "--json",
    ]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("\"walkers\":60"), "{stdout}");

    // A model without styles: no style is accepted.
    let plain = path("plain.mlod");
    let (ok, _, stderr) = run(&["build", "-o", &plain]);
    assert!(ok, "{stderr}");
    let (ok, _, stderr) = run(&[
        "synth",
        &plain,
        "--dx",
        "0",
        "--dz",
        "1.3",
        "--turn",
        "0",
        "--style",
        "p160",
        "-o",
        &path("p.bvh"),
    ]);
    assert!(
        !ok && stderr.contains("the model has no styles"),
        "{stderr}"
    );
    // A control the model ignores, given a value, is said with why: five cycles cannot hold a
    // trend over every control, so the build leaves the least varying out.
    let few = path("few.mlod");
    let (ok, _, stderr) = run(&["build", "--samples", "5", "-o", &few]);
    assert!(ok, "{stderr}");
    let (ok, _, stderr) = run(&[
        "synth",
        &few,
        "--dx",
        "0.1",
        "--dz",
        "1.3",
        "--turn",
        "20",
        "--height",
        "1.7",
        "-o",
        &path("t.bvh"),
    ]);
    assert!(ok, "{stderr}");
    assert!(
        stderr.contains("has no effect: the model ignores")
            && stderr.contains("too few samples (5)")
            && stderr.contains("the other controls imply"),
        "{stderr}"
    );
    // A track's height column is said as `--height` is (it was ignored unsaid).
    std::fs::write(
        dir.join("height.csv"),
        "time,dx,dz,turn,height\n0,0,1.3,0,1.9\n2,0,1.3,0,1.9\n",
    )
    .unwrap();
    let (ok, _, stderr) = run(&[
        "synth",
        &few,
        "--track",
        &path("height.csv"),
        "-o",
        &path("h.bvh"),
    ]);
    assert!(
        ok && stderr.contains("height 1.900 has no effect"),
        "{stderr}"
    );
    // The embedded model: the cross-validation by take keeps turn, but the quality grid's walks
    // with it face against their travel beyond the data's narrow range at the hull's edges (0.8
    // degrees beyond -2.2..3.3), so the quality guard drops it again: a turn given is said with
    // the figures.
    let (ok, _, stderr) = run(&[
        "synth",
        &plain,
        "--dx",
        "0",
        "--dz",
        "1.3",
        "--turn",
        "20",
        "-o",
        &path("t20.bvh"),
    ]);
    assert!(ok, "{stderr}");
    assert!(
        stderr.contains("warning: turn 20.000 has no effect")
            && stderr.contains("by the quality guard: kept by 5-fold cross-validation by take")
            && stderr.contains("fail the motion-quality thresholds (facing"),
        "{stderr}"
    );
    let (ok, _, stderr) = run(&[
        "synth",
        &plain,
        "--dx",
        "0",
        "--dz",
        "1.3",
        "--turn",
        "0",
        "-o",
        &path("t0.bvh"),
    ]);
    assert!(ok && !stderr.contains("warning"), "{stderr}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Issue 33: the CMU (cgspeed) conventions are detected from the files: `--preset` defaults to
/// `auto`, which picks `cmu` for the CMU takes (and says why) and `default` for Bandai.
#[test]
fn the_cmu_preset_is_detected_from_the_files() {
    let Some(cmu) =
        motion_io::test_data::shared_mocap(env!("CARGO_MANIFEST_DIR"), "cmu-daz-walk-s07-s08")
    else {
        return;
    };
    let dir = cmu.to_str().unwrap();
    let (ok, stdout, stderr) = run(&["cycles", dir, "--json"]);
    assert!(ok, "{stderr}");
    assert!(
        stderr.contains("note: using --preset cmu") && stderr.contains("lButtock"),
        "{stderr}"
    );
    let auto: serde_json::Value = serde_json::from_str(stdout.trim()).unwrap();
    let (ok, stdout, _) = run(&["cycles", dir, "--preset", "cmu", "--json"]);
    assert!(ok);
    let given: serde_json::Value = serde_json::from_str(stdout.trim()).unwrap();
    assert_eq!(
        auto["cycles"], given["cycles"],
        "auto is the cmu preset here"
    );
    let (ok, stdout, stderr) = run(&["cycles", dir, "--preset", "default", "--json"]);
    assert!(ok && !stderr.contains("note: using"), "{stderr}");
    let default: serde_json::Value = serde_json::from_str(stdout.trim()).unwrap();
    assert_ne!(
        default["cycles"], given["cycles"],
        "the presets differ on these files"
    );
    if let Some(bandai) =
        motion_io::test_data::shared_mocap(env!("CARGO_MANIFEST_DIR"), "bandai-namco-2-walk")
    {
        let (ok, _, stderr) = run(&["cycles", bandai.to_str().unwrap(), "--json"]);
        assert!(ok && !stderr.contains("note: using"), "{stderr}");
    }
}

/// Issue 36: the conventions `cycles --json` prints (`root_positions`: `Same`, `Absolute`,
/// `Relative`) are explained.
#[test]
fn the_root_position_readings_are_explained() {
    for word in ["Same", "Absolute", "Relative", "root_positions"] {
        let (ok, stdout, stderr) = run(&["explain", word]);
        assert!(ok, "{word}: {stderr}");
        assert!(stdout.contains("OFFSET"), "{word}: {stdout}");
    }
}

/// Issue 33, item 6: the control selection decides by 5-fold cross-validation by take. On the
/// embedded data it keeps every control (dropping turn would raise the held-out error); the
/// quality guard then drops turn again, and `build` says why with the figures. With turn in the
/// model (`--keep-controls`, what the cross-validation chose), `synth --turn 20` walks another
/// walk than `--turn 0`.
#[test]
fn the_selection_keeps_turn_by_cross_validation_and_the_guard_says_why_it_drops_it() {
    let dir = std::env::temp_dir().join(format!("motion-lod-cli-select-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let (ok, stdout, stderr) = run(&["build", "-o", &path("m.mlod")]);
    assert!(ok, "{stderr}");
    let out = stdout + &stderr;
    for name in ["dx (m)", "dz (m)", "height (m)"] {
        assert!(
            out.contains(&format!(
                "control {name} used: 5-fold cross-validation by take RMSE"
            )),
            "{name}: {out}"
        );
    }
    let turn = out
        .lines()
        .find(|l| l.starts_with("control turn"))
        .expect("a turn line");
    assert!(
        turn.starts_with("control turn (rad) dropped: kept by 5-fold cross-validation by take")
            && turn.contains("the quality guard"),
        "{turn}"
    );
    let (ok, info, stderr) = run(&["info", &path("m.mlod")]);
    assert!(ok && info.contains(turn), "{info}{stderr}");

    let keep = path("keep.mlod");
    let (ok, _, stderr) = run(&["build", "--keep-controls", "-o", &keep]);
    assert!(ok, "{stderr}");
    let walk = |turn: &str, name: &str| {
        let (ok, _, stderr) = run(&[
            "synth",
            &keep,
            "--dx",
            "0.1",
            "--dz",
            "1.3",
            "--turn",
            turn,
            "-o",
            &path(name),
        ]);
        assert!(ok && !stderr.contains("has no effect"), "{stderr}");
        std::fs::read(path(name)).unwrap()
    };
    assert_ne!(walk("20", "t20.bvh"), walk("0", "t0.bvh"));
    std::fs::remove_dir_all(&dir).ok();
}

/// A set too small for the control selection's folds (one take, four cycles) says in words why a
/// control is kept, never "inf without, t = inf", and counts its one take in the singular.
#[test]
fn a_one_take_model_says_why_it_keeps_its_control() {
    let dir = std::env::temp_dir().join(format!("motion-lod-cli-one-take-{}", std::process::id()));
    let takes = dir.join("takes");
    std::fs::create_dir_all(&takes).unwrap();
    let fixture =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/walk_p160_t01.bvh");
    std::fs::copy(&fixture, takes.join("walk_p160_t01.bvh")).unwrap();
    let model = dir.join("one.mlod");
    let (ok, _, stderr) = run(&[
        "build",
        takes.to_str().unwrap(),
        "-o",
        model.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    let (ok, stdout, stderr) = run(&["info", model.to_str().unwrap()]);
    assert!(ok, "{stderr}");
    let controls: Vec<&str> = stdout
        .lines()
        .filter(|l| l.starts_with("control"))
        .collect();
    assert!(
        controls
            .iter()
            .any(|l| l.contains("used: the first control kept")),
        "{controls:#?}"
    );
    assert!(controls.iter().all(|l| !l.contains("inf")), "{controls:#?}");
    assert!(
        controls.iter().any(|l| l.contains("1 take is fewer")),
        "{controls:#?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A reader that has gone away (`motion-lod explain | head -1`) ends the command quietly: every
/// write to stdout fails with a broken pipe here, from the first. `println!` panicked there
/// (exit 101, "failed printing to stdout"; found 2026-11-28).
#[test]
fn a_closed_pipe_on_stdout_is_not_a_panic() {
    for args in [
        &["explain"][..],
        &["explain", "pop"],
        &["crowd", "--walkers", "20", "--seconds", "0.5"],
        &["crowd", "--walkers", "20", "--seconds", "0.5", "--json"],
    ] {
        let (reader, writer) = std::io::pipe().unwrap();
        drop(reader);
        let out = Command::new(BIN)
            .args(args)
            .stdout(writer)
            .output()
            .expect("the binary runs");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            out.status.success() && !stderr.contains("panicked"),
            "{args:?}: {:?} {stderr}",
            out.status
        );
    }
}

/// Options of another mode are refused, not ignored (found 2026-11-28: `quality --walkers 5`
/// without `--crowd`, `crowd --export-walkers 3` without `--export` ran as if not given), and so
/// are outputs that are folders or the command's own input, before any work.
#[test]
fn options_of_another_mode_and_outputs_that_cannot_be_are_refused() {
    let dir = std::env::temp_dir().join(format!("mlod-cli-modes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let model = dir.join("m.mlod");
    let m = model.to_str().unwrap();
    let (ok, _, stderr) = run(&["build", "-o", m, "--samples", "12", "--levels", "2"]);
    assert!(ok, "{stderr}");
    let folder_glb = dir.join("clip.glb");
    std::fs::create_dir_all(&folder_glb).unwrap();
    let empty = dir.join("no-takes");
    std::fs::create_dir_all(&empty).unwrap();
    // One file not there yet, named two ways.
    let (tensor, same_tensor) = (dir.join("t.npy"), dir.join("no-takes/../t.npy"));
    // The model's takes under another skeleton (the chest's rotation order changed; other names
    // alone are the same skeleton, `skeleton_variants.rs`).
    let other = dir.join("other-skeleton");
    std::fs::create_dir_all(&other).unwrap();
    let fixtures = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures");
    for name in [
        "walk_p160_t01.bvh",
        "walk_p160_t02.bvh",
        "walk_p175_t01.bvh",
    ] {
        let text = std::fs::read_to_string(fixtures.join(name)).unwrap();
        let chest = text.find("JOINT Chest\n").unwrap();
        let at = chest
            + text[chest..]
                .find("CHANNELS 3 Zrotation Xrotation")
                .unwrap();
        let reordered = format!(
            "{}CHANNELS 3 Xrotation Zrotation{}",
            &text[..at],
            &text[at + "CHANNELS 3 Zrotation Xrotation".len()..]
        );
        std::fs::write(other.join(name), reordered).unwrap();
    }
    for (args, says) in [
        (&["quality", m, "--walkers", "5"][..], "--crowd"),
        (&["quality", m, "--camera", "ground"], "--crowd"),
        (&["quality", m, "--crowd", "--level", "0"], "--crowd"),
        (&["crowd", m, "--export-walkers", "3"], "--export"),
        (&["crowd", m, "--render-every", "3"], "--render"),
        (&["crowd", m, "--no-lod", "--policy", "screen"], "--no-lod"),
        (&["build", "-o", dir.to_str().unwrap()], "it is a folder"),
        (
            &[
                "synth", m, "--dx", "0", "--dz", "1.2", "--turn", "0", "-o", m,
            ],
            "is the model",
        ),
        (
            &["crowd", m, "--export", folder_glb.to_str().unwrap()],
            "it is a folder",
        ),
        (
            &["build", "--control-margin", "-1", "-o", "x.mlod"],
            "[0, 1]",
        ),
        (
            &["eval", m, "--holdout", empty.to_str().unwrap()],
            "no .bvh file in",
        ),
        // In the user's numbers, before any data are read (it said "min rank 5 above max rank 1
        // in mode 0", the 7 scaled by the DOF reference).
        (
            &[
                "build",
                "--max-ranks",
                "1,1,1",
                "--min-ranks",
                "7,7,9",
                "-o",
                "x.mlod",
            ],
            "--min-ranks 7,7,9 is above --max-ranks 1,1,1 in mode 0",
        ),
        // The options named, and both cycles by take and frames (it said "sequence 1 against
        // reference 0").
        (
            &["cycles", "--band", "0", "--max-slope", "0"],
            "widen --band or raise --max-slope",
        ),
        (
            &["cycles", "--band", "0", "--max-slope", "0"],
            "against the reference cycle fixtures/walk_",
        ),
        // A model brings its own settings: they were ignored without a word.
        (
            &["eval", m, "--levels", "3", "--frames", "50"],
            "--levels, --frames apply to folders of takes only",
        ),
        // Another skeleton's data evaluated a model refitted on them, printed as the model's.
        (
            &["eval", m, "--data", other.to_str().unwrap()],
            "their skeleton differs (joint 2 (`Chest`) has another parent or channels",
        ),
        (
            &[
                "cycles",
                "--tensor",
                tensor.to_str().unwrap(),
                "--controls",
                same_tensor.to_str().unwrap(),
            ],
            "both name",
        ),
    ] {
        let (ok, _, stderr) = run(args);
        assert!(!ok && stderr.contains(says), "{args:?}: {stderr}");
    }
    // The model is still the model.
    let (ok, _, stderr) = run(&["info", m]);
    assert!(ok, "{stderr}");
    // A file named `.glb` is glTF (it was written as BVH: `Path::extension` reads no extension).
    let dot_glb = dir.join(".glb");
    let (ok, _, stderr) = run(&[
        "synth",
        m,
        "--dx",
        "0",
        "--dz",
        "1.2",
        "--turn",
        "0",
        "-o",
        dot_glb.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    assert!(std::fs::read(&dot_glb).unwrap().starts_with(b"glTF"));
    // The seconds as given (it printed "0.0 s").
    let (ok, stdout, stderr) = run(&["crowd", m, "--walkers", "5", "--seconds", "0.001"]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("5 walkers, 0.001 s at 30 fps"), "{stdout}");
    // Fewer key levels than asked for are said (the ranks leave room for 4: 8,8,10 down to 7,7,9).
    let few = dir.join("few.mlod");
    let (ok, _, stderr) = run(&[
        "build",
        "--samples",
        "12",
        "--max-ranks",
        "8,8,10",
        "--min-ranks",
        "7,7,9",
        "--dof-rank-reference",
        "0",
        "--levels",
        "5",
        "-o",
        few.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    assert!(
        stderr.contains("note: --levels 5: the model has 4 key levels"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
