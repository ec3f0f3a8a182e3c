//! Style through the C ABI: a model built with style labels names its styles and their shares of
//! the data, `MlodControls.style` weighs them exactly as the Rust API's `StyleMix` does (bit for
//! bit), a bad weight is a status with a message, and a model without styles ignores the weights.

use std::ffi::{CStr, c_char};
use std::ptr::{null, null_mut};

use lod_policy::{ClipKernel, Controls, Detail, KernelScratch, RuntimeModel, StyleMix};
use motion_lod_ffi::*;

use crate::common;

use common::{model_bytes, styled_model_bytes};

fn message() -> String {
    // SAFETY: mlod_last_error returns a valid NUL-terminated string for this thread.
    unsafe { CStr::from_ptr(mlod_last_error()) }
        .to_string_lossy()
        .into_owned()
}

/// A model of the C ABI from `bytes`.
fn load(bytes: &[u8]) -> *mut MlodModel {
    let mut model: *mut MlodModel = null_mut();
    // SAFETY: the bytes are readable and `model` writable.
    let status = unsafe { mlod_model_from_bytes(bytes.as_ptr(), bytes.len(), &mut model) };
    assert_eq!(status, MlodStatus::Ok, "{}", message());
    model
}

/// The model's style count through the C ABI.
fn style_count(model: *const MlodModel) -> usize {
    let mut n = usize::MAX;
    // SAFETY: live model, writable output.
    assert_eq!(
        unsafe { mlod_model_style_count(model, &mut n) },
        MlodStatus::Ok
    );
    n
}

/// Style `index`'s name through the C ABI.
fn style_name(model: *const MlodModel, index: usize) -> String {
    let mut buffer = [0 as c_char; 64];
    let mut len = 0usize;
    // SAFETY: live model, a buffer of its length, writable length.
    let status =
        unsafe { mlod_model_style_name(model, index, buffer.as_mut_ptr(), buffer.len(), &mut len) };
    assert_eq!(status, MlodStatus::Ok, "{}", message());
    // SAFETY: the library NUL-terminates the name within the buffer.
    let name = unsafe { CStr::from_ptr(buffer.as_ptr()) }
        .to_str()
        .expect("UTF-8")
        .to_string();
    assert_eq!(name.len(), len);
    name
}

/// Style `index`'s share of the data through the C ABI.
fn style_share(model: *const MlodModel, index: usize) -> f32 {
    let mut share = f32::NAN;
    // SAFETY: live model, writable output.
    let status = unsafe { mlod_model_style_share(model, index, &mut share) };
    assert_eq!(status, MlodStatus::Ok, "{}", message());
    share
}

/// The model's (levels, animated joints).
fn sizes(model: *const MlodModel) -> (usize, usize) {
    let (mut levels, mut animated) = (0, 0);
    // SAFETY: live model, writable outputs.
    let status =
        unsafe { mlod_model_sizes(model, &mut levels, null_mut(), &mut animated, null_mut()) };
    assert_eq!(status, MlodStatus::Ok);
    (levels, animated)
}

/// Controls a fraction `u` of the way through the model's range (style all 0).
fn controls_at(model: *const MlodModel, u: f32) -> MlodControls {
    let (mut lo, mut hi) = (MlodControls::default(), MlodControls::default());
    // SAFETY: live model, writable outputs.
    assert_eq!(
        unsafe { mlod_model_control_range(model, &mut lo, &mut hi) },
        MlodStatus::Ok
    );
    assert_eq!(
        (lo.style, hi.style),
        ([0.0; MLOD_MAX_STYLES], [0.0; MLOD_MAX_STYLES])
    );
    MlodControls {
        dx: lo.dx + (hi.dx - lo.dx) * u,
        dz: lo.dz + (hi.dz - lo.dz) * u,
        turn: lo.turn + (hi.turn - lo.turn) * u,
        height: lo.height + (hi.height - lo.height) * u,
        style: [0.0; MLOD_MAX_STYLES],
    }
}

/// `c` with the weights `weights` (the rest 0).
fn styled(c: MlodControls, weights: &[f32]) -> MlodControls {
    let mut style = [0.0; MLOD_MAX_STYLES];
    style[..weights.len()].copy_from_slice(weights);
    MlodControls { style, ..c }
}

/// The times a clip is sampled at: its start, inside it and its end, as fractions of its duration.
const PHASES: [f64; 5] = [0.0, 0.17, 0.5, 0.83, 1.0];

/// The cycle and the poses at [`PHASES`] that the C ABI's lower-level path gives `controls` at
/// `detail`.
fn c_clip(
    model: *mut MlodModel,
    controls: &MlodControls,
    detail: MlodDetail,
) -> (MlodCycle, Vec<Vec<f32>>) {
    let mut pose_len = 0;
    let mut walker: *mut MlodWalker = null_mut();
    let mut cycle = MlodCycle::default();
    // SAFETY: live model and walker, writable outputs, pose buffers of `pose_len` floats.
    unsafe {
        assert_eq!(
            mlod_model_sizes(model, null_mut(), null_mut(), null_mut(), &mut pose_len),
            MlodStatus::Ok
        );
        assert_eq!(mlod_walker_new(model, &mut walker), MlodStatus::Ok);
        assert_eq!(
            mlod_walker_prepare(walker, model, controls, detail, &mut cycle),
            MlodStatus::Ok,
            "{}",
            message()
        );
        let poses = PHASES
            .iter()
            .map(|f| {
                let mut pose = vec![f32::NAN; pose_len];
                assert_eq!(
                    mlod_walker_pose(
                        walker,
                        model,
                        f * cycle.duration_s,
                        pose.as_mut_ptr(),
                        pose.len()
                    ),
                    MlodStatus::Ok
                );
                pose
            })
            .collect();
        mlod_walker_free(walker);
        (cycle, poses)
    }
}

/// What the Rust runtime API gives `controls` at `detail`: the cycle (duration, root motion, body
/// scale) and the poses at [`PHASES`].
fn rust_clip(
    model: &RuntimeModel,
    controls: &Controls,
    detail: MlodDetail,
) -> (MlodCycle, Vec<Vec<f32>>) {
    let lod = model.lod();
    let detail = lod
        .check_detail(Detail::new(detail.level as usize, detail.joints as usize))
        .expect("detail");
    let mut kernel = ClipKernel::new(lod);
    let mut scratch = KernelScratch::new(lod);
    lod.build_kernel(controls, detail, &mut scratch, &mut kernel)
        .expect("kernel");
    let motion = kernel.root_motion();
    let cycle = MlodCycle {
        duration_s: kernel.duration(),
        dx: motion.dx,
        dz: motion.dz,
        turn: motion.turn,
        body_scale: model.body_scale(controls),
    };
    let poses = PHASES
        .iter()
        .map(|f| {
            let mut pose = vec![f32::NAN; lod.p()];
            lod.pose(&kernel, kernel.phase_at(f * kernel.duration()), &mut pose)
                .expect("pose");
            pose
        })
        .collect();
    (cycle, poses)
}

/// The bits of every value, to compare bit for bit (NaN included).
fn bits(poses: &[Vec<f32>]) -> Vec<Vec<u32>> {
    poses
        .iter()
        .map(|p| p.iter().map(|v| v.to_bits()).collect())
        .collect()
}

fn cycle_bits(c: &MlodCycle) -> [u64; 5] {
    [
        c.duration_s.to_bits(),
        c.dx.to_bits().into(),
        c.dz.to_bits().into(),
        c.turn.to_bits().into(),
        c.body_scale.to_bits().into(),
    ]
}

#[test]
fn a_styled_model_names_its_styles_and_their_shares() {
    let bytes = styled_model_bytes();
    let rust = RuntimeModel::from_bytes(&bytes).expect("the runtime reads the model");
    let model = load(&bytes);
    assert_eq!(style_count(model), 3);
    let names: Vec<String> = (0..3).map(|j| style_name(model, j)).collect();
    assert_eq!(names, ["p160", "p175", "p190"]);
    assert_eq!(names, rust.styles());
    let shares: Vec<f32> = (0..3).map(|j| style_share(model, j)).collect();
    assert_eq!(shares, rust.data_style_mix());
    assert!(shares.iter().all(|&s| s > 0.0 && s < 1.0), "{shares:?}");
    let sum: f32 = shares.iter().sum();
    assert!((sum - 1.0).abs() < 1e-5, "the shares sum to 1: {shares:?}");

    unsafe {
        // A name truncated to the buffer, its length reported in full; the length alone.
        let mut short = [0x7f as c_char; 3];
        let mut len = 0usize;
        assert_eq!(
            mlod_model_style_name(model, 2, short.as_mut_ptr(), short.len(), &mut len),
            MlodStatus::Ok
        );
        assert_eq!(CStr::from_ptr(short.as_ptr()).to_bytes(), b"p1");
        assert_eq!(len, 4);
        len = 0;
        assert_eq!(
            mlod_model_style_name(model, 0, null_mut(), 0, &mut len),
            MlodStatus::Ok
        );
        assert_eq!(len, 4);

        // An index out of range, null pointers: refused, the outputs untouched.
        let mut share = -1.0f32;
        len = 99;
        assert_eq!(
            mlod_model_style_name(model, 3, short.as_mut_ptr(), short.len(), &mut len),
            MlodStatus::InvalidArgument
        );
        assert!(
            message().contains("style 3 is out of range"),
            "{}",
            message()
        );
        assert!(message().contains("mlod_model_style_name"), "{}", message());
        assert_eq!(len, 99);
        assert_eq!(
            mlod_model_style_share(model, 3, &mut share),
            MlodStatus::InvalidArgument
        );
        assert!(message().contains("out of range"), "{}", message());
        assert!(message().contains("3 styles"), "{}", message());
        assert_eq!(share, -1.0);
        assert_eq!(
            mlod_model_style_share(model, 0, null_mut()),
            MlodStatus::NullPointer
        );
        assert_eq!(
            mlod_model_style_share(null(), 0, &mut share),
            MlodStatus::NullPointer
        );
        assert_eq!(
            mlod_model_style_count(model, null_mut()),
            MlodStatus::NullPointer
        );
        assert!(message().contains("out is null"), "{}", message());
        assert_eq!(
            mlod_model_style_name(null(), 0, null_mut(), 0, null_mut()),
            MlodStatus::NullPointer
        );
        mlod_model_free(model);
    }
}

#[test]
fn style_weights_pose_as_the_rust_api_bit_for_bit() {
    let bytes = styled_model_bytes();
    let rust = RuntimeModel::from_bytes(&bytes).expect("the runtime reads the model");
    let model = load(&bytes);
    let (levels, animated) = sizes(model);
    let p160 = rust.style_index("p160").expect("p160");
    let p190 = rust.style_index("p190").expect("p190");
    let details = [
        MlodDetail {
            level: 0,
            joints: animated as u32,
        },
        MlodDetail {
            level: levels as u32 - 1,
            joints: (animated / 2) as u32,
        },
    ];
    for detail in details {
        for u in [0.3, 0.6] {
            let c = controls_at(model, u);
            let plain = Controls::from_array([c.dx, c.dz, c.turn, c.height]);
            let mut one = [0.0; 3];
            one[p160] = 1.0;
            let (c160, poses160) = c_clip(model, &styled(c, &one), detail);
            let (r160, rust160) = rust_clip(&rust, &plain.with_style(StyleMix::one(p160)), detail);
            assert_eq!(cycle_bits(&c160), cycle_bits(&r160), "p160 at {detail:?}");
            assert_eq!(bits(&poses160), bits(&rust160), "p160 at {detail:?}");

            // Weights are normalised: 2.5 of one style alone is that style.
            let mut heavy = [0.0; 3];
            heavy[p190] = 2.5;
            let (c190, poses190) = c_clip(model, &styled(c, &heavy), detail);
            let (r190, rust190) = rust_clip(&rust, &plain.with_style(StyleMix::one(p190)), detail);
            assert_eq!(cycle_bits(&c190), cycle_bits(&r190), "p190 at {detail:?}");
            assert_eq!(bits(&poses190), bits(&rust190), "p190 at {detail:?}");

            // The styles walk differently.
            let largest = poses160
                .iter()
                .flatten()
                .zip(poses190.iter().flatten())
                .map(|(a, b)| (a - b).abs())
                .fold(0.0f32, f32::max);
            assert!(largest > 1e-3, "p160 and p190 differ by {largest}");

            // All 0 is the data's mix; a blend is the Rust API's blend; weights beyond the
            // model's styles are ignored.
            let (cmix, posesmix) = c_clip(model, &c, detail);
            let (rmix, rustmix) = rust_clip(&rust, &plain.with_style(StyleMix::DATA_MIX), detail);
            assert_eq!(
                cycle_bits(&cmix),
                cycle_bits(&rmix),
                "data mix at {detail:?}"
            );
            assert_eq!(bits(&posesmix), bits(&rustmix), "data mix at {detail:?}");
            assert_ne!(bits(&posesmix), bits(&poses160));
            let blend = [0.2, 0.0, 0.6, 0.0, 0.0, 0.0, 0.0, 5.0];
            let (cblend, posesblend) = c_clip(model, &styled(c, &blend), detail);
            let mut weights = [0.0; lod_policy::MAX_STYLES];
            weights[..3].copy_from_slice(&blend[..3]);
            let (rblend, rustblend) =
                rust_clip(&rust, &plain.with_style(StyleMix { weights }), detail);
            assert_eq!(
                cycle_bits(&cblend),
                cycle_bits(&rblend),
                "blend at {detail:?}"
            );
            assert_eq!(bits(&posesblend), bits(&rustblend), "blend at {detail:?}");
        }
    }
    // SAFETY: a live model, freed once.
    unsafe { mlod_model_free(model) };
}

#[test]
fn walkers_carry_the_style_into_every_cycle() {
    let bytes = styled_model_bytes();
    let rust = RuntimeModel::from_bytes(&bytes).expect("the runtime reads the model");
    let model = load(&bytes);
    let (_, animated) = sizes(model);
    let detail = MlodDetail {
        level: 0,
        joints: animated as u32,
    };
    let c = controls_at(model, 0.5);
    let plain = Controls::from_array([c.dx, c.dz, c.turn, c.height]);
    let p160 = rust.style_index("p160").expect("p160");
    let p190 = rust.style_index("p190").expect("p190");
    let (mut first, mut next) = (c, c);
    first.style[p160] = 1.0;
    next.style[p190] = 1.0;
    let (r160, _) = rust_clip(&rust, &plain.with_style(StyleMix::one(p160)), detail);
    let (r190, _) = rust_clip(&rust, &plain.with_style(StyleMix::one(p190)), detail);
    assert_ne!(
        r160.duration_s, r190.duration_s,
        "the styles' cycles differ"
    );
    unsafe {
        let mut walker: *mut MlodWalker = null_mut();
        assert_eq!(mlod_walker_new(model, &mut walker), MlodStatus::Ok);
        let mut state = MlodWalkerState::default();
        assert_eq!(
            mlod_walker_start(walker, model, &first, detail, 0.0, 0.0, 0.0, &mut state),
            MlodStatus::Ok
        );
        assert_eq!(state.cycle_duration_s.to_bits(), r160.duration_s.to_bits());
        assert_eq!(state.body_scale.to_bits(), r160.body_scale.to_bits());
        // Until the first cycle ends the next cycle's style is only kept; then it is p190's.
        let mut steps = 0;
        while state.cycle < 2 {
            assert_eq!(
                mlod_walker_advance(walker, model, 1.0 / 30.0, &next, &detail, &mut state),
                MlodStatus::Ok
            );
            let expected = if state.cycle == 0 { r160 } else { r190 };
            assert_eq!(
                state.cycle_duration_s.to_bits(),
                expected.duration_s.to_bits(),
                "cycle {}",
                state.cycle
            );
            steps += 1;
            assert!(steps < 300, "{state:?}");
        }
        mlod_walker_free(walker);
        mlod_model_free(model);
    }
}

#[test]
fn a_bad_style_weight_is_refused_with_a_message() {
    let bytes = styled_model_bytes();
    let model = load(&bytes);
    let (_, animated) = sizes(model);
    let detail = MlodDetail {
        level: 0,
        joints: animated as u32,
    };
    let c = controls_at(model, 0.5);
    unsafe {
        let mut walker: *mut MlodWalker = null_mut();
        assert_eq!(mlod_walker_new(model, &mut walker), MlodStatus::Ok);
        // Every weight is checked, also those beyond the model's three styles.
        for (index, value) in [(1, f32::NAN), (0, -0.5), (2, f32::INFINITY), (7, f32::NAN)] {
            let mut bad = styled(c, &[1.0, 0.0, 0.0]);
            bad.style[index] = value;
            let what = format!("style weight {index} is {value}");
            assert_eq!(
                mlod_walker_prepare(walker, model, &bad, detail, null_mut()),
                MlodStatus::InvalidArgument
            );
            assert!(message().contains(&what), "{what}: {}", message());
            assert!(message().contains("controls"), "{}", message());
            assert_eq!(
                mlod_walker_start(walker, model, &bad, detail, 0.0, 0.0, 0.0, null_mut()),
                MlodStatus::InvalidArgument
            );
            assert!(message().contains(&what), "{what}: {}", message());
        }
        // A walk refuses a bad next cycle and goes on unchanged.
        let mut state = MlodWalkerState::default();
        assert_eq!(
            mlod_walker_start(walker, model, &c, detail, 0.0, 0.0, 0.0, &mut state),
            MlodStatus::Ok
        );
        let started = state;
        let mut bad = c;
        bad.style[1] = f32::NAN;
        assert_eq!(
            mlod_walker_advance(walker, model, 0.1, &bad, null(), &mut state),
            MlodStatus::InvalidArgument
        );
        assert!(message().contains("next_controls"), "{}", message());
        assert!(message().contains("style weight 1 is NaN"), "{}", message());
        assert_eq!(state, started);
        assert_eq!(
            mlod_walker_advance(walker, model, 0.1, null(), null(), &mut state),
            MlodStatus::Ok
        );
        mlod_walker_free(walker);
        mlod_model_free(model);
    }
}

#[test]
fn a_model_without_styles_ignores_the_weights() {
    let bytes = model_bytes();
    let rust = RuntimeModel::from_bytes(&bytes).expect("the runtime reads the model");
    assert!(rust.styles().is_empty());
    let model = load(&bytes);
    assert_eq!(style_count(model), 0);
    let (_, animated) = sizes(model);
    let detail = MlodDetail {
        level: 0,
        joints: animated as u32,
    };
    unsafe {
        let mut share = 0.0;
        assert_eq!(
            mlod_model_style_share(model, 0, &mut share),
            MlodStatus::InvalidArgument
        );
        assert!(
            message().contains("the model has 0 styles"),
            "{}",
            message()
        );
        assert_eq!(
            mlod_model_style_name(model, 0, null_mut(), 0, null_mut()),
            MlodStatus::InvalidArgument
        );
        assert!(message().contains("out of range"), "{}", message());
    }
    let c = controls_at(model, 0.4);
    let (cycle, poses) = c_clip(model, &c, detail);
    let (r, rust_poses) = rust_clip(
        &rust,
        &Controls::from_array([c.dx, c.dz, c.turn, c.height]),
        detail,
    );
    assert_eq!(cycle_bits(&cycle), cycle_bits(&r));
    assert_eq!(bits(&poses), bits(&rust_poses));
    let (weighted, weighted_poses) = c_clip(model, &styled(c, &[0.0, 1.0, 3.0]), detail);
    assert_eq!(cycle_bits(&weighted), cycle_bits(&cycle));
    assert_eq!(bits(&weighted_poses), bits(&poses));
    // SAFETY: a live model, freed once.
    unsafe { mlod_model_free(model) };
}
