//! The procedural walker: turns a [`TakeSpec`] into a BVH take (a `motion_io::Motion`) at 120 Hz.
//!
//! Per frame: the gait phase and path give the pelvis (bob, sway, transverse rotation, obliquity,
//! lean into turns); the foot planner gives both ankles; two-bone IK places the knees; the trunk
//! counter-rotates, the head keeps looking along the path and the arms swing against the legs.
//! The pelvis height is the designed height softly limited so that both legs reach their ankles,
//! which keeps stance feet planted without sliding.

use glam::{DQuat, DVec3};
use motion_io::Motion;

use crate::euler::{quat_to_zxy_degrees, unwrap_degrees};
use crate::footsteps::{FootPlanner, FootState, Side, smoothstep};
use crate::gait::{GRAVITY, SpecError, TakeSpec, Trajectory};
use crate::leg_ik::solve_leg;
use crate::rig::{self, Rig};

/// Frame rate of the generated takes, Hz (the paper's capture rate).
pub const FPS: f64 = 120.0;
/// Fraction of the full leg length (hip to ankle) a leg may reach; keeps the knee bent a little
/// (about 9 degrees at the limit), as a human knee never locks fully while walking.
const REACH: f64 = 0.997;
/// Swing fraction over which a foot's reach limit on the pelvis height fades out after toe off
/// (it fades back in between 50 % and 75 % of the swing, before the leg reaches forward).
const SWING_FADE: f64 = 0.2;
/// Height added to a fully faded reach limit, cm (large against `SOFTMIN_CM`: no effect).
const FADED_CM: f64 = 30.0;
/// Width of the soft minimum between designed and reachable pelvis height, cm.
const SOFTMIN_CM: f64 = 0.4;

/// A generated take and the generator state needed to inspect it.
#[derive(Debug, Clone)]
pub struct Take {
    /// What was generated.
    pub spec: TakeSpec,
    /// The performer's rig.
    pub rig: Rig,
    /// Root path and phase.
    pub trajectory: Trajectory,
    /// Foot placement.
    pub planner: FootPlanner,
    /// The frames, channels in the rig's skeleton order (Euler degrees, cm).
    pub motion: Motion,
}

impl Take {
    /// Time of frame `i`, seconds.
    pub fn time(&self, i: usize) -> f64 {
        i as f64 / FPS
    }

    /// State of foot `side` at frame `i` as planned (before IK).
    pub fn foot(&self, side: Side, i: usize) -> FootState {
        self.planner.state(
            &self.trajectory,
            side,
            self.trajectory.phase_at(self.time(i)),
        )
    }
}

/// World pose of the pelvis at one instant.
struct Pelvis {
    position: DVec3,
    rotation: DQuat,
}

/// `-k ln(sum exp(-x_i / k))`: a smooth lower bound of `min(x_i)`, within `k ln n` of it.
fn soft_min(values: &[f64], k: f64) -> f64 {
    let m = values.iter().copied().fold(f64::INFINITY, f64::min);
    let s: f64 = values.iter().map(|v| (-(v - m) / k).exp()).sum();
    m - k * s.ln()
}

/// Generates the take described by `spec`, or says which field is out of range.
pub fn generate(spec: &TakeSpec) -> Result<Take, SpecError> {
    spec.validate()?;
    let rig = Rig::new(spec.height_m);
    let trajectory = Trajectory::new(spec, rig.hip_height());
    let planner = FootPlanner::new(rig, spec);
    let frames = (trajectory.end * FPS).floor() as usize + 1;
    let skeleton = rig.skeleton();
    let mut data = vec![0.0; frames * rig::CHANNEL_COUNT];
    let mut locals = [DQuat::IDENTITY; rig::JOINT_COUNT];
    for i in 0..frames {
        let t = i as f64 / FPS;
        let root = pose_frame(spec, &rig, &trajectory, &planner, t, &mut locals);
        let row = &mut data[i * rig::CHANNEL_COUNT..(i + 1) * rig::CHANNEL_COUNT];
        row[0] = root.x;
        row[1] = root.y;
        row[2] = root.z;
        for (j, q) in locals.iter().enumerate() {
            let start = if j == 0 { 3 } else { 3 + 3 * j };
            row[start..start + 3].copy_from_slice(&quat_to_zxy_degrees(*q));
        }
    }
    // Keep every Euler channel continuous (no jumps of 360 degrees, e.g. the heading of a turn).
    for i in 1..frames {
        let (prev, cur) = data.split_at_mut(i * rig::CHANNEL_COUNT);
        let prev = &prev[(i - 1) * rig::CHANNEL_COUNT..];
        for c in 3..rig::CHANNEL_COUNT {
            cur[c] = unwrap_degrees(cur[c], prev[c]);
        }
    }
    let motion = Motion {
        skeleton,
        frame_time: 1.0 / FPS,
        frames: data,
    };
    Ok(Take {
        spec: *spec,
        rig,
        trajectory,
        planner,
        motion,
    })
}

/// Poses one frame: writes every joint's local rotation into `locals` (index = joint) and returns
/// the root position (cm).
fn pose_frame(
    spec: &TakeSpec,
    rig: &Rig,
    traj: &Trajectory,
    planner: &FootPlanner,
    t: f64,
    locals: &mut [DQuat; rig::JOINT_COUNT],
) -> DVec3 {
    let phi = traj.phase_at(t);
    let feet = [
        planner.state(traj, Side::Left, phi),
        planner.state(traj, Side::Right, phi),
    ];
    let pelvis = pelvis_pose(spec, rig, traj, &feet, t, phi);
    locals[rig::HIPS] = pelvis.rotation;

    // Legs.
    let legs = [
        (
            Side::Left,
            rig::UPPER_LEG_L,
            rig::LOWER_LEG_L,
            rig::FOOT_L,
            rig::TOES_L,
        ),
        (
            Side::Right,
            rig::UPPER_LEG_R,
            rig::LOWER_LEG_R,
            rig::FOOT_R,
            rig::TOES_R,
        ),
    ];
    for ((side, upper, lower, foot, toes), fs) in legs.into_iter().zip(feet.iter()) {
        let hip = pelvis.position + pelvis.rotation * rig.hip_offset(side.sign());
        let forward = DVec3::new(fs.yaw.sin(), 0.0, fs.yaw.cos());
        let leg = solve_leg(hip, fs.ankle, rig.thigh, rig.shank, forward);
        let foot_world = crate::footsteps::foot_rotation(fs.yaw, fs.pitch);
        locals[upper] = (pelvis.rotation.inverse() * leg.thigh).normalize();
        locals[lower] = (leg.thigh.inverse() * leg.shank).normalize();
        locals[foot] = (leg.shank.inverse() * foot_world).normalize();
        locals[toes] = DQuat::from_rotation_x(fs.toe);
    }

    // Trunk: the thorax counter-rotates against the pelvis, leans forward with speed and into turns.
    let a = amplitude_scale(traj, t);
    let heading = traj.heading(t);
    let cycle = std::f64::consts::TAU * phi;
    let turn_lean = -(traj.speed_at(t) / 100.0 * traj.turn_rate(t) / GRAVITY).atan() * 0.6;
    let chest_world = DQuat::from_rotation_y(heading + (3.5 * a).to_radians() * cycle.cos())
        * DQuat::from_rotation_x((spec.style.trunk_lean_deg * (0.6 + 0.4 * a)).to_radians())
        * DQuat::from_rotation_z(turn_lean * 0.8);
    let correction = pelvis.rotation.inverse() * chest_world;
    let spine = DQuat::IDENTITY.slerp(correction, 0.5);
    locals[rig::SPINE] = spine;
    locals[rig::CHEST] = (spine.inverse() * correction).normalize();

    // Head: level, looking a little into the turn (where the walker will be in 0.35 s).
    let head_world = DQuat::from_rotation_y(heading + 0.35 * traj.turn_rate(t));
    let correction = chest_world.inverse() * head_world;
    let neck = DQuat::IDENTITY.slerp(correction, 0.5);
    locals[rig::NECK] = neck;
    locals[rig::HEAD] = (neck.inverse() * correction).normalize();

    // Arms swing against the legs (left arm forward at right heel strike), lagging a little.
    let swing = (spec.style.arm_swing_deg * a).to_radians();
    let elbow = spec.style.elbow_deg.to_radians();
    let lagged = std::f64::consts::TAU * (phi - 0.04);
    let arms = [
        (
            1.0,
            lagged.cos(),
            rig::UPPER_ARM_L,
            rig::LOWER_ARM_L,
            rig::HAND_L,
        ),
        (
            -1.0,
            -lagged.cos(),
            rig::UPPER_ARM_R,
            rig::LOWER_ARM_R,
            rig::HAND_R,
        ),
    ];
    for (sign, c, upper, lower, hand) in arms {
        // c = -1: arm fully forward (negative X rotation swings the arm forward).
        let abduction = sign * 7f64.to_radians();
        locals[upper] =
            DQuat::from_rotation_z(abduction) * DQuat::from_rotation_x(swing * c - 0.05);
        let flex = elbow * (0.7 + 0.6 * 0.5 * (1.0 - c) * a.min(1.3));
        locals[lower] = DQuat::from_rotation_x(-flex);
        locals[hand] = DQuat::from_rotation_x(-(4.0 + 3.0 * c).to_radians());
    }
    pelvis.position
}

/// Factor on gait amplitudes: the current speed relative to 1.2 m/s, in `[0.3, 1.4]`.
fn amplitude_scale(traj: &Trajectory, t: f64) -> f64 {
    (traj.speed_at(t) / 120.0).clamp(0.3, 1.4)
}

/// Pelvis position and orientation at time `t` and phase `phi`, given both feet.
///
/// With `psi = 2 pi (phi - beta / 2)` (0 at left mid-stance): sway `A_s cos psi` towards the stance
/// foot, obliquity `A_r cos psi` (the swing side drops), transverse rotation `-A_y cos 2 pi phi`
/// (the leading leg's hip forward), vertical bob `-A_b (1 - cos 2 psi) / 2` (highest at
/// mid-stance), then the height is limited so that each leg reaches its ankle within `REACH`.
fn pelvis_pose(
    spec: &TakeSpec,
    rig: &Rig,
    traj: &Trajectory,
    feet: &[FootState; 2],
    t: f64,
    phi: f64,
) -> Pelvis {
    let a = amplitude_scale(traj, t);
    let h = rig.height;
    let psi = std::f64::consts::TAU * (phi - 0.5 * traj.duty);
    let heading = traj.heading(t);
    let yaw = -(4.0 * a).to_radians() * (std::f64::consts::TAU * phi).cos();
    let roll = (3.5 * a).to_radians() * psi.cos();
    let turn_lean = -(traj.speed_at(t) / 100.0 * traj.turn_rate(t) / GRAVITY).atan() * 0.6;
    let tilt = (3.0 + 1.0 * (2.0 * psi).cos()).to_radians();
    let rotation = DQuat::from_rotation_y(heading + yaw)
        * DQuat::from_rotation_x(tilt)
        * DQuat::from_rotation_z(roll + turn_lean);
    let sway = 0.014 * h * (1.3 - 0.4 * a) * psi.cos();
    let surge = -0.004 * h * a * (2.0 * psi).sin();
    let ground = traj.position(t) + DQuat::from_rotation_y(heading) * DVec3::new(sway, 0.0, surge);

    // Designed height: knee bent 6 degrees at mid-stance, minus the bob.
    let leg = rig.thigh + rig.shank;
    let mid_stance = (rig.thigh.powi(2)
        + rig.shank.powi(2)
        + 2.0 * rig.thigh * rig.shank * 6f64.to_radians().cos())
    .sqrt();
    let bob = 0.012 * h * spec.style.bob_scale * a;
    let designed =
        rig.ankle_height + mid_stance + rig.hip_drop - bob * 0.5 * (1.0 - (2.0 * psi).cos());

    // Highest pelvis for which each hip is within REACH * leg of its ankle.
    let mut candidates = [designed, 0.0, 0.0];
    for (k, (fs, side)) in feet.iter().zip([1.0, -1.0]).enumerate() {
        let off = rotation * rig.hip_offset(side);
        let hip_xz = ground + off;
        let dx = hip_xz.x - fs.ankle.x;
        let dz = hip_xz.z - fs.ankle.z;
        let max_h = (REACH * leg).powi(2);
        let horizontal = (dx * dx + dz * dz).min(0.98 * max_h);
        let fade = if fs.stance {
            0.0
        } else {
            let u = fs.progress;
            FADED_CM * smoothstep(u / SWING_FADE) * smoothstep((0.75 - u) / 0.25)
        };
        candidates[k + 1] = fs.ankle.y + (max_h - horizontal).sqrt() - off.y + fade;
    }
    let y = soft_min(&candidates, SOFTMIN_CM);
    Pelvis {
        position: DVec3::new(ground.x, y, ground.z),
        rotation,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_specs_are_errors() {
        let good = TakeSpec {
            height_m: 1.7,
            speed: 1.2,
            turn_rate_deg: 10.0,
            heading0_deg: 0.0,
            start_m: [0.0, 0.0],
            steady_cycles: 2,
            style: crate::gait::Style::default(),
        };
        assert!(generate(&good).is_ok());
        let bad = [
            TakeSpec { speed: 0.0, ..good },
            TakeSpec {
                speed: f64::NAN,
                ..good
            },
            TakeSpec {
                height_m: 0.2,
                ..good
            },
            TakeSpec {
                turn_rate_deg: f64::INFINITY,
                ..good
            },
            TakeSpec {
                speed: 0.3,
                turn_rate_deg: 60.0,
                ..good
            },
            TakeSpec {
                steady_cycles: 0,
                ..good
            },
            TakeSpec {
                start_m: [f64::NAN, 0.0],
                ..good
            },
        ];
        for spec in bad {
            let e = generate(&spec).unwrap_err();
            assert!(e.to_string().starts_with("take spec: "), "{e}");
        }
    }

    #[test]
    fn soft_min_is_a_smooth_lower_bound() {
        let v = [3.0, 5.0, 10.0];
        let s = soft_min(&v, 0.4);
        assert!(s <= 3.0 && s > 3.0 - 0.4 * 3f64.ln());
    }
}
