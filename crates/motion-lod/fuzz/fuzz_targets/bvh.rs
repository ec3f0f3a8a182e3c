//! BVH reader: any bytes that are UTF-8 go to `parse_bvh`; a file that parses must write back
//! as text that parses to the same shape (joints, channels, frames).
#![no_main]

use libfuzzer_sys::fuzz_target;
use motion_io::{parse_bvh, to_bvh_string};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(motion) = parse_bvh(text) else {
        return;
    };
    let nch = motion.skeleton.channel_count();
    assert!(nch > 0 && motion.frames.len() % nch == 0);
    assert!(motion.frames.iter().all(|v| v.is_finite()));
    let again = parse_bvh(&to_bvh_string(&motion)).expect("written text reads back");
    assert_eq!(again.skeleton.joints.len(), motion.skeleton.joints.len());
    assert_eq!(again.skeleton.channel_count(), nch);
    assert_eq!(again.frame_count(), motion.frame_count());
});
