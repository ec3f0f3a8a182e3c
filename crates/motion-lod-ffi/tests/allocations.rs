//! A walker allocates nothing after `mlod_walker_new`: starting, advancing across cycles with
//! controls and details that change, asking the camera for its detail and reading its local
//! rotations and joint transforms, nor a crowd stepped by `mlod_walkers_step`; counted by a global
//! allocator on this test's thread.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::ptr::{null, null_mut};

use motion_lod_ffi::*;

mod common;

/// The system allocator, counting the allocations of each thread.
struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

// SAFETY: forwards to the system allocator; the counter is a const-initialised thread local.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.with(|c| c.set(c.get() + 1));
        // SAFETY: per GlobalAlloc's contract.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: per GlobalAlloc's contract.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.with(|c| c.set(c.get() + 1));
        // SAFETY: per GlobalAlloc's contract.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn allocations() -> usize {
    ALLOCATIONS.with(Cell::get)
}

#[test]
fn walking_allocates_nothing_after_creation() {
    let model = common::load_model();
    unsafe {
        let (mut levels, mut joints, mut animated) = (0, 0, 0);
        assert_eq!(
            mlod_model_sizes(model, &mut levels, &mut joints, &mut animated, null_mut()),
            MlodStatus::Ok
        );
        let (mut lo, mut hi) = (MlodControls::default(), MlodControls::default());
        assert_eq!(
            mlod_model_control_range(model, &mut lo, &mut hi),
            MlodStatus::Ok
        );
        let camera = common::camera_behind_origin();
        let mut walker: *mut MlodWalker = null_mut();
        assert_eq!(mlod_walker_new(model, &mut walker), MlodStatus::Ok);
        let mut rotations = vec![MlodQuat::default(); joints];
        let mut transforms = vec![MlodJointTransform::default(); joints];
        // A failed call first: its message is cleared by the next success (which may allocate
        // once to do so).
        assert_eq!(
            mlod_walker_advance(walker, model, 0.1, null(), null(), null_mut()),
            MlodStatus::NotPrepared
        );
        let mut detail = MlodDetail::default();
        assert_eq!(
            mlod_model_detail_at(model, 1.0, &mut detail),
            MlodStatus::Ok
        );

        // Allocated before counting starts.
        let mut details = Vec::with_capacity(200);
        let before = allocations();
        let mut state = MlodWalkerState::default();
        let first = MlodControls {
            turn: hi.turn,
            ..lo
        };
        assert_eq!(
            mlod_walker_start(walker, model, &first, detail, 0.0, 0.0, 0.0, &mut state),
            MlodStatus::Ok
        );
        for f in 0..150u32 {
            let mut visible = false;
            assert_eq!(
                mlod_walker_detail_from_camera(
                    walker,
                    model,
                    &camera,
                    1.0,
                    &mut detail,
                    &mut visible
                ),
                MlodStatus::Ok
            );
            // Every fifth frame the lowest detail, to change details between cycles.
            if f % 5 == 0 {
                detail = MlodDetail {
                    level: levels as u32 - 1,
                    joints: (animated / 2) as u32,
                };
            }
            let u = (f % 7) as f32 / 6.0;
            let next = MlodControls {
                dx: lo.dx + (hi.dx - lo.dx) * u,
                dz: lo.dz + (hi.dz - lo.dz) * u,
                turn: hi.turn - (hi.turn - lo.turn) * u,
                height: lo.height + (hi.height - lo.height) * u,
                ..lo
            };
            assert_eq!(
                mlod_walker_advance(walker, model, 1.0 / 30.0, &next, &detail, &mut state),
                MlodStatus::Ok
            );
            assert_eq!(
                mlod_walker_local_rotations(walker, model, rotations.as_mut_ptr(), joints),
                MlodStatus::Ok
            );
            assert_eq!(
                mlod_walker_joint_transforms(walker, model, transforms.as_mut_ptr(), joints),
                MlodStatus::Ok
            );
            details.push((state.detail.level, state.detail.joints));
        }
        let during = allocations() - before;
        assert!(state.cycle >= 3, "{state:?}");
        details.sort();
        details.dedup();
        assert!(details.len() >= 2, "{details:?}");
        assert!(state.foot_locked);
        assert_eq!(during, 0, "allocations while walking");

        mlod_walker_free(walker);
        mlod_model_free(model);
    }
}

/// `mlod_walkers_step` allocates nothing either: a crowd stepped across cycles (clips built in one
/// walker's scratch for all) with a camera that gives walkers in view joints and those behind it none.
#[test]
fn crowd_steps_allocate_nothing() {
    let model = common::load_model();
    unsafe {
        let (mut lo, mut hi) = (MlodControls::default(), MlodControls::default());
        assert_eq!(
            mlod_model_control_range(model, &mut lo, &mut hi),
            MlodStatus::Ok
        );
        let camera = common::camera_behind_origin();
        let n = 40;
        let mut walkers: Vec<*mut MlodWalker> = vec![null_mut(); n];
        let mut controls = vec![lo; n];
        for (i, c) in controls.iter_mut().enumerate() {
            let u = (i % 5) as f32 / 4.0;
            c.dz = lo.dz + (hi.dz - lo.dz) * u;
            c.height = lo.height + (hi.height - lo.height) * u;
        }
        let mut states = vec![MlodWalkerState::default(); n];
        let mut visible = vec![false; n];
        let mut detail = MlodDetail::default();
        assert_eq!(
            mlod_model_detail_at(model, 1.0, &mut detail),
            MlodStatus::Ok
        );
        for (i, w) in walkers.iter_mut().enumerate() {
            assert_eq!(mlod_walker_new(model, w), MlodStatus::Ok);
            // A row of walkers 8 m apart along the camera's view, the first ten behind it.
            assert_eq!(
                mlod_walker_start(
                    *w,
                    model,
                    &controls[i],
                    detail,
                    0.0,
                    8.0 * (i as f64 - 10.0),
                    0.0,
                    &mut states[i]
                ),
                MlodStatus::Ok
            );
        }
        let before = allocations();
        for _ in 0..150 {
            assert_eq!(
                mlod_walkers_step(
                    walkers.as_ptr(),
                    n,
                    model,
                    &camera,
                    1.0,
                    1.0 / 30.0,
                    controls.as_ptr(),
                    states.as_mut_ptr(),
                    visible.as_mut_ptr(),
                ),
                MlodStatus::Ok
            );
        }
        let during = allocations() - before;
        assert!(states.iter().all(|s| s.cycle >= 3), "{:?}", states[0]);
        assert!(states.iter().any(|s| s.detail.joints > 0));
        assert!(states.iter().any(|s| s.detail.joints == 0));
        assert_eq!(during, 0, "allocations while stepping the crowd");
        for w in walkers {
            mlod_walker_free(w);
        }
        mlod_model_free(model);
    }
}
