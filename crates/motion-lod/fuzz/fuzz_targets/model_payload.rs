//! Model payload decoder: any bytes go to `model_file::decode_payload::<MotionModel>`, the bincode
//! decoder (same configuration and limits as `decode`) without the checksum in front, so the
//! fuzzer reaches the deserializers of `MotionModel` and the runtime model's validation. A model
//! that decodes must encode to a payload that decodes and encodes to the same bytes.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use motion_lod::MotionModel;
use motion_lod::model_file::{HEADER_LEN, decode_payload, encode};

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.mlod");
    let Ok(model) = decode_payload::<MotionModel>(data, path) else {
        return;
    };
    let bytes = encode(&model, path).expect("a decoded model encodes");
    let again: MotionModel =
        decode_payload(&bytes[HEADER_LEN..], path).expect("an encoded model decodes");
    let bytes2 = encode(&again, path).expect("encodes again");
    assert_eq!(bytes, bytes2);
});
