//! Gait timing and the root path: stride and cadence from speed and leg length, the speed ramp of
//! the first cycle, the circular (or straight) path and the gait phase over time.
//!
//! Units: centimetres and seconds inside, metres per second at the interface ([`TakeSpec`]).

use glam::DVec3;

/// Gravitational acceleration, m/s^2.
pub const GRAVITY: f64 = 9.81;

/// Stride length (two steps) in metres at speed `v` (m/s) for hip height `leg` (m).
///
/// Alexander's dynamic-similarity relation `lambda / L = k (v^2 / (g L))^0.3` with `k = 2.5`
/// (fitted to adult walking: a 0.93 m leg at 1.3 m/s gives a 1.40 m stride and 111 steps/min).
pub fn stride_length(v: f64, leg: f64) -> f64 {
    2.5 * leg * (v * v / (GRAVITY * leg)).powf(0.3)
}

/// Gait cycles (strides) per second at speed `v` (m/s): `f = v / stride_length(v, leg)`.
pub fn cycle_frequency(v: f64, leg: f64) -> f64 {
    v / stride_length(v, leg)
}

/// Fraction of the cycle a foot is on the ground (duty factor): 0.64 at 0.8 m/s falling linearly to
/// 0.58 at 1.6 m/s (double support shrinks as walking gets faster), clamped to `[0.56, 0.66]`.
pub fn duty_factor(v: f64) -> f64 {
    (0.64 - 0.06 * (v - 0.8) / 0.8).clamp(0.56, 0.66)
}

/// Personal style of a performer; all amplitudes are at 1.2 m/s and scale with the speed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Style {
    /// Shoulder flexion amplitude of the arm swing, degrees.
    pub arm_swing_deg: f64,
    /// Mean elbow flexion, degrees.
    pub elbow_deg: f64,
    /// Distance between the left and right ankle paths, as a fraction of the height.
    pub step_width: f64,
    /// Outward rotation of each foot from the walking direction, degrees.
    pub toe_out_deg: f64,
    /// Factor on the vertical excursion of the pelvis.
    pub bob_scale: f64,
    /// Forward lean of the trunk, degrees.
    pub trunk_lean_deg: f64,
}

impl Default for Style {
    fn default() -> Self {
        Style {
            arm_swing_deg: 18.0,
            elbow_deg: 18.0,
            step_width: 0.06,
            toe_out_deg: 6.0,
            bob_scale: 1.0,
            trunk_lean_deg: 4.0,
        }
    }
}

/// Everything that defines one take.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TakeSpec {
    /// Standing height of the performer, metres.
    pub height_m: f64,
    /// Steady walking speed, m/s.
    pub speed: f64,
    /// Steady turn rate, degrees per second (positive = turning left, towards +X when facing +Z).
    pub turn_rate_deg: f64,
    /// Heading at time 0, degrees (0 = facing +Z).
    pub heading0_deg: f64,
    /// Root position on the floor at time 0, metres (x, z).
    pub start_m: [f64; 2],
    /// Number of whole steady cycles (left heel strike to left heel strike) after the speed ramp.
    pub steady_cycles: usize,
    /// The performer's style.
    pub style: Style,
}

/// A take specification outside the range the walker models.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SpecError {
    /// A field is NaN, infinite or outside its accepted range.
    #[error("take spec: {field} = {value} is outside {range}")]
    OutOfRange {
        /// The field's name.
        field: &'static str,
        /// Its value.
        value: f64,
        /// The accepted range, for the message.
        range: &'static str,
    },
}

impl TakeSpec {
    /// Checks every field: height 1.0..=2.5 m, speed 0.3..=2.5 m/s, turn rate within +-90 deg/s,
    /// curvature at most 1.5 rad/m (a turn radius of 0.67 m or more), finite start heading and
    /// position, 1..=100 steady cycles.
    pub fn validate(&self) -> Result<(), SpecError> {
        let check = |field, value: f64, lo: f64, hi: f64, range| {
            if value.is_finite() && (lo..=hi).contains(&value) {
                Ok(())
            } else {
                Err(SpecError::OutOfRange {
                    field,
                    value,
                    range,
                })
            }
        };
        check("height_m", self.height_m, 1.0, 2.5, "[1.0, 2.5]")?;
        check("speed", self.speed, 0.3, 2.5, "[0.3, 2.5]")?;
        check(
            "turn_rate_deg",
            self.turn_rate_deg,
            -90.0,
            90.0,
            "[-90, 90]",
        )?;
        let curvature = self.turn_rate_deg.to_radians() / self.speed;
        check(
            "turn_rate / speed (rad/m)",
            curvature,
            -1.5,
            1.5,
            "[-1.5, 1.5]",
        )?;
        check(
            "heading0_deg",
            self.heading0_deg,
            -1e6,
            1e6,
            "finite values",
        )?;
        check("start_m[0]", self.start_m[0], -1e6, 1e6, "finite values")?;
        check("start_m[1]", self.start_m[1], -1e6, 1e6, "finite values")?;
        check(
            "steady_cycles",
            self.steady_cycles as f64,
            1.0,
            100.0,
            "[1, 100]",
        )?;
        Ok(())
    }
}

/// Speed at time 0 as a fraction of the steady speed (a standstill-like first cycle).
pub const START_SPEED_FRACTION: f64 = 0.3;
/// Length of the speed ramp in cycles of the steady gait.
pub const RAMP_CYCLES: f64 = 1.25;
/// Cycles walked after the last steady cycle's closing heel strike: half a cycle of the same steady
/// walk, so that a window of one cycle centred on that heel strike (over which `motion_io`
/// measures the heading of travel) lies inside the take, plus a tenth of a cycle for the contact
/// detection.
pub const END_MARGIN: f64 = 0.6;
/// Resolution of the tabulated gait phase, seconds.
const PHASE_DT: f64 = 1.0 / 2400.0;
/// How far before time 0 the phase table reaches (footholds of the first steps lie in the past).
const LEAD_IN: f64 = 4.0;

/// The root path and gait phase of one take.
///
/// Speed `v(t) = v r(t)` with `r(t) = r0 + (1 - r0) S(t / T_r)` on `[0, T_r]` (`S` the smoothstep
/// `3x^2 - 2x^3`), `r0` before and 1 after. The path has constant curvature
/// `kappa = omega / v`, so the turn rate is `kappa v(t)` and reaches `omega` with the speed.
/// The phase advances at the cadence of the current speed, `dphi/dt = f(v(t))`.
#[derive(Debug, Clone)]
pub struct Trajectory {
    /// Steady speed, cm/s.
    pub speed: f64,
    /// Path curvature, radians per cm.
    pub curvature: f64,
    /// Heading at arc length 0, radians.
    pub heading0: f64,
    /// Root position on the floor at time 0, cm.
    pub start: DVec3,
    /// Ramp duration `T_r`, seconds.
    pub ramp: f64,
    /// Leg length (hip height), metres: sets the cadence.
    pub leg: f64,
    /// Duty factor at the steady speed.
    pub duty: f64,
    /// Time of the first tabulated phase value.
    t_min: f64,
    /// Phase at `t_min + i * PHASE_DT`.
    phase: Vec<f64>,
    /// Time at which the take ends (last frame at or before it).
    pub end: f64,
    /// Time of the first left heel strike after the ramp (start of the steady cycles).
    pub steady_start: f64,
}

impl Trajectory {
    /// The trajectory of `spec` for a performer whose hip joints are `hip_height_cm` above the floor.
    /// `spec` must pass [`TakeSpec::validate`] (checked in debug builds).
    pub fn new(spec: &TakeSpec, hip_height_cm: f64) -> Trajectory {
        debug_assert!(spec.validate().is_ok(), "{spec:?}");
        let leg = hip_height_cm / 100.0;
        let speed = spec.speed * 100.0;
        let curvature = spec.turn_rate_deg.to_radians() / speed;
        let ramp = RAMP_CYCLES / cycle_frequency(spec.speed, leg);
        let mut traj = Trajectory {
            speed,
            curvature,
            heading0: spec.heading0_deg.to_radians(),
            start: DVec3::new(spec.start_m[0] * 100.0, 0.0, spec.start_m[1] * 100.0),
            ramp,
            leg,
            duty: duty_factor(spec.speed),
            t_min: -LEAD_IN,
            phase: Vec::new(),
            end: 0.0,
            steady_start: 0.0,
        };
        // Integrate the phase with the trapezoid rule on a fine grid, far enough past the end
        // that the footholds of the last steps are known.
        let t_max = ramp + (spec.steady_cycles as f64 + 4.0) / cycle_frequency(spec.speed, leg);
        let n = ((t_max - traj.t_min) / PHASE_DT).ceil() as usize + 1;
        let mut phase = Vec::with_capacity(n);
        let rate = |t: f64| cycle_frequency(traj.speed_at(t) / 100.0, leg);
        // Phase 0 at time 0: shift after integrating.
        let mut acc = 0.0;
        let mut prev = rate(traj.t_min);
        phase.push(0.0);
        for i in 1..n {
            let cur = rate(traj.t_min + i as f64 * PHASE_DT);
            acc += 0.5 * (prev + cur) * PHASE_DT;
            prev = cur;
            phase.push(acc);
        }
        traj.phase = phase;
        // Shift the phase so that a left heel strike falls exactly at the end of the ramp: the
        // take then holds the accelerating first cycle and whole steady cycles after it.
        let at_ramp = traj.phase_at(ramp);
        let shift = at_ramp.ceil() - at_ramp;
        for p in &mut traj.phase {
            *p += shift;
        }
        let first_steady = traj.phase_at(ramp).round();
        traj.steady_start = ramp;
        traj.end = traj.time_at_phase(first_steady + spec.steady_cycles as f64 + END_MARGIN);
        traj
    }

    /// Speed ramp factor `r(t)`.
    pub fn ramp_factor(&self, t: f64) -> f64 {
        let r0 = START_SPEED_FRACTION;
        if t <= 0.0 {
            r0
        } else if t >= self.ramp {
            1.0
        } else {
            let x = t / self.ramp;
            r0 + (1.0 - r0) * x * x * (3.0 - 2.0 * x)
        }
    }

    /// Root speed at time `t`, cm/s.
    pub fn speed_at(&self, t: f64) -> f64 {
        self.speed * self.ramp_factor(t)
    }

    /// Arc length travelled since time 0, cm: the integral of `v(t)`, with
    /// `int_0^x S = x^3 - x^4 / 2` on the ramp.
    pub fn arc_length(&self, t: f64) -> f64 {
        let r0 = START_SPEED_FRACTION;
        let tr = self.ramp;
        let unit = if t <= 0.0 {
            r0 * t
        } else if t <= tr {
            let x = t / tr;
            r0 * t + (1.0 - r0) * tr * (x * x * x - 0.5 * x * x * x * x)
        } else {
            r0 * tr + 0.5 * (1.0 - r0) * tr + (t - tr)
        };
        self.speed * unit
    }

    /// Heading (rotation about +Y, radians) at time `t`: `theta0 + kappa s(t)`.
    pub fn heading(&self, t: f64) -> f64 {
        self.heading0 + self.curvature * self.arc_length(t)
    }

    /// Turn rate at time `t`, radians per second.
    pub fn turn_rate(&self, t: f64) -> f64 {
        self.curvature * self.speed_at(t)
    }

    /// Point of the path on the floor at time `t`, cm. Forward is `(sin theta, 0, cos theta)`;
    /// on a circle `x = x0 + (cos theta0 - cos theta) / kappa`, `z = z0 + (sin theta - sin theta0) / kappa`.
    pub fn position(&self, t: f64) -> DVec3 {
        let s = self.arc_length(t);
        let th0 = self.heading0;
        let k = self.curvature;
        let d = if (k * s).abs() < 1e-9 {
            DVec3::new(th0.sin() * s, 0.0, th0.cos() * s)
        } else {
            let th = th0 + k * s;
            DVec3::new((th0.cos() - th.cos()) / k, 0.0, (th.sin() - th0.sin()) / k)
        };
        self.start + d
    }

    /// Gait phase at time `t` (cycles; integer values are left heel strikes), interpolated.
    pub fn phase_at(&self, t: f64) -> f64 {
        let x = (t - self.t_min) / PHASE_DT;
        let last = self.phase.len() - 1;
        if x <= 0.0 {
            return self.phase[0] + x * (self.phase[1] - self.phase[0]);
        }
        let i = (x.floor() as usize).min(last - 1);
        let f = x - i as f64;
        self.phase[i] + f * (self.phase[i + 1] - self.phase[i])
    }

    /// The time at which the phase reaches `phi` (inverse of [`Trajectory::phase_at`]; the phase
    /// is strictly increasing). Clamped to the tabulated range.
    pub fn time_at_phase(&self, phi: f64) -> f64 {
        let i = self.phase.partition_point(|&p| p < phi);
        if i == 0 {
            return self.t_min;
        }
        if i >= self.phase.len() {
            return self.t_min + (self.phase.len() - 1) as f64 * PHASE_DT;
        }
        let (a, b) = (self.phase[i - 1], self.phase[i]);
        let f = (phi - a) / (b - a);
        self.t_min + (i as f64 - 1.0 + f) * PHASE_DT
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(speed: f64, turn: f64) -> TakeSpec {
        TakeSpec {
            height_m: 1.75,
            speed,
            turn_rate_deg: turn,
            heading0_deg: 30.0,
            start_m: [1.0, -2.0],
            steady_cycles: 4,
            style: Style::default(),
        }
    }

    #[test]
    fn stride_and_cadence_are_human() {
        let s = stride_length(1.3, 0.93);
        assert!((1.3..1.5).contains(&s), "stride {s}");
        let steps_per_min = 120.0 * cycle_frequency(1.3, 0.93);
        assert!(
            (100.0..120.0).contains(&steps_per_min),
            "cadence {steps_per_min}"
        );
        assert!(cycle_frequency(1.6, 0.93) > cycle_frequency(0.8, 0.93));
        assert!(
            cycle_frequency(1.2, 0.85) > cycle_frequency(1.2, 1.0),
            "shorter legs step faster"
        );
    }

    #[test]
    fn arc_length_is_the_integral_of_speed() {
        let tr = Trajectory::new(&spec(1.2, 20.0), 92.75);
        let dt = 1e-4;
        let mut s = 0.0;
        let mut t = 0.0;
        while t < tr.end - 1e-9 {
            s += 0.5 * (tr.speed_at(t) + tr.speed_at(t + dt)) * dt;
            t += dt;
        }
        assert!(
            (s - tr.arc_length(t)).abs() < 1e-3 * s,
            "{s} vs {}",
            tr.arc_length(t)
        );
    }

    #[test]
    fn path_direction_follows_heading() {
        let tr = Trajectory::new(&spec(1.0, -25.0), 92.75);
        for &t in &[-0.5, 0.0, 0.7, 2.0, 4.0] {
            let h = 1e-5;
            let d = (tr.position(t + h) - tr.position(t - h)) / (2.0 * h);
            let th = tr.heading(t);
            let fwd = DVec3::new(th.sin(), 0.0, th.cos());
            assert!(
                (d - fwd * tr.speed_at(t)).length() < 1e-3 * tr.speed,
                "t={t}: {d} vs {fwd}"
            );
        }
    }

    #[test]
    fn phase_inverse_and_steady_cycles() {
        let tr = Trajectory::new(&spec(1.4, 0.0), 92.75);
        let p_ramp = tr.phase_at(tr.ramp);
        assert!(
            (p_ramp - p_ramp.round()).abs() < 1e-9,
            "left heel strike at the end of the ramp"
        );
        for &d in &[-0.5, 0.0, 1.0, 2.25, 4.0] {
            let phi = tr.phase_at(0.0) + d;
            assert!((tr.phase_at(tr.time_at_phase(phi)) - phi).abs() < 1e-9);
        }
        let p0 = tr.phase_at(tr.steady_start);
        assert!((p0 - p0.round()).abs() < 1e-9 && tr.steady_start >= tr.ramp - 1e-9);
        // Four steady cycles and the half cycle (plus margin) walked after the last one.
        assert!((tr.phase_at(tr.end) - p0 - 4.0 - END_MARGIN).abs() < 1e-6);
    }
}
