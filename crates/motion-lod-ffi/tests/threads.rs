//! The header's thread rules, held: one model shared by four threads at once, each advancing its own
//! walkers, gives every walker the bits it gets walked alone on one thread, and each thread's
//! `mlod_last_error` is its own failure's message, whatever the others' calls do.

use std::ffi::CStr;
use std::ptr::{null, null_mut};

use motion_lod_ffi::*;

use crate::common;

const THREADS: usize = 4;
const FRAMES: usize = 300;

/// Walks the walker of `lane` (its own controls and a detail that changes each cycle) for
/// [`FRAMES`] frames and returns every joint transform of every frame, as bits.
///
/// # Safety
/// `model` is a live model no call frees while this runs.
unsafe fn walk(model: *const MlodModel, lane: usize) -> Vec<u32> {
    let facts = common::model_facts(model);
    let t = (lane as f32 + 0.5) / THREADS as f32;
    let mut controls = facts.lo;
    controls.dz = facts.lo.dz + t * (facts.hi.dz - facts.lo.dz);
    controls.turn = facts.lo.turn + t * (facts.hi.turn - facts.lo.turn);
    controls.height = 0.5 * (facts.lo.height + facts.hi.height);
    let mut out = Vec::with_capacity(FRAMES * facts.joints * 7);
    let mut transforms = vec![MlodJointTransform::default(); facts.joints];
    unsafe {
        let mut walker = null_mut();
        assert_eq!(mlod_walker_new(model, &mut walker), MlodStatus::Ok);
        let detail = |cycle: u64| MlodDetail {
            level: ((cycle as usize + lane) % facts.levels) as u32,
            joints: facts.animated as u32,
        };
        let mut state = MlodWalkerState::default();
        assert_eq!(
            mlod_walker_start(
                walker,
                model,
                &controls,
                detail(0),
                0.0,
                0.0,
                0.0,
                &mut state
            ),
            MlodStatus::Ok
        );
        for _ in 0..FRAMES {
            let next = detail(state.cycle + 1);
            assert_eq!(
                mlod_walker_advance(walker, model, 1.0 / 30.0, &controls, &next, &mut state),
                MlodStatus::Ok
            );
            assert_eq!(
                mlod_walker_joint_transforms(
                    walker,
                    model,
                    transforms.as_mut_ptr(),
                    transforms.len()
                ),
                MlodStatus::Ok
            );
            for x in &transforms {
                out.extend(x.rotation.iter().chain(&x.translation).map(|v| v.to_bits()));
            }
        }
        mlod_walker_free(walker);
    }
    out
}

/// Makes a call fail, and returns this thread's last error.
fn fail_and_read() -> String {
    // SAFETY: a null model is refused with a status, never dereferenced.
    let status = unsafe { mlod_walker_new(null(), &mut null_mut()) };
    assert_ne!(status, MlodStatus::Ok);
    // SAFETY: the pointer is valid until this thread's next call.
    unsafe { CStr::from_ptr(mlod_last_error()) }
        .to_string_lossy()
        .into_owned()
}

#[test]
fn threads_sharing_one_model_walk_as_one_thread_does() {
    let model = common::load_model();
    // SAFETY: the model lives until freed at the end, after every thread has joined.
    let alone: Vec<Vec<u32>> = (0..THREADS)
        .map(|lane| unsafe { walk(model, lane) })
        .collect();
    let shared = model as usize;
    let together: Vec<(Vec<u32>, String, String)> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..THREADS)
            .map(|lane| {
                s.spawn(move || {
                    let model = shared as *const MlodModel;
                    let failed = fail_and_read();
                    // SAFETY: as above; the scope joins before the model is freed.
                    let bits = unsafe { walk(model, lane) };
                    // Success clears this thread's message, not the others'.
                    let after = unsafe { CStr::from_ptr(mlod_last_error()) }
                        .to_string_lossy()
                        .into_owned();
                    (bits, failed, after)
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    for (lane, ((bits, failed, after), alone)) in together.iter().zip(&alone).enumerate() {
        assert!(
            bits == alone,
            "walker {lane} differs when threads share the model"
        );
        assert!(failed.contains("mlod_walker_new"), "{failed}");
        assert!(after.is_empty(), "{after}");
    }
    // The lanes differ from each other, so the comparison above can fail.
    assert!(alone[0] != alone[1]);
    // SAFETY: no walker of it is left and no thread runs.
    unsafe { mlod_model_free(model) };
}
