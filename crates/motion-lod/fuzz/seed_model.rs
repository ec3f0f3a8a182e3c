//! The small real model every model-file fuzz target and hostile-model test starts from: built
//! from `fixtures/` (8 cycles, T = 16, 2 key levels, 3 accuracy levels; about 10.8 KB as a file).
//! Shared with `#[path]` by `examples/seed_corpus.rs`, `fuzz_targets/model_mutated.rs` and
//! `tests/hostile_model.rs`.

use std::path::Path;

use motion_lod::dataset::DataSpec;
use motion_lod::progress::NoProgress;
use motion_lod::{BuildConfig, MotionModel};

/// Builds the small seed model from `fixtures`.
pub fn build_small_model(fixtures: &Path) -> Result<MotionModel, Box<dyn std::error::Error>> {
    let spec = DataSpec {
        dirs: vec![fixtures.to_path_buf()],
        frames: Some(16),
        samples: Some(8),
        ..DataSpec::default()
    };
    let data = spec.load_with_default(motion_io::test_data::fixture_takes(), &|_, _| {})?;
    let config = BuildConfig {
        key_levels: 2,
        accuracy_levels: 3,
        max_ranks: [8, 8, 6],
        min_ranks: [3, 3, 3],
        importance_poses: 200,
        error_samples: 4,
        ..BuildConfig::default()
    };
    Ok(MotionModel::build(&data.training, &config, &NoProgress)?)
}

/// The seed model for the fuzz targets (built from the repository's `fixtures/`, three folders
/// above the fuzz crate); panics with the reason when it cannot be built, the only way a fuzz
/// target can report.
#[allow(dead_code)]
pub fn small_model() -> MotionModel {
    let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../fixtures");
    build_small_model(&fixtures)
        .unwrap_or_else(|e| panic!("seed model from {}: {e}", fixtures.display()))
}
