//! The checked-in C header is what cbindgen makes of the current source.
//!
//! To regenerate it after changing the ABI: `MOTION_LOD_BLESS_HEADER=1 cargo test -p motion-lod-ffi --test header`.

use std::path::Path;

#[test]
fn header_is_current() {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config =
        cbindgen::Config::from_file(crate_dir.join("cbindgen.toml")).expect("cbindgen.toml");
    let bindings = cbindgen::Builder::new()
        .with_crate(crate_dir)
        .with_config(config)
        .generate()
        .expect("cbindgen parses the crate");
    let mut generated = Vec::new();
    bindings.write(&mut generated);
    let path = crate_dir.join("include/motion_lod.h");
    if std::env::var_os("MOTION_LOD_BLESS_HEADER").is_some() {
        std::fs::write(&path, &generated).expect("write the header");
        return;
    }
    let checked_in = std::fs::read(&path).unwrap_or_default();
    assert!(
        checked_in == generated,
        "{} is out of date with src/lib.rs; regenerate it with \
         `MOTION_LOD_BLESS_HEADER=1 cargo test -p motion-lod-ffi --test header`",
        path.display()
    );
}
