//! The PCA baseline as a crowd clip source, on the model built from the embedded data set: equal to the
//! naive source with every component, the projection `U U^T` of the naive pose with fewer, fewer
//! components and more error at lower accuracy levels, root-only clips, thread-count determinism and
//! rejected inputs.

use crowd_sim::{Camera, ClipSource, CrowdConfig};
use glam::Vec3;
use lod_policy::{Controls, Detail, DistancePolicy, Precision};
use motion_lod::build::Analysis;
use motion_lod::metrics::ErrorMeter;
use motion_lod::{MotionModel, NaiveSource, PcaSource, TIME_ROW};

use crate::common;

use common::built;

/// Training controls of a few samples and midpoints between pairs of them.
fn test_controls(analysis: &Analysis) -> Vec<Controls> {
    let c = &analysis.controls;
    let s = c.len();
    let mut out: Vec<[f64; 4]> = [0, s / 3, (2 * s) / 3, s - 1].map(|i| c[i]).to_vec();
    out.push(std::array::from_fn(|k| 0.5 * (c[1][k] + c[s / 2][k])));
    out.push(std::array::from_fn(|k| 0.5 * (c[s / 4][k] + c[s - 2][k])));
    out.into_iter().map(Controls::from_f64).collect()
}

fn all_joints(model: &MotionModel, accuracy: usize) -> Detail {
    Detail {
        accuracy,
        active_joints: model.lod().joints(),
    }
}

/// Fractional aligned frames at which poses are compared (first, inner and last frames).
fn phases(t: usize) -> [f64; 5] {
    let last = (t - 1) as f64;
    [0.0, 1.5, 0.37 * last, 0.81 * last + 0.25, last]
}

/// The pose of `source`'s clip at aligned phase `phase`, through the clip's own time table.
fn pose_at<S: ClipSource>(source: &S, clip: &S::Clip, seconds: f64, p: usize) -> Vec<f32> {
    let mut pose = vec![f32::NAN; p];
    let rows = source.pose(clip, seconds as f32, &mut pose);
    assert_eq!(rows, p, "full detail writes every row");
    pose
}

fn assert_close(a: &[f32], b: &[f32], tol: f32, what: &str) {
    assert_eq!(a.len(), b.len());
    for (r, (&x, &y)) in a.iter().zip(b).enumerate() {
        assert!(
            (x - y).abs() <= tol * (1.0 + y.abs()),
            "{what}: row {r}: {x} vs {y}"
        );
    }
}

#[test]
fn all_components_at_level_0_equal_the_naive_clip() {
    let (model, analysis) = built();
    let p = model.lod().p();
    let pca = PcaSource::new(model, analysis, p).unwrap();
    assert_eq!(pca.rank(), p);
    assert_eq!(pca.level_ranks()[0], p);
    let naive = NaiveSource::new(model, analysis).unwrap();
    let (mut pc, mut nc) = (pca.new_clip(), naive.new_clip());
    for controls in test_controls(analysis) {
        pca.build_clip(&controls, all_joints(model, 0), &mut pc)
            .unwrap();
        naive
            .build_clip(&controls, all_joints(model, 0), &mut nc)
            .unwrap();
        assert_eq!(pc.rank(), p);
        let (dp, dn) = (pca.clip_duration(&pc), naive.clip_duration(&nc));
        assert!((dp - dn).abs() <= 1e-4 * dn, "duration {dp} vs {dn}");
        let (rp, rn) = (pca.clip_root_motion(&pc), naive.clip_root_motion(&nc));
        assert!(
            (rp.dx - rn.dx).abs() < 1e-4 && (rp.dz - rn.dz).abs() < 1e-4,
            "{rp:?} vs {rn:?}"
        );
        assert!((rp.turn - rn.turn).abs() < 1e-4, "{rp:?} vs {rn:?}");
        for phase in phases(model.lod().t()) {
            let a = pose_at(&pca, &pc, pc.times().time_at(phase), p);
            let b = pose_at(&naive, &nc, nc.times().time_at(phase), p);
            assert_close(&a, &b, 2e-4, &format!("{controls:?} at phase {phase}"));
        }
    }
}

#[test]
fn fewer_components_give_the_projection_of_the_naive_pose() {
    let (model, analysis) = built();
    let p = model.lod().p();
    let r = 12.min(p - 1);
    let pca = PcaSource::new(model, analysis, r).unwrap();
    assert_eq!(pca.rank(), r);
    assert_eq!(pca.basis().len(), p * r);
    // The orthonormal U: the runtime basis with its time row scaled back.
    let scale = analysis.time_scale;
    let u = |row: usize, j: usize| {
        let v = f64::from(pca.basis()[row * r + j]);
        if row == TIME_ROW { v * scale } else { v }
    };
    for i in 0..r {
        for j in 0..r {
            let dot: f64 = (0..p).map(|row| u(row, i) * u(row, j)).sum();
            let want = if i == j { 1.0 } else { 0.0 };
            assert!((dot - want).abs() < 1e-5, "U^T U [{i}, {j}] = {dot}");
        }
    }
    let naive = NaiveSource::new(model, analysis).unwrap();
    let (mut pc, mut nc) = (pca.new_clip(), naive.new_clip());
    let mut worst = 0.0f64;
    for controls in test_controls(analysis) {
        pca.build_clip(&controls, all_joints(model, 0), &mut pc)
            .unwrap();
        naive
            .build_clip(&controls, all_joints(model, 0), &mut nc)
            .unwrap();
        assert_eq!(pc.rank(), r);
        for phase in phases(model.lod().t()) {
            let a = pose_at(&pca, &pc, pc.times().time_at(phase), p);
            let b = pose_at(&naive, &nc, nc.times().time_at(phase), p);
            // D^-1 U U^T D b, with D scaling the time row as the analysis does.
            let x: Vec<f64> = (0..p)
                .map(|row| f64::from(b[row]) * if row == TIME_ROW { scale } else { 1.0 })
                .collect();
            let y: Vec<f64> = (0..r)
                .map(|j| (0..p).map(|row| u(row, j) * x[row]).sum())
                .collect();
            let proj: Vec<f32> = (0..p)
                .map(|row| {
                    let v: f64 = (0..r).map(|j| u(row, j) * y[j]).sum();
                    (if row == TIME_ROW { v / scale } else { v }) as f32
                })
                .collect();
            assert_close(&a, &proj, 5e-4, &format!("{controls:?} at phase {phase}"));
            let off: f64 = a
                .iter()
                .zip(&b)
                .map(|(&x, &y)| f64::from(x - y).abs())
                .fold(0.0, f64::max);
            worst = worst.max(off);
        }
    }
    assert!(
        worst > 1e-3,
        "{r} of {p} components should not reproduce the naive pose exactly"
    );
}

#[test]
fn lower_levels_use_fewer_components_and_lose_accuracy() {
    let (model, analysis) = built();
    let lod = model.lod();
    let (p, levels) = (lod.p(), lod.levels().len());
    let pca = PcaSource::new(model, analysis, 40).unwrap();
    let ranks = pca.level_ranks().to_vec();
    assert_eq!(ranks.len(), levels);
    assert_eq!(pca.levels().accuracy_levels, levels);
    assert_eq!(ranks[0], 40.min(p));
    let last_rp = lod.levels().last().unwrap().ranks.p.clamp(1, ranks[0]);
    assert_eq!(*ranks.last().unwrap(), last_rp);
    assert!(ranks.windows(2).all(|w| w[1] <= w[0]), "{ranks:?}");
    assert!(levels < 2 || ranks[0] > last_rp, "{ranks:?}");
    assert_eq!(
        pca.bytes(Precision::F32),
        (p * ranks[0] + lod.s() * lod.t() * ranks[0]) * 4
    );
    assert_eq!(pca.bytes(Precision::F64), 2 * pca.bytes(Precision::F32));

    let naive = NaiveSource::new(model, analysis).unwrap();
    let (mut pc, mut nc) = (pca.new_clip(), naive.new_clip());
    let mut errors = Vec::new();
    for (level, &rank) in ranks.iter().enumerate() {
        let mut meter = ErrorMeter::new(&model.layout);
        for controls in test_controls(analysis) {
            pca.build_clip(&controls, all_joints(model, level), &mut pc)
                .unwrap();
            naive
                .build_clip(&controls, all_joints(model, 0), &mut nc)
                .unwrap();
            assert_eq!(pc.rank(), rank, "level {level}");
            for phase in phases(lod.t()) {
                let a = pose_at(&pca, &pc, pc.times().time_at(phase), p);
                let b = pose_at(&naive, &nc, nc.times().time_at(phase), p);
                let a: Vec<f64> = a.iter().map(|&v| f64::from(v)).collect();
                let b: Vec<f64> = b.iter().map(|&v| f64::from(v)).collect();
                meter.compare(&a, &b);
            }
        }
        errors.push(meter.total().mean_joint_cm);
    }
    let (first, last) = (errors[0], *errors.last().unwrap());
    assert!(first.is_finite() && last.is_finite(), "{errors:?}");
    assert!(
        errors.iter().all(|&e| e >= first - 1e-9),
        "no level beats level 0: {errors:?} for ranks {ranks:?}"
    );
    if levels > 1 {
        assert!(
            last > first,
            "the last level ({} components) loses accuracy: {errors:?}",
            last_rp
        );
    }
}

#[test]
fn root_only_writes_the_root_rows_of_the_last_level() {
    let (model, analysis) = built();
    let lod = model.lod();
    let p = lod.p();
    let pca = PcaSource::new(model, analysis, 40).unwrap();
    let last = pca.level_ranks().len() - 1;
    let controls = test_controls(analysis)[4];
    let (mut root, mut full) = (pca.new_clip(), pca.new_clip());
    let root_only = Detail {
        accuracy: 0,
        active_joints: 0,
    };
    pca.build_clip(&controls, root_only, &mut root).unwrap();
    pca.build_clip(&controls, all_joints(model, last), &mut full)
        .unwrap();
    assert_eq!(root.rows(), lod.always_rows());
    assert_eq!(root.rank(), pca.level_ranks()[last]);
    assert_eq!(
        pca.clip_duration(&root).to_bits(),
        pca.clip_duration(&full).to_bits()
    );
    let joints = lod.joints();
    for phase in phases(lod.t()) {
        let t = root.times().time_at(phase) as f32;
        let mut a = vec![f32::NAN; p];
        assert_eq!(pca.pose(&root, t, &mut a), lod.always_rows());
        assert!(a[lod.always_rows()..].iter().all(|v| v.is_nan()));
        let mut b = vec![f32::NAN; p];
        assert_eq!(pca.pose(&full, t, &mut b), p);
        assert_eq!(&a[..lod.always_rows()], &b[..lod.always_rows()]);
        let mut pos = vec![Vec3::NAN; 1 + joints];
        assert_eq!(pca.joints(&root, &a[..lod.always_rows()], &mut pos), 1);
        assert_eq!(pos[0], Vec3::new(a[0], a[1], a[2]));
        assert!(pos[1..].iter().all(|v| v.is_nan()));
        assert_eq!(pca.joints(&full, &b, &mut pos), 1 + joints);
    }
}

#[test]
fn crowd_poses_are_bit_identical_for_1_and_2_threads() {
    let (model, analysis) = built();
    let lod = model.lod();
    let source = PcaSource::new(model, analysis, 40).unwrap();
    let policy = DistancePolicy::for_model(lod);
    let config = CrowdConfig {
        seed: 11,
        ..CrowdConfig::with_density(200, 0.05)
    };
    let lens = Camera::default();
    let path = crowd_sim::CameraPath::inside_crowd(config.field_size_m);
    let simulate = |threads: usize| -> (Vec<u32>, Vec<u32>) {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut crowd = crowd_sim::Crowd::new(&source, config).unwrap();
            let mut stats = crowd_sim::FrameStats::default();
            for f in 0..45 {
                let cam = path.camera_at(f as f32 / 30.0, &lens);
                crowd
                    .step_into(&source, &policy, &cam, 1.0 / 30.0, &mut stats)
                    .unwrap();
            }
            let bits = (0..crowd.len())
                .flat_map(|i| crowd.joint_positions(i).to_vec())
                .flat_map(|p| p.to_array())
                .map(f32::to_bits)
                .collect();
            (bits, stats.level_histogram.clone())
        })
    };
    let (one, histogram) = simulate(1);
    assert!(!one.is_empty());
    assert_eq!(histogram.iter().sum::<u32>(), 200);
    assert!(
        histogram.iter().filter(|&&n| n > 0).count() > 1,
        "the policy spreads walkers over levels: {histogram:?}"
    );
    assert!(one == simulate(2).0, "2 threads differ from 1");
}

#[test]
fn bad_analysis_is_rejected() {
    let (model, analysis) = built();
    let mut bad = analysis.clone();
    bad.time_scale = f64::NAN;
    let err = PcaSource::new(model, &bad, 40).unwrap_err();
    assert!(err.to_string().contains("time scale"), "{err}");
    let mut bad = analysis.clone();
    bad.tensor.as_mut_slice()[17] = f64::INFINITY;
    assert!(PcaSource::new(model, &bad, 40).is_err());
    let mut other = analysis.clone();
    let [p, t, s] = analysis.tensor.dims();
    other.tensor = tensor_ops::Tensor3::zeros([p, t, s - 1]);
    let err = PcaSource::new(model, &other, 40).unwrap_err();
    assert!(err.to_string().contains("does not match"), "{err}");
    // A rank of 0 is clamped to one component.
    assert_eq!(PcaSource::new(model, analysis, 0).unwrap().rank(), 1);
}
