//! The checked-in C header is what cbindgen makes of the current source, and every library name it
//! mentions, in a declaration or a comment, is a function, type or constant the library has.
//!
//! To regenerate it after changing the ABI:
//! `MOTION_LOD_BLESS_HEADER=1 cargo test -p motion-lod-ffi --test integration header::`.

use std::collections::BTreeSet;
use std::path::Path;

use motion_lod_ffi::*;

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
         `MOTION_LOD_BLESS_HEADER=1 cargo test -p motion-lod-ffi --test integration header::`",
        path.display()
    );
}

/// The library's names as C sees them, each checked by the compiler to be an item of the crate:
/// functions (`mlod_*`), types (`Mlod*`), constants and the status codes (`MLOD_*`). A function,
/// type or status added to the library without being listed here fails the test below (its name
/// in the header is unknown); one listed here that the library lacks does not compile.
struct Known {
    functions: BTreeSet<&'static str>,
    others: BTreeSet<String>,
    /// Every status variant with its value.
    statuses: Vec<(&'static str, i32)>,
}

macro_rules! functions {
    ($($f:ident),* $(,)?) => {
        [$({
            let _ = $f as *const ();
            stringify!($f)
        }),*]
    };
}

macro_rules! types {
    ($($t:ident),* $(,)?) => {
        [$({
            let _ = std::mem::size_of::<$t>();
            stringify!($t)
        }),*]
    };
}

macro_rules! statuses {
    ($($v:ident),* $(,)?) => {{
        // Every variant is listed: a new one makes this match non-exhaustive.
        fn _every_status_is_listed(s: MlodStatus) {
            match s {
                $(MlodStatus::$v => {}),*
            }
        }
        [$((stringify!($v), MlodStatus::$v as i32)),*]
    }};
}

/// `BufferTooSmall` as cbindgen writes an enum variant: `BUFFER_TOO_SMALL`.
fn screaming_snake(name: &str) -> String {
    let mut out = String::new();
    for (k, c) in name.chars().enumerate() {
        if c.is_ascii_uppercase() && k > 0 {
            out.push('_');
        }
        out.push(c.to_ascii_uppercase());
    }
    out
}

fn known() -> Known {
    let functions = functions![
        mlod_version,
        mlod_abi_version,
        mlod_model_from_bytes,
        mlod_model_load,
        mlod_model_free,
        mlod_model_sizes,
        mlod_model_joint,
        mlod_model_joint_rest,
        mlod_model_root_joint,
        mlod_model_control_range,
        mlod_model_ignored_controls,
        mlod_model_style_count,
        mlod_model_style_name,
        mlod_model_style_share,
        mlod_model_detail_at,
        mlod_model_detail_from_camera,
        mlod_walker_new,
        mlod_walker_free,
        mlod_walker_prepare,
        mlod_walker_pose,
        mlod_walker_start,
        mlod_walker_advance,
        mlod_walker_set_foot_lock,
        mlod_walker_set_seam_blend,
        mlod_walkers_step,
        mlod_walker_detail_from_camera,
        mlod_walker_joint_transforms,
        mlod_walker_local_rotations,
        mlod_walker_shown_pose,
        mlod_last_error,
        mlod_buffer_new,
        mlod_buffer_free,
    ];
    let types = types![
        MlodStatus,
        MlodControls,
        MlodDetail,
        MlodCycle,
        MlodJointTransform,
        MlodQuat,
        MlodWalkerState,
        MlodCamera,
        MlodModel,
        MlodWalker,
    ];
    let statuses = statuses![
        Ok,
        NullPointer,
        InvalidArgument,
        InvalidModel,
        Io,
        BufferTooSmall,
        NotPrepared,
        Panic,
    ];
    let _ = (
        MLOD_ABI_VERSION,
        MLOD_MAX_STEP_S,
        MLOD_MAX_STYLES,
        MLOD_BUFFER_ALIGN,
        MLOD_SEAM_HALFLIFE_S,
    );
    let mut others: BTreeSet<String> = types.iter().map(|t| t.to_string()).collect();
    others.extend([
        "MLOD_ABI_VERSION".to_string(),
        "MLOD_MAX_STEP_S".to_string(),
        "MLOD_MAX_STYLES".to_string(),
        "MLOD_BUFFER_ALIGN".to_string(),
        "MLOD_SEAM_HALFLIFE_S".to_string(),
    ]);
    others.extend(
        statuses
            .iter()
            .map(|(v, _)| format!("MLOD_STATUS_{}", screaming_snake(v))),
    );
    Known {
        functions: functions.into_iter().collect(),
        others,
        statuses: statuses.to_vec(),
    }
}

/// Every identifier of `text` that names something of the library: `mlod_...`, `Mlod...` or
/// `MLOD_...` (a bare `mlod`, as in a `.mlod` file name, is not a name).
fn library_names(text: &str) -> BTreeSet<&str> {
    text.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .filter(|w| {
            w.starts_with("mlod_")
                || w.starts_with("MLOD_")
                || (w.starts_with("Mlod") && w[4..].starts_with(|c: char| c.is_ascii_uppercase()))
        })
        .collect()
}

/// The functions the header declares: a name followed by `(` at the start of a declaration.
fn declared_functions(header: &str) -> BTreeSet<&str> {
    header
        .lines()
        .filter(|l| !l.starts_with(' ') && l.contains('('))
        .filter_map(|l| {
            let name = l[..l.find('(')?].rsplit([' ', '*']).next()?;
            name.starts_with("mlod_").then_some(name)
        })
        .collect()
}

#[test]
fn every_name_in_the_header_exists() {
    let header = include_str!("../include/motion_lod.h");
    let known = known();
    let unknown: Vec<&str> = library_names(header)
        .into_iter()
        .filter(|n| !known.functions.contains(n) && !known.others.contains(*n))
        .collect();
    assert!(
        unknown.is_empty(),
        "motion_lod.h names what the library does not have: {unknown:?}"
    );
    // The list above is the library's: the header declares every function in it and no other.
    let declared = declared_functions(header);
    assert_eq!(
        declared, known.functions,
        "functions declared in the header"
    );
    // The status codes carry the library's values.
    for &(v, value) in &known.statuses {
        let line = format!("MLOD_STATUS_{} = {value},", screaming_snake(v));
        assert!(header.contains(&line), "the header lacks `{line}`");
    }
    // The crate's own documentation names only what exists, too.
    let docs: String = include_str!("../src/lib.rs")
        .lines()
        .filter(|l| l.trim_start().starts_with("//"))
        .map(|l| l.to_string() + "\n")
        .collect();
    let unknown: Vec<&str> = library_names(&docs)
        .into_iter()
        .filter(|n| !known.functions.contains(n) && !known.others.contains(*n))
        .collect();
    assert!(
        unknown.is_empty(),
        "src/lib.rs's comments name what the library does not have: {unknown:?}"
    );
}

#[test]
fn the_name_check_finds_a_name_that_does_not_exist() {
    let known = known();
    let text = "/* the pose has `mlod_model_pose_len` floats; see MlodPose and MLOD_STATUS_GONE */";
    let unknown: Vec<&str> = library_names(text)
        .into_iter()
        .filter(|n| !known.functions.contains(n) && !known.others.contains(*n))
        .collect();
    assert_eq!(
        unknown,
        ["MLOD_STATUS_GONE", "MlodPose", "mlod_model_pose_len"]
    );
    assert!(library_names("walk.mlod and Mlodder").is_empty());
}
