//! Defects found by an audit of the runtime's public API: each test fails without its fix.
//! Bad input gets an error or a documented neutral result, never a panic, an abort, or an `Ok`
//! carrying NaN or infinity; ordinary results keep their bits.

use crate::common;

use common::*;
use lod_policy::{
    AccuracyLevel, ClipKernel, ControlRange, ControlSpace, Controls, Detail, DistancePolicy,
    KernelError, KernelScratch, LevelPolicy, LodModel, PoseState, RootMotion, ScreenSpacePolicy,
    SeamScratch, SeamTransition, StyleMix, TimeTable, Variogram, VariogramModel, ViewParams,
    clamp_control,
};

fn model() -> LodModel {
    build_model(&random_truth(7, 0.0))
}

/// Mid-range controls of the test model (two dimensions).
fn mid(model: &LodModel) -> Vec<f32> {
    let c = model.controls();
    c.min
        .iter()
        .zip(&c.max)
        .map(|(a, b)| 0.5 * (a + b))
        .collect()
}

fn built(model: &LodModel, detail: Detail) -> ClipKernel {
    let mut s = KernelScratch::new(model);
    let mut k = ClipKernel::new(model);
    model
        .build_kernel_values(&mid(model), detail, &mut s, &mut k)
        .unwrap();
    k
}

fn all_finite(v: &[f32]) -> bool {
    v.iter().all(|x| x.is_finite())
}

// 1. A kernel built by another model (the same P and T) is refused, not read out of range.
#[test]
fn a_kernel_from_another_model_is_refused() {
    let a = model();
    let mut parts = a.parts().clone();
    let last = parts.keys.len() - 1;
    let ranks = parts.keys[last].ranks;
    let n = parts.levels.len();
    parts.levels = vec![AccuracyLevel { key: last, ranks }; n];
    let b = LodModel::new(parts).unwrap();
    let k = built(&a, a.full_detail());
    let mut out = vec![0.0f32; a.p()];
    for phase in [0.0f32, 1.0, (T - 1) as f32] {
        let e = b.pose(&k, phase, &mut out).unwrap_err();
        assert!(
            matches!(e, KernelError::Capacity { what: "kernel", .. }),
            "{e}"
        );
        let mut root = [0.0f32; 7];
        assert!(b.pose_rows(&k, phase, &mut root).is_err());
        // Its own model still reads it.
        a.pose(&k, phase, &mut out).unwrap();
    }
    // A kernel B built (smaller ranks) is fine for B.
    let kb = built(&b, b.full_detail());
    b.pose(&kb, 2.0, &mut out).unwrap();
}

// 2. A model that passed validation but whose values overflow the clip: an error, not NaN.
#[test]
fn an_overflowing_model_gives_an_error_not_nan() {
    let m = model();
    // A clip whose largest time increment is 0.99 f64::MAX: with the second largest, its
    // duration overflows.
    let k = built(&m, m.full_detail());
    let mut steps: Vec<f64> = k
        .time_table()
        .times()
        .windows(2)
        .map(|w| w[1] - w[0])
        .collect();
    steps.sort_by(|a, b| b.total_cmp(a));
    assert!(steps[1] > 0.02 * steps[0]);
    // (Time row of U_P times `factor`, time scale 1e-300: the largest step 0.99 f64::MAX.)
    let factor = (0.99 * f64::MAX * 1e-300 / steps[0]) as f32;
    type Edit = Box<dyn Fn(&mut lod_policy::ModelParts)>;
    let cases: Vec<(&str, Edit)> = vec![
        (
            "G(c)",
            Box::new(|p| p.keys[0].core.iter_mut().for_each(|v| *v = 3e38)),
        ),
        (
            "kriging weights",
            Box::new(|p| p.controls.variogram.sill = 1e300),
        ),
        (
            "duration",
            Box::new(move |p| {
                p.time_scale = 1e-300;
                let rows = p.p;
                for key in &mut p.keys {
                    for j in 0..key.ranks.p {
                        key.u_p[6 + rows * j] *= factor;
                    }
                }
            }),
        ),
    ];
    for (what, edit) in cases {
        let mut parts = m.parts().clone();
        edit(&mut parts);
        let bad = LodModel::new(parts).expect("passes validation");
        let mut s = KernelScratch::new(&bad);
        for mut k in [ClipKernel::new(&bad), ClipKernel::compact(&bad)] {
            let r = bad.build_kernel_values(&mid(&bad), bad.full_detail(), &mut s, &mut k);
            let Err(e) = r else {
                panic!(
                    "{what}: Ok with G {:?} duration {}",
                    &k.g()[..4],
                    k.duration()
                )
            };
            assert!(
                matches!(e, KernelError::Overflow { what: w, .. } if w == what),
                "{what}: {e}"
            );
            // The kernel is left unbuilt, and reads as a new one.
            let mut out = vec![f32::NAN; bad.p()];
            bad.pose(&k, 3.0, &mut out).unwrap();
            assert!(all_finite(&out), "{what}");
            assert!(k.phase_at(0.5).is_finite() && k.duration().is_finite());
            assert_eq!(k.detail(), bad.root_only());
        }
    }
}

// 3. A huge holding request is capped at what the model can use.
#[test]
fn compact_holding_caps_huge_requests() {
    let m = model();
    let most = m.p() * m.max_ranks().t * 4 + m.t() * 8;
    for entries in [usize::MAX, 1usize << 40] {
        let k = ClipKernel::compact_holding(&m, entries);
        assert!(k.heap_bytes() <= most, "{}", k.heap_bytes());
    }
}

// 4. Joints above the model's count are the documented error.
#[test]
fn joints_above_the_model_are_an_error() {
    let m = model();
    let mut s = KernelScratch::new(&m);
    let mut k = ClipKernel::new(&m);
    let e = m
        .build_kernel_values(&mid(&m), Detail::new(0, usize::MAX), &mut s, &mut k)
        .unwrap_err();
    assert!(matches!(e, KernelError::Joints { .. }));
}

// 5. A seam at a huge or NaN clip time gives a finite state (zero velocity), not NaN or a panic.
#[test]
fn seams_at_huge_or_nan_times_stay_finite() {
    let m = model();
    let k = built(&m, m.full_detail());
    let dur = k.duration() as f32;
    let pose_at = |t: f32, out: &mut [f32]| -> Result<usize, KernelError> {
        m.pose(&k, k.phase_at(f64::from(t)), out)?;
        Ok(out.len())
    };
    for t in [1e9f32, f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        let mut sc = SeamScratch::new(m.p());
        sc.capture(t, dur, None, pose_at).unwrap();
        let mut tr = SeamTransition::new(m.p(), 0.1);
        sc.start(t, dur, pose_at, &mut tr).unwrap();
        let mut pose = vec![0.0; m.p()];
        m.pose(&k, 1.0, &mut pose).unwrap();
        tr.apply(0.01, &mut pose);
        assert!(all_finite(&pose), "t = {t}");
    }
    let mut s = PoseState::new(10);
    s.set(&[0.0; 10], &[0.0; 10], &[1.0; 10], 0.0);
    assert!(s.velocity.iter().all(|&v| v == 0.0));
    s.set(&[0.0; 10], &[0.0; 10], &[1.0; 10], f32::NAN);
    assert!(s.velocity.iter().all(|&v| v == 0.0));
    s.set(&[0.0; 10], &[0.0; 10], &[1.0; 10], 0.5);
    assert!(s.velocity[6..].iter().all(|&v| v == 2.0));
}

// 6. A transition long past (or at infinity) is finished and adds nothing.
#[test]
fn a_transition_at_infinite_time_is_finished() {
    let mut prev = PoseState::new(10);
    prev.pose[8] = 0.5;
    prev.velocity[8] = 1.0;
    prev.pose[4] = 0.3;
    let next = PoseState::new(10);
    let mut t = SeamTransition::new(10, 0.1);
    t.start(&prev, &next, 10);
    for time in [1e30f32, 2.5e37, f32::MAX, f32::INFINITY, f32::NAN] {
        let mut pose = vec![0.0f32; 10];
        t.apply(time, &mut pose);
        assert!(all_finite(&pose), "t = {time}");
    }
    assert!(!t.clone().finish_after(1e6));
    assert!(!t.finish_after(f32::INFINITY));
}

// 7. Huge increments saturate: every time, phase and inverse is a number.
#[test]
fn time_tables_of_huge_increments_stay_finite() {
    let t = TimeTable::from_increments(&[1e308, 1e308, 1e308, 0.0]);
    assert!(t.times().iter().all(|x| x.is_finite()), "{:?}", t.times());
    for x in [0.5, 1e308, f64::MAX, f64::INFINITY] {
        let ph = t.phase_at(x);
        assert!((0.0..=3.0).contains(&ph), "phase_at({x}) = {ph}");
    }
    assert_eq!(t.phase_at(f64::INFINITY), 3.0);
    for ph in [0.5, 1.5, 2.5, 3.0] {
        assert!(t.time_at(ph).is_finite(), "time_at({ph})");
    }
    // Ordinary tables are unchanged: the running sum as written.
    let inc = [0.011, 0.0123, 0.009, 0.0];
    let t = TimeTable::from_increments(&inc);
    let mut want = vec![0.0f64];
    for d in &inc[..3] {
        want.push(want.last().unwrap() + d);
    }
    assert_eq!(t.times(), &want[..]);
    assert_eq!(lod_policy::offline::split_phase(1.5, 0), (0, 0.0));
}

// 8. Clamping never panics, and keeps f32::clamp's bits for valid ranges.
#[test]
fn clamp_control_never_panics_and_keeps_the_bits() {
    assert_eq!(clamp_control(1.0, 2.0, 0.0), 0.0);
    assert_eq!(clamp_control(1.0, f32::NAN, 2.0), 1.0);
    assert_eq!(clamp_control(3.0, 0.0, f32::NAN), 3.0);
    let r = ControlRange {
        min: Controls::from_array([1.0; 4]),
        max: Controls::from_array([0.0; 4]),
    };
    assert!(r.problem().is_some());
    assert_eq!(
        r.clamp(&Controls::from_array([0.5; 4])).to_array(),
        [0.0; 4]
    );
    let values = [
        -0.0f32,
        0.0,
        -1.0,
        1.0,
        0.5,
        -0.5,
        f32::MIN_POSITIVE,
        -f32::MIN_POSITIVE,
        1e-45,
        -1e-45,
        f32::MAX,
        f32::MIN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        3.7,
        -2.25,
    ];
    for &lo in &values {
        for &hi in &values {
            if lo > hi {
                continue;
            }
            for &v in &values {
                assert_eq!(
                    clamp_control(v, lo, hi).to_bits(),
                    v.clamp(lo, hi).to_bits(),
                    "{v} in [{lo}, {hi}]"
                );
            }
        }
    }
}

/// A hand-built walk control space of four dimensions.
fn walk_space() -> ControlSpace {
    let s = 3;
    ControlSpace {
        variogram: Variogram::new(VariogramModel::Exponential, 0.0, 1.0, 1.0, 1.0).unwrap(),
        offset: vec![0.0; 4],
        scale: vec![1.0; 4],
        samples: vec![0.1; 4 * s],
        min: vec![-1.0, 0.5, -1.0, 1.5],
        max: vec![1.0, 1.8, 1.0, 1.9],
        projection: vec![0.0; 5 * (s + 1)],
        implied: Vec::new(),
    }
}

// 9. A hand-built control space whose vectors disagree, or a bad argument: neutral values.
#[test]
fn control_space_readers_do_not_panic() {
    let c = Controls::from_array([0.1, 1.2, 0.0, 1.7]);
    let cs = model().controls().clone();
    assert_eq!(cs.implied(99, &c), 0.0);
    assert_eq!(cs.root_motion(&c, &[], &[]), RootMotion::default());
    let mut w = walk_space();
    assert_eq!(w.implied(99, &c), 0.0);
    assert_eq!(
        w.root_motion(&c, &[0.0; 3], &[0.0; 7]),
        RootMotion::default()
    );
    w.min.truncate(1);
    assert_eq!(w.body_scale(Some(1.7), &c), 1.0);
    assert_eq!(w.implied(2, &c), 0.0);
    let mut w = walk_space();
    w.scale.push(1.0);
    assert_eq!(w.data_style_mix(), [0.0; lod_policy::MAX_STYLES]);
    // Inverted bounds of a hand-built space: no panic in the clamp.
    let mut w = walk_space();
    w.min[2] = 2.0;
    assert!(w.implied(2, &c).is_finite());
}

// 10. Bad sizes give None, not a panic.
#[test]
fn style_mix_normalised_checks_sizes() {
    let mut out = [0.0f32; 16];
    assert_eq!(StyleMix::one(0).normalised(9, &[0.0; 16], &mut out), None);
    let mut short = [0.0f32; 1];
    assert_eq!(
        StyleMix::DATA_MIX.normalised(3, &[0.3; 3], &mut short),
        None
    );
    assert_eq!(StyleMix::one(0).normalised(3, &[0.3; 2], &mut out), None);
    assert_eq!(
        StyleMix::one(1).normalised(3, &[0.3; 3], &mut out),
        Some(())
    );
    assert_eq!(&out[..3], &[0.0, 1.0, 0.0]);
}

// 11. Deserialising re-runs the checks; JSON round-trips infinite errors; bincode bytes are
//     those of the plain fields.
#[test]
fn policies_deserialise_with_their_checks() {
    let m = model();
    let d = DistancePolicy::for_model(&m);
    let s = ScreenSpacePolicy::for_model(&m).unwrap();
    // JSON round trips (infinite errors included).
    let j = serde_json::to_string(&d).unwrap();
    assert_eq!(serde_json::from_str::<DistancePolicy>(&j).unwrap(), d);
    let j = serde_json::to_string(&s).unwrap();
    assert_eq!(serde_json::from_str::<ScreenSpacePolicy>(&j).unwrap(), s);
    // A level whose quality fails has an infinite error: written as "inf", and null reads back.
    let mut v = serde_json::to_value(&d).unwrap();
    v["level_err_m"][1] = serde_json::json!("inf");
    let inf: DistancePolicy = serde_json::from_value(v.clone()).unwrap();
    let back = serde_json::to_value(&inf).unwrap();
    assert_eq!(back["level_err_m"][1], serde_json::json!("inf"));
    v["level_err_m"][1] = serde_json::Value::Null;
    assert_eq!(serde_json::from_value::<DistancePolicy>(v).unwrap(), inf);

    // Hostile data: errors, not policies that panic later.
    let hostile = |edit: &dyn Fn(&mut serde_json::Value)| {
        let mut v = serde_json::to_value(&d).unwrap();
        edit(&mut v);
        serde_json::from_value::<DistancePolicy>(v)
    };
    assert!(hostile(&|v| v["joint_err_m"] = serde_json::json!([])).is_err());
    assert!(hostile(&|v| v["config"]["key_step_m"] = serde_json::json!(-5.0)).is_err());
    assert!(hostile(&|v| v["config"]["near_m"] = serde_json::json!(-1e30)).is_err());
    assert!(hostile(&|v| v["positions"] = serde_json::json!([])).is_err());
    assert!(hostile(&|v| v["costs"]["level_row_cost"][0] = serde_json::json!(u64::MAX)).is_err());
    assert!(hostile(&|_| {}).is_ok());
    let mut v = serde_json::to_value(&s).unwrap();
    v["costs"]["level_base_cost"] = serde_json::json!([]);
    assert!(serde_json::from_value::<ScreenSpacePolicy>(v).is_err());
    let mut v = serde_json::to_value(&s).unwrap();
    v["config"]["budget_px"] = serde_json::json!(0.0);
    assert!(serde_json::from_value::<ScreenSpacePolicy>(v).is_err());

    // Binary: the bytes of the plain fields, in order, and a round trip.
    let cfg = bincode::config::standard();
    let bytes = bincode::serde::encode_to_vec(&d, cfg).unwrap();
    let (back, _): (DistancePolicy, usize) =
        bincode::serde::decode_from_slice(&bytes, cfg).unwrap();
    assert_eq!(back, d);
    let bytes_s = bincode::serde::encode_to_vec(&s, cfg).unwrap();
    let (back, _): (ScreenSpacePolicy, usize) =
        bincode::serde::decode_from_slice(&bytes_s, cfg).unwrap();
    assert_eq!(back, s);
    // The same bytes as a plain struct of the same fields (the layout before this change).
    #[derive(serde::Serialize)]
    struct Plain<'a> {
        config: lod_policy::DistanceConfig,
        positions: &'a [f32],
        groups: usize,
        joints: usize,
        level_err_m: &'a [f32],
        joint_err_m: &'a [f32],
        costs: serde_json::Value,
    }
    let v = serde_json::to_value(&d).unwrap();
    let f32s = |k: &str| -> Vec<f32> {
        serde_json::from_value::<Vec<serde_json::Value>>(v[k].clone())
            .unwrap()
            .iter()
            .map(|x| x.as_f64().map_or(f32::INFINITY, |f| f as f32))
            .collect()
    };
    let (pos, le, je) = (f32s("positions"), f32s("level_err_m"), f32s("joint_err_m"));
    let head = Plain {
        config: d.config(),
        positions: &pos,
        groups: v["groups"].as_u64().unwrap() as usize,
        joints: v["joints"].as_u64().unwrap() as usize,
        level_err_m: &le,
        joint_err_m: &je,
        costs: serde_json::Value::Null,
    };
    // Everything up to the costs (bincode writes `()` for the null as nothing).
    let plain = bincode::serde::encode_to_vec(&head, cfg).unwrap();
    assert_eq!(&bytes[..plain.len()], &plain[..]);
}

// 12. A valid view at an overflowing distance gives the cheapest detail, not full detail.
#[test]
fn screen_policy_far_away_is_cheap() {
    let m = model();
    let p = ScreenSpacePolicy::for_model(&m).unwrap();
    let v = ViewParams::default();
    let far = p.detail(1e30, true, &v);
    for d in [1e38f32, 2e38, f32::MAX, f32::INFINITY] {
        assert_eq!(p.detail(d, true, &v), far, "distance {d}");
        assert_ne!(p.detail(d, true, &v), m.full_detail());
    }
    // A view that is not valid still gets full detail.
    let bad = ViewParams {
        fov_y_radians: f32::NAN,
        image_height_px: 1080.0,
    };
    assert_eq!(p.detail(50.0, true, &bad), m.full_detail());
}

// 13. Forward kinematics refusing rows that are not finite: `footlock.rs`'s unit tests
// (`forward_kinematics_refuses_non_finite_rows`, on their legs rig).

// 14. Slices of mismatched lengths: no panic.
#[test]
fn short_slices_do_not_panic() {
    let mut p = [1.0f32; 3];
    lod_policy::CycleFrame::default().place_root(&mut p);
    assert_eq!(p, [1.0; 3]);
    let mut s = PoseState {
        pose: vec![0.0; 10],
        velocity: vec![],
    };
    s.set(&[1.0; 10], &[0.0; 10], &[1.0; 10], 0.1);
    let mut s = PoseState {
        pose: vec![0.0; 10],
        velocity: vec![0.0; 2],
    };
    s.into_next_frame(&RootMotion {
        dx: 1.0,
        dz: 0.0,
        turn: 0.1,
    });
    let prev = PoseState {
        pose: vec![0.0; 10],
        velocity: vec![],
    };
    let mut t = SeamTransition::new(10, 0.1);
    t.start(&prev, &PoseState::new(10), 10);
    assert_eq!(t.rows(), 0);
}
