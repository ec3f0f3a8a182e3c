//! Planted feet at run time: [`FootLock`], a causal foot lock over the poses a character shows, frame
//! by frame, in f32, without allocation.
//!
//! A synthesized walk slides its stance foot a little (the root's path and the leg rotations are
//! interpolated separately); coarse levels slide more. The offline walk writer (`motion_lod::footlock`)
//! sees the whole walk and centres each contact; a character in an engine or a crowd only knows the
//! frames shown so far. Per foot, each frame:
//!
//! 1. **Pivot and contact.** The pivot is the lower of the foot's points (ankle, and toe when the rig
//!    has one), placed in the world by the cycle frame. The foot is in contact while the pivot is
//!    within [`LOCK_HEIGHT_M`] of the floor ([`FootRig::floor_m`]) and its horizontal speed since
//!    the previous frame is below [`LOCK_SPEED_M_S`].
//! 2. **Correction.** In contact, the horizontal motion of the pivot is cancelled:
//!    `d(f) = d(f - 1) - (x_j(f) - x_j(f - 1))_xz` (world frame; `j` the pivot of frame `f`, which
//!    may pass from heel to toe), and a stance above the floor is lowered onto it,
//!    `d_y(f) = d_y(f - 1) + w (-max(0, h_low(f)) - d_y(f - 1))` (`h_low` the lowest pivot height
//!    above the floor since the contact started: the foot keeps its own rise and roll within the
//!    stance), as the offline lock puts each stance's lowest point on the floor. Both corrections
//!    are weighted by `w`, which eases from 0 to 1 over [`ONSET_S`] from the contact's start.
//!    Contact starts from the correction held (0 after a full release),
//!    so the foot never jumps. Out of contact the correction held at lift-off eases to zero over
//!    [`RELEASE_S`] (`e(1 - r / RELEASE_S)` with the ease curve [`crate::ease_in_out`], `r` the
//!    time since lift-off), while the foot is in the air.
//!    **Clearance**: once a foot has risen above the lock height after lift-off, it is in the air
//!    until its next contact; while in the air a pivot lower than [`LOCK_HEIGHT_M`] above the floor
//!    (a swing toe scuffing the floor) is lifted to that height, `l(f) = max(0, floor + h - y_j(f))`,
//!    which is continuous since it starts at 0; at touchdown the lift held eases out like the
//!    horizontal correction.
//!    **Ground**: out of the air (in contact, or low and not yet risen), a pivot that sinks below
//!    the floor is raised onto it: its height `h` (with the correction held) is shown as
//!    `grounded(h)`, which is `h` from [`GROUND_MARGIN_M`] up, 0 from the margin below the floor
//!    down and a quadratic between (continuous slope, the clearance's rounding at a lower level),
//!    so the synthesized stance foot that sinks a centimetre or two (interpolated leg rotations)
//!    stands on the floor; the lift is the larger of this one and the landing's easing one.
//! 3. **Two-bone IK.** The ankle is moved by the correction with the hip fixed ([`two_bone`]): the
//!    knee stays in the leg's current bend plane, thigh and shin keep their lengths, and the foot keeps
//!    its world orientation (its points move with the ankle). Beyond [`SOFT_REACH`] of the leg's length
//!    the reach eases toward full length ([`soft_reach`]), so the knee never snaps straight. The new
//!    rotations of the thigh, knee and ankle joints are written back into the pose rows, so forward
//!    kinematics, local rotations for skinning and the C ABI all see the planted foot.
//!
//! A leg whose three joints are not all evaluated at the pose's detail (fewer active joints) is not
//! locked, and its correction is released. [`FootLock::release`] forgets the anchors (a teleport).

use glam::{DVec2, DVec3, Quat, Vec3};
use serde::{Deserialize, Serialize};

use crate::chain::{CycleFrame, nearest_branch, quat_to_exp_map};
use crate::math::ease_in_out;
use crate::model::{ALWAYS_ROWS, ROWS_PER_JOINT};
use crate::rig::{JointRole, JointTransform, Rig, STACK_JOINTS};

/// A foot point counts as planted within this height above the floor (m): the motion-quality meter's
/// 2 cm contact height and a margin.
pub const LOCK_HEIGHT_M: f32 = 0.03;
/// A foot point counts as planted below this horizontal speed (m/s); a swing foot passes faster.
pub const LOCK_SPEED_M_S: f32 = 0.8;
/// The correction held at lift-off decays to zero over this time (s).
pub const RELEASE_S: f32 = 0.3;
/// At the start of a contact the lock's hold on the foot grows from none to full over this time
/// (s), so the foot slows down instead of stopping dead.
pub const ONSET_S: f32 = 0.1;
/// Share of the leg's length (thigh plus shin) beyond which the IK reach is softened.
pub const SOFT_REACH: f32 = 0.97;
/// The IK never straightens the leg beyond this share of its length.
pub const MAX_REACH: f32 = 0.9999;
/// Weight of the pole (the character's forward, in thigh lengths) in the IK's bend plane
/// ([`two_bone`]): small against the offset of a bent knee, decisive for a straight leg.
pub const POLE_WEIGHT: f32 = 0.1;
/// Half-width of the soft floor of [`FootLock`]'s ground correction (m): a pivot from this far below
/// the floor down is shown on it, one from this far above it up as it is.
pub const GROUND_MARGIN_M: f32 = 0.005;
/// A pivot moving faster than this between two frames (m/s) has been moved, not walked: the lock
/// forgets its anchor.
pub const TELEPORT_SPEED_M_S: f32 = 20.0;

/// One foot of a rig: the ankle joint (whose parent is the knee, whose parent is the thigh) and the
/// toe joint below it when the skeleton has one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Foot {
    /// Rig index of the ankle joint.
    pub ankle: usize,
    /// Rig index of the toe joint, below the ankle.
    pub toe: Option<usize>,
}

/// The feet of a rig and the data's floor: what a foot lock needs beyond the [`Rig`]. Stored in the
/// model file (format 6) when the build found the feet.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FootRig {
    /// Left foot.
    pub left: Foot,
    /// Right foot.
    pub right: Foot,
    /// Height of the data's floor in the cycle frame (m), as the motion-quality meter measures it on
    /// the training takes.
    pub floor_m: f32,
}

/// One leg as the lock drives it: rig indices of thigh, knee, ankle, and the foot's points.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Leg {
    thigh: usize,
    knee: usize,
    ankle: usize,
    toe: Option<usize>,
}

impl FootRig {
    /// Checks the feet against `rig`: the ankle's parent (knee) and grandparent (thigh) exist, the
    /// three rotate, and the toe is below the ankle; the floor is finite. The message names the joint.
    pub fn check(&self, rig: &Rig) -> Result<(), String> {
        self.legs(rig).map(|_| ())
    }

    /// The two legs (left, right) of `rig`, checked as [`FootRig::check`] says.
    fn legs(&self, rig: &Rig) -> Result<[Leg; 2], String> {
        if !self.floor_m.is_finite() {
            return Err(format!(
                "feet: the floor height {} is not finite",
                self.floor_m
            ));
        }
        Ok([
            leg(rig, &self.left).map_err(|e| format!("left foot: {e}"))?,
            leg(rig, &self.right).map_err(|e| format!("right foot: {e}"))?,
        ])
    }
}

fn leg(rig: &Rig, foot: &Foot) -> Result<Leg, String> {
    let joints = rig.joints();
    let name = |j: usize| joints.get(j).map_or("?", |x| x.name.as_str());
    let ankle = foot.ankle;
    if ankle >= joints.len() {
        return Err(format!(
            "ankle joint {ankle} of a rig of {} joints",
            joints.len()
        ));
    }
    let knee = joints[ankle]
        .parent
        .ok_or_else(|| format!("ankle {} has no parent (knee)", name(ankle)))?;
    let thigh = joints[knee]
        .parent
        .ok_or_else(|| format!("knee {} has no parent (thigh)", name(knee)))?;
    for j in [thigh, knee, ankle] {
        if !matches!(joints[j].role, JointRole::Rotating(_)) {
            return Err(format!(
                "joint {j} ({}) of the leg does not rotate",
                name(j)
            ));
        }
    }
    if let Some(toe) = foot.toe {
        let mut up = joints.get(toe).and_then(|t| t.parent);
        while let Some(p) = up {
            if p == ankle {
                break;
            }
            up = joints[p].parent;
        }
        if up != Some(ankle) {
            return Err(format!(
                "toe joint {toe} is not below the ankle {}",
                name(ankle)
            ));
        }
    }
    Ok(Leg {
        thigh,
        knee,
        ankle,
        toe: foot.toe,
    })
}

/// Whether rotating joint `j` of `rig` is evaluated with `active` active joints.
fn evaluated(rig: &Rig, j: usize, active: usize) -> bool {
    matches!(rig.joints()[j].role, JointRole::Rotating(k) if k < active)
}

/// The lock state of one foot (module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct FootState {
    /// The previous frame's uncorrected foot points on the ground (world `(x, z)` of ankle and
    /// toe), once seen, in double precision: a foot's motion over one frame is their difference,
    /// millimetres however far from the origin the walker is.
    prev: Option<[DVec2; 2]>,
    /// In contact at the previous frame.
    planted: bool,
    /// Seconds since the contact started.
    since_contact: f32,
    /// Lowest pivot height above the floor since the contact started (m).
    contact_low: f32,
    /// The correction shown at the previous frame (world): the cancelled horizontal drift and the
    /// stance's lowering onto the floor (`y`), without the lift.
    offset: Vec3,
    /// Its rate of change at the previous frame (m/s).
    velocity: Vec3,
    /// Correction and rate at lift-off, released from there.
    lift_off: (Vec3, Vec3),
    /// Seconds since lift-off.
    since_lift: f32,
    /// Risen above the lock height since the last contact.
    airborne: bool,
    /// The clearance lift shown at the previous frame (m).
    lift: f32,
    /// The lift at touchdown, easing out.
    landing_lift: f32,
    /// Seconds since touchdown.
    since_landing: f32,
}

/// The horizontal correction `t` seconds after lift-off from `x0` changing at `v0`: a critically
/// damped decay `(x0 + (v0 + g x0) t) e^(-g t)`, `g = 2 ln 2 / (RELEASE_S / 4)`, windowed by
/// `e(1 - t / RELEASE_S)`: continuous in position and velocity at lift-off, zero from `RELEASE_S`.
fn released(x0: Vec3, v0: Vec3, t: f32) -> Vec3 {
    if t >= RELEASE_S {
        return Vec3::ZERO;
    }
    let g = 2.0 * std::f32::consts::LN_2 / (0.25 * RELEASE_S);
    (x0 + (v0 + g * x0) * t) * (-g * t).exp() * ease_in_out(1.0 - t / RELEASE_S)
}

/// `max(h, level)` with the corner rounded over `level +- m`: `h` from `level + m` up, `level` from
/// `level - m` down and `level + (h - level + m)^2 / (4 m)` between. Never below `h` nor below
/// `level`, with a continuous slope, so a pivot pushed up to `level` moves without a kink.
fn soft_max(h: f32, level: f32, m: f32) -> f32 {
    if h >= level + m {
        h
    } else if h <= level - m {
        level
    } else {
        let u = h - level + m;
        level + u * u / (4.0 * m)
    }
}

/// The pivot height shown in the air for an uncorrected height `h` above the floor: at least the
/// lock height, rounded over half of it (`soft_max(h, LOCK_HEIGHT_M, LOCK_HEIGHT_M / 2)`), so a
/// swing foot is lifted without a kink.
fn cleared(h: f32) -> f32 {
    soft_max(h, LOCK_HEIGHT_M, 0.5 * LOCK_HEIGHT_M)
}

/// The pivot height shown on the ground for an uncorrected height `h` above the floor: never below
/// the floor, rounded over [`GROUND_MARGIN_M`] (`soft_max(h, 0, GROUND_MARGIN_M)`), so a sinking
/// stance foot is raised without a kink.
fn grounded(h: f32) -> f32 {
    soft_max(h, 0.0, GROUND_MARGIN_M)
}

impl FootState {
    /// Advances the state by one frame with the foot's uncorrected world points; returns the world
    /// correction to show.
    fn step(&mut self, points: [DVec3; 2], floor: f32, dt: f32) -> Vec3 {
        let pivot = usize::from(points[1].y < points[0].y);
        let ground = points.map(|p| DVec2::new(p.x, p.z));
        let moved = self.prev.map(|prev| {
            let m = ground[pivot] - prev[pivot];
            Vec3::new(m.x as f32, 0.0, m.y as f32)
        });
        self.prev = Some(ground);
        let speed = moved.map(|m| m.length() / dt);
        if speed.is_some_and(|s| s.is_nan() || s >= TELEPORT_SPEED_M_S) {
            *self = FootState {
                prev: Some(ground),
                ..FootState::default()
            };
            return Vec3::ZERO;
        }
        let height = points[pivot].y as f32 - floor;
        let contact = height < LOCK_HEIGHT_M && speed.is_some_and(|s| s < LOCK_SPEED_M_S);
        let before = self.offset;
        if contact {
            if !self.planted {
                self.planted = true;
                self.since_contact = 0.0;
                self.contact_low = height;
            }
            self.since_contact += dt;
            self.contact_low = self.contact_low.min(height);
            let w = ease_in_out((self.since_contact / ONSET_S).min(1.0));
            self.offset -= w * moved.unwrap_or(Vec3::ZERO);
            // Down onto the floor: a stance whose lowest point so far is above it is lowered by
            // that much, with the same onset.
            self.offset.y += w * (-self.contact_low.max(0.0) - self.offset.y);
        } else {
            self.release(dt);
        }
        self.velocity = (self.offset - before) / dt;
        self.clear(height, height + self.offset.y, contact, dt);
        self.offset + Vec3::new(0.0, self.lift, 0.0)
    }

    /// Out of contact: the correction (horizontal drift and lowering) released from lift-off.
    fn release(&mut self, dt: f32) {
        if self.planted {
            self.planted = false;
            self.lift_off = (self.offset, self.velocity);
            self.since_lift = 0.0;
        }
        self.since_lift += dt;
        self.offset = released(self.lift_off.0, self.lift_off.1, self.since_lift);
    }

    /// The vertical lift for a pivot `height` above the floor, `shown` with the correction held
    /// (module documentation, step 2): the clearance lift in the air, on the ground the larger of
    /// the landing's easing lift and the ground correction, both of the height shown.
    fn clear(&mut self, height: f32, shown: f32, contact: bool, dt: f32) {
        if contact {
            self.land();
        } else if height >= LOCK_HEIGHT_M {
            self.airborne = true;
        }
        if self.airborne {
            self.lift = cleared(shown) - shown;
        } else {
            self.ease_lift(dt);
            self.lift = self.lift.max(grounded(shown) - shown);
        }
    }

    /// Ends a flight: the lift held eases out from here.
    fn land(&mut self) {
        if self.airborne {
            self.airborne = false;
            self.landing_lift = self.lift;
            self.since_landing = 0.0;
        }
    }

    /// The lift held at touchdown easing out.
    fn ease_lift(&mut self, dt: f32) {
        self.since_landing += dt;
        self.lift = if self.since_landing >= RELEASE_S {
            0.0
        } else {
            self.landing_lift * ease_in_out(1.0 - self.since_landing / RELEASE_S)
        };
    }

    /// Lets go of the foot (its leg is not evaluated): both corrections ease out from where they are.
    fn let_go(&mut self, dt: f32) -> Vec3 {
        self.prev = None;
        self.land();
        self.ease_lift(dt);
        let before = self.offset;
        self.release(dt);
        self.velocity = (self.offset - before) / dt;
        self.offset + Vec3::new(0.0, self.lift, 0.0)
    }
}

/// Why [`FootLock::apply`] refused its inputs.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FootLockError {
    /// The frame step is not a positive finite number of seconds.
    #[error("foot lock: the frame step {0} s is not positive and finite")]
    FrameStep(f32),
    /// The feet do not fit the rig.
    #[error("foot lock: {0}")]
    Feet(String),
    /// The pose or the rig (forward kinematics) refused.
    #[error("foot lock: {0}")]
    Rig(#[from] crate::error::RigError),
}

/// A character's foot lock state (module documentation): at most 256 bytes, no heap.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FootLock {
    feet: [FootState; 2],
}

impl FootLock {
    /// A lock holding no foot.
    pub fn new() -> FootLock {
        FootLock::default()
    }

    /// Forgets both feet at once (the character was moved): no correction from the next frame on.
    pub fn release(&mut self) {
        *self = FootLock::default();
    }

    /// Whether either foot is planted or still easing out of a correction.
    pub fn is_active(&self) -> bool {
        self.feet
            .iter()
            .any(|f| f.planted || f.offset != Vec3::ZERO || f.lift != 0.0)
    }

    /// Plants the feet of `pose`, the pose shown this frame (the rows of `active_joints` rotating
    /// joints; cycle frame `frame`; a body `scale` times the rig's size, as
    /// [`Rig::joint_positions_scaled`] draws it, 1 for the rig's own), `dt` seconds after the
    /// previous call, and writes the corrected rotations of each locked leg's thigh, knee and ankle
    /// into `pose` (module documentation).
    ///
    /// Validates and then runs: a non-positive `dt`, a body scale that is not finite and positive,
    /// feet that do not fit the rig, a pose shorter than its active rows or with a row among them
    /// that is not finite (or beyond [`crate::MAX_POSE_VALUE`]) is an error and changes nothing. No allocation for rigs of up to 128 joints (`STACK_JOINTS`).
    #[allow(clippy::too_many_arguments)]
    pub fn apply(
        &mut self,
        rig: &Rig,
        feet: &FootRig,
        frame: &CycleFrame,
        active_joints: usize,
        scale: f32,
        dt: f32,
        pose: &mut [f32],
    ) -> Result<(), FootLockError> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(FootLockError::FrameStep(dt));
        }
        let legs = feet.legs(rig).map_err(FootLockError::Feet)?;
        // (Forward kinematics checks the pose too; a detail that evaluates no leg skips it.)
        rig.check_pose(pose, active_joints)?;
        let active = active_joints.min(rig.rotating_joints().len());
        let leg_evaluated = |leg: &Leg| {
            [leg.thigh, leg.knee, leg.ankle]
                .iter()
                .all(|&j| evaluated(rig, j, active))
        };
        if !legs.iter().any(leg_evaluated) {
            // No leg is evaluated (a root-only or arms-only detail): every foot lets go, and no
            // forward kinematics is needed (the loop below would do the same, after it).
            for (state, _) in self.feet.iter_mut().zip(&legs) {
                state.let_go(dt);
            }
            return Ok(());
        }
        let nj = rig.joint_count();
        let mut stack = [JointTransform::default(); STACK_JOINTS];
        let mut heap = Vec::new();
        let world: &mut [JointTransform] = if nj <= STACK_JOINTS {
            &mut stack[..nj]
        } else {
            heap.resize(nj, JointTransform::default());
            &mut heap
        };
        // Forward kinematics of the legs' chains only (the feet's points and their ancestors).
        let mut stack_needed = [false; STACK_JOINTS];
        let mut heap_needed = Vec::new();
        let needed: &mut [bool] = if nj <= STACK_JOINTS {
            &mut stack_needed[..nj]
        } else {
            heap_needed.resize(nj, false);
            &mut heap_needed
        };
        for leg in &legs {
            for start in [Some(leg.ankle), leg.toe].into_iter().flatten() {
                let mut j = Some(start);
                while let Some(k) = j.filter(|&k| !needed[k]) {
                    needed[k] = true;
                    j = rig.joints()[k].parent;
                }
            }
        }
        rig.joint_transforms_of(pose, active_joints, scale, needed, world)?;
        let to_frame = frame.rotation().inverse();
        for (state, leg) in self.feet.iter_mut().zip(legs) {
            if !leg_evaluated(&leg) {
                state.let_go(dt);
                continue;
            }
            let ankle = world[leg.ankle].position;
            let toe = leg.toe.map_or(ankle, |t| world[t].position);
            let points = [frame.to_world(ankle), frame.to_world(toe)];
            let d = to_frame * state.step(points, feet.floor_m, dt);
            if d.length_squared() < 1e-12 {
                continue;
            }
            bend_leg(rig, &leg, world, d, pose);
        }
        Ok(())
    }
}

/// Moves the ankle of `leg` by `d` (cycle frame) with the thigh's position fixed and the foot's world
/// orientation kept, and writes the three new local rotations into `pose`.
fn bend_leg(rig: &Rig, leg: &Leg, world: &[JointTransform], d: Vec3, pose: &mut [f32]) {
    let (thigh, knee, ankle) = (world[leg.thigh], world[leg.knee], world[leg.ankle]);
    let parent_rot = rig.joints()[leg.thigh]
        .parent
        .map_or(Quat::IDENTITY, |p| world[p].rotation);
    // The character's forward direction (its root's heading in the cycle frame): where a knee
    // points when the leg is nearly straight.
    let root = world[rig.root()].rotation * Vec3::Z;
    let pole = Vec3::new(root.x, 0.0, root.z).normalize_or(Vec3::Z);
    let (r_thigh, r_knee) = two_bone(
        thigh.position,
        knee.position,
        ankle.position,
        ankle.position + d,
        pole,
    );
    let thigh_rot = (r_thigh * thigh.rotation).normalize();
    let knee_rot = (r_knee * r_thigh * knee.rotation).normalize();
    let locals = [
        (leg.thigh, parent_rot.inverse() * thigh_rot),
        (leg.knee, thigh_rot.inverse() * knee_rot),
        (leg.ankle, knee_rot.inverse() * ankle.rotation),
    ];
    for (j, q) in locals {
        if let JointRole::Rotating(k) = rig.joints()[j].role {
            let r = ALWAYS_ROWS + ROWS_PER_JOINT * k;
            let old = Vec3::new(pose[r], pose[r + 1], pose[r + 2]);
            let v = nearest_branch(quat_to_exp_map(q.normalize()), old);
            pose[r..r + 3].copy_from_slice(&v.to_array());
        }
    }
}

/// The reach the IK uses for a target `reach` away from the hip with a leg of length `len` whose
/// ankle is `current` away from the hip now: itself up to `d_s = max(SOFT_REACH len, current)`, then
/// `d_s + (len - d_s)(1 - exp(-(reach - d_s) / (len - d_s)))` (continuous slope at `d_s`), at most
/// `max(MAX_REACH len, current)`. The current reach is kept as it is, so a correction of zero leaves
/// the leg unchanged even when the data straighten it beyond [`SOFT_REACH`] (a heel strike), and a
/// growing correction bends it continuously.
pub fn soft_reach(reach: f32, current: f32, len: f32) -> f32 {
    let start = (SOFT_REACH * len).max(current);
    if reach <= start {
        return reach;
    }
    let span = len - start;
    if span <= 0.0 {
        return start;
    }
    (start + span * (1.0 - (-(reach - start) / span).exp())).min((MAX_REACH * len).max(current))
}

/// Two-bone IK with the hip fixed: the world rotations to apply to the thigh (`r_thigh`, about the
/// hip) and then to the shin (`r_knee`, about the moved knee) so that the ankle reaches `target`
/// (at the [`soft_reach`]), the knee staying on the side it bends to now.
///
/// The bend plane holds the hip-target line and the knee's offset from it, plus [`POLE_WEIGHT`]
/// times the thigh's length along `pole` (a unit direction, the character's forward): a bent knee
/// keeps its side, and a nearly straight leg, whose knee offset says little about its side, bends
/// toward the pole instead of flipping around the line from one frame to the next.
pub fn two_bone(hip: Vec3, knee: Vec3, ankle: Vec3, target: Vec3, pole: Vec3) -> (Quat, Quat) {
    let (l1, l2) = ((knee - hip).length(), (ankle - knee).length());
    let to_target = target - hip;
    let reach = to_target.length();
    if l1 < 1e-5 || l2 < 1e-5 || reach < 1e-5 {
        return (Quat::IDENTITY, Quat::IDENTITY);
    }
    let d = soft_reach(reach, (ankle - hip).length(), l1 + l2).max((l1 - l2).abs() + 1e-4);
    let u = to_target / reach;
    // The bend direction: the current knee's offset from the hip-target line, leaning toward the
    // pole (decisive only when the leg is nearly straight).
    let kh = knee - hip;
    let side = kh + POLE_WEIGHT * l1 * pole;
    let mut w = side - side.dot(u) * u;
    if w.length_squared() < 1e-10 {
        w = (ankle - hip).cross(Vec3::Y).cross(u);
    }
    let w = w.normalize_or_zero();
    let cos_a = ((l1 * l1 + d * d - l2 * l2) / (2.0 * l1 * d)).clamp(-1.0, 1.0);
    let new_knee = hip + l1 * (cos_a * u + (1.0 - cos_a * cos_a).max(0.0).sqrt() * w);
    let r_thigh = Quat::from_rotation_arc(kh / l1, (new_knee - hip) / l1);
    let shin = r_thigh * (ankle - knee);
    let goal = hip + d * u - new_knee;
    let r_knee = Quat::from_rotation_arc(shin.normalize(), goal.normalize());
    (r_thigh, r_knee)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::RigError;
    use crate::rig::RigJoint;

    fn joint(name: &str, parent: Option<usize>, offset: [f32; 3], role: JointRole) -> RigJoint {
        RigJoint {
            name: name.into(),
            parent,
            offset: Vec3::from_array(offset),
            rest: Quat::IDENTITY,
            role,
        }
    }

    /// Hips (root, 0.9 m up) with two legs: thigh, knee (0.42 m down), ankle (0.42 m down), toe.
    fn legs() -> (Rig, FootRig) {
        let mut joints = vec![joint("hips", None, [0.0; 3], JointRole::Root)];
        for (k, x) in [0.1f32, -0.1].into_iter().enumerate() {
            let base = joints.len();
            joints.push(joint(
                "thigh",
                Some(0),
                [x, 0.0, 0.0],
                JointRole::Rotating(3 * k),
            ));
            joints.push(joint(
                "knee",
                Some(base),
                [0.0, -0.42, 0.0],
                JointRole::Rotating(3 * k + 1),
            ));
            joints.push(joint(
                "ankle",
                Some(base + 1),
                [0.0, -0.42, 0.0],
                JointRole::Rotating(3 * k + 2),
            ));
            joints.push(joint(
                "toe",
                Some(base + 2),
                [0.0, -0.04, 0.12],
                JointRole::Static,
            ));
        }
        let rig = Rig::new(joints).unwrap();
        let feet = FootRig {
            left: Foot {
                ankle: 3,
                toe: Some(4),
            },
            right: Foot {
                ankle: 7,
                toe: Some(8),
            },
            floor_m: 0.0,
        };
        (rig, feet)
    }

    /// A pose of [`legs`] with the root at `(0, hip_y, z)` and both legs bent the same way: thighs
    /// forward 0.3 rad, knees back 0.6, ankles forward 0.3 (feet flat), so the ankles are 0.8025 m
    /// below the hips and the toes 0.04 m below the ankles.
    fn bent_legs(rig: &Rig, hip_y: f32, z: f32) -> Vec<f32> {
        let mut pose = vec![0.0f32; rig.dof()];
        pose[..3].copy_from_slice(&[0.0, hip_y, z]);
        for leg in [7, 16] {
            pose[leg] = 0.3;
            pose[leg + 3] = -0.6;
            pose[leg + 6] = 0.3;
        }
        pose
    }

    fn positions(rig: &Rig, pose: &[f32]) -> Vec<Vec3> {
        let mut out = vec![Vec3::ZERO; rig.joint_count()];
        rig.joint_positions(pose, 6, &mut out).unwrap();
        out
    }

    #[test]
    fn two_bone_reaches_the_target_and_keeps_lengths() {
        let hip = Vec3::new(0.1, 0.9, 0.0);
        let knee = Vec3::new(0.1, 0.5, 0.05);
        let ankle = Vec3::new(0.1, 0.1, 0.0);
        let target = ankle + Vec3::new(0.0, 0.05, -0.08);
        let (r_hip, r_knee) = two_bone(hip, knee, ankle, target, Vec3::Z);
        let new_knee = hip + r_hip * (knee - hip);
        let new_ankle = new_knee + r_knee * (r_hip * (ankle - knee));
        assert!(new_ankle.distance(target) < 1e-5, "{new_ankle}");
        assert!(((new_knee - hip).length() - (knee - hip).length()).abs() < 1e-5);
        assert!(new_knee.z > hip.z.min(target.z));
    }

    /// A nearly straight leg whose knee sits a millimetre behind or ahead of the hip-ankle line
    /// bends forward (toward the pole) either way: the knee does not flip sides between frames.
    /// A clearly bent knee keeps its side even against the pole.
    #[test]
    fn a_straight_leg_bends_toward_the_pole() {
        let (hip, ankle) = (Vec3::new(0.1, 0.9, 0.0), Vec3::new(0.1, 0.1, 0.0));
        let target = ankle + Vec3::new(0.0, 0.1, 0.0);
        for (z, forward) in [(0.001, true), (-0.001, true), (-0.08, false)] {
            let knee = Vec3::new(0.1, 0.5, z);
            let (r_hip, _) = two_bone(hip, knee, ankle, target, Vec3::Z);
            let new_knee = hip + r_hip * (knee - hip);
            assert_eq!(
                new_knee.z > 0.0,
                forward,
                "knee at z {z}: moved to {new_knee}"
            );
        }
    }

    #[test]
    fn soft_reach_is_continuous_and_short_of_full_length() {
        let len = 0.9;
        let mut prev = (0.0f32, 1.0f32);
        for i in 1..=2000 {
            let r = i as f32 * 0.001;
            let s = soft_reach(r, 0.5, len);
            assert!(s < len && s <= r + 1e-6, "{r}: {s}");
            let slope = (s - prev.0) / 0.001;
            assert!(
                slope >= -1e-3 && (i <= 2 || (slope - prev.1).abs() < 0.06),
                "{r}: {slope}"
            );
            prev = (s, slope);
        }
        // No correction, no change, even for a leg the data straighten beyond the soft start.
        let straight = 0.995 * len;
        assert_eq!(soft_reach(straight, straight, len), straight);
        let further = soft_reach(straight + 0.01, straight, len);
        assert!(further > straight && further < len, "{further}");
    }

    /// A stance foot sliding 0.5 cm per frame at 30 fps (below the lock speed) on the floor stays
    /// where it landed; once it lifts, the correction eases out within RELEASE_S.
    #[test]
    fn a_sliding_stance_foot_stays_where_it_landed_and_lets_go_smoothly() {
        let (rig, feet) = legs();
        let dt = 1.0 / 30.0;
        let mut lock = FootLock::new();
        let frame = CycleFrame::default();
        // Hips at 0.83 m put the toes 1.25 cm under the floor (raised onto it by the ground
        // correction), the ankles 2.75 cm above it. The walk slides 0.5 cm per frame (0.15 m/s).
        let pose_at = |f: usize| {
            let mut pose = bent_legs(&rig, 0.83, 0.005 * f as f32);
            if f >= 20 {
                pose[1] += 0.05 * (f - 19) as f32;
            }
            pose
        };
        let mut anchor = None;
        let mut prev_toe: Option<Vec3> = None;
        for f in 0..40 {
            let mut pose = pose_at(f);
            lock.apply(&rig, &feet, &frame, 6, 1.0, dt, &mut pose)
                .unwrap();
            let p = positions(&rig, &pose);
            let toe = p[4];
            if (1..20).contains(&f) {
                let a = *anchor.get_or_insert(p[4]);
                assert!(toe.distance(a) < 2e-3, "frame {f}: toe {toe} left {a}");
            }
            if f >= 20 + (RELEASE_S / dt).ceil() as usize {
                let free = positions(&rig, &pose_at(f))[4];
                assert!(toe.distance(free) < 1e-5, "frame {f}: still corrected");
            }
            if let Some(q) = prev_toe {
                // No jump: the toe never moves more than the walk's 0.5 cm, the lift's 5 cm and
                // the release's largest step (9.5 cm eased over 6 frames: under 3 cm) together.
                assert!(
                    toe.distance(q) < 0.09,
                    "frame {f}: toe jumps {}",
                    toe.distance(q)
                );
            }
            prev_toe = Some(toe);
        }
        assert!(!lock.is_active());
    }

    #[test]
    fn grounded_height_is_continuous_with_its_slope_and_never_below_the_floor() {
        let m = GROUND_MARGIN_M;
        assert_eq!(grounded(m), m);
        assert_eq!(grounded(0.2), 0.2);
        assert_eq!(grounded(-m), 0.0);
        assert_eq!(grounded(-0.02), 0.0);
        let step = 1e-4f32;
        let mut prev: Option<(f32, f32)> = None;
        for i in -300..=300 {
            let h = i as f32 * step;
            let g = grounded(h);
            assert!(g >= 0.0 && g >= h - 1e-7, "{h}: {g}");
            if let Some((pg, ps)) = prev {
                let slope = (g - pg) / step;
                assert!((0.0..=1.0 + 1e-3).contains(&slope), "{h}: slope {slope}");
                assert!(
                    (slope - ps).abs() < 0.05,
                    "{h}: slope jumps {ps} -> {slope}"
                );
                prev = Some((g, slope));
            } else {
                prev = Some((g, 0.0));
            }
        }
    }

    /// A stance foot that sinks (the walk lowers the hips from 0.845 m to 0.82 m over 15 frames, the
    /// toes from 0.25 cm above the floor to 2.25 cm under it) is shown on the floor, within the soft
    /// margin, and its toe never jumps: the ground correction grows with the sink.
    #[test]
    fn a_sinking_stance_foot_stands_on_the_floor() {
        let (rig, feet) = legs();
        let dt = 1.0 / 30.0;
        let mut lock = FootLock::new();
        let frame = CycleFrame::default();
        let pose_at = |f: usize| {
            let sink = 0.025 * (f.min(15) as f32 / 15.0);
            bent_legs(&rig, 0.845 - sink, 0.002 * f as f32)
        };
        let mut prev_toe: Option<Vec3> = None;
        let mut lowest_free = f32::MAX;
        for f in 0..30 {
            let mut pose = pose_at(f);
            lock.apply(&rig, &feet, &frame, 6, 1.0, dt, &mut pose)
                .unwrap();
            let (shown, free) = (positions(&rig, &pose), positions(&rig, &pose_at(f)));
            lowest_free = lowest_free.min(free[4].y);
            for toe in [3 + 1, 7 + 1] {
                let y = shown[toe].y;
                assert!(
                    (-1e-4..=GROUND_MARGIN_M).contains(&y),
                    "frame {f}: toe {toe} shown at {y} (free {})",
                    free[toe].y
                );
            }
            if let Some(q) = prev_toe {
                // The walk moves 2 mm a frame and sinks under 2 mm a frame: the correction adds
                // no jump of its own.
                assert!(
                    shown[4].distance(q) < 4e-3,
                    "frame {f}: toe jumps {}",
                    shown[4].distance(q)
                );
            }
            prev_toe = Some(shown[4]);
        }
        assert!(lowest_free < -0.02, "the free toe sinks to {lowest_free}");
    }

    /// A stance foot that floats 1.5 cm above the floor (hips at 0.8575 m) is lowered onto it once
    /// the onset has passed, without a jump, and lets go of the floor when it lifts.
    #[test]
    fn a_floating_stance_foot_is_lowered_onto_the_floor() {
        let (rig, feet) = legs();
        let dt = 1.0 / 30.0;
        let mut lock = FootLock::new();
        let frame = CycleFrame::default();
        let pose_at = |f: usize| {
            let mut pose = bent_legs(&rig, 0.8575, 0.002 * f as f32);
            if f >= 20 {
                pose[1] += 0.05 * (f - 19) as f32;
            }
            pose
        };
        let mut prev_toe: Option<Vec3> = None;
        for f in 0..40 {
            let mut pose = pose_at(f);
            lock.apply(&rig, &feet, &frame, 6, 1.0, dt, &mut pose)
                .unwrap();
            let (shown, free) = (positions(&rig, &pose), positions(&rig, &pose_at(f)));
            if (5..20).contains(&f) {
                assert!(
                    (free[4].y - 0.015).abs() < 1e-4,
                    "frame {f}: free toe {}",
                    free[4].y
                );
                for toe in [4, 8] {
                    assert!(
                        (0.0..=GROUND_MARGIN_M).contains(&shown[toe].y),
                        "frame {f}: toe {toe} shown at {}",
                        shown[toe].y
                    );
                }
            }
            if f >= 20 + (RELEASE_S / dt).ceil() as usize {
                assert!(
                    shown[4].distance(free[4]) < 1e-5,
                    "frame {f}: still corrected"
                );
            }
            if let Some(q) = prev_toe {
                // At most the walk's 2 mm, the lift's 5 cm and an eased share of the 1.5 cm.
                let step = shown[4].distance(q);
                assert!(step < 0.06, "frame {f}: toe jumps {step}");
                if f < 20 {
                    assert!(step < 0.01, "frame {f}: toe jumps {step} while planted");
                }
            }
            prev_toe = Some(shown[4]);
        }
        assert!(!lock.is_active());
    }

    /// A body 1.25 times the rig's size (hips 1.25 times as high) plants its feet where the scaled
    /// forward kinematics draws them, with the scaled leg lengths; the same walk locked as if it had
    /// the rig's size finds no foot on the floor and leaves the drawn toe sliding.
    #[test]
    fn a_scaled_body_plants_the_feet_it_draws() {
        let (rig, feet) = legs();
        let (dt, scale) = (1.0 / 30.0, 1.25f32);
        let pose_at = |f: usize| bent_legs(&rig, 0.83 * scale, 0.005 * f as f32);
        let drawn = |pose: &[f32]| {
            let mut out = vec![Vec3::ZERO; rig.joint_count()];
            rig.joint_positions_scaled(pose, 6, scale, &mut out)
                .unwrap();
            out
        };
        for (lock_scale, planted) in [(scale, true), (1.0, false)] {
            let mut lock = FootLock::new();
            let mut first = None;
            for f in 0..15 {
                let mut pose = pose_at(f);
                lock.apply(
                    &rig,
                    &feet,
                    &CycleFrame::default(),
                    6,
                    lock_scale,
                    dt,
                    &mut pose,
                )
                .unwrap();
                let p = drawn(&pose);
                let shin = p[3].distance(p[2]);
                assert!((shin - 0.42 * scale).abs() < 1e-4, "frame {f}: shin {shin}");
                // The anchor once the lock holds (the onset ramp eases the first frame).
                if f >= 1 {
                    let a = *first.get_or_insert(p[4]);
                    let moved = p[4].distance(a);
                    if planted {
                        assert!(moved < 2e-3, "frame {f}: toe left its anchor by {moved}");
                    } else {
                        let walked = 0.005 * (f - 1) as f32;
                        assert!((moved - walked).abs() < 1e-4, "frame {f}: {moved}");
                    }
                }
            }
        }
        let mut pose = pose_at(0);
        let mut lock = FootLock::new();
        for bad in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            assert!(matches!(
                lock.apply(&rig, &feet, &CycleFrame::default(), 6, bad, dt, &mut pose),
                Err(FootLockError::Rig(RigError::Scale(_)))
            ));
        }
        assert_eq!(pose, pose_at(0));
        assert_eq!(lock, FootLock::new());
    }

    #[test]
    fn a_swing_foot_and_unevaluated_legs_are_not_touched() {
        let (rig, feet) = legs();
        let dt = 1.0 / 30.0;
        let mut lock = FootLock::new();
        for f in 0..10 {
            // Fast (1 m/s), 2 cm above the floor (toes): never planted, nothing to lift.
            let mut pose = vec![0.0f32; rig.dof()];
            pose[..3].copy_from_slice(&[0.0, 0.90, 0.033 * f as f32]);
            let before = pose.clone();
            lock.apply(&rig, &feet, &CycleFrame::default(), 6, 1.0, dt, &mut pose)
                .unwrap();
            assert_eq!(pose, before);
        }
        let mut lock = FootLock::new();
        for f in 0..10 {
            // Slow, on the floor, but only the first two joints evaluated: the legs are not driven.
            let mut pose = vec![0.0f32; rig.dof()];
            pose[..3].copy_from_slice(&[0.0, 0.86, 0.01 * f as f32]);
            let before = pose.clone();
            lock.apply(&rig, &feet, &CycleFrame::default(), 2, 1.0, dt, &mut pose)
                .unwrap();
            assert_eq!(pose, before);
        }
    }

    #[test]
    fn a_lock_is_small() {
        let size = std::mem::size_of::<FootLock>();
        eprintln!("FootLock: {size} bytes");
        assert!(size <= 256, "{size} bytes");
    }

    #[test]
    fn bad_inputs_are_refused_without_change() {
        let (rig, feet) = legs();
        let mut lock = FootLock::new();
        let mut pose = vec![0.0f32; rig.dof()];
        let frame = CycleFrame::default();
        assert!(matches!(
            lock.apply(&rig, &feet, &frame, 6, 1.0, 0.0, &mut pose),
            Err(FootLockError::FrameStep(_))
        ));
        let bad = FootRig {
            left: Foot {
                ankle: 99,
                toe: None,
            },
            ..feet
        };
        let e = lock
            .apply(&rig, &bad, &frame, 6, 1.0, 0.1, &mut pose)
            .unwrap_err();
        assert!(e.to_string().contains("left foot"), "{e}");
        let not_below = FootRig {
            left: Foot {
                ankle: 3,
                toe: Some(8),
            },
            ..feet
        };
        assert!(not_below.check(&rig).is_err());
        let mut short = vec![0.0f32; 7];
        assert!(matches!(
            lock.apply(&rig, &feet, &frame, 6, 1.0, 0.1, &mut short),
            Err(FootLockError::Rig(_))
        ));
        assert_eq!(lock, FootLock::new());
    }

    // 13. Forward kinematics refuses rows that are not finite or absurdly large, and offsets.
    #[test]
    fn forward_kinematics_refuses_non_finite_rows() {
        let (rig, feet) = legs();
        let n = rig.joint_count();
        let mut good = vec![0.0f32; rig.dof()];
        good[1] = 0.9;
        let mut pos = vec![Vec3::ZERO; n];
        let mut tr = vec![JointTransform::default(); n];
        let mut q = vec![Quat::IDENTITY; n];
        rig.joint_positions(&good, usize::MAX, &mut pos).unwrap();
        for (row, value) in [(0, f32::INFINITY), (8, f32::NAN), (9, 3e38), (4, -3e38)] {
            let mut pose = good.clone();
            pose[row] = value;
            let e = rig
                .joint_positions(&pose, usize::MAX, &mut pos)
                .unwrap_err();
            assert!(
                matches!(e, RigError::PoseValue { row: r, .. } if r == row),
                "{e}"
            );
            assert!(rig.joint_transforms(&pose, usize::MAX, &mut tr).is_err());
            assert!(rig.local_rotations(&pose, usize::MAX, &mut q).is_err());
            let mut lock = FootLock::new();
            let before = pose.clone();
            let r = lock.apply(
                &rig,
                &feet,
                &Default::default(),
                usize::MAX,
                1.0,
                1.0 / 30.0,
                &mut pose,
            );
            assert!(r.is_err());
            assert_eq!(pose.len(), before.len());
        }
        // A body scale that would overflow the positions.
        let e = rig
            .joint_positions_scaled(&good, usize::MAX, 3e38, &mut pos)
            .unwrap_err();
        assert!(matches!(e, RigError::Overflow { .. }), "{e}");
        // Offsets of 3e38 are refused at construction.
        let mut joints = rig.joints().to_vec();
        joints[1].offset = Vec3::splat(3e38);
        assert!(matches!(
            Rig::new(joints),
            Err(RigError::Joint { joint: 1, .. })
        ));
    }
}
