//! Exporter conventions: joint names of every common tool, feet from the hierarchy, up axis, root
//! position semantics, units and reference frames (`motion_io::normalize`).

use motion_io::{
    FootNames, NormalizeOptions, RootPositions, SignedAxis, SkipReason, Units, feet_by_hierarchy,
    find_feet, name_words, normalize_take, parse_bvh, side_of,
};

#[test]
fn side_markers_of_every_common_convention() {
    let pairs = [
        ("LeftFoot", "RightFoot"),
        ("Foot_L", "Foot_R"),
        ("L_Foot", "R_Foot"),
        ("CC_Base_L_Foot", "CC_Base_R_Foot"),
        ("lFoot", "rFoot"),
        ("LeftToeBase", "RightToeBase"),
        ("mixamorig:LeftFoot", "mixamorig:RightFoot"),
        ("foot.L", "foot.R"),
        ("l_ankle", "r_ankle"),
        ("L_Ankle", "R_Ankle"),
        ("LHipJoint", "RHipJoint"),
        ("Bip01 L Foot", "Bip01 R Foot"),
        ("Character1_LeftFoot", "Character1_RightFoot"),
    ];
    for (l, r) in pairs {
        assert_eq!(side_of(l), Some(true), "{l}");
        assert_eq!(side_of(r), Some(false), "{r}");
    }
    for none in [
        "Hips",
        "Spine",
        "LowerBack",
        "abdomen",
        "joint_Root",
        "CC_Base_Hip",
        "mixamorig:Hips",
        "Head",
        "Pelvis",
        "Neck1",
        "root",
    ] {
        assert_eq!(side_of(none), None, "{none}");
    }
}

#[test]
fn names_split_into_words() {
    assert_eq!(name_words("CC_Base_L_Foot"), ["cc", "base", "l", "foot"]);
    assert_eq!(name_words("mixamorig:LeftToeBase"), ["left", "toe", "base"]);
    assert_eq!(name_words("LHipJoint"), ["l", "hip", "joint"]);
    assert_eq!(name_words("lFoot"), ["l", "foot"]);
    assert_eq!(name_words("foot.L"), ["foot", "l"]);
    assert_eq!(name_words("Spine01"), ["spine01"]);
}

/// A small skeleton with the given names for (pelvis, spine, head, hip, knee, ankle, toe) per side,
/// legs along -y, 90 units to the ankle.
fn skeleton_text(names: &[&str; 7], sides: (&str, &str)) -> String {
    let [pelvis, spine, head, hip, knee, ankle, toe] = names;
    let leg = |side: &str, x: f64| {
        let n = |s: &str| s.replace('#', side);
        format!(
            "JOINT {}\n{{\nOFFSET {x} 0 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n\
             JOINT {}\n{{\nOFFSET 0 -45 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n\
             JOINT {}\n{{\nOFFSET 0 -42 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n\
             JOINT {}\n{{\nOFFSET 0 -8 14\nCHANNELS 3 Zrotation Xrotation Yrotation\n\
             End Site\n{{\nOFFSET 0 0 5\n}}\n}}\n}}\n}}\n}}\n",
            n(hip),
            n(knee),
            n(ankle),
            n(toe)
        )
    };
    format!(
        "HIERARCHY\nROOT {pelvis}\n{{\nOFFSET 0 0 0\n\
         CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n\
         JOINT {spine}\n{{\nOFFSET 0 20 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n\
         JOINT {head}\n{{\nOFFSET 0 45 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n\
         End Site\n{{\nOFFSET 0 20 0\n}}\n}}\n}}\n{}{}}}\n",
        leg(sides.0, 10.0),
        leg(sides.1, -10.0)
    )
}

/// A walk of `frames` frames at 30 fps along +z at 1.2 m/s (in centimetres), hips at 95.
fn walking_frames(frames: usize, channels: usize) -> String {
    let mut s = format!("MOTION\nFrames: {frames}\nFrame Time: 0.0333333\n");
    for f in 0..frames {
        let t = f as f64 / 30.0;
        let mut row = vec![0.0; channels];
        row[1] = 95.0;
        row[2] = 120.0 * t;
        // Legs swing in antiphase (the left hip is the 4th joint: channels 9..12 are the spine,
        // head follows; hips at 12 and 24).
        let swing = 25.0 * (std::f64::consts::TAU * t).sin();
        row[12 + 1] = swing;
        row[24 + 1] = -swing;
        for v in row {
            s.push_str(&format!("{v} "));
        }
        s.push('\n');
    }
    s
}

#[test]
fn feet_by_name_in_every_convention() {
    // (joint names with `#` for the side, side markers, expected left foot, expected left toe)
    type Convention<'a> = ([&'a str; 7], (&'a str, &'a str), &'a str, &'a str);
    let conventions: [Convention; 6] = [
        (
            [
                "Hips", "Spine", "Head", "#UpLeg", "#Leg", "#Foot", "#ToeBase",
            ],
            ("Left", "Right"),
            "LeftFoot",
            "LeftToeBase",
        ),
        (
            [
                "CC_Base_Hip",
                "CC_Base_Waist",
                "CC_Base_Head",
                "CC_Base_#_Thigh",
                "CC_Base_#_Calf",
                "CC_Base_#_Foot",
                "CC_Base_#_ToeBase",
            ],
            ("L", "R"),
            "CC_Base_L_Foot",
            "CC_Base_L_ToeBase",
        ),
        (
            [
                "mixamorig:Hips",
                "mixamorig:Spine",
                "mixamorig:Head",
                "mixamorig:#UpLeg",
                "mixamorig:#Leg",
                "mixamorig:#Foot",
                "mixamorig:#ToeBase",
            ],
            ("Left", "Right"),
            "mixamorig:LeftFoot",
            "mixamorig:LeftToeBase",
        ),
        (
            [
                "pelvis", "spine", "head", "thigh.#", "shin.#", "foot.#", "toe.#",
            ],
            ("L", "R"),
            "foot.L",
            "toe.L",
        ),
        (
            [
                "Pelvis", "Spine1", "Head", "#_Hip", "#_Knee", "#_Ankle", "#_Foot",
            ],
            ("L", "R"),
            "L_Ankle",
            "L_Foot",
        ),
        (
            ["hip", "abdomen", "head", "#Thigh", "#Shin", "#Foot", "#Toe"],
            ("l", "r"),
            "lFoot",
            "lToe",
        ),
    ];
    for (names, sides, foot, toe) in conventions {
        let text = skeleton_text(&names, sides) + &walking_frames(3, 6 + 3 * 10);
        let m = parse_bvh(&text).unwrap_or_else(|e| panic!("{foot}: {e}"));
        let sk = &m.skeleton;
        let feet = find_feet(sk, &FootNames::default()).unwrap_or_else(|e| panic!("{foot}: {e}"));
        assert_eq!(sk.joints[feet.left_foot].name, foot);
        assert_eq!(feet.left_toe.map(|t| sk.joints[t].name.as_str()), Some(toe));
        assert!(side_of(&sk.joints[feet.right_foot].name) == Some(false));
    }
}

fn anonymous_walk(frames: usize) -> motion_io::Motion {
    let names = ["j0", "j1", "j2", "j3#", "j4#", "j5#", "j6#"];
    let text = skeleton_text(&names, ("a", "b")) + &walking_frames(frames, 36);
    parse_bvh(&text).expect("parses")
}

#[test]
fn feet_from_the_hierarchy_when_no_name_says_foot() {
    let m = anonymous_walk(90);
    assert!(find_feet(&m.skeleton, &FootNames::default()).is_err());
    let names = feet_by_hierarchy(&m, &FootNames::default()).expect("two legs found");
    // Travelling +z with y up, the walker's left is +x: the leg at x = +10 ("a").
    assert_eq!(names.left_foot.as_deref(), Some("j5a"));
    assert_eq!(names.right_foot.as_deref(), Some("j5b"));
    assert_eq!(names.left_toe.as_deref(), Some("j6a"));
    assert_eq!(names.right_toe.as_deref(), Some("j6b"));
    assert_eq!(
        names.head.as_deref(),
        Some("j2"),
        "the highest joint outside the legs"
    );
    // Travelling the other way without turning round (a mirrored take) swaps them.
    let mut back = m.clone();
    let n = back.skeleton.channel_count();
    for f in back.frames.chunks_exact_mut(n) {
        f[2] = -f[2];
    }
    let names = feet_by_hierarchy(&back, &FootNames::default()).expect("two legs found");
    assert_eq!(names.left_foot.as_deref(), Some("j5b"));
    // A joint map wins over the hierarchy for the roles it names.
    let map = FootNames {
        left_toe: Some("j5a".into()),
        ..FootNames::default()
    };
    let names = feet_by_hierarchy(&m, &map).expect("two legs found");
    assert_eq!(names.left_toe.as_deref(), Some("j5a"));
}

#[test]
fn normalize_detects_units_up_and_root_semantics() {
    let base = anonymous_walk(90);
    let opts = NormalizeOptions::default();
    let n = normalize_take(&base, &opts).expect("normalizes");
    let c = &n.conventions;
    assert_eq!(c.units, Units::Centimetres);
    assert!(c.units_detected && c.up_detected && c.feet_by_hierarchy);
    assert_eq!(c.up, SignedAxis::Y);
    assert_eq!(c.forward, Some(SignedAxis::Z));
    assert_eq!(c.root_positions, RootPositions::Same);
    assert_eq!(n.segments, vec![0..90]);
    assert!(n.skipped.is_empty());
    assert_eq!(
        n.motion, base,
        "a take in the project's conventions is left as it is"
    );

    // Z up: a quarter turn about x (y -> z): channels renamed and signs flipped, exactly undone.
    let mut zup = base.clone();
    let nch = zup.skeleton.channel_count();
    let mut negate = Vec::new();
    for j in &mut zup.skeleton.joints {
        j.offset = glam::DVec3::new(j.offset.x, -j.offset.z, j.offset.y);
        j.end_site = j.end_site.map(|e| glam::DVec3::new(e.x, -e.z, e.y));
        for ch in &mut j.channels {
            use motion_io::Channel::*;
            let (c, neg) = match ch {
                Xposition => (Xposition, false),
                Yposition => (Zposition, false),
                Zposition => (Yposition, true),
                Xrotation => (Xrotation, false),
                Yrotation => (Zrotation, false),
                Zrotation => (Yrotation, true),
            };
            *ch = c;
            negate.push(neg);
        }
    }
    for f in zup.frames.chunks_exact_mut(nch) {
        for (v, &neg) in f.iter_mut().zip(&negate) {
            if neg {
                *v = -*v;
            }
        }
    }
    let nz = normalize_take(&zup, &opts).expect("normalizes");
    assert_eq!(nz.conventions.up, SignedAxis::Z);
    let p0 = base.skeleton.joint_positions(base.frame(40));
    let p1 = nz.motion.skeleton.joint_positions(nz.motion.frame(40));
    for (a, b) in p0.iter().zip(&p1) {
        assert!((*a - *b).length() < 1e-9, "{a} vs {b}");
    }
    // Forcing the wrong axis is obeyed (and reported as given).
    let forced = normalize_take(
        &zup,
        &NormalizeOptions {
            up: Some(SignedAxis::Y),
            ..opts.clone()
        },
    );
    if let Ok(f) = forced {
        assert!(!f.conventions.up_detected);
        assert_eq!(f.conventions.up, SignedAxis::Y);
    }

    // Hip height in the OFFSET, relative channels: rewritten as absolute.
    let mut rel = base.clone();
    rel.skeleton.joints[0].offset.y = 95.0;
    for f in rel.frames.chunks_exact_mut(nch) {
        f[1] -= 95.0;
    }
    let nr = normalize_take(&rel, &opts).expect("normalizes");
    assert_eq!(nr.conventions.root_positions, RootPositions::Relative);
    let p2 = nr.motion.skeleton.joint_positions(nr.motion.frame(40));
    for (a, b) in p0.iter().zip(&p2) {
        assert!((*a - *b).length() < 1e-9, "{a} vs {b}");
    }
    // Absolute channels with the hip height repeated in the OFFSET stay absolute.
    let mut abs = base.clone();
    abs.skeleton.joints[0].offset.y = 95.0;
    let na = normalize_take(&abs, &opts).expect("normalizes");
    assert_eq!(na.conventions.root_positions, RootPositions::Absolute);

    // Metres, millimetres and inches: detected from the standing height.
    for (units, s) in [
        (Units::Metres, 0.01),
        (Units::Millimetres, 10.0),
        (Units::Inches, 1.0 / 2.54),
    ] {
        let mut scaled = base.clone();
        for j in &mut scaled.skeleton.joints {
            j.offset *= s;
            j.end_site = j.end_site.map(|e| e * s);
        }
        for f in scaled.frames.chunks_exact_mut(nch) {
            for v in &mut f[0..3] {
                *v *= s;
            }
        }
        let ns = normalize_take(&scaled, &opts).expect("normalizes");
        assert_eq!(ns.conventions.units, units);
        let h = ns.conventions.standing_height / units.per_metre();
        let h0 = n.conventions.standing_height / 100.0;
        assert!((h - h0).abs() < 1e-9, "{h} vs {h0}");
        // Forced units are kept.
        let forced = normalize_take(
            &scaled,
            &NormalizeOptions {
                units: Some(Units::Centimetres),
                ..opts.clone()
            },
        )
        .expect("normalizes");
        assert_eq!(forced.conventions.units, Units::Centimetres);
        assert!(!forced.conventions.units_detected);
    }
}

#[test]
fn reference_pose_first_frame_and_long_stand_are_skipped() {
    let base = anonymous_walk(90);
    let nch = base.skeleton.channel_count();
    // A reference pose 3 m away in front of the take.
    let mut t = base.clone();
    let mut first = vec![0.0; nch];
    first[0] = 300.0;
    first[1] = 95.0;
    first.extend_from_slice(&t.frames);
    t.frames = first;
    let n = normalize_take(&t, &NormalizeOptions::default()).expect("normalizes");
    assert_eq!(n.segments, vec![1..91]);
    assert_eq!(n.skipped.len(), 1);
    assert_eq!((n.skipped[0].first, n.skipped[0].last), (0, 0));
    assert!(matches!(n.skipped[0].reason, SkipReason::Jump { metres } if metres > 2.9));
    // Two seconds standing before the walk: skipped but for its last half second.
    let mut s = base.clone();
    let mut still = Vec::new();
    for _ in 0..60 {
        still.extend_from_slice(&s.frames[..nch]);
    }
    still.extend_from_slice(&s.frames);
    s.frames = still;
    let n = normalize_take(&s, &NormalizeOptions::default()).expect("normalizes");
    assert_eq!(n.skipped.len(), 1, "{:?}", n.skipped);
    assert_eq!(n.skipped[0].reason, SkipReason::StandingStill);
    assert_eq!(n.skipped[0].first, 0);
    let cut = n.segments[0].start;
    assert!((35..=60).contains(&cut), "walking piece starts at {cut}");
}

#[test]
fn bad_takes_are_errors_not_panics() {
    let mut m = anonymous_walk(10);
    m.frame_time = 0.0;
    assert!(normalize_take(&m, &NormalizeOptions::default()).is_err());
    let mut m = anonymous_walk(10);
    m.frames[5] = f64::NAN;
    assert!(normalize_take(&m, &NormalizeOptions::default()).is_err());
    let mut m = anonymous_walk(10);
    m.frames.clear();
    assert!(normalize_take(&m, &NormalizeOptions::default()).is_err());
    // A map naming a joint that does not exist.
    let m = anonymous_walk(30);
    let map = NormalizeOptions {
        feet: FootNames {
            left_foot: Some("nope".into()),
            ..FootNames::default()
        },
        ..NormalizeOptions::default()
    };
    assert!(normalize_take(&m, &map).is_err());
}
