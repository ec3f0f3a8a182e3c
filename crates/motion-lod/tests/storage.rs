//! One model, one size: the storage `info` reports (a built model, error tables measured) equals the
//! storage `eval` reports (the runtime model of the same analysis, before its errors are measured).

use crate::common;

use motion_lod::BuildConfig;
use motion_lod::progress::NoProgress;
use motion_lod::storage::Storage;

#[test]
fn info_and_eval_count_the_same_bytes() {
    let (model, analysis) = common::built();
    assert!(
        !model.lod().level_errors().is_empty(),
        "the built model has its error tables"
    );
    let unmeasured = analysis
        .runtime_model(&BuildConfig::default(), &NoProgress)
        .unwrap();
    assert!(unmeasured.lod().level_errors().is_empty());
    let (a, b) = (Storage::of(model), Storage::of(&unmeasured));
    assert_eq!(a.model_f64, b.model_f64);
    assert_eq!(a.model_f32, b.model_f32);
}
