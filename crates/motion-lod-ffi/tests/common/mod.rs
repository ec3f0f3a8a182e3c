//! What the C ABI's tests share: small models built from the checkout's fixtures.

// Each test binary compiles this module and uses part of it.
#![allow(dead_code)]

/// The bytes of a model file built from the checkout's fixtures with small settings (12 cycles,
/// 3 key levels, 4 accuracy levels), built once per test binary.
pub fn model_bytes() -> Vec<u8> {
    static BYTES: std::sync::OnceLock<Vec<u8>> = std::sync::OnceLock::new();
    BYTES.get_or_init(build_model_bytes).clone()
}

/// The model of [`model_bytes`] loaded through the C ABI (`mlod_model_from_bytes`, asserted to
/// succeed); the caller frees it with `mlod_model_free`.
pub fn load_model() -> *mut motion_lod_ffi::MlodModel {
    let bytes = model_bytes();
    let mut model = std::ptr::null_mut();
    // SAFETY: `bytes` holds `len` bytes; `model` is a writable out pointer.
    let status =
        unsafe { motion_lod_ffi::mlod_model_from_bytes(bytes.as_ptr(), bytes.len(), &mut model) };
    assert_eq!(status, motion_lod_ffi::MlodStatus::Ok);
    assert!(!model.is_null());
    model
}

/// What a walk needs to know of a model: `mlod_model_sizes` and `mlod_model_control_range`.
pub struct ModelFacts {
    /// Accuracy levels.
    pub levels: usize,
    /// Joints of the skeleton.
    pub joints: usize,
    /// Joints a detail can animate.
    pub animated: usize,
    /// Floats of a pose vector.
    pub pose_len: usize,
    /// The smallest controls of the data.
    pub lo: motion_lod_ffi::MlodControls,
    /// The largest controls of the data.
    pub hi: motion_lod_ffi::MlodControls,
}

/// The [`ModelFacts`] of a live `model`, both calls asserted to succeed.
pub fn model_facts(model: *const motion_lod_ffi::MlodModel) -> ModelFacts {
    use motion_lod_ffi::*;
    let (mut levels, mut joints, mut animated, mut pose_len) = (0, 0, 0, 0);
    let (mut lo, mut hi) = (MlodControls::default(), MlodControls::default());
    // SAFETY: a live model (the caller's contract) and writable outputs.
    unsafe {
        assert_eq!(
            mlod_model_sizes(
                model,
                &mut levels,
                &mut joints,
                &mut animated,
                &mut pose_len
            ),
            MlodStatus::Ok
        );
        assert_eq!(
            mlod_model_control_range(model, &mut lo, &mut hi),
            MlodStatus::Ok
        );
    }
    ModelFacts {
        levels,
        joints,
        animated,
        pose_len,
        lo,
        hi,
    }
}

/// A camera 3 m behind the origin at eye height, looking along +z (1080 px high, no far plane).
pub fn camera_behind_origin() -> motion_lod_ffi::MlodCamera {
    motion_lod_ffi::MlodCamera {
        position: [0.0, 1.7, -3.0],
        direction: [0.0, 0.0, 1.0],
        fov_y: 1.0,
        aspect: 1.5,
        image_height_px: 1080.0,
        near_m: 0.1,
        far_m: 0.0,
    }
}

fn build_model_bytes() -> Vec<u8> {
    use motion_lod::BuildConfig;
    use motion_lod::dataset::DataSpec;
    let spec = DataSpec {
        samples: Some(12),
        ..DataSpec::default()
    };
    let data = spec
        .load_with_default(motion_io::test_data::fixture_takes(), &|_, _| {})
        .expect("fixtures load");
    let config = BuildConfig {
        key_levels: 3,
        accuracy_levels: 4,
        ..BuildConfig::default()
    };
    let model =
        motion_lod::MotionModel::build(&data.training, &config, &motion_lod::progress::NoProgress)
            .expect("builds");
    motion_lod::model_file::encode(&model, std::path::Path::new("m")).expect("encodes")
}

/// The style labels of [`styled_model_bytes`]: the performer in each fixture take's file name
/// (`walk_p160_t01.bvh` is `p160`).
pub const STYLE_PATTERN: &str = r"walk_(p\d+)_";

/// The bytes of a model file built from every cycle of the checkout's fixtures, each labelled with
/// its performer ([`STYLE_PATTERN`]: styles `p160`, `p175`, `p190`), with small settings (3 key
/// levels, 4 accuracy levels), built once per test binary.
pub fn styled_model_bytes() -> Vec<u8> {
    static BYTES: std::sync::OnceLock<Vec<u8>> = std::sync::OnceLock::new();
    BYTES.get_or_init(build_styled_model_bytes).clone()
}

fn build_styled_model_bytes() -> Vec<u8> {
    use motion_lod::BuildConfig;
    use motion_lod::dataset::DataSpec;
    use motion_lod::style::StyleSpec;
    let data = DataSpec::default()
        .load_with_default(motion_io::test_data::fixture_takes(), &|_, _| {})
        .expect("fixtures load");
    let training = data
        .training
        .with_styles(Some(&StyleSpec::Name(STYLE_PATTERN.into())))
        .expect("every take is labelled");
    let config = BuildConfig {
        key_levels: 3,
        accuracy_levels: 4,
        ..BuildConfig::default()
    };
    let model =
        motion_lod::MotionModel::build(&training, &config, &motion_lod::progress::NoProgress)
            .expect("builds");
    motion_lod::model_file::encode(&model, std::path::Path::new("m")).expect("encodes")
}
