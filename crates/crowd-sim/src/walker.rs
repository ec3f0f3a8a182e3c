//! Per-walker state and the three per-frame stages run for each walker: advance and rebuild
//! clips (kernels), evaluate and blend poses, forward kinematics into the world.

use crate::controls::{ControlBounds, Controls, Detail, LevelTable, RootMotion};
use crate::path::{EllipsePath, forward, left, path_controls, wrap_angle};
use crate::source::ClipSource;
use crate::transition::{BlendWindow, blend_into};
use glam::{Vec2, Vec3};

/// Settings the stages need, copied out of the crowd config.
#[derive(Debug, Clone, Copy)]
pub(crate) struct StageParams {
    pub levels: LevelTable,
    pub bounds: ControlBounds,
    pub blend_levels: usize,
    pub blend_fraction: f32,
}

/// One walker: its path, cycle base frame, current and previous clips.
#[derive(Debug, Clone)]
pub(crate) struct Walker<C> {
    pub path: EllipsePath,
    /// Path parameter closest to the current cycle's base.
    pub s: f32,
    /// Preferred forward displacement per cycle (m).
    pub stride: f32,
    pub height: f32,
    /// Ground position of the current cycle frame's origin.
    pub base: Vec2,
    /// Heading of the current cycle frame.
    pub heading: f32,
    /// Seconds into the current cycle.
    pub t: f32,
    pub controls: Controls,
    pub cur: C,
    pub cur_detail: Detail,
    pub cur_dur: f32,
    pub cur_motion: RootMotion,
    pub prev: C,
    pub prev_detail: Detail,
    pub prev_dur: f32,
    pub blend: Option<BlendWindow>,
    /// Rows of the pose vector written this frame.
    pub rows: usize,
    /// Joint positions written this frame.
    pub n_joints: usize,
    /// World root position after the last frame.
    pub root: Vec3,
}

/// Duration check: finite and at least 1 ms.
pub(crate) fn valid_duration(d: f32) -> bool {
    d.is_finite() && d >= 1e-3
}

/// A failure found while running a stage for one walker.
#[derive(Debug, Clone, Copy)]
pub(crate) enum WalkerFault {
    Duration(f32),
    Level(usize),
}

impl<C> Walker<C> {
    fn blends(p: &StageParams, new: &Detail, old: &Detail) -> bool {
        new.accuracy < p.blend_levels && new.active_joints > 0 && old.active_joints > 0
    }

    /// Builds `cur` for `self.controls` at `d`, after moving the old clip to `prev`.
    fn rebuild<S: ClipSource<Clip = C>>(&mut self, src: &S, d: Detail) -> Result<(), WalkerFault> {
        std::mem::swap(&mut self.cur, &mut self.prev);
        self.prev_detail = self.cur_detail;
        self.prev_dur = self.cur_dur;
        src.build_clip(&self.controls, d, &mut self.cur);
        let dur = src.clip_duration(&self.cur);
        if !valid_duration(dur) {
            return Err(WalkerFault::Duration(dur));
        }
        self.cur_detail = d;
        self.cur_dur = dur;
        self.cur_motion = src.clip_root_motion(&self.cur);
        Ok(())
    }

    /// Kernel stage: advance time by `dt`; at each cycle end accumulate the root motion, pick
    /// controls from the path ahead and build the next clip at `d` (blended in over the first
    /// `blend_fraction` of the cycle at blending levels); mid-cycle, rebuild when `d` is finer
    /// than the clip held (see the deferral rule inside). Returns the number of kernels built.
    pub fn advance<S: ClipSource<Clip = C>>(
        &mut self,
        src: &S,
        p: &StageParams,
        d: Detail,
        dt: f32,
    ) -> Result<usize, WalkerFault> {
        if d.accuracy >= p.levels.accuracy_levels {
            return Err(WalkerFault::Level(d.accuracy));
        }
        let d = Detail {
            accuracy: d.accuracy,
            active_joints: d.active_joints.min(p.levels.joints),
        };
        let mut built = 0;
        self.t += dt;
        while self.t >= self.cur_dur {
            self.t -= self.cur_dur;
            let m = self.cur_motion;
            self.base += left(self.heading) * m.dx + forward(self.heading) * m.dz;
            self.heading = wrap_angle(self.heading + m.turn);
            self.s = self.path.closest_param_near(self.base, self.s);
            self.controls = path_controls(
                &self.path,
                self.s,
                self.base,
                self.heading,
                self.stride,
                self.height,
                &p.bounds,
            );
            self.rebuild(src, d)?;
            built += 1;
            self.blend = Self::blends(p, &d, &self.prev_detail).then_some(BlendWindow {
                start: 0.0,
                end: p.blend_fraction,
            });
        }
        if built == 0 && d.is_finer_than(&self.cur_detail) {
            let u = self.t / self.cur_dur;
            // A blended upgrade needs a whole window before the cycle ends and no blend running;
            // otherwise it waits (at most one window) for the cycle boundary, where it is built
            // anyway. Upgrades that need no blend (from root only, or beyond the blend levels)
            // happen at once.
            let blend = Self::blends(p, &d, &self.cur_detail);
            if !blend || (self.blend.is_none() && u + p.blend_fraction <= 1.0) {
                self.rebuild(src, d)?;
                built += 1;
                self.t = (u * self.cur_dur).min(self.cur_dur * 0.999_999);
                self.blend = blend.then_some(BlendWindow {
                    start: u,
                    end: u + p.blend_fraction,
                });
            }
        }
        Ok(built)
    }

    /// Pose stage: the current clip's pose at `t`, blended with the previous clip at the same
    /// phase inside a blend window. `scratch` has the pose length.
    pub fn pose<S: ClipSource<Clip = C>>(&mut self, src: &S, out: &mut [f32], scratch: &mut [f32]) {
        let u = self.t / self.cur_dur;
        self.rows = src.pose(&self.cur, self.t, out).min(out.len());
        if let Some(w) = self.blend {
            if u < w.end {
                let n_prev = src
                    .pose(&self.prev, (u * self.prev_dur).min(self.prev_dur), scratch)
                    .min(scratch.len());
                blend_into(&scratch[..n_prev], &mut out[..self.rows], w.weight(u));
            } else {
                self.blend = None;
            }
        }
    }

    /// FK stage: cycle-frame joint positions from the source, then `world = base + R_y(h) p`
    /// with `R_y(h) (x, y, z) = (x cos h + z sin h, y, -x sin h + z cos h)`.
    pub fn place<S: ClipSource<Clip = C>>(&mut self, src: &S, pose: &[f32], out: &mut [Vec3]) {
        let n = src
            .joints(&self.cur, &pose[..self.rows], out)
            .min(out.len());
        let (sh, ch) = self.heading.sin_cos();
        for q in &mut out[..n] {
            *q = Vec3::new(
                self.base.x + q.x * ch + q.z * sh,
                q.y,
                self.base.y - q.x * sh + q.z * ch,
            );
        }
        self.n_joints = n;
        if n > 0 {
            self.root = out[0];
        }
    }
}
