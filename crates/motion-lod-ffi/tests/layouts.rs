//! The struct layouts `viewer/mlod.js` reads and writes in the WebAssembly runtime's memory: the
//! sizes and field offsets its header comment lists. A change of layout must change that file
//! (and the ABI version) too; this test names what moved.

use std::mem::{offset_of, size_of};

use motion_lod_ffi::*;

#[test]
fn the_layouts_the_page_uses() {
    assert_eq!(size_of::<MlodControls>(), 48);
    assert_eq!(offset_of!(MlodControls, style), 16);
    assert_eq!(size_of::<MlodDetail>(), 8);
    assert_eq!(size_of::<MlodJointTransform>(), 28);
    assert_eq!(offset_of!(MlodJointTransform, translation), 16);
    assert_eq!(size_of::<MlodCamera>(), 56);
    assert_eq!(offset_of!(MlodCamera, direction), 24);
    assert_eq!(offset_of!(MlodCamera, far_m), 52);
    assert_eq!(size_of::<MlodWalkerState>(), 112);
    let state = [
        (offset_of!(MlodWalkerState, time_in_cycle_s), 0),
        (offset_of!(MlodWalkerState, cycle_duration_s), 8),
        (offset_of!(MlodWalkerState, cycle), 16),
        (offset_of!(MlodWalkerState, root_position), 24),
        (offset_of!(MlodWalkerState, cycle_x), 48),
        (offset_of!(MlodWalkerState, cycle_z), 56),
        (offset_of!(MlodWalkerState, heading), 64),
        (offset_of!(MlodWalkerState, root_rotation), 72),
        (offset_of!(MlodWalkerState, body_scale), 88),
        (offset_of!(MlodWalkerState, detail), 92),
        (offset_of!(MlodWalkerState, cycles_begun), 100),
        (offset_of!(MlodWalkerState, foot_locked), 104),
    ];
    for (k, (offset, expected)) in state.into_iter().enumerate() {
        assert_eq!(offset, expected, "MlodWalkerState field {k}");
    }
    let js = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../viewer/mlod.js"),
    )
    .expect("viewer/mlod.js");
    assert!(
        js.contains(&format!("export const ABI_VERSION = {MLOD_ABI_VERSION};")),
        "viewer/mlod.js expects another ABI version than {MLOD_ABI_VERSION}"
    );
}

#[test]
fn buffers_for_hosts_without_an_allocator() {
    assert!(mlod_buffer_new(0).is_null(), "an empty buffer is refused");
    assert!(
        mlod_buffer_new(usize::MAX).is_null(),
        "an impossible size is refused"
    );
    let p = mlod_buffer_new(100);
    assert!(!p.is_null());
    assert_eq!(p as usize % MLOD_BUFFER_ALIGN, 0);
    // SAFETY: 100 bytes from mlod_buffer_new.
    let bytes = unsafe { std::slice::from_raw_parts(p, 100) };
    assert!(bytes.iter().all(|&b| b == 0), "zero-filled");
    // SAFETY: allocated above with this length; null is ignored.
    unsafe {
        mlod_buffer_free(p, 100);
        mlod_buffer_free(std::ptr::null_mut(), 100);
    }
}
