//! Foot joints found by name, leg length, and per-frame foot contacts ("ankle or toe slow and near
//! the floor").

use glam::DVec3;

use crate::skeleton::Skeleton;

/// Errors of foot detection and cycle segmentation.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CycleError {
    /// No joint matches the foot (or the name override) for a side.
    #[error("no {side} foot joint found (names tried: {tried}); set CycleConfig::{side}_foot")]
    FootNotFound {
        /// `left` or `right`.
        side: &'static str,
        /// Names or rules tried.
        tried: String,
    },
    /// An override names a joint that does not exist.
    #[error("joint `{0}` named in the configuration does not exist")]
    UnknownJoint(String),
    /// The two feet share no common ancestor below them (degenerate skeleton).
    #[error("left and right feet do not hang from distinct hips")]
    NoHips,
    /// The leg length is zero or not finite.
    #[error("leg length {0} is not positive")]
    BadLegLength(f64),
    /// The motion has frames with NaN or infinity, or a bad frame time.
    #[error("invalid motion: {0}")]
    BadMotion(String),
    /// A configuration value out of range.
    #[error("invalid configuration: {0}")]
    BadConfig(String),
    /// Pose conversion failed.
    #[error(transparent)]
    Pose(#[from] crate::pose::PoseError),
}

/// The joints used for contacts and the standing height, and the leg length.
#[derive(Debug, Clone, PartialEq)]
pub struct Feet {
    /// Left ankle (foot) joint.
    pub left_foot: usize,
    /// Right ankle (foot) joint.
    pub right_foot: usize,
    /// Left toe joint, when the skeleton has one.
    pub left_toe: Option<usize>,
    /// Right toe joint, when the skeleton has one.
    pub right_toe: Option<usize>,
    /// Left hip: the ancestor of the left foot whose parent is the feet's lowest common ancestor.
    pub left_hip: usize,
    /// Right hip, likewise.
    pub right_hip: usize,
    /// The feet's lowest common ancestor (the pelvis).
    pub pelvis: usize,
    /// Leg length in file units: the longer of the two bone chains pelvis -> foot.
    pub leg_length: f64,
}

/// Side of a joint name: `Some(true)` left, `Some(false)` right, `None` when the name carries no
/// side marker (or both): `left`/`right` anywhere (any case), `l_`/`r_` prefixes, `_l`/`_r` and
/// `.l`/`.r` suffixes, and camel-case `lFoot`/`RFoot` prefixes.
pub fn side_of(name: &str) -> Option<bool> {
    let lower = name.to_ascii_lowercase();
    let b = name.as_bytes();
    let camel = |c: u8| b.len() > 1 && (b[0] == c) && b[1].is_ascii_uppercase();
    let left = lower.contains("left")
        || lower.starts_with("l_")
        || lower.ends_with("_l")
        || lower.ends_with(".l")
        || camel(b'l')
        || camel(b'L');
    let right = lower.contains("right")
        || lower.starts_with("r_")
        || lower.ends_with("_r")
        || lower.ends_with(".r")
        || camel(b'r')
        || camel(b'R');
    match (left, right) {
        (true, false) => Some(true),
        (false, true) => Some(false),
        _ => None,
    }
}

/// Names the joint `name` would have on the other side: every single swap of one side marker that
/// [`side_of`] recognises (`Left`<->`Right` in the case written, `l_`<->`r_`, `_L`<->`_R`, `.l`<->`.r`,
/// `lFoot`<->`rFoot`), without duplicates. Empty for a name without a side marker. A caller picks the
/// candidate that exists in its skeleton.
pub fn mirrored_names(name: &str) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    let mut push = |n: String| {
        if n != name && !out.contains(&n) {
            out.push(n);
        }
    };
    for (a, b) in [
        ("left", "right"),
        ("Left", "Right"),
        ("LEFT", "RIGHT"),
        ("right", "left"),
        ("Right", "Left"),
        ("RIGHT", "LEFT"),
    ] {
        if name.contains(a) {
            push(name.replacen(a, b, 1));
        }
    }
    let swap = |c: char| match c {
        'l' => Some('r'),
        'r' => Some('l'),
        'L' => Some('R'),
        'R' => Some('L'),
        _ => None,
    };
    let chars: Vec<char> = name.chars().collect();
    let n = chars.len();
    let replace_at = |i: usize, c: char| {
        let mut v = chars.clone();
        v[i] = c;
        v.into_iter().collect::<String>()
    };
    if n > 1 {
        // Prefix `l_` / camel `lFoot`.
        if let Some(c) = swap(chars[0]) {
            if chars[1] == '_' || chars[1].is_ascii_uppercase() {
                push(replace_at(0, c));
            }
        }
        // Suffix `_l` / `.l`.
        if let Some(c) = swap(chars[n - 1]) {
            if chars[n - 2] == '_' || chars[n - 2] == '.' {
                push(replace_at(n - 1, c));
            }
        }
    }
    out
}

fn depth(sk: &Skeleton, mut j: usize) -> usize {
    let mut d = 0;
    while let Some(p) = sk.joints[j].parent {
        d += 1;
        j = p;
    }
    d
}

/// Finds a joint by rule: name contains one of `words` (case-insensitive) and is on `left`'s side;
/// the shallowest such joint (optionally below `under`) wins.
fn find_by_name(sk: &Skeleton, words: &[&str], left: bool, under: Option<usize>) -> Option<usize> {
    sk.joints
        .iter()
        .enumerate()
        .filter(|(j, x)| {
            let l = x.name.to_ascii_lowercase();
            words.iter().any(|w| l.contains(w))
                && side_of(&x.name) == Some(left)
                && under.is_none_or(|u| *j != u && sk.is_ancestor_or_self(u, *j))
        })
        .min_by_key(|(j, _)| depth(sk, *j))
        .map(|(j, _)| j)
}

fn lookup(sk: &Skeleton, name: &str) -> Result<usize, CycleError> {
    sk.find(name)
        .ok_or_else(|| CycleError::UnknownJoint(name.into()))
}

/// Name overrides for [`find_feet`]; `None` means "find by name".
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FootNames {
    /// Left ankle joint name.
    pub left_foot: Option<String>,
    /// Right ankle joint name.
    pub right_foot: Option<String>,
    /// Left toe joint name.
    pub left_toe: Option<String>,
    /// Right toe joint name.
    pub right_toe: Option<String>,
}

/// Finds the feet: ankles are the shallowest joints whose name contains `foot` or `ankle` with a
/// side marker (`Left`, `l_`, `_L`, `lFoot` ...); toes are joints below them containing `toe`.
pub fn find_feet(sk: &Skeleton, names: &FootNames) -> Result<Feet, CycleError> {
    let foot = |ov: &Option<String>, left: bool, side: &'static str| -> Result<usize, CycleError> {
        match ov {
            Some(n) => lookup(sk, n),
            None => {
                find_by_name(sk, &["foot", "ankle"], left, None).ok_or(CycleError::FootNotFound {
                    side,
                    tried: "*foot*/*ankle* with a side marker".into(),
                })
            }
        }
    };
    let left_foot = foot(&names.left_foot, true, "left")?;
    let right_foot = foot(&names.right_foot, false, "right")?;
    let toe = |ov: &Option<String>, left: bool, f: usize| -> Result<Option<usize>, CycleError> {
        match ov {
            Some(n) => lookup(sk, n).map(Some),
            None => Ok(find_by_name(sk, &["toe"], left, Some(f))),
        }
    };
    let left_toe = toe(&names.left_toe, true, left_foot)?;
    let right_toe = toe(&names.right_toe, false, right_foot)?;
    // Lowest common ancestor of the feet.
    let mut pelvis = left_foot;
    while !sk.is_ancestor_or_self(pelvis, right_foot) {
        pelvis = sk.joints[pelvis].parent.ok_or(CycleError::NoHips)?;
    }
    let hip_of = |mut f: usize| -> Result<usize, CycleError> {
        if f == pelvis {
            return Err(CycleError::NoHips);
        }
        while sk.joints[f].parent != Some(pelvis) {
            f = sk.joints[f].parent.ok_or(CycleError::NoHips)?;
        }
        Ok(f)
    };
    let left_hip = hip_of(left_foot)?;
    let right_hip = hip_of(right_foot)?;
    if left_hip == right_hip {
        return Err(CycleError::NoHips);
    }
    let leg_length = sk
        .chain_length(pelvis, left_foot)
        .max(sk.chain_length(pelvis, right_foot));
    if !(leg_length.is_finite() && leg_length > 0.0) {
        return Err(CycleError::BadLegLength(leg_length));
    }
    Ok(Feet {
        left_foot,
        right_foot,
        left_toe,
        right_toe,
        left_hip,
        right_hip,
        pelvis,
        leg_length,
    })
}

/// Standing height of the skeleton in file units, from bone lengths only (so it is the same for
/// every take of one skeleton): leg length (pelvis -> ankle) plus the chain from the pelvis to the
/// head (the shallowest joint named `head`, or else the highest-reaching chain) and the head's
/// End Site. It leaves out the ankle height and the scalp, so it underestimates the height of a
/// real person by about 10%.
pub fn standing_height(sk: &Skeleton, feet: &Feet) -> f64 {
    let head = sk
        .joints
        .iter()
        .enumerate()
        .filter(|(j, x)| {
            x.name.to_ascii_lowercase().contains("head") && sk.is_ancestor_or_self(feet.pelvis, *j)
        })
        .min_by_key(|(j, _)| depth(sk, *j))
        .map(|(j, _)| j);
    let trunk = match head {
        Some(h) => {
            sk.chain_length(feet.pelvis, h) + sk.joints[h].end_site.map_or(0.0, |e| e.length())
        }
        None => 0.0,
    };
    feet.leg_length + trunk
}

/// Contact thresholds, relative to the leg length.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactThresholds {
    /// A joint is near the floor when it is less than this many leg lengths above its own floor
    /// level (its lowest height within +-0.75 s).
    pub height: f64,
    /// A joint is slow when its speed is below this many leg lengths per second.
    pub speed: f64,
    /// Contact runs shorter than this (seconds) are removed, then gaps shorter than this are filled.
    pub min_run_seconds: f64,
}

/// Per-frame contacts of one foot: ankle or toe slow and near the floor, then short runs and short
/// gaps removed. `positions[f]` holds the world positions of every joint at frame `f`; y is up.
pub fn foot_contacts(
    positions: &[Vec<DVec3>],
    ankle: usize,
    toe: Option<usize>,
    leg_length: f64,
    frame_time: f64,
    th: &ContactThresholds,
) -> Vec<bool> {
    let n = positions.len();
    let mut contact = vec![false; n];
    if n < 3 {
        return contact;
    }
    // Speed: central difference over +-0.04 s (1 frame at 30 fps, 5 at 120 fps) to damp marker
    // jitter. Floor: the lowest height of the joint within +-0.75 s (a stance always falls in
    // such a window while walking), which follows floors that drift within a take.
    let k = ((0.04 / frame_time).round() as usize).max(1);
    let w = ((0.75 / frame_time).round() as usize).max(2);
    let mut joint_contact = |j: usize| {
        let ys: Vec<f64> = positions.iter().map(|p| p[j].y).collect();
        let floor = rolling_min(&ys, w);
        for f in 0..n {
            let (a, b) = (f.saturating_sub(k), (f + k).min(n - 1));
            let speed =
                (positions[b][j] - positions[a][j]).length() / ((b - a) as f64 * frame_time);
            let near = ys[f] - floor[f] < th.height * leg_length;
            if near && speed < th.speed * leg_length {
                contact[f] = true;
            }
        }
    };
    joint_contact(ankle);
    if let Some(t) = toe {
        joint_contact(t);
    }
    let min_run = ((th.min_run_seconds / frame_time).round() as usize).max(1);
    clean_runs(&mut contact, true, min_run);
    clean_runs(&mut contact, false, min_run);
    contact
}

/// Minimum of `v` over the window `[f - w, f + w]` for every `f` (O(n w), w is small).
fn rolling_min(v: &[f64], w: usize) -> Vec<f64> {
    (0..v.len())
        .map(|f| {
            v[f.saturating_sub(w)..(f + w + 1).min(v.len())]
                .iter()
                .copied()
                .fold(f64::INFINITY, f64::min)
        })
        .collect()
}

/// Flips runs of `value` shorter than `min_run` that lie strictly inside the sequence.
fn clean_runs(c: &mut [bool], value: bool, min_run: usize) {
    let n = c.len();
    let mut i = 0;
    while i < n {
        if c[i] != value {
            i += 1;
            continue;
        }
        let s = i;
        while i < n && c[i] == value {
            i += 1;
        }
        let inside = s > 0 && i < n;
        if i - s < min_run && (inside || value) {
            c[s..i].iter_mut().for_each(|x| *x = !value);
        }
    }
}

/// Frames where a contact run starts (`c[f] && (f == 0 || !c[f-1])`); a run already under way at
/// frame 0 does not count.
pub fn contact_starts(c: &[bool]) -> Vec<usize> {
    (1..c.len()).filter(|&f| c[f] && !c[f - 1]).collect()
}
