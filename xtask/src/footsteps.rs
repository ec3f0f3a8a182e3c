//! Footholds and foot trajectories: where each stance foot is planted, how it rolls over heel,
//! sole and ball during stance, and how it swings to the next foothold.
//!
//! The left foot's heel strikes at integer gait phases, the right's half a cycle later; each foot is
//! on the ground for the duty factor `beta` of the cycle. A foothold is placed under the path point
//! at the middle of the foot-flat interval, so steps follow the path (straight or curved) and step
//! length equals `speed x half cycle` by construction. Contact is rolling without slip: the heel
//! point is fixed while the foot lowers, the whole foot is fixed while flat, the ball joint is fixed
//! while the heel rises.

use glam::{DQuat, DVec3};

use crate::gait::{Style, TakeSpec, Trajectory};
use crate::rig::Rig;

/// Stance fraction at which the forefoot lands (end of the heel rocker).
pub const FOOT_FLAT: f64 = 0.12;
/// Stance fraction at which the heel starts to rise (start of the forefoot rocker).
pub const HEEL_RISE: f64 = 0.55;
/// Cycle fraction after its heel strike at which the pelvis passes over a foothold (the ankle is
/// placed under the path point of that instant; about 40 % of stance, as in human walking).
pub const OVER_FOOT: f64 = 0.25;

/// Left (`+X`) or right (`-X`) side.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// The left foot (heel strike at phase 0).
    Left,
    /// The right foot (heel strike at phase 0.5).
    Right,
}

impl Side {
    /// `+1` for left, `-1` for right (the sign of the lateral X offset).
    pub fn sign(self) -> f64 {
        match self {
            Side::Left => 1.0,
            Side::Right => -1.0,
        }
    }

    /// Gait phase of this foot's heel strike within the cycle.
    pub fn phase_offset(self) -> f64 {
        match self {
            Side::Left => 0.0,
            Side::Right => 0.5,
        }
    }
}

/// Where the foot is and how it is oriented at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FootState {
    /// Ankle (`Foot` joint) position, cm.
    pub ankle: DVec3,
    /// Heading of the foot about +Y, radians.
    pub yaw: f64,
    /// Pitch of the foot about its lateral axis, radians (positive = toes down).
    pub pitch: f64,
    /// Toe flexion relative to the foot, radians (negative = toes bent up).
    pub toe: f64,
    /// Whether the foot is on the ground.
    pub stance: bool,
    /// Fraction of the stance (`0..1`, in stance) or of the swing (`0..1`, in swing).
    pub progress: f64,
}

/// Foot pitch/placement parameters derived from the speed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FootPlanner {
    rig: Rig,
    /// Foot pitch at heel strike (negative: toes up), radians.
    pitch_strike: f64,
    /// Foot pitch at toe off (positive: heel up), radians.
    pitch_off: f64,
    /// Half the distance between the ankle paths, cm.
    half_width: f64,
    /// Outward foot rotation, radians.
    toe_out: f64,
    /// Extra ankle lift during swing, cm.
    lift: f64,
}

/// `3x^2 - 2x^3` on `[0, 1]`.
pub fn smoothstep(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// Minimum-jerk profile `10x^3 - 15x^4 + 6x^5` on `[0, 1]`.
pub fn min_jerk(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    x * x * x * (10.0 + x * (-15.0 + 6.0 * x))
}

/// Orientation of a foot with heading `yaw` and pitch `pitch`: `Ry(yaw) Rx(pitch)`.
pub fn foot_rotation(yaw: f64, pitch: f64) -> DQuat {
    DQuat::from_rotation_y(yaw) * DQuat::from_rotation_x(pitch)
}

impl FootPlanner {
    /// The planner of a take: pitches grow with speed (heel strike 12..20 degrees toes up, toe off
    /// 40..55 degrees heel up between 0.8 and 1.6 m/s).
    pub fn new(rig: Rig, spec: &TakeSpec) -> FootPlanner {
        let x = ((spec.speed - 0.8) / 0.8).clamp(-0.5, 1.5);
        let style: &Style = &spec.style;
        FootPlanner {
            rig,
            pitch_strike: -(12.0 + 8.0 * x).to_radians(),
            pitch_off: (40.0 + 15.0 * x).to_radians(),
            half_width: 0.5 * style.step_width * rig.height,
            toe_out: style.toe_out_deg.to_radians(),
            lift: 0.045 * rig.height,
        }
    }

    /// Foothold of stance number `k` of foot `side` (heel strike at phase `k + offset`): the flat
    /// ankle position and the foot heading.
    pub fn foothold(&self, traj: &Trajectory, side: Side, k: i64) -> (DVec3, f64) {
        let phi = k as f64 + side.phase_offset() + OVER_FOOT;
        let t = traj.time_at_phase(phi);
        let heading = traj.heading(t);
        let local = DVec3::new(side.sign() * self.half_width, self.rig.ankle_height, 0.0);
        let ankle = traj.position(t) + DQuat::from_rotation_y(heading) * local;
        (ankle, heading + side.sign() * self.toe_out)
    }

    /// Ankle, pitch and toe angle at stance fraction `u` for a foothold `(flat, yaw)`.
    fn stance(&self, flat: DVec3, yaw: f64, u: f64) -> (DVec3, f64, f64) {
        let level = foot_rotation(yaw, 0.0);
        if u < FOOT_FLAT {
            // Heel rocker: rotate about the fixed heel point.
            let pitch = self.pitch_strike * (1.0 - smoothstep(u / FOOT_FLAT));
            let heel = flat + level * self.rig.heel_local();
            (
                heel - foot_rotation(yaw, pitch) * self.rig.heel_local(),
                pitch,
                0.0,
            )
        } else if u < HEEL_RISE {
            (flat, 0.0, 0.0)
        } else {
            // Forefoot rocker: rotate about the fixed ball joint; the toes stay flat.
            let w = (u - HEEL_RISE) / (1.0 - HEEL_RISE);
            let pitch = self.pitch_off * w * w.sqrt();
            let ball = flat + level * self.rig.ball_local();
            (
                ball - foot_rotation(yaw, pitch) * self.rig.ball_local(),
                pitch,
                -pitch,
            )
        }
    }

    /// State of foot `side` at gait phase `phi`.
    pub fn state(&self, traj: &Trajectory, side: Side, phi: f64) -> FootState {
        let beta = traj.duty;
        let x = phi - side.phase_offset();
        let k = x.floor();
        let frac = x - k;
        let k = k as i64;
        let (flat, yaw) = self.foothold(traj, side, k);
        if frac < beta {
            let u = frac / beta;
            let (ankle, pitch, toe) = self.stance(flat, yaw, u);
            return FootState {
                ankle,
                yaw,
                pitch,
                toe,
                stance: true,
                progress: u,
            };
        }
        let u = (frac - beta) / (1.0 - beta);
        let (a0, p0, _) = self.stance(flat, yaw, 1.0);
        let (next_flat, next_yaw) = self.foothold(traj, side, k + 1);
        let (a1, p1, _) = self.stance(next_flat, next_yaw, 0.0);
        let s = min_jerk(u);
        let mut ankle = a0.lerp(a1, s);
        // Lift with its peak a third into the swing: (27/4) u (1 - u)^2 has maximum 1 at u = 1/3.
        ankle.y += self.lift * 6.75 * u * (1.0 - u) * (1.0 - u);
        let pitch = p0 + (p1 - p0) * s;
        let toe = -p0 * (1.0 - smoothstep(u / 0.4));
        FootState {
            ankle,
            yaw: yaw + (next_yaw - yaw) * s,
            pitch,
            toe,
            stance: false,
            progress: u,
        }
    }

    /// The planner's rig.
    pub fn rig(&self) -> &Rig {
        &self.rig
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn setup(turn: f64) -> (Trajectory, FootPlanner) {
        let spec = TakeSpec {
            height_m: 1.75,
            speed: 1.2,
            turn_rate_deg: turn,
            heading0_deg: 0.0,
            start_m: [0.0, 0.0],
            steady_cycles: 4,
            style: Style::default(),
        };
        let rig = Rig::new(spec.height_m);
        (
            Trajectory::new(&spec, rig.hip_height()),
            FootPlanner::new(rig, &spec),
        )
    }

    #[test]
    fn foot_is_continuous_over_the_cycle() {
        let (traj, fp) = setup(25.0);
        for side in [Side::Left, Side::Right] {
            let base = traj.phase_at(traj.steady_start).round();
            let mut prev = fp.state(&traj, side, base);
            let n = 4000;
            for i in 1..=n {
                let phi = base + 2.0 * i as f64 / n as f64;
                let s = fp.state(&traj, side, phi);
                assert!(
                    (s.ankle - prev.ankle).length() < 1.0,
                    "{side:?} jump at phase {phi}"
                );
                assert!((s.pitch - prev.pitch).abs() < 0.02 && (s.toe - prev.toe).abs() < 0.02);
                prev = s;
            }
        }
    }

    #[test]
    fn contact_points_do_not_slip() {
        let (traj, fp) = setup(-20.0);
        let rig = *fp.rig();
        let beta = traj.duty;
        // Heel fixed during the heel rocker, ball fixed during the forefoot rocker.
        let base = traj.phase_at(traj.steady_start).round() + 1.0;
        let at = |u: f64| fp.state(&traj, Side::Left, base + u * beta);
        let heel = |s: FootState| s.ankle + foot_rotation(s.yaw, s.pitch) * rig.heel_local();
        let ball = |s: FootState| s.ankle + foot_rotation(s.yaw, s.pitch) * rig.ball_local();
        assert!((heel(at(0.0)) - heel(at(0.1))).length() < 1e-9);
        assert!(heel(at(0.0)).y.abs() < 1e-9, "heel on the floor at strike");
        assert!((ball(at(0.6)) - ball(at(0.99))).length() < 1e-9);
        assert!((ball(at(0.99)).y - rig.ball_height).abs() < 1e-9);
    }

    #[test]
    fn steps_alternate_sides_and_follow_the_path() {
        let (traj, fp) = setup(0.0);
        let k = traj.phase_at(traj.steady_start).round() as i64 + 1;
        let (l, _) = fp.foothold(&traj, Side::Left, k);
        let (r, _) = fp.foothold(&traj, Side::Right, k);
        let (l2, _) = fp.foothold(&traj, Side::Left, k + 1);
        assert!(
            l.x > 0.0 && r.x < 0.0,
            "left foot at +X when walking along +Z"
        );
        assert!(r.z > l.z && l2.z > r.z);
        // Straight steady walking: one stride per cycle.
        let stride = (l2 - l).length() / 100.0;
        let expected = crate::gait::stride_length(1.2, traj.leg);
        assert!(
            (stride - expected).abs() < 0.01 * expected,
            "{stride} vs {expected}"
        );
    }
}
