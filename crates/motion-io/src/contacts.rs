//! Foot joints found by name, leg length, and per-frame foot contacts ("ankle or toe slow and near
//! the floor").

use glam::DVec3;
use serde::{Deserialize, Serialize};

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
    /// The head: the joint the names override gives, else the shallowest joint below the pelvis
    /// whose name contains `head`; `None` when there is none.
    pub head: Option<usize>,
}

/// The words of a joint name, lower-case: the part after the last `:` (a namespace such as
/// `mixamorig:`), split at every character that is not a letter or digit and at case changes
/// (`CC_Base_L_Foot` -> `cc`, `base`, `l`, `foot`; `lFoot` -> `l`, `foot`; `LHipJoint` -> `l`, `hip`,
/// `joint`; `LeftToeBase` -> `left`, `toe`, `base`).
pub fn name_words(name: &str) -> Vec<String> {
    let name = name.rsplit(':').next().unwrap_or(name);
    let mut words = Vec::new();
    for part in name.split(|c: char| !c.is_ascii_alphanumeric()) {
        let chars: Vec<char> = part.chars().collect();
        let mut word = String::new();
        for (i, &c) in chars.iter().enumerate() {
            let boundary = i > 0
                && c.is_ascii_uppercase()
                && (chars[i - 1].is_ascii_lowercase()
                    || chars[i - 1].is_ascii_digit()
                    || (chars[i - 1].is_ascii_uppercase()
                        && chars.get(i + 1).is_some_and(|n| n.is_ascii_lowercase())));
            if boundary && !word.is_empty() {
                words.push(std::mem::take(&mut word));
            }
            word.push(c.to_ascii_lowercase());
        }
        if !word.is_empty() {
            words.push(word);
        }
    }
    words
}

/// Side of a joint name: `Some(true)` left, `Some(false)` right, `None` when the name carries no
/// side marker (or both): `left`/`right` anywhere (any case), `l_`/`r_` prefixes, `_l`/`_r` and
/// `.l`/`.r` suffixes, camel-case `lFoot`/`RFoot` prefixes, and a word `l`/`r` anywhere in the name
/// ([`name_words`]: `CC_Base_L_Foot`, `mixamorig:LeftFoot`, `LHipJoint`).
pub fn side_of(name: &str) -> Option<bool> {
    let lower = name.to_ascii_lowercase();
    let b = name.as_bytes();
    let camel = |c: u8| b.len() > 1 && (b[0] == c) && b[1].is_ascii_uppercase();
    let words = name_words(name);
    let word = |w: &str| words.iter().any(|x| x == w);
    let left = lower.contains("left")
        || lower.starts_with("l_")
        || lower.ends_with("_l")
        || lower.ends_with(".l")
        || camel(b'l')
        || camel(b'L')
        || word("l");
    let right = lower.contains("right")
        || lower.starts_with("r_")
        || lower.ends_with("_r")
        || lower.ends_with(".r")
        || camel(b'r')
        || camel(b'R')
        || word("r");
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
///
/// Takes time proportional to the size of its result (at most one candidate per character of
/// `name`, each as long as `name`).
pub fn mirrored_names(name: &str) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    // Whole-word swaps change the length by one byte (`left` <-> `right`): they never equal
    // `name` nor a single-letter swap below, and there are at most six of them to deduplicate.
    for (a, b) in [
        ("left", "right"),
        ("Left", "Right"),
        ("LEFT", "RIGHT"),
        ("right", "left"),
        ("Right", "Left"),
        ("RIGHT", "LEFT"),
    ] {
        if name.contains(a) {
            let n = name.replacen(a, b, 1);
            if !out.contains(&n) {
                out.push(n);
            }
        }
    }
    let swap = |c: u8| match c {
        b'l' => Some(b'r'),
        b'r' => Some(b'l'),
        b'L' => Some(b'R'),
        b'R' => Some(b'L'),
        _ => None,
    };
    // The markers are ASCII, and an ASCII byte of UTF-8 text is always a whole character, so the
    // rules can be read on bytes: the characters next to an ASCII letter at byte `i` start at
    // `i - 1` (when that byte is ASCII) and `i + 1`.
    let bytes = name.as_bytes();
    let len = bytes.len();
    // Each single-letter swap changes exactly one position, a different one for every
    // candidate: they are distinct from each other and from `name`.
    let replace_at = |i: usize, c: u8| {
        let mut s = String::with_capacity(len);
        s.push_str(&name[..i]);
        s.push(char::from(c));
        s.push_str(&name[i + 1..]);
        s
    };
    if name.chars().nth(1).is_some() {
        // Prefix `l_` / camel `lFoot`.
        if let Some(c) = swap(bytes[0]) {
            if bytes[1] == b'_' || bytes[1].is_ascii_uppercase() {
                out.push(replace_at(0, c));
            }
        }
        // A middle marker `_L_` (`CC_Base_L_Foot`).
        for i in 1..len - 1 {
            if let Some(c) = swap(bytes[i]) {
                if bytes[i - 1] == b'_' && bytes[i + 1] == b'_' {
                    out.push(replace_at(i, c));
                }
            }
        }
        // Suffix `_l` / `.l`.
        if let Some(c) = swap(bytes[len - 1]) {
            if bytes[len - 2] == b'_' || bytes[len - 2] == b'.' {
                out.push(replace_at(len - 1, c));
            }
        }
    }
    out
}

/// Number of ancestors of joint `j` (at most the joint count, whatever the parent links).
pub(crate) fn depth(sk: &Skeleton, mut j: usize) -> usize {
    let mut d = 0;
    while let Some(p) = sk.joints.get(j).and_then(|x| x.parent) {
        if d == sk.joints.len() {
            break;
        }
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
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct FootNames {
    /// Left ankle joint name.
    pub left_foot: Option<String>,
    /// Right ankle joint name.
    pub right_foot: Option<String>,
    /// Left toe joint name.
    pub left_toe: Option<String>,
    /// Right toe joint name.
    pub right_toe: Option<String>,
    /// Head joint name (for the standing height).
    #[serde(default)]
    pub head: Option<String>,
}

/// Finds the feet: ankles are the shallowest joints whose name contains `foot` or `ankle` with a
/// side marker (`Left`, `l_`, `_L`, `lFoot`, `CC_Base_L_Foot`, `mixamorig:LeftFoot`, `foot.L` ...,
/// see [`side_of`]); toes are joints below them containing `toe` (or `ball`), or, below a joint
/// named `ankle`, `foot` (SMPL's `L_Ankle` and `L_Foot`).
///
/// Fails with [`CycleError::Pose`] ([`crate::PoseError::Skeleton`]) on a skeleton that
/// [`Skeleton::validate`] rejects (a hand-built one with a parent cycle or out of range, say).
pub fn find_feet(sk: &Skeleton, names: &FootNames) -> Result<Feet, CycleError> {
    sk.validate().map_err(crate::pose::PoseError::from)?;
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
            None => Ok(
                find_by_name(sk, &["toe", "ball"], left, Some(f)).or_else(|| {
                    let ankle = sk.joints[f].name.to_ascii_lowercase().contains("ankle");
                    ankle
                        .then(|| find_by_name(sk, &["foot"], left, Some(f)))
                        .flatten()
                }),
            ),
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
    let head = match &names.head {
        Some(n) => Some(lookup(sk, n)?),
        None => sk
            .joints
            .iter()
            .enumerate()
            .filter(|(j, x)| {
                x.name.to_ascii_lowercase().contains("head") && sk.is_ancestor_or_self(pelvis, *j)
            })
            .min_by_key(|(j, _)| depth(sk, *j))
            .map(|(j, _)| j),
    };
    Ok(Feet {
        head,
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

/// Finds the feet of a Y-up take from its hierarchy when no name says which joint is a foot, and
/// returns their names (the given `names` kept where they are set), or `None` when the skeleton has
/// no two legs or the subject does not travel.
///
/// The pelvis is the joint with two child chains reaching lowest below it (mean over the take); each
/// leg follows, from the pelvis down, the child whose subtree reaches lowest; the ankle is the first
/// joint of that chain within 15% of the chain's lowest mean height (so the knee is above it and the
/// toe, if any, below it: the toe is the ankle's next joint in the chain). Left and right: the left
/// hip lies on the walker's left of the direction of travel (`up x forward`), on average. The head
/// (unless named) is the highest joint on average outside the legs.
///
/// `None` as well for a skeleton whose parents are not all listed before their children
/// ([`Skeleton::validate`]).
pub fn feet_by_hierarchy(motion: &crate::Motion, names: &FootNames) -> Option<FootNames> {
    let sk = &motion.skeleton;
    let nf = motion.frame_count();
    let nj = sk.joints.len();
    if nf < 3 || nj < 3 || !sk.hierarchy_ok() {
        return None;
    }
    let step = nf.div_ceil(256).max(1);
    let mut t = vec![crate::Transform::IDENTITY; nj];
    let frames: Vec<usize> = (0..nf).step_by(step).collect();
    let positions: Vec<Vec<DVec3>> = frames
        .iter()
        .map(|&f| {
            sk.forward_kinematics(motion.frame(f), &mut t);
            t.iter().map(|x| x.position).collect()
        })
        .collect();
    let (pelvis, a, b, _, mean_y, low) = legs_below(sk, &positions, DVec3::Y)?;
    let leg = |top: usize| -> (usize, Option<usize>) {
        let mut chain = vec![top];
        let mut j = top;
        while let Some(next) = sk
            .children(j)
            .min_by(|&x, &y| low[x].total_cmp(&low[y]).then(x.cmp(&y)))
        {
            chain.push(next);
            j = next;
        }
        let lowest = chain
            .iter()
            .map(|&k| mean_y[k] - mean_y[pelvis])
            .fold(f64::INFINITY, f64::min);
        let i = chain
            .iter()
            .position(|&k| mean_y[k] - mean_y[pelvis] <= 0.85 * lowest)
            .unwrap_or(chain.len() - 1);
        (chain[i], chain.get(i + 1).copied())
    };
    let (foot_a, toe_a) = leg(a);
    let (foot_b, toe_b) = leg(b);
    // Left of travel: up x forward = (fz, 0, -fx).
    let k = ((0.25 / motion.frame_time).round() as usize / step).max(1);
    let mut side = 0.0;
    for i in k..positions.len().saturating_sub(k) {
        let d = positions[i + k][pelvis] - positions[i - k][pelvis];
        let left = DVec3::new(d.z, 0.0, -d.x);
        side += (positions[i][a] - positions[i][b]).dot(left);
    }
    if side == 0.0 || !side.is_finite() {
        return None;
    }
    let ((lf, lt), (rf, rt)) = if side > 0.0 {
        ((foot_a, toe_a), (foot_b, toe_b))
    } else {
        ((foot_b, toe_b), (foot_a, toe_a))
    };
    // The head: the highest joint on average outside the legs (the joint, not its End Site).
    let legs = |j: usize| sk.is_ancestor_or_self(a, j) || sk.is_ancestor_or_self(b, j);
    let head = (0..nj)
        .filter(|&j| sk.is_ancestor_or_self(pelvis, j) && j != pelvis && !legs(j))
        .max_by(|&x, &y| mean_y[x].total_cmp(&mean_y[y]).then(y.cmp(&x)));
    let name = |j: usize| Some(sk.joints[j].name.clone());
    Some(FootNames {
        left_foot: names.left_foot.clone().or_else(|| name(lf)),
        right_foot: names.right_foot.clone().or_else(|| name(rf)),
        left_toe: names.left_toe.clone().or_else(|| lt.and_then(name)),
        right_toe: names.right_toe.clone().or_else(|| rt.and_then(name)),
        head: names.head.clone().or_else(|| head.and_then(name)),
    })
}

/// The pelvis and its two legs seen along `up`: the joint whose second-lowest child subtree reaches
/// lowest below it, on average over the frames of `positions` (world positions of every joint per
/// frame). Returns `(pelvis, leg a, leg b, depth, mean height per joint, mean lowest height per
/// subtree)`, heights along `up`; `None` when no joint has two children reaching below it.
#[allow(clippy::type_complexity)]
pub(crate) fn legs_below(
    sk: &Skeleton,
    positions: &[Vec<DVec3>],
    up: DVec3,
) -> Option<(usize, usize, usize, f64, Vec<f64>, Vec<f64>)> {
    let nj = sk.joints.len();
    let count = positions.len() as f64;
    if positions.is_empty() {
        return None;
    }
    // Mean height of every joint, and mean lowest height of every subtree.
    let mean_y: Vec<f64> = (0..nj)
        .map(|j| positions.iter().map(|p| p[j].dot(up)).sum::<f64>() / count)
        .collect();
    let mut low = mean_y.clone();
    for j in (1..nj).rev() {
        if let Some(p) = sk.joints[j].parent {
            low[p] = low[p].min(low[j]);
        }
    }
    let mut best: Option<(usize, usize, usize, f64)> = None;
    for (j, &height) in mean_y.iter().enumerate() {
        let mut kids: Vec<usize> = sk.children(j).collect();
        if kids.len() < 2 {
            continue;
        }
        kids.sort_by(|&a, &b| low[a].total_cmp(&low[b]).then(a.cmp(&b)));
        let depth = height - low[kids[1]];
        if depth > 0.0 && best.is_none_or(|b| depth > b.3) {
            best = Some((j, kids[0], kids[1], depth));
        }
    }
    let (pelvis, a, b, depth) = best?;
    Some((pelvis, a, b, depth, mean_y, low))
}

/// Standing height of the skeleton in file units, from bone lengths only (so it is the same for
/// every take of one skeleton): leg length (pelvis -> ankle) plus the chain from the pelvis to the
/// head ([`Feet::head`]: by name, or as [`feet_by_hierarchy`] found it) and the head's End Site;
/// the leg length alone without a head. It leaves out the ankle height and the scalp, so it underestimates the height of a
/// real person by about 10%.
///
/// Never loops or panics on a skeleton that does not match `feet` ([`Skeleton::chain_length`]
/// stops at a parent cycle; a head index out of range has no End Site), but the result is only
/// meaningful for the skeleton [`find_feet`] was given.
pub fn standing_height(sk: &Skeleton, feet: &Feet) -> f64 {
    let head = feet.head;
    let trunk = match head {
        Some(h) => {
            sk.chain_length(feet.pelvis, h)
                + sk.joints
                    .get(h)
                    .and_then(|j| j.end_site)
                    .map_or(0.0, |e| e.length())
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
///
/// No contact at all when `frame_time` is not positive and finite. Windows longer than the take
/// (a tiny `frame_time`) are cut to the take.
///
/// # Panics
/// If `ankle` or `toe` is not an index into every `positions[f]` (with at least 3 frames).
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
    if n < 3 || !(frame_time.is_finite() && frame_time > 0.0) {
        return contact;
    }
    for j in std::iter::once(ankle).chain(toe) {
        if let Some(f) = positions.iter().position(|p| j >= p.len()) {
            panic!(
                "foot_contacts: joint {j} out of range at frame {f} ({} joints)",
                positions[f].len()
            );
        }
    }
    // Speed: central difference over +-0.04 s (1 frame at 30 fps, 5 at 120 fps) to damp marker
    // jitter. Floor: the lowest height of the joint within +-0.75 s (a stance always falls in
    // such a window while walking), which follows floors that drift within a take. A window
    // beyond the take's length acts as the take's length (so it is cut there, which also keeps
    // `f + k` from overflowing).
    let k = ((0.04 / frame_time).round() as usize).clamp(1, n);
    let w = ((0.75 / frame_time).round() as usize).clamp(2, n.max(2));
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
    // Runs longer than the take are as long as it (no run is that short).
    let min_run = ((th.min_run_seconds / frame_time).round() as usize).clamp(1, n + 1);
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
