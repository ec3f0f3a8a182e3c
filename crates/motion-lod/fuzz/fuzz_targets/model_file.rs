//! Model file loader: any bytes go to `model_file::decode::<MotionModel>` (magic, version,
//! length, CRC, then the bincode payload). Mutations mostly stop at the checksum; the
//! `model_payload` target fuzzes the decoder behind it.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use motion_lod::MotionModel;
use motion_lod::model_file::decode;

fuzz_target!(|data: &[u8]| {
    let _ = decode::<MotionModel>(data, Path::new("fuzz.mlod"));
});
