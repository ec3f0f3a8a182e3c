//! BVH reader/writer: structure, round trips, malformed input with line numbers, folders.

use glam::DVec3;
use motion_io::{
    BvhErrorKind, Channel, Joint, Motion, Skeleton, parse_bvh, read_bvh, read_folder,
    to_bvh_string, write_bvh,
};
use proptest::prelude::*;

const SMALL: &str = "HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT LeftUpLeg
  {
    OFFSET 10 -5 0
    CHANNELS 3 Xrotation Yrotation Zrotation
    JOINT LeftFoot
    {
      OFFSET 0 -40 0
      CHANNELS 3 Yrotation Zrotation Xrotation
      End Site
      {
        OFFSET 0 0 12
      }
    }
  }
  JOINT Spine
  {
    OFFSET 0 10 0
    CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation
    End Site
    {
      OFFSET 0 30 0
    }
  }
}
MOTION
Frames: 2
Frame Time: 0.0333333
1 90 2 10 20 30 5 6 7 -170 0 179 0 10 0 0 0 0
1.5 91 2.5 11 21 31 5 6 7 170 1 -179 0 10 0 90 0 0
";

fn tmpdir(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("motion-io-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn parses_hierarchy_channels_end_sites_and_frames() {
    let m = parse_bvh(SMALL).unwrap();
    let sk = &m.skeleton;
    assert_eq!(sk.joints.len(), 4);
    assert_eq!(sk.find("LeftFoot"), Some(2));
    assert_eq!(sk.joints[2].parent, Some(1));
    assert_eq!(sk.joints[3].parent, Some(0));
    assert_eq!(
        sk.joints[2].channels,
        vec![Channel::Yrotation, Channel::Zrotation, Channel::Xrotation]
    );
    assert_eq!(sk.joints[2].end_site, Some(DVec3::new(0.0, 0.0, 12.0)));
    assert_eq!(sk.joints[1].end_site, None);
    assert_eq!(sk.channel_count(), 18);
    assert_eq!(m.frame_count(), 2);
    assert!((m.frame_time - 0.0333333).abs() < 1e-12);
    assert_eq!(m.frame(1)[9], 170.0);
}

#[test]
fn forward_kinematics_follows_channel_order_and_position_channels() {
    let m = parse_bvh(SMALL).unwrap();
    let mut t = vec![motion_io::Transform::IDENTITY; 4];
    // Frame with only a 90-degree Z rotation of the root (channel order Z X Y).
    let mut f = vec![0.0; 18];
    f[3] = 90.0;
    f[12] = 1.0; // Spine position channels replace its offset (x only; y, z channels are 0).
    m.skeleton.forward_kinematics(&f, &mut t);
    // Root rotated +90 about z maps local +x to +y: LeftUpLeg offset (10,-5,0) -> (5, 10, 0).
    assert!((t[1].position - DVec3::new(5.0, 10.0, 0.0)).length() < 1e-9);
    assert!((t[3].position - DVec3::new(0.0, 1.0, 0.0)).length() < 1e-9);
    // Intrinsic order: R = Rz(a) Rx(b) Ry(c); compare with an explicit product.
    let mut g = vec![0.0; 18];
    g[3] = 30.0;
    g[4] = 40.0;
    g[5] = 50.0;
    m.skeleton.forward_kinematics(&g, &mut t);
    let expected = glam::DQuat::from_rotation_z(30f64.to_radians())
        * glam::DQuat::from_rotation_x(40f64.to_radians())
        * glam::DQuat::from_rotation_y(50f64.to_radians());
    assert!(t[0].rotation.dot(expected).abs() > 1.0 - 1e-12);
}

#[test]
fn written_file_reads_back_equal() {
    let m = parse_bvh(SMALL).unwrap();
    let dir = tmpdir("write");
    let path = dir.join("out.bvh");
    write_bvh(&m, &path).unwrap();
    let back = read_bvh(&path).unwrap();
    assert_eq!(back.skeleton, m.skeleton);
    assert_eq!(back.frames.len(), m.frames.len());
    for (a, b) in back.frames.iter().zip(&m.frames) {
        assert!((a - b).abs() < 1e-4);
    }
    // No temporary file is left behind.
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn writer_refuses_non_finite_and_bad_shapes() {
    let mut m = parse_bvh(SMALL).unwrap();
    m.frames[20] = f64::NAN;
    let dir = tmpdir("nan");
    let e = write_bvh(&m, dir.join("x.bvh")).unwrap_err();
    assert!(
        matches!(
            e.kind(),
            Some(BvhErrorKind::WriteNonFinite {
                frame: 1,
                channel: 2
            })
        ),
        "{e}"
    );
    m.frames.truncate(5);
    assert!(matches!(
        write_bvh(&m, dir.join("x.bvh")).unwrap_err().kind(),
        Some(BvhErrorKind::BadMotion(_))
    ));
    assert!(!dir.join("x.bvh").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// Replaces the first occurrence of `from` and returns the 1-based line of the change.
fn corrupt(from: &str, to: &str) -> (String, usize) {
    let i = SMALL.find(from).unwrap();
    let line = SMALL[..i].matches('\n').count() + 1;
    (SMALL.replacen(from, to, 1), line)
}

#[test]
fn malformed_files_name_the_line() {
    // Channel count mismatch: declares 3, lists 2.
    let (t, line) = corrupt(
        "CHANNELS 3 Xrotation Yrotation Zrotation",
        "CHANNELS 3 Xrotation Yrotation",
    );
    let e = parse_bvh(&t).unwrap_err();
    assert!(
        matches!(e.kind(), Some(BvhErrorKind::ChannelCount { listed: 2, .. })),
        "{e}"
    );
    assert_eq!(e.line(), Some(line));
    // Unknown channel.
    let (t, line) = corrupt(
        "Yrotation Zrotation Xrotation",
        "Yrotation Wrotation Xrotation",
    );
    let e = parse_bvh(&t).unwrap_err();
    assert!(
        matches!(e.kind(), Some(BvhErrorKind::UnknownChannel(c)) if c == "Wrotation"),
        "{e}"
    );
    assert_eq!(e.line(), Some(line));
    // Non-numeric value in the motion.
    let (t, line) = corrupt("1.5 91", "1.5 abc");
    let e = parse_bvh(&t).unwrap_err();
    assert!(
        matches!(e.kind(), Some(BvhErrorKind::NotANumber(v)) if v == "abc"),
        "{e}"
    );
    assert_eq!(e.line(), Some(line));
    // Non-numeric offset.
    let (t, line) = corrupt("OFFSET 0 -40 0", "OFFSET 0 x 0");
    assert_eq!(parse_bvh(&t).unwrap_err().line(), Some(line));
    // Infinity is rejected.
    let (t, line) = corrupt("1.5 91", "1.5 inf");
    let e = parse_bvh(&t).unwrap_err();
    assert!(matches!(e.kind(), Some(BvhErrorKind::NonFinite(_))), "{e}");
    assert_eq!(e.line(), Some(line));
    // Too few frames: declares 3, has 2; the error points at the last line.
    let (t, _) = corrupt("Frames: 2", "Frames: 3");
    let e = parse_bvh(&t).unwrap_err();
    assert!(
        matches!(
            e.kind(),
            Some(BvhErrorKind::TooFewFrames {
                declared: 3,
                found: 2
            })
        ),
        "{e}"
    );
    assert_eq!(e.line(), Some(SMALL.lines().count()));
    // A frame line with a missing value.
    let (t, line) = corrupt("0 10 0 90 0 0", "0 10 0 90 0");
    let e = parse_bvh(&t).unwrap_err();
    assert!(
        matches!(
            e.kind(),
            Some(BvhErrorKind::FrameLength {
                frame: 1,
                expected: 18,
                found: 17
            })
        ),
        "{e}"
    );
    assert_eq!(e.line(), Some(line));
    // Truncated hierarchy (file ends inside the hierarchy).
    let cut = &SMALL[..SMALL.find("JOINT Spine").unwrap()];
    let e = parse_bvh(cut).unwrap_err();
    assert!(
        matches!(e.kind(), Some(BvhErrorKind::UnexpectedEof { .. })),
        "{e}"
    );
    assert_eq!(e.line(), Some(cut.lines().count()));
    // Missing closing brace before MOTION.
    let (t, line) = corrupt("}\nMOTION", "MOTION");
    let e = parse_bvh(&t).unwrap_err();
    assert!(e.line().is_some_and(|l| l >= line - 1), "{e}");
    // Zero frames.
    let (t, line) = corrupt("Frames: 2", "Frames: 0");
    let e = parse_bvh(&t).unwrap_err();
    assert!(matches!(e.kind(), Some(BvhErrorKind::NoFrames)), "{e}");
    assert_eq!(e.line(), Some(line));
    // Display names the line.
    assert!(e.to_string().contains(&format!(":{line}:")));
    // Empty input does not panic.
    assert!(parse_bvh("").is_err());
}

#[test]
fn crlf_and_extra_frames() {
    let crlf = SMALL.replace('\n', "\r\n");
    assert_eq!(
        parse_bvh(&crlf).unwrap().frames,
        parse_bvh(SMALL).unwrap().frames
    );
    let more = format!("{SMALL}1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18\n");
    let e = parse_bvh(&more).unwrap_err();
    assert!(
        matches!(e.kind(), Some(BvhErrorKind::TooManyFrames { declared: 2 })),
        "{e}"
    );
    assert_eq!(e.line(), Some(more.lines().count()));
}

#[test]
fn folder_with_a_bad_file_reports_it_and_loads_the_rest() {
    let dir = tmpdir("folder");
    std::fs::write(dir.join("b_good.bvh"), SMALL).unwrap();
    std::fs::write(dir.join("a_good.BVH"), SMALL).unwrap();
    std::fs::write(
        dir.join("c_bad.bvh"),
        SMALL.replace("Frame Time: 0.0333333", "Frame Time: fast"),
    )
    .unwrap();
    std::fs::write(dir.join("notes.txt"), "not a bvh").unwrap();
    let r = read_folder(&dir).unwrap();
    let names: Vec<_> = r
        .motions
        .iter()
        .map(|(p, _)| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, ["a_good.BVH", "b_good.bvh"]);
    assert_eq!(r.failed.len(), 1);
    let (p, e) = &r.failed[0];
    assert!(p.ends_with("c_bad.bvh"));
    assert_eq!(
        e.line(),
        Some(
            SMALL
                .lines()
                .position(|l| l.starts_with("Frame Time"))
                .unwrap()
                + 1
        )
    );
    assert!(e.to_string().contains("c_bad.bvh"), "{e}");
    assert!(read_folder(dir.join("missing")).is_err());
    let _ = std::fs::remove_dir_all(&dir);
}

fn arb_motion() -> impl Strategy<Value = Motion> {
    let orders = prop::sample::select(vec![
        [Channel::Xrotation, Channel::Yrotation, Channel::Zrotation],
        [Channel::Zrotation, Channel::Xrotation, Channel::Yrotation],
        [Channel::Yrotation, Channel::Zrotation, Channel::Xrotation],
        [Channel::Zrotation, Channel::Yrotation, Channel::Xrotation],
    ]);
    (
        prop::collection::vec((orders, -50.0..50.0f64, any::<bool>()), 1..6),
        1..5usize,
    )
        .prop_flat_map(|(js, nf)| {
            let mut joints = vec![Joint {
                name: "root".into(),
                parent: None,
                offset: DVec3::ZERO,
                channels: vec![
                    Channel::Xposition,
                    Channel::Yposition,
                    Channel::Zposition,
                    Channel::Zrotation,
                    Channel::Xrotation,
                    Channel::Yrotation,
                ],
                end_site: None,
            }];
            for (i, (o, off, end)) in js.iter().enumerate() {
                joints.push(Joint {
                    name: format!("j{i}"),
                    parent: Some(if *end { 0 } else { i }),
                    offset: DVec3::new(*off, 1.0, -0.5),
                    channels: o.to_vec(),
                    end_site: end.then_some(DVec3::new(0.0, 2.0, 0.0)),
                });
            }
            let sk = Skeleton { joints };
            let n = sk.channel_count() * nf;
            prop::collection::vec(-1000.0..1000.0f64, n).prop_map(move |frames| Motion {
                skeleton: sk.clone(),
                frame_time: 1.0 / 30.0,
                frames,
            })
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    #[test]
    fn text_round_trip_within_1e4(m in arb_motion()) {
        let back = parse_bvh(&to_bvh_string(&m)).unwrap();
        prop_assert_eq!(back.skeleton.joints.len(), m.skeleton.joints.len());
        for (a, b) in back.skeleton.joints.iter().zip(&m.skeleton.joints) {
            prop_assert_eq!(&a.name, &b.name);
            prop_assert_eq!(a.parent, b.parent);
            prop_assert_eq!(&a.channels, &b.channels);
            prop_assert!((a.offset - b.offset).length() < 1e-4);
        }
        for (a, b) in back.frames.iter().zip(&m.frames) {
            prop_assert!((a - b).abs() < 1e-4);
        }
    }
}
