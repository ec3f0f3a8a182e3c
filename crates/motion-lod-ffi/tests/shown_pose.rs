//! A root-only walker's shown pose is the whole pose of its clip: a walk rewrites only the rows
//! its clip evaluates while the rest still hold the mean pose (`MlodWalker::mean_from`), so after
//! cycles with every joint the rows they evaluated must be back at the mean at the first root-only
//! frame. Compared bit for bit with `mlod_walker_pose` of a second walker prepared with the same
//! clip, over a walk whose detail goes from every joint to root only and back at every cycle,
//! with the foot lock on and off.

use std::ptr::null_mut;

use motion_lod_ffi::*;

use crate::common;

#[test]
fn root_only_frames_show_the_whole_pose_of_their_clip() {
    for foot_lock in [true, false] {
        walk_and_compare(foot_lock);
    }
}

fn walk_and_compare(foot_lock: bool) {
    let model = common::load_model();
    let common::ModelFacts {
        levels,
        animated,
        pose_len: p,
        lo,
        hi,
        ..
    } = common::model_facts(model);
    unsafe {
        let mut controls = lo;
        controls.dz = 0.5 * (lo.dz + hi.dz);
        controls.height = 0.5 * (lo.height + hi.height);
        let full = MlodDetail {
            level: 0,
            joints: animated as u32,
        };
        let root_only = MlodDetail {
            level: levels as u32 - 1,
            joints: 0,
        };
        let (mut walker, mut reference) = (null_mut(), null_mut());
        assert_eq!(mlod_walker_new(model, &mut walker), MlodStatus::Ok);
        assert_eq!(mlod_walker_new(model, &mut reference), MlodStatus::Ok);
        assert_eq!(mlod_walker_set_foot_lock(walker, foot_lock), MlodStatus::Ok);
        assert_eq!(
            mlod_walker_prepare(reference, model, &controls, root_only, null_mut()),
            MlodStatus::Ok
        );
        let mut state = MlodWalkerState::default();
        assert_eq!(
            mlod_walker_start(walker, model, &controls, full, 0.0, 0.0, 0.0, &mut state),
            MlodStatus::Ok
        );
        let (mut shown, mut expected) = (vec![0.0f32; p], vec![0.0f32; p]);
        let (mut compared, mut animated_cycles) = (0, 0);
        for _ in 0..600 {
            // The next cycle root only after a cycle with every joint, and back.
            let next = if state.cycle % 2 == 0 {
                root_only
            } else {
                full
            };
            assert_eq!(
                mlod_walker_advance(walker, model, 1.0 / 30.0, &controls, &next, &mut state),
                MlodStatus::Ok
            );
            if state.detail.joints > 0 {
                animated_cycles += usize::from(state.cycles_begun > 0);
                continue;
            }
            assert_eq!(
                mlod_walker_shown_pose(walker, model, shown.as_mut_ptr(), p),
                MlodStatus::Ok
            );
            assert_eq!(
                mlod_walker_pose(
                    reference,
                    model,
                    state.time_in_cycle_s,
                    expected.as_mut_ptr(),
                    p
                ),
                MlodStatus::Ok
            );
            let same = shown
                .iter()
                .zip(&expected)
                .all(|(a, b)| a.to_bits() == b.to_bits());
            assert!(
                same,
                "foot lock {foot_lock}, cycle {}: {shown:?} != {expected:?}",
                state.cycle
            );
            compared += 1;
        }
        assert!(
            compared > 100 && animated_cycles >= 3,
            "{compared} {animated_cycles}"
        );
        mlod_walker_free(walker);
        mlod_walker_free(reference);
        mlod_model_free(model);
    }
}
