//! The purpose of the fixtures: `motion_io`'s contact detection and cycle segmentation, run with
//! their default settings on the generated takes, find the steady two-step cycles, and EVERY kept
//! cycle's controls (the first and the last of each take included) match the generating
//! parameters.
//!
//! Tolerances, per cycle: duration within 0.02 s of the generating period, turn within 2 degrees
//! of `omega * period`, displacement length within 3 % of the arc's chord, and the sideways
//! displacement `dx` within 3 cm of `chord * sin(turn / 2)` (the chord of an arc leaves the start
//! heading by half the turn; a straight walk has `dx = 0`).
//!
//! Every cycle but the first of a take is held to 0.5 degrees and 1 cm. The first steady cycle
//! starts where the walker's speed ramp ends, so the window of one cycle centred on its first
//! frame (over which motion-io measures the heading of travel) reaches half a cycle back into the
//! acceleration: the chord's midpoint by arc length then lies after that frame, and its start
//! heading leans into the turn by up to 1 degree.

use std::path::Path;

use motion_io::expmap::{exp_to_quat, quat_to_exp};
use motion_io::{CycleConfig, CycleReport, Motion, PoseLayout, parse_bvh, segment_cycles};
use xtask::fixtures::{self, PlannedTake, SEED};
use xtask::gait::{cycle_frequency, stride_length};
use xtask::rig::Rig;
use xtask::walker;

/// What the walker generated for one take's steady cycles.
struct Expected {
    /// Cycle duration, seconds.
    period: f64,
    /// Heading change over one cycle, radians.
    turn: f64,
    /// Length of the chord of one cycle's arc, metres.
    chord: f64,
}

impl Expected {
    fn of(p: &PlannedTake) -> Expected {
        let leg = Rig::new(p.spec.height_m).hip_height() / 100.0;
        let period = 1.0 / cycle_frequency(p.spec.speed, leg);
        let turn = p.spec.turn_rate_deg.to_radians() * period;
        let stride = stride_length(p.spec.speed, leg);
        // Chord of a circular arc of one stride: 2 R sin(theta / 2), R = stride / theta.
        let chord = if turn.abs() < 1e-9 {
            stride
        } else {
            2.0 * stride / turn * (0.5 * turn).sin()
        };
        Expected {
            period,
            turn,
            chord,
        }
    }
}

/// Largest errors over the checked cycles, for the failure messages and the printout.
#[derive(Default, Debug)]
struct Worst {
    duration_s: f64,
    turn_deg: f64,
    chord_rel: f64,
    dx_m: f64,
}

/// Turn (degrees) and `dx` (metres) tolerances of one cycle: loose for a take's first cycle when
/// its start heading window reaches into the speed ramp (module docs), strict otherwise.
fn tolerances(first_after_ramp: bool) -> (f64, f64) {
    if first_after_ramp {
        (2.0, 0.03)
    } else {
        (0.5, 0.01)
    }
}

/// Checks every kept cycle of `report` against `e`; `what` names the take in messages, `ramp`
/// says whether the first cycle's start window reaches into the speed ramp.
fn check_all(what: &str, report: &CycleReport, e: &Expected, ramp: bool, worst: &mut Worst) {
    for (k, c) in report.cycles.iter().enumerate() {
        let at = format!("{what} cycle {}..{}", c.first_frame, c.last_frame);
        let (turn_tol, dx_tol) = tolerances(ramp && k == 0);
        let dur = (c.duration() - e.period).abs();
        assert!(
            dur < 0.02,
            "{at}: {} s, expected {}",
            c.duration(),
            e.period
        );
        let turn = (c.controls.turn - e.turn).abs().to_degrees();
        assert!(
            turn < turn_tol,
            "{at}: turn {} deg, expected {} deg",
            c.controls.turn.to_degrees(),
            e.turn.to_degrees()
        );
        let d = c.controls.dx.hypot(c.controls.dz);
        let rel = (d - e.chord).abs() / e.chord;
        assert!(rel < 0.03, "{at}: displacement {d} m, expected {}", e.chord);
        let dx = (c.controls.dx - e.chord * (0.5 * e.turn).sin()).abs();
        assert!(
            dx < dx_tol,
            "{at}: dx {} m, expected {} m",
            c.controls.dx,
            e.chord * (0.5 * e.turn).sin()
        );
        assert!(c.controls.dz > 0.0, "{at}: moves forward");
        worst.duration_s = worst.duration_s.max(dur);
        worst.turn_deg = worst.turn_deg.max(turn);
        worst.chord_rel = worst.chord_rel.max(rel);
        worst.dx_m = worst.dx_m.max(dx);
    }
}

/// Frames `first..=last` of `m` as a new take.
fn cut(m: &Motion, first: usize, last: usize) -> Motion {
    let n = m.skeleton.channel_count();
    Motion {
        skeleton: m.skeleton.clone(),
        frame_time: m.frame_time,
        frames: m.frames[first * n..(last + 1) * n].to_vec(),
    }
}

/// Every fixture take, read back from its BVH text, with its plan and layout.
fn takes() -> Vec<(PlannedTake, Motion, PoseLayout)> {
    fixtures::plan(SEED)
        .into_iter()
        .map(|p| {
            let take = walker::generate(&p.spec).unwrap();
            let m = parse_bvh(&fixtures::bvh_text(&take.motion)).unwrap();
            let layout = PoseLayout::new(&m.skeleton, 100.0).unwrap();
            (p, m, layout)
        })
        .collect()
}

#[test]
fn segmentation_keeps_every_steady_cycle_with_its_controls() {
    let config = CycleConfig::default();
    let mut total = 0;
    let mut worst = Worst::default();
    for (p, m, layout) in takes() {
        let report = segment_cycles(&m, &layout, &config, Path::new(&p.file)).unwrap();
        // The take holds the accelerating first cycle (no left contact starts it inside the take)
        // and `steady_cycles` steady ones, all of which are kept: the last one too, thanks to the
        // half cycle of walking after it.
        assert_eq!(
            report.cycles.len(),
            p.spec.steady_cycles,
            "{}: cycles {:?}, dropped {:?}",
            p.file,
            report
                .cycles
                .iter()
                .map(|c| (c.first_frame, c.last_frame))
                .collect::<Vec<_>>(),
            report.dropped
        );
        total += report.cycles.len();
        check_all(&p.file, &report, &Expected::of(&p), true, &mut worst);
    }
    println!("worst errors over {total} cycles: {worst:?}");
    assert_eq!(total, 60, "{total} cycles over the set");
}

#[test]
fn headings_extrapolated_near_cut_take_ends_are_right() {
    // Cut each take so that the windows centred on its first and last kept cycles' end frames
    // reach past the take: motion-io then extrapolates the heading from inside the take.
    let config = CycleConfig::default();
    let mut checked = 0;
    let mut worst = Worst::default();
    for (p, m, layout) in takes() {
        let full = segment_cycles(&m, &layout, &config, Path::new(&p.file)).unwrap();
        let (first, last) = (&full.cycles[0], &full.cycles[full.cycles.len() - 1]);
        // A tenth of a cycle of margin at both ends (the contact detection needs a few frames).
        let margin = (last.frame_count() / 10).max(2);
        let (a, b) = (first.first_frame - margin, last.last_frame + margin);
        let cut_take = cut(&m, a, b);
        let what = format!("{} cut to {a}..={b}", p.file);
        let report = segment_cycles(&cut_take, &layout, &config, Path::new(&what)).unwrap();
        assert_eq!(
            report.cycles.len(),
            full.cycles.len(),
            "{what}: dropped {:?}",
            report.dropped
        );
        let (c0, c1) = (&report.cycles[0], &report.cycles[report.cycles.len() - 1]);
        let half = c1.frame_count() / 2;
        assert!(
            c0.first_frame < half && c1.last_frame + half > cut_take.frame_count() - 1,
            "{what}: the end cycles' windows fit inside the take, nothing extrapolated"
        );
        check_all(&what, &report, &Expected::of(&p), false, &mut worst);
        checked += report.cycles.len();
    }
    println!("worst errors over {checked} cycles of the cut takes: {worst:?}");
}

#[test]
fn takes_too_short_for_a_heading_drop_the_cycle_with_the_reason() {
    // One steady cycle cut out with a tenth of a cycle around it: 1.2 cycle lengths of track,
    // less than the 1.5 the extrapolating fit needs.
    let (p, m, layout) = takes().swap_remove(0);
    let config = CycleConfig::default();
    let full = segment_cycles(&m, &layout, &config, Path::new(&p.file)).unwrap();
    let c = &full.cycles[1];
    let margin = c.frame_count() / 10;
    let short = cut(&m, c.first_frame - margin, c.last_frame + margin);
    let report = segment_cycles(&short, &layout, &config, Path::new("short")).unwrap();
    assert!(report.cycles.is_empty(), "{:?}", report.cycles.len());
    assert_eq!(report.dropped.len(), 1);
    let reason = &report.dropped[0].reason;
    assert!(
        matches!(
            reason,
            motion_io::DropReason::HeadingWindowTruncated { frame, .. } if *frame == margin
        ),
        "{reason:?}"
    );
    assert!(
        reason
            .to_string()
            .starts_with("heading window truncated at take")
    );
}

#[test]
fn a_pelvis_yawed_against_the_walk_keeps_straight_walks_straight() {
    // Real performers hold the pelvis a few degrees off the walking direction (the hip line of
    // the Bandai-Namco straight walks is off by 2.4 degrees on average). Yaw the pelvis of the
    // straight takes by 5 degrees about the vertical: the controls follow the root's travel, so
    // they stay straight, and the canonical poses keep the posture (a 5 degree root yaw).
    let config = CycleConfig::default();
    let yaw = glam::DQuat::from_rotation_y(5f64.to_radians());
    let mut checked = 0;
    for (p, m, layout) in takes()
        .into_iter()
        .filter(|t| t.0.spec.turn_rate_deg == 0.0)
    {
        let mut poses = layout.poses_from_motion(&m).unwrap();
        for row in poses.chunks_exact_mut(layout.dof()) {
            let q = exp_to_quat(glam::DVec3::from_slice(&row[3..6]));
            row[3..6].copy_from_slice(&quat_to_exp(yaw * q).to_array());
        }
        let yawed = layout.motion_from_poses(&poses, m.frame_time).unwrap();
        let plain = segment_cycles(&m, &layout, &config, Path::new(&p.file)).unwrap();
        let report = segment_cycles(&yawed, &layout, &config, Path::new(&p.file)).unwrap();
        assert_eq!(report.cycles.len(), plain.cycles.len(), "{}", p.file);
        let root_yaw = |c: &motion_io::GaitCycle| {
            let f = exp_to_quat(glam::DVec3::from_slice(&c.poses[3..6])) * glam::DVec3::Z;
            f.x.atan2(f.z)
        };
        for (c, o) in report.cycles.iter().zip(&plain.cycles) {
            assert!(
                c.controls.dx.abs() < 0.01 && c.controls.turn.abs() < 0.5f64.to_radians(),
                "{} cycle {}..{}: {:?}",
                p.file,
                c.first_frame,
                c.last_frame,
                c.controls
            );
            let posture = (root_yaw(c) - root_yaw(o)).to_degrees();
            assert!(
                (posture - 5.0).abs() < 0.3,
                "{}: root yaw {posture} deg",
                p.file
            );
            checked += 1;
        }
    }
    assert!(checked >= 12, "{checked} cycles of straight takes");
}
