//! Every misuse of the C ABI is a status code with a message naming what was wrong, never a crash.

use std::ffi::CStr;
use std::ptr::{null, null_mut};

use motion_lod_ffi::*;

use crate::common;

use common::model_bytes;

fn message() -> String {
    // SAFETY: mlod_last_error returns a valid NUL-terminated string for this thread.
    unsafe { CStr::from_ptr(mlod_last_error()) }
        .to_string_lossy()
        .into_owned()
}

#[test]
fn misuse_is_a_status_with_a_message() {
    let bytes = model_bytes();
    unsafe {
        let mut model: *mut MlodModel = null_mut();
        assert_eq!(
            mlod_model_from_bytes(bytes.as_ptr(), bytes.len(), &mut model),
            MlodStatus::Ok
        );
        assert!(!model.is_null());
        assert_eq!(message(), "");

        // Null pointers.
        assert_eq!(
            mlod_model_from_bytes(null(), 10, &mut model as *mut _),
            MlodStatus::NullPointer
        );
        assert!(model.is_null(), "the output is cleared on failure");
        assert!(message().contains("bytes is null"), "{}", message());
        assert_eq!(
            mlod_model_from_bytes(bytes.as_ptr(), bytes.len(), &mut model),
            MlodStatus::Ok
        );
        assert_eq!(
            mlod_model_sizes(null(), null_mut(), null_mut(), null_mut(), null_mut()),
            MlodStatus::NullPointer
        );

        // Damaged bytes: every truncation is refused.
        for cut in [0, 10, 24, bytes.len() / 2, bytes.len() - 1] {
            let mut other: *mut MlodModel = null_mut();
            assert_eq!(
                mlod_model_from_bytes(bytes.as_ptr(), cut, &mut other),
                MlodStatus::InvalidModel,
                "cut at {cut}"
            );
            assert!(other.is_null());
        }
        let path = c"/no/such/model.mlod";
        let mut other: *mut MlodModel = null_mut();
        assert_eq!(mlod_model_load(path.as_ptr(), &mut other), MlodStatus::Io);
        assert!(message().contains("/no/such/model.mlod"), "{}", message());

        let common::ModelFacts {
            levels,
            joints,
            animated,
            pose_len,
            lo,
            hi,
        } = common::model_facts(model);
        assert_eq!(pose_len, 7 + 3 * animated);
        assert!(levels >= 3 && joints > animated && animated > 0);

        // Joint names: truncated to the buffer, length reported, out of range refused.
        let mut name = [0 as std::ffi::c_char; 4];
        let (mut len, mut parent) = (0usize, 0i32);
        assert_eq!(
            mlod_model_joint(model, 1, name.as_mut_ptr(), 4, &mut len, &mut parent),
            MlodStatus::Ok
        );
        assert_eq!(CStr::from_ptr(name.as_ptr()).to_bytes().len(), len.min(3));
        assert!(parent >= 0);
        assert_eq!(
            mlod_model_joint(model, joints, null_mut(), 0, null_mut(), null_mut()),
            MlodStatus::InvalidArgument
        );
        assert!(message().contains("out of range"), "{}", message());

        // A walker: not prepared, bad controls and levels, short buffers, another model.
        let mut walker: *mut MlodWalker = null_mut();
        assert_eq!(mlod_walker_new(model, &mut walker), MlodStatus::Ok);
        let mut pose = vec![0.0f32; pose_len];
        assert_eq!(
            mlod_walker_pose(walker, model, 0.0, pose.as_mut_ptr(), pose.len()),
            MlodStatus::NotPrepared
        );
        let nan = MlodControls {
            turn: f32::NAN,
            ..lo
        };
        let detail = MlodDetail {
            level: 0,
            joints: animated as u32,
        };
        assert_eq!(
            mlod_walker_prepare(walker, model, &nan, detail, null_mut()),
            MlodStatus::InvalidArgument
        );
        assert!(message().contains("turn"), "{}", message());
        let far = MlodDetail {
            level: levels as u32,
            joints: 0,
        };
        assert_eq!(
            mlod_walker_prepare(walker, model, &lo, far, null_mut()),
            MlodStatus::InvalidArgument
        );
        let mut cycle = MlodCycle::default();
        assert_eq!(
            mlod_walker_prepare(walker, model, &hi, detail, &mut cycle),
            MlodStatus::Ok
        );
        assert!(cycle.duration_s > 0.3 && cycle.dz > 0.5, "{cycle:?}");
        assert_eq!(
            mlod_walker_pose(walker, model, f64::NAN, pose.as_mut_ptr(), pose.len()),
            MlodStatus::InvalidArgument
        );
        assert_eq!(
            mlod_walker_pose(walker, model, 0.1, pose.as_mut_ptr(), pose.len() - 1),
            MlodStatus::BufferTooSmall
        );
        assert!(
            message().contains(&format!("{pose_len} are needed")),
            "{}",
            message()
        );
        assert_eq!(
            mlod_walker_pose(walker, model, 0.1, pose.as_mut_ptr(), pose.len()),
            MlodStatus::Ok
        );
        assert!(pose.iter().all(|v| v.is_finite()));
        let mut transforms = vec![MlodJointTransform::default(); joints];
        assert_eq!(
            mlod_walker_joint_transforms(walker, model, transforms.as_mut_ptr(), joints - 1),
            MlodStatus::BufferTooSmall
        );
        assert_eq!(
            mlod_walker_joint_transforms(walker, model, transforms.as_mut_ptr(), joints),
            MlodStatus::Ok
        );
        let q = transforms[1].rotation;
        let norm = q.iter().map(|v| v * v).sum::<f32>().sqrt();
        assert!((norm - 1.0).abs() < 1e-4, "unit rotations: {q:?}");

        let mut second: *mut MlodModel = null_mut();
        assert_eq!(
            mlod_model_from_bytes(bytes.as_ptr(), bytes.len(), &mut second),
            MlodStatus::Ok
        );
        assert_eq!(
            mlod_walker_prepare(walker, second, &lo, detail, null_mut()),
            MlodStatus::InvalidArgument
        );
        assert!(message().contains("another model"), "{}", message());

        // The policy: near is full detail, far is root only; a bad distance is refused.
        let mut near = MlodDetail::default();
        let mut distant = MlodDetail::default();
        assert_eq!(mlod_model_detail_at(model, 2.0, &mut near), MlodStatus::Ok);
        assert_eq!(
            mlod_model_detail_at(model, 1e5, &mut distant),
            MlodStatus::Ok
        );
        assert_eq!(near.level, 0);
        assert!(distant.joints < near.joints, "{near:?} {distant:?}");
        assert_eq!(
            mlod_model_detail_at(model, -1.0, &mut near),
            MlodStatus::InvalidArgument
        );

        mlod_walker_free(walker);
        mlod_walker_free(null_mut());
        mlod_model_free(second);
        mlod_model_free(model);
        mlod_model_free(null_mut());
    }
}

/// Mid-range controls of a model ([`common::model_facts`]).
fn middle(facts: &common::ModelFacts) -> MlodControls {
    let (lo, hi) = (facts.lo, facts.hi);
    MlodControls {
        dx: 0.5 * (lo.dx + hi.dx),
        dz: 0.5 * (lo.dz + hi.dz),
        turn: 0.5 * (lo.turn + hi.turn),
        height: 0.5 * (lo.height + hi.height),
        ..MlodControls::default()
    }
}

/// A camera at 1.7 m looking along +z.
fn camera() -> MlodCamera {
    MlodCamera {
        position: [0.0, 1.7, 0.0],
        direction: [0.0, 0.0, 1.0],
        fov_y: 1.0,
        aspect: 16.0 / 9.0,
        image_height_px: 1080.0,
        near_m: 0.1,
        far_m: 200.0,
    }
}

#[test]
fn the_version_is_the_crate_s_and_the_abi_the_header_s() {
    // SAFETY: a static NUL-terminated string.
    let version = unsafe { CStr::from_ptr(mlod_version()) };
    assert_eq!(version.to_str(), Ok(env!("CARGO_PKG_VERSION")));
    assert_eq!(mlod_abi_version(), MLOD_ABI_VERSION);
    let header = include_str!("../include/motion_lod.h");
    assert!(
        header.contains(&format!("#define MLOD_ABI_VERSION {MLOD_ABI_VERSION}\n")),
        "the header's ABI version is the library's"
    );
}

#[test]
fn walking_misuse_is_a_status_with_a_message() {
    let model = common::load_model();
    let second = common::load_model();
    let facts = common::model_facts(model);
    let (levels, joints, animated) = (facts.levels, facts.joints, facts.animated);
    let controls = middle(&facts);
    let full = MlodDetail {
        level: 0,
        joints: animated as u32,
    };
    unsafe {
        let mut walker: *mut MlodWalker = null_mut();
        assert_eq!(mlod_walker_new(model, &mut walker), MlodStatus::Ok);
        let mut state = MlodWalkerState::default();
        let mut rotations = vec![MlodQuat::default(); joints];
        let cam = camera();
        let mut detail = MlodDetail::default();
        let mut visible = false;

        // Before the start: nothing to advance, no pose, no root to see.
        assert_eq!(
            mlod_walker_advance(walker, model, 0.1, null(), null(), &mut state),
            MlodStatus::NotPrepared
        );
        assert!(message().contains("mlod_walker_start"), "{}", message());
        assert_eq!(
            mlod_walker_local_rotations(walker, model, rotations.as_mut_ptr(), joints),
            MlodStatus::NotPrepared
        );
        assert_eq!(
            mlod_walker_detail_from_camera(walker, model, &cam, 1.0, &mut detail, &mut visible),
            MlodStatus::NotPrepared
        );

        // Start: null pointers, NaN controls or position, a level the model lacks, another model.
        let start = |w, m, c, d: MlodDetail, x: f64, state: *mut MlodWalkerState| {
            mlod_walker_start(w, m, c, d, x, 2.0, 0.5, state)
        };
        assert_eq!(
            start(null_mut(), model, &controls, full, 0.0, null_mut()),
            MlodStatus::NullPointer
        );
        assert!(message().contains("walker is null"), "{}", message());
        assert_eq!(
            start(walker, null(), &controls, full, 0.0, null_mut()),
            MlodStatus::NullPointer
        );
        assert_eq!(
            start(walker, model, null(), full, 0.0, null_mut()),
            MlodStatus::NullPointer
        );
        assert!(message().contains("controls is null"), "{}", message());
        let nan = MlodControls {
            height: f32::NAN,
            ..controls
        };
        assert_eq!(
            start(walker, model, &nan, full, 0.0, null_mut()),
            MlodStatus::InvalidArgument
        );
        assert!(message().contains("height"), "{}", message());
        assert_eq!(
            start(walker, model, &controls, full, f64::INFINITY, null_mut()),
            MlodStatus::InvalidArgument
        );
        assert!(message().contains("x is inf"), "{}", message());
        let missing = MlodDetail {
            level: levels as u32,
            joints: 0,
        };
        assert_eq!(
            start(walker, model, &controls, missing, 0.0, null_mut()),
            MlodStatus::InvalidArgument
        );
        assert!(message().contains("out of range"), "{}", message());
        assert_eq!(
            start(walker, second, &controls, full, 0.0, null_mut()),
            MlodStatus::InvalidArgument
        );
        assert!(message().contains("another model"), "{}", message());
        assert_eq!(
            mlod_walker_advance(walker, model, 0.1, null(), null(), &mut state),
            MlodStatus::NotPrepared,
            "failed starts start nothing"
        );

        assert_eq!(
            start(walker, model, &controls, full, 1.0, &mut state),
            MlodStatus::Ok
        );
        assert_eq!(message(), "");
        assert_eq!((state.cycle, state.time_in_cycle_s), (0, 0.0));
        assert_eq!(
            (state.cycle_x, state.cycle_z, state.heading),
            (1.0, 2.0, 0.5)
        );
        assert_eq!(state.detail, full);
        assert!(state.foot_locked, "the fixture model knows its feet");
        let started = state;

        // Advance: null pointers, NaN or out-of-range steps, NaN controls, a level the model
        // lacks, another model; none of them changes the walk.
        assert_eq!(
            mlod_walker_advance(null_mut(), model, 0.1, null(), null(), &mut state),
            MlodStatus::NullPointer
        );
        assert_eq!(
            mlod_walker_advance(walker, null(), 0.1, null(), null(), &mut state),
            MlodStatus::NullPointer
        );
        for dt in [f64::NAN, f64::INFINITY, 0.0, -0.1, MLOD_MAX_STEP_S * 1.5] {
            assert_eq!(
                mlod_walker_advance(walker, model, dt, null(), null(), &mut state),
                MlodStatus::InvalidArgument,
                "step {dt}"
            );
            assert!(message().contains("step"), "{}", message());
        }
        let nan_turn = MlodControls {
            turn: f32::NAN,
            ..controls
        };
        assert_eq!(
            mlod_walker_advance(walker, model, 0.1, &nan_turn, null(), &mut state),
            MlodStatus::InvalidArgument
        );
        assert!(message().contains("next_controls"), "{}", message());
        assert!(message().contains("turn"), "{}", message());
        assert_eq!(
            mlod_walker_advance(walker, model, 0.1, null(), &missing, &mut state),
            MlodStatus::InvalidArgument
        );
        assert!(message().contains("next_detail"), "{}", message());
        assert_eq!(
            mlod_walker_advance(walker, second, 0.1, null(), null(), &mut state),
            MlodStatus::InvalidArgument
        );
        assert!(message().contains("another model"), "{}", message());
        assert_eq!(state, started, "failed calls leave the state alone");

        // The refused calls changed nothing: this walker and a fresh one walk alike.
        let mut fresh: *mut MlodWalker = null_mut();
        assert_eq!(mlod_walker_new(model, &mut fresh), MlodStatus::Ok);
        let mut fresh_state = MlodWalkerState::default();
        assert_eq!(
            mlod_walker_start(
                fresh,
                model,
                &controls,
                full,
                1.0,
                2.0,
                0.5,
                &mut fresh_state
            ),
            MlodStatus::Ok
        );
        let mut crossed = false;
        for _ in 0..90 {
            assert_eq!(
                mlod_walker_advance(walker, model, 1.0 / 30.0, null(), null(), &mut state),
                MlodStatus::Ok
            );
            assert_eq!(
                mlod_walker_advance(fresh, model, 1.0 / 30.0, &controls, &full, &mut fresh_state),
                MlodStatus::Ok
            );
            assert_eq!(state, fresh_state);
            crossed |= state.cycles_begun == 1;
            assert!(state.time_in_cycle_s < state.cycle_duration_s);
        }
        assert!(crossed && state.cycle >= 2, "{state:?}");

        // The root's world rotation is the cycle frame's heading times its local rotation.
        assert_eq!(
            mlod_walker_local_rotations(walker, model, rotations.as_mut_ptr(), joints - 1),
            MlodStatus::BufferTooSmall
        );
        assert!(
            message().contains(&format!("{joints} are needed")),
            "{}",
            message()
        );
        assert_eq!(
            mlod_walker_local_rotations(walker, model, null_mut(), joints),
            MlodStatus::NullPointer
        );
        assert_eq!(
            mlod_walker_local_rotations(walker, second, rotations.as_mut_ptr(), joints),
            MlodStatus::InvalidArgument
        );
        assert_eq!(
            mlod_walker_local_rotations(walker, model, rotations.as_mut_ptr(), joints),
            MlodStatus::Ok
        );
        for q in &rotations {
            let norm = (q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w).sqrt();
            assert!((norm - 1.0).abs() < 1e-4, "unit rotations: {q:?}");
        }
        let mut root = joints;
        assert_eq!(mlod_model_root_joint(model, &mut root), MlodStatus::Ok);
        assert_eq!(
            mlod_model_root_joint(model, null_mut()),
            MlodStatus::NullPointer
        );
        let mut parent = 0i32;
        assert_eq!(
            mlod_model_joint(model, root, null_mut(), 0, null_mut(), &mut parent),
            MlodStatus::Ok
        );
        assert!(root < joints && parent < root as i32);
        let quat = |q: MlodQuat| lod_policy::glam::Quat::from_xyzw(q.x, q.y, q.z, q.w);
        let heading = lod_policy::glam::Quat::from_rotation_y(state.heading as f32);
        let world = heading * quat(rotations[root]);
        assert!(
            world.dot(quat(state.root_rotation)).abs() > 1.0 - 1e-6,
            "{world:?} {:?}",
            state.root_rotation
        );

        // The camera: null pointers, a bad camera or radius.
        assert_eq!(
            mlod_walker_detail_from_camera(walker, model, null(), 1.0, &mut detail, null_mut()),
            MlodStatus::NullPointer
        );
        assert_eq!(
            mlod_walker_detail_from_camera(walker, model, &cam, 1.0, null_mut(), null_mut()),
            MlodStatus::NullPointer
        );
        assert_eq!(
            mlod_walker_detail_from_camera(walker, second, &cam, 1.0, &mut detail, null_mut()),
            MlodStatus::InvalidArgument
        );
        let bad_cameras = [
            (
                MlodCamera {
                    direction: [0.0, 0.0, 2.0],
                    ..cam
                },
                "unit",
            ),
            (
                MlodCamera {
                    position: [f64::NAN, 0.0, 0.0],
                    ..cam
                },
                "finite",
            ),
            (MlodCamera { fov_y: 0.0, ..cam }, "fov_y"),
            (
                MlodCamera {
                    aspect: -1.0,
                    ..cam
                },
                "aspect",
            ),
            (
                MlodCamera {
                    image_height_px: 0.0,
                    ..cam
                },
                "image_height_px",
            ),
            (
                MlodCamera {
                    near_m: -1.0,
                    ..cam
                },
                "near_m",
            ),
            (MlodCamera { far_m: 0.05, ..cam }, "far_m"),
        ];
        for (bad, what) in bad_cameras {
            assert_eq!(
                mlod_walker_detail_from_camera(walker, model, &bad, 1.0, &mut detail, null_mut()),
                MlodStatus::InvalidArgument,
                "{bad:?}"
            );
            assert!(message().contains(what), "{what}: {}", message());
        }
        for radius in [-1.0, f32::NAN] {
            assert_eq!(
                mlod_walker_detail_from_camera(
                    walker,
                    model,
                    &cam,
                    radius,
                    &mut detail,
                    null_mut()
                ),
                MlodStatus::InvalidArgument
            );
            assert!(message().contains("radius"), "{}", message());
        }
        assert_eq!(
            mlod_walker_detail_from_camera(walker, model, &cam, 1.0, &mut detail, &mut visible),
            MlodStatus::Ok
        );
        let mut same = MlodDetail::default();
        let mut same_visible = !visible;
        let p = state.root_position;
        assert_eq!(
            mlod_model_detail_from_camera(
                model,
                &cam,
                p[0],
                p[1],
                p[2],
                1.0,
                &mut same,
                &mut same_visible
            ),
            MlodStatus::Ok
        );
        assert_eq!((detail, visible), (same, same_visible), "the walker's root");

        // Near in view: full detail; behind the camera, beside its view or beyond its far
        // distance: root only at the smallest level.
        let root_only = MlodDetail {
            level: levels as u32 - 1,
            joints: 0,
        };
        for (x, z, expected, seen) in [
            (0.0, 5.0, full, true),
            (0.0, -5.0, root_only, false),
            (20.0, 2.0, root_only, false),
            (0.0, 500.0, root_only, false),
        ] {
            assert_eq!(
                mlod_model_detail_from_camera(
                    model,
                    &cam,
                    x,
                    1.0,
                    z,
                    1.0,
                    &mut detail,
                    &mut visible
                ),
                MlodStatus::Ok
            );
            assert_eq!((detail, visible), (expected, seen), "at ({x}, {z})");
        }
        assert_eq!(
            mlod_model_detail_from_camera(
                model,
                &cam,
                f64::NAN,
                1.0,
                0.0,
                1.0,
                &mut detail,
                null_mut()
            ),
            MlodStatus::InvalidArgument
        );
        assert_eq!(
            mlod_model_detail_from_camera(
                null(),
                &cam,
                0.0,
                1.0,
                0.0,
                1.0,
                &mut detail,
                null_mut()
            ),
            MlodStatus::NullPointer
        );

        // The foot lock's switch.
        assert_eq!(
            mlod_walker_set_foot_lock(null_mut(), false),
            MlodStatus::NullPointer
        );
        assert_eq!(mlod_walker_set_foot_lock(walker, false), MlodStatus::Ok);
        assert_eq!(
            mlod_walker_advance(walker, model, 0.02, null(), null(), &mut state),
            MlodStatus::Ok
        );
        assert!(!state.foot_locked);
        assert_eq!(mlod_walker_set_foot_lock(walker, true), MlodStatus::Ok);
        assert_eq!(
            mlod_walker_advance(walker, model, 0.02, null(), null(), &mut state),
            MlodStatus::Ok
        );
        assert!(state.foot_locked);

        // The skeleton's rest transforms.
        let mut rest = MlodJointTransform::default();
        assert_eq!(
            mlod_model_joint_rest(model, joints, &mut rest),
            MlodStatus::InvalidArgument
        );
        assert!(message().contains("out of range"), "{}", message());
        assert_eq!(
            mlod_model_joint_rest(model, 0, null_mut()),
            MlodStatus::NullPointer
        );
        assert_eq!(
            mlod_model_joint_rest(model, joints - 1, &mut rest),
            MlodStatus::Ok
        );
        let norm = rest.rotation.iter().map(|v| v * v).sum::<f32>().sqrt();
        assert!((norm - 1.0).abs() < 1e-4, "{rest:?}");

        // Preparing a clip ends the walk.
        assert_eq!(
            mlod_walker_prepare(walker, model, &controls, full, null_mut()),
            MlodStatus::Ok
        );
        assert_eq!(
            mlod_walker_advance(walker, model, 0.1, null(), null(), &mut state),
            MlodStatus::NotPrepared
        );

        mlod_walker_free(fresh);
        mlod_walker_free(walker);
        mlod_model_free(second);
        mlod_model_free(model);
    }
}

/// `mlod_walkers_step` moves walkers as one `mlod_walker_detail_from_camera` and one
/// `mlod_walker_advance` each do, bit for bit, and refuses a bad list before moving any walker.
#[test]
fn a_crowd_step_is_the_walkers_steps_and_checks_first() {
    let model = common::load_model();
    let facts = common::model_facts(model);
    let animated = facts.animated;
    let controls = middle(&facts);
    let cam = camera();
    let detail = MlodDetail {
        level: 0,
        joints: animated as u32,
    };
    // SAFETY: live objects; readable inputs; writable outputs throughout.
    unsafe {
        let mut batch = [null_mut::<MlodWalker>(); 3];
        let mut single = [null_mut::<MlodWalker>(); 3];
        for (k, w) in batch.iter_mut().chain(single.iter_mut()).enumerate() {
            assert_eq!(mlod_walker_new(model, w), MlodStatus::Ok);
            let x = (k % 3) as f64 * 4.0 - 4.0;
            assert_eq!(
                mlod_walker_start(*w, model, &controls, detail, x, 10.0, 0.2, null_mut()),
                MlodStatus::Ok
            );
        }
        let next = [controls; 3];
        let mut states = [MlodWalkerState::default(); 3];
        let mut visible = [false; 3];
        for _ in 0..40 {
            assert_eq!(
                mlod_walkers_step(
                    batch.as_ptr(),
                    3,
                    model,
                    &cam,
                    1.2,
                    1.0 / 30.0,
                    next.as_ptr(),
                    states.as_mut_ptr(),
                    visible.as_mut_ptr(),
                ),
                MlodStatus::Ok,
                "{}",
                message()
            );
            for (k, &w) in single.iter().enumerate() {
                let mut d = MlodDetail::default();
                let mut v = false;
                let mut s = MlodWalkerState::default();
                assert_eq!(
                    mlod_walker_detail_from_camera(w, model, &cam, 1.2, &mut d, &mut v),
                    MlodStatus::Ok
                );
                assert_eq!(
                    mlod_walker_advance(w, model, 1.0 / 30.0, &controls, &d, &mut s),
                    MlodStatus::Ok
                );
                assert_eq!(s, states[k], "walker {k}");
                assert_eq!(v, visible[k], "walker {k}");
            }
        }
        assert!(states.iter().all(|s| s.cycle >= 1), "cycles were chained");

        // A bad entry is refused, by index, and nothing moves.
        let before = states;
        let mut bad = next;
        bad[2].dz = f32::NAN;
        assert_eq!(
            mlod_walkers_step(
                batch.as_ptr(),
                3,
                model,
                &cam,
                1.2,
                1.0 / 30.0,
                bad.as_ptr(),
                states.as_mut_ptr(),
                null_mut(),
            ),
            MlodStatus::InvalidArgument
        );
        assert!(message().contains("next_controls[2]"), "{}", message());
        assert_eq!(states, before, "no walker moved");
        let mut fresh = null_mut();
        assert_eq!(mlod_walker_new(model, &mut fresh), MlodStatus::Ok);
        let list = [batch[0], fresh];
        assert_eq!(
            mlod_walkers_step(
                list.as_ptr(),
                2,
                model,
                &cam,
                1.2,
                1.0 / 30.0,
                next.as_ptr(),
                states.as_mut_ptr(),
                null_mut(),
            ),
            MlodStatus::NotPrepared
        );
        assert!(message().contains("walker 1"), "{}", message());
        assert_eq!(
            mlod_walkers_step(
                null(),
                2,
                model,
                &cam,
                1.2,
                1.0 / 30.0,
                next.as_ptr(),
                states.as_mut_ptr(),
                null_mut(),
            ),
            MlodStatus::NullPointer
        );
        for w in batch.into_iter().chain(single).chain([fresh]) {
            mlod_walker_free(w);
        }
        mlod_model_free(model);
    }
}

/// The controls the C ABI says a model ignores are those the build left out.
#[test]
fn ignored_controls_are_the_builds() {
    for bytes in [model_bytes(), common::styled_model_bytes()] {
        let offline = motion_lod::MotionModel::from_bytes(&bytes, std::path::Path::new("m"))
            .expect("the model reads back");
        let expected = offline
            .ignored_controls()
            .iter()
            .enumerate()
            .filter(|(_, ignored)| **ignored)
            .fold(0u32, |bits, (k, _)| bits | (1 << k));
        let mut model: *mut MlodModel = null_mut();
        let mut bits = u32::MAX;
        // SAFETY: readable bytes, writable outputs; the model is freed once.
        unsafe {
            assert_eq!(
                mlod_model_from_bytes(bytes.as_ptr(), bytes.len(), &mut model),
                MlodStatus::Ok
            );
            assert_eq!(
                mlod_model_ignored_controls(model, &mut bits),
                MlodStatus::Ok
            );
            assert_eq!(
                mlod_model_ignored_controls(model, null_mut()),
                MlodStatus::NullPointer
            );
            mlod_model_free(model);
        }
        assert_eq!(
            bits, expected,
            "ignored controls of the C ABI and of the build"
        );
    }
}

/// Values at the edges of what the header accepts work as it says (found by a C audit,
/// 2026-11-28): more joints than the model animates mean all of them; a step of 1e-300 s (`0 <
/// dt_s`, but 0 in single precision, where the foot lock refused it after the walk had moved,
/// and ended the walk) is a step; a start heading of 1e18 is reported in `(-pi, pi]` (it was
/// 128).
#[test]
fn edge_values_the_header_accepts_work_as_it_says() {
    let model = common::load_model();
    let facts = common::model_facts(model);
    let animated = facts.animated as u32;
    let controls = middle(&facts);
    let full = MlodDetail {
        level: 0,
        joints: animated,
    };
    // SAFETY: live objects; readable inputs; writable outputs throughout.
    unsafe {
        let mut walkers = [null_mut::<MlodWalker>(); 3];
        let mut states = [MlodWalkerState::default(); 3];
        let more = [
            full,
            MlodDetail {
                joints: animated + 1,
                ..full
            },
            MlodDetail {
                joints: u32::MAX,
                ..full
            },
        ];
        for ((w, s), d) in walkers.iter_mut().zip(&mut states).zip(more) {
            assert_eq!(mlod_walker_new(model, w), MlodStatus::Ok);
            assert_eq!(
                mlod_walker_start(*w, model, &controls, d, 0.0, 0.0, 0.0, s),
                MlodStatus::Ok,
                "{d:?}: {}",
                message()
            );
        }
        assert_eq!(states[1], states[0]);
        assert_eq!(states[2], states[0]);
        assert_eq!(
            states[0].detail, full,
            "the state's detail is clamped to the model's"
        );
        let next = MlodDetail {
            joints: u32::MAX,
            ..full
        };
        for _ in 0..45 {
            for (k, (&w, s)) in walkers.iter().zip(&mut states).enumerate() {
                let d = if k == 0 { &full } else { &next };
                assert_eq!(
                    mlod_walker_advance(w, model, 1.0 / 30.0, null(), d, s),
                    MlodStatus::Ok,
                    "{}",
                    message()
                );
            }
            assert_eq!(states[1], states[0]);
            assert_eq!(states[2], states[0]);
        }

        // Steps of 1e-300 s and the smallest double, with the foot lock on, alone and in a crowd
        // step: each is a step, and the walkers walk on.
        for dt in [1e-300, f64::from_bits(1)] {
            assert!(states[0].foot_locked);
            assert_eq!(
                mlod_walker_advance(walkers[0], model, dt, null(), null(), &mut states[0]),
                MlodStatus::Ok,
                "{dt}: {}",
                message()
            );
            let cam = camera();
            let (next, mut visible) = ([controls; 2], [false; 2]);
            assert_eq!(
                mlod_walkers_step(
                    walkers[1..].as_ptr(),
                    2,
                    model,
                    &cam,
                    1.2,
                    dt,
                    next.as_ptr(),
                    states[1..].as_mut_ptr(),
                    visible.as_mut_ptr(),
                ),
                MlodStatus::Ok,
                "{dt}: {}",
                message()
            );
        }
        for (&w, s) in walkers.iter().zip(&mut states) {
            assert_eq!(
                mlod_walker_advance(w, model, 1.0 / 30.0, null(), null(), s),
                MlodStatus::Ok,
                "{}",
                message()
            );
            assert!(s.root_position.iter().all(|v| v.is_finite()), "{s:?}");
        }

        // A heading far beyond a turn is reported wrapped.
        use std::f64::consts::PI;
        for heading in [1e18, -1e18, 1e300, 7.0] {
            assert_eq!(
                mlod_walker_start(
                    walkers[0],
                    model,
                    &controls,
                    full,
                    0.0,
                    0.0,
                    heading,
                    &mut states[0]
                ),
                MlodStatus::Ok
            );
            let h = states[0].heading;
            assert!(-PI < h && h <= PI, "{heading} -> {h}");
        }
        assert_eq!(states[0].heading, 7.0 - 2.0 * PI);
        for w in walkers {
            mlod_walker_free(w);
        }
        mlod_model_free(model);
    }
}

/// A model file whose checksums hold but whose runtime section has one number set to `f32::MAX`
/// (fixed CRC-32s, as a C audit made 9,000 of them on 2026-11-28: 483 loaded and animated with
/// infinite joints) is refused when read, or plays finite poses at every level, at the middle of
/// its controls and at both ends of their range.
#[test]
fn a_huge_number_behind_valid_checksums_is_refused_or_plays_finite() {
    use lod_policy::file::{Section, frame, sections};
    use lod_policy::{ClipKernel, Controls, Detail, KernelScratch, RuntimeModel};
    let bytes = model_bytes();
    let path = std::path::Path::new("m.mlod");
    let parts = sections(&bytes, path).unwrap();
    let rtim = parts
        .iter()
        .position(|s| s.tag == RuntimeModel::SECTION)
        .unwrap();
    let payload = parts[rtim].bytes;
    let (mut refused, mut played) = (0, 0);
    for at in (0..payload.len() - 4).step_by(5) {
        let mut changed = payload.to_vec();
        changed[at..at + 4].copy_from_slice(&f32::MAX.to_le_bytes());
        let framed: Vec<Section> = parts
            .iter()
            .enumerate()
            .map(|(i, s)| Section {
                tag: s.tag,
                version: s.version,
                bytes: if i == rtim { &changed } else { s.bytes },
                offset: 0,
            })
            .collect();
        let Ok(model) = RuntimeModel::from_bytes(&frame(&framed)) else {
            refused += 1;
            continue;
        };
        played += 1;
        let lod = model.lod();
        let range = lod.controls().range().unwrap();
        let (lo, hi) = (range.min.to_array(), range.max.to_array());
        let mut scratch = KernelScratch::new(lod);
        let mut kernel = ClipKernel::new(lod);
        let mut pose = vec![0.0f32; lod.p()];
        for c in [lo, std::array::from_fn(|k| 0.5 * lo[k] + 0.5 * hi[k]), hi] {
            for level in 0..lod.levels().len() {
                let detail = Detail::new(level, lod.joints());
                lod.build_kernel(&Controls::from_array(c), detail, &mut scratch, &mut kernel)
                    .unwrap();
                for frame in 0..lod.t() {
                    lod.pose(&kernel, frame as f32, &mut pose).unwrap();
                    assert!(
                        pose.iter().all(|v| v.is_finite()),
                        "f32::MAX at byte {at} of the runtime section: level {level}, controls \
                         {c:?}, frame {frame}: {pose:?}"
                    );
                }
            }
        }
    }
    assert!(
        refused > 0 && played > 0,
        "{refused} refused, {played} played"
    );
}
