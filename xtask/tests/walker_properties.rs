//! Properties of the generated walks, checked on the frames as written to BVH and read back
//! with `motion_io::parse_bvh` (so rounding to 4 decimals and the Euler convention are covered).

use std::sync::OnceLock;

use glam::{DQuat, DVec3};
use motion_io::Motion;
use xtask::fixtures::{self, PlannedTake, SEED};
use xtask::footsteps::{FOOT_FLAT, HEEL_RISE, Side};
use xtask::gait::{Style, TakeSpec};
use xtask::rig;
use xtask::walker::{self, FPS, Take};

/// Every take of the fixture plan, generated and read back from its BVH text.
struct Generated {
    planned: PlannedTake,
    take: Take,
    text: String,
    parsed: Motion,
}

fn fixture_takes() -> &'static [Generated] {
    static CELL: OnceLock<Vec<Generated>> = OnceLock::new();
    CELL.get_or_init(|| {
        fixtures::plan(SEED)
            .into_iter()
            .map(|planned| {
                let take = walker::generate(&planned.spec).unwrap();
                let text = fixtures::bvh_text(&take.motion);
                let parsed = motion_io::parse_bvh(&text).expect("generated BVH parses");
                Generated {
                    planned,
                    take,
                    text,
                    parsed,
                }
            })
            .collect()
    })
}

/// World transforms of every joint of frame `i`.
fn world(m: &Motion, i: usize) -> Vec<motion_io::Transform> {
    let mut out = vec![motion_io::Transform::IDENTITY; m.skeleton.joint_count()];
    m.skeleton.forward_kinematics(m.frame(i), &mut out);
    out
}

fn horizontal(v: DVec3) -> f64 {
    (v.x * v.x + v.z * v.z).sqrt()
}

#[test]
fn written_bvh_parses_back_with_the_same_values() {
    for g in fixture_takes() {
        let (m, p) = (&g.take.motion, &g.parsed);
        assert_eq!(
            p.skeleton.joint_count(),
            rig::JOINT_COUNT,
            "{}",
            g.planned.file
        );
        assert_eq!(p.skeleton.channel_count(), rig::CHANNEL_COUNT);
        assert_eq!(p.frame_count(), m.frame_count());
        assert!((p.fps() - FPS).abs() < 1e-2, "{} fps", p.fps());
        for (j, (a, b)) in p.skeleton.joints.iter().zip(&m.skeleton.joints).enumerate() {
            assert_eq!(a.name, b.name, "joint {j}");
            assert_eq!(a.parent, b.parent, "joint {j}");
            assert!((a.offset - b.offset).length() < 1e-5, "joint {j}");
        }
        let worst = m
            .frames
            .iter()
            .zip(&p.frames)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(
            worst <= 5.0001e-5,
            "{}: largest rounding error {worst}",
            g.planned.file
        );
    }
}

#[test]
fn stance_feet_are_planted() {
    // Mid-stance (foot flat): the ankle does not move. Heel rocker: the heel point stays put;
    // forefoot rocker: the ball (Toes joint) stays put. Measured by forward kinematics of the
    // frames read back from the BVH text.
    for g in fixture_takes() {
        let m = &g.parsed;
        let heel_local = g.take.rig.heel_local();
        for (side, foot, toes) in [
            (Side::Left, rig::FOOT_L, rig::TOES_L),
            (Side::Right, rig::FOOT_R, rig::TOES_R),
        ] {
            let mut prev: Option<(usize, DVec3, DVec3, DVec3)> = None;
            let mut checked = 0;
            for i in 0..m.frame_count() {
                let fs = g.take.foot(side, i);
                let w = world(m, i);
                let ankle = w[foot].position;
                let heel = w[foot].transform_point(heel_local);
                let ball = w[toes].position;
                if let Some((pi, pa, ph, pb)) = prev
                    && fs.stance
                    && g.take.foot(side, pi).stance
                    && pi + 1 == i
                {
                    let u = fs.progress;
                    // Horizontal speeds in cm/s.
                    if u > FOOT_FLAT + 0.02 && u < HEEL_RISE - 0.02 {
                        let v = horizontal(ankle - pa) * FPS;
                        assert!(
                            v < 0.5,
                            "{} {side:?} frame {i}: ankle slides at {v} cm/s",
                            g.planned.file
                        );
                        checked += 1;
                    }
                    if u < FOOT_FLAT - 0.01 {
                        let v = (heel - ph).length() * FPS;
                        assert!(
                            v < 0.5,
                            "{} {side:?} frame {i}: heel slides at {v} cm/s",
                            g.planned.file
                        );
                    }
                    if u > HEEL_RISE + 0.01 {
                        let v = (ball - pb).length() * FPS;
                        assert!(
                            v < 0.5,
                            "{} {side:?} frame {i}: ball slides at {v} cm/s",
                            g.planned.file
                        );
                    }
                }
                prev = Some((i, ankle, heel, ball));
            }
            assert!(
                checked > 100,
                "{} {side:?}: only {checked} mid-stance frames",
                g.planned.file
            );
        }
    }
}

#[test]
fn nothing_goes_through_the_floor_and_swing_feet_clear_it() {
    for g in fixture_takes() {
        let m = &g.parsed;
        let sk = &m.skeleton;
        let tip_l = sk.joints[rig::TOES_L].end_site.unwrap();
        let tip_r = sk.joints[rig::TOES_R].end_site.unwrap();
        for i in 0..m.frame_count() {
            let w = world(m, i);
            for (j, t) in w.iter().enumerate() {
                assert!(
                    t.position.y > -0.05,
                    "{} frame {i}: joint {j} at y = {}",
                    g.planned.file,
                    t.position.y
                );
            }
            for (side, toes, tip) in [
                (Side::Left, rig::TOES_L, tip_l),
                (Side::Right, rig::TOES_R, tip_r),
            ] {
                let y = w[toes].transform_point(tip).y;
                assert!(y > -0.05, "{} frame {i}: toe tip at {y}", g.planned.file);
                let fs = g.take.foot(side, i);
                if !fs.stance && fs.progress > 0.1 && fs.progress < 0.9 {
                    assert!(
                        y > 0.5,
                        "{} frame {i} {side:?}: swing toe tip only {y} cm high",
                        g.planned.file
                    );
                }
            }
        }
    }
}

/// Root heading (radians about +Y) from the root rotation: the direction its +Z axis faces.
fn heading_of(q: DQuat) -> f64 {
    let f = q * DVec3::Z;
    f.x.atan2(f.z)
}

#[test]
fn root_travels_the_commanded_speed_and_turn_rate() {
    for g in fixture_takes() {
        let m = &g.parsed;
        let traj = &g.take.trajectory;
        let spec = &g.planned.spec;
        // Two whole cycles of the steady part, from the same gait phase to the same phase, so
        // the oscillations of the pelvis cancel.
        let phi0 = traj.phase_at(traj.steady_start) + 1.0;
        let i0 = (traj.time_at_phase(phi0) * FPS).round() as usize;
        let i1 = (traj.time_at_phase(phi0 + 2.0) * FPS).round() as usize;
        assert!(i1 < m.frame_count(), "{}: take too short", g.planned.file);
        let dt = (i1 - i0) as f64 / FPS;
        let (a, b) = (world(m, i0)[0], world(m, i1)[0]);
        let turn = motion_io::expmap::wrap_angle(heading_of(b.rotation) - heading_of(a.rotation));
        let rate = turn.to_degrees() / dt;
        assert!(
            (rate - spec.turn_rate_deg).abs() < 0.5,
            "{}: turn rate {rate} deg/s, commanded {}",
            g.planned.file,
            spec.turn_rate_deg
        );
        // Arc length from the chord of a circular arc: s = c (theta / 2) / sin(theta / 2).
        let chord = horizontal(b.position - a.position);
        let arc = if turn.abs() < 1e-6 {
            chord
        } else {
            chord * (0.5 * turn) / (0.5 * turn).sin()
        };
        let speed = arc / dt / 100.0;
        assert!(
            (speed - spec.speed).abs() < 0.02 * spec.speed,
            "{}: speed {speed} m/s, commanded {}",
            g.planned.file,
            spec.speed
        );
        // The first cycle starts from a near standstill.
        let n = (0.25 * FPS) as usize;
        let start_speed =
            horizontal(world(m, n)[0].position - world(m, 0)[0].position) / 0.25 / 100.0;
        assert!(
            start_speed < 0.5 * spec.speed,
            "{}: starts at {start_speed} m/s",
            g.planned.file
        );
    }
}

#[test]
fn takes_hold_enough_gait_cycles() {
    let mut total = 0;
    for g in fixture_takes() {
        let traj = &g.take.trajectory;
        let end = (g.parsed.frame_count() - 1) as f64 / FPS;
        // Left heel strikes inside the take (integer phases).
        let first = traj.phase_at(0.0).ceil() as i64;
        let last = traj.phase_at(end).floor() as i64;
        let cycles = last - first;
        let steady = last - traj.phase_at(traj.steady_start).round() as i64;
        assert!(steady >= 4, "{}: {steady} steady cycles", g.planned.file);
        total += cycles;
    }
    assert!(
        (60..=120).contains(&total),
        "{total} two-step cycles in the set"
    );
}

#[test]
fn arms_swing_against_the_legs() {
    // At a right heel strike (right leg forward) the left hand is ahead of the left shoulder and
    // the right hand behind the right shoulder, along the walking direction.
    for g in fixture_takes().iter().take(5) {
        let traj = &g.take.trajectory;
        let phi = traj.phase_at(traj.steady_start) + 1.5;
        let t = traj.time_at_phase(phi);
        let i = (t * FPS).round() as usize;
        let w = world(&g.parsed, i);
        let th = traj.heading(t);
        let fwd = DVec3::new(th.sin(), 0.0, th.cos());
        let ahead = |a: usize, b: usize| (w[a].position - w[b].position).dot(fwd);
        assert!(
            ahead(rig::HAND_L, rig::UPPER_ARM_L) > 2.0,
            "{}",
            g.planned.file
        );
        assert!(
            ahead(rig::HAND_R, rig::UPPER_ARM_R) < -2.0,
            "{}",
            g.planned.file
        );
        assert!(
            ahead(rig::FOOT_R, rig::FOOT_L) > 20.0,
            "{}: right foot forward",
            g.planned.file
        );
    }
}

#[test]
fn joint_angles_are_human_like() {
    // Sagittal angles over the steady cycles, from the Euler X channels (hinge-dominated joints):
    // knee flexion (LowerLeg, positive), hip flexion (UpperLeg, negative = thigh forward).
    for g in fixture_takes() {
        let m = &g.parsed;
        let start = (g.take.trajectory.steady_start * FPS).ceil() as usize;
        let knee = 3 + 3 * rig::LOWER_LEG_L + 1;
        let hip = 3 + 3 * rig::UPPER_LEG_L + 1;
        let range = |c: usize| {
            (start..m.frame_count())
                .map(|i| m.frame(i)[c])
                .fold((f64::MAX, f64::MIN), |(lo, hi), v| (lo.min(v), hi.max(v)))
        };
        let (k_lo, k_hi) = range(knee);
        let (h_lo, h_hi) = range(hip);
        let f = &g.planned.file;
        assert!((-0.5..15.0).contains(&k_lo), "{f}: knee min {k_lo}");
        assert!((50.0..80.0).contains(&k_hi), "{f}: knee max {k_hi}");
        assert!((-50.0..-25.0).contains(&h_lo), "{f}: hip flexion {h_lo}");
        assert!((5.0..30.0).contains(&h_hi), "{f}: hip extension {h_hi}");
    }
}

#[test]
fn generation_is_deterministic() {
    let a = fixtures::generate_all(SEED).unwrap();
    let b = fixtures::generate_all(SEED).unwrap();
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(x.name, y.name);
        assert!(x.content == y.content, "{} differs between runs", x.name);
    }
    // Same text as the cached takes (generated separately).
    for g in fixture_takes() {
        let f = a.iter().find(|f| f.name == g.planned.file).unwrap();
        assert!(f.content == g.text);
    }
    // Another seed gives another plan.
    assert_ne!(
        fixtures::plan(SEED + 1)[0].spec,
        fixtures::plan(SEED)[0].spec
    );
}

#[test]
fn fixture_set_is_small_enough_to_commit() {
    let files = fixtures::generate_all(SEED).unwrap();
    let size = |variants: bool| -> usize {
        files
            .iter()
            .filter(|f| f.name.starts_with("variants/") == variants)
            .map(|f| f.content.len())
            .sum()
    };
    // The base set, and the exporter variants of two of its takes (issue 13).
    assert!(size(false) < 4_200_000, "{} bytes", size(false));
    assert!(size(true) < 5_800_000, "{} bytes of variants", size(true));
    let csv = files.iter().find(|f| f.name == "controls.csv").unwrap();
    assert_eq!(csv.content.lines().count(), 1 + fixture_takes().len());
}

#[test]
fn committed_fixtures_match_the_generator() {
    let dir = fixtures::default_dir();
    if !dir.join("controls.csv").exists() {
        motion_io::test_data::missing("fixtures/ not generated yet (run `cargo xtask fixtures`)");
        return;
    }
    let files = fixtures::generate_all(SEED).unwrap();
    let stale = fixtures::check(&dir, &files);
    assert!(
        stale.is_empty(),
        "fixtures/ is out of date, run `cargo xtask fixtures`: {stale:?}"
    );
}

#[test]
fn any_height_speed_and_turn_in_range_stays_finite_and_reaches_the_feet() {
    for (h, v, w) in [
        (1.5, 0.7, -35.0),
        (2.0, 1.7, 35.0),
        (1.6, 1.6, 30.0),
        (1.9, 0.8, 0.0),
    ] {
        let spec = TakeSpec {
            height_m: h,
            speed: v,
            turn_rate_deg: w,
            heading0_deg: 170.0,
            start_m: [0.0, 0.0],
            steady_cycles: 4,
            style: Style::default(),
        };
        let take = walker::generate(&spec).unwrap();
        assert!(take.motion.frames.iter().all(|x| x.is_finite()));
        let mut worst: f64 = 0.0;
        for i in 0..take.motion.frame_count() {
            let fs = take.foot(Side::Left, i);
            if fs.stance {
                let p = take.motion.skeleton.joint_positions(take.motion.frame(i))[rig::FOOT_L];
                worst = worst.max((p - fs.ankle).length());
            }
        }
        assert!(
            worst < 0.05,
            "h={h} v={v} w={w}: stance ankle off its target by {worst} cm"
        );
    }
}
