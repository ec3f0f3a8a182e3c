//! Skeleton variants of the procedural walker's takes (`fixtures/variants/<variant>/`): the same
//! walks written the way other tools export them, so that tests can check that every convention
//! gives the same cycles and controls as the base takes.
//!
//! Each variant rewrites the base take exactly (a rotation that renames channels, a unit scale, new
//! joint names, an OFFSET moved out of the channels, one frame added in front); only the decimals
//! printed differ (6 for metres, 4 otherwise).

use std::fmt::Write as _;

use glam::DVec3;
use motion_io::{Channel, Motion};

use crate::fixtures::{FixtureFile, bvh_text_with};

/// The takes of the base set the variants are made from (one turning, one straight; two performers).
pub const VARIANT_TAKES: [&str; 2] = ["walk_p160_t01.bvh", "walk_p190_t03.bvh"];

/// One variant: folder name and what it changes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Variant {
    /// Z up (a quarter turn about x: y becomes z).
    ZUp,
    /// Metres instead of centimetres.
    Metres,
    /// Millimetres.
    Millimetres,
    /// Inches.
    Inches,
    /// iClone / Character Creator joint names (`CC_Base_L_Foot`).
    IcloneNames,
    /// Mixamo joint names (`mixamorig:LeftFoot`).
    MixamoNames,
    /// cgspeed CMU conversion joint names (`LeftUpLeg`, `LeftToeBase`, `LowerBack`).
    CgspeedNames,
    /// Names that say nothing (`j00`...): the feet must come from the hierarchy.
    AnonymousNames,
    /// The hip height in the root OFFSET, the position channels relative to it.
    RootOffset,
    /// A T-pose frame in front of the take, away from where the walk starts.
    TPoseFirst,
}

impl Variant {
    /// Every variant, in folder order.
    pub const ALL: [Variant; 10] = [
        Variant::ZUp,
        Variant::Metres,
        Variant::Millimetres,
        Variant::Inches,
        Variant::IcloneNames,
        Variant::MixamoNames,
        Variant::CgspeedNames,
        Variant::AnonymousNames,
        Variant::RootOffset,
        Variant::TPoseFirst,
    ];

    /// Folder name under `fixtures/variants/`.
    pub fn folder(self) -> &'static str {
        match self {
            Variant::ZUp => "z-up",
            Variant::Metres => "metres",
            Variant::Millimetres => "millimetres",
            Variant::Inches => "inches",
            Variant::IcloneNames => "iclone-names",
            Variant::MixamoNames => "mixamo-names",
            Variant::CgspeedNames => "cgspeed-names",
            Variant::AnonymousNames => "anonymous-names",
            Variant::RootOffset => "root-offset",
            Variant::TPoseFirst => "t-pose-first",
        }
    }

    /// One line on what the variant changes (for the README).
    pub fn description(self) -> &'static str {
        match self {
            Variant::ZUp => "Z up: every offset and channel turned a quarter turn about x (y -> z)",
            Variant::Metres => "metres (6 decimals)",
            Variant::Millimetres => "millimetres",
            Variant::Inches => "inches",
            Variant::IcloneNames => "iClone / Character Creator names (`CC_Base_L_Foot`)",
            Variant::MixamoNames => "Mixamo names (`mixamorig:LeftFoot`)",
            Variant::CgspeedNames => "cgspeed CMU names (`LeftUpLeg`, `LeftToeBase`, `LowerBack`)",
            Variant::AnonymousNames => {
                "names that say nothing (`j00`..`j18`): feet from the hierarchy"
            }
            Variant::RootOffset => {
                "hip height in the root OFFSET, position channels relative to it"
            }
            Variant::TPoseFirst => "a T-pose first frame 3 m away from the walk",
        }
    }

    /// The variant of one base take.
    pub fn apply(self, base: &Motion) -> Motion {
        let mut m = base.clone();
        match self {
            Variant::ZUp => rotate_y_to_z(&mut m),
            Variant::Metres => scale(&mut m, 0.01),
            Variant::Millimetres => scale(&mut m, 10.0),
            Variant::Inches => scale(&mut m, 1.0 / 2.54),
            Variant::IcloneNames => rename(&mut m, iclone_name),
            Variant::MixamoNames => rename(&mut m, mixamo_name),
            Variant::CgspeedNames => rename(&mut m, cgspeed_name),
            Variant::AnonymousNames => {
                for (j, joint) in m.skeleton.joints.iter_mut().enumerate() {
                    joint.name = format!("j{j:02}");
                }
            }
            Variant::RootOffset => root_offset(&mut m),
            Variant::TPoseFirst => t_pose_first(&mut m),
        }
        m
    }

    /// Decimals printed for the frames.
    fn decimals(self) -> usize {
        match self {
            Variant::Metres => 6,
            _ => 4,
        }
    }
}

/// Every variant file (`variants/<folder>/<take>`) of the given base takes `(file name, motion)`,
/// and `variants/README.md`.
pub fn variant_files(base: &[(String, Motion)]) -> Vec<FixtureFile> {
    let mut files = Vec::new();
    for v in Variant::ALL {
        for (name, m) in base {
            if !VARIANT_TAKES.contains(&name.as_str()) {
                continue;
            }
            files.push(FixtureFile {
                name: format!("variants/{}/{name}", v.folder()),
                content: bvh_text_with(&v.apply(m), v.decimals()),
            });
        }
    }
    let mut readme = String::from(
        "# fixtures/variants: the walker's takes as other tools export them\n\n\
         Generated by `cargo xtask fixtures`; do not edit by hand. Each folder holds the takes\n",
    );
    let _ = writeln!(
        readme,
        "{} of `fixtures/`, rewritten exactly in one exporter convention; every folder must give the\n\
         same cycles and controls (in metres) as those takes (`crates/motion-lod/tests/skeleton_variants.rs`).\n",
        VARIANT_TAKES
            .iter()
            .map(|t| format!("`{t}`"))
            .collect::<Vec<_>>()
            .join(" and ")
    );
    for v in Variant::ALL {
        let _ = writeln!(readme, "- `{}/`: {}", v.folder(), v.description());
    }
    files.push(FixtureFile {
        name: "variants/README.md".into(),
        content: readme,
    });
    files
}

/// A quarter turn about x taking +y to +z: `(x, y, z) -> (x, -z, y)`. Offsets rotate; a channel
/// about (or along) old y becomes one about new z, old z becomes new -y (value negated).
fn rotate_y_to_z(m: &mut Motion) {
    let rot = |v: DVec3| DVec3::new(v.x, -v.z, v.y);
    let n = m.skeleton.channel_count();
    let mut negate = Vec::with_capacity(n);
    for joint in &mut m.skeleton.joints {
        joint.offset = rot(joint.offset);
        joint.end_site = joint.end_site.map(rot);
        for c in &mut joint.channels {
            let (new, neg) = match c {
                Channel::Xposition => (Channel::Xposition, false),
                Channel::Yposition => (Channel::Zposition, false),
                Channel::Zposition => (Channel::Yposition, true),
                Channel::Xrotation => (Channel::Xrotation, false),
                Channel::Yrotation => (Channel::Zrotation, false),
                Channel::Zrotation => (Channel::Yrotation, true),
            };
            *c = new;
            negate.push(neg);
        }
    }
    for frame in m.frames.chunks_exact_mut(n) {
        for (v, &neg) in frame.iter_mut().zip(&negate) {
            if neg {
                *v = -*v;
            }
        }
    }
}

/// Scales every length (offsets, End Sites, position channels) by `s`.
fn scale(m: &mut Motion, s: f64) {
    let mut position = Vec::new();
    for joint in &mut m.skeleton.joints {
        joint.offset *= s;
        joint.end_site = joint.end_site.map(|e| e * s);
        position.extend(joint.channels.iter().map(|c| c.is_position()));
    }
    let n = position.len();
    for frame in m.frames.chunks_exact_mut(n) {
        for (v, &p) in frame.iter_mut().zip(&position) {
            if p {
                *v *= s;
            }
        }
    }
}

fn rename(m: &mut Motion, f: fn(&str) -> String) {
    for joint in &mut m.skeleton.joints {
        joint.name = f(&joint.name);
    }
}

/// Splits `UpperLeg_L` into (`UpperLeg`, Some(true)).
fn split_side(name: &str) -> (&str, Option<bool>) {
    if let Some(b) = name.strip_suffix("_L") {
        (b, Some(true))
    } else if let Some(b) = name.strip_suffix("_R") {
        (b, Some(false))
    } else {
        (name, None)
    }
}

fn iclone_name(name: &str) -> String {
    let (base, side) = split_side(name);
    let part = match base {
        "Hips" => "Hip",
        "Spine" => "Waist",
        "Chest" => "Spine01",
        "Neck" => "NeckTwist01",
        "UpperArm" => "Upperarm",
        "LowerArm" => "Forearm",
        "UpperLeg" => "Thigh",
        "LowerLeg" => "Calf",
        "Toes" => "ToeBase",
        other => other,
    };
    match side {
        Some(true) => format!("CC_Base_L_{part}"),
        Some(false) => format!("CC_Base_R_{part}"),
        None => format!("CC_Base_{part}"),
    }
}

fn mixamo_name(name: &str) -> String {
    let (base, side) = split_side(name);
    let part = match base {
        "Chest" => "Spine1",
        "UpperArm" => "Arm",
        "LowerArm" => "ForeArm",
        "UpperLeg" => "UpLeg",
        "LowerLeg" => "Leg",
        "Toes" => "ToeBase",
        other => other,
    };
    match side {
        Some(true) => format!("mixamorig:Left{part}"),
        Some(false) => format!("mixamorig:Right{part}"),
        None => format!("mixamorig:{part}"),
    }
}

fn cgspeed_name(name: &str) -> String {
    let (base, side) = split_side(name);
    let part = match base {
        "Spine" => "LowerBack",
        "Chest" => "Spine",
        "UpperArm" => "Arm",
        "LowerArm" => "ForeArm",
        "UpperLeg" => "UpLeg",
        "LowerLeg" => "Leg",
        "Toes" => "ToeBase",
        other => other,
    };
    match side {
        Some(true) => format!("Left{part}"),
        Some(false) => format!("Right{part}"),
        None => part.to_string(),
    }
}

/// Moves the root's rest height (its mean height over the take, to 0.1 units) into its OFFSET and
/// subtracts it from the Yposition channel.
fn root_offset(m: &mut Motion) {
    let n = m.skeleton.channel_count();
    let Some(k) = m.skeleton.joints[0]
        .channels
        .iter()
        .position(|c| *c == Channel::Yposition)
    else {
        return;
    };
    let nf = m.frame_count().max(1);
    let mean = m.frames.iter().skip(k).step_by(n).sum::<f64>() / nf as f64;
    let h = (mean * 10.0).round() / 10.0;
    m.skeleton.joints[0].offset.y += h;
    for frame in m.frames.chunks_exact_mut(n) {
        frame[k] -= h;
    }
}

/// Puts a T-pose frame in front: every rotation zero but the upper arms raised sideways (Zrotation
/// +-90 degrees), the root 3 m to the side of the first frame, at the same height.
fn t_pose_first(m: &mut Motion) {
    let n = m.skeleton.channel_count();
    let first = m.frame(0).to_vec();
    let mut t = vec![0.0; n];
    let mut k = 0;
    for joint in &m.skeleton.joints {
        for c in &joint.channels {
            t[k] = match c {
                Channel::Xposition => first[k] + 300.0,
                Channel::Yposition | Channel::Zposition => first[k],
                Channel::Zrotation if joint.name == "UpperArm_L" => 90.0,
                Channel::Zrotation if joint.name == "UpperArm_R" => -90.0,
                _ => 0.0,
            };
            k += 1;
        }
    }
    let mut frames = t;
    frames.extend_from_slice(&m.frames);
    m.frames = frames;
}
