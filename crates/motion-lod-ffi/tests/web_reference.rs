//! The native side of the viewer's browser test (issue 31): the scripted walk and crowd that the
//! page runs through the runtime compiled to WebAssembly (`viewer/crowd.js`, `runWalk` and
//! `runCrowd`), walked here through the same C ABI in native code.
//!
//! Writes to `target/web-ref/` (or `$MOTION_LOD_WEB_REF`): `model.mlod` (a model of the checkout's
//! fixtures with three styles), `script.json` (the scripts), and what the native runtime gives for
//! them: `walk_states.f64`, `walk_joints.f32`, `crowd_roots.f64`, `crowd_details.f32`,
//! `crowd_joints.f32` (little-endian arrays, laid out as `viewer/crowd.js` returns them).
//! `.ci/web-checks` serves the model with `motion-lod view`, runs the scripts in headless Chromium
//! (`viewer/checks/live.mjs`) and fails when any value differs by more than 1e-5.
//!
//! The scripts: one walker over 10 cycles whose controls (speed, sidestep, turn, height, style)
//! and level of detail change every cycle, with the foot lock; and a crowd of 1,000 walkers for
//! 300 frames, each on its own path of control presets, its detail from a camera every frame.

use crate::common;

use std::path::PathBuf;

use motion_lod_ffi::*;
use serde_json::{Value, json};

const DT: f64 = 1.0 / 30.0;
const WALK_FRAMES: usize = 360;
const WALK_CYCLES: usize = 10;
const CROWD: usize = 1000;
const COLUMNS: usize = 40;
const CROWD_FRAMES: usize = 300;
const SAMPLE_WALKERS: usize = 10;
const SAMPLE_FRAMES: usize = 10;
const RADIUS_M: f32 = 1.2;
/// The floats of a state, as `viewer/crowd.js` lists them (`STATE_VALUES`).
const STATE_VALUES: usize = 16;

fn out_dir() -> PathBuf {
    let dir = std::env::var_os("MOTION_LOD_WEB_REF").map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../target/web-ref"),
        PathBuf::from,
    );
    std::fs::create_dir_all(&dir).expect("output folder");
    dir
}

fn ok(status: MlodStatus, what: &str) {
    assert_eq!(
        status,
        MlodStatus::Ok,
        "{what}: {}",
        // SAFETY: the library's static-per-thread message.
        unsafe { std::ffi::CStr::from_ptr(mlod_last_error()) }.to_string_lossy()
    );
}

fn controls_json(c: &MlodControls) -> Value {
    json!({
        "dx": f64::from(c.dx), "dz": f64::from(c.dz), "turn": f64::from(c.turn),
        "height": f64::from(c.height),
        "style": c.style.iter().map(|&w| f64::from(w)).collect::<Vec<_>>(),
    })
}

fn camera_json(c: &MlodCamera) -> Value {
    let v = |a: &[f32]| a.iter().map(|&x| f64::from(x)).collect::<Vec<_>>();
    json!({
        "position": c.position, "direction": v(&c.direction), "fovY": f64::from(c.fov_y),
        "aspect": f64::from(c.aspect), "heightPx": f64::from(c.image_height_px),
        "near": f64::from(c.near_m), "far": f64::from(c.far_m),
    })
}

fn state_values(s: &MlodWalkerState, out: &mut Vec<f64>) {
    let r = s.root_rotation;
    out.extend([
        s.time_in_cycle_s,
        s.cycle as f64,
        s.root_position[0],
        s.root_position[1],
        s.root_position[2],
        f64::from(r.x),
        f64::from(r.y),
        f64::from(r.z),
        f64::from(r.w),
        s.cycle_x,
        s.cycle_z,
        s.heading,
        f64::from(s.body_scale),
        f64::from(s.detail.level),
        f64::from(s.detail.joints),
        if s.foot_locked { 1.0 } else { 0.0 },
    ]);
}

fn transforms(w: *mut MlodWalker, m: *const MlodModel, joints: usize, out: &mut Vec<f32>) {
    let mut t = vec![MlodJointTransform::default(); joints];
    // SAFETY: live walker and model, `t` holds `joints` transforms.
    ok(
        unsafe { mlod_walker_joint_transforms(w, m, t.as_mut_ptr(), joints) },
        "transforms",
    );
    for x in &t {
        out.extend(x.rotation);
        out.extend(x.translation);
    }
}

fn write_f32(name: &str, values: &[f32]) {
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    std::fs::write(out_dir().join(name), bytes).expect("write");
}

fn write_f64(name: &str, values: &[f64]) {
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    std::fs::write(out_dir().join(name), bytes).expect("write");
}

#[test]
fn the_pages_scripts_walked_natively() {
    let bytes = common::styled_model_bytes();
    std::fs::write(out_dir().join("model.mlod"), &bytes).expect("write the model");
    let mut model: *mut MlodModel = std::ptr::null_mut();
    // SAFETY: valid bytes and out pointer.
    ok(
        unsafe { mlod_model_from_bytes(bytes.as_ptr(), bytes.len(), &mut model) },
        "load",
    );
    let (mut levels, mut joints, mut animated) = (0usize, 0usize, 0usize);
    // SAFETY: live model, writable outputs.
    ok(
        unsafe {
            mlod_model_sizes(
                model,
                &mut levels,
                &mut joints,
                &mut animated,
                std::ptr::null_mut(),
            )
        },
        "sizes",
    );
    let (mut lo, mut hi) = (MlodControls::default(), MlodControls::default());
    // SAFETY: live model, writable outputs.
    ok(
        unsafe { mlod_model_control_range(model, &mut lo, &mut hi) },
        "range",
    );
    let mut styles = 0usize;
    // SAFETY: live model, writable output.
    ok(
        unsafe { mlod_model_style_count(model, &mut styles) },
        "styles",
    );
    assert!(styles >= 2, "the styled model has {styles} styles");
    let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
    // A style mix: 0 = the data's (all zero), 1..=styles one style, beyond: a blend of two.
    let style = |k: usize| {
        let mut s = [0.0f32; MLOD_MAX_STYLES];
        match k % (styles + 2) {
            0 => {}
            j if j <= styles => s[j - 1] = 1.0,
            _ => {
                s[0] = 0.5;
                s[styles - 1] = 0.5;
            }
        }
        s
    };

    // The walk: controls and detail change every cycle.
    let cycles: Vec<(MlodControls, MlodDetail)> = (0..WALK_CYCLES)
        .map(|k| {
            let t = k as f32 / (WALK_CYCLES - 1) as f32;
            let c = MlodControls {
                dx: lerp(lo.dx, hi.dx, [0.5, 0.3, 0.7][k % 3]),
                dz: lerp(lo.dz, hi.dz, 0.2 + 0.6 * t),
                turn: lerp(lo.turn, hi.turn, [0.5, 0.2, 0.8, 0.5, 0.35][k % 5]),
                height: lerp(lo.height, hi.height, [0.5, 0.0, 1.0][k % 3]),
                style: style(k),
            };
            let d = MlodDetail {
                level: (k % levels) as u32,
                joints: if k % 4 == 3 {
                    (animated / 2) as u32
                } else {
                    animated as u32
                },
            };
            (c, d)
        })
        .collect();
    let (x0, z0, heading0) = (1.5f64, -2.0f64, 0.3f64);
    let mut walker: *mut MlodWalker = std::ptr::null_mut();
    // SAFETY: live model, writable out pointer.
    ok(unsafe { mlod_walker_new(model, &mut walker) }, "walker");
    let mut state = MlodWalkerState::default();
    let (mut walk_states, mut walk_joints) = (Vec::new(), Vec::new());
    // SAFETY: live walker and model; readable controls and detail; writable state.
    ok(
        unsafe {
            mlod_walker_start(
                walker,
                model,
                &cycles[0].0,
                cycles[0].1,
                x0,
                z0,
                heading0,
                &mut state,
            )
        },
        "start",
    );
    let mut locked = 0;
    for f in 0..WALK_FRAMES {
        if f > 0 {
            let k = (state.cycle as usize + 1).min(WALK_CYCLES - 1);
            // SAFETY: as above.
            ok(
                unsafe {
                    mlod_walker_advance(walker, model, DT, &cycles[k].0, &cycles[k].1, &mut state)
                },
                "advance",
            );
        }
        locked += usize::from(state.foot_locked);
        state_values(&state, &mut walk_states);
        transforms(walker, model, joints, &mut walk_joints);
    }
    // SAFETY: created above.
    unsafe { mlod_walker_free(walker) };
    assert!(
        state.cycle as usize >= WALK_CYCLES - 1,
        "the scripted walk reached cycle {} of {WALK_CYCLES}",
        state.cycle
    );
    assert!(locked > WALK_FRAMES / 2, "feet locked on {locked} frames");

    // The crowd: a grid in front of and around a camera; 8 presets, each walker its own sequence.
    let camera = MlodCamera {
        position: [0.0, 1.7, -8.0],
        direction: [0.0, 0.0, 1.0],
        fov_y: std::f32::consts::FRAC_PI_3,
        aspect: 16.0 / 9.0,
        image_height_px: 1080.0,
        near_m: 0.1,
        far_m: 60.0,
    };
    let presets: Vec<MlodControls> = (0..8)
        .map(|p| {
            let t = p as f32 / 7.0;
            MlodControls {
                dx: lerp(lo.dx, hi.dx, [0.5, 0.4, 0.6, 0.5][p % 4]),
                dz: lerp(lo.dz, hi.dz, 0.15 + 0.7 * t),
                turn: lerp(
                    lo.turn,
                    hi.turn,
                    [0.5, 0.25, 0.75, 0.5, 0.4, 0.6, 0.5, 0.5][p],
                ),
                height: lerp(lo.height, hi.height, [0.3, 0.7][p % 2]),
                style: style(p),
            }
        })
        .collect();
    let starts: Vec<[f64; 3]> = (0..CROWD)
        .map(|i| {
            let x = ((i % COLUMNS) as f64 - 19.5) * 2.5;
            let z = ((i / COLUMNS) as f64 - 5.0) * 2.5;
            let heading = (i % 16) as f64 * std::f64::consts::FRAC_PI_8 - 3.0;
            [x, z, heading]
        })
        .collect();
    let controls_for = |i: usize, k: usize| &presets[(7 * i + 3 * k) % presets.len()];
    let mut walkers = vec![std::ptr::null_mut::<MlodWalker>(); CROWD];
    let mut states = vec![MlodWalkerState::default(); CROWD];
    let (mut roots, mut details, mut crowd_joints) = (Vec::new(), Vec::new(), Vec::new());
    let (mut seen_levels, mut hidden, mut shown) = (std::collections::BTreeSet::new(), 0, 0);
    for f in 0..CROWD_FRAMES {
        for i in 0..CROWD {
            let mut detail = MlodDetail::default();
            let mut visible = false;
            // SAFETY: live objects; readable inputs; writable outputs.
            unsafe {
                if f == 0 {
                    let [x, z, heading] = starts[i];
                    ok(
                        mlod_model_detail_from_camera(
                            model,
                            &camera,
                            x,
                            1.0,
                            z,
                            RADIUS_M,
                            &mut detail,
                            &mut visible,
                        ),
                        "model detail",
                    );
                    ok(mlod_walker_new(model, &mut walkers[i]), "walker");
                    ok(
                        mlod_walker_start(
                            walkers[i],
                            model,
                            controls_for(i, 0),
                            detail,
                            x,
                            z,
                            heading,
                            &mut states[i],
                        ),
                        "start",
                    );
                } else {
                    ok(
                        mlod_walker_detail_from_camera(
                            walkers[i],
                            model,
                            &camera,
                            RADIUS_M,
                            &mut detail,
                            &mut visible,
                        ),
                        "walker detail",
                    );
                    let next = controls_for(i, states[i].cycle as usize + 1);
                    ok(
                        mlod_walker_advance(walkers[i], model, DT, next, &detail, &mut states[i]),
                        "advance",
                    );
                }
            }
            let s = &states[i];
            roots.extend(s.root_position);
            details.extend([
                s.detail.level as f32,
                s.detail.joints as f32,
                f32::from(u8::from(visible)),
            ]);
            seen_levels.insert((s.detail.level, s.detail.joints));
            if visible {
                shown += 1;
            } else {
                hidden += 1;
            }
        }
        if f % SAMPLE_FRAMES == 0 || f == CROWD_FRAMES - 1 {
            for i in (0..CROWD).step_by(SAMPLE_WALKERS) {
                transforms(walkers[i], model, joints, &mut crowd_joints);
            }
        }
    }
    for w in walkers {
        // SAFETY: created above, freed once.
        unsafe { mlod_walker_free(w) };
    }
    // SAFETY: created above; its walkers are freed.
    unsafe { mlod_model_free(model) };
    assert!(
        seen_levels.len() >= 3 && shown > 0 && hidden > 0,
        "the crowd script exercises the policy: details {seen_levels:?}, {shown} walker-frames in view, {hidden} out of view"
    );

    let script = json!({
        "dt": DT,
        "walk": {
            "frames": WALK_FRAMES,
            "x": x0, "z": z0, "heading": heading0,
            "footLock": true,
            "cycles": cycles.iter().map(|(c, d)| json!({
                "controls": controls_json(c),
                "detail": { "level": d.level, "joints": d.joints },
            })).collect::<Vec<_>>(),
        },
        "crowd": {
            "frames": CROWD_FRAMES,
            "camera": camera_json(&camera),
            "radius": f64::from(RADIUS_M),
            "starts": starts,
            "presets": presets.iter().map(controls_json).collect::<Vec<_>>(),
            "sampleWalkers": SAMPLE_WALKERS,
            "sampleFrames": SAMPLE_FRAMES,
        },
        "joints": joints,
        "stateValues": STATE_VALUES,
    });
    std::fs::write(
        out_dir().join("script.json"),
        serde_json::to_string(&script).expect("json"),
    )
    .expect("write the script");
    write_f64("walk_states.f64", &walk_states);
    write_f32("walk_joints.f32", &walk_joints);
    write_f64("crowd_roots.f64", &roots);
    write_f32("crowd_details.f32", &details);
    write_f32("crowd_joints.f32", &crowd_joints);
    assert_eq!(walk_states.len(), WALK_FRAMES * STATE_VALUES);
}
