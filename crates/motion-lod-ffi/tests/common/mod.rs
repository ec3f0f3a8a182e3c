//! What the C ABI's tests share: a small model built from the checkout's fixtures.

/// The bytes of a model file built from the checkout's fixtures with small settings (12 cycles,
/// 3 key levels, 4 accuracy levels), built once per test binary.
pub fn model_bytes() -> Vec<u8> {
    static BYTES: std::sync::OnceLock<Vec<u8>> = std::sync::OnceLock::new();
    BYTES.get_or_init(build_model_bytes).clone()
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
