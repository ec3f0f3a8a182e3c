//! What the GPU crowd's test files share: the fixture model, built once a test binary, and the
//! adapter, opened once (`Gpu::open_or_skip`: `None` skips a test, or fails it with
//! `MOTION_LOD_REQUIRE_GPU=1`, as in CI).

use std::sync::OnceLock;

use gpu_crowd::Gpu;
use lod_policy::RuntimeModel;
use motion_lod::MotionModel;
use motion_lod::dataset::DataSpec;
use motion_lod::progress::NoProgress;

/// The model built from the fixture takes with the default build settings.
#[allow(dead_code)] // Not every test binary needs the offline model.
pub fn motion_model() -> &'static MotionModel {
    static MODEL: OnceLock<MotionModel> = OnceLock::new();
    MODEL.get_or_init(|| {
        let loaded = DataSpec::default()
            .load_with_default(motion_io::test_data::fixture_takes(), &|_, _| {})
            .expect("fixture takes");
        MotionModel::build(
            &loaded.training,
            &motion_lod::BuildConfig::default(),
            &NoProgress,
        )
        .expect("model")
    })
}

/// The runtime model of [`motion_model`].
pub fn model() -> &'static RuntimeModel {
    motion_model().runtime()
}

/// The adapter (`None`: no adapter, the test is skipped).
#[allow(dead_code)] // Some test binaries open their own.
pub fn gpu() -> Option<&'static Gpu> {
    static GPU: OnceLock<Option<Gpu>> = OnceLock::new();
    GPU.get_or_init(Gpu::open_or_skip).as_ref()
}
