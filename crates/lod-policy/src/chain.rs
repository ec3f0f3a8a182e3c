//! Chaining clips into continuous locomotion: the one routine `synth`, the crowd and an engine use.
//!
//! A clip is one gait cycle in its own *cycle frame* (root on the ground origin at the start, facing
//! +z, +x left, y up). Consecutive clips are chained in two steps:
//!
//! 1. **Root motion.** The next cycle frame is the previous one advanced by the clip's
//!    [`RootMotion`]: the root's ground displacement `(dx, dz)` from the first to the last aligned
//!    frame and the travel turn (the control the clip was built for: the direction of travel, as the
//!    data define it, not the pelvis's yaw change). [`RootMotion::next_frame`].
//! 2. **Inertialization of the seam.** What the next clip's first pose lacks to continue the
//!    previous clip's last displayed pose, position *and* velocity, is an offset that decays to zero
//!    with a critically damped spring (the inertialization of motion-matching systems):
//!    `o(t) = (x0 + (v0 + y x0) t) e^{-y t}`, `y = 2 ln 2 / halflife`, so `o(0) = x0`,
//!    `o'(0) = v0`. `x0` and `v0` are the differences of the poses and of their velocities at the
//!    seam, with the previous pose brought into the next cycle frame. Joint rows (exponential maps
//!    on one branch) and the root position take the difference row by row; the root orientation
//!    takes the rotation `log(q_prev q_next^-1)` and the difference of the angular velocities, and is
//!    applied as `exp(o(t)) q_next(t)`. The time-increment row is not touched.
//!
//! The result is continuous in position and velocity for every row, whatever the controls of the two
//! clips (changing controls and levels between cycles included), and costs `3 P` floats per character.
//! A transition started while another is running starts from the displayed pose, so the offsets never
//! jump. The paper's ease-in/out blend of the overlapping halves (section 5) only hides the jump in
//! position and leaves a kink in velocity; [`SeamTransition`] replaces it.

use glam::{DVec3, Quat, Vec3};
use serde::{Deserialize, Serialize};

use crate::math::wrap_angle_f64;
use crate::model::{ALWAYS_ROWS, TIME_ROW};

/// Default half-life of a seam offset (s), chosen with the motion-quality meter (`motion-lod
/// quality`): the offset is under 5% of its start 0.5 s after the seam, inside the first half of a
/// 1.1 s walk cycle.
pub const DEFAULT_HALFLIFE_S: f32 = 0.15;

/// Root motion of one clip in its start cycle frame: ground displacement and travel turn.
///
/// Not [`Controls`](crate::Controls), though it has three of their fields: controls are what a
/// clip is *asked* for, root motion is where the clip's root *actually goes* from its first to its
/// last aligned frame (the model's output: the requested displacement up to clamping and the
/// model's error), which is what the next cycle must start from. Only the turn is taken from the
/// (clamped) controls, since the data define a cycle's turn as that of its direction of travel
/// ([`ControlSpace::root_motion`](crate::ControlSpace::root_motion)).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct RootMotion {
    /// Displacement to the character's left (m).
    pub dx: f32,
    /// Displacement forward (m).
    pub dz: f32,
    /// Turn of the cycle frame (radians, + = left).
    pub turn: f32,
}

/// A cycle frame on the ground: origin `(x, z)` and heading (radians about +y, 0 = facing +z).
///
/// In double precision, as large worlds keep their object frames: a walker an hour's walk from the
/// origin, or 1 km away, chains thousands of cycles whose displacements would otherwise be rounded
/// to the single-precision spacing there (61 µm at 1 km) at every cycle end. The pose inside the
/// frame stays in single precision (metres from the frame's origin); [`CycleFrame::to_world`]
/// places its points in double precision.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct CycleFrame {
    /// Ground x of the origin (m).
    pub x: f64,
    /// Ground z of the origin (m).
    pub z: f64,
    /// Heading (radians), in `(-pi, pi]` once chained ([`CycleFrame::next`]).
    pub heading: f64,
}

impl CycleFrame {
    /// The frame's rotation, in single precision: it rotates points of the cycle frame (metres
    /// from its origin), whose error it scales by their length.
    pub fn rotation(&self) -> Quat {
        Quat::from_rotation_y(self.heading as f32)
    }

    /// A point of the cycle frame in the world, in double precision:
    /// `(x + p_x cos h + p_z sin h, p_y, z - p_x sin h + p_z cos h)`, the rotation applied in
    /// single precision ([`CycleFrame::rotation`]) and the origin added in double.
    pub fn to_world(&self, p: Vec3) -> DVec3 {
        let v = self.rotation() * p;
        DVec3::new(
            self.x + f64::from(v.x),
            f64::from(v.y),
            self.z + f64::from(v.z),
        )
    }

    /// Places the root of `pose` (a pose vector of this cycle frame, at least 6 rows; a shorter
    /// one is left as it is) in the world:
    /// rows `0..3` become the world position ([`CycleFrame::to_world`], rounded to single
    /// precision: for poses near the origin, such as a synthesized take written to a file; far
    /// from it keep the frame and the pose apart), rows `3..6` the exponential map of the world
    /// orientation (the frame's rotation times the root's). The other rows are local and stay as
    /// they are.
    pub fn place_root(&self, pose: &mut [f32]) {
        if pose.len() < 6 {
            return;
        }
        let root = self.to_world(Vec3::from_slice(&pose[0..3])).as_vec3();
        let orient = self.rotation() * exp_map_to_quat(Vec3::from_slice(&pose[3..6]));
        pose[0..3].copy_from_slice(&root.to_array());
        pose[3..6].copy_from_slice(&quat_to_exp_map(orient).to_array());
    }

    /// The frame after `motion` (step 1 of the module documentation), in double precision: the
    /// origin moves by the clip's displacement rotated by the heading, the heading turns by the
    /// clip's turn and wraps to `(-pi, pi]`.
    pub fn next(&self, motion: &RootMotion) -> CycleFrame {
        let (sin, cos) = self.heading.sin_cos();
        let (dx, dz) = (f64::from(motion.dx), f64::from(motion.dz));
        CycleFrame {
            x: self.x + dx * cos + dz * sin,
            z: self.z - dx * sin + dz * cos,
            heading: wrap_angle_f64(self.heading + f64::from(motion.turn)),
        }
    }
}

impl RootMotion {
    /// The next cycle frame after this motion, from `frame`.
    pub fn next_frame(&self, frame: &CycleFrame) -> CycleFrame {
        frame.next(self)
    }
}

/// The quaternion of an exponential map (rotation vector), as `Quat::from_axis_angle(v / |v|, |v|)`
/// (identity below `|v| = 1e-12`), used for the root's heading in cycle chaining, root motion and
/// seams.
///
/// [`crate::rig::exp_to_quat`] is the same rotation computed another way (`v sin(|v|/2) / |v|`, with
/// a Taylor series near 0) for forward kinematics. The two can differ in the last bits, and both are
/// kept because each one's rounding is part of results that are checked bit for bit: chained crowd
/// paths and root motions here, joint positions there (and the C ABI's poses against Rust's).
pub fn exp_map_to_quat(v: Vec3) -> Quat {
    let angle = v.length();
    if angle > 1e-12 {
        Quat::from_axis_angle(v / angle, angle)
    } else {
        Quat::IDENTITY
    }
}

/// The exponential map (rotation vector, `|v| <= pi`) of a quaternion.
pub fn quat_to_exp_map(q: Quat) -> Vec3 {
    let q = if q.w < 0.0 { -q } else { q };
    let (axis, angle) = q.to_axis_angle();
    if angle.abs() < 1e-12 {
        Vec3::ZERO
    } else {
        axis * angle
    }
}

/// A pose and its velocity (per second) at one instant: the state a seam transition starts from.
///
/// Rows as the model's pose vector; in `velocity`, rows `3..6` hold the root's angular velocity (rad/s,
/// cycle frame) instead of the derivative of its exponential map.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseState {
    /// Pose rows.
    pub pose: Vec<f32>,
    /// Velocity rows.
    pub velocity: Vec<f32>,
}

impl PoseState {
    /// A zero state of `p` rows.
    pub fn new(p: usize) -> PoseState {
        PoseState {
            pose: vec![0.0; p],
            velocity: vec![0.0; p],
        }
    }

    /// Sets the state to `pose` with the velocity from `earlier` to `later`, two poses `h` seconds
    /// apart (finite differences; `pose` is usually one of them). Sets the rows all four slices
    /// (`pose`, `earlier`, `later` and this state's `pose` and `velocity`) hold. An `h` that is not
    /// finite and positive (two poses at the same time) gives zero velocity.
    pub fn set(&mut self, pose: &[f32], earlier: &[f32], later: &[f32], h: f32) {
        let n = pose
            .len()
            .min(earlier.len())
            .min(later.len())
            .min(self.pose.len())
            .min(self.velocity.len());
        self.pose[..n].copy_from_slice(&pose[..n]);
        if !(h.is_finite() && h > 0.0) {
            self.velocity[..n].fill(0.0);
            return;
        }
        for ((v, &a), &b) in self.velocity[..n].iter_mut().zip(later).zip(earlier) {
            *v = (a - b) / h;
        }
        if n >= 6 {
            let q1 = exp_map_to_quat(Vec3::from_slice(&later[3..6]));
            let q0 = exp_map_to_quat(Vec3::from_slice(&earlier[3..6]));
            let w = quat_to_exp_map(q1 * q0.inverse()) / h;
            self.velocity[3..6].copy_from_slice(&w.to_array());
        }
    }

    /// Re-expresses the state, given in a cycle frame, in the frame after `motion` (the next cycle's):
    /// root position `R_y(-turn) (p - (dx, 0, dz))`, orientation `R_y(-turn) q`, and the velocities
    /// rotated likewise. A state of fewer than 6 pose or velocity rows is left as it is.
    pub fn into_next_frame(&mut self, motion: &RootMotion) {
        if self.pose.len() < 6 || self.velocity.len() < 6 {
            return;
        }
        let r = Quat::from_rotation_y(-motion.turn);
        let p = Vec3::from_slice(&self.pose[0..3]) - Vec3::new(motion.dx, 0.0, motion.dz);
        self.pose[0..3].copy_from_slice(&(r * p).to_array());
        let q = r * exp_map_to_quat(Vec3::from_slice(&self.pose[3..6]));
        self.pose[3..6].copy_from_slice(&quat_to_exp_map(q).to_array());
        for range in [0..3, 3..6] {
            let v = r * Vec3::from_slice(&self.velocity[range.clone()]);
            self.velocity[range].copy_from_slice(&v.to_array());
        }
    }
}

/// The inertialized seam between two clips (module documentation): offsets that decay from the
/// previous clip's displayed state to the next clip's own motion. Holds `3 P` floats; starting and
/// applying allocate nothing.
#[derive(Debug, Clone, PartialEq)]
pub struct SeamTransition {
    offset: Vec<f32>,
    velocity: Vec<f32>,
    /// The incoming side's rows at the seam: for rows the incoming clip does not evaluate (a joint
    /// fading out), the rest rotation the transition decays to ([`SeamTransition::fill_beyond`]).
    base: Vec<f32>,
    rows: usize,
    decay: f32,
    active: bool,
}

impl SeamTransition {
    /// A transition over pose vectors of `p` rows with the given half-life (s, clamped to at least 1 ms).
    pub fn new(p: usize, halflife_s: f32) -> SeamTransition {
        SeamTransition {
            offset: vec![0.0; p],
            velocity: vec![0.0; p],
            base: vec![0.0; p],
            rows: 0,
            decay: 2.0 * std::f32::consts::LN_2 / halflife_s.max(1e-3),
            active: false,
        }
    }

    /// Whether a transition is running (until [`SeamTransition::finish_after`] or [`SeamTransition::clear`]).
    pub fn is_active(&self) -> bool {
        self.active
    }

    /// Stops any transition.
    pub fn clear(&mut self) {
        self.active = false;
        self.rows = 0;
    }

    /// Stops the transition once its offset has decayed below `1e-4` of its start (`t` seconds after
    /// the seam; an infinite `t` finishes it); returns whether it is still active.
    pub fn finish_after(&mut self, t: f32) -> bool {
        let x = self.decay * t;
        if self.active && (x == f32::INFINITY || (1.0 + x) * (-x).exp() < 1e-4) {
            self.clear();
        }
        self.active
    }

    /// Starts a transition from `prev` (the displayed state at the seam, already in the next clip's
    /// cycle frame, see [`PoseState::into_next_frame`]) to `next` (the next clip's own state at the
    /// seam). Only the first `rows` rows are blended (both clips evaluate at least that many; at
    /// most the rows every pose and velocity of the two states holds).
    pub fn start(&mut self, prev: &PoseState, next: &PoseState, rows: usize) {
        let rows = rows
            .min(self.offset.len())
            .min(prev.pose.len())
            .min(next.pose.len())
            .min(prev.velocity.len())
            .min(next.velocity.len());
        for r in 0..rows {
            let (x, v) = if r == TIME_ROW || (3..6).contains(&r) {
                (0.0, 0.0)
            } else {
                (
                    prev.pose[r] - next.pose[r],
                    prev.velocity[r] - next.velocity[r],
                )
            };
            self.offset[r] = x;
            self.velocity[r] = v;
        }
        self.base[..rows].copy_from_slice(&next.pose[..rows]);
        if rows >= 6 {
            let qp = exp_map_to_quat(Vec3::from_slice(&prev.pose[3..6]));
            let qn = exp_map_to_quat(Vec3::from_slice(&next.pose[3..6]));
            let x = quat_to_exp_map(qp * qn.inverse());
            let v = Vec3::from_slice(&prev.velocity[3..6]) - Vec3::from_slice(&next.velocity[3..6]);
            self.offset[3..6].copy_from_slice(&x.to_array());
            self.velocity[3..6].copy_from_slice(&v.to_array());
        }
        self.rows = rows;
        self.active = rows > 0;
    }

    /// Rows the running transition covers (0 when none runs). More than the incoming clip evaluates
    /// while joints it dropped fade out ([`SeamScratch::start_from_rest`]).
    pub fn rows(&self) -> usize {
        if self.active { self.rows } else { 0 }
    }

    /// Completes a pose whose first `from` rows the incoming clip wrote: rows `from..` up to the
    /// transition's rows (and `pose.len()`) get the values the transition decays to there, the rest
    /// rotations of joints fading out, so that [`SeamTransition::apply`] fades them. Returns the
    /// rows to show: `from`, or more while joints fade out.
    pub fn fill_beyond(&self, from: usize, pose: &mut [f32]) -> usize {
        let to = self.rows().min(pose.len());
        if to <= from {
            return from;
        }
        pose[from..to].copy_from_slice(&self.base[from..to]);
        to
    }

    /// Applies the transition `t` seconds after the seam to the next clip's pose (its first `rows`
    /// rows, in its cycle frame). Does nothing when no transition is active, or when `t` is so
    /// large that the transition has decayed completely (`decay t` infinite).
    pub fn apply(&self, t: f32, pose: &mut [f32]) {
        if !self.active {
            return;
        }
        let t = t.max(0.0);
        if !(self.decay * t).is_finite() {
            return;
        }
        let e = (-self.decay * t).exp();
        let (a, b) = ((1.0 + self.decay * t) * e, t * e);
        let rows = self.rows.min(pose.len());
        for (r, ((v, &x), &w)) in pose
            .iter_mut()
            .zip(&self.offset)
            .zip(&self.velocity)
            .enumerate()
            .take(rows)
        {
            if r != TIME_ROW && !(3..6).contains(&r) {
                *v += a * x + b * w;
            }
        }
        if rows >= 6 {
            let o = a * Vec3::from_slice(&self.offset[3..6])
                + b * Vec3::from_slice(&self.velocity[3..6]);
            let q = exp_map_to_quat(o) * exp_map_to_quat(Vec3::from_slice(&pose[3..6]));
            let v = nearest_branch(quat_to_exp_map(q), Vec3::from_slice(&pose[3..6]));
            pose[3..6].copy_from_slice(&v.to_array());
        }
    }
}

/// Step of the finite differences that give the velocities at a seam (s): one 30 fps frame, longer
/// than an aligned frame of 120 Hz data, whose single-segment slopes are noisy.
pub const SEAM_STEP_S: f32 = 1.0 / 30.0;

/// Caller-owned scratch that starts seam transitions: the states of the outgoing and incoming
/// clips and two pose buffers (`4 P` floats and two `P`-float buffers, allocated once; starting a
/// seam allocates nothing). One per thread is enough; it holds nothing between seams.
///
/// A seam is started in two calls, so that the outgoing clip's buffer may be rebuilt in between:
/// [`SeamScratch::capture`] reads the outgoing clip's *displayed* pose (with the transition already
/// running applied) and its velocity, [`SeamScratch::start`] reads the incoming clip and starts the
/// transition from the captured state. Both take the pose as a function of clip time, so the same
/// routine serves `synth`, the crowd and an engine.
#[derive(Debug, Clone, PartialEq)]
pub struct SeamScratch {
    prev: PoseState,
    next: PoseState,
    a: Vec<f32>,
    b: Vec<f32>,
    rows: usize,
}

/// The two times whose poses give the velocity at `t` in a clip of `duration` seconds by a finite
/// difference over `h`: backward `(t - h, t)` when there is room, else forward `(t, t + h)`; `h` is
/// at most a quarter of the clip.
fn difference_window(t: f32, duration: f32, h: f32) -> (f32, f32) {
    let h = h.min(0.25 * duration).max(1e-4);
    if t - h >= 0.0 { (t - h, t) } else { (t, t + h) }
}

impl SeamScratch {
    /// Scratch for pose vectors of length `p`.
    pub fn new(p: usize) -> SeamScratch {
        SeamScratch {
            prev: PoseState::new(p),
            next: PoseState::new(p),
            a: vec![0.0; p],
            b: vec![0.0; p],
            rows: 0,
        }
    }

    /// Fills `state` with the pose at `t` and its velocity over `h` (see [`difference_window`]);
    /// returns the rows both evaluations wrote.
    #[allow(clippy::too_many_arguments)]
    fn sample<E, F>(
        state: &mut PoseState,
        a: &mut [f32],
        b: &mut [f32],
        t: f32,
        duration: f32,
        h: f32,
        mut pose_at: F,
    ) -> Result<usize, E>
    where
        F: FnMut(f32, &mut [f32]) -> Result<usize, E>,
    {
        // A time that is not finite reads as the clip's start (NaN, -inf) or end (+inf); a time so
        // large that the window collapses (`t - h == t`) gives zero velocity (`PoseState::set`).
        let t = if t.is_finite() {
            t
        } else if t > 0.0 && duration.is_finite() {
            duration
        } else {
            0.0
        };
        let (t0, t1) = difference_window(t, duration, h);
        let rows = pose_at(t0, a)?.min(pose_at(t1, b)?);
        let at = if t1 == t { &*b } else { &*a };
        state.set(at, a, b, t1 - t0);
        Ok(rows)
    }

    /// Captures the outgoing clip at `t` seconds (of its `duration`): `displayed(t, out)` writes the
    /// pose the character shows at clip time `t` (the clip's pose with any running transition
    /// applied) and returns how many rows it wrote. With `motion` (a seam at the end of a cycle) the
    /// state is re-expressed in the next cycle frame ([`PoseState::into_next_frame`]); without (a
    /// change of detail mid-cycle) it stays in the current frame. A `t` that is not finite reads
    /// as 0 (NaN, -infinity) or `duration` (+infinity); at a `t` so large that single precision
    /// cannot step back from it, the velocity is zero.
    pub fn capture<E, F>(
        &mut self,
        t: f32,
        duration: f32,
        motion: Option<&RootMotion>,
        displayed: F,
    ) -> Result<(), E>
    where
        F: FnMut(f32, &mut [f32]) -> Result<usize, E>,
    {
        let h = SEAM_STEP_S;
        self.rows = Self::sample(
            &mut self.prev,
            &mut self.a,
            &mut self.b,
            t,
            duration,
            h,
            displayed,
        )?;
        if let Some(m) = motion {
            self.prev.into_next_frame(m);
        }
        Ok(())
    }

    /// Starts `transition` from the captured state to the incoming clip at its time `t` (of its
    /// `duration`; `pose_at(t, out)` writes the clip's own pose and returns the rows written). The
    /// transition then applies over the rows both clips hold, with its clock at 0 at `t`. A `t`
    /// that is not finite or very large is read as [`SeamScratch::capture`] reads it.
    pub fn start<E, F>(
        &mut self,
        t: f32,
        duration: f32,
        pose_at: F,
        transition: &mut SeamTransition,
    ) -> Result<(), E>
    where
        F: FnMut(f32, &mut [f32]) -> Result<usize, E>,
    {
        self.start_from_rest(t, duration, pose_at, &[], transition)
    }

    /// [`SeamScratch::start`] across a change of evaluated joints: `rest` holds the rows forward
    /// kinematics takes for joints a clip does not evaluate (their rest rotations; the root rows are
    /// not read). A joint the captured pose did not show but the incoming clip evaluates fades in
    /// from its rest rotation (what was drawn for it); a joint the captured pose showed but the
    /// incoming clip drops fades out to its rest rotation instead of snapping to it, and the
    /// transition then covers more rows than the clip writes: the caller completes each pose with
    /// [`SeamTransition::fill_beyond`] and draws those joints until the transition finishes. Each
    /// rest rotation is taken on the exponential-map branch nearest the other side's rows. With
    /// `rest` shorter than the larger side, only the rows both clips hold are blended.
    pub fn start_from_rest<E, F>(
        &mut self,
        t: f32,
        duration: f32,
        pose_at: F,
        rest: &[f32],
        transition: &mut SeamTransition,
    ) -> Result<(), E>
    where
        F: FnMut(f32, &mut [f32]) -> Result<usize, E>,
    {
        let h = SEAM_STEP_S;
        let rows = Self::sample(
            &mut self.next,
            &mut self.a,
            &mut self.b,
            t,
            duration,
            h,
            pose_at,
        )?;
        let (shown, incoming) = (self.rows, rows);
        let wide = shown.max(incoming).min(self.prev.pose.len());
        let rows = if rest.len() >= wide && shown.min(incoming) >= ALWAYS_ROWS {
            // The side that lacks rows [narrow, wide) takes the rest rotations there, still.
            let narrow = shown.min(incoming);
            let (lacking, other) = if shown < incoming {
                (&mut self.prev, &self.next)
            } else {
                (&mut self.next, &self.prev)
            };
            let mut r = narrow;
            while r + 3 <= wide {
                let v = nearest_branch(
                    Vec3::from_slice(&rest[r..r + 3]),
                    Vec3::from_slice(&other.pose[r..r + 3]),
                );
                lacking.pose[r..r + 3].copy_from_slice(&v.to_array());
                lacking.velocity[r..r + 3].fill(0.0);
                r += 3;
            }
            r
        } else {
            shown.min(incoming)
        };
        transition.start(&self.prev, &self.next, rows);
        Ok(())
    }
}

/// The exponential map of the same rotation as `v` on the branch nearest `reference`
/// (`v + 2 pi k v / |v|` for the integer `k` that brings it closest).
pub fn nearest_branch(v: Vec3, reference: Vec3) -> Vec3 {
    let angle = v.length();
    if angle < 1e-6 {
        return v;
    }
    let axis = v / angle;
    let tau = std::f32::consts::TAU;
    let k = ((axis.dot(reference) - angle) / tau).round();
    let w = axis * (angle + k * tau);
    if (w - reference).length() <= (v - reference).length() {
        w
    } else {
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offset_starts_at_the_difference_with_its_velocity_and_decays() {
        let p = 10;
        let mut prev = PoseState::new(p);
        let mut next = PoseState::new(p);
        prev.pose[8] = 0.3;
        prev.velocity[8] = 2.0;
        next.velocity[8] = -1.0;
        prev.pose[1] = 0.9;
        next.pose[1] = 1.0;
        let mut s = SeamTransition::new(p, 0.15);
        s.start(&prev, &next, p);
        let at = |t: f32, base: f32, vel: f32, row: usize| {
            let mut pose = vec![0.0; p];
            pose[row] = base + vel * t;
            s.apply(t, &mut pose);
            pose[row]
        };
        // Position continuous at the seam.
        assert!((at(0.0, 0.0, -1.0, 8) - 0.3).abs() < 1e-6);
        assert!((at(0.0, 1.0, 0.0, 1) - 0.9).abs() < 1e-6);
        // Velocity continuous: the displayed slope right after the seam is the previous clip's.
        let h = 1e-3;
        let slope = (at(h, 0.0, -1.0, 8) - at(0.0, 0.0, -1.0, 8)) / h;
        assert!((slope - 2.0).abs() < 0.05, "slope {slope}");
        // Decays: after ten half-lives the offset is gone.
        assert!((at(1.5, 0.0, -1.0, 8) - (-1.5)).abs() < 0.01);
        // The time row is never touched.
        let mut pose = vec![0.0; p];
        pose[TIME_ROW] = 0.5;
        s.apply(0.0, &mut pose);
        assert_eq!(pose[TIME_ROW], 0.5);
    }

    /// A seam that drops a joint fades it from its shown rotation to its rest rotation (taken on
    /// the branch near the shown one) over more rows than the incoming clip writes; a seam that adds
    /// one fades it in from its rest rotation, what was drawn for it.
    #[test]
    fn joints_dropped_or_added_at_a_seam_fade_to_and_from_rest() {
        let p = 13; // the root rows and two joints
        let mut rest = vec![0.0f32; p];
        rest[10..13].copy_from_slice(&[0.2, 0.0, 0.0]);
        // The shown clip moves joint 1 (rows 10-12) at 0.5 + t about x; near the branch of rest +
        // 2 pi, to check the branch is chosen near the shown rows.
        let tau = std::f32::consts::TAU;
        let wide = |t: f32, out: &mut [f32]| -> Result<usize, ()> {
            out[..p].fill(0.0);
            out[10] = 0.5 + t - tau;
            Ok(p)
        };
        let narrow = |_: f32, out: &mut [f32]| -> Result<usize, ()> {
            out[..10].fill(0.0);
            Ok(10)
        };
        let mut scratch = SeamScratch::new(p);
        let mut seam = SeamTransition::new(p, 0.15);
        // Dropped: 13 rows shown, 10 in the incoming clip.
        scratch.capture(0.5, 1.0, None, wide).unwrap();
        scratch
            .start_from_rest(0.0, 1.0, narrow, &rest, &mut seam)
            .unwrap();
        assert_eq!(seam.rows(), p);
        let shown = |seam: &SeamTransition, t: f32, written: usize| {
            let mut out = vec![f32::NAN; p];
            out[..written].fill(0.0);
            let rows = seam.fill_beyond(written, &mut out);
            seam.apply(t, &mut out[..rows]);
            (rows, out)
        };
        let (rows, at0) = shown(&seam, 0.0, 10);
        assert_eq!(rows, p);
        assert!(
            (at0[10] - (1.0 - tau)).abs() < 1e-5,
            "continuous: {}",
            at0[10]
        );
        let (_, late) = shown(&seam, 2.0, 10);
        assert!(
            (late[10] - (0.2 - tau)).abs() < 1e-3,
            "decays to rest: {}",
            late[10]
        );
        // Without rest rows the joint is not blended: only the rows both clips hold.
        scratch.capture(0.5, 1.0, None, wide).unwrap();
        scratch
            .start_from_rest(0.0, 1.0, narrow, &[], &mut seam)
            .unwrap();
        assert_eq!(seam.rows(), 10);
        // Added: 10 rows shown, 13 in the incoming clip; the new joint starts at rest.
        scratch.capture(0.5, 1.0, None, narrow).unwrap();
        scratch
            .start_from_rest(0.0, 1.0, wide, &rest, &mut seam)
            .unwrap();
        assert_eq!(seam.rows(), p);
        let mut out = vec![0.0f32; p];
        wide(0.0, &mut out).unwrap();
        assert_eq!(seam.fill_beyond(p, &mut out), p);
        seam.apply(0.0, &mut out);
        assert!(
            (out[10] - (0.2 - tau)).abs() < 1e-5,
            "fades in from rest: {}",
            out[10]
        );
    }

    #[test]
    fn root_rotation_offset_is_a_rotation_applied_on_the_left() {
        let p = 7;
        let mut prev = PoseState::new(p);
        let next = PoseState::new(p);
        // The previous clip ends rolled 11 degrees; the next starts level.
        let roll = exp_map_to_quat(Vec3::new(0.0, 0.0, 11f32.to_radians()));
        prev.pose[3..6].copy_from_slice(&quat_to_exp_map(roll).to_array());
        let mut s = SeamTransition::new(p, 0.15);
        s.start(&prev, &next, p);
        let mut pose = vec![0.0; p];
        s.apply(0.0, &mut pose);
        let q = exp_map_to_quat(Vec3::from_slice(&pose[3..6]));
        assert!(q.angle_between(roll) < 1e-5);
    }

    #[test]
    fn frames_far_from_the_origin_chain_as_near_it() {
        // An hour of 1.1 s cycles (3,300) walked 1 km from the origin lands where the same walk
        // from the origin does, moved by 1 km: single precision would round every cycle's step to
        // 61 um there.
        let m = RootMotion {
            dx: 0.013,
            dz: 0.71,
            turn: 0.0021,
        };
        let (mut near, mut far) = (
            CycleFrame::default(),
            CycleFrame {
                x: 1000.0,
                z: -1000.0,
                heading: 0.0,
            },
        );
        for _ in 0..3300 {
            near = near.next(&m);
            far = far.next(&m);
        }
        let (ex, ez) = ((far.x - 1000.0) - near.x, (far.z + 1000.0) - near.z);
        assert!(ex.abs() < 1e-9 && ez.abs() < 1e-9, "{ex} {ez}");
        assert_eq!(far.heading, near.heading);
        // The placed point is in double precision: 1 mm in the frame is 1 mm in the world.
        let p = far.to_world(Vec3::new(0.001, 0.0, 0.0)) - far.to_world(Vec3::ZERO);
        assert!((p.length() - 0.001).abs() < 1e-9, "{p}");
    }

    #[test]
    fn frames_chain_by_the_root_motion() {
        let f = CycleFrame::default();
        let m = RootMotion {
            dx: 0.0,
            dz: 1.0,
            turn: std::f32::consts::FRAC_PI_2,
        };
        let g = f.next(&m).next(&m);
        assert!(
            (g.z - 1.0).abs() < 1e-6 && (g.x - 1.0).abs() < 1e-6,
            "{g:?}"
        );
        assert!(wrap_angle_f64(g.heading - std::f64::consts::PI).abs() < 1e-6);
        // A state at the end of the clip is at the origin of the next frame.
        let mut s = PoseState::new(7);
        s.pose[0..3].copy_from_slice(&[0.0, 0.9, 1.0]);
        s.velocity[2] = 1.0;
        s.into_next_frame(&m);
        assert!(Vec3::from_slice(&s.pose[0..3]).distance(Vec3::new(0.0, 0.9, 0.0)) < 1e-6);
        // Forward velocity in the old frame is sideways (to the right, -x) in the turned one.
        assert!(
            (s.velocity[0] + 1.0).abs() < 1e-6,
            "{:?}",
            &s.velocity[0..3]
        );
    }
}
