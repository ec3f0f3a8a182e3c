//! Shared by the integration tests: the models built once per run from the embedded data set and
//! from the shared Bandai and CMU sets.

use std::sync::OnceLock;

use motion_lod::build::Analysis;
use motion_lod::dataset::DataSpec;
use motion_lod::progress::NoProgress;
use motion_lod::{BuildConfig, MotionModel};

/// The model (and its analysis) built from the embedded data set with the default settings, once per
/// test run.
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

/// Everything a crowd step leaves per walker: rows of the pose, joint positions, level bin; and the
/// frame's visible count.
#[derive(Debug, PartialEq)]
pub struct Frame {
    pub poses: Vec<Vec<f32>>,
    pub joints: Vec<Vec<[f32; 3]>>,
    pub bins: Vec<usize>,
    pub visible: usize,
}

/// `frames` steps at 30 fps of a crowd of `source` under `policy` with `config`, the camera of
/// `scene`: what every step left.
pub fn crowd_frames<S, P>(
    source: &S,
    policy: &P,
    config: crowd_sim::CrowdConfig,
    scene: crowd_sim::Scene,
    frames: usize,
) -> Vec<Frame>
where
    S: crowd_sim::ClipSource,
    P: lod_policy::LevelPolicy + Sync,
{
    let path = scene.path(config.field_size_m);
    let lens = scene.lens(crowd_sim::Camera::default(), config.field_size_m);
    let mut crowd = crowd_sim::Crowd::new(source, config).expect("crowd");
    (0..frames)
        .map(|f| {
            let cam = path.camera_at(f as f32 / 30.0, &lens);
            let stats = crowd.step(source, policy, &cam, 1.0 / 30.0).expect("step");
            Frame {
                poses: (0..crowd.len()).map(|i| crowd.pose(i).to_vec()).collect(),
                joints: (0..crowd.len())
                    .map(|i| {
                        crowd
                            .joint_positions(i)
                            .iter()
                            .map(|p| p.to_array())
                            .collect()
                    })
                    .collect(),
                bins: (0..crowd.len()).map(|i| crowd.level_bin(i)).collect(),
                visible: stats.visible,
            }
        })
        .collect()
}

/// The shared Bandai data set (all 800 cycles); `None` (skipped) without it.
pub fn bandai_spec() -> Option<DataSpec> {
    Some(DataSpec {
        dirs: vec![motion_io::test_data::shared_mocap(
            env!("CARGO_MANIFEST_DIR"),
            "bandai-namco-2-walk",
        )?],
        ..DataSpec::default()
    })
}

/// The shared CMU data set (`Preset::Cmu`); `None` (skipped) without it.
pub fn cmu_spec() -> Option<DataSpec> {
    Some(DataSpec {
        dirs: vec![motion_io::test_data::shared_mocap(
            env!("CARGO_MANIFEST_DIR"),
            "cmu-daz-walk-s07-s08",
        )?],
        preset: motion_lod::dataset::Preset::Cmu,
        ..DataSpec::default()
    })
}

/// The model of `spec` with the default settings, and its training controls.
fn build_with_controls(spec: &DataSpec) -> (MotionModel, Vec<[f64; 4]>) {
    let loaded = spec
        .load_with_default(motion_io::test_data::fixture_takes(), &|_, _| {})
        .expect("data loads");
    let model = MotionModel::build(&loaded.training, &BuildConfig::default(), &NoProgress)
        .expect("model builds");
    (model, loaded.training.controls.clone())
}

/// The Bandai model ([`bandai_spec`], default settings) and its training controls, built once per
/// test run; `None` without the data.
pub fn bandai() -> Option<&'static (MotionModel, Vec<[f64; 4]>)> {
    static MODEL: OnceLock<Option<(MotionModel, Vec<[f64; 4]>)>> = OnceLock::new();
    MODEL
        .get_or_init(|| Some(build_with_controls(&bandai_spec()?)))
        .as_ref()
}

/// The CMU model ([`cmu_spec`], default settings) and its training controls, built once per test
/// run; `None` without the data.
pub fn cmu() -> Option<&'static (MotionModel, Vec<[f64; 4]>)> {
    static MODEL: OnceLock<Option<(MotionModel, Vec<[f64; 4]>)>> = OnceLock::new();
    MODEL
        .get_or_init(|| Some(build_with_controls(&cmu_spec()?)))
        .as_ref()
}
