//! Defects of the public API found by an audit (each test failed before its fix): bad input gets an
//! error, not a panic, an abort or an `Ok` with NaN; ordinary input keeps its results.

use std::sync::OnceLock;

use motion_lod::build::{BuildError, TrainingSet};
use motion_lod::crowd::{CrowdQualityError, crowd_quality, record_walkers};
use motion_lod::crowd_sim::{ClipSource, CrowdConfig, CrowdError, Scene};
use motion_lod::dataset::{DataSpec, DatasetError};
use motion_lod::eval::{EvalConfig, FoldBy, k_fold, leave_one_out};
use motion_lod::lod_policy::{Controls, DistancePolicy};
use motion_lod::progress::NoProgress;
use motion_lod::quality::QualityError;
use motion_lod::style::StyleLabels;
use motion_lod::synth::{Walk, WalkRequest};
use motion_lod::walk_quality::measure_walk;
use motion_lod::{BuildConfig, LodSource, MotionModel};

use crate::common;

/// The embedded data set's training set, loaded once.
fn training() -> &'static TrainingSet {
    static SET: OnceLock<TrainingSet> = OnceLock::new();
    SET.get_or_init(|| {
        DataSpec::default()
            .load_with_default(motion_io::test_data::fixture_takes(), &|_, _| {})
            .expect("embedded data loads")
            .training
    })
}

fn model() -> &'static MotionModel {
    &common::built().0
}

/// The data error's message, or a panic naming what came instead.
fn data_error(r: Result<(), BuildError>) -> String {
    match r {
        Err(BuildError::Data(m)) => m,
        other => panic!("expected a data error, got {other:?}"),
    }
}

fn middle_controls() -> Controls {
    let r = model().control_range();
    Controls::from_array(std::array::from_fn(|k| 0.5 * (r[k].0 + r[k].1)))
}

fn walk() -> Walk {
    model()
        .synthesize_walk(&WalkRequest {
            controls: middle_controls(),
            detail: model().lod().full_detail(),
            cycles: 3,
            fps: 30.0,
            blend: true,
            plant_feet: true,
        })
        .expect("the walk synthesizes")
}

// Defect 1: non-finite tensor values passed validation and panicked in the build.
#[test]
fn validate_names_the_first_non_finite_tensor_value() {
    let mut set = training().clone();
    let [p, t, _] = set.tensor.dims();
    set.tensor.as_mut_slice()[2 * p * t + 3 * p + 6] = f64::NAN;
    let m = data_error(set.validate());
    assert!(
        m.contains("row 6, frame 3, sample 2"),
        "message names where: {m}"
    );
    let mut set = training().clone();
    set.tensor.as_mut_slice()[1] = f64::INFINITY;
    let m = data_error(set.validate());
    assert!(m.contains("row 1, frame 0, sample 0"), "{m}");
    // The build refuses it before any work (it panicked in the row permutation).
    let err = MotionModel::build(&set, &BuildConfig::default(), &NoProgress).unwrap_err();
    assert!(matches!(err, BuildError::Data(_)), "{err}");
    // The embedded set passes.
    training().validate().expect("the embedded set is valid");
}

// Defect 2: style labels not checked against the samples.
#[test]
fn validate_checks_the_style_labels() {
    let s = training().tensor.dims()[2];
    let names = vec!["a".to_string(), "b".to_string()];
    let labelled = |names: Vec<String>, of_sample: Vec<usize>| {
        let mut set = training().clone();
        set.styles = Some(StyleLabels { names, of_sample });
        set
    };
    let short = labelled(names.clone(), (0..s - 1).map(|i| i % 2).collect());
    assert!(data_error(short.validate()).contains("style labels for"));
    let out_of_range = labelled(names.clone(), (0..s).map(|i| 5 * (i % 2)).collect());
    let m = data_error(out_of_range.validate());
    assert!(m.contains("sample 1 has style 5"), "{m}");
    let none = labelled(Vec::new(), vec![0; s]);
    assert!(data_error(none.validate()).contains("without style names"));
    let twice = labelled(vec!["a".into(), "a".into()], vec![0; s]);
    assert!(data_error(twice.validate()).contains("appears twice"));
    labelled(names, (0..s).map(|i| i % 2).collect())
        .validate()
        .expect("good labels pass");
}

// Defect 3: sources not checked against the samples (k_fold panicked on its threads, or left
// samples out of every fold).
#[test]
fn validate_and_k_fold_check_the_sources() {
    let mut long = training().clone();
    long.sources
        .extend((0..20).map(|i| format!("extra_{i}.bvh [0..=9]")));
    assert!(data_error(long.validate()).contains("sources for"));
    let err = k_fold(
        &long,
        &BuildConfig::default(),
        3,
        FoldBy::Sample,
        &EvalConfig::default(),
        &NoProgress,
    )
    .unwrap_err();
    assert!(matches!(err, BuildError::Data(_)), "{err}");
    let mut short = training().clone();
    short.sources.truncate(2);
    assert!(data_error(short.validate()).contains("2 sources for"));
}

// Defect 4: `r * p` overflowed (a panic in debug builds, a wrapped R_P = 1 in release).
#[test]
fn rank_bounds_saturate_and_keep_ordinary_results() {
    let old = |r: usize, p: usize, reference: usize| {
        (((r * p) as f64 / reference as f64).round() as usize).max(1)
    };
    for reference in [1usize, 94, 1000] {
        let config = BuildConfig {
            dof_rank_reference: Some(reference),
            ..BuildConfig::default()
        };
        let step = if reference == 94 { 1 } else { 7 };
        for p in (0..=1000).step_by(step) {
            for r in (0..=10_000).step_by(step) {
                let config = BuildConfig {
                    max_ranks: [r, 40, 60],
                    min_ranks: [r / 2, 7, 9],
                    ..config.clone()
                };
                let (max, min) = config.rank_bounds(p);
                assert_eq!(max[0], old(r, p, reference), "r {r} p {p} ref {reference}");
                assert_eq!(min[0], old(r / 2, p, reference));
            }
        }
    }
    let huge = BuildConfig {
        max_ranks: [usize::MAX, 40, 60],
        ..BuildConfig::default()
    };
    assert!(huge.rank_bounds(61).0[0] > 1 << 60);
    assert_eq!(huge.rank_bounds(usize::MAX).0[0], usize::MAX);
    // This product wrapped to 45 (R_P = 1 after scaling): it saturates instead.
    let wrapping = BuildConfig {
        max_ranks: [302_405_640_552_615_601, 40, 60],
        ..BuildConfig::default()
    };
    assert!(wrapping.rank_bounds(61).0[0] > 1 << 50);
}

// Defect 5: the seams of every implied cycle were allocated before the durations were checked.
#[test]
fn measure_walk_checks_its_durations_first() {
    let w = walk();
    for (cycle, frame, what) in [
        (1e-12, w.frame_time, "cycle duration"),
        (0.0, w.frame_time, "cycle duration"),
        (f64::NAN, w.frame_time, "cycle duration"),
        (w.cycle_seconds, 1e300, "frame time"),
        (w.cycle_seconds, 0.0, "frame time"),
        (w.cycle_seconds, f64::INFINITY, "frame time"),
    ] {
        let bad = Walk {
            cycle_seconds: cycle,
            frame_time: frame,
            ..w.clone()
        };
        let got = measure_walk(model(), &bad);
        if frame == 1e300 || cycle == 1e-12 {
            // Finite and positive (frames of 1e300 s, cycles of 1e-12 s): measured with at most a
            // seam per frame, or refused, but never a capacity overflow or a 26 TB allocation.
            continue;
        }
        match got {
            Err(QualityError::Bad { what: got, .. }) => assert_eq!(got, what),
            other => panic!("cycle {cycle} frame {frame}: {other:?}"),
        }
    }
    // A cycle shorter than a frame: at most a seam per frame, measured or refused, quickly.
    let tiny = Walk {
        cycle_seconds: 1e-6,
        ..w.clone()
    };
    let _ = measure_walk(model(), &tiny);
    // The ordinary walk measures.
    let q = measure_walk(model(), &w).expect("the walk measures");
    assert!(q.pop_cm.is_finite());
}

// Defect 8: finite poses too large to measure gave Ok with infinite or NaN figures.
#[test]
fn measure_walk_refuses_non_finite_figures() {
    let mut w = walk();
    w.poses.iter_mut().for_each(|v| *v *= 1e200);
    match measure_walk(model(), &w) {
        Err(QualityError::NonFiniteFigure { figure, value }) => {
            assert!(!value.is_finite(), "{figure} = {value}");
        }
        other => panic!("expected a non-finite figure, got {other:?}"),
    }
}

// Defect 6: the tracks' buffers were reserved unchecked (abort or capacity-overflow panic).
#[test]
fn record_walkers_refuses_tracks_past_memory() {
    let policy = DistancePolicy::for_model(model().lod());
    let config = CrowdConfig {
        walkers: 5,
        ..CrowdConfig::default()
    };
    for frames in [usize::MAX / 4, 1 << 40] {
        match record_walkers(model(), config, Scene::Overview, &policy, frames, &[0]) {
            Err(CrowdError::OutOfMemory { what, walkers }) => {
                assert_eq!((what, walkers), ("recorded tracks", 1));
            }
            other => panic!("{frames} frames: {:?}", other.map(|t| t.len())),
        }
    }
    let tracks = record_walkers(model(), config, Scene::Overview, &policy, 3, &[0, 99])
        .expect("three frames record");
    assert_eq!(tracks.len(), 1);
    assert_eq!(tracks[0].levels.len(), 3);
}

// Defect 7: huge finite seconds turned into the same abort.
#[test]
fn crowd_quality_refuses_too_many_frames() {
    let policy = DistancePolicy::for_model(model().lod());
    let config = CrowdConfig {
        walkers: 5,
        ..CrowdConfig::default()
    };
    match crowd_quality(model(), config, Scene::Overview, &policy, 1e9) {
        Err(CrowdQualityError::TooLong { seconds, .. }) => assert_eq!(seconds, 1e9),
        other => panic!("{:?}", other.map(|t| t.len())),
    }
}

// Defect 9: a tensor whose rows are not the layout's panicked in `Analysis::prepare`.
#[test]
fn prepare_checks_the_tensor_rows() {
    let analysis = &common::built().1;
    let set = training();
    let bad = motion_lod::tensor_ops::Tensor3::from_vec([5, 4, 1], vec![0.0; 20]).unwrap();
    let err = analysis.prepare(&set.layout, &bad).unwrap_err();
    assert!(matches!(err, BuildError::Data(_)), "{err}");
    let good = analysis
        .prepare(&set.layout, &set.tensor)
        .expect("the training tensor prepares");
    assert_eq!(good.dims(), analysis.tensor.dims());
}

// Defect 10: short buffers panicked in the clip source (the trait's clip fault is 0 rows).
#[test]
fn lod_source_reports_short_buffers_as_clip_faults() {
    let source = LodSource::new(model());
    let mut clip = source.new_clip();
    source
        .build_clip(&middle_controls(), model().lod().full_detail(), &mut clip)
        .unwrap();
    let mut short = vec![0.0f32; 3];
    assert_eq!(source.pose(&clip, 0.3, &mut short), 0);
    let mut out = vec![0.0f32; model().lod().p()];
    let rows = source.pose(&clip, 0.3, &mut out);
    assert!(rows > 0);
    let mut none: Vec<motion_lod::glam::Vec3> = Vec::new();
    assert_eq!(source.joints(&clip, &[], &mut none), 0);
    assert_eq!(source.joints(&clip, &out[..rows], &mut none), 0);
    let mut one = vec![motion_lod::glam::Vec3::ZERO; 1];
    assert_eq!(source.joints(&clip, &out[..rows], &mut one), 1);
}

// Minor: `max_samples: Some(0)` evaluated one sample; `samples: Some(0)` loaded no samples.
#[test]
fn zero_sample_counts_are_refused() {
    let analysis = &common::built().1;
    let config = EvalConfig {
        max_samples: Some(0),
        ..EvalConfig::default()
    };
    let err = leave_one_out(analysis, 0, &[], &config, &NoProgress).unwrap_err();
    assert!(err.to_string().contains("max_samples"), "{err}");
    let spec = DataSpec {
        samples: Some(0),
        ..DataSpec::default()
    };
    let err = spec
        .load_with_default(motion_io::test_data::fixture_takes(), &|_, _| {})
        .unwrap_err();
    assert!(matches!(err, DatasetError::NoSamplesAsked), "{err}");
    assert!(err.to_string().contains("samples"));
}
