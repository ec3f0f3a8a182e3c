//! Segmentation of whole takes into two-step gait cycles (one left contact to the next),
//! canonicalisation and control parameters.
//!
//! A cycle runs from the frame a left contact starts to the frame the next one starts (both
//! included). Its poses are canonicalised: the root starts over the ground origin with its
//! heading along +Z (y up, +x = the character's left). Controls (docs/architecture.md): `dx`, `dz`
//! root displacement over the cycle in the start heading frame (metres), `turn` heading change
//! (radians, positive = left), `height` standing height (metres).
//!
//! # Heading = direction of travel
//! The heading at frame `f` is the direction the root travels over one gait cycle centred on `f`:
//! with `g(t)` the root's ground track (interpolated between frames) and `L` the cycle's duration,
//!
//! `h(f) = atan2(d.x, d.z)`, `d = g(f + L/2) - g(f - L/2)`.
//!
//! The root's lateral sway and fore-aft surge repeat once per cycle, so on a straight path they
//! cancel in `d`; on a path of constant curvature the chord is parallel to the tangent at its
//! midpoint, so `h` is the path direction for constant turn rates. On a turn a sway (which turns
//! with the walker) only changes the chord's length; a surge of amplitude `a` tilts it by at most
//! `a kappa` (`kappa` the curvature: 0.2 degrees for 1 cm at 30 degrees per 1.3 m). While the
//! walker accelerates the chord's midpoint by arc length moves away from `f`, which biases `h`
//! on turns (about 1 degree on the fixtures' first steady cycle, whose window reaches back into
//! the speed ramp).
//!
//! `turn = h(last) - h(first)` (wrapped to `(-pi, pi]`) and `(dx, dz)` is `g(last) - g(first)`
//! rotated by `-h(first)`: a straight walk has `dx ~ 0`, and on an arc `dx = |d| sin(turn / 2)`.
//!
//! The pelvis (hip line) is not used for the heading: performers hold their pelvis yawed against
//! the walking direction by a few degrees (the Bandai-Namco straight walks: 2.4 degrees on average,
//! up to 5 degrees for some styles, with mirror-symmetric hip offsets), which showed up as a
//! sideways drift `dx` of up to 0.1 m per straight cycle. The canonical poses keep that posture:
//! the root's yaw at frame 0 is the pelvis's yaw against the direction of travel.
//!
//! Near the ends of a take the centred window does not fit. There the heading is extrapolated: a
//! least-squares line through the centred-window headings `h(c)` over the half cycle of centres
//! nearest that end, evaluated at `f` (exact for constant turn rates, and free of the gait
//! oscillation, which the chords have already removed). In a take shorter than 1.5 cycle lengths
//! the fit has no support, and the cycle is dropped with [`DropReason::HeadingWindowTruncated`].

use std::f64::consts::PI;
use std::fmt;
use std::path::{Path, PathBuf};

use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};

use crate::contacts::{
    ContactThresholds, CycleError, FootNames, contact_starts, find_feet, foot_contacts,
    standing_height,
};
use crate::expmap::{exp_to_quat, quat_to_exp, wrap_angle};
use crate::motion::Motion;
use crate::normalize::{check_frame_time, check_whole_frames};
use crate::pose::{ALWAYS_ROWS, PoseLayout, align_sequence};
use crate::skeleton::Transform;

/// Settings of contact detection and cycle selection. Lengths are relative to the leg length
/// (pelvis to ankle bone chain), times in seconds.
#[derive(Debug, Clone, PartialEq)]
pub struct CycleConfig {
    /// Contact height threshold above the joint's floor level, in leg lengths.
    pub contact_height: f64,
    /// Contact speed threshold, in leg lengths per second.
    pub contact_speed: f64,
    /// Shortest contact run and shortest gap kept, seconds.
    pub min_contact_seconds: f64,
    /// Shortest accepted cycle, seconds.
    pub min_cycle_seconds: f64,
    /// Longest accepted cycle, seconds.
    pub max_cycle_seconds: f64,
    /// Slowest accepted mean root ground speed in any third of a cycle, leg lengths per second
    /// (slower = a start or a stop).
    pub min_speed: f64,
    /// Largest accepted relative change of the root ground speed between the first and last third
    /// of a cycle (`|v_last - v_first| / max`), larger = accelerating (start) or braking (stop).
    pub max_speed_change: f64,
    /// Largest accepted heading change over one cycle, radians.
    pub max_turn: f64,
    /// The right contact must start within this phase window of the cycle (fractions of its
    /// duration).
    pub right_contact_phase: (f64, f64),
    /// Contacts that start before this time are ignored (CMU: 0.1 s, the blend from the
    /// reference pose).
    pub skip_start_seconds: f64,
    /// Foot joint name overrides.
    pub feet: FootNames,
}

impl Default for CycleConfig {
    fn default() -> Self {
        CycleConfig {
            contact_height: 0.12,
            contact_speed: 0.6,
            min_contact_seconds: 0.06,
            min_cycle_seconds: 0.6,
            max_cycle_seconds: 1.6,
            min_speed: 0.3,
            max_speed_change: 0.3,
            max_turn: 100f64.to_radians(),
            right_contact_phase: (0.3, 0.7),
            skip_start_seconds: 0.0,
            feet: FootNames::default(),
        }
    }
}

impl CycleConfig {
    /// Settings for the CMU (cgspeed) conversions: frame 0 is a reference pose and the motion
    /// blends in from it, so contacts in the first 0.1 s are ignored; floors drift by about 5 cm,
    /// so the height threshold is looser and speed decides.
    pub fn cmu() -> Self {
        CycleConfig {
            skip_start_seconds: 0.1,
            contact_height: 0.2,
            ..CycleConfig::default()
        }
    }

    fn validate(&self) -> Result<(), CycleError> {
        let pos = |v: f64| v.is_finite() && v > 0.0;
        let ok = pos(self.contact_height)
            && pos(self.contact_speed)
            && pos(self.max_cycle_seconds)
            && pos(self.max_turn)
            && self.min_cycle_seconds.is_finite()
            && self.min_cycle_seconds < self.max_cycle_seconds
            && self.min_speed.is_finite()
            && self.max_speed_change.is_finite()
            && self.skip_start_seconds.is_finite()
            && self.min_contact_seconds.is_finite()
            && self.right_contact_phase.0 < self.right_contact_phase.1;
        if !ok {
            return Err(CycleError::BadConfig(format!("{self:?}")));
        }
        Ok(())
    }
}

/// The control parameters of one cycle *as measured* from the take (`f64`, offline): the
/// runtime's controls (`lod_policy::Controls`, `f32`, what a clip is asked for) are made from
/// these once, by `lod_policy::Controls::from_f64(measured.to_array())` (this crate does not
/// depend on the runtime).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MeasuredControls {
    /// Root displacement to the character's left over the cycle, metres (start heading frame).
    pub dx: f64,
    /// Root displacement forward over the cycle, metres (start heading frame).
    pub dz: f64,
    /// Heading change over the cycle, radians, positive = turn left.
    pub turn: f64,
    /// Standing height of the skeleton, metres ([`crate::contacts::standing_height`]).
    pub height: f64,
}

impl MeasuredControls {
    /// The controls as `[dx, dz, turn, height]`.
    pub fn to_array(&self) -> [f64; 4] {
        [self.dx, self.dz, self.turn, self.height]
    }
}

/// One steady two-step cycle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GaitCycle {
    /// The take it comes from.
    pub source: PathBuf,
    /// First frame in the take (a left contact starts here).
    pub first_frame: usize,
    /// Last frame in the take, included (the next left contact starts here).
    pub last_frame: usize,
    /// Seconds between frames.
    pub frame_time: f64,
    /// Canonical pose vectors, `frames x dof` row-major, `frames = last_frame - first_frame + 1`;
    /// exp-maps continuous over time and on the branch nearest the layout's rest pose.
    pub poses: Vec<f64>,
    /// Control parameters.
    pub controls: MeasuredControls,
    /// Left foot contact per cycle frame (true at frame 0 and the last frame).
    pub left_contact: Vec<bool>,
    /// Right foot contact per cycle frame.
    pub right_contact: Vec<bool>,
    /// Cycle frame (0-based) where the right contact starts.
    pub right_contact_start: usize,
}

impl GaitCycle {
    /// Number of frames.
    pub fn frame_count(&self) -> usize {
        self.last_frame - self.first_frame + 1
    }

    /// Duration from the first to the last frame, seconds.
    pub fn duration(&self) -> f64 {
        (self.last_frame - self.first_frame) as f64 * self.frame_time
    }

    /// Pose vector of cycle frame `i`.
    ///
    /// # Panics
    /// If `i >= frame_count()` or `dof` does not divide the poses.
    pub fn pose(&self, i: usize, dof: usize) -> &[f64] {
        &self.poses[i * dof..(i + 1) * dof]
    }

    /// Features for the Kovar-Gleicher pose distance used in time warping: for every frame, the
    /// positions (metres) of the layout's rotating joints, in its joint order, expressed in the
    /// root's frame: `R_root^T (p_j - p_root)`. Length `frames x 3 * layout.joint_count()`.
    ///
    /// Returns an empty vector when the poses do not fit the layout.
    pub fn features(&self, layout: &PoseLayout) -> Vec<f64> {
        let p = layout.dof();
        if p == 0 || self.poses.len() % p != 0 {
            return Vec::new();
        }
        let nj = layout.skeleton().joints.len();
        let mut t = vec![Transform::IDENTITY; nj];
        let order = layout.joint_order();
        let root = layout.root();
        let mut out = Vec::with_capacity(self.poses.len() / p * order.len() * 3);
        for pose in self.poses.chunks_exact(p) {
            layout.joint_transforms_f64(pose, &mut t);
            let inv = t[root].rotation.inverse();
            for &j in order {
                let v = inv * (t[j].position - t[root].position);
                out.extend_from_slice(&v.to_array());
            }
        }
        out
    }
}

/// Why a candidate cycle was dropped.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum DropReason {
    /// Shorter than `min_cycle_seconds`.
    TooShort {
        /// Duration, seconds.
        seconds: f64,
    },
    /// Longer than `max_cycle_seconds`.
    TooLong {
        /// Duration, seconds.
        seconds: f64,
    },
    /// Not exactly one right contact between the two left contacts.
    ContactPattern {
        /// Right contacts found.
        right_contacts: usize,
    },
    /// The right contact is far from mid-cycle (limping or a contact misdetected).
    Asymmetric {
        /// Phase of the right contact start.
        phase: f64,
    },
    /// The walk starts (slow or accelerating).
    Start {
        /// Root ground speed in the first and last third, m/s.
        speeds: (f64, f64),
    },
    /// The walk stops (slow or braking).
    Stop {
        /// Root ground speed in the first and last third, m/s.
        speeds: (f64, f64),
    },
    /// The root moves backwards in its start heading frame.
    NotForward {
        /// Forward displacement, metres.
        dz: f64,
    },
    /// Heading changes by more than `max_turn` (U-turn, reversal).
    SharpTurn {
        /// Heading change, radians.
        turn: f64,
    },
    /// The heading at the first or last frame cannot be measured: the take is shorter than 1.5
    /// cycle lengths, so neither a window of one cycle centred on the frame nor the extrapolating
    /// fit of the module docs stays inside the take.
    HeadingWindowTruncated {
        /// The frame whose heading is missing (the cycle's first or last frame).
        frame: usize,
        /// `true` when the window runs past the end of the take, `false` past its start.
        at_end: bool,
    },
}

impl fmt::Display for DropReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DropReason::TooShort { seconds } => write!(f, "too short ({seconds:.2} s)"),
            DropReason::TooLong { seconds } => write!(f, "too long ({seconds:.2} s)"),
            DropReason::ContactPattern { right_contacts } => {
                write!(
                    f,
                    "{right_contacts} right contacts between the left contacts (need 1)"
                )
            }
            DropReason::Asymmetric { phase } => write!(f, "right contact at phase {phase:.2}"),
            DropReason::Start { speeds } => {
                write!(
                    f,
                    "start of the walk (speed {:.2} -> {:.2} m/s)",
                    speeds.0, speeds.1
                )
            }
            DropReason::Stop { speeds } => write!(
                f,
                "stop of the walk (speed {:.2} -> {:.2} m/s)",
                speeds.0, speeds.1
            ),
            DropReason::NotForward { dz } => write!(f, "not moving forward (dz = {dz:.2} m)"),
            DropReason::SharpTurn { turn } => {
                write!(f, "sharp turn ({:.0} deg)", turn.to_degrees())
            }
            DropReason::HeadingWindowTruncated { frame, at_end } => write!(
                f,
                "heading window truncated at take {} (frame {frame})",
                if *at_end { "end" } else { "start" }
            ),
        }
    }
}

/// A rejected candidate cycle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DroppedCycle {
    /// First frame in the take.
    pub first_frame: usize,
    /// Last frame in the take.
    pub last_frame: usize,
    /// Why it was dropped.
    pub reason: DropReason,
}

/// The cycles of one take.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct CycleReport {
    /// Steady cycles, in time order.
    pub cycles: Vec<GaitCycle>,
    /// Rejected candidates, in time order.
    pub dropped: Vec<DroppedCycle>,
}

/// Point of the ground track `g` at the fractional frame `t` (linear interpolation, clamped to
/// the take).
fn track_point(g: &[DVec3], t: f64) -> DVec3 {
    debug_assert!(!g.is_empty());
    let last = g.len() - 1;
    let t = t.clamp(0.0, last as f64);
    let i = (t.floor() as usize).min(last.saturating_sub(1));
    let u = t - i as f64;
    if i == last {
        return g[i];
    }
    g[i].lerp(g[i + 1], u)
}

/// Direction of travel over the window `[c - half, c + half]` (fractional frames, inside the
/// take): `atan2(d.x, d.z)` with `d = g(c + half) - g(c - half)`; 0 = +Z, positive towards +X.
fn chord_heading(g: &[DVec3], c: f64, half: f64) -> f64 {
    let d = track_point(g, c + half) - track_point(g, c - half);
    d.x.atan2(d.z)
}

/// Heading at frame `f` of the ground track `g` (one point per frame, y = 0) for a gait cycle of
/// `period` frames (see the module docs): the chord heading over one period centred on `f` when
/// that window lies inside the take, otherwise the least-squares line `h(c) = alpha + beta (c - f)`
/// through the (unwrapped) chord headings of the centres `c` within half a period of the nearest
/// valid centre, evaluated at `c = f` (`alpha`).
///
/// Returns `Err(at_end)` when the take is shorter than 1.5 periods, so the fit has no support
/// (`at_end`: `f` lies in the second half of the take).
fn travel_heading(g: &[DVec3], f: usize, period: f64) -> Result<f64, bool> {
    debug_assert!(period > 0.0);
    let half = 0.5 * period;
    let last = g.len().saturating_sub(1) as f64;
    let (lo, hi) = (half, last - half);
    let x = f as f64;
    let at_end = x > 0.5 * last;
    if hi - lo < half {
        return Err(at_end);
    }
    if (lo..=hi).contains(&x) {
        return Ok(chord_heading(g, x, half));
    }
    // Centres from the edge of the valid range inwards, one frame apart, over half a period.
    let (edge, step) = if x > hi { (hi, -1.0) } else { (lo, 1.0) };
    let count = half.floor() as usize + 1;
    let (mut sx, mut sy, mut sxx, mut sxy) = (0.0, 0.0, 0.0, 0.0);
    let mut prev = chord_heading(g, edge, half);
    let mut unwrapped = prev;
    for k in 0..count {
        let c = edge + step * k as f64;
        let h = chord_heading(g, c, half);
        unwrapped += wrap_angle(h - prev);
        prev = h;
        let dx = c - x;
        sx += dx;
        sy += unwrapped;
        sxx += dx * dx;
        sxy += dx * unwrapped;
    }
    let n = count as f64;
    let var = sxx - sx * sx / n;
    let beta = if var > 0.0 {
        (sxy - sx * sy / n) / var
    } else {
        0.0
    };
    Ok(sy / n - beta * sx / n)
}

/// Splits a take into steady two-step cycles.
///
/// Contacts: per foot, ankle or toe within `contact_height` leg lengths of its floor level and
/// slower than `contact_speed` leg lengths/s ([`foot_contacts`]). Candidates: consecutive left
/// contact starts after `skip_start_seconds`. A candidate is kept when its duration is in range,
/// it holds exactly one right contact start within the phase window, the root ground speed of
/// each third is above `min_speed` and the first and last thirds differ by at most
/// `max_speed_change`, the headings at both ends can be measured inside the take (module docs), it
/// moves forward and turns less than `max_turn`; otherwise it is dropped with the reason.
///
/// Errors: a bad `config`; a frame time that is not finite and at least
/// [`crate::normalize::MIN_FRAME_TIME`], a frame buffer that is not whole frames, or non-finite
/// values ([`CycleError::BadMotion`]); a skeleton that [`crate::Skeleton::validate`] rejects or
/// feet that cannot be found ([`find_feet`]); a pose conversion error ([`CycleError::Pose`]).
pub fn segment_cycles(
    motion: &Motion,
    layout: &PoseLayout,
    config: &CycleConfig,
    source: &Path,
) -> Result<CycleReport, CycleError> {
    config.validate()?;
    let dt = motion.frame_time;
    check_frame_time(dt)?;
    check_whole_frames(motion)?;
    if let Some(i) = motion.frames.iter().position(|v| !v.is_finite()) {
        return Err(CycleError::BadMotion(format!(
            "non-finite value at index {i}"
        )));
    }
    let sk = &motion.skeleton;
    let feet = find_feet(sk, &config.feet)?;
    let upm = layout.units_per_metre();
    let height = standing_height(sk, &feet) / upm;
    let nf = motion.frame_count();
    let nj = sk.joints.len();
    if nf < 3 {
        return Ok(CycleReport::default());
    }
    let mut t = vec![Transform::IDENTITY; nj];
    let positions: Vec<Vec<DVec3>> = (0..nf)
        .map(|f| {
            sk.forward_kinematics(motion.frame(f), &mut t);
            t.iter().map(|x| x.position).collect()
        })
        .collect();
    let th = ContactThresholds {
        height: config.contact_height,
        speed: config.contact_speed,
        min_run_seconds: config.min_contact_seconds,
    };
    let left = foot_contacts(
        &positions,
        feet.left_foot,
        feet.left_toe,
        feet.leg_length,
        dt,
        &th,
    );
    let right = foot_contacts(
        &positions,
        feet.right_foot,
        feet.right_toe,
        feet.leg_length,
        dt,
        &th,
    );
    let skip = (config.skip_start_seconds / dt).ceil() as usize;
    let lstarts: Vec<usize> = contact_starts(&left)
        .into_iter()
        .filter(|&f| f >= skip)
        .collect();
    let rstarts = contact_starts(&right);
    let root = layout.root();
    // Ground track of the root, metres.
    let track: Vec<DVec3> = positions
        .iter()
        .map(|p| DVec3::new(p[root].x, 0.0, p[root].z) / upm)
        .collect();
    let ground = |f: usize| track[f];
    let leg_m = feet.leg_length / upm;
    let p = layout.dof();
    let reference = layout.rest_pose();
    let mut report = CycleReport::default();
    for w in lstarts.windows(2) {
        let (a, b) = (w[0], w[1]);
        let drop = |reason| DroppedCycle {
            first_frame: a,
            last_frame: b,
            reason,
        };
        let seconds = (b - a) as f64 * dt;
        if seconds < config.min_cycle_seconds {
            report.dropped.push(drop(DropReason::TooShort { seconds }));
            continue;
        }
        if seconds > config.max_cycle_seconds {
            report.dropped.push(drop(DropReason::TooLong { seconds }));
            continue;
        }
        let rs: Vec<usize> = rstarts
            .iter()
            .copied()
            .filter(|&f| f > a && f < b)
            .collect();
        if rs.len() != 1 {
            report.dropped.push(drop(DropReason::ContactPattern {
                right_contacts: rs.len(),
            }));
            continue;
        }
        let phase = (rs[0] - a) as f64 / (b - a) as f64;
        if phase < config.right_contact_phase.0 || phase > config.right_contact_phase.1 {
            report.dropped.push(drop(DropReason::Asymmetric { phase }));
            continue;
        }
        // Root ground speed over thirds of the cycle.
        let third = |k: usize| {
            let s = a + (b - a) * k / 3;
            let e = a + (b - a) * (k + 1) / 3;
            (ground(e) - ground(s)).length() / ((e - s).max(1) as f64 * dt)
        };
        let (v0, v1, v2) = (third(0), third(1), third(2));
        let speeds = (v0, v2);
        let vmax = v0.max(v1).max(v2);
        let slow = v0.min(v1).min(v2) < config.min_speed * leg_m;
        let change = (v2 - v0).abs() / vmax.max(1e-12);
        if slow || change > config.max_speed_change {
            let reason = if v0 < v2 {
                DropReason::Start { speeds }
            } else {
                DropReason::Stop { speeds }
            };
            report.dropped.push(drop(reason));
            continue;
        }
        let period = (b - a) as f64;
        let headings = (
            travel_heading(&track, a, period),
            travel_heading(&track, b, period),
        );
        let (h0, h1) = match headings {
            (Ok(h0), Ok(h1)) => (h0, h1),
            (Err(at_end), _) => {
                report
                    .dropped
                    .push(drop(DropReason::HeadingWindowTruncated {
                        frame: a,
                        at_end,
                    }));
                continue;
            }
            (_, Err(at_end)) => {
                report
                    .dropped
                    .push(drop(DropReason::HeadingWindowTruncated {
                        frame: b,
                        at_end,
                    }));
                continue;
            }
        };
        let turn = wrap_angle(h1 - h0);
        let c = DQuat::from_rotation_y(-h0);
        let d = c * (ground(b) - ground(a));
        if d.z <= 0.0 {
            report
                .dropped
                .push(drop(DropReason::NotForward { dz: d.z }));
            continue;
        }
        if turn.abs() > config.max_turn.min(PI) {
            report.dropped.push(drop(DropReason::SharpTurn { turn }));
            continue;
        }
        // Canonical poses.
        let n = b - a + 1;
        let mut poses = vec![0.0; n * p];
        let origin = ground(a);
        for (i, row) in poses.chunks_exact_mut(p).enumerate() {
            layout.pose_from_frame(motion, a + i, row)?;
            let pos = DVec3::from_slice(&row[0..3]);
            let q = exp_to_quat(DVec3::from_slice(&row[3..6]));
            let pos = c * (pos - origin);
            row[0..3].copy_from_slice(&pos.to_array());
            row[3..6].copy_from_slice(&quat_to_exp(c * q).to_array());
        }
        align_sequence(&mut poses, &reference)?;
        debug_assert_eq!(poses.len() % p, 0);
        debug_assert!(p >= ALWAYS_ROWS);
        report.cycles.push(GaitCycle {
            source: source.to_path_buf(),
            first_frame: a,
            last_frame: b,
            frame_time: dt,
            poses,
            controls: MeasuredControls {
                dx: d.x,
                dz: d.z,
                turn,
                height,
            },
            left_contact: left[a..=b].to_vec(),
            right_contact: right[a..=b].to_vec(),
            right_contact_start: rs[0] - a,
        });
    }
    Ok(report)
}

/// [`segment_cycles`] on each frame range of `segments` separately (the walking pieces of a take,
/// see [`crate::normalize_take`]), with frame numbers of the whole take: cycles never span two
/// pieces, and `skip_start_seconds` counts from the start of the take. One range covering the whole
/// take gives exactly [`segment_cycles`]'s result.
///
/// Errors: those of [`segment_cycles`]; a frame buffer that is not whole frames is refused
/// whatever the ranges.
pub fn segment_take(
    motion: &Motion,
    layout: &PoseLayout,
    config: &CycleConfig,
    source: &Path,
    segments: &[std::ops::Range<usize>],
) -> Result<CycleReport, CycleError> {
    check_whole_frames(motion)?;
    let nf = motion.frame_count();
    if let [only] = segments {
        if only.start == 0 && only.end == nf {
            return segment_cycles(motion, layout, config, source);
        }
    }
    let n = motion.skeleton.channel_count();
    let mut report = CycleReport::default();
    for range in segments {
        let range = range.start.min(nf)..range.end.min(nf);
        if range.len() < 3 {
            continue;
        }
        let piece = Motion {
            skeleton: motion.skeleton.clone(),
            frame_time: motion.frame_time,
            frames: motion.frames[range.start * n..range.end * n].to_vec(),
        };
        let config = CycleConfig {
            skip_start_seconds: (config.skip_start_seconds
                - range.start as f64 * motion.frame_time)
                .max(0.0),
            ..config.clone()
        };
        let mut r = segment_cycles(&piece, layout, &config, source)?;
        for c in &mut r.cycles {
            c.first_frame += range.start;
            c.last_frame += range.start;
        }
        for d in &mut r.dropped {
            d.first_frame += range.start;
            d.last_frame += range.start;
        }
        report.cycles.extend(r.cycles);
        report.dropped.extend(r.dropped);
    }
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Ground track of a walk at `v` m/s turning at `omega` rad/s from heading `h0`, sampled every
    /// `dt` s for `n` frames, with a lateral sway and a fore-aft surge of amplitude `surge` (m)
    /// that repeat every `period` seconds in the walker's frame (as the root of a walker does),
    /// and its true heading per frame.
    fn arc(
        v: f64,
        omega: f64,
        surge: f64,
        period: f64,
        dt: f64,
        n: usize,
    ) -> (Vec<DVec3>, Vec<f64>) {
        let w = std::f64::consts::TAU / period;
        let h0 = 2.9;
        (0..n)
            .map(|i| {
                let t = i as f64 * dt;
                let h = h0 + omega * t;
                let p = if omega.abs() < 1e-12 {
                    DVec3::new(h0.sin(), 0.0, h0.cos()) * v * t
                } else {
                    let r = v / omega;
                    DVec3::new(r * (h0.cos() - h.cos()), 0.0, r * (h.sin() - h0.sin()))
                };
                let fwd = DVec3::new(h.sin(), 0.0, h.cos());
                let left = DVec3::new(h.cos(), 0.0, -h.sin());
                let sway = 0.03 * (w * t + 0.4).cos() + 0.004 * (2.0 * w * t).sin();
                let surge = surge * (2.0 * w * t + 1.0).sin();
                (p + left * sway + fwd * surge, h)
            })
            .unzip()
    }

    #[test]
    fn travel_heading_is_exact_on_arcs_with_sway_at_every_frame() {
        // 1.1 s cycles at 120 Hz (132 frames), 3.3 cycles of track, both turn directions. A sway
        // that turns with the walker leaves the chords' directions alone (its residual
        // `s (left(h + d) - left(h - d)) = -2 s sin(d) fwd(h)` is along the chord).
        for omega in [-0.5, 0.0, 0.3] {
            let (g, truth) = arc(1.3, omega, 0.0, 1.1, 1.0 / 120.0, 436);
            for f in [0, 20, 65, 66, 200, 370, 400, 435] {
                let h = travel_heading(&g, f, 132.0).unwrap();
                let err = wrap_angle(h - truth[f]).abs();
                assert!(err < 1e-9, "omega {omega} frame {f}: error {err} rad");
            }
        }
    }

    #[test]
    fn a_surge_on_a_turn_tilts_the_heading_by_at_most_surge_times_curvature() {
        // The surge's residual `2 a sin(d) left(h)` is sideways: `a kappa` radians on a chord of
        // `2 R sin(d)`; the extrapolation near the take ends may amplify it by half again.
        let (v, omega, a) = (1.3, -0.5, 0.01);
        let (g, truth) = arc(v, omega, a, 1.1, 1.0 / 120.0, 436);
        let bound = 1.5 * a * (omega / v).abs();
        for (f, t) in truth.iter().enumerate() {
            let h = travel_heading(&g, f, 132.0).unwrap();
            let err = wrap_angle(h - t).abs();
            assert!(err < bound, "frame {f}: error {err} rad, bound {bound}");
        }
    }

    #[test]
    fn travel_heading_of_a_straight_track_is_its_direction() {
        // A straight walk along +X: heading pi/2 wherever the frame lies.
        let g: Vec<DVec3> = (0..100)
            .map(|i| DVec3::new(0.01 * i as f64, 0.0, 0.0))
            .collect();
        for f in [0, 50, 99] {
            let h = travel_heading(&g, f, 40.0).unwrap();
            assert!((h - std::f64::consts::FRAC_PI_2).abs() < 1e-12, "{h}");
        }
    }

    #[test]
    fn travel_heading_needs_one_and_a_half_cycles_of_track() {
        let (g, _) = arc(1.0, 0.2, 0.01, 1.0, 0.01, 151);
        assert!(travel_heading(&g, 0, 100.0).is_ok());
        assert_eq!(travel_heading(&g, 0, 101.0), Err(false));
        assert_eq!(travel_heading(&g, 150, 101.0), Err(true));
        // Inside the centred range the window always fits.
        assert!(travel_heading(&g, 75, 100.0).is_ok());
    }

    #[test]
    fn track_points_interpolate_and_clamp() {
        let g = [
            DVec3::ZERO,
            DVec3::new(1.0, 0.0, 2.0),
            DVec3::new(3.0, 0.0, 2.0),
        ];
        assert_eq!(track_point(&g, 0.5), DVec3::new(0.5, 0.0, 1.0));
        assert_eq!(track_point(&g, 2.0), g[2]);
        assert_eq!(track_point(&g, 7.0), g[2]);
        assert_eq!(track_point(&g, -1.0), g[0]);
        assert_eq!(track_point(&g[..1], 0.3), g[0]);
    }

    #[test]
    fn drop_reason_names_the_truncated_end() {
        let r = DropReason::HeadingWindowTruncated {
            frame: 12,
            at_end: true,
        };
        assert_eq!(
            r.to_string(),
            "heading window truncated at take end (frame 12)"
        );
    }
}
