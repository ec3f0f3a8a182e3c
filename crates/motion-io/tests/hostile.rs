//! Hostile BVH input: every case ends in a clear error (or a correct parse) in bounded time and
//! memory, never a panic, a stack overflow or an allocation sized by a number in the file.
//!
//! Limits under test: at most `MAX_JOINTS` (4096) joints, unique joint names, finite numbers,
//! `Frames:` never trusted for allocation, nesting depth read without recursion.

use motion_io::bvh::MAX_JOINTS;
use motion_io::{BvhError, BvhErrorKind, Motion, parse_bvh, read_bvh, to_bvh_string};

const FIXTURES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures");

/// Two joints, 9 channels, two frames.
const SMALL: &str = "HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT Spine
  {
    OFFSET 0 10 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    End Site
    {
      OFFSET 0 30 0
    }
  }
}
MOTION
Frames: 2
Frame Time: 0.0333333
1 90 2 10 20 30 1 2 3
1.5 91 2.5 11 21 31 4 5 6
";

/// The error of a parse that must fail; its message must name the place.
fn fail(r: Result<Motion, BvhError>) -> BvhError {
    match r {
        Ok(m) => panic!("expected an error, parsed {} frames", m.frame_count()),
        Err(e) => {
            assert!(
                e.to_string().starts_with("<bvh>:"),
                "error names no place: {e}"
            );
            assert!(e.kind().is_some(), "{e}");
            e
        }
    }
}

#[test]
fn small_reference_parses() {
    let m = parse_bvh(SMALL).unwrap();
    assert_eq!((m.skeleton.joints.len(), m.frame_count()), (2, 2));
    // A UTF-8 byte-order mark first (what some Windows tools write) is not part of the text: it
    // gave "expected `HIERARCHY`, found `\u{feff}HIERARCHY`".
    let with_mark = parse_bvh(&format!("\u{feff}{SMALL}")).unwrap();
    assert_eq!(with_mark, m);
}

#[test]
fn duplicate_joint_names_are_rejected_at_the_second_one() {
    let text = SMALL.replace("JOINT Spine", "JOINT Hips");
    let e = fail(parse_bvh(&text));
    let (k, line) = (e.kind().unwrap(), e.line().unwrap_or(0));
    assert!(
        matches!(k, BvhErrorKind::DuplicateJoint(n) if n == "Hips"),
        "{k:?}"
    );
    assert_eq!(line, 6);
}

#[test]
fn joint_declared_after_motion_is_an_error() {
    let text = SMALL.replace("MOTION\n", "MOTION\nJOINT Late\n{\nOFFSET 0 0 0\n}\n");
    let e = fail(parse_bvh(&text));
    let (k, line) = (e.kind().unwrap(), e.line().unwrap_or(0));
    assert!(
        matches!(k, BvhErrorKind::Unexpected { expected, found } if expected.contains("Frames:") && found == "JOINT"),
        "{k:?}"
    );
    assert_eq!(line, 17);
}

#[test]
fn unbalanced_braces_are_errors_with_lines() {
    // One `}` too many: found where MOTION was expected.
    let extra = SMALL.replace("}\nMOTION", "}\n}\nMOTION");
    let e = fail(parse_bvh(&extra));
    let (k, line) = (e.kind().unwrap(), e.line().unwrap_or(0));
    assert!(
        matches!(k, BvhErrorKind::Unexpected { found, .. } if found == "}"),
        "{k:?}"
    );
    assert_eq!(line, 16);
    // The root's `}` missing: the hierarchy ends at MOTION.
    let missing = SMALL.replace("  }\n}\nMOTION", "  }\nMOTION");
    let e = fail(parse_bvh(&missing));
    let (k, _) = (e.kind().unwrap(), e.line().unwrap_or(0));
    assert!(matches!(k, BvhErrorKind::UnexpectedEof { .. }), "{k:?}");
    // A `{` too many.
    let open = SMALL.replace("OFFSET 0 10 0", "{ OFFSET 0 10 0");
    let e = fail(parse_bvh(&open));
    let (k, line) = (e.kind().unwrap(), e.line().unwrap_or(0));
    assert!(
        matches!(k, BvhErrorKind::Unexpected { found, .. } if found == "{"),
        "{k:?}"
    );
    assert_eq!(line, 8);
}

#[test]
fn second_root_is_named() {
    let text = SMALL.replace("}\nMOTION", "}\nROOT Other\n{\nOFFSET 0 0 0\n}\nMOTION");
    let e = fail(parse_bvh(&text));
    let (k, _) = (e.kind().unwrap(), e.line().unwrap_or(0));
    assert!(
        matches!(k, BvhErrorKind::SecondRoot(n) if n == "Other"),
        "{k:?}"
    );
}

/// `n` joints, each a child of the root (wide) or of the previous joint (deep).
fn many_joints(n: usize, deep: bool) -> String {
    let mut s = String::with_capacity(n * 48);
    s.push_str("HIERARCHY\nROOT j0\n{\nOFFSET 0 0 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n");
    for i in 1..n {
        s.push_str("JOINT j");
        s.push_str(&i.to_string());
        s.push_str("\n{\nOFFSET 0 1 0\n");
        if !deep {
            s.push_str("}\n");
        }
    }
    if deep {
        for _ in 1..n {
            s.push_str("}\n");
        }
    }
    s.push_str("}\nMOTION\nFrames: 1\nFrame Time: 0.01\n0 0 0\n");
    s
}

#[test]
fn a_million_joints_wide_is_rejected_at_the_limit() {
    let text = many_joints(1_000_000, false);
    let e = fail(parse_bvh(&text));
    let (k, line) = (e.kind().unwrap(), e.line().unwrap_or(0));
    assert!(
        matches!(k, BvhErrorKind::TooManyJoints { max } if *max == MAX_JOINTS),
        "{k:?}"
    );
    // Joint `j4096` (the 4097th) is declared on line 6 + 4 * 4095.
    assert_eq!(line, 6 + 4 * (MAX_JOINTS - 1));
}

#[test]
fn a_million_joints_deep_is_rejected_without_recursion() {
    let text = many_joints(1_000_000, true);
    let e = fail(parse_bvh(&text));
    let (k, _) = (e.kind().unwrap(), e.line().unwrap_or(0));
    assert!(
        matches!(k, BvhErrorKind::TooManyJoints { max } if *max == MAX_JOINTS),
        "{k:?}"
    );
}

#[test]
fn a_chain_of_max_joints_parses_and_writes_back() {
    for deep in [false, true] {
        let m = parse_bvh(&many_joints(MAX_JOINTS, deep)).unwrap();
        assert_eq!(m.skeleton.joints.len(), MAX_JOINTS);
        let parent = m.skeleton.joints[MAX_JOINTS - 1].parent;
        assert_eq!(parent, Some(if deep { MAX_JOINTS - 2 } else { 0 }));
        let again = parse_bvh(&to_bvh_string(&m)).unwrap();
        assert_eq!(again.skeleton.joints.len(), MAX_JOINTS);
    }
}

#[test]
fn absurd_frame_counts_are_errors_without_allocation() {
    // 10^12 frames declared, two present: reading must neither reserve 10^12 * 9 values nor
    // loop over the declared count.
    let text = SMALL.replace("Frames: 2", "Frames: 1000000000000");
    let e = fail(parse_bvh(&text));
    let (k, _) = (e.kind().unwrap(), e.line().unwrap_or(0));
    assert!(
        matches!(
            k,
            BvhErrorKind::TooFewFrames {
                declared: 1_000_000_000_000,
                found: 2
            }
        ),
        "{k:?}"
    );
    // usize::MAX frames, and a count beyond u64.
    let text = SMALL.replace("Frames: 2", &format!("Frames: {}", usize::MAX));
    let e = fail(parse_bvh(&text));
    let (k, _) = (e.kind().unwrap(), e.line().unwrap_or(0));
    assert!(
        matches!(k, BvhErrorKind::TooFewFrames { found: 2, .. }),
        "{k:?}"
    );
    let text = SMALL.replace("Frames: 2", "Frames: 1000000000000000000000000000000");
    let e = fail(parse_bvh(&text));
    let (k, line) = (e.kind().unwrap(), e.line().unwrap_or(0));
    assert!(matches!(k, BvhErrorKind::NotANumber(_)), "{k:?}");
    assert_eq!(line, 17);
    for bad in ["Frames: -1", "Frames: 2.5", "Frames: 0x10"] {
        let e = fail(parse_bvh(&SMALL.replace("Frames: 2", bad)));
        let (k, _) = (e.kind().unwrap(), e.line().unwrap_or(0));
        assert!(matches!(k, BvhErrorKind::NotANumber(_)), "{bad}: {k:?}");
    }
}

#[test]
fn a_very_long_frame_line_is_rejected_with_its_count() {
    let mut text = SMALL.replace("Frames: 2", "Frames: 1");
    let cut = text.find("1.5 91").unwrap();
    text.truncate(cut - "1 90 2 10 20 30 1 2 3\n".len());
    text.push_str(&"0.5 ".repeat(1_000_000));
    text.push('\n');
    let e = fail(parse_bvh(&text));
    let (k, _) = (e.kind().unwrap(), e.line().unwrap_or(0));
    assert!(
        matches!(
            k,
            BvhErrorKind::FrameLength {
                frame: 0,
                expected: 9,
                found: 1_000_000
            }
        ),
        "{k:?}"
    );
}

#[test]
fn huge_numbers_parse_and_overflowing_ones_are_non_finite() {
    let text = SMALL.replace("1 90 2 10", "1e308 -1.7976931348623157e308 2 10");
    let m = parse_bvh(&text).unwrap();
    assert_eq!(m.frames[0], 1e308);
    assert_eq!(m.frames[1], -f64::MAX);
    let text = SMALL.replace("OFFSET 0 10 0", "OFFSET 0 1e308 0");
    assert_eq!(parse_bvh(&text).unwrap().skeleton.joints[1].offset.y, 1e308);
    // Subnormals and long mantissas are fine.
    let text = SMALL.replace(
        "1 90 2 10",
        "4.9e-324 0.1000000000000000055511151231257827 2 10",
    );
    assert!(parse_bvh(&text).is_ok());
    for (place, from) in [("frame", "1 90 2 10"), ("offset", "OFFSET 0 10 0")] {
        let to = if place == "frame" {
            "1e400 90 2 10"
        } else {
            "OFFSET 0 1e400 0"
        };
        let e = fail(parse_bvh(&SMALL.replace(from, to)));
        let (k, _) = (e.kind().unwrap(), e.line().unwrap_or(0));
        assert!(
            matches!(k, BvhErrorKind::NonFinite(v) if v == "1e400"),
            "{place}: {k:?}"
        );
    }
}

#[test]
fn nan_and_infinity_are_rejected_everywhere() {
    for v in [
        "NaN",
        "nan",
        "inf",
        "-inf",
        "infinity",
        "+Infinity",
        "-1e999",
    ] {
        let e = fail(parse_bvh(&SMALL.replace("1.5 91", &format!("1.5 {v}"))));
        let (k, line) = (e.kind().unwrap(), e.line().unwrap_or(0));
        assert!(
            matches!(k, BvhErrorKind::NonFinite(s) if s == v),
            "{v}: {k:?}"
        );
        assert_eq!(line, 20);
        let e = fail(parse_bvh(
            &SMALL.replace("OFFSET 0 30 0", &format!("OFFSET 0 {v} 0")),
        ));
        let (k, line) = (e.kind().unwrap(), e.line().unwrap_or(0));
        assert!(matches!(k, BvhErrorKind::NonFinite(_)), "{v}: {k:?}");
        assert_eq!(line, 12);
        let e = fail(parse_bvh(
            &SMALL.replace("Frame Time: 0.0333333", &format!("Frame Time: {v}")),
        ));
        let (k, _) = (e.kind().unwrap(), e.line().unwrap_or(0));
        assert!(matches!(k, BvhErrorKind::NonFinite(_)), "{v}: {k:?}");
    }
    for v in ["1,5", "0x1p3", "--1", "1e", ""] {
        if v.is_empty() {
            continue;
        }
        let e = fail(parse_bvh(&SMALL.replace("1.5 91", &format!("{v} 91"))));
        let (k, _) = (e.kind().unwrap(), e.line().unwrap_or(0));
        assert!(matches!(k, BvhErrorKind::NotANumber(_)), "{v}: {k:?}");
    }
}

#[test]
fn crlf_tabs_and_mixed_whitespace_parse_the_same() {
    let reference = parse_bvh(SMALL).unwrap();
    let variants = [
        SMALL.replace('\n', "\r\n"),
        SMALL.replace("  ", "\t"),
        SMALL.replace(' ', "\t").replace('\n', "\r\n"),
        SMALL.replace(' ', " \t \x0c "),
        format!("\u{feff}{SMALL}").replacen('\u{feff}', "", 1),
        format!("\n\n  \t\r\n{SMALL}\n\n\r\n"),
    ];
    for (i, v) in variants.iter().enumerate() {
        let m = parse_bvh(v).unwrap_or_else(|e| panic!("variant {i}: {e}"));
        assert_eq!(m, reference, "variant {i}");
    }
}

#[test]
fn unicode_joint_names_parse_and_write_back() {
    let text = SMALL
        .replace("ROOT Hips", "ROOT 腰")
        .replace("JOINT Spine", "JOINT Épine_🦴");
    let m = parse_bvh(&text).unwrap();
    assert_eq!(m.skeleton.joints[0].name, "腰");
    assert_eq!(m.skeleton.joints[1].name, "Épine_🦴");
    let again = parse_bvh(&to_bvh_string(&m)).unwrap();
    assert_eq!(again.skeleton.joints[1].name, "Épine_🦴");
    // A non-ASCII space (U+3000) is part of a name, not a separator.
    let m = parse_bvh(&SMALL.replace("JOINT Spine", "JOINT Spi\u{3000}ne")).unwrap();
    assert_eq!(m.skeleton.joints[1].name, "Spi\u{3000}ne");
}

#[test]
fn missing_motion_section_is_named() {
    let cut = SMALL.find("MOTION").unwrap();
    let e = fail(parse_bvh(&SMALL[..cut]));
    let (k, line) = (e.kind().unwrap(), e.line().unwrap_or(0));
    assert!(
        matches!(k, BvhErrorKind::UnexpectedEof { expected } if expected.contains("MOTION")),
        "{k:?}"
    );
    assert_eq!(line, 15);
    // MOTION with no header after it.
    let e = fail(parse_bvh(&SMALL[..cut + 7]));
    let (k, _) = (e.kind().unwrap(), e.line().unwrap_or(0));
    assert!(matches!(k, BvhErrorKind::UnexpectedEof { .. }), "{k:?}");
}

#[test]
fn empty_and_blank_files_are_errors() {
    for text in ["", "\n", "   \r\n\t\n", "\0"] {
        let e = fail(parse_bvh(text));
        let (k, _) = (e.kind().unwrap(), e.line().unwrap_or(0));
        assert!(
            matches!(
                k,
                BvhErrorKind::UnexpectedEof { .. } | BvhErrorKind::Unexpected { .. }
            ),
            "{text:?}: {k:?}"
        );
    }
    let e = fail(parse_bvh("MOTION\nFrames: 1\nFrame Time: 0.1\n0\n"));
    let (k, _) = (e.kind().unwrap(), e.line().unwrap_or(0));
    assert!(
        matches!(k, BvhErrorKind::UnexpectedEof { expected } if expected.contains("HIERARCHY")),
        "{k:?}"
    );
}

/// SplitMix64: a small deterministic generator for mutations.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

#[test]
fn binary_garbage_is_rejected() {
    // Not UTF-8: the file reader names the line of the first bad byte.
    let dir = std::env::temp_dir().join(format!("motion-io-hostile-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("garbage.bvh");
    std::fs::write(&path, b"HIERARCHY\nROOT \xff\xfe\x00\x01\n").unwrap();
    let e = read_bvh(&path).unwrap_err();
    assert!(matches!(e.kind(), Some(BvhErrorKind::NotUtf8)), "{e}");
    assert_eq!(e.line(), Some(2));
    assert!(e.to_string().contains("garbage.bvh:2"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
    // Random bytes that happen to be text (lossy-decoded): always an error, never a panic.
    let mut rng = Rng(7);
    for _ in 0..200 {
        let n = rng.below(4096);
        let bytes: Vec<u8> = (0..n).map(|_| rng.next() as u8).collect();
        assert!(parse_bvh(&String::from_utf8_lossy(&bytes)).is_err());
    }
}

/// The plain-test counterpart of the `bvh` fuzz target: seeded mutations of the fixtures and
/// of `SMALL` (byte flips, token swaps, truncations, splices) must parse or fail cleanly, and
/// whatever parses must write back as text that parses to the same shape.
#[test]
fn mutated_fixtures_never_panic() {
    let mut seeds = vec![SMALL.to_string()];
    if let Ok(dir) = std::fs::read_dir(FIXTURES) {
        let mut files: Vec<_> = dir
            .flatten()
            .map(|e| e.path())
            .filter(|p| p.extension().is_some_and(|x| x == "bvh"))
            .collect();
        files.sort();
        for f in files.iter().take(3) {
            let text = std::fs::read_to_string(f).unwrap();
            // The hierarchy and a few frames: mutations reach every part quickly.
            let keep = text
                .match_indices('\n')
                .nth(150)
                .map_or(text.len(), |(i, _)| i + 1);
            let head = &text[..keep];
            let frames = head
                .lines()
                .skip_while(|l| !l.starts_with("Frame Time"))
                .count()
                - 1;
            let start = head.find("Frames:").unwrap();
            let end = start + head[start..].find('\n').unwrap();
            seeds.push(format!(
                "{}Frames: {frames}{}",
                &head[..start],
                &head[end..]
            ));
        }
    }
    assert!(parse_bvh(&seeds[seeds.len() - 1]).is_ok());
    let words = [
        "{",
        "}",
        "JOINT",
        "End",
        "Site",
        "ROOT",
        "MOTION",
        "CHANNELS",
        "OFFSET",
        "0",
        "-1",
        "1e400",
        "nan",
        "Frames:",
        "Frame",
        "Time:",
        "\n",
        "7",
        "Xrotation",
        "Hips",
    ];
    let mut rng = Rng(2024);
    let mut parsed = 0;
    for round in 0..3000 {
        let mut bytes = seeds[round % seeds.len()].clone().into_bytes();
        for _ in 0..1 + rng.below(4) {
            let at = rng.below(bytes.len());
            match rng.below(5) {
                0 => bytes[at] ^= 1 << rng.below(8),
                1 => bytes.truncate(at),
                2 => {
                    let w = words[rng.below(words.len())];
                    bytes.splice(at..at, format!(" {w} ").into_bytes());
                }
                3 => {
                    let len = rng.below(64).min(bytes.len() - at);
                    bytes.drain(at..at + len);
                }
                _ => {
                    let from = rng.below(bytes.len());
                    let len = rng.below(64).min(bytes.len() - from);
                    let chunk: Vec<u8> = bytes[from..from + len].to_vec();
                    bytes.splice(at..at, chunk);
                }
            }
            if bytes.is_empty() {
                break;
            }
        }
        let text = String::from_utf8_lossy(&bytes);
        if let Ok(m) = parse_bvh(&text) {
            parsed += 1;
            let nch = m.skeleton.channel_count();
            assert!(nch > 0 && m.frames.len() == nch * m.frame_count());
            let again = parse_bvh(&to_bvh_string(&m))
                .unwrap_or_else(|e| panic!("round {round}: written text does not read: {e}"));
            assert_eq!(again.skeleton.joints.len(), m.skeleton.joints.len());
            assert_eq!(again.frame_count(), m.frame_count());
        }
    }
    // Some mutations keep the file valid (a changed digit): the check above ran.
    assert!(parsed > 10, "only {parsed} mutants parsed");
}
