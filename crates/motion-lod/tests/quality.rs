//! Issue 12's motion-quality acceptance: walks measured by the one motion-quality meter
//! (`motion_lod::quality`) against the data's own takes.
//!
//! On Bandai (all 800 cycles, as the README quotes; skipped with `skipped: ../shared/mocap not found` when the data is
//! absent, failed under `MOTION_LOD_REQUIRE_DATA`), every walk of the quality grid (straight, turns of 30 degrees both ways, sidesteps, slow,
//! fast and the corners of the control hull), 4 cycles at full detail: largest joint acceleration at
//! most 1.25x the data at the walk's step length (`QualityReference::at_controls`), foot skate at most 1.5x, floor offset within 1 cm, facing against
//! travel within the data's range; the same on CMU (33 cycles, its control ranges). On the embedded
//! data (always present): the foot lock measurably
//! beats the sliding feet. (Seam continuity itself is tested in `lod_policy::SeamTransition`.)
//!
//! Issue 34: on every walk of the grid at every accuracy level (Bandai and the embedded data), the
//! meter's skate agrees with an independent forward-kinematics probe (`fk_probe`) within 20% (2.5 cm/s
//! where the feet are planted).
//!
//! The screen check, on both: every detail the distance and screen-space policies use, measured
//! anew at controls the build did not measure (midpoints between training samples), shows at most
//! one pixel of pose error (shell) and of foot slide at the nearest distance it is used.

use crate::common;
use crate::fk_probe;

use std::collections::BTreeMap;

use lod_policy::{Controls, Detail, DistancePolicy, LevelPolicy, ScreenSpacePolicy, ViewParams};
use motion_lod::MotionModel;
use motion_lod::build::foot_slide_cm;
use motion_lod::metrics::ErrorMeter;
use motion_lod::progress::NoProgress;
use motion_lod::quality::{self, MotionQuality};
use motion_lod::synth::WalkRequest;
use motion_lod::walk_quality;

/// The data folder `name` under `../shared/mocap`, or `None` (with the skip message) when absent; a
/// test failure instead when `MOTION_LOD_REQUIRE_DATA` is set (CI).
fn walk(model: &MotionModel, controls: Controls, blend: bool, plant_feet: bool) -> MotionQuality {
    walk_at(
        model,
        controls,
        model.lod().full_detail(),
        blend,
        plant_feet,
    )
}

/// [`walk`] at `detail`.
fn walk_at(
    model: &MotionModel,
    controls: Controls,
    detail: Detail,
    blend: bool,
    plant_feet: bool,
) -> MotionQuality {
    let req = WalkRequest {
        controls,
        detail,
        cycles: 4,
        fps: 30.0,
        blend,
        plant_feet,
    };
    let w = model.synthesize_walk(&req).expect("walk synthesizes");
    walk_quality::measure_walk(model, &w).expect("walk measures")
}

/// Every detail the two policies use (1080p, 60 degrees, 0 to 1000 m), measured at midpoints between
/// training samples: shell error against full detail and foot slide beyond full detail's, projected at
/// the nearest distance the detail is used, at most one pixel.
fn details_stay_under_a_pixel(model: &MotionModel, controls: &[[f64; 4]]) {
    let lod = model.lod();
    let joints = lod.joints();
    let view = ViewParams::default();
    let distance = DistancePolicy::for_model(lod);
    let screen = ScreenSpacePolicy::for_model(lod).expect("the model has error tables");
    let policies: [&dyn LevelPolicy; 2] = [&distance, &screen];
    let mut nearest: BTreeMap<(usize, usize), f32> = BTreeMap::new();
    for i in 0..=2000 {
        let d = i as f32 * 0.5;
        for policy in policies {
            let detail = policy.detail(d, true, &view);
            if detail == lod.root_only() {
                continue;
            }
            let key = (
                lod.check_detail(detail)
                    .expect("a detail of the model")
                    .accuracy,
                detail.active_joints.min(joints),
            );
            nearest.entry(key).or_insert(d);
        }
    }
    assert!(
        nearest.len() > 3,
        "the policies use {} details",
        nearest.len()
    );
    let stride = controls.len().div_ceil(6).max(1);
    let probes: Vec<Controls> = (0..controls.len() - 1)
        .step_by(stride)
        .map(|i| {
            Controls::from_f64(std::array::from_fn(|k| {
                0.5 * (controls[i][k] + controls[i + 1][k])
            }))
        })
        .collect();
    let full = lod.full_detail();
    let full_slides: Vec<f64> = probes
        .iter()
        .map(|c| foot_slide_cm(model, c, full).expect("full-detail slide"))
        .collect();
    for (&(level, active), &d) in &nearest {
        if (level, active) == (0, joints) {
            continue;
        }
        let detail = Detail::new(level, active);
        let mut meter = ErrorMeter::new(&model.layout);
        let mut slide = 0.0f64;
        for (c, full_slide) in probes.iter().zip(&full_slides) {
            let reference = model.synthesize_aligned(c, full).expect("synthesizes");
            let poses = model.synthesize_aligned(c, detail).expect("synthesizes");
            meter.compare_sequences(&reference, &poses);
            slide = slide.max(foot_slide_cm(model, c, detail).expect("slide") - full_slide);
        }
        let shell = meter.total().shell_cm;
        let px = |cm: f64| cm / 100.0 / f64::from(view.metres_per_pixel(d));
        assert!(
            px(shell) <= 1.0 && px(slide) <= 1.0,
            "level {level} with {active} joints, used from {d} m: shell {shell:.2} cm = {:.2} px, \
             foot slide {slide:.2} cm = {:.2} px",
            px(shell),
            px(slide)
        );
    }
}

#[test]
fn embedded_policies_keep_pose_error_and_foot_slide_under_a_pixel() {
    let (model, analysis) = common::built();
    details_stay_under_a_pixel(model, &analysis.controls);
}

#[test]
fn bandai_policies_keep_pose_error_and_foot_slide_under_a_pixel() {
    let Some((model, controls)) = common::bandai() else {
        return;
    };
    details_stay_under_a_pixel(model, controls);
}

/// Every walk of the quality grid inside the data's hull (the hull's corners and its edges along
/// turn and sidestep included; at least half the grid), 4 cycles with the foot lock, at full detail
/// and at every level the policies give to walkers with joints (`LevelError::passes_quality`; the
/// build measured the same walks): pop at most 1.25x the data at the walk's step length
/// (`QualityReference::at_controls`), skate at most 1.5x, floor within 1 cm, facing inside the
/// data's range. Returns the levels checked.
fn walks_look_like_the_data(what: &str, model: &MotionModel, min_takes: usize) -> Vec<usize> {
    let reference = model.report.quality.clone().expect("the feet are found");
    assert!(
        reference.takes >= min_takes,
        "{what}: {} takes measured",
        reference.takes
    );
    let grid = walk_quality::walk_grid(model);
    let names: Vec<&str> = grid.iter().map(|g| g.name.as_str()).collect();
    for edge in ["turn edge +", "turn edge -"] {
        assert!(
            model.ignored_controls()[2] || names.contains(&edge),
            "{what}: no `{edge}` walk in {names:?}"
        );
    }
    let lod = model.lod();
    let used: Vec<usize> = (0..lod.levels().len())
        .filter(|&l| lod.level_serves_joints(l))
        .collect();
    let inside: Vec<_> = grid.iter().filter(|g| g.in_hull).collect();
    assert!(
        inside.len() >= grid.len() / 2,
        "{what}: only {} of {} grid walks inside the hull",
        inside.len(),
        grid.len()
    );
    for &level in &used {
        for g in &inside {
            let detail = Detail::new(level, lod.joints());
            let q = walk_at(model, g.controls, detail, true, true);
            let data = reference.at_controls(&g.controls);
            let name = format!("{what} {} at level {level}", g.name);
            assert!(
                q.pop_cm <= 1.25 * data.pop_cm,
                "{name}: pop {:.2} cm/frame^2 > 1.25 x the data's {:.2}",
                q.pop_cm,
                data.pop_cm
            );
            assert!(
                q.skate_cm_s <= 1.5 * data.skate_cm_s,
                "{name}: skate {:.2} cm/s > 1.5 x the data's {:.2}",
                q.skate_cm_s,
                data.skate_cm_s
            );
            assert!(
                q.floor_offset_cm.abs() <= 1.0,
                "{name}: floor offset {:.2} cm",
                q.floor_offset_cm
            );
            let (lo, hi) = reference.facing_range_deg;
            assert!(
                (lo..=hi).contains(&q.facing_deg),
                "{name}: facing {:.1} deg outside the data's {lo:.1}..{hi:.1}",
                q.facing_deg
            );
        }
    }
    used
}

/// Bandai: the grid passes at level 0 and at levels 1 and 2, which the policies use (levels 3-14
/// pop up to 2.7x or skate up to 8x the data even with the lock and serve only root-only walkers).
#[test]
fn bandai_walks_look_like_the_data() {
    let Some((model, _)) = common::bandai() else {
        return;
    };
    let used = walks_look_like_the_data("bandai", model, 100);
    assert_eq!(used, [0, 1, 2], "levels the policies use");
    // And the distance policy does use them, from its screen check's distances on.
    let policy = DistancePolicy::for_model(model.lod());
    let view = ViewParams::default();
    let shown: std::collections::BTreeSet<usize> = (0..600)
        .map(|d| policy.detail(d as f32, true, &view))
        .filter(|d| d.active_joints > 0)
        .map(|d| d.accuracy)
        .collect();
    assert_eq!(shown.into_iter().collect::<Vec<_>>(), used);
}

/// The embedded data (15 takes of a procedural walker whose own pop grows threefold from its slowest
/// takes to its fastest): the grid passes at level 0 and at every level the policies use, each walk
/// against the takes of similar step length. (Against the median of all takes, level 0's fastest
/// walk, `corner +dz`, read pop 1.36x and skate 1.54x: the median take walks 0.3 m a cycle shorter.)
#[test]
fn embedded_walks_look_like_the_data() {
    let (model, _) = common::built();
    let used = walks_look_like_the_data("embedded", model, 15);
    assert!(
        used.len() > 2 && used[0] == 0,
        "levels the policies use: {used:?}"
    );
}

/// CMU (the cgspeed conversion of subjects 7 and 8, 33 cycles, `Preset::Cmu`): the same thresholds
/// within its control ranges (the cross-validation by take keeps dx and turn; with dx, drift of
/// +-5 cm, level 0 fails and the build's quality guard drops it, so the sidestep walks of the grid
/// walk straight, and the turn walks turn within the data's +-3 degrees).
#[test]
fn cmu_walks_look_like_the_data() {
    let Some((model, _)) = common::cmu() else {
        return;
    };
    walks_look_like_the_data("cmu", model, 10);
}

/// Issue 17's reproducibility on the shared data: a second build of each set, on one thread (the
/// first used the default pool), writes the same model file bytes.
#[test]
fn shared_data_sets_build_to_the_same_bytes_on_one_thread() {
    let sets = [
        (
            "bandai",
            common::bandai().map(|(m, _)| m),
            common::bandai_spec(),
        ),
        ("cmu", common::cmu().map(|(m, _)| m), common::cmu_spec()),
    ];
    for (what, model, spec) in sets {
        let (Some(model), Some(spec)) = (model, spec) else {
            continue;
        };
        let reference = motion_lod::model_file::encode(model, std::path::Path::new("m")).unwrap();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let again = pool.install(|| {
            let loaded = spec
                .load_with_default(motion_io::test_data::fixture_takes(), &|_, _| {})
                .expect("data loads");
            MotionModel::build(&loaded.training, &Default::default(), &NoProgress)
                .expect("model builds")
        });
        let bytes = motion_lod::model_file::encode(&again, std::path::Path::new("m")).unwrap();
        assert!(
            bytes == reference,
            "{what}: a one-thread build writes other bytes"
        );
    }
}

#[test]
fn planted_feet_skate_less_than_sliding_ones() {
    let (model, _) = common::built();
    let reference = model.report.quality.as_ref().expect("reference measured");
    assert!(reference.takes > 0 && reference.median.pop_cm > 0.0);
    let (mut skate_free, mut skate_locked) = (0.0, 0.0);
    for g in walk_quality::walk_grid(model) {
        skate_free += walk(model, g.controls, true, false).skate_cm_s;
        skate_locked += walk(model, g.controls, true, true).skate_cm_s;
    }
    assert!(
        skate_locked < 0.5 * skate_free,
        "locked feet skate {skate_locked:.2} against {skate_free:.2} free"
    );
}

/// Issue 34's acceptance: on every walk of the quality grid (4 cycles at 30 fps, foot lock on, as
/// the `quality` command measures them) at every accuracy level, the meter's skate agrees with the
/// independent probe's (`fk_probe`: the walk as `synth` writes it, placed by the BVH reader's forward
/// kinematics, one floor per foot and cycle) within 20%, or within [`PLANTED_SLACK_CM_S`] where the
/// feet are planted and the figure is the speed of a few frames at the edges of the stances (landing
/// and lift-off), which any two floor estimates count a little differently. Measured (Bandai and
/// the embedded data, 349 walks): 17 walks differ by more than 20%, all below 6.1 cm/s and by at
/// most 2.2 cm/s.
fn meter_agrees_with_the_probe_on_the_grid(what: &str, model: &MotionModel) {
    let data = model.report.quality.as_ref().expect("reference").median;
    let mut skating = 0;
    let slack = PLANTED_SLACK_CM_S;
    for level in 0..model.lod().levels().len() {
        for g in walk_quality::walk_grid(model) {
            let req = WalkRequest {
                controls: g.controls,
                detail: Detail::new(level, model.lod().joints()),
                cycles: 4,
                fps: 30.0,
                blend: true,
                plant_feet: true,
            };
            let w = model.synthesize_walk(&req).expect("walk synthesizes");
            let q = walk_quality::measure_walk(model, &w).expect("walk measures");
            let motion = model.walk_motion(&w).expect("walk as BVH");
            let x = fk_probe::positions(
                &motion,
                model.layout.units_per_metre(),
                0..motion.frame_count(),
            );
            let p = fk_probe::skate(&motion, &x, w.frame_time, w.cycle_seconds);
            eprintln!(
                "{what} level {level} {}: skate {:.2} cm/s ({:.2}x the data), probe {:.2}; contact \
                 {:.2}, probe {:.2}; floating {:.2} cm",
                g.name,
                q.skate_cm_s,
                q.skate_cm_s / data.skate_cm_s,
                p.skate_cm_s,
                q.contact_share,
                p.contact_share,
                q.floating_cm
            );
            // Where 20% of the probe's reading is more than the slack, the 20% decides.
            skating += usize::from(0.2 * p.skate_cm_s > slack);
            assert!(
                (q.skate_cm_s - p.skate_cm_s).abs() <= (0.2 * p.skate_cm_s).max(slack),
                "{what} level {level} {}: the meter reads skate {:.2} cm/s, the probe {:.2}",
                g.name,
                q.skate_cm_s,
                p.skate_cm_s
            );
        }
    }
    eprintln!(
        "{what}: {skating} walks skate faster than {:.1} cm/s",
        5.0 * slack
    );
    assert!(skating >= 10, "{what}: {skating} walks skate");
}

/// How far the meter and the probe may read apart where the feet are planted, cm/s (see
/// [`meter_agrees_with_the_probe_on_the_grid`]).
const PLANTED_SLACK_CM_S: f64 = 2.5;

#[test]
fn embedded_meter_agrees_with_an_independent_probe_on_the_grid() {
    let (model, _) = common::built();
    meter_agrees_with_the_probe_on_the_grid("embedded", model);
}

#[test]
fn bandai_meter_agrees_with_an_independent_probe_on_the_grid() {
    let Some((model, _)) = common::bandai() else {
        return;
    };
    meter_agrees_with_the_probe_on_the_grid("bandai", model);
}

/// What crowd walkers show as the crowd plays them: 8 walkers for 10 s at 30 fps on their curved
/// paths (controls changing every cycle, seams inertialized), all at full detail and in view of the
/// overview camera (the lock runs for visible walkers), measured by the
/// meter from each walker's first seam on ([`motion_lod::crowd::measure_track`]); with the foot lock
/// (`CrowdConfig::foot_lock_levels`, default) and without it (0).
fn crowd_tracks(model: &MotionModel, foot_lock_levels: usize) -> Vec<MotionQuality> {
    use motion_lod::crowd::record_walkers;
    use motion_lod::crowd_sim::{CrowdConfig, Scene};
    let config = CrowdConfig {
        seed: 5,
        foot_lock_levels,
        ..CrowdConfig::with_density(8, 0.02)
    };
    let walkers: Vec<usize> = (0..8).collect();
    let tracks = record_walkers(
        model,
        config,
        Scene::Overview,
        &lod_policy::FullDetail::for_model(model.lod()),
        300,
        &walkers,
    )
    .expect("crowd runs");
    assert_eq!(tracks.len(), 8);
    tracks
        .iter()
        .map(|t| {
            assert!(
                t.seams.len() >= 5,
                "walker {}: seams {:?}",
                t.walker,
                t.seams
            );
            motion_lod::crowd::measure_track(model, t, 1.0 / f64::from(config.fps))
                .expect("track measures")
        })
        .collect()
}

fn median_skate(qs: &[MotionQuality]) -> f64 {
    let mut v: Vec<f64> = qs.iter().map(|q| q.skate_cm_s).collect();
    quality::median(&mut v)
}

/// Issue 12, planted feet for near crowd walkers: on the embedded data the runtime foot lock
/// halves the walkers' median foot skate at least.
#[test]
fn embedded_crowd_walkers_plant_their_feet() {
    let (model, _) = common::built();
    assert!(model.feet().is_some(), "the model records its feet");
    let (locked, free) = (crowd_tracks(model, 3), crowd_tracks(model, 0));
    let (l, f) = (median_skate(&locked), median_skate(&free));
    eprintln!("embedded crowd: median skate {l:.2} cm/s locked, {f:.2} free");
    assert!(
        l < 0.5 * f,
        "locked feet skate {l:.2} cm/s against {f:.2} free"
    );
}

/// The embedded data's performers are 1.60 to 1.90 m tall and the model has one skeleton (the first
/// take's): every walker is drawn at its height's body scale (drawn at the skeleton's size they
/// floated or sank by up to 10 cm), and the runtime lock's ground correction raises a sinking
/// stance foot, so near walkers (levels 0-2, both legs and feet evaluated) stand on the data's
/// floor within [`FLOOR_CM`] in both scenes (without the correction they sank up to 1.19 cm on the
/// ground). Under the distance policy in the overview, joint counts change at seams: the joints
/// dropped fade out and the joints added fade in, so no walker with both legs evaluated pops more
/// than 1.25x the data's median at a seam (a switch snapped them: 2.7x). Walkers with fewer joints
/// hold their legs at the mean rotation, which pops by itself (up to 1.3x at level 0 and 1.7x at
/// level 5 on the quality grid with 2 joints); the policies give them those few joints only where
/// their error projects under a pixel, and they are held to 2x.
#[test]
fn embedded_crowd_walkers_stand_on_the_floor_and_fade_joints_at_seams() {
    use motion_lod::crowd_sim::Scene;
    let (model, _) = common::built();
    let data = model.report.quality.as_ref().expect("reference").median;
    let ground = distance_policy_crowd(model, Scene::Ground);
    let near_ground = locked_walkers_stand_on_the_floor(model, Scene::Ground, &ground);
    assert!(
        near_ground >= 20,
        "{near_ground} near walkers on the ground"
    );
    let walkers = distance_policy_crowd(model, Scene::Overview);
    let joint_changes = walkers.iter().filter(|w| w.joints.0 != w.joints.1).count();
    assert!(joint_changes >= 10, "{joint_changes} walkers change joints");
    for w in &walkers {
        let q = &w.quality;
        let bound = if w.joints.0 >= LEG_JOINTS { 1.25 } else { 2.0 };
        assert!(
            q.seam_pop_cm <= bound * data.pop_cm,
            "walker {} (levels {:?}, joints {:?}): seam pop {:.2} > {bound} x the data's {:.2}",
            w.walker,
            w.levels,
            w.joints,
            q.seam_pop_cm,
            data.pop_cm
        );
    }
    let near = locked_walkers_stand_on_the_floor(model, Scene::Overview, &walkers);
    assert!(near >= 20, "{near} near walkers");
}

/// How far crowd walkers with both legs evaluated (the runtime foot lock's, at every level) may
/// stand from the data's floor, cm: the lock's soft ground margin
/// ([`lod_policy::offline::GROUND_MARGIN_M`]), half issue 12's 1 cm.
const FLOOR_CM: f64 = 0.5;

/// The joints that evaluate both legs (thighs, knees, ankles and toes come first in the evaluation
/// order of the embedded, CMU and Bandai skeletons): the foot lock's.
const LEG_JOINTS: usize = 8;

/// Asserts that the crowd walkers the runtime lock held for their whole stretch (at least the
/// [`LEG_JOINTS`] joints that evaluate both legs, at any level) stand on the data's floor: within
/// [`FLOOR_CM`] at levels 0-2; at coarser levels, which the policies give walkers with joints only
/// when their grid walks stand within the near-character threshold of 1 cm
/// (`LevelError::floor_cm`), within the worst of their levels' grid figures plus the lock's margin
/// [`FLOOR_CM`] (the crowd's controls lie between the grid's walks: CMU walkers at level 5, 0.85 cm
/// on the grid, stand up to 1.14 cm off; the lock's ground correction cannot undo a coarse level's
/// hip height); returns how many there were.
fn locked_walkers_stand_on_the_floor(
    model: &MotionModel,
    scene: motion_lod::crowd_sim::Scene,
    walkers: &[motion_lod::crowd::WalkerQuality],
) -> usize {
    let locked: Vec<_> = walkers
        .iter()
        .filter(|w| w.joints.0 >= LEG_JOINTS)
        .collect();
    let errors = model.lod().level_errors();
    for w in &locked {
        let grid = (w.levels.0..=w.levels.1)
            .map(|l| f64::from(errors[l].floor_cm))
            .fold(0.0, f64::max);
        let bound = if w.levels.1 <= 2 {
            FLOOR_CM
        } else {
            grid + FLOOR_CM
        };
        assert!(
            w.quality.floor_offset_cm.abs() <= bound,
            "{scene:?} walker {} (levels {:?}, joints {:?}): floor offset {:.2} cm > {bound}",
            w.walker,
            w.levels,
            w.joints,
            w.quality.floor_offset_cm
        );
    }
    locked.len()
}

/// 200 walkers at 0.01 per m² for 10 s under the model's distance policy with the camera of
/// `scene`, each measured by the meter as the crowd plays it.
fn distance_policy_crowd(
    model: &MotionModel,
    scene: motion_lod::crowd_sim::Scene,
) -> Vec<motion_lod::crowd::WalkerQuality> {
    let policy = DistancePolicy::for_model(model.lod());
    let config = motion_lod::crowd_sim::CrowdConfig::with_density(200, 0.01);
    motion_lod::crowd::crowd_quality(model, config, scene, &policy, 10.0).expect("crowd measures")
}

/// CMU crowds as the distance policy plays them (200 walkers, 10 s, both scenes): the near
/// walkers stand on the data's floor within [`FLOOR_CM`] (their stances floated up to 1.38 cm above
/// it before the runtime lock lowered them, and sank up to 0.55 cm before it raised them), and no
/// walker pops more than 1.5x the data's median.
#[test]
fn cmu_crowd_walkers_stand_on_the_floor() {
    use motion_lod::crowd_sim::Scene;
    let Some((model, _)) = common::cmu() else {
        return;
    };
    let data = model.report.quality.as_ref().expect("reference").median;
    for scene in [Scene::Ground, Scene::Overview] {
        let walkers = distance_policy_crowd(model, scene);
        for w in &walkers {
            assert!(
                w.quality.pop_cm <= 1.5 * data.pop_cm,
                "{scene:?} walker {}: pop {:.2} > 1.5 x {:.2}",
                w.walker,
                w.quality.pop_cm,
                data.pop_cm
            );
        }
        let near = locked_walkers_stand_on_the_floor(model, scene, &walkers);
        assert!(near >= 20, "{scene:?}: {near} near walkers");
    }
}

/// Bandai crowds as the distance policy plays them, both scenes (200 walkers, 10 s): every walker's
/// seams pop at most 1.25x the data's median and no walker pops more than 1.5x anywhere (the
/// runtime lock's knee flips and its reach at heel strikes took them to 1.68x); near walkers'
/// feet skate at most 1.5x the data's median, and those with both legs evaluated stand on the
/// floor within [`FLOOR_CM`].
#[test]
fn bandai_crowds_under_the_distance_policy_look_like_the_data() {
    use motion_lod::crowd_sim::Scene;
    let Some((model, _)) = common::bandai() else {
        return;
    };
    let data = model.report.quality.as_ref().expect("reference").median;
    for scene in [Scene::Ground, Scene::Overview] {
        let walkers = distance_policy_crowd(model, scene);
        let worst = walkers.iter().map(|w| w.quality.pop_cm).fold(0.0, f64::max);
        eprintln!(
            "bandai {scene:?}: {} walkers measured, worst pop {:.2}x the data",
            walkers.len(),
            worst / data.pop_cm
        );
        assert!(walkers.len() >= 50, "{scene:?}: {} walkers", walkers.len());
        for w in &walkers {
            let q = &w.quality;
            let what = format!(
                "{scene:?} walker {} (levels {:?}, joints {:?})",
                w.walker, w.levels, w.joints
            );
            assert!(
                q.seam_pop_cm <= 1.25 * data.pop_cm,
                "{what}: seam pop {:.2} > 1.25 x {:.2}",
                q.seam_pop_cm,
                data.pop_cm
            );
            assert!(
                q.pop_cm <= 1.5 * data.pop_cm,
                "{what}: pop {:.2} > 1.5 x {:.2}",
                q.pop_cm,
                data.pop_cm
            );
        }
        // The lock holds their stances on the floor (they sank up to 1.85 cm without it).
        locked_walkers_stand_on_the_floor(model, scene, &walkers);
        let mut near: Vec<f64> = walkers
            .iter()
            .filter(|w| w.levels.1 < 3 && w.joints.0 > 0)
            .map(|w| w.quality.skate_cm_s)
            .collect();
        assert!(near.len() >= 20, "{scene:?}: {} near walkers", near.len());
        let skate = quality::median(&mut near);
        assert!(
            skate <= 1.5 * data.skate_cm_s,
            "{scene:?}: near walkers skate {skate:.2} cm/s (median) > 1.5 x {:.2}",
            data.skate_cm_s
        );
    }
}

/// Issue 12's acceptance for crowd walkers on Bandai: near walkers as the crowd plays them pop at
/// most 1.25x the data's median, skate at most 1.5x and stand on the floor within [`FLOOR_CM`];
/// the lock takes most of the free feet's skate away (a quarter of it at most remains).
#[test]
fn bandai_crowd_walkers_look_like_the_data() {
    let Some((model, _)) = common::bandai() else {
        return;
    };
    let data = model.report.quality.as_ref().expect("reference").median;
    let (locked, free) = (crowd_tracks(model, 3), crowd_tracks(model, 0));
    for (i, (q, f)) in locked.iter().zip(&free).enumerate() {
        eprintln!(
            "bandai crowd walker {i}: pop {:.2} (free {:.2}, data {:.2}), seam pop {:.2}, skate {:.2} (free {:.2}, data {:.2}), floor {:.2} cm",
            q.pop_cm,
            f.pop_cm,
            data.pop_cm,
            q.seam_pop_cm,
            q.skate_cm_s,
            f.skate_cm_s,
            data.skate_cm_s,
            q.floor_offset_cm
        );
        assert!(
            q.pop_cm <= 1.25 * data.pop_cm,
            "walker {i}: pop {:.2} cm/frame^2 > 1.25 x the data's {:.2}",
            q.pop_cm,
            data.pop_cm
        );
        assert!(
            q.skate_cm_s <= 1.5 * data.skate_cm_s,
            "walker {i}: skate {:.2} cm/s > 1.5 x the data's {:.2}",
            q.skate_cm_s,
            data.skate_cm_s
        );
        assert!(
            q.floor_offset_cm.abs() <= FLOOR_CM,
            "walker {i}: floor offset {:.2} cm",
            q.floor_offset_cm
        );
    }
    let (l, f) = (median_skate(&locked), median_skate(&free));
    assert!(
        l < 0.25 * f,
        "locked feet skate {l:.2} cm/s against {f:.2} free"
    );
}

/// Issue 16's acceptance at the Bandai sample count (S = 800, where the kriging sums are longest):
/// the crowd's fast source (folded f64 kriging rows, blocked sums, the AVX2 build where the CPU has
/// it) places every joint within 1e-5 m of the reference source (projections summed column by
/// column, the straightforward loops), at the same levels, in both scenes.
#[test]
fn bandai_crowd_fast_path_matches_the_reference_path() {
    use motion_lod::LodSource;
    use motion_lod::crowd_sim::{CrowdConfig, Scene};
    let Some((model, _)) = common::bandai() else {
        return;
    };
    let policy = DistancePolicy::for_model(model.lod());
    let config = CrowdConfig {
        seed: 5,
        ..CrowdConfig::with_density(300, 0.01)
    };
    for scene in [Scene::Ground, Scene::Overview] {
        let fast = common::crowd_frames(&LodSource::new(model), &policy, config, scene, 90);
        let reference =
            common::crowd_frames(&LodSource::reference(model), &policy, config, scene, 90);
        let mut worst = 0.0f32;
        let mut placed = 0usize;
        for (f, (a, b)) in fast.iter().zip(&reference).enumerate() {
            assert_eq!(a.bins, b.bins, "{scene:?} frame {f}: levels differ");
            for (a, b) in a.joints.iter().zip(&b.joints) {
                assert_eq!(a.len(), b.len(), "{scene:?} frame {f}: joints shown");
                for (p, q) in a.iter().zip(b) {
                    for k in 0..3 {
                        worst = worst.max((p[k] - q[k]).abs());
                    }
                    placed += 1;
                }
            }
        }
        eprintln!("bandai {scene:?}: {placed} joint positions, worst difference {worst:.2e} m");
        assert!(placed > 300 * 90, "{scene:?}: {placed} joint positions");
        assert!(worst <= 1e-5, "{scene:?}: joints differ by {worst} m");
        same_trajectories_for_a_minute(model, &policy, config, scene);
    }
}

/// The two sources' walkers keep the same trajectories for 60 s (1,800 frames), within the
/// runtime's bound for the world (docs/architecture.md, "Precision"): cycle frames within 1 mm per
/// simulated minute and headings within 1e-5 rad per minute, roots within 1e-5 m. The bound allows
/// the arithmetic of a clip to differ in the last bits (a root motion an ulp apart carries into
/// every later cycle frame, in double precision since ABI 5); the trajectories may not drift.
fn same_trajectories_for_a_minute(
    model: &MotionModel,
    policy: &DistancePolicy,
    config: motion_lod::crowd_sim::CrowdConfig,
    scene: motion_lod::crowd_sim::Scene,
) {
    use motion_lod::LodSource;
    use motion_lod::crowd_sim::{Camera, Crowd, FrameStats};
    let (fast, reference) = (LodSource::new(model), LodSource::reference(model));
    let mut a = Crowd::new(&fast, config).expect("crowd");
    let mut b = Crowd::new(&reference, config).expect("crowd");
    let path = scene.path(config.field_size_m);
    let lens = scene.lens(Camera::default(), config.field_size_m);
    let (mut sa, mut sb) = (FrameStats::default(), FrameStats::default());
    let (mut builds, mut worst) = (0, 0.0f64);
    for f in 0..1800u32 {
        let cam = path.camera_at(f as f32 / 30.0, &lens);
        a.step_into(&fast, policy, &cam, 1.0 / 30.0, &mut sa)
            .expect("step");
        b.step_into(&reference, policy, &cam, 1.0 / 30.0, &mut sb)
            .expect("step");
        builds += sa.kernels_built;
        let minutes = f64::from(f + 1) / 30.0 / 60.0;
        for i in 0..a.len() {
            let (fa, fb) = (a.cycle_frame(i), b.cycle_frame(i));
            let moved = (fa.x - fb.x).abs().max((fa.z - fb.z).abs());
            let turned = lod_policy::wrap_angle_f64(fa.heading - fb.heading).abs();
            assert!(
                moved <= 1e-3 * minutes && turned <= 1e-5 * minutes,
                "{scene:?} frame {f} walker {i}: cycle frame {fa:?} against the reference's {fb:?}"
            );
            worst = worst.max(moved);
            let (p, q) = (a.root_position(i), b.root_position(i));
            assert!(
                (p - q).abs().max_element() <= 1e-5,
                "{scene:?} frame {f} walker {i}: root {p} against the reference's {q}"
            );
        }
    }
    eprintln!(
        "bandai {scene:?}: cycle frames within {worst:.1e} m of the reference's after a minute"
    );
    // About two cycles a second for each of 300 walkers: every walker chained many clips.
    assert!(builds > 300 * 50, "{scene:?}: {builds} clips built");
}
