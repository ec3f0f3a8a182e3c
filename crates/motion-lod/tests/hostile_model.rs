//! Hostile model files: truncated at every offset, every byte flipped, a future version, empty,
//! garbage, forged checksums over hostile sections. Every case is a `ModelFileError` naming the
//! file, in bounded time and memory; nothing panics.

use std::path::Path;

use motion_lod::lod_policy::file::{Section, decode_section, frame};
use motion_lod::model_file::{
    FORMAT_VERSION, HEADER_LEN, MAGIC, ModelFileError, SECTION_HEADER_LEN, decode_payload,
};
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

#[path = "../fuzz/seed_model.rs"]
mod seed_model;

#[path = "../fuzz/mutate_model.rs"]
mod mutate_model;

const FIXTURES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures");

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct Small {
    name: String,
    dims: [u32; 3],
    values: Vec<f32>,
    levels: Vec<(usize, f64)>,
    note: Option<String>,
}

fn small() -> Small {
    Small {
        name: "walk".into(),
        dims: [94, 10, 8],
        values: (0..40).map(|i| i as f32 * 0.5).collect(),
        levels: vec![(1, 0.5), (3, 0.25)],
        note: Some("ok".into()),
    }
}

fn p() -> &'static Path {
    Path::new("hostile.mlod")
}

/// The section the framing tests store their values in.
const TAG: [u8; 4] = *b"TEST";

/// A file of one section holding `body`, with the right magic, version and lengths and correct
/// checksums.
fn forge(body: &[u8]) -> Vec<u8> {
    frame(&[Section {
        tag: TAG,
        version: 1,
        bytes: body,
        offset: 0,
    }])
}

/// `value` in a file of one section.
fn encode<T: Serialize>(value: &T) -> Vec<u8> {
    forge(&bincode::serde::encode_to_vec(value, bincode::config::standard()).unwrap())
}

/// The value of a file of one section.
fn decode<T: DeserializeOwned>(bytes: &[u8], path: &Path) -> Result<T, ModelFileError> {
    decode_section(bytes, TAG, 1, "a test value", path)
}

/// The bincode of `small()`, as its section stores it.
fn small_body() -> Vec<u8> {
    encode(&small())[HEADER_LEN + SECTION_HEADER_LEN..].to_vec()
}

fn assert_names_file(e: &ModelFileError) {
    assert!(e.to_string().contains("hostile.mlod"), "{e}");
}

/// Every truncation and every flipped byte of `bytes` is an error of the expected kind.
fn check_truncations_and_flips<T: serde::de::DeserializeOwned>(bytes: &[u8]) {
    for len in 0..bytes.len() {
        let e = decode::<T>(&bytes[..len], p())
            .err()
            .unwrap_or_else(|| panic!("cut at {len} decoded"));
        assert!(
            matches!(
                e,
                ModelFileError::TooShort { .. } | ModelFileError::LengthMismatch { .. }
            ),
            "cut at {len}: {e}"
        );
        assert_names_file(&e);
    }
    let mut bad = bytes.to_vec();
    for i in 0..bytes.len() {
        for bit in [0x01, 0x80] {
            bad[i] ^= bit;
            let e = decode::<T>(&bad, p())
                .err()
                .unwrap_or_else(|| panic!("flip {bit:#x} at {i} decoded"));
            let expected = match i {
                0..8 => matches!(e, ModelFileError::BadMagic { .. }),
                8..12 => matches!(
                    e,
                    ModelFileError::BadVersion { .. }
                        | ModelFileError::FutureVersion { .. }
                        | ModelFileError::OldVersion { .. }
                ),
                12..20 => matches!(e, ModelFileError::LengthMismatch { .. }),
                _ => matches!(e, ModelFileError::Checksum { .. }),
            };
            assert!(expected, "flip {bit:#x} at {i}: {e}");
            bad[i] ^= bit;
        }
    }
}

#[test]
fn small_value_round_trips() {
    let bytes = encode(&small());
    assert_eq!(decode::<Small>(&bytes, p()).unwrap(), small());
}

#[test]
fn small_value_truncated_everywhere_and_flipped_everywhere() {
    check_truncations_and_flips::<Small>(&encode(&small()));
}

#[test]
fn future_and_zero_versions() {
    let mut bytes = encode(&small());
    bytes[8..12].copy_from_slice(&(FORMAT_VERSION + 1).to_le_bytes());
    let e = decode::<Small>(&bytes, p()).unwrap_err();
    assert!(
        matches!(e, ModelFileError::FutureVersion { found, .. } if found == FORMAT_VERSION + 1)
    );
    assert!(e.to_string().contains("newer"), "{e}");
    bytes[8..12].copy_from_slice(&u32::MAX.to_le_bytes());
    assert!(matches!(
        decode::<Small>(&bytes, p()),
        Err(ModelFileError::FutureVersion { .. })
    ));
    bytes[8..12].copy_from_slice(&0u32.to_le_bytes());
    assert!(matches!(
        decode::<Small>(&bytes, p()),
        Err(ModelFileError::BadVersion { found: 0, .. })
    ));
}

#[test]
fn empty_and_garbage_files() {
    let e = decode::<Small>(&[], p()).unwrap_err();
    assert!(matches!(e, ModelFileError::TooShort { len: 0, .. }), "{e}");
    assert_names_file(&e);
    for garbage in [
        &b"HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n}\n"[..],
        b"\x93NUMPY\x01\x00v\x00{'descr': '<f8', 'fortran_order': False}",
        &[0u8; 64],
        &[0xffu8; 1000],
    ] {
        assert!(matches!(
            decode::<Small>(garbage, p()),
            Err(ModelFileError::BadMagic { .. })
        ));
    }
    // The right magic followed by garbage.
    let mut b = MAGIC.to_vec();
    b.extend((0..200u32).map(|i| (i * 37 % 251) as u8));
    assert!(decode::<Small>(&b, p()).is_err());
    // A length field of u64::MAX in a small file.
    let mut b = encode(&small());
    b[12..20].copy_from_slice(&u64::MAX.to_le_bytes());
    assert!(matches!(
        decode::<Small>(&b, p()),
        Err(ModelFileError::LengthMismatch {
            expected: u64::MAX,
            ..
        })
    ));
    // A missing file.
    let e = motion_lod::MotionModel::load(Path::new("/nonexistent/hostile.mlod")).unwrap_err();
    assert!(matches!(e, ModelFileError::Io { .. }));
    assert_names_file(&e);
}

#[test]
fn forged_checksum_over_a_wrong_payload_is_a_decode_error() {
    // Valid frame, payload of another type.
    let e = decode::<Small>(&forge(&[1, 2, 3]), p()).unwrap_err();
    assert!(matches!(e, ModelFileError::Decode { .. }), "{e}");
    assert_names_file(&e);
    // Trailing bytes after a valid payload.
    let mut payload = small_body();
    payload.extend_from_slice(&[0, 0]);
    let e = decode::<Small>(&forge(&payload), p()).unwrap_err();
    assert!(e.to_string().contains("2 trailing bytes"), "{e}");
}

#[test]
fn a_huge_length_prefix_inside_the_payload_is_refused_before_allocating() {
    // `name` (a String) claims 2^33 bytes: bincode would allocate them before reading. The
    // decode limit scales with the payload (a 9-byte payload gets 64 KiB), so this is refused.
    let mut payload = vec![253u8];
    payload.extend_from_slice(&(1u64 << 33).to_le_bytes());
    let e = decode::<Small>(&forge(&payload), p()).unwrap_err();
    assert!(matches!(e, ModelFileError::Decode { .. }), "{e}");
    assert!(e.to_string().to_lowercase().contains("limit"), "{e}");
    // The same for a length just above the budget, and a long Vec<f32>.
    let mut payload = vec![252u8];
    payload.extend_from_slice(&(1u32 << 17).to_le_bytes());
    assert!(decode_payload::<Small>(&payload, p()).is_err());
    let mut payload = small_body();
    let at = 1 + 4 + 3; // after `name` ("walk") and `dims` (three 1-byte varints)
    assert_eq!(payload[at], 40, "length of `values`");
    payload.splice(
        at..=at,
        [253u8].into_iter().chain((1u64 << 40).to_le_bytes()),
    );
    assert!(decode_payload::<Small>(&payload, p()).is_err());
}

#[test]
fn random_payloads_behind_a_valid_frame_never_panic() {
    let mut state = 0x1234_5678_9abc_def0u64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let good = small_body();
    for round in 0..5000 {
        let mut payload = if round % 2 == 0 {
            good.clone()
        } else {
            (0..next() % 200).map(|_| next() as u8).collect()
        };
        for _ in 0..1 + next() % 4 {
            if payload.is_empty() {
                break;
            }
            let at = (next() % payload.len() as u64) as usize;
            payload[at] = next() as u8;
        }
        let r = decode::<Small>(&forge(&payload), p());
        if let Ok(v) = r {
            // Whatever decodes re-encodes to a payload that decodes to the same value.
            let again = encode(&v);
            let back: Small = decode(&again, p()).unwrap();
            assert_eq!(format!("{back:?}"), format!("{v:?}"));
        }
    }
}

/// The small real model of the fuzz targets (`fuzz/seed_model.rs`: 8 cycles, 2 key levels), or
/// `None` with the skip message when the fixtures are missing.
fn small_model() -> Option<motion_lod::MotionModel> {
    if !Path::new(FIXTURES).join("walk_p160_t01.bvh").exists() {
        motion_io::test_data::missing("fixtures/ not found");
        return None;
    }
    Some(seed_model::build_small_model(Path::new(FIXTURES)).unwrap())
}

#[test]
fn real_model_file_is_checked_like_any_other() {
    use motion_lod::MotionModel;
    use motion_lod::lod_policy::RuntimeModel;

    let Some(model) = small_model() else {
        return;
    };
    let read = |bytes: &[u8]| MotionModel::from_bytes(bytes, p());
    let bytes = motion_lod::model_file::encode(&model, p()).unwrap();
    assert_eq!(read(&bytes).unwrap(), model);
    assert_eq!(&RuntimeModel::from_bytes(&bytes).unwrap(), model.runtime());

    // Every truncation; flips at a stride (every byte of a ~100 KB file would be slow in the
    // dev profile): all of the header, then every 7th byte of the sections.
    for len in (0..bytes.len())
        .step_by(13)
        .chain(bytes.len() - 30..bytes.len())
    {
        assert!(read(&bytes[..len]).is_err(), "cut at {len}");
        assert!(
            RuntimeModel::from_bytes(&bytes[..len]).is_err(),
            "cut at {len}"
        );
    }
    let mut bad = bytes.clone();
    for i in (0..HEADER_LEN).chain((HEADER_LEN..bytes.len()).step_by(7)) {
        bad[i] ^= 0x10;
        assert!(read(&bad).is_err(), "flip at {i}");
        assert!(RuntimeModel::from_bytes(&bad).is_err(), "flip at {i}");
        bad[i] ^= 0x10;
    }
    let mut future = bytes.clone();
    future[8..12].copy_from_slice(&(FORMAT_VERSION + 1).to_le_bytes());
    assert!(matches!(
        read(&future),
        Err(ModelFileError::FutureVersion { .. })
    ));

    // Behind forged checksums, corrupted or cut sections reach the decoders and the validation
    // of the runtime model, the pose layout and the report: an error or a model, never a panic,
    // and the runtime reads whatever the offline reader reads.
    let (runtime, report) = mutate_model::RawModel::new(&model).section_bytes();
    assert_eq!(runtime, model.runtime().section_bytes());
    assert_eq!(mutate_model::frame(&runtime, &report), bytes);
    let mut decoded = 0;
    for (which, section) in [(0, &runtime), (1, &report)] {
        for i in (0..section.len()).step_by(section.len() / 300 + 1) {
            let mut bad = section.clone();
            bad[i] = bad[i].wrapping_add(0x41);
            let cut = section[..i].to_vec();
            for (edited, is_cut) in [(bad, false), (cut, true)] {
                let file = if which == 0 {
                    mutate_model::frame(&edited, &report)
                } else {
                    mutate_model::frame(&runtime, &edited)
                };
                let runtime_read = RuntimeModel::from_bytes(&file);
                match read(&file) {
                    Ok(m) => {
                        assert!(!is_cut, "section {which} cut at {i} was read");
                        // As bytes: an edited model may hold NaN, never equal to itself.
                        assert_eq!(
                            runtime_read.as_ref().ok().map(RuntimeModel::section_bytes),
                            Some(m.runtime().section_bytes())
                        );
                        decoded += 1;
                    }
                    Err(e) => assert!(e.to_string().contains("hostile.mlod"), "{e}"),
                }
            }
        }
    }
    println!("{decoded} corrupted sections still decoded (changed numbers)");
}

/// Hand-made files with a valid checksum and a broken part: every command refuses each with a
/// clear error naming what is wrong, and none panics.
#[test]
fn valid_checksum_broken_models_are_refused_by_every_command() {
    let Some(model) = small_model() else {
        return;
    };
    {
        let dir = std::env::temp_dir().join(format!("mlod-hostile-cli-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let raw = || mutate_model::RawModel::new(&model);
        let mut parent = raw();
        parent.runtime.joints[3].parent = Some(200);
        let mut layout_parent = raw();
        layout_parent.layout.skeleton.joints[3].parent = Some(200);
        let mut rank = raw();
        rank.runtime.lod.keys[0].ranks.p = rank.runtime.lod.p + 1;
        let mut nan = raw();
        nan.runtime.lod.keys[0].core[5] = f32::NAN;
        let mut report = raw();
        report.report.row_weights.pop();
        let mut feet = raw();
        let mut broken = *model.feet().expect("the embedded data's model has feet");
        // The hips as an ankle: its parent is the top joint, which has no parent (thigh).
        broken.left.ankle = model.layout.root();
        feet.runtime.feet = Some(broken);
        let mut stature = raw();
        stature.runtime.stature_m = Some(f32::NAN);
        let mut controls = raw();
        controls.runtime.control_names[2] = "style".into();
        let cases = [
            ("parent.mlod", parent, "parent"),
            ("layout-parent.mlod", layout_parent, "parent"),
            ("controls.mlod", controls, "controls"),
            ("rank.mlod", rank, "rank"),
            ("nan.mlod", nan, "non-finite"),
            ("weights.mlod", report, "row weights"),
            ("feet.mlod", feet, "left foot"),
            ("stature.mlod", stature, "stature"),
        ];
        let exe = env!("CARGO_BIN_EXE_motion-lod");
        for (name, value, expected) in cases {
            let path = dir.join(name);
            std::fs::write(&path, value.file()).unwrap();
            let err = motion_lod::MotionModel::load(&path)
                .unwrap_err()
                .to_string();
            assert!(
                err.contains(name) && err.contains(expected),
                "{name}: {err}"
            );
            let path_s = path.to_str().unwrap();
            let out = dir.join("walk.bvh");
            let commands: [&[&str]; 4] = [
                &["info", path_s],
                &["crowd", path_s, "--walkers", "3", "--seconds", "0.1"],
                &[
                    "synth",
                    path_s,
                    "--dx",
                    "0",
                    "--dz",
                    "1",
                    "--turn",
                    "0",
                    "-o",
                    out.to_str().unwrap(),
                ],
                &["eval", path_s],
            ];
            for args in commands {
                let o = std::process::Command::new(exe).args(args).output().unwrap();
                let stderr = String::from_utf8_lossy(&o.stderr);
                assert_eq!(o.status.code(), Some(1), "{args:?}: {stderr}");
                assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
                assert!(stderr.contains(expected), "{args:?}: {stderr}");
            }
        }
        std::fs::remove_dir_all(&dir).ok();
    }
}

/// The `model_mutated` fuzz target's harness on 400 pseudo-random edit lists: every edited model
/// is refused or loads and runs through info, a crowd and a synthesized walk without panicking
/// (a panic fails the test). The counts show that the edits reach each stage.
#[test]
fn mutated_models_never_panic() {
    use mutate_model::Outcome;

    let Some(model) = small_model() else {
        return;
    };
    let seed = mutate_model::Seed::new(&model);
    // The unedited seed loads and runs everywhere.
    assert_eq!(
        mutate_model::run(&seed, &[]),
        Outcome::Loaded {
            crowd_failed: false,
            synth_failed: false
        }
    );
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let (mut not_parts, mut refused, mut loaded, mut failed_later) = (0, 0, 0, 0);
    for _ in 0..400 {
        let len = 6 + (next() % 24) as usize;
        let data: Vec<u8> = (0..len).map(|_| next() as u8).collect();
        match mutate_model::run(&seed, &data) {
            Outcome::NotParts => not_parts += 1,
            Outcome::Refused => refused += 1,
            Outcome::Loaded {
                crowd_failed,
                synth_failed,
            } => {
                loaded += 1;
                if crowd_failed || synth_failed {
                    failed_later += 1;
                }
            }
        }
    }
    println!(
        "400 edit lists: {not_parts} not the parts' layout, {refused} refused on load, \
         {loaded} loaded ({failed_later} of them refused by the crowd or synthesis)"
    );
    assert!(
        refused > 0 && loaded > 0,
        "the edits must reach validation and the consumers"
    );
}

/// A report section of the current version whose layout is another build's (a format change
/// without a version change: the quality reference's `take_steps` of 2026-11-27 became
/// `step_trends` under report version 4) passes every checksum and fails to decode: the error
/// names the section and its version and asks for a rebuild, and the runtime, which skips the
/// report, still reads the file.
#[test]
fn a_section_of_another_builds_layout_asks_for_a_rebuild() {
    use motion_lod::MotionModel;
    use motion_lod::lod_policy::RuntimeModel;
    let Some(model) = small_model() else {
        return;
    };
    let (runtime, report) = mutate_model::RawModel::new(&model).section_bytes();
    // The report with one field's bytes replaced: an `Option` tag no build writes.
    let mut other = report.clone();
    let at = other.len() / 2;
    other.splice(at..at, [168u8]);
    let file = mutate_model::frame(&runtime, &other);
    let e = MotionModel::from_bytes(&file, p()).unwrap_err();
    let text = e.to_string();
    assert!(
        matches!(e, ModelFileError::Decode { .. })
            && text.contains("section RPRT")
            && text.contains("the build report of version")
            && text.contains("rebuild the model with `motion-lod build`"),
        "{text}"
    );
    assert_eq!(
        RuntimeModel::from_bytes(&file).unwrap().section_bytes(),
        runtime
    );
}
