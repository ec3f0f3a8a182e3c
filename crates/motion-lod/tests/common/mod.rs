//! Shared by the integration tests: the model built once from the embedded data set.

use std::sync::OnceLock;

use motion_lod::build::Analysis;
use motion_lod::dataset::DataSpec;
use motion_lod::progress::NoProgress;
use motion_lod::{BuildConfig, MotionModel};

/// The model (and its analysis) built from the embedded data set with the default settings, once per
/// test binary.
pub fn built() -> &'static (MotionModel, Analysis) {
    static MODEL: OnceLock<(MotionModel, Analysis)> = OnceLock::new();
    MODEL.get_or_init(|| {
        let loaded = DataSpec::default()
            .load_with_default(motion_io::test_data::fixture_takes(), &|_, _| {})
            .expect("embedded data loads");
        MotionModel::build_with_analysis(&loaded.training, &BuildConfig::default(), &NoProgress)
            .expect("model builds")
    })
}
