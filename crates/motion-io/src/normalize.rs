//! Bringing a take from its exporter's conventions into the project's: length units, up axis, root
//! position semantics, the joints that play the feet, and the frames that are not walking.
//!
//! BVH says nothing about units, axes or what the root's position channels mean, and every tool
//! decides differently. [`normalize_take`] decides from the data, in this order:
//!
//! 1. **Up axis** (gravity): the signed file axis along which two legs hang deepest below a pelvis,
//!    on average over the take ([`detect_up`]: while walking or standing the feet stay at the bottom;
//!    a stride or a T-pose reaches less far sideways, and upside down no joint has two chains hanging
//!    below it). The take is
//!    rotated by the proper rotation that maps that axis to +Y; the rotation only renames channels
//!    and flips signs (`Zrotation` about the old up axis becomes `Yrotation`), so values stay exact.
//!    `--up y|z` forces it.
//! 2. **Root position semantics**. The reader's forward kinematics takes a position channel as the
//!    joint's translation, replacing that component of the OFFSET (absolute channels: MotionBuilder,
//!    CMU, Bandai-Namco write the hip height in the channels). Some exporters write the hip height in
//!    the root OFFSET and only the motion in the channels (relative channels). The two readings differ
//!    by a translation by the OFFSET; the one that puts the lowest joint of the take nearer the floor
//!    (height 0) wins, and relative channels are rewritten as absolute (OFFSET added), so the rest of
//!    the pipeline sees one convention. A zero OFFSET makes both the same.
//! 3. **Feet**: by name ([`crate::find_feet`], every common naming convention), else by the
//!    hierarchy ([`feet_by_hierarchy`]: the two deepest leg chains below the pelvis, left and right
//!    told apart by the direction of travel), or as a joint map names them.
//! 4. **Units**: from the skeleton's standing height measured on its bone lengths (leg chain plus
//!    trunk to the head, in the take's poses, so that position channels on inner joints count), never
//!    from the root channel: the candidate unit ([`Units`]) that makes it closest to 1.5 m (the
//!    measure leaves out the ankle height and the scalp) is chosen.
//! 5. **Frames that are not walking**: a jump of any joint by more than a fifth of the standing
//!    height between two frames (a T-pose or reference pose in frame 0, a teleport) splits the take;
//!    pieces shorter than half a second are skipped. Standing still for more than a second at the
//!    start of a piece (the subject has not started walking) is skipped too, keeping its last half
//!    second. Cycles never span a split.
//!
//! The forward axis (the direction the skeleton faces with a zero root rotation) is reported from the
//! direction of travel; it needs no change, since cycles are canonicalised by their direction of
//! travel.

use std::fmt;
use std::ops::Range;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::contacts::{CycleError, Feet, FootNames, feet_by_hierarchy, find_feet};
use crate::motion::Motion;
use crate::skeleton::{Channel, Transform};
use crate::units::motion_root;

/// Length units of a BVH file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Units {
    /// Metres.
    Metres,
    /// Centimetres.
    Centimetres,
    /// Millimetres.
    Millimetres,
    /// Inches.
    Inches,
    /// The CMU ASF/AMC unit, 1/0.45 inch (5.64 cm), kept by some conversions.
    CmuUnits,
}

impl Units {
    /// Every unit [`Units::detect`] chooses from.
    pub const ALL: [Units; 5] = [
        Units::Metres,
        Units::Centimetres,
        Units::Millimetres,
        Units::Inches,
        Units::CmuUnits,
    ];

    /// File units per metre.
    pub fn per_metre(self) -> f64 {
        match self {
            Units::Metres => 1.0,
            Units::Centimetres => 100.0,
            Units::Millimetres => 1000.0,
            Units::Inches => 1.0 / 0.0254,
            Units::CmuUnits => 0.45 / 0.0254,
        }
    }

    /// Short name: `m`, `cm`, `mm`, `in`, `cmu`.
    pub fn name(self) -> &'static str {
        match self {
            Units::Metres => "m",
            Units::Centimetres => "cm",
            Units::Millimetres => "mm",
            Units::Inches => "in",
            Units::CmuUnits => "cmu",
        }
    }

    /// Parses a short name (see [`Units::name`]).
    pub fn parse(name: &str) -> Option<Units> {
        Units::ALL.into_iter().find(|u| u.name() == name)
    }

    /// The unit that makes a standing height (as [`crate::standing_height`] measures it, in file
    /// units) closest to 1.5 m on a log scale. `None` when the height is not positive and finite.
    pub fn detect(standing_height: f64) -> Option<Units> {
        if !(standing_height.is_finite() && standing_height > 0.0) {
            return None;
        }
        Units::ALL.into_iter().min_by(|a, b| {
            let d = |u: Units| (standing_height / u.per_metre() / 1.5).ln().abs();
            d(*a).total_cmp(&d(*b))
        })
    }
}

impl fmt::Display for Units {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A signed coordinate axis of a file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct SignedAxis {
    /// 0 = x, 1 = y, 2 = z.
    pub axis: u8,
    /// Pointing along the negative axis.
    pub negative: bool,
}

impl SignedAxis {
    /// +Y, the project's up axis.
    pub const Y: SignedAxis = SignedAxis {
        axis: 1,
        negative: false,
    };
    /// +Z.
    pub const Z: SignedAxis = SignedAxis {
        axis: 2,
        negative: false,
    };

    /// The unit vector.
    pub fn vector(self) -> DVec3 {
        let mut v = [0.0; 3];
        v[self.axis as usize] = if self.negative { -1.0 } else { 1.0 };
        DVec3::from_array(v)
    }

    /// The signed axis nearest to a direction (`None` for a zero or non-finite vector).
    pub fn nearest(v: DVec3) -> Option<SignedAxis> {
        if !(v.is_finite() && v.length() > 0.0) {
            return None;
        }
        let a = v.abs();
        let axis = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        Some(SignedAxis {
            axis,
            negative: v[axis as usize] < 0.0,
        })
    }
}

impl fmt::Display for SignedAxis {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = if self.negative { '-' } else { '+' };
        let a = ['x', 'y', 'z'][self.axis as usize];
        write!(f, "{s}{a}")
    }
}

/// How the root's position channels combine with its OFFSET.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum RootPositions {
    /// The channels hold the position; the OFFSET is ignored where a channel exists.
    Absolute,
    /// The channels hold a displacement from the OFFSET (rewritten as absolute on reading).
    Relative,
    /// Both readings agree (zero OFFSET, or no position channel).
    Same,
}

impl std::fmt::Display for RootPositions {
    /// What the reader did with the root's position channels, in words for reports.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            RootPositions::Absolute => "absolute (channels hold the position)",
            RootPositions::Relative => "relative to the OFFSET (made absolute)",
            RootPositions::Same => {
                "either reading (the OFFSET is zero or there is no position channel)"
            }
        })
    }
}

/// Choices that [`normalize_take`] would otherwise make from the data.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct NormalizeOptions {
    /// Length units (`None`: detect).
    pub units: Option<Units>,
    /// Up axis of the file (`None`: detect).
    pub up: Option<SignedAxis>,
    /// Joint names of the feet (a joint map); names not given are found by name or hierarchy.
    pub feet: FootNames,
}

/// What [`normalize_take`] decided about a take.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Conventions {
    /// Length units.
    pub units: Units,
    /// Whether the units were detected (`false`: given).
    pub units_detected: bool,
    /// Standing height in file units (the measure units are detected from).
    pub standing_height: f64,
    /// The file's up axis.
    pub up: SignedAxis,
    /// Whether the up axis was detected (`false`: given).
    pub up_detected: bool,
    /// The file axis the skeleton faces with a zero root rotation, nearest to the mean direction of
    /// travel in the root's frame (`None` when the subject does not travel).
    pub forward: Option<SignedAxis>,
    /// Root position semantics found.
    pub root_positions: RootPositions,
    /// The feet's joint names used.
    pub feet: FootNames,
    /// Whether the feet were found from the hierarchy (no name matched).
    pub feet_by_hierarchy: bool,
}

/// Why frames of a take are skipped.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum SkipReason {
    /// A piece shorter than half a second between jumps (a T-pose or reference pose, a teleport).
    Jump {
        /// The largest joint displacement at the jump, metres.
        metres: f64,
    },
    /// The subject stands still before walking.
    StandingStill,
}

impl fmt::Display for SkipReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SkipReason::Jump { metres } => write!(
                f,
                "pose jump of {metres:.2} m (T-pose, reference pose or teleport)"
            ),
            SkipReason::StandingStill => f.write_str("standing still before walking"),
        }
    }
}

/// Frames of a take that are skipped, with the reason.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SkippedFrames {
    /// First skipped frame.
    pub first: usize,
    /// Last skipped frame (included).
    pub last: usize,
    /// Why.
    pub reason: SkipReason,
}

impl fmt::Display for SkippedFrames {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "frames {}..={}: {}", self.first, self.last, self.reason)
    }
}

/// A take in the project's conventions and what was done to it.
#[derive(Debug, Clone, PartialEq)]
pub struct NormalizedTake {
    /// The take: Y up, absolute root channels, the file's units (see [`Conventions::units`]) and its
    /// frames unchanged in number and order.
    pub motion: Motion,
    /// What was decided.
    pub conventions: Conventions,
    /// The frame ranges to segment into cycles (jumps and skipped frames excluded), in order.
    pub segments: Vec<Range<usize>>,
    /// The frames left out of every segment.
    pub skipped: Vec<SkippedFrames>,
    /// The feet (joint indices, leg length in file units).
    pub feet: Feet,
}

/// At most this many frames (evenly strided) are used for the decisions that average over a take.
const SAMPLE_FRAMES: usize = 256;

fn sampled_positions(motion: &Motion) -> Vec<Vec<DVec3>> {
    let nf = motion.frame_count();
    let step = nf.div_ceil(SAMPLE_FRAMES).max(1);
    let mut t = vec![Transform::IDENTITY; motion.skeleton.joints.len()];
    (0..nf)
        .step_by(step)
        .map(|f| {
            motion.skeleton.forward_kinematics(motion.frame(f), &mut t);
            t.iter().map(|x| x.position).collect()
        })
        .collect()
}

/// Detects the up axis (module docs, step 1): the signed axis along which the legs hang deepest
/// below the pelvis, on average over the take (for every signed axis, the joint whose second-lowest
/// child subtree reaches lowest below it; the pelvis with its two legs wins along the true up axis,
/// by the leg length against a stride's reach sideways or a trunk's reach upside down). `None` when
/// no axis stands out (by 20%) from the four perpendicular ones, or when the skeleton's parents are
/// not all listed before their children ([`crate::Skeleton::validate`]).
pub fn detect_up(motion: &Motion) -> Option<SignedAxis> {
    if !motion.skeleton.hierarchy_ok() {
        return None;
    }
    let frames = sampled_positions(motion);
    if frames.is_empty() {
        return None;
    }
    let mut reach = [0.0f64; 6];
    for (k, r) in reach.iter_mut().enumerate() {
        let a = SignedAxis {
            axis: (k / 2) as u8,
            negative: k % 2 == 1,
        };
        *r =
            crate::contacts::legs_below(&motion.skeleton, &frames, a.vector()).map_or(0.0, |l| l.3);
    }
    let best = (0..6).max_by(|&a, &b| reach[a].total_cmp(&reach[b]).then(b.cmp(&a)))?;
    let side = (0..6)
        .filter(|&k| k / 2 != best / 2)
        .map(|k| reach[k])
        .fold(0.0, f64::max);
    if !(reach[best] > 0.0 && reach[best] > 1.2 * side) {
        return None;
    }
    Some(SignedAxis {
        axis: (best / 2) as u8,
        negative: best % 2 == 1,
    })
}

/// For each old axis, the new axis and sign of the proper rotation taking `up` to +Y (a quarter or
/// half turn about x or z; the identity for +Y).
fn rotation_to_y_up(up: SignedAxis) -> [(usize, f64); 3] {
    match (up.axis, up.negative) {
        (1, false) => [(0, 1.0), (1, 1.0), (2, 1.0)],
        // Half turn about x.
        (1, true) => [(0, 1.0), (1, -1.0), (2, -1.0)],
        // Quarter turn about x: z -> y, y -> -z.
        (2, false) => [(0, 1.0), (2, -1.0), (1, 1.0)],
        (2, true) => [(0, 1.0), (2, 1.0), (1, -1.0)],
        // Quarter turn about z: x -> y, y -> -x.
        (0, false) => [(1, 1.0), (0, -1.0), (2, 1.0)],
        _ => [(1, -1.0), (0, 1.0), (2, 1.0)],
    }
}

/// Rotates a take by a signed axis permutation (`map[a] = (b, s)`: old axis `a` becomes `s` times new
/// axis `b`; a proper rotation): offsets and End Sites rotated, every channel renamed to its new
/// axis and its values multiplied by the sign. World positions become `R p` exactly.
fn rotate_take(motion: &mut Motion, map: [(usize, f64); 3]) {
    let rot = |v: DVec3| {
        let mut out = [0.0; 3];
        for (a, &(b, s)) in map.iter().enumerate() {
            out[b] = s * v[a];
        }
        DVec3::from_array(out)
    };
    let n = motion.skeleton.channel_count();
    let mut signs = Vec::with_capacity(n);
    for joint in &mut motion.skeleton.joints {
        joint.offset = rot(joint.offset);
        joint.end_site = joint.end_site.map(rot);
        for c in &mut joint.channels {
            let (b, s) = map[c.axis()];
            *c = channel(b, c.is_position());
            signs.push(s);
        }
    }
    if signs.iter().any(|&s| s < 0.0) {
        for frame in motion.frames.chunks_exact_mut(n) {
            for (v, s) in frame.iter_mut().zip(&signs) {
                *v *= s;
            }
        }
    }
}

fn channel(axis: usize, position: bool) -> Channel {
    match (axis, position) {
        (0, true) => Channel::Xposition,
        (1, true) => Channel::Yposition,
        (2, true) => Channel::Zposition,
        (0, false) => Channel::Xrotation,
        (1, false) => Channel::Yrotation,
        _ => Channel::Zrotation,
    }
}

/// The lowest height (y) of any joint over the sampled frames.
fn lowest(motion: &Motion) -> f64 {
    sampled_positions(motion)
        .iter()
        .flatten()
        .map(|p| p.y)
        .fold(f64::INFINITY, f64::min)
}

/// Decides the root position semantics of a Y-up take (module docs, step 2) and rewrites relative
/// channels as absolute.
fn fix_root_positions(motion: &mut Motion) -> RootPositions {
    let root = motion_root(motion);
    let joint = &motion.skeleton.joints[root];
    let offset = joint.offset;
    let has_position = joint.channels.iter().any(|c| c.is_position());
    if !has_position || offset.length() == 0.0 {
        return RootPositions::Same;
    }
    let start = motion.skeleton.channel_starts()[root];
    let shifts: Vec<(usize, f64)> = joint
        .channels
        .iter()
        .enumerate()
        .filter(|(_, c)| c.is_position())
        .map(|(k, c)| (start + k, offset[c.axis()]))
        .collect();
    let n = motion.skeleton.channel_count();
    let mut relative = motion.clone();
    for frame in relative.frames.chunks_exact_mut(n) {
        for &(k, d) in &shifts {
            frame[k] += d;
        }
    }
    let (abs_floor, rel_floor) = (lowest(motion).abs(), lowest(&relative).abs());
    if rel_floor < abs_floor {
        *motion = relative;
        RootPositions::Relative
    } else {
        RootPositions::Absolute
    }
}

/// Standing height (file units) measured on the take's bone lengths (median over sampled frames):
/// the leg chain (pelvis to ankle, the longer side) plus the chain from the pelvis to the head
/// ([`Feet::head`]) and its End Site; without a head, 1.75 leg lengths.
///
/// 0 when the skeleton's parents are not all listed before their children
/// ([`crate::Skeleton::validate`]).
///
/// # Panics
/// If a joint of `feet` is not a joint of the skeleton (`feet` comes from [`find_feet`] on another
/// skeleton).
pub fn take_standing_height(motion: &Motion, feet: &Feet) -> f64 {
    let sk = &motion.skeleton;
    if !sk.hierarchy_ok() {
        return 0.0;
    }
    let head = feet.head;
    let chain = |p: &[DVec3], top: usize, mut j: usize| {
        let mut len = 0.0;
        // Parents come before children, so the chain ends within the joint count.
        while j != top {
            let Some(parent) = sk.joints[j].parent else {
                break;
            };
            len += (p[j] - p[parent]).length();
            j = parent;
        }
        len
    };
    let mut heights: Vec<f64> = sampled_positions(motion)
        .iter()
        .map(|p| {
            let leg =
                chain(p, feet.pelvis, feet.left_foot).max(chain(p, feet.pelvis, feet.right_foot));
            match head {
                Some(h) => {
                    leg + chain(p, feet.pelvis, h)
                        + sk.joints[h].end_site.map_or(0.0, |e| e.length())
                }
                None => 1.75 * leg,
            }
        })
        .filter(|h| h.is_finite())
        .collect();
    if heights.is_empty() {
        return 0.0;
    }
    heights.sort_by(f64::total_cmp);
    heights[heights.len() / 2]
}

/// Brings a take into the project's conventions (see the module documentation).
///
/// Errors: a take without frames, with a frame buffer that is not whole frames, with non-finite
/// values or a frame time that is not finite and at least [`MIN_FRAME_TIME`]
/// ([`CycleError::BadMotion`]), a skeleton that [`crate::Skeleton::validate`] rejects
/// ([`CycleError::Pose`]), feet that cannot be found (by the map, by name or by hierarchy), or a
/// standing height of zero.
pub fn normalize_take(
    motion: &Motion,
    options: &NormalizeOptions,
) -> Result<NormalizedTake, CycleError> {
    let dt = motion.frame_time;
    check_frame_time(dt)?;
    if motion.frame_count() == 0 {
        return Err(CycleError::BadMotion("no frames".into()));
    }
    check_whole_frames(motion)?;
    if let Some(i) = motion.frames.iter().position(|v| !v.is_finite()) {
        return Err(CycleError::BadMotion(format!(
            "non-finite value at index {i}"
        )));
    }
    motion
        .skeleton
        .validate()
        .map_err(crate::pose::PoseError::from)?;
    let mut m = motion.clone();
    let (up, up_detected) = match options.up {
        Some(u) => (u, false),
        None => (detect_up(&m).unwrap_or(SignedAxis::Y), true),
    };
    if up != SignedAxis::Y {
        rotate_take(&mut m, rotation_to_y_up(up));
    }
    let root_positions = fix_root_positions(&mut m);
    let (names, by_hierarchy) = match find_feet(&m.skeleton, &options.feet) {
        Ok(f) if f.head.is_none() => {
            // Feet by name or map, but no head by name: the hierarchy's head.
            let mut names = options.feet.clone();
            names.head = feet_by_hierarchy(&m, &options.feet).and_then(|h| h.head);
            (names, false)
        }
        Ok(_) => (options.feet.clone(), false),
        Err(name_error) => match feet_by_hierarchy(&m, &options.feet) {
            Some(names) => (names, true),
            None => return Err(name_error),
        },
    };
    let feet = find_feet(&m.skeleton, &names)?;
    let standing_height = take_standing_height(&m, &feet);
    let (units, units_detected) = match options.units {
        Some(u) => (u, false),
        None => (
            Units::detect(standing_height).ok_or(CycleError::BadLegLength(standing_height))?,
            true,
        ),
    };
    let forward = travel_forward(&m);
    let (segments, skipped) = walking_segments(&m, standing_height, units);
    Ok(NormalizedTake {
        motion: m,
        conventions: Conventions {
            units,
            units_detected,
            standing_height,
            up,
            up_detected,
            forward,
            root_positions,
            feet: names,
            feet_by_hierarchy: by_hierarchy,
        },
        segments,
        skipped,
        feet,
    })
}

/// Shortest frame time (seconds) that [`normalize_take`] and [`crate::segment_cycles`] accept: a
/// million frames per second, far beyond any capture system, and far enough from 0 that every
/// window they compute in frames (`seconds / frame_time`) stays an ordinary number.
pub const MIN_FRAME_TIME: f64 = 1e-6;

/// A frame time that is finite and at least [`MIN_FRAME_TIME`], else [`CycleError::BadMotion`].
pub(crate) fn check_frame_time(dt: f64) -> Result<(), CycleError> {
    if !(dt.is_finite() && dt > 0.0) {
        return Err(CycleError::BadMotion(format!("frame time {dt}")));
    }
    if dt < MIN_FRAME_TIME {
        return Err(CycleError::BadMotion(format!(
            "frame time {dt} s is below {MIN_FRAME_TIME} s (a frame rate above a million per second)"
        )));
    }
    Ok(())
}

/// A frame buffer of whole frames (its length a multiple of the channel count), else
/// [`CycleError::BadMotion`].
pub(crate) fn check_whole_frames(motion: &Motion) -> Result<(), CycleError> {
    let n = motion.skeleton.channel_count();
    if n > 0 && motion.frames.len() % n != 0 {
        return Err(CycleError::BadMotion(format!(
            "{} values are not whole frames of {n} channels",
            motion.frames.len()
        )));
    }
    Ok(())
}

/// The ground velocity of the motion root at each of the given frames' positions (file units per
/// frame, central differences over `k` frames).
fn ground_speeds(track: &[DVec3], k: usize) -> Vec<f64> {
    let n = track.len();
    (0..n)
        .map(|f| {
            let (a, b) = (
                f.saturating_sub(k),
                f.saturating_add(k).min(n.saturating_sub(1)),
            );
            if b <= a {
                return 0.0;
            }
            let d = track[b] - track[a];
            DVec3::new(d.x, 0.0, d.z).length() / (b - a) as f64
        })
        .collect()
}

/// The file axis the skeleton faces at a zero root rotation: the mean direction of travel (over a
/// quarter second) expressed in the motion root's frame, projected on the ground.
fn travel_forward(motion: &Motion) -> Option<SignedAxis> {
    let root = motion_root(motion);
    let nf = motion.frame_count();
    let k = ((0.25 / motion.frame_time).round() as usize).max(1);
    if nf <= k.saturating_mul(2) {
        return None;
    }
    let mut t = vec![Transform::IDENTITY; motion.skeleton.joints.len()];
    let step = nf.div_ceil(SAMPLE_FRAMES).max(1);
    let mut sum = DVec3::ZERO;
    let at = |f: usize, t: &mut [Transform]| {
        motion.skeleton.forward_kinematics(motion.frame(f), t);
        t[root]
    };
    for f in (k..nf - k).step_by(step) {
        let a = at(f - k, &mut t).position;
        let b = at(f + k, &mut t).position;
        let here = at(f, &mut t);
        let d = DVec3::new(b.x - a.x, 0.0, b.z - a.z);
        if d.length() == 0.0 {
            continue;
        }
        let local = here.rotation.inverse() * d.normalize();
        sum += DVec3::new(local.x, 0.0, local.z);
    }
    SignedAxis::nearest(sum)
}

/// Splits a Y-up take at pose jumps and skips short pieces and a long still start (module docs,
/// step 5).
fn walking_segments(
    motion: &Motion,
    height: f64,
    units: Units,
) -> (Vec<Range<usize>>, Vec<SkippedFrames>) {
    let nf = motion.frame_count();
    let dt = motion.frame_time;
    let nj = motion.skeleton.joints.len();
    let mut t = vec![Transform::IDENTITY; nj];
    let positions: Vec<Vec<DVec3>> = (0..nf)
        .map(|f| {
            motion.skeleton.forward_kinematics(motion.frame(f), &mut t);
            t.iter().map(|x| x.position).collect()
        })
        .collect();
    let limit = (0.2 * height).max(6.0 * height * dt);
    let mut pieces: Vec<(Range<usize>, f64)> = Vec::new();
    let mut start = 0;
    let mut jump_before = 0.0f64;
    for f in 1..nf {
        let jump = positions[f]
            .iter()
            .zip(&positions[f - 1])
            .map(|(a, b)| (*a - *b).length())
            .fold(0.0, f64::max);
        if jump > limit {
            pieces.push((start..f, jump_before.max(jump)));
            start = f;
            jump_before = jump;
        }
    }
    pieces.push((start..nf, jump_before));
    let mut segments = Vec::new();
    let mut skipped = Vec::new();
    let metres = |x: f64| x / units.per_metre();
    let min_len = ((0.5 / dt).round() as usize).max(1);
    let single = pieces.len() == 1;
    for (range, jump) in pieces {
        if !single && range.len() < min_len {
            skipped.push(SkippedFrames {
                first: range.start,
                last: range.end - 1,
                reason: SkipReason::Jump {
                    metres: metres(jump),
                },
            });
            continue;
        }
        // Standing still at the start of the piece: root ground speed below 0.1 standing heights
        // per second (about 0.15 m/s) for more than a second.
        let root = motion_root(motion);
        let track: Vec<DVec3> = positions[range.clone()].iter().map(|p| p[root]).collect();
        let k = ((0.25 / dt).round() as usize).max(1);
        let speeds = ground_speeds(&track, k);
        let still = speeds
            .iter()
            .take_while(|&&v| v < 0.1 * height * dt)
            .count();
        let keep = ((0.5 / dt).round() as usize).max(1);
        if still as f64 * dt > 1.0 && still < range.len() {
            let cut = range.start + still - keep;
            skipped.push(SkippedFrames {
                first: range.start,
                last: cut - 1,
                reason: SkipReason::StandingStill,
            });
            segments.push(cut..range.end);
        } else {
            segments.push(range);
        }
    }
    (segments, skipped)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_from_standing_height() {
        assert_eq!(Units::detect(1.4), Some(Units::Metres));
        assert_eq!(Units::detect(134.5), Some(Units::Centimetres));
        assert_eq!(Units::detect(1600.0), Some(Units::Millimetres));
        assert_eq!(Units::detect(62.0), Some(Units::Inches));
        assert_eq!(Units::detect(27.0), Some(Units::CmuUnits));
        assert_eq!(Units::detect(0.0), None);
        assert_eq!(Units::detect(f64::NAN), None);
        for u in Units::ALL {
            assert_eq!(Units::parse(u.name()), Some(u));
        }
    }

    #[test]
    fn rotations_to_y_up_take_up_to_y_and_are_proper() {
        for axis in 0..3u8 {
            for negative in [false, true] {
                let up = SignedAxis { axis, negative };
                let map = rotation_to_y_up(up);
                let mut m = [[0.0; 3]; 3];
                for (a, &(b, s)) in map.iter().enumerate() {
                    m[b][a] = s;
                }
                let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
                    - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
                    + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
                assert_eq!(det, 1.0, "{up}");
                let (b, s) = map[axis as usize];
                assert_eq!((b, s), (1, if negative { -1.0 } else { 1.0 }), "{up}");
            }
        }
    }
}
