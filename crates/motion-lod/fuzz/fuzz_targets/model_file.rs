//! Model file loader: any bytes go to both readers, the runtime's (`RuntimeModel::from_bytes`:
//! magic, version, length, CRC, the section table, then its own section) and the offline one
//! (`MotionModel::from_bytes`: both sections and their fit). Mutations mostly stop at the
//! checksums; the `model_payload` target fuzzes the runtime section's decoder behind them.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use motion_lod::MotionModel;
use motion_lod::lod_policy::RuntimeModel;

fuzz_target!(|data: &[u8]| {
    let runtime = RuntimeModel::from_bytes(data);
    if let Ok(model) = MotionModel::from_bytes(data, Path::new("fuzz.mlod")) {
        // As bytes: a model may hold NaN (an unused variogram exponent), never equal to itself.
        assert_eq!(
            runtime.ok().map(|r| r.section_bytes()),
            Some(model.runtime().section_bytes())
        );
    }
});
