//! Clip kernels and poses against a direct f64 evaluation of eq. 4/7/8 (full reconstruction of the
//! truncated tensor, trend F = K C^+, residual kriging weights from a dense solve).
// Index loops mirror the formulas' subscripts.
#![allow(clippy::needless_range_loop)]

use crate::common;

use common::*;
use lod_policy::TimeTable;
use lod_policy::{ClipKernel, Detail, KernelError, KernelScratch, LodModel};

fn kernel_pose(model: &LodModel, c: &[f32], detail: Detail, phase: f32) -> (ClipKernel, Vec<f32>) {
    let mut scratch = KernelScratch::new(model);
    let mut kernel = ClipKernel::new(model);
    model
        .build_kernel_values(c, detail, &mut scratch, &mut kernel)
        .unwrap();
    let mut out = vec![f32::NAN; model.p()];
    model.pose(&kernel, phase, &mut out).unwrap();
    (kernel, out)
}

fn queries(truth: &Truth, rng: &mut Rng, n: usize) -> Vec<Vec<f64>> {
    (0..n)
        .map(|_| {
            (0..truth.d)
                .map(|k| rng.uniform(truth.min[k], truth.max[k]))
                .collect()
        })
        .collect()
}

#[test]
fn pose_matches_direct_universal_kriging_at_every_level() {
    for (seed, nugget) in [(1u64, 0.0), (2, 0.05)] {
        let truth = random_truth(seed, nugget);
        let model = build_model(&truth);
        let mut rng = Rng::new(seed + 100);
        for c in queries(&truth, &mut rng, 4) {
            let c32: Vec<f32> = c.iter().map(|&v| v as f32).collect();
            for level in 0..truth.levels.len() {
                for phase in [0.0f32, 3.3, 7.5, (T - 1) as f32] {
                    let want = direct_pose(&truth, level, &c, phase as f64);
                    let (kernel, got) =
                        kernel_pose(&model, &c32, Detail::new(level, model.joints()), phase);
                    assert!(!kernel.clamped());
                    assert_eq!(kernel.rows(), P);
                    let e = rel_err(&got, &want);
                    assert!(
                        e < 1e-4,
                        "seed {seed} level {level} phase {phase}: relative error {e}"
                    );
                }
            }
        }
    }
}

#[test]
fn truncated_level_differs_from_its_key() {
    // Guards against a truncation that silently evaluates the whole key.
    let truth = random_truth(3, 0.0);
    let model = build_model(&truth);
    let c = [0.1f32, 1.2];
    let (_, full) = kernel_pose(&model, &c, Detail::new(0, model.joints()), 4.0);
    let (_, trunc) = kernel_pose(&model, &c, Detail::new(1, model.joints()), 4.0);
    let diff = full
        .iter()
        .zip(&trunc)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f32, f32::max);
    assert!(diff > 1e-3, "levels 0 and 1 give the same pose");
}

#[test]
fn interpolates_samples_exactly_without_nugget() {
    // With gamma(0) = 0 and no nugget, kriging at a sample's control returns that sample:
    // K(c_i) = K_i, so the pose is the Tucker reconstruction of sample i.
    let truth = random_truth(4, 0.0);
    let model = build_model(&truth);
    let s = truth.s;
    for i in [0usize, 5, s - 1] {
        // Raw control whose scaled value is the sample's.
        let c: Vec<f32> = (0..truth.d)
            .map(|k| (truth.controls[i + s * k] / truth.scale[k] + truth.offset[k]) as f32)
            .collect();
        let key = &truth.keys[0];
        let r = key.ranks;
        let j = 6usize;
        let want: Vec<f64> = (0..truth.p)
            .map(|row| {
                let mut v = 0.0;
                for l in 0..r.s {
                    for b in 0..r.t {
                        for a in 0..r.p {
                            v += key.core[a + r.p * (b + r.t * l)]
                                * key.u_p[row + truth.p * a]
                                * key.u_t[j + truth.t * b]
                                * key.u_s[i + s * l];
                        }
                    }
                }
                v
            })
            .collect();
        let (_, got) = kernel_pose(&model, &c, model.full_detail(), j as f32);
        let e = rel_err(&got, &want);
        assert!(e < 1e-4, "sample {i}: relative error {e}");
    }
}

#[test]
fn reduced_joints_evaluate_leading_rows_and_mean_pose_elsewhere() {
    let truth = random_truth(5, 0.02);
    let model = build_model(&truth);
    let c = [0.05f64, 1.1];
    let c32 = [0.05f32, 1.1];
    for joints in 0..=JOINTS {
        let (kernel, got) = kernel_pose(&model, &c32, Detail::new(2, joints), 2.25);
        let rows = 7 + 3 * joints;
        assert_eq!(kernel.rows(), rows);
        let want = direct_pose(&truth, 2, &c, 2.25);
        assert!(rel_err(&got[..rows], &want[..rows]) < 1e-4);
        for row in rows..P {
            assert_eq!(
                got[row], truth.mean_pose[row] as f32,
                "row {row} with {joints} joints"
            );
        }
    }
}

#[test]
fn root_only_uses_smallest_level_and_seven_rows() {
    let truth = random_truth(6, 0.02);
    let model = build_model(&truth);
    let c = [-0.2f64, 0.9];
    let (kernel, got) = kernel_pose(&model, &[-0.2, 0.9], model.root_only(), 5.0);
    assert_eq!(kernel.level(), truth.levels.len() - 1);
    assert_eq!(kernel.rows(), 7);
    let want = direct_pose(&truth, truth.levels.len() - 1, &c, 5.0);
    assert!(rel_err(&got[..7], &want[..7]) < 1e-4);
    assert_eq!(&got[7..], &model.mean_pose()[7..]);
}

#[test]
fn time_table_comes_from_the_increment_row() {
    let truth = random_truth(7, 0.0);
    let model = build_model(&truth);
    let c = [0.3f64, 1.6];
    let (kernel, _) = kernel_pose(&model, &[0.3, 1.6], Detail::new(0, 0), 0.0);
    // Increments straight from the direct evaluation, one per aligned frame.
    let inc: Vec<f64> = (0..T)
        .map(|j| direct_pose(&truth, 0, &c, j as f64)[6])
        .collect();
    let want = TimeTable::from_increments(&inc);
    let got = kernel.time_table().times();
    assert_eq!(got.len(), T);
    for (j, (&g, &w)) in got.iter().zip(want.times()).enumerate() {
        assert!(
            (g - w).abs() < 1e-4 * (1.0 + w.abs()),
            "frame {j}: {g} vs {w}"
        );
    }
    assert!((kernel.duration() - want.duration()).abs() < 1e-4 * (1.0 + want.duration()));
    // phase_at inverts the table.
    for j in 0..T {
        let ph = kernel.phase_at(got[j]);
        assert!((ph - j as f32).abs() < 1e-3, "frame {j}: phase {ph}");
    }
    assert_eq!(kernel.phase_at(-1.0), 0.0);
    assert_eq!(kernel.phase_at(1e9), (T - 1) as f32);
    assert_eq!(kernel.phase_at(f64::NAN), 0.0);
}

#[test]
fn playback_time_increases_strictly() {
    // A random model has increments of either sign; negative ones are raised to MIN_INCREMENT.
    let truth = random_truth(8, 0.0);
    let model = build_model(&truth);
    let (kernel, _) = kernel_pose(&model, &[0.0, 1.0], model.full_detail(), 0.0);
    let times = kernel.time_table().times();
    assert!(
        times.windows(2).all(|w| w[1] > w[0]),
        "playback time must increase strictly"
    );
    assert_eq!(times[0], 0.0);
    assert_eq!(kernel.duration(), times[T - 1]);
}

#[test]
fn out_of_range_controls_are_clamped_and_flagged() {
    let truth = random_truth(9, 0.02);
    let model = build_model(&truth);
    let outside = [10.0f32, -3.0];
    let clamped = [truth.max[0] as f32, truth.min[1] as f32];
    let (k1, p1) = kernel_pose(&model, &outside, model.full_detail(), 3.0);
    let (k2, p2) = kernel_pose(&model, &clamped, model.full_detail(), 3.0);
    assert!(k1.clamped());
    assert!(!k2.clamped());
    assert_eq!(p1, p2);
}

#[test]
fn bad_inputs_are_errors() {
    let truth = random_truth(10, 0.0);
    let model = build_model(&truth);
    let mut scratch = KernelScratch::new(&model);
    let mut kernel = ClipKernel::new(&model);
    assert!(matches!(
        model.build_kernel_values(
            &[f32::NAN, 1.0],
            model.full_detail(),
            &mut scratch,
            &mut kernel
        ),
        Err(KernelError::NonFiniteControl { index: 0, .. })
    ));
    assert!(matches!(
        model.build_kernel_values(
            &[0.0, f32::INFINITY],
            model.full_detail(),
            &mut scratch,
            &mut kernel
        ),
        Err(KernelError::NonFiniteControl { index: 1, .. })
    ));
    assert!(matches!(
        model.build_kernel_values(&[0.0], model.full_detail(), &mut scratch, &mut kernel),
        Err(KernelError::ControlLength {
            expected: 2,
            found: 1
        })
    ));
    assert!(matches!(
        model.build_kernel_values(&[0.0, 1.0], Detail::new(4, 1), &mut scratch, &mut kernel),
        Err(KernelError::Level {
            level: 4,
            levels: 4
        })
    ));
    model
        .build_kernel_values(&[0.0, 1.0], model.full_detail(), &mut scratch, &mut kernel)
        .unwrap();
    let mut short = vec![0.0; P - 1];
    assert!(matches!(
        model.pose(&kernel, 1.0, &mut short),
        Err(KernelError::OutputLength { .. })
    ));
    let mut out = vec![0.0; P];
    assert!(matches!(
        model.pose(&kernel, f32::NAN, &mut out),
        Err(KernelError::NonFinitePhase { .. })
    ));
    // Phases outside [0, T-1] are clamped.
    let mut lo = vec![0.0; P];
    let mut hi = vec![0.0; P];
    model.pose(&kernel, -5.0, &mut lo).unwrap();
    model.pose(&kernel, 0.0, &mut out).unwrap();
    assert_eq!(lo, out);
    model.pose(&kernel, 1e6, &mut hi).unwrap();
    model.pose(&kernel, (T - 1) as f32, &mut out).unwrap();
    assert_eq!(hi, out);
}

#[test]
fn kernel_from_another_model_is_rejected() {
    let model = build_model(&random_truth(11, 0.0));
    let mut parts = model.parts().clone();
    // A model with fewer frames: same shapes otherwise.
    parts.t = T - 1;
    for key in &mut parts.keys {
        let rt = key.ranks.t;
        key.u_t = (0..(T - 1) * rt)
            .map(|i| key.u_t[(i / (T - 1)) * T + i % (T - 1)])
            .collect();
    }
    let other = LodModel::new(parts).unwrap();
    let mut scratch = KernelScratch::new(&model);
    let mut kernel = ClipKernel::new(&other);
    assert!(matches!(
        model.build_kernel_values(&[0.0, 1.0], model.full_detail(), &mut scratch, &mut kernel),
        Err(KernelError::Capacity { what: "kernel", .. })
    ));
}

#[test]
fn rebuilding_a_kernel_is_deterministic_and_independent_of_history() {
    let model = build_model(&random_truth(12, 0.02));
    let mut scratch = KernelScratch::new(&model);
    let mut k1 = ClipKernel::new(&model);
    model
        .build_kernel_values(
            &[0.1, 1.3],
            Detail::new(0, model.joints()),
            &mut scratch,
            &mut k1,
        )
        .unwrap();
    let g1 = k1.g().to_vec();
    // Build at a different level and controls in between, then rebuild.
    model
        .build_kernel_values(&[-0.4, 0.7], model.root_only(), &mut scratch, &mut k1)
        .unwrap();
    model
        .build_kernel_values(
            &[0.1, 1.3],
            Detail::new(0, model.joints()),
            &mut scratch,
            &mut k1,
        )
        .unwrap();
    let mut fresh_scratch = KernelScratch::new(&model);
    let mut k2 = ClipKernel::new(&model);
    model
        .build_kernel_values(
            &[0.1, 1.3],
            Detail::new(0, model.joints()),
            &mut fresh_scratch,
            &mut k2,
        )
        .unwrap();
    assert_eq!(k1.g(), g1.as_slice());
    assert_eq!(k1, k2);
}

#[test]
fn pose_rows_equal_the_leading_rows_of_pose() {
    let truth = random_truth(5, 0.0);
    let model = build_model(&truth);
    let mut scratch = KernelScratch::new(&model);
    let mut kernel = ClipKernel::new(&model);
    let c: Vec<f32> = (0..D).map(|k| 0.3 + 0.1 * k as f32).collect();
    for detail in [model.full_detail(), Detail::new(1, 2), model.root_only()] {
        model
            .build_kernel_values(&c, detail, &mut scratch, &mut kernel)
            .unwrap();
        // Seven rows (the root pose's own function) at every kind of phase: the first frame,
        // between frames, the last interval and the last frame (whose row of `U_T` is the last).
        let t = model.t() as f32;
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        for phase in [0.0, 0.37, 2.5, t - 1.3, t - 1.0, t + 4.0] {
            let mut full = vec![0.0f32; P];
            model.pose(&kernel, phase, &mut full).unwrap();
            for n in [0, 3, 7, 9, P] {
                let mut head = vec![f32::NAN; n];
                model.pose_rows(&kernel, phase, &mut head).unwrap();
                let what = format!("{detail:?}, r_T {}, {n} rows", kernel.ranks().t);
                assert_eq!(bits(&head), bits(&full[..n]), "{what} at {phase}");
            }
        }
        let mut too_long = vec![0.0f32; P + 1];
        assert!(model.pose_rows(&kernel, 2.5, &mut too_long).is_err());
    }
}

#[test]
fn compact_kernels_hold_their_level_and_give_the_same_bits() {
    let truth = random_truth(21, 0.03);
    let model = build_model(&truth);
    let mut scratch = KernelScratch::new(&model);
    let mut full = ClipKernel::new(&model);
    let mut compact = ClipKernel::compact(&model);
    // Holding every level from the start: never resizes.
    let all = model.p() * model.max_ranks().t;
    let mut joints = ClipKernel::compact_holding(&model, all);
    assert!(compact.is_compact() && !full.is_compact() && joints.is_compact());
    assert!(compact.heap_bytes() < full.heap_bytes());
    assert_eq!(joints.heap_bytes(), full.heap_bytes());
    let joints_buffer = joints.g().as_ptr();
    let mut rng = Rng::new(77);
    let levels = model.levels().len();
    // Coarse to fine and back: the compact buffer grows and shrinks.
    let details = [
        model.root_only(),
        Detail::new(0, model.joints()),
        Detail::new(levels - 1, 1),
        model.root_only(),
        Detail::new(1.min(levels - 1), 2),
    ];
    for (i, &detail) in details.iter().enumerate() {
        let c: Vec<f32> = (0..truth.d)
            .map(|k| rng.uniform(truth.min[k], truth.max[k]) as f32)
            .collect();
        model
            .build_kernel_values(&c, detail, &mut scratch, &mut full)
            .unwrap();
        model
            .build_kernel_values(&c, detail, &mut scratch, &mut compact)
            .unwrap();
        model
            .build_kernel_values(&c, detail, &mut scratch, &mut joints)
            .unwrap();
        assert_eq!(compact.g(), full.g(), "step {i}");
        assert_eq!(
            model.kernel_entries(detail),
            compact.rows() * compact.ranks().t,
            "step {i}"
        );
        assert_eq!(joints.g(), full.g(), "step {i}");
        assert_eq!(joints.time_table(), full.time_table());
        assert_eq!(joints.root_motion(), full.root_motion());
        assert_eq!(joints.heap_bytes(), full.heap_bytes(), "step {i}");
        assert_eq!(joints.g().as_ptr(), joints_buffer, "step {i}: reallocated");
        assert_eq!(compact.time_table(), full.time_table());
        assert_eq!(compact.root_motion(), full.root_motion());
        let r = compact.ranks();
        assert!(
            compact.heap_bytes() <= 2 * 4 * compact.rows() * r.t + 8 * model.t(),
            "step {i}: {} bytes for {} x {}",
            compact.heap_bytes(),
            compact.rows(),
            r.t
        );
        for phase in [0.0, 0.3, 1.0, 2.5, (model.t() - 1) as f32] {
            let (mut a, mut b) = (vec![0.0; compact.rows()], vec![0.0; full.rows()]);
            model.pose_rows(&compact, phase, &mut a).unwrap();
            model.pose_rows(&full, phase, &mut b).unwrap();
            assert_eq!(a, b);
        }
    }
}

/// A kernel holding fewer entries than a build needs grows once and then keeps its buffer for
/// every smaller build.
#[test]
fn a_holding_kernel_grows_for_a_larger_build_and_keeps_its_buffer() {
    let truth = random_truth(22, 0.03);
    let model = build_model(&truth);
    let mut scratch = KernelScratch::new(&model);
    let c: Vec<f32> = (0..truth.d)
        .map(|k| 0.5 * (truth.min[k] + truth.max[k]) as f32)
        .collect();
    let small = model.kernel_entries(model.root_only());
    let mut kernel = ClipKernel::compact_holding(&model, small);
    let mut full = ClipKernel::new(&model);
    model
        .build_kernel_values(&c, model.full_detail(), &mut scratch, &mut kernel)
        .unwrap();
    let buffer = kernel.g().as_ptr();
    for detail in [model.root_only(), Detail::new(1, 2), model.full_detail()] {
        model
            .build_kernel_values(&c, detail, &mut scratch, &mut kernel)
            .unwrap();
        model
            .build_kernel_values(&c, detail, &mut scratch, &mut full)
            .unwrap();
        assert_eq!(kernel.g(), full.g(), "{detail:?}");
        assert_eq!(kernel.g().as_ptr(), buffer, "{detail:?}: reallocated");
    }
}

#[test]
fn fast_kernel_agrees_with_the_column_order_reference() {
    for seed in [3u64, 4, 5] {
        let truth = random_truth(seed, 0.02 * seed as f64);
        let model = build_model(&truth);
        let mut scratch = KernelScratch::new(&model);
        let (mut fast, mut reference) = (ClipKernel::compact(&model), ClipKernel::new(&model));
        let mut rng = Rng::new(seed + 9);
        for detail in [model.full_detail(), Detail::new(1, 3), model.root_only()] {
            let c: Vec<f32> = (0..truth.d)
                .map(|k| rng.uniform(truth.min[k], truth.max[k]) as f32)
                .collect();
            model
                .build_kernel_values(&c, detail, &mut scratch, &mut fast)
                .unwrap();
            model
                .build_kernel_reference(&c, detail, &mut scratch, &mut reference)
                .unwrap();
            assert_eq!(fast.rows(), reference.rows());
            for (a, b) in fast.g().iter().zip(reference.g()) {
                assert!((a - b).abs() <= 1e-5 * (1.0 + b.abs()), "{a} vs {b}");
            }
        }
    }
}

#[test]
fn kernel_phase_lookup_equals_the_time_table_bitwise() {
    let truth = random_truth(8, 0.0);
    let model = build_model(&truth);
    let mut scratch = KernelScratch::new(&model);
    let mut kernel = ClipKernel::compact(&model);
    let mut rng = Rng::new(5);
    for _ in 0..6 {
        let c: Vec<f32> = (0..truth.d)
            .map(|k| rng.uniform(truth.min[k], truth.max[k]) as f32)
            .collect();
        model
            .build_kernel_values(&c, model.full_detail(), &mut scratch, &mut kernel)
            .unwrap();
        let table: &TimeTable = kernel.time_table();
        let d = kernel.duration();
        let mut ts: Vec<f64> = (0..=500).map(|i| d * (i as f64 / 500.0)).collect();
        ts.extend(table.times().iter().copied());
        ts.extend([-1.0, d * 1.5, f64::NAN, f64::INFINITY, 1e-12]);
        for t in ts {
            let want = table.phase_at(t) as f32;
            assert_eq!(kernel.phase_at(t).to_bits(), want.to_bits(), "t = {t}");
        }
    }
}

/// The per-sample form of steps 1-4 (every control, one sample at a time, `eval` of the distance,
/// projections accumulated column by column): what `kriging_weights_reference` computes, bit for bit.
fn per_sample_weights(model: &LodModel, controls: &[f32], key: usize, r_s: usize) -> Vec<f32> {
    let (s, d) = (model.s(), model.d());
    let cs = model.controls();
    let key = &model.keys()[key];
    let big = key.ranks;
    let mut c = vec![0.0f64; d + 1];
    for k in 0..d {
        let v = controls[k].clamp(cs.min[k], cs.max[k]);
        c[k] = (f64::from(v) - f64::from(cs.offset[k])) * f64::from(cs.scale[k]);
    }
    c[d] = 1.0;
    let mut x = vec![0.0f64; s + 1];
    for i in 0..s {
        let mut h2 = 0.0f64;
        for k in 0..d {
            let diff = c[k] - f64::from(cs.samples[i + s * k]);
            h2 += diff * diff;
        }
        x[i] = cs.variogram.eval(h2.sqrt());
    }
    x[s] = 1.0;
    let mut y = vec![0.0f64; r_s + d + 1];
    for (j, col) in key.projection.chunks_exact(big.s).enumerate() {
        for l in 0..r_s {
            y[l] += f64::from(col[l]) * x[j];
        }
    }
    for (j, col) in cs.projection.chunks_exact(d + 1).enumerate() {
        for m in 0..=d {
            y[r_s + m] += f64::from(col[m]) * x[j];
        }
    }
    (0..r_s)
        .map(|l| {
            let mut acc = y[l];
            for m in 0..=d {
                acc += f64::from(key.trend[l + big.s * m]) * (c[m] - y[r_s + m]);
            }
            acc as f32
        })
        .collect()
}

#[test]
fn kriging_weights_are_the_per_sample_formula_bitwise() {
    for seed in [3u64, 6, 7] {
        let truth = random_truth(seed, 0.01 * seed as f64);
        let model = build_model(&truth);
        let mut scratch = KernelScratch::new(&model);
        let mut rng = Rng::new(seed + 40);
        for key in 0..model.keys().len() {
            let big = model.keys()[key].ranks.s;
            for r_s in [1, big.div_ceil(2), big] {
                // Inside the data and beyond it (clamped).
                let c: Vec<f32> = (0..truth.d)
                    .map(|k| rng.uniform(truth.min[k] - 0.2, truth.max[k] + 0.2) as f32)
                    .collect();
                let want = per_sample_weights(&model, &c, key, r_s);
                let got = model
                    .kriging_weights_reference(&c, key, r_s, &mut scratch)
                    .unwrap();
                let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(got), bits(&want), "seed {seed} key {key} r_S {r_s}");
                let fast = model
                    .kriging_weights_values(&c, key, r_s, &mut scratch)
                    .unwrap();
                for (a, b) in fast.iter().zip(&want) {
                    assert!((a - b).abs() <= 1e-5 * (1.0 + b.abs()), "{a} vs {b}");
                }
            }
        }
    }
}

#[test]
fn kriging_weights_are_the_per_sample_formula_bitwise_for_each_variogram_and_control_count() {
    // The step that sums squared distances and applies the variogram in one pass (three or four
    // controls, spherical or linear) and the ones that apply it after (other models, other
    // control counts) against the per-sample formula, bit for bit.
    for d in 1..=5 {
        for model in lod_policy::VariogramModel::ALL {
            let truth = random_truth_with(11 + d as u64, 0.02, d, model);
            let lod = build_model(&truth);
            let mut scratch = KernelScratch::new(&lod);
            let mut rng = Rng::new(70 + d as u64);
            let big = lod.keys()[0].ranks.s;
            for _ in 0..4 {
                let c: Vec<f32> = (0..d)
                    .map(|k| rng.uniform(truth.min[k] - 0.2, truth.max[k] + 0.2) as f32)
                    .collect();
                let want = per_sample_weights(&lod, &c, 0, big);
                let got = lod
                    .kriging_weights_reference(&c, 0, big, &mut scratch)
                    .unwrap();
                let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(got), bits(&want), "d {d} {model:?} at {c:?}");
            }
        }
    }
}

#[test]
fn kriging_weights_refuse_a_missing_key_or_rank() {
    let truth = random_truth(9, 0.0);
    let model = build_model(&truth);
    let mut scratch = KernelScratch::new(&model);
    let c: Vec<f32> = truth.min.iter().map(|&v| v as f32).collect();
    let keys = model.keys().len();
    let big = model.keys()[0].ranks.s;
    for (key, r_s) in [(keys, 1), (0, 0), (0, big + 1)] {
        assert!(matches!(
            model.kriging_weights_values(&c, key, r_s, &mut scratch),
            Err(KernelError::Key { .. })
        ));
    }
    assert!(matches!(
        model.kriging_weights_values(&c[1..], 0, 1, &mut scratch),
        Err(KernelError::ControlLength { .. })
    ));
}

#[test]
fn time_table_is_the_per_frame_sum_of_the_time_row() {
    // dt_j = G[6, :] . U_T[j, :r_T] / time_scale, each summed over the columns in order
    // (`Iterator::sum`), then accumulated into playback times: the kernel's vectorised loop over
    // frames must give exactly these bits.
    let truth = random_truth(5, 0.03);
    let model = build_model(&truth);
    let mut scratch = KernelScratch::new(&model);
    let mut kernel = ClipKernel::compact(&model);
    let mut rng = Rng::new(9);
    let t = model.t();
    for level in 0..model.levels().len() {
        for joints in [0, model.joints()] {
            let c: Vec<f32> = (0..truth.d)
                .map(|k| rng.uniform(truth.min[k], truth.max[k]) as f32)
                .collect();
            model
                .build_kernel_values(&c, Detail::new(level, joints), &mut scratch, &mut kernel)
                .unwrap();
            let key = &model.keys()[model.levels()[level].key];
            let (g, rows, rt) = (kernel.g(), kernel.rows(), kernel.ranks().t);
            let inv_scale = 1.0 / model.parts().time_scale;
            let increments: Vec<f64> = (0..t)
                .map(|j| {
                    inv_scale
                        * (0..rt)
                            .map(|b| f64::from(g[6 + rows * b]) * f64::from(key.u_t[j + t * b]))
                            .sum::<f64>()
                })
                .collect();
            let expected = TimeTable::from_increments(&increments);
            let bits = |tt: &TimeTable| tt.times().iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(kernel.time_table()), bits(&expected), "level {level}");
        }
    }
}
