//! Walks from the model: cycles synthesized at given controls, chained end to start, played back at any
//! frame rate through the incremental inverse timewarp, and turned into a BVH motion.
//!
//! Chaining (paper section 5): cycle `k + 1` starts where cycle `k` ends; its cycle frame is placed at
//! the root's ground position at the end of cycle `k`, turned by the cycle's travel turn (the control:
//! the direction of travel, as the data define it, which is not always the pelvis's yaw change). With `blend`, the difference between
//! the end pose of one cycle and the start pose of the next (joint rotations, root height and the
//! pelvis's yaw beyond the travel turn) is faded
//! out over the first half of the next cycle with an ease-in/out curve `3u^2 - 2u^3`, so the seam is
//! continuous; without it, cycles are switched as they are (what the crowd does for distant walkers).

use glam::{DQuat, DVec3};
use lod_policy::Detail;
use motion_io::Motion;
use motion_io::expmap::{exp_to_quat, quat_to_exp};

use crate::model::{Evaluator, MotionModel, TIME_ROW};

/// What to synthesize.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WalkRequest {
    /// Controls `(dx, dz, turn, height)` of every cycle (metres, metres, radians, metres).
    pub controls: [f32; 4],
    /// Level of detail.
    pub detail: Detail,
    /// Number of cycles.
    pub cycles: usize,
    /// Output frames per second.
    pub fps: f64,
    /// Ease-in/out blending at the seams between cycles.
    pub blend: bool,
}

/// Why a walk could not be synthesized.
#[derive(Debug, thiserror::Error)]
pub enum SynthError {
    /// A request field is out of range.
    #[error("{0}")]
    Request(String),
    /// The runtime model refused the controls or the level.
    #[error("synthesis: {0}")]
    Kernel(#[from] lod_policy::KernelError),
    /// The poses could not be converted to BVH channels.
    #[error("BVH conversion: {0}")]
    Pose(#[from] motion_io::PoseError),
}

/// A synthesized walk.
#[derive(Debug, Clone)]
pub struct Walk {
    /// Pose vectors in the walk's world frame, `frames x P` (time row in seconds).
    pub poses: Vec<f64>,
    /// Seconds between frames.
    pub frame_time: f64,
    /// Duration of one cycle (s).
    pub cycle_seconds: f64,
    /// True when a control was outside the data's range and was clamped.
    pub clamped: bool,
}

/// Ground transform of a cycle frame: position on the ground plane and heading (yaw about +y).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct Ground {
    x: f64,
    z: f64,
    yaw: f64,
}

impl Ground {
    fn rotation(&self) -> DQuat {
        DQuat::from_rotation_y(self.yaw)
    }

    /// `self` followed by a local motion `(dx, dz, turn)` in `self`'s frame.
    fn then(&self, dx: f64, dz: f64, turn: f64) -> Ground {
        let v = self.rotation() * DVec3::new(dx, 0.0, dz);
        Ground {
            x: self.x + v.x,
            z: self.z + v.z,
            yaw: self.yaw + turn,
        }
    }
}

/// Heading (yaw) of a rotation: the direction its +z axis points to on the ground.
fn yaw_of(q: DQuat) -> f64 {
    let f = q * DVec3::Z;
    f.x.atan2(f.z)
}

/// Ease-in/out weight `3u^2 - 2u^3` on `[0, 1]`.
fn ease(u: f64) -> f64 {
    let u = u.clamp(0.0, 1.0);
    u * u * (3.0 - 2.0 * u)
}

impl MotionModel {
    /// Synthesizes a walk of `req.cycles` cycles (see the module documentation).
    pub fn synthesize_walk(&self, req: &WalkRequest) -> Result<Walk, SynthError> {
        if req.cycles == 0 {
            return Err(SynthError::Request("at least one cycle is needed".into()));
        }
        if !(req.fps.is_finite() && req.fps > 0.0 && req.fps <= 10_000.0) {
            return Err(SynthError::Request(format!(
                "frame rate {} is not in (0, 10000] frames per second",
                req.fps
            )));
        }
        let lod = &self.lod;
        let (p, t) = (lod.p(), lod.t());
        let mut ev = Evaluator::new(self);
        lod.build_kernel(&req.controls, req.detail, &mut ev.scratch, &mut ev.kernel)?;
        let duration = ev.kernel.duration();
        let at = |phase: f32, ev: &mut Evaluator| -> Result<Vec<f64>, SynthError> {
            lod.pose(&ev.kernel, phase, &mut ev.pose)?;
            Ok(ev.pose.iter().map(|&v| f64::from(v)).collect())
        };
        let start = at(0.0, &mut ev)?;
        let end = at((t - 1) as f32, &mut ev)?;
        // Root motion of one cycle in its own frame.
        let start_yaw = yaw_of(exp_to_quat(DVec3::from_slice(&start[3..6])));
        let end_yaw = yaw_of(exp_to_quat(DVec3::from_slice(&end[3..6])));
        // The next cycle's frame turns by the cycle's travel turn (the control, which the kriging trend
        // reproduces exactly), not by the pelvis's yaw change: on cycles that enter or leave a turn
        // the two differ (by more than 5 degrees for a third of the Bandai cycles), and the walk must
        // travel what was asked. The pelvis's extra yaw is eased out at the seam with the rest.
        let (lo, hi) = self.control_range()[2];
        let travel_turn = f64::from(req.controls[2].clamp(lo, hi));
        let (step_dx, step_dz, step_turn) = (end[0] - start[0], end[2] - start[2], travel_turn);
        let seam_yaw = motion_io::expmap::wrap_angle(end_yaw - start_yaw - travel_turn);
        // Seam offset: what the next cycle's start lacks to continue the previous cycle's end.
        let seam: Vec<f64> = (0..p)
            .map(|r| {
                if r == 1 || r > TIME_ROW {
                    end[r] - start[r]
                } else {
                    0.0
                }
            })
            .collect();

        let frame_time = 1.0 / req.fps;
        let total = duration * req.cycles as f64;
        let frames = (total / frame_time).floor() as usize + 1;
        let mut poses = Vec::with_capacity(frames * p);
        let mut ground = Ground::default();
        let mut cycle = 0usize;
        for f in 0..frames {
            let time = f as f64 * frame_time;
            let k = ((time / duration).floor() as usize).min(req.cycles - 1);
            while cycle < k {
                ground = ground.then(step_dx, step_dz, step_turn);
                cycle += 1;
            }
            let local = time - k as f64 * duration;
            let mut pose = at(ev.kernel.phase_at(local), &mut ev)?;
            // Yaw added to the root orientation in the cycle frame: the seam's pelvis yaw beyond the
            // travel turn, eased out with blending (without it the cycles switch as they are).
            let mut extra_yaw = 0.0;
            if req.blend && k > 0 {
                let w = 1.0 - ease(local / (0.5 * duration));
                for (v, s) in pose.iter_mut().zip(&seam) {
                    *v += w * s;
                }
                extra_yaw = w * seam_yaw;
            }
            // Place the cycle frame in the world: root position and orientation.
            let rot = ground.rotation();
            let pos = rot * DVec3::from_slice(&pose[0..3]) + DVec3::new(ground.x, 0.0, ground.z);
            let orient = rot
                * DQuat::from_rotation_y(extra_yaw)
                * exp_to_quat(DVec3::from_slice(&pose[3..6]));
            pose[0..3].copy_from_slice(&pos.to_array());
            pose[3..6].copy_from_slice(&quat_to_exp(orient).to_array());
            pose[TIME_ROW] /= lod.parts().time_scale;
            poses.extend_from_slice(&pose);
        }
        motion_io::unwrap_exp_maps(&mut poses, p)?;
        Ok(Walk {
            poses,
            frame_time,
            cycle_seconds: duration,
            clamped: ev.kernel.clamped(),
        })
    }

    /// The walk as a BVH motion of the model's skeleton (in the skeleton's file units).
    pub fn walk_motion(&self, walk: &Walk) -> Result<Motion, SynthError> {
        Ok(self
            .layout
            .motion_from_poses(&walk.poses, walk.frame_time)?)
    }
}
