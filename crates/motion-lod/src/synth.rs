//! Walks from the model: cycles synthesized at given controls, chained end to start, played back at any
//! frame rate through the incremental inverse timewarp, and turned into a BVH motion.
//!
//! Chaining is the runtime's one routine ([`lod_policy::SeamTransition`]): cycle `k + 1`'s frame is cycle `k`'s
//! advanced by the clip's root motion (ground displacement and travel turn), and with `blend` the seam
//! is inertialized, so every joint and the whole root are continuous in position and velocity; without
//! it, cycles are switched as they are (what the crowd does for distant walkers). With `plant_feet`,
//! feet on the floor are held in place by two-bone IK ([`crate::footlock`]).

use lod_policy::{Controls, Detail};
use lod_policy::{CycleFrame, DEFAULT_HALFLIFE_S, SeamScratch, SeamTransition};
use motion_io::Motion;

use crate::model::{Evaluator, MotionModel, TIME_ROW};

/// The most frames one synthesized walk holds: about 4.6 hours at 60 fps, `8 P` MB of f64 pose
/// vectors (0.8 GB for `P = 100` rows). Longer requests are refused before allocating.
pub const MAX_WALK_FRAMES: usize = 1_000_000;

/// The longest gait cycle a walk may have (s); a model that gives a longer one is broken (found by
/// the `model_mutated` fuzz target: a mutated time table gave cycles of 3 hours).
pub const MAX_CYCLE_S: f64 = 60.0;

/// The fewest frames a walk samples each gait cycle with: below two the frames alias the steps
/// (a walk at 0.5 fps showed one frame of four cycles' worth of time; at 1e-300 fps, one frame).
pub const MIN_FRAMES_PER_CYCLE: f64 = 2.0;

/// Refuses a frame rate that gives a cycle of `duration` seconds fewer than
/// [`MIN_FRAMES_PER_CYCLE`] frames.
fn check_frames_per_cycle(duration: f64, fps: f64) -> Result<(), SynthError> {
    if duration * fps < MIN_FRAMES_PER_CYCLE {
        return Err(SynthError::Request(format!(
            "at {fps} fps a gait cycle of {duration:.3} s gets {:.2} frames; a walk needs at least \
             {MIN_FRAMES_PER_CYCLE} a cycle (a frame rate of at least {:.2} fps)",
            duration * fps,
            MIN_FRAMES_PER_CYCLE / duration
        )));
    }
    Ok(())
}

/// What to synthesize.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WalkRequest {
    /// Controls of every cycle.
    pub controls: Controls,
    /// Level of detail.
    pub detail: Detail,
    /// Number of cycles.
    pub cycles: usize,
    /// Output frames per second.
    pub fps: f64,
    /// Seamless transitions between cycles ([`lod_policy::SeamTransition`]); without, cycles switch as they
    /// are (what the crowd does for distant walkers).
    pub blend: bool,
    /// Keep planted feet planted ([`crate::footlock`]; needs the model's quality reference).
    pub plant_feet: bool,
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
    /// Duration of one cycle (s; for a track, the mean of its cycles).
    pub cycle_seconds: f64,
    /// Number of cycles the walk plays.
    pub cycles: usize,
    /// True when a control was outside the data's range and was clamped.
    pub clamped: bool,
    /// The character's body scale ([`MotionModel::body_scale`]): its bones are the skeleton's
    /// times this ([`MotionModel::walk_layout`]).
    pub body_scale: f64,
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
        let lod = self.lod();
        let p = lod.p();
        let mut ev = Evaluator::new(self);
        lod.build_kernel(&req.controls, req.detail, &mut ev.scratch, &mut ev.kernel)?;
        let kernel = &ev.kernel;
        let duration = kernel.duration();
        let motion = kernel.root_motion();
        let eval = |t: f64, out: &mut [f32]| lod.pose(kernel, kernel.phase_at(t), out);
        // Displayed pose `t` seconds into the current cycle: the clip's pose and the running seam
        // transition (chain.rs).
        let displayed = |t: f64, tr: &SeamTransition, out: &mut [f32]| -> Result<(), SynthError> {
            eval(t, out)?;
            if req.blend {
                tr.apply(t as f32, out);
            }
            Ok(())
        };

        if !(duration.is_finite() && duration > 0.0 && duration <= MAX_CYCLE_S) {
            return Err(SynthError::Request(format!(
                "the model gives a cycle of {duration} s for controls {:?}, not a walk's (0 to \
                 {MAX_CYCLE_S} s; a model file with a broken time table?)",
                req.controls
            )));
        }
        check_frames_per_cycle(duration, req.fps)?;
        let frame_time = 1.0 / req.fps;
        let total = duration * req.cycles as f64;
        let frames_f = (total / frame_time).floor() + 1.0;
        if frames_f > MAX_WALK_FRAMES as f64 {
            return Err(SynthError::Request(format!(
                "{} cycles of {duration:.3} s at {} fps are {frames_f} frames; at most \
                 {MAX_WALK_FRAMES} are written",
                req.cycles, req.fps
            )));
        }
        let frames = frames_f as usize;
        let mut poses = Vec::with_capacity(frames * p);
        let mut transition = SeamTransition::new(p, DEFAULT_HALFLIFE_S);
        let mut seam = SeamScratch::new(p);
        let mut pose = vec![0.0f32; p];
        let rows = kernel.rows();
        let mut frame = CycleFrame::default();
        let mut cycle = 0usize;
        for f in 0..frames {
            let time = f as f64 * frame_time;
            let k = ((time / duration).floor() as usize).min(req.cycles - 1);
            while cycle < k {
                // The seam: the displayed end of this cycle, in the next cycle's frame, against the
                // next cycle's own start.
                let end = duration as f32;
                seam.capture(end, end, Some(&motion), |t, out| {
                    displayed(f64::from(t), &transition, out).map(|()| rows)
                })?;
                seam.start(
                    0.0,
                    end,
                    |t, out| eval(f64::from(t), out).map(|()| rows),
                    &mut transition,
                )?;
                frame = frame.next(&motion);
                cycle += 1;
            }
            let local = time - k as f64 * duration;
            displayed(local, &transition, &mut pose)?;
            // Place the cycle frame in the world: root position and orientation.
            frame.place_root(&mut pose);
            poses.extend(pose.iter().map(|&v| f64::from(v)));
            poses[f * p + TIME_ROW] /= lod.parts().time_scale;
        }
        let body_scale =
            self.finish_poses(&mut poses, &req.controls, req.plant_feet, frame_time)?;
        Ok(Walk {
            poses,
            frame_time,
            cycle_seconds: duration,
            cycles: req.cycles,
            clamped: kernel.clamped(),
            body_scale,
        })
    }

    /// Synthesizes a walk whose controls change over time: `track` holds `(time in seconds,
    /// controls)` rows in increasing time (the first at time 0 or earlier); each cycle takes the
    /// controls of the last row at or before its start, so a change applies at the next cycle
    /// seam, through the runtime's chaining. The walk ends with the first cycle that starts at or
    /// after the last row's time (every row takes effect). `req.controls` and `req.cycles` are not
    /// used; the body scale is the first row's.
    pub fn synthesize_track(
        &self,
        req: &WalkRequest,
        track: &[(f64, Controls)],
    ) -> Result<Walk, SynthError> {
        let Some(&(first, _)) = track.first() else {
            return Err(SynthError::Request("the track has no rows".into()));
        };
        if !first.is_finite() || first > 0.0 {
            return Err(SynthError::Request(format!(
                "the track's first row is at {first} s: it must be at 0 s (the walk's start)"
            )));
        }
        if let Some(i) =
            (1..track.len()).find(|&i| track[i].0 <= track[i - 1].0 || !track[i].0.is_finite())
        {
            return Err(SynthError::Request(format!(
                "track row {} (time {} s) does not come after row {} ({} s): times must increase",
                i + 1,
                track[i].0,
                i,
                track[i - 1].0
            )));
        }
        let last = track.last().map_or(0.0, |r| r.0);
        // Set once a cycle starts at or after the last row: that cycle is the walk's last.
        let mut ended = false;
        self.synthesize_cycles(req, &mut |_, start| {
            if ended {
                return None;
            }
            ended = start >= last;
            // The last row at or before `start` (times increase, checked above), by bisection: a
            // track of a million rows (10,000 s) took 24.4 s with a scan per cycle, 11.1 s so
            // (the same bytes; 2026-11-28, release build, this machine).
            let after = track.partition_point(|r| r.0 <= start);
            Some(track[after.saturating_sub(1)].1)
        })
    }

    /// The walk whose cycle `k`, starting at `start` seconds, has the controls `next(k, start)`;
    /// the walk ends before the first cycle for which it gives `None` (the first must be given).
    /// Each seam is [`MotionModel::synthesize_walk`]'s, between two different clips.
    fn synthesize_cycles(
        &self,
        req: &WalkRequest,
        next: &mut dyn FnMut(usize, f64) -> Option<Controls>,
    ) -> Result<Walk, SynthError> {
        if !(req.fps.is_finite() && req.fps > 0.0 && req.fps <= 10_000.0) {
            return Err(SynthError::Request(format!(
                "frame rate {} is not in (0, 10000] frames per second",
                req.fps
            )));
        }
        let lod = self.lod();
        let p = lod.p();
        let first = next(0, 0.0)
            .ok_or_else(|| SynthError::Request("at least one cycle is needed".into()))?;
        // Two clips: the one playing and the next, built at the seam.
        let mut ev = Evaluator::new(self);
        let mut upcoming = Evaluator::new(self);
        let check = |kernel: &lod_policy::ClipKernel, c: &Controls| -> Result<f64, SynthError> {
            let duration = kernel.duration();
            if !(duration.is_finite() && duration > 0.0 && duration <= MAX_CYCLE_S) {
                return Err(SynthError::Request(format!(
                    "the model gives a cycle of {duration} s for controls {c:?}, not a walk's (0 to \
                    {MAX_CYCLE_S} s; a model file with a broken time table?)"
                )));
            }
            check_frames_per_cycle(duration, req.fps)?;
            Ok(duration)
        };
        lod.build_kernel(&first, req.detail, &mut ev.scratch, &mut ev.kernel)?;
        let mut duration = check(&ev.kernel, &first)?;
        let frame_time = 1.0 / req.fps;
        let mut poses = Vec::new();
        let mut transition = SeamTransition::new(p, DEFAULT_HALFLIFE_S);
        let mut seam = SeamScratch::new(p);
        let mut pose = vec![0.0f32; p];
        let mut frame = CycleFrame::default();
        let mut clamped = ev.kernel.clamped();
        let (mut cycle, mut start) = (0usize, 0.0f64);
        let mut f = 0usize;
        loop {
            let time = f as f64 * frame_time;
            // Past this cycle's end: chain to the next, or stop after the last frame of the walk.
            while time > start + duration + 1e-12 {
                let Some(c) = next(cycle + 1, start + duration) else {
                    break;
                };
                lod.build_kernel(&c, req.detail, &mut upcoming.scratch, &mut upcoming.kernel)?;
                check(&upcoming.kernel, &c)?;
                clamped |= upcoming.kernel.clamped();
                let (kernel, new) = (&ev.kernel, &upcoming.kernel);
                let motion = kernel.root_motion();
                let rows = kernel.rows().min(new.rows());
                let end = duration as f32;
                // The seam: the displayed end of this cycle, in the next cycle's frame, against the
                // next cycle's own start.
                seam.capture(end, end, Some(&motion), |t, out| {
                    lod.pose(kernel, kernel.phase_at(f64::from(t)), out)?;
                    if req.blend {
                        transition.apply(t, out);
                    }
                    Ok::<usize, SynthError>(rows)
                })?;
                seam.start(
                    0.0,
                    new.duration() as f32,
                    |t, out| {
                        lod.pose(new, new.phase_at(f64::from(t)), out)
                            .map(|()| rows)
                    },
                    &mut transition,
                )?;
                frame = frame.next(&motion);
                start += duration;
                duration = new.duration();
                cycle += 1;
                std::mem::swap(&mut ev, &mut upcoming);
            }
            if time > start + duration + 1e-12 {
                break;
            }
            if poses.len() / p.max(1) >= MAX_WALK_FRAMES {
                return Err(SynthError::Request(format!(
                    "{} cycles at {} fps are more than {MAX_WALK_FRAMES} frames, the most a walk writes",
                    cycle + 1,
                    req.fps
                )));
            }
            let kernel = &ev.kernel;
            let local = (time - start).clamp(0.0, duration);
            lod.pose(kernel, kernel.phase_at(local), &mut pose)?;
            if req.blend {
                transition.apply(local as f32, &mut pose);
            }
            // Place the cycle frame in the world: root position and orientation.
            frame.place_root(&mut pose);
            poses.extend(pose.iter().map(|&v| f64::from(v)));
            poses[f * p + TIME_ROW] /= lod.parts().time_scale;
            f += 1;
        }
        let body_scale = self.finish_poses(&mut poses, &first, req.plant_feet, frame_time)?;
        Ok(Walk {
            poses,
            frame_time,
            cycle_seconds: if cycle == 0 {
                duration
            } else {
                start / cycle as f64
            },
            cycles: cycle + 1,
            clamped,
            body_scale,
        })
    }

    /// What every walk does to its world-frame poses once they are placed: exp-maps kept on one
    /// branch over time, then with `plant_feet` the foot lock on the layout scaled to the body
    /// scale of `controls` (which it returns).
    fn finish_poses(
        &self,
        poses: &mut [f64],
        controls: &Controls,
        plant_feet: bool,
        frame_time: f64,
    ) -> Result<f64, SynthError> {
        motion_io::unwrap_exp_maps(poses, self.lod().p())?;
        let body_scale = f64::from(self.body_scale(controls));
        if plant_feet && let Some(reference) = &self.report.quality {
            crate::footlock::plant_feet(
                &self.layout.scaled(body_scale)?,
                &reference.feet,
                reference.floor_m,
                poses,
                frame_time,
            );
        }
        Ok(body_scale)
    }

    /// The pose layout a walk is drawn with: the model's, its bones scaled by the walk's body scale
    /// ([`PoseLayout::scaled`](motion_io::PoseLayout::scaled)).
    pub fn walk_layout(&self, walk: &Walk) -> Result<motion_io::PoseLayout, SynthError> {
        Ok(self.layout.scaled(walk.body_scale)?)
    }

    /// The walk as a BVH motion of the model's skeleton scaled by the walk's body scale (in the
    /// skeleton's file units).
    pub fn walk_motion(&self, walk: &Walk) -> Result<Motion, SynthError> {
        Ok(self
            .walk_layout(walk)?
            .motion_from_poses(&walk.poses, walk.frame_time)?)
    }
}
