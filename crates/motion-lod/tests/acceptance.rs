//! Issue 5's acceptance on the real data in `../shared/mocap` (each test prints
//! `skipped: ../shared/mocap not found` and passes when it is absent, and fails when
//! `MOTION_LOD_REQUIRE_DATA` is set, as CI sets it), and the same checks on the
//! embedded data set, which is always present:
//!
//! - the leave-one-out error of the full level is within 10% of naive kriging of the raw samples and
//!   below RBF and nearest neighbour;
//! - the error grows strictly with every key level;
//! - at the paper's settings (186 cycles, T = 100, 10 key levels from (40, 40, 60) to (7, 7, 9), `R_P`
//!   scaled to the data's DOF) the hybrid model keeps at most 1/8 of the raw samples' bytes in f64;
//! - a synthesized walk, written as BVH and measured back from the file, travels the requested
//!   (dx, dz, turn) within 10% of the step length and 5 degrees, for controls inside the data.
//!
//! It also checks the row weighting against the paper's unweighted tensor (`RowWeights::Unit`).

use std::path::{Path, PathBuf};

use glam::DVec3;
use motion_io::expmap::exp_to_quat;
use motion_lod::build::{Analysis, RowWeights};
use motion_lod::dataset::{DataSpec, Preset};
use motion_lod::eval::{EvalConfig, EvalReport, leave_one_out};
use motion_lod::progress::NoProgress;
use motion_lod::storage::Storage;
use motion_lod::synth::WalkRequest;
use motion_lod::{BuildConfig, MotionModel};

/// The data folder `name` under `../shared/mocap`, or `None` (with the skip message) when absent;
/// a test failure instead when `MOTION_LOD_REQUIRE_DATA` is set (CI).
fn mocap(name: &str) -> Option<PathBuf> {
    motion_io::test_data::shared_mocap(env!("CARGO_MANIFEST_DIR"), name)
}

/// Travel of a three-cycle walk's cycles, measured back from its BVH:
///
/// - `(dx, dz)`: the root's ground displacement over the first cycle, whose frame is the walk's world
///   frame (the cycle starts over the origin, travelling along +z);
/// - `turn`: the heading change over the middle cycle, measured as the data's controls are
///   (motion-io's cycles module): the heading at a frame is the direction of the root's ground chord
///   over one cycle centred on it.
///
/// It also checks that the pelvis's yaw is continuous across the two seams.
fn measured_cycle(model: &MotionModel, bvh: &Path, cycle_frames: usize) -> (f64, f64, f64) {
    let motion = motion_io::read_bvh(bvh).unwrap();
    let layout = &model.layout;
    let mut pose = vec![0.0; layout.dof()];
    let mut yaws = Vec::new();
    let track: Vec<(f64, f64)> = (0..motion.frame_count())
        .map(|f| {
            layout.pose_from_frame(&motion, f, &mut pose).unwrap();
            let forward = exp_to_quat(DVec3::from_slice(&pose[3..6])) * DVec3::Z;
            yaws.push(forward.x.atan2(forward.z));
            (pose[0], pose[2])
        })
        .collect();
    // The blended seams are continuous: the pelvis turns no faster across them than inside a cycle.
    let step = |f: usize| motion_io::expmap::wrap_angle(yaws[f] - yaws[f - 1]).abs();
    let inside = (1..cycle_frames).map(step).fold(0.0, f64::max);
    for seam in [cycle_frames, 2 * cycle_frames] {
        let jump = step(seam).max(step(seam + 1));
        assert!(
            jump <= 2.0 * inside + 0.5f64.to_radians(),
            "pelvis yaw jumps {:.2} deg at frame {seam} (at most {:.2} deg per frame inside a cycle)",
            jump.to_degrees(),
            inside.to_degrees()
        );
    }
    let (first, last, half) = (cycle_frames, 2 * cycle_frames, cycle_frames / 2);
    assert!(last + half < track.len(), "walk too short to measure");
    let heading = |f: usize| {
        let (a, b) = (track[f - half], track[f + half]);
        (b.0 - a.0).atan2(b.1 - a.1)
    };
    let turn = motion_io::expmap::wrap_angle(heading(last) - heading(first));
    (
        track[first].0 - track[0].0,
        track[first].1 - track[0].1,
        turn,
    )
}

/// Builds a model from `spec` and checks that walks synthesized at training controls (every
/// `S / 6`-th) and at midpoints between pairs of them travel what was asked, measured from the BVH.
fn assert_walks_travel(what: &str, spec: &DataSpec) {
    let loaded = spec
        .load_with_default(motion_io::test_data::fixture_takes(), &|_, _| {})
        .expect("data loads");
    let model = MotionModel::build(&loaded.training, &BuildConfig::default(), &NoProgress)
        .expect("model builds");
    let c = &loaded.training.controls;
    let s = c.len();
    let stride = (s / 6).max(1);
    let picks: Vec<[f64; 4]> = (0..s).step_by(stride).map(|i| c[i]).collect();
    let mids: Vec<[f64; 4]> = (0..picks.len() / 2)
        .map(|i| {
            let (a, b) = (
                c[(i * stride + stride / 2) % s],
                c[(s - 1 - i * stride) % s],
            );
            std::array::from_fn(|k| 0.5 * (a[k] + b[k]))
        })
        .collect();
    let dir = std::env::temp_dir().join(format!(
        "motion-lod-acceptance-{}-{}",
        what.to_lowercase(),
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    let fps = 120.0;
    for (n, ctl) in picks.iter().chain(&mids).enumerate() {
        let req = WalkRequest {
            controls: lod_policy::Controls::from_f64(*ctl),
            detail: model.lod().full_detail(),
            cycles: 3,
            fps,
            blend: true,
            plant_feet: true,
        };
        let walk = model.synthesize_walk(&req).unwrap();
        assert!(!walk.clamped, "{what} walk {n}: {ctl:?} is inside the data");
        let path = dir.join(format!("walk{n}.bvh"));
        motion_io::write_bvh(&model.walk_motion(&walk).unwrap(), &path).unwrap();
        let frames = (walk.cycle_seconds * fps).round() as usize;
        let (dx, dz, turn) = measured_cycle(&model, &path, frames);
        let step = (ctl[0].powi(2) + ctl[1].powi(2)).sqrt();
        let err = ((dx - ctl[0]).powi(2) + (dz - ctl[1]).powi(2)).sqrt();
        assert!(
            err <= 0.1 * step,
            "{what} walk {n}: travelled ({dx:.3}, {dz:.3}) for ({:.3}, {:.3}): {err:.3} m > 10% of {step:.3} m",
            ctl[0],
            ctl[1]
        );
        let turn_err = (turn - ctl[2]).to_degrees().abs();
        assert!(
            turn_err <= 5.0,
            "{what} walk {n}: turned {:.1} deg for {:.1} deg",
            turn.to_degrees(),
            ctl[2].to_degrees()
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A random 240-cycle subset of the Bandai data (keeps the tests fast; the README quotes all 800).
fn bandai_subset() -> Option<DataSpec> {
    Some(DataSpec {
        dirs: vec![mocap("bandai-namco-2-walk")?],
        samples: Some(240),
        ..DataSpec::default()
    })
}

/// The CMU folder with its contact preset.
fn cmu() -> Option<DataSpec> {
    Some(DataSpec {
        dirs: vec![mocap("cmu-daz-walk-s07-s08")?],
        preset: Preset::Cmu,
        ..DataSpec::default()
    })
}

fn loo(spec: &DataSpec, config: &BuildConfig) -> EvalReport {
    let loaded = spec
        .load_with_default(motion_io::test_data::fixture_takes(), &|_, _| {})
        .expect("data loads");
    let analysis =
        Analysis::run_guarded(&loaded.training, config, &NoProgress).expect("analysis runs");
    leave_one_out(&analysis, 0, &[], &EvalConfig::default(), &NoProgress).expect("evaluation runs")
}

fn error_of(report: &EvalReport, name: &str) -> f64 {
    report
        .methods
        .iter()
        .find(|m| m.name == name)
        .unwrap_or_else(|| panic!("no method {name}"))
        .error_cm
}

/// Leave-one-out errors of the multilinear model, one per key level in level order.
fn key_level_errors(report: &EvalReport) -> Vec<f64> {
    report
        .methods
        .iter()
        .filter(|m| m.name == "multilinear")
        .map(|m| m.error_cm)
        .collect()
}

/// The comparison and monotonicity the issue asks for.
fn assert_acceptance(what: &str, report: &EvalReport) {
    let ml = key_level_errors(report);
    assert!(ml.len() >= 5, "{what}: only {} key levels", ml.len());
    let (naive, rbf, nearest) = (
        error_of(report, "naive-kriging"),
        error_of(report, "rbf"),
        error_of(report, "nearest"),
    );
    assert!(
        ml[0] <= 1.1 * naive,
        "{what}: full level {:.3} cm against naive kriging {naive:.3} cm",
        ml[0]
    );
    assert!(
        ml[0] < rbf && ml[0] < nearest,
        "{what}: full level {:.3} cm against RBF {rbf:.3}, nearest {nearest:.3}",
        ml[0]
    );
    for (k, w) in ml.windows(2).enumerate() {
        assert!(
            w[1] > w[0],
            "{what}: key level {} ({:.3} cm) is not worse than key level {k} ({:.3} cm): {ml:?}",
            k + 1,
            w[1],
            w[0]
        );
    }
}

#[test]
fn embedded_data_meets_the_comparison_and_grows_with_every_level() {
    let report = loo(&DataSpec::default(), &BuildConfig::default());
    assert_acceptance("embedded data", &report);
}

#[test]
fn row_weights_lower_the_error_of_every_reduced_level() {
    let spec = DataSpec::default();
    let weighted = key_level_errors(&loo(&spec, &BuildConfig::default()));
    let unit = key_level_errors(&loo(
        &spec,
        &BuildConfig {
            row_weights: RowWeights::Unit,
            ..BuildConfig::default()
        },
    ));
    // Both searches end at the same smallest ranks: compare the full and the smallest level.
    assert!(
        weighted[0] <= unit[0],
        "full level: weighted {weighted:?}, unit {unit:?}"
    );
    let (w, u) = (weighted.last().unwrap(), unit.last().unwrap());
    assert!(
        *w < 0.5 * u,
        "smallest level: weighted {w:.3} cm, unit {u:.3} cm"
    );
}

#[test]
fn bandai_meets_the_comparison_and_grows_with_every_level() {
    if let Some(spec) = bandai_subset() {
        assert_acceptance("Bandai", &loo(&spec, &BuildConfig::default()));
    }
}

#[test]
fn cmu_meets_the_comparison_and_grows_with_every_level() {
    if let Some(spec) = cmu() {
        // With every control, as the paper builds it. By default the build drops CMU's dx and turn,
        // which vary only by noise (tests/joints_and_controls.rs): held-out cycles then no longer get
        // their own measured drift back, the full level (which reproduces each of the 33 cycles)
        // rises to the first truncation's error, and only the comparison with the other methods holds.
        let all = BuildConfig {
            select_controls: false,
            ..BuildConfig::default()
        };
        assert_acceptance("CMU", &loo(&spec, &all));
        let report = loo(&spec, &BuildConfig::default());
        let (ml, naive) = (
            key_level_errors(&report)[0],
            error_of(&report, "naive-kriging"),
        );
        assert!(
            ml <= 1.1 * naive,
            "CMU: full level {ml:.3} cm, naive {naive:.3} cm"
        );
        assert!(ml < error_of(&report, "rbf") && ml < error_of(&report, "nearest"));
    }
}

#[test]
fn bandai_at_the_papers_settings_keeps_at_most_an_eighth_of_the_samples() {
    let Some(dir) = mocap("bandai-namco-2-walk") else {
        return;
    };
    let spec = DataSpec {
        dirs: vec![dir],
        frames: Some(100),
        samples: Some(186),
        seed: 1,
        ..DataSpec::default()
    };
    let loaded = spec
        .load_with_default(motion_io::test_data::fixture_takes(), &|_, _| {})
        .expect("data loads");
    let config = BuildConfig::default();
    assert_eq!(
        (config.key_levels, config.max_ranks, config.min_ranks),
        (10, [40, 40, 60], [7, 7, 9])
    );
    let model = MotionModel::build(&loaded.training, &config, &NoProgress).expect("model builds");
    assert_eq!(model.lod().t(), 100);
    assert_eq!(model.lod().s(), 186);
    assert_eq!(model.lod().keys().len(), 10);
    let st = Storage::of(&model);
    assert_eq!(st.raw_f64, model.lod().p() * 100 * 186 * 8);
    assert!(
        st.model_f64 * 8 <= st.raw_f64,
        "hybrid model {} bytes in f64 against {} raw: {:.1}%",
        st.model_f64,
        st.raw_f64,
        100.0 * st.model_f64 as f64 / st.raw_f64 as f64
    );
    assert!(st.model_f32 < st.model_f64);
}

#[test]
fn embedded_walks_travel_the_requested_controls() {
    assert_walks_travel("embedded", &DataSpec::default());
}

#[test]
fn bandai_walks_travel_the_requested_controls() {
    if let Some(spec) = bandai_subset() {
        assert_walks_travel("Bandai", &spec);
    }
}

#[test]
fn cmu_walks_travel_the_requested_controls() {
    if let Some(spec) = cmu() {
        assert_walks_travel("CMU", &spec);
    }
}
