//! The runtime section's decoder: any bytes go to `RuntimeModel::from_section_bytes`, the bincode
//! decoder of the runtime's own section (same configuration and limits as a whole file's) without
//! the checksums in front, so the fuzzer reaches the deserializers of the rig, the multilinear
//! model, the feet and the stature, and the runtime model's validation. A model that decodes must
//! encode to section bytes that decode and encode to the same bytes, and a file of that section
//! alone must read back to the same model.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use motion_lod::lod_policy::RuntimeModel;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.mlod");
    let Ok(model) = RuntimeModel::from_section_bytes(data, path) else {
        return;
    };
    let bytes = model.section_bytes();
    let again = RuntimeModel::from_section_bytes(&bytes, path).expect("an encoded model decodes");
    assert_eq!(bytes, again.section_bytes());
    let file = RuntimeModel::from_bytes(&model.to_bytes()).expect("a runtime-only file reads");
    assert_eq!(file.section_bytes(), bytes);
});
