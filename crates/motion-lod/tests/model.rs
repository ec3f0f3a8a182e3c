//! The model end to end on the embedded data set: build, file round trip, determinism, synthesized walks
//! that travel what was asked and the crowd source. The acceptance on the real data is in
//! `tests/acceptance.rs`.

use std::path::{Path, PathBuf};

use crowd_sim::{Camera, ClipSource, CrowdConfig};
use lod_policy::{Detail, DistancePolicy};
use motion_lod::build::Analysis;
use motion_lod::crowd::{CrowdRun, run_crowd};
use motion_lod::dataset::DataSpec;
use motion_lod::eval::EvalConfig;
use motion_lod::model_file;
use motion_lod::progress::NoProgress;
use motion_lod::synth::WalkRequest;
use motion_lod::{BuildConfig, LodSource, MotionModel, NaiveSource};

use crate::common;

use common::built;

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("motion-lod-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

#[test]
fn model_has_levels_with_growing_error_and_a_compact_size() {
    let (model, analysis) = built();
    let lod = model.lod();
    assert_eq!(lod.s(), analysis.tensor.dims()[2]);
    assert!(lod.levels().len() >= lod.keys().len());
    let errors = lod.level_errors();
    assert_eq!(errors.len(), lod.levels().len());
    assert_eq!(errors[0].mean_joint_cm, 0.0, "level 0 is the reference");
    let last = errors.last().unwrap().mean_joint_cm;
    assert!(last > 1.0, "the smallest level loses detail: {last} cm");
    // Distinct rank triples, each within its key and never growing.
    for w in lod.levels().windows(2) {
        assert_ne!(w[0].ranks, w[1].ranks);
        assert!(
            w[1].ranks.fits_in(&w[0].ranks),
            "{:?} then {:?}",
            w[0],
            w[1]
        );
    }
    let storage = motion_lod::storage::Storage::of(model);
    // f32 halves every stored value; a few counts and sizes are stored at a fixed width.
    assert!(
        (storage.model_f32 as f64) < 0.51 * storage.model_f64 as f64,
        "{storage:?}"
    );
    assert!(storage.model_f64 < storage.raw_f64, "{storage:?}");
}

#[test]
fn model_file_round_trips_and_rejects_damage() {
    let (model, _) = built();
    let path = temp("round.mlod");
    model.save(&path).unwrap();
    let back = MotionModel::load(&path).unwrap();
    assert_eq!(&back, model);
    let bytes = std::fs::read(&path).unwrap();
    let mut bad = bytes.clone();
    let mid = bad.len() / 2;
    bad[mid] ^= 0x40;
    std::fs::write(&path, &bad).unwrap();
    let err = MotionModel::load(&path).unwrap_err();
    assert!(err.to_string().contains("corrupted"), "{err}");
    std::fs::write(&path, &bytes[..bytes.len() - 7]).unwrap();
    let err = MotionModel::load(&path).unwrap_err();
    assert!(err.to_string().contains("truncated"), "{err}");
}

#[test]
fn build_is_deterministic_whatever_the_thread_count() {
    let (model, _) = built();
    let reference = model_file::encode(model, Path::new("m")).unwrap();
    let loaded = DataSpec::default()
        .load_with_default(motion_io::test_data::fixture_takes(), &|_, _| {})
        .unwrap();
    // The file holds no timing: every build of the same data and settings writes the same bytes.
    // The reference was built on the default pool: the other counts of 1, 2 and 8 are compared.
    let default_threads = rayon::current_num_threads();
    for threads in [1, 2, 8].into_iter().filter(|&t| t != default_threads) {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let other = pool.install(|| {
            MotionModel::build(&loaded.training, &BuildConfig::default(), &NoProgress).unwrap()
        });
        let bytes = model_file::encode(&other, Path::new("m")).unwrap();
        assert!(
            bytes == reference,
            "model bytes differ with {threads} threads"
        );
    }
}

#[test]
fn out_of_range_controls_are_clamped_and_reported() {
    let (model, _) = built();
    let range = model.control_range();
    let req = WalkRequest {
        controls: lod_policy::Controls::from_array([0.0, range[1].1 * 3.0, 0.0, range[3].0]),
        detail: model.lod().full_detail(),
        cycles: 1,
        fps: 30.0,
        blend: false,
        plant_feet: true,
    };
    assert!(model.synthesize_walk(&req).unwrap().clamped);
    let bad = WalkRequest {
        controls: lod_policy::Controls::from_array([f32::NAN, 1.0, 0.0, 1.7]),
        ..req
    };
    assert!(model.synthesize_walk(&bad).is_err());
    let zero = WalkRequest { cycles: 0, ..req };
    assert!(model.synthesize_walk(&zero).is_err());
}

/// A walk samples every cycle with at least two frames, and says how many cycles it plays: at
/// 1e-9 fps it was one frame reported as 832,471,138 cycles, at 1e-300 fps as `usize::MAX`.
#[test]
fn a_frame_rate_too_low_for_the_steps_is_refused_and_walks_count_their_cycles() {
    let (model, _) = built();
    let req = WalkRequest {
        controls: lod_policy::Controls::from_array([0.0, 1.2, 0.0, 1.7]),
        detail: model.lod().full_detail(),
        cycles: 4,
        fps: 30.0,
        blend: true,
        plant_feet: true,
    };
    let walk = model.synthesize_walk(&req).unwrap();
    assert_eq!(walk.cycles, 4);
    let duration = walk.cycle_seconds;
    let track = [
        (0.0, req.controls),
        (
            duration * 1.5,
            lod_policy::Controls::from_array([0.0, 1.0, 0.3, 1.7]),
        ),
    ];
    // Rows at 0 s and mid second cycle: the walk ends with the third cycle, the first to start
    // after the last row.
    assert_eq!(model.synthesize_track(&req, &track).unwrap().cycles, 3);
    // Two frames a cycle is the least.
    let least = WalkRequest {
        fps: 2.01 / duration,
        ..req
    };
    assert_eq!(model.synthesize_walk(&least).unwrap().cycles, 4);
    for fps in [1.9 / duration, 0.5, 1e-9, 1e-300] {
        let low = WalkRequest { fps, ..req };
        for e in [
            model.synthesize_walk(&low).unwrap_err(),
            model.synthesize_track(&low, &track).unwrap_err(),
        ] {
            assert!(
                e.to_string().contains("needs at least 2 a cycle"),
                "{fps}: {e}"
            );
        }
    }
}

#[test]
fn crowd_runs_with_the_model_and_the_naive_source_identically_for_any_thread_count() {
    let (model, analysis) = built();
    let run = CrowdRun {
        config: CrowdConfig {
            seed: 3,
            ..CrowdConfig::with_density(300, 0.05)
        },
        seconds: 2.0,
        lens: Camera::default(),
        scene: crowd_sim::Scene::Ground,
        render: None,
    };
    let lod = model.lod();
    let source = LodSource::new(model);
    let policy = DistancePolicy::for_model(lod);
    let a = run_crowd(&source, &policy, &run).unwrap();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let b = pool.install(|| run_crowd(&source, &policy, &run).unwrap());
    assert_eq!(a.last.level_histogram, b.last.level_histogram);
    assert_eq!(a.last.level_histogram.iter().sum::<u32>(), 300);
    let mut clip = source.new_clip();
    let controls = lod_policy::Controls::from_f64(analysis.controls[7]);
    source
        .build_clip(
            &controls,
            lod_policy::Detail::new(0, lod.joints()),
            &mut clip,
        )
        .unwrap();
    // A level the model does not have is refused loudly, and the clip is left as it was.
    let (held_duration, held_motion) =
        (source.clip_duration(&clip), source.clip_root_motion(&clip));
    let refused = source
        .build_clip(&controls, lod_policy::Detail::new(99, 3), &mut clip)
        .unwrap_err();
    assert!(refused.to_string().contains("level"), "{refused}");
    assert_eq!(source.clip_duration(&clip), held_duration);
    assert_eq!(source.clip_root_motion(&clip), held_motion);
    // Root motion of a clip is the root's displacement from its first pose to its last.
    let mut start = vec![0.0f32; lod.p()];
    let mut end = vec![0.0f32; lod.p()];
    source.pose(&clip, 0.0, &mut start);
    source.pose(&clip, source.clip_duration(&clip), &mut end);
    let rm = source.clip_root_motion(&clip);
    let (dx, dz) = (end[0] - start[0], end[2] - start[2]);
    assert!(
        (rm.dx - dx).abs() < 1e-4 && (rm.dz - dz).abs() < 1e-4,
        "root motion ({}, {}) against the poses' ({dx}, {dz})",
        rm.dx,
        rm.dz
    );
    assert!(dz > 0.3, "a walk travels forward: dz = {dz}");
    let naive = NaiveSource::new(model, analysis).unwrap();
    let n = run_crowd(
        &naive,
        &lod_policy::FullDetail::for_model(model.lod()),
        &run,
    )
    .unwrap();
    assert_eq!(n.last.level_histogram[0], 300);
}

#[test]
fn crowd_poses_are_bit_identical_for_1_2_and_8_threads() {
    let (model, _) = built();
    let lod = model.lod();
    let source = LodSource::new(model);
    let policy = DistancePolicy::for_model(lod);
    let config = CrowdConfig {
        seed: 5,
        ..CrowdConfig::with_density(200, 0.05)
    };
    let lens = Camera::default();
    let path = crowd_sim::CameraPath::inside_crowd(config.field_size_m);
    let simulate = |threads: usize| -> Vec<u32> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut crowd = crowd_sim::Crowd::new(&source, config).unwrap();
            for f in 0..45 {
                let cam = path.camera_at(f as f32 / 30.0, &lens);
                crowd.step(&source, &policy, &cam, 1.0 / 30.0).unwrap();
            }
            (0..crowd.len())
                .flat_map(|i| crowd.joint_positions(i).to_vec())
                .flat_map(|p| p.to_array())
                .map(f32::to_bits)
                .collect()
        })
    };
    let one = simulate(1);
    assert!(!one.is_empty());
    assert!(one == simulate(2), "2 threads differ from 1");
    assert!(one == simulate(8), "8 threads differ from 1");
}

#[test]
fn held_out_takes_are_predicted_from_the_training_takes() {
    use motion_lod::dataset::{DatasetConfig, align_cycles_to, load_cycles_like};
    let fixtures = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures"));
    let (train, hold) = (temp("train"), temp("hold"));
    for dir in [&train, &hold] {
        std::fs::create_dir_all(dir).unwrap();
    }
    for entry in std::fs::read_dir(fixtures).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if name.ends_with(".bvh") {
            let to = if name.ends_with("_t05.bvh") {
                &hold
            } else {
                &train
            };
            std::fs::copy(&path, to.join(&name)).unwrap();
        }
    }
    let spec = DataSpec {
        dirs: vec![train],
        ..DataSpec::default()
    };
    let loaded = spec
        .load_with_default(motion_io::test_data::fixture_takes(), &|_, _| {})
        .unwrap();
    let analysis = Analysis::run(&loaded.training, &BuildConfig::default(), &NoProgress).unwrap();
    let held = load_cycles_like(
        &[hold],
        &DatasetConfig::default(),
        &loaded.cycles,
        &|_, _| {},
    )
    .unwrap();
    assert_eq!(held.files, 3);
    let reference = &loaded.cycles.cycles[loaded.aligned.reference];
    let t = loaded.aligned.tensor.dims()[1];
    let aligned = align_cycles_to(&held, t, spec.align.method(), reference).unwrap();
    assert_eq!(aligned.tensor.dims()[1], t);
    let targets = analysis
        .prepare(&loaded.aligned.layout, &aligned.tensor)
        .unwrap();
    let controls: Vec<[f64; 4]> = aligned.controls.iter().map(|c| c.to_array()).collect();
    let report = motion_lod::eval::held_out(
        &analysis,
        &targets,
        &controls,
        None,
        0,
        &[],
        &EvalConfig::default(),
        &NoProgress,
    )
    .unwrap();
    assert_eq!(report.evaluated, held.cycles.len());
    let get = |name: &str| {
        report
            .methods
            .iter()
            .find(|m| m.name == name)
            .unwrap()
            .error_cm
    };
    let full = report.methods[0].error_cm;
    assert!(
        report
            .methods
            .iter()
            .all(|m| m.error_cm.is_finite() && m.error_cm > 0.0)
    );
    assert!(full <= 1.1 * get("naive-kriging"), "{:?}", report.methods);
    // Held-out walks are new combinations of speed and turn: interpolation beats the nearest take.
    assert!(full < get("nearest"), "{:?}", report.methods);
}

#[test]
fn k_fold_refits_per_fold_and_holds_out_whole_takes() {
    use motion_lod::eval::{FoldBy, fold_of_samples, k_fold};
    let loaded = DataSpec::default()
        .load_with_default(motion_io::test_data::fixture_takes(), &|_, _| {})
        .unwrap();
    let set = &loaded.training;
    let s = set.tensor.dims()[2];
    let fold = fold_of_samples(&set.sources, 3, FoldBy::Take).unwrap();
    // A take's cycles share one fold.
    for (i, a) in set.sources.iter().enumerate() {
        for (j, b) in set.sources.iter().enumerate() {
            if motion_lod::dataset::take_of(a) == motion_lod::dataset::take_of(b) {
                assert_eq!(fold[i], fold[j], "{a} and {b}");
            }
        }
    }
    assert!(fold_of_samples(&set.sources, 1000, FoldBy::Take).is_err());
    let config = BuildConfig {
        key_levels: 3,
        accuracy_levels: 3,
        ..BuildConfig::default()
    };
    let report = k_fold(
        set,
        &config,
        3,
        FoldBy::Take,
        &EvalConfig::default(),
        &NoProgress,
    )
    .unwrap();
    assert_eq!(report.fold_sizes.iter().sum::<usize>(), s);
    assert_eq!(report.pooled.evaluated, s);
    let error = |name: &str| {
        report
            .pooled
            .methods
            .iter()
            .find(|m| m.name == name)
            .unwrap()
            .error_cm
    };
    let (multi, naive) = (error("multilinear"), error("naive-kriging"));
    assert!(multi.is_finite() && multi > 0.0 && naive > 0.0);
    // Refitted on two thirds of the takes, the full level stays close to naive kriging.
    assert!(
        multi < 1.5 * naive,
        "multilinear {multi} cm, naive {naive} cm"
    );
}

/// The AVX2 build of the kernel and pose loops (chosen at run time where the CPU has it) gives the
/// same bits as the baseline build, on the embedded model at every accuracy level, for all joints,
/// a few joints and root only (covering the blocked K, G and pose paths and the short ones).
#[test]
fn avx2_and_baseline_builds_of_the_kernels_give_the_same_bits() {
    if !std::arch::is_x86_feature_detected!("avx2") {
        eprintln!(
            "note: this CPU has no AVX2: both builds are the baseline and are compared as such"
        );
    }
    let (model, analysis) = built();
    let lod = model.lod();
    let mut scratch = lod_policy::KernelScratch::new(lod);
    let (mut fast, mut base) = (
        lod_policy::ClipKernel::compact(lod),
        lod_policy::ClipKernel::compact(lod),
    );
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let levels = lod.levels().len();
    let mut compared = 0;
    for (i, c) in analysis.controls.iter().step_by(7).enumerate() {
        let c = lod_policy::Controls::from_f64(*c);
        for level in 0..levels {
            for joints in [lod.joints(), 3, 0] {
                let detail = if joints == 0 {
                    lod.root_only()
                } else {
                    Detail::new(level, joints)
                };
                lod.build_kernel(&c, detail, &mut scratch, &mut fast)
                    .unwrap();
                lod.build_kernel_baseline(&c.to_array(), detail, &mut scratch, &mut base)
                    .unwrap();
                let what = format!("controls {i}, level {level}, {joints} joints");
                assert_eq!(bits(fast.g()), bits(base.g()), "G, {what}");
                let times = |k: &lod_policy::ClipKernel| {
                    k.time_table()
                        .times()
                        .iter()
                        .map(|t| t.to_bits())
                        .collect::<Vec<_>>()
                };
                assert_eq!(times(&fast), times(&base), "time table, {what}");
                let (a, b) = (fast.root_motion(), base.root_motion());
                assert_eq!(
                    [a.dx, a.dz, a.turn].map(f32::to_bits),
                    [b.dx, b.dz, b.turn].map(f32::to_bits),
                    "root motion, {what}"
                );
                let rows = fast.rows();
                let (mut pa, mut pb) = (vec![0.0f32; rows], vec![0.0f32; rows]);
                for phase in [0.0, 0.37, 5.5, (lod.t() - 1) as f32] {
                    lod.pose_rows(&fast, phase, &mut pa).unwrap();
                    lod.pose_rows_baseline(&base, phase, &mut pb).unwrap();
                    assert_eq!(bits(&pa), bits(&pb), "pose at {phase}, {what}");
                    // The root pose alone (its own function, eight-wide time weights up to
                    // r_T = 8), in both builds, against the leading rows of the whole pose.
                    let (mut ra, mut rb) = ([0.0f32; 7], [0.0f32; 7]);
                    lod.pose_rows(&fast, phase, &mut ra).unwrap();
                    lod.pose_rows_baseline(&base, phase, &mut rb).unwrap();
                    assert_eq!(bits(&ra), bits(&pa[..7]), "root pose at {phase}, {what}");
                    assert_eq!(
                        bits(&rb),
                        bits(&pa[..7]),
                        "baseline root at {phase}, {what}"
                    );
                }
                compared += 1;
            }
        }
    }
    assert!(compared >= 3 * levels, "{compared} kernels compared");
}

/// A rendered crowd is watched from its first frame, so it starts primed (every walker's clip at
/// the policy's detail, mid-stride): after one frame the walkers in view have joints, where a timed
/// run (not rendered) still holds most of them root only while it spreads its first clip builds.
#[test]
fn a_rendered_crowd_starts_with_every_walker_at_its_detail() {
    let (model, _) = built();
    let source = LodSource::new(model);
    let policy = DistancePolicy::for_model(model.lod());
    let dir = std::env::temp_dir().join(format!("mlod-render-{}", std::process::id()));
    let run = |render: bool| {
        let run = CrowdRun {
            config: CrowdConfig::with_density(200, 0.05),
            seconds: 1.0 / 30.0,
            lens: Camera::default(),
            scene: crowd_sim::Scene::Overview,
            render: render.then(|| (dir.clone(), 1)),
        };
        run_crowd(&source, &policy, &run).unwrap()
    };
    let root_only = |o: &motion_lod::crowd::CrowdOutcome| *o.last.level_histogram.last().unwrap();
    let (rendered, timed) = (run(true), run(false));
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(rendered.rendered, 1);
    assert!(
        root_only(&rendered) + 20 < root_only(&timed),
        "root-only walkers after one frame: {} rendered (primed), {} timed",
        root_only(&rendered),
        root_only(&timed)
    );
}
