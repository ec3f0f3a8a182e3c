//! Level-of-detail policies: the paper's distance schedule and the screen-space pixel budget.
// Index loops mirror the formulas' subscripts.
#![allow(clippy::needless_range_loop)]

use crate::common;

use common::*;
use lod_policy::{
    Detail, DistanceConfig, DistancePolicy, ErrorMetric, LevelError, LevelPolicy, LodModel,
    PolicyError, ScreenConfig, ScreenSpacePolicy, ViewParams,
};
use proptest::prelude::*;

fn model() -> LodModel {
    build_model(&random_truth(31, 0.0))
}

#[test]
fn distance_policy_follows_the_paper_schedule() {
    let m = model();
    let published = DistanceConfig {
        screen_budget_px: None,
        ..DistanceConfig::default()
    };
    let pol = DistancePolicy::new(&m, published).unwrap();
    let v = ViewParams::default();
    let at = |d: f32| pol.detail(d, true, &v);
    assert_eq!(at(0.0), Detail::new(0, JOINTS));
    assert_eq!(at(29.9), Detail::new(0, JOINTS));
    // Key group 0 (levels 0, 1) over [30, 80), group 1 (levels 2, 3) over [80, 130).
    assert_eq!(at(30.0).accuracy, 0);
    assert_eq!(at(54.9).accuracy, 0);
    assert_eq!(at(55.0).accuracy, 1);
    assert_eq!(at(80.0).accuracy, 2);
    assert_eq!(at(105.0).accuracy, 3);
    assert_eq!(at(129.9).accuracy, 3);
    assert_eq!(at(130.0), m.root_only());
    // One joint fewer every 10 m past 30 m.
    assert_eq!(at(39.9).active_joints, JOINTS);
    assert_eq!(at(40.0).active_joints, JOINTS - 1);
    assert_eq!(at(60.0).active_joints, JOINTS - 3);
    assert_eq!(at(75.0).active_joints, 0);
    // Invisible or NaN: root only.
    assert_eq!(pol.detail(1.0, false, &v), m.root_only());
    assert_eq!(pol.detail(f32::NAN, true, &v), m.root_only());
}

#[test]
fn distance_policy_is_configurable_and_validated() {
    let m = model();
    let cfg = DistanceConfig {
        near_m: 10.0,
        key_step_m: 20.0,
        joint_step_m: 5.0,
        joints_per_step: 2,
        screen_budget_px: None,
    };
    let pol = DistancePolicy::new(&m, cfg).unwrap();
    let v = ViewParams::default();
    assert_eq!(pol.detail(9.0, true, &v), Detail::new(0, JOINTS));
    assert_eq!(pol.detail(30.0, true, &v).accuracy, 2);
    assert_eq!(pol.detail(15.0, true, &v).active_joints, JOINTS - 2);
    assert_eq!(pol.detail(50.0, true, &v), m.root_only());
    let bad = DistanceConfig {
        key_step_m: 0.0,
        ..cfg
    };
    assert!(matches!(
        DistancePolicy::new(&m, bad),
        Err(PolicyError::Config {
            name: "key_step_m",
            ..
        })
    ));
    let bad = DistanceConfig {
        near_m: f32::NAN,
        ..cfg
    };
    assert!(DistancePolicy::new(&m, bad).is_err());
}

fn detail_rank(m: &LodModel, d: Detail) -> (usize, usize) {
    (
        m.check_detail(d).unwrap().accuracy,
        d.active_joints.min(m.joints()),
    )
}

/// The screen check: wherever the schedule's detail would show more than the budget (pose error or
/// foot slide, projected), the policy picks a finer one that fits; where the schedule fits, it is
/// unchanged.
#[test]
fn distance_policy_screen_check_keeps_visible_error_under_the_budget() {
    let mut parts = model().into_parts();
    // Level 3 slides 40 cm per stance (its pose error is 7 cm): usable only beyond ~374 m at 1 px.
    parts.level_errors[3].slide_cm = 40.0;
    let m = LodModel::new(parts).unwrap();
    let v = ViewParams::default();
    let published = DistancePolicy::new(
        &m,
        DistanceConfig {
            screen_budget_px: None,
            ..DistanceConfig::default()
        },
    )
    .unwrap();
    for budget in [0.5f32, 1.0, 3.0] {
        let checked = DistancePolicy::new(
            &m,
            DistanceConfig {
                screen_budget_px: Some(budget),
                ..DistanceConfig::default()
            },
        )
        .unwrap();
        let (mut changed, mut kept) = (0, 0);
        for i in 0..1400 {
            let dist = i as f32 * 0.1;
            let d = checked.detail(dist, true, &v);
            let s = published.detail(dist, true, &v);
            // Beyond the schedule (the model's two keys end it two key steps past `near_m`) both
            // say root only; inside it, the published schedule's last level without joints is
            // the same detail, which the screen check may refine.
            let beyond = dist >= checked.config().near_m + 2.0 * checked.config().key_step_m;
            if beyond {
                assert_eq!(
                    (d, s),
                    (m.root_only(), m.root_only()),
                    "root only stays root only"
                );
                continue;
            }
            if s == m.root_only() && d == s {
                continue;
            }
            let (l, j) = detail_rank(&m, d);
            let err_m = lod_policy::ERROR_MARGIN * m.level_errors()[l].visible_m(true)
                + lod_policy::ERROR_MARGIN
                    * (j..=JOINTS)
                        .map(|k| m.joint_errors()[k].visible_m(true))
                        .fold(0.0, f32::max);
            let px = err_m / v.metres_per_pixel(dist);
            let (sl, sj) = detail_rank(&m, s);
            // Never coarser than the schedule.
            assert!(l <= sl && j >= sj, "at {dist} m: {d:?} coarser than {s:?}");
            if (l, j) == (sl, sj) {
                kept += 1;
            } else {
                changed += 1;
                // Changed only to fit the budget, and then it fits (or is full detail).
                assert!(
                    px <= budget * 1.0001 || (l, j) == (0, JOINTS),
                    "at {dist} m: {px} px with {d:?}"
                );
            }
            if (l, j) != (0, JOINTS) {
                assert!(px <= budget * 1.0001, "at {dist} m: {px} px with {d:?}");
            }
        }
        assert!(
            changed > 0 && kept > 0,
            "budget {budget}: {changed} changed, {kept} kept"
        );
    }
    let bad = DistanceConfig {
        screen_budget_px: Some(0.0),
        ..DistanceConfig::default()
    };
    assert!(matches!(
        DistancePolicy::new(&m, bad),
        Err(PolicyError::Config {
            name: "screen_budget_px",
            ..
        })
    ));
}

/// The distance policy's cost (a cycle's kernel and poses, the screen policy's cost model) never
/// increases with distance, and its detail is never coarser than the paper's schedule in either
/// level or joints: the screen check only refines, and takes the cheapest refinement that fits.
#[test]
fn distance_policy_cost_never_increases_with_distance() {
    let m = model();
    let pol = DistancePolicy::for_model(&m);
    let schedule = DistancePolicy::new(
        &m,
        DistanceConfig {
            screen_budget_px: None,
            ..DistanceConfig::default()
        },
    )
    .unwrap();
    let costs = ScreenSpacePolicy::for_model(&m).unwrap();
    let v = ViewParams::default();
    let mut prev = costs.cost(pol.detail(0.0, true, &v)).unwrap();
    let mut levels = std::collections::BTreeSet::new();
    for i in 1..4000 {
        let dist = i as f32 * 0.1;
        let d = pol.detail(dist, true, &v);
        let cur = costs.cost(d).unwrap();
        assert!(cur <= prev, "at {dist} m: cost {cur} after {prev} ({d:?})");
        let (l, j) = detail_rank(&m, d);
        let (ls, js) = detail_rank(&m, schedule.detail(dist, true, &v));
        assert!(
            l <= ls && j >= js,
            "at {dist} m: {d:?} is coarser than the schedule's ({ls}, {js})"
        );
        levels.insert(l);
        prev = cur;
    }
    assert!(levels.len() > 2, "levels used: {levels:?}");
}

/// A level whose measured motion quality fails is never given to a walker with joints, by either
/// policy, at any distance; with the same errors and passing quality it is used.
#[test]
fn policies_skip_levels_whose_motion_quality_fails() {
    let used = |m: &LodModel| {
        let v = ViewParams::default();
        let d = DistancePolicy::for_model(m);
        let s = ScreenSpacePolicy::for_model(m).unwrap();
        let mut levels = std::collections::BTreeSet::new();
        for i in 0..4000 {
            for det in [
                d.detail(i as f32 * 0.25, true, &v),
                s.detail(i as f32 * 0.25, true, &v),
            ] {
                if det.active_joints > 0 {
                    levels.insert(det.accuracy);
                }
            }
        }
        levels
    };
    let m = model();
    assert!(used(&m).contains(&1), "level 1 is used: {:?}", used(&m));
    let mut parts = m.into_parts();
    parts.level_errors[1].pop_x = lod_policy::QUALITY_POP_LIMIT * 1.01;
    parts.level_errors[2].skate_x = lod_policy::QUALITY_SKATE_LIMIT * 1.01;
    let failing = LodModel::new(parts).unwrap();
    let levels = used(&failing);
    assert!(
        !levels.contains(&1) && !levels.contains(&2),
        "levels used: {levels:?}"
    );
    assert!(
        levels.contains(&0) && levels.len() > 1,
        "levels used: {levels:?}"
    );
}

#[test]
fn screen_policy_meets_the_budget_and_is_cheapest() {
    let m = model();
    let pol = ScreenSpacePolicy::for_model(&m).unwrap();
    let v = ViewParams {
        fov_y_radians: 0.8,
        image_height_px: 720.0,
    };
    let mut prev_cost = u64::MAX;
    for i in 0..3000 {
        let dist = i as f32 * 0.25;
        let d = pol.detail(dist, true, &v);
        let (level, joints) = detail_rank(&m, d);
        let cost = pol.cost(Detail::new(level, joints)).unwrap();
        assert!(cost <= prev_cost, "cost rose at {dist} m");
        prev_cost = cost;
        let budget_m = v.metres_per_pixel(dist) * 1.0;
        let err = pol.estimated_error_m(Detail::new(level, joints)).unwrap();
        let any_fits = (0..4).any(|l| {
            (0..=JOINTS).any(|j| pol.estimated_error_m(Detail::new(l, j)).unwrap() <= budget_m)
        });
        if any_fits {
            // Projected error within 1 px (err_px = err_m H / (2 d tan(fov/2))).
            let err_px = err * v.image_height_px / (2.0 * dist * (0.5 * v.fov_y_radians).tan());
            assert!(err_px <= 1.0 + 1e-4, "{err_px} px at {dist} m");
            for l in 0..4 {
                for j in 0..=JOINTS {
                    if pol.estimated_error_m(Detail::new(l, j)).unwrap() <= budget_m {
                        assert!(
                            pol.cost(Detail::new(l, j)).unwrap() >= cost,
                            "({l}, {j}) is cheaper at {dist} m"
                        );
                    }
                }
            }
        } else {
            assert_eq!(
                d,
                Detail::new(0, JOINTS),
                "fallback must be full detail at {dist} m"
            );
        }
    }
    // Far enough, the cheapest pair is the smallest level with no joints: root only.
    assert_eq!(detail_rank(&m, pol.detail(1e4, true, &v)), (3, 0));
    assert_eq!(pol.detail(5.0, false, &v), m.root_only());
}

#[test]
fn screen_policy_needs_an_error_table_and_a_positive_budget() {
    let mut parts = model().into_parts();
    parts.level_errors.clear();
    let m = LodModel::new(parts).unwrap();
    assert_eq!(
        ScreenSpacePolicy::for_model(&m),
        Err(PolicyError::NoErrorTable)
    );
    let m = model();
    let cfg = ScreenConfig {
        budget_px: 0.0,
        metric: ErrorMetric::Shell,
    };
    assert!(matches!(
        ScreenSpacePolicy::new(&m, cfg),
        Err(PolicyError::Config { .. })
    ));
}

#[test]
fn screen_policy_without_joint_table_keeps_every_joint() {
    let mut parts = model().into_parts();
    parts.joint_errors.clear();
    let m = LodModel::new(parts).unwrap();
    let pol = ScreenSpacePolicy::new(
        &m,
        ScreenConfig {
            budget_px: 1.0,
            metric: ErrorMetric::MeanJoint,
        },
    )
    .unwrap();
    let v = ViewParams::default();
    for dist in [1.0f32, 50.0, 500.0, 5000.0] {
        assert_eq!(pol.detail(dist, true, &v).active_joints, JOINTS);
    }
    // The mean-joint metric uses the smaller errors: level 3 (4 cm, times the margin 1.5) fits at
    // 1 px when 1.5 x 0.04 m <= 2 d tan(30 deg) / 1080, i.e. d >= 56.1 m.
    assert_eq!(lod_policy::ERROR_MARGIN, 1.5);
    assert_eq!(pol.detail(56.2, true, &v).accuracy, 3);
    assert_eq!(pol.detail(55.9, true, &v).accuracy, 2);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn screen_policy_cost_is_monotone_for_any_error_table(
        level_cm in proptest::collection::vec(0.0f32..20.0, 4),
        joint_cm in proptest::collection::vec(0.0f32..20.0, JOINTS + 1),
        budget in 0.2f32..4.0,
    ) {
        let mut parts = model().into_parts();
        parts.level_errors = level_cm.iter().map(|&e| LevelError { mean_joint_cm: e, shell_cm: e, slide_cm: 0.0, ..LevelError::default() }).collect();
        parts.joint_errors = joint_cm.iter().map(|&e| LevelError { mean_joint_cm: e, shell_cm: e, slide_cm: 0.0, ..LevelError::default() }).collect();
        let m = LodModel::new(parts).unwrap();
        let pol = ScreenSpacePolicy::new(&m, ScreenConfig { budget_px: budget, metric: ErrorMetric::Shell }).unwrap();
        let v = ViewParams::default();
        let mut prev = u64::MAX;
        for i in 0..400 {
            let d = pol.detail(i as f32 * 2.0, true, &v);
            let (l, j) = detail_rank(&m, d);
            let c = pol.cost(Detail::new(l, j)).unwrap();
            prop_assert!(c <= prev);
            prev = c;
        }
    }
}
