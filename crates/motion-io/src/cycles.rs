//! Segmentation of whole takes into two-step gait cycles (one left contact to the next),
//! canonicalisation and control parameters.
//!
//! A cycle runs from the frame a left contact starts to the frame the next one starts (both
//! included). Its poses are canonicalised: the root starts over the ground origin heading +Z
//! (y up, +x = the character's left). Controls (docs/architecture.md): `dx`, `dz` root
//! displacement over the cycle in the start heading frame (metres), `turn` heading change
//! (radians, positive = left), `height` standing height (metres).

use std::f64::consts::PI;
use std::fmt;
use std::path::{Path, PathBuf};

use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};

use crate::contacts::{
    ContactThresholds, CycleError, Feet, FootNames, contact_starts, find_feet, foot_contacts,
    standing_height,
};
use crate::expmap::{exp_to_quat, quat_to_exp, wrap_angle};
use crate::motion::Motion;
use crate::pose::{PoseLayout, ROOT_ROWS, align_sequence};
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

/// The control parameters of one cycle.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Controls {
    /// Root displacement to the character's left over the cycle, metres (start heading frame).
    pub dx: f64,
    /// Root displacement forward over the cycle, metres (start heading frame).
    pub dz: f64,
    /// Heading change over the cycle, radians, positive = turn left.
    pub turn: f64,
    /// Standing height of the skeleton, metres ([`crate::contacts::standing_height`]).
    pub height: f64,
}

impl Controls {
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
    pub controls: Controls,
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

/// Forward direction of the character at one frame: `left x up` with
/// `left = p(left hip) - p(right hip)` projected on the ground (unit length); its heading is
/// `atan2(f.x, f.z)` (0 = +Z, positive towards +X = turning left).
fn forward(p: &[DVec3], feet: &Feet) -> DVec3 {
    let mut left = p[feet.left_hip] - p[feet.right_hip];
    left.y = 0.0;
    left.cross(DVec3::Y).normalize_or_zero()
}

/// Heading at frame `f` averaged over a window of `len` frames centred on it (clipped to the
/// take): the pelvis yaws back and forth within a gait cycle, and averaging over one cycle removes
/// that oscillation so a straight walk has `dx ~ 0`.
fn heading(positions: &[Vec<DVec3>], feet: &Feet, f: usize, len: usize) -> f64 {
    let half = len / 2;
    let (a, b) = (f.saturating_sub(half), (f + half).min(positions.len() - 1));
    let mut sum = DVec3::ZERO;
    for p in &positions[a..=b] {
        sum += forward(p, feet);
    }
    sum.x.atan2(sum.z)
}

/// Splits a take into steady two-step cycles.
///
/// Contacts: per foot, ankle or toe within `contact_height` leg lengths of its floor level and
/// slower than `contact_speed` leg lengths/s ([`foot_contacts`]). Candidates: consecutive left
/// contact starts after `skip_start_seconds`. A candidate is kept when its duration is in range,
/// it holds exactly one right contact start within the phase window, the root ground speed of
/// each third is above `min_speed` and the first and last thirds differ by at most
/// `max_speed_change`, it moves forward and turns less than `max_turn`; otherwise it is dropped
/// with the reason.
pub fn segment_cycles(
    motion: &Motion,
    layout: &PoseLayout,
    config: &CycleConfig,
    source: &Path,
) -> Result<CycleReport, CycleError> {
    config.validate()?;
    let dt = motion.frame_time;
    if !(dt.is_finite() && dt > 0.0) {
        return Err(CycleError::BadMotion(format!("frame time {dt}")));
    }
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
    let ground = |f: usize| {
        let p = positions[f][root];
        DVec3::new(p.x, 0.0, p.z) / upm
    };
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
        let h0 = heading(&positions, &feet, a, b - a);
        let h1 = heading(&positions, &feet, b, b - a);
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
        debug_assert!(p >= ROOT_ROWS);
        report.cycles.push(GaitCycle {
            source: source.to_path_buf(),
            first_frame: a,
            last_frame: b,
            frame_time: dt,
            poses,
            controls: Controls {
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
