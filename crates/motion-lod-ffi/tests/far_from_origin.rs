//! Walker world frames in double precision (issue 35): an hour's walk that starts 1 km from the
//! origin holds the runtime's bound. Two walkers take the same walk, one started at the origin and
//! one 1 km away with the same heading, the same controls and details every cycle, the foot lock
//! and the inertialized seams on:
//!
//! - in the cycle frame, their shown poses agree within 1e-5 (metres for the root, radians for
//!   the rotations) at every frame: the foot lock, which follows each foot in the world, sees the
//!   same motion 1 km away;
//! - in the world, the far walker's cycle frames and root are the near walker's moved by 1 km,
//!   within 1 mm per simulated minute.
//!
//! The pose bound is what fails in single precision: with the foot lock fed the feet's world
//! points rounded to floats, as before ABI 5, the poses differ by 2.2e-5 at the first frame
//! (measured, 2026-11-27). The same root motions chained in single precision from 1 km are
//! measured beside them and reported (3.2 mm off after the hour, against 4e-12 m in double).

use std::ptr::null_mut;

use motion_lod_ffi::*;

use crate::common;

const FPS: f64 = 30.0;
const SECONDS: f64 = 3600.0;
/// The far walker's start: 1 km from the origin.
const FAR: [f64; 2] = [800.0, -600.0];
const HEADING: f64 = 0.4;

/// Controls and detail of cycle `k`: speed, sidestep and turn sweep the model's ranges (a
/// meandering path), and every fifth cycle is at the coarsest level with half the joints.
fn cycle_inputs(
    lo: &MlodControls,
    hi: &MlodControls,
    animated: u32,
    k: u64,
) -> (MlodControls, MlodDetail) {
    let u = |n: u64, m: u64| ((k * n) % m) as f32 / (m - 1) as f32;
    let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
    let controls = MlodControls {
        dx: lerp(lo.dx, hi.dx, 0.3 + 0.4 * u(3, 7)),
        dz: lerp(lo.dz, hi.dz, 0.2 + 0.6 * u(5, 11)),
        turn: lerp(lo.turn, hi.turn, 0.25 + 0.5 * u(7, 13)),
        height: lerp(lo.height, hi.height, 0.5),
        ..MlodControls::default()
    };
    let detail = if k % 5 == 4 {
        MlodDetail {
            level: 1,
            joints: animated / 2,
        }
    } else {
        MlodDetail {
            level: 0,
            joints: animated,
        }
    };
    (controls, detail)
}

#[test]
fn an_hour_one_kilometre_away_walks_as_at_the_origin() {
    let model = common::load_model();
    // SAFETY: live model and walkers created here; writable outputs; buffers of `p` floats.
    let common::ModelFacts {
        levels,
        animated,
        pose_len: p,
        lo,
        hi,
        ..
    } = common::model_facts(model);
    assert!(levels >= 2);
    unsafe {
        let animated = animated as u32;
        let (mut near, mut far) = (null_mut(), null_mut());
        assert_eq!(mlod_walker_new(model, &mut near), MlodStatus::Ok);
        assert_eq!(mlod_walker_new(model, &mut far), MlodStatus::Ok);
        let (c0, d0) = cycle_inputs(&lo, &hi, animated, 0);
        let (mut sn, mut sf) = (MlodWalkerState::default(), MlodWalkerState::default());
        assert_eq!(
            mlod_walker_start(near, model, &c0, d0, 0.0, 0.0, HEADING, &mut sn),
            MlodStatus::Ok
        );
        assert_eq!(
            mlod_walker_start(far, model, &c0, d0, FAR[0], FAR[1], HEADING, &mut sf),
            MlodStatus::Ok
        );
        let (mut pn, mut pf) = (vec![0.0f32; p], vec![0.0f32; p]);
        // The near walker's cycle frames chained again in single precision from the far start.
        let mut single = [FAR[0] as f32, FAR[1] as f32, HEADING as f32];
        let mut last_near = (sn.cycle_x, sn.cycle_z, sn.heading);
        let (mut worst_pose, mut worst_world, mut worst_single) = (0.0f32, 0.0f64, 0.0f64);
        let frames = (SECONDS * FPS) as usize;
        for f in 1..=frames {
            let (c, d) = cycle_inputs(&lo, &hi, animated, sn.cycle + 1);
            assert_eq!(
                mlod_walker_advance(near, model, 1.0 / FPS, &c, &d, &mut sn),
                MlodStatus::Ok
            );
            assert_eq!(
                mlod_walker_advance(far, model, 1.0 / FPS, &c, &d, &mut sf),
                MlodStatus::Ok
            );
            assert_eq!((sn.cycle, sn.detail), (sf.cycle, sf.detail), "frame {f}");
            assert!(
                sf.foot_locked,
                "frame {f}: the far walker's feet are locked"
            );
            assert_eq!(
                mlod_walker_shown_pose(near, model, pn.as_mut_ptr(), p),
                MlodStatus::Ok
            );
            assert_eq!(
                mlod_walker_shown_pose(far, model, pf.as_mut_ptr(), p),
                MlodStatus::Ok
            );
            let pose = pn
                .iter()
                .zip(&pf)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0f32, f32::max);
            assert!(
                pose <= 1e-5,
                "frame {f}: the poses in the cycle frame differ by {pose}"
            );
            worst_pose = worst_pose.max(pose);
            // The world: 1 mm per simulated minute.
            let minutes = f as f64 / FPS / 60.0;
            let moved = [
                (sf.cycle_x - FAR[0]) - sn.cycle_x,
                (sf.cycle_z - FAR[1]) - sn.cycle_z,
                (sf.root_position[0] - FAR[0]) - sn.root_position[0],
                (sf.root_position[2] - FAR[1]) - sn.root_position[2],
            ];
            let world = moved.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            assert!(
                world <= 1e-3 * minutes,
                "frame {f} ({minutes:.1} min): the far walk is {world} m off the near one moved by 1 km"
            );
            assert_eq!(
                sf.heading.to_bits(),
                sn.heading.to_bits(),
                "frame {f}: headings"
            );
            worst_world = worst_world.max(world);
            if sn.cycles_begun > 0 {
                // The near walker's root motion of the cycle that ended (in its frame), chained in
                // single precision.
                let (x0, z0, h0) = last_near;
                let (dx_w, dz_w) = (sn.cycle_x - x0, sn.cycle_z - z0);
                let (s, c) = h0.sin_cos();
                let (dx, dz) = ((dx_w * c - dz_w * s) as f32, (dx_w * s + dz_w * c) as f32);
                let turn = lod_policy::wrap_angle_f64(sn.heading - h0) as f32;
                let (s, c) = single[2].sin_cos();
                single = [
                    single[0] + dx * c + dz * s,
                    single[1] - dx * s + dz * c,
                    lod_policy::wrap_angle(single[2] + turn),
                ];
                last_near = (sn.cycle_x, sn.cycle_z, sn.heading);
                let off = ((f64::from(single[0]) - sf.cycle_x).abs())
                    .max((f64::from(single[1]) - sf.cycle_z).abs());
                worst_single = worst_single.max(off);
            }
        }
        eprintln!(
            "{} cycles 1 km from the origin: poses within {worst_pose:e}, world within \
             {worst_world:e} m; chained in single precision, {worst_single:e} m off",
            sn.cycle
        );
        assert!(
            sn.cycle > 2000,
            "an hour walks thousands of cycles: {}",
            sn.cycle
        );
        mlod_walker_free(near);
        mlod_walker_free(far);
        mlod_model_free(model);
    }
}
