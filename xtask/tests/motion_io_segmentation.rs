//! The purpose of the fixtures: `motion_io`'s contact detection and cycle segmentation, run with
//! their default settings on the generated takes, find the steady two-step cycles, and the
//! cycles' controls match the generating parameters.

use std::path::Path;

use xtask::fixtures::{self, SEED};
use xtask::gait::{cycle_frequency, stride_length};
use xtask::rig::Rig;
use xtask::walker;

#[test]
fn segmentation_finds_the_steady_cycles_with_their_controls() {
    let mut total = 0;
    for p in fixtures::plan(SEED) {
        let take = walker::generate(&p.spec).unwrap();
        let m = motion_io::parse_bvh(&fixtures::bvh_text(&take.motion)).unwrap();
        let layout = motion_io::PoseLayout::new(&m.skeleton, 100.0).unwrap();
        let config = motion_io::CycleConfig::default();
        let report = motion_io::segment_cycles(&m, &layout, &config, Path::new(&p.file)).unwrap();
        let n = report.cycles.len();
        assert!(
            n >= 3,
            "{}: {n} cycles found, dropped {:?}",
            p.file,
            report.dropped
        );
        total += n;
        let leg = Rig::new(p.spec.height_m).hip_height() / 100.0;
        let period = 1.0 / cycle_frequency(p.spec.speed, leg);
        let omega = p.spec.turn_rate_deg.to_radians();
        // Chord of a circular arc of one stride: 2 R sin(theta / 2), R = stride / theta.
        let theta = omega * period;
        let stride = stride_length(p.spec.speed, leg);
        let chord = if theta.abs() < 1e-9 {
            stride
        } else {
            2.0 * stride / theta * (0.5 * theta).sin()
        };
        // The first and last cycles' headings are estimated near the ends of the take; check the
        // interior ones.
        for c in &report.cycles[1..n - 1] {
            assert!(
                (c.duration() - period).abs() < 0.02,
                "{}: cycle of {} s, expected {period}",
                p.file,
                c.duration()
            );
            let turn = c.controls.turn;
            assert!(
                (turn - theta).abs() < 2f64.to_radians(),
                "{}: turn {turn}, expected {theta}",
                p.file
            );
            let d = c.controls.dx.hypot(c.controls.dz);
            assert!(
                (d - chord).abs() < 0.03 * chord,
                "{}: displacement {d} m, expected {chord}",
                p.file
            );
            assert!(
                c.controls.dz > 0.0 && c.controls.dx * omega >= -1e-3,
                "{}: moves forward, drifts into the turn",
                p.file
            );
        }
    }
    assert!((45..=120).contains(&total), "{total} cycles over the set");
}
