//! Per-walker state and the three per-frame stages run for each walker: advance and rebuild
//! clips (kernels), evaluate poses with the running seam transition, forward kinematics into the
//! world.

use crate::error::ClipError;
use crate::levels::LevelTable;
use crate::path::{EllipsePath, path_controls_rotated};
use crate::source::ClipSource;
use crate::stock::Lender;
use glam::{DVec2, Vec3};
use lod_policy::SeamTransition;
use lod_policy::{ControlRange, Controls, CycleFrame, Detail, FootLock, RootMotion};

/// Settings the stages need, copied out of the crowd config.
#[derive(Debug, Clone, Copy)]
pub(crate) struct StageParams {
    pub levels: LevelTable,
    pub bounds: ControlRange,
    pub seam_levels: usize,
    /// Half-life of a seam's offset (s), for the transitions the crowd's stock makes.
    pub seam_halflife_s: f32,
    /// Walkers at accuracy levels below this have their feet planted.
    pub foot_lock_levels: usize,
}

/// One walker: its path, cycle base frame, current clip and the seam transition into it.
///
/// Laid out in declaration order (`repr(C)`) so that what every frame reads of a walker far
/// away or out of view (its clock, placement, detail and clip handles) shares the first cache
/// lines; what only a cycle end reads (path, controls, root motion) comes last.
#[derive(Debug, Clone)]
#[repr(C)]
pub(crate) struct Walker<C> {
    /// Seconds into the current cycle.
    pub t: f32,
    pub cur_dur: f32,
    /// Seconds left before a mid-cycle refinement is allowed: spreads the clip builds of a new
    /// crowd's first frames over its first cycle (0 once the walker has switched clips).
    pub hold_s: f32,
    /// Clip time at which the running seam started (its clock is `t - seam_start`).
    pub seam_start: f32,
    /// World root position after the last frame.
    pub root: Vec3,
    pub height: f32,
    /// The current cycle frame (origin and heading, in double precision: `lod_policy::CycleFrame`),
    /// chained by each clip's root motion ([`CycleFrame::next`]).
    pub frame: CycleFrame,
    /// The frame's heading's `sin_cos()` in single precision, kept with it (the FK stage rotates
    /// every walker's points every frame).
    pub heading_sc: (f32, f32),
    /// Rows of the pose vector written this frame.
    pub rows: usize,
    /// Joint positions written this frame.
    pub n_joints: usize,
    /// The walker's foot lock (`lod_policy::FootLock`, 240 bytes), lent by the crowd's stock
    /// ([`Lender`]) while it is near enough to plant its feet and given back (released) when
    /// it leaves: far and culled walkers hold no lock state.
    pub lock: Option<Box<FootLock>>,
    /// The inertialized seam into the current clip (`lod_policy::SeamTransition`), lent by the
    /// crowd's stock while a seam runs and given back when it ends: far and culled walkers never
    /// hold its `3 P` floats.
    pub seam: Option<Box<SeamTransition>>,
    pub cur_detail: Detail,
    pub cur: C,
    // Read at cycle ends only.
    pub path: EllipsePath,
    /// Path parameter closest to the current cycle frame's origin (double precision, as the
    /// frame: [`crate::path::path_controls`]).
    pub s: f64,
    /// Preferred forward displacement per cycle (m).
    pub stride: f32,
    pub controls: Controls,
    pub cur_motion: RootMotion,
}

/// The single-precision `(sin, cos)` of a cycle frame's heading, computed in double: what
/// [`Walker::heading_sc`] caches.
pub(crate) fn heading_sin_cos(frame: &CycleFrame) -> (f32, f32) {
    to_single(frame.heading.sin_cos())
}

/// A `(sin, cos)` computed in double, rounded to single: [`Walker::heading_sc`]'s precision.
fn to_single((sin, cos): (f64, f64)) -> (f32, f32) {
    (sin as f32, cos as f32)
}

/// `slot.take()`, without writing to `slot` when it holds nothing: most walkers hold no seam or
/// lock, and asking every frame must not dirty their memory.
#[inline]
fn take_held<T>(slot: &mut Option<T>) -> Option<T> {
    if slot.is_some() { slot.take() } else { None }
}

/// Duration check: finite and at least 1 ms.
pub(crate) fn valid_duration(d: f32) -> bool {
    d.is_finite() && d >= 1e-3
}

/// What one walker's kernel stage did: clips built, and clips the source failed to build (the
/// walker kept its previous clip) with the first error.
#[derive(Debug, Default)]
pub(crate) struct Advance {
    pub built: usize,
    pub faults: usize,
    pub fault: Option<ClipError>,
}

impl Advance {
    fn count(&mut self, outcome: Option<ClipError>) {
        match outcome {
            None => self.built += 1,
            Some(e) => {
                self.faults += 1;
                self.fault.get_or_insert(e);
            }
        }
    }
}

/// A failure found while running a stage for one walker.
#[derive(Debug, Clone, Copy)]
pub(crate) enum WalkerFault {
    Duration(f32),
    /// The policy's detail, which the source's level table does not have.
    Level(Detail),
}

impl<C> Walker<C> {
    /// Whether a change from `old` to `new` is inertialized: both have joints and `new` is one of
    /// the first `seam_levels` accuracy levels (farther walkers switch clips as they are).
    fn seams(p: &StageParams, new: &Detail, old: &Detail) -> bool {
        new.accuracy < p.seam_levels && new.active_joints > 0 && old.active_joints > 0
    }

    /// The pose the walker shows at clip time `t`: the current clip's pose with the running seam
    /// applied. Returns the rows written.
    /// Joints the seam fades out (dropped by the current clip) are shown beyond the clip's rows.
    fn displayed<S: ClipSource<Clip = C>>(&self, src: &S, t: f32, out: &mut [f32]) -> usize {
        let rows = src.pose(&self.cur, t, out).min(out.len());
        let Some(seam) = self.seam.as_deref() else {
            return rows;
        };
        let rows = seam.fill_beyond(rows, out);
        seam.apply(t - self.seam_start, &mut out[..rows]);
        rows
    }

    /// Ends the running seam, if any (its transition goes back to the stock).
    fn clear_seam(&mut self, stock: &mut Lender<'_, C>) {
        if let Some(seam) = take_held(&mut self.seam) {
            stock.give_seam(seam);
        }
        self.seam_start = 0.0;
    }

    /// Whether a seam transition is running.
    pub fn in_transition(&self) -> bool {
        self.seam.as_deref().is_some_and(SeamTransition::is_active)
    }

    /// Rebuilds `cur` for `self.controls` at `d` (in place: the outgoing clip's state has been
    /// captured before when a seam follows). When `d` needs another size class of clip than the
    /// one held ([`ClipSource::clip_class`]), the clip is exchanged for one of that class from
    /// `stock` and built there; the walker's goes back to the stock. `Ok(Some(error))` when the
    /// source could not build it: `cur` is then the previous clip, unchanged.
    fn rebuild<S: ClipSource<Clip = C>>(
        &mut self,
        src: &S,
        d: Detail,
        stock: &mut Lender<'_, C>,
    ) -> Result<Option<ClipError>, WalkerFault> {
        let (class, held_class) = (src.clip_class(&d), src.clip_class(&self.cur_detail));
        if class != held_class {
            // `held` is a spare of the stock now holding the walker's clip.
            let mut held = stock.clip(src, &mut self.cur, class);
            if let Err(e) = src.build_clip(&self.controls, d, &mut self.cur) {
                std::mem::swap(&mut self.cur, &mut *held);
                stock.give_clip(held, class);
                return Ok(Some(e));
            }
            stock.give_clip(held, held_class);
        } else if let Err(e) = src.build_clip(&self.controls, d, &mut self.cur) {
            return Ok(Some(e));
        }
        let dur = src.clip_duration(&self.cur);
        if !valid_duration(dur) {
            return Err(WalkerFault::Duration(dur));
        }
        self.cur_detail = d;
        self.cur_dur = dur;
        self.cur_motion = src.clip_root_motion(&self.cur);
        Ok(None)
    }

    /// Replaces the current clip by one at `d` (and `self.controls`), shown from clip phase
    /// `phase` of the new clip; with `seam`, the change is inertialized from the displayed state at
    /// clip time `t_out` of the outgoing clip (in the next cycle frame when `motion` is given).
    ///
    /// When the source cannot build the new clip (`Ok(Some(error))`), the walker keeps the
    /// previous one: mid-cycle it plays on with its running seam; at a cycle end it replays from
    /// the start in the next cycle frame, switched as it is (no seam).
    #[allow(clippy::too_many_arguments)]
    fn switch<S: ClipSource<Clip = C>>(
        &mut self,
        src: &S,
        d: Detail,
        stock: &mut Lender<'_, C>,
        seam: Option<&StageParams>,
        t_out: f32,
        motion: Option<&RootMotion>,
        phase: f32,
    ) -> Result<Option<ClipError>, WalkerFault> {
        let failed = match seam {
            Some(p) => {
                let (dur_out, this) = (self.cur_dur, &*self);
                let captured = stock.scratch.capture(t_out, dur_out, motion, |t, out| {
                    Ok::<usize, std::convert::Infallible>(this.displayed(src, t, out))
                });
                let Ok(()) = captured;
                if let Some(e) = self.rebuild(src, d, stock)? {
                    if motion.is_some() {
                        self.clear_seam(stock);
                    }
                    return Ok(Some(e));
                }
                let t_in = phase * self.cur_dur;
                let cur = &self.cur;
                // A walker without a running seam borrows a transition from the stock.
                let transition = self
                    .seam
                    .get_or_insert_with(|| stock.seam(p.levels.pose_len, p.seam_halflife_s));
                let started = stock.scratch.start_from_rest(
                    t_in,
                    self.cur_dur,
                    |t, out| Ok::<usize, std::convert::Infallible>(src.pose(cur, t, out)),
                    src.rest_rows(),
                    transition,
                );
                let Ok(()) = started;
                self.seam_start = t_in;
                None
            }
            None => {
                let failed = self.rebuild(src, d, stock)?;
                if failed.is_none() || motion.is_some() {
                    self.clear_seam(stock);
                }
                failed
            }
        };
        Ok(failed)
    }

    /// Before a crowd's first frame: the clip held becomes one at `d` (the policy's answer for where
    /// the walker starts, checked against the level table) when that is finer, built at once
    /// without a seam (nothing was shown yet) at the same phase of the cycle, and the spread of
    /// first builds is cancelled. Returns the kernels built and the builds that failed.
    pub fn prime<S: ClipSource<Clip = C>>(
        &mut self,
        src: &S,
        p: &StageParams,
        d: Detail,
        stock: &mut Lender<'_, C>,
    ) -> Result<Advance, WalkerFault> {
        let d = p.levels.check(&d).ok_or(WalkerFault::Level(d))?;
        let mut done = Advance::default();
        self.hold_s = 0.0;
        if d.is_finer_than(&self.cur_detail) {
            let u = self.t / self.cur_dur;
            let failed = self.switch(src, d, stock, None, self.t, None, u)?;
            if failed.is_none() {
                self.t = (u * self.cur_dur).min(self.cur_dur * 0.999_999);
            }
            done.count(failed);
        }
        Ok(done)
    }

    /// Places the root where the current clip puts it at the walker's clip time `t` (its pose's
    /// root rows, `out` a pose buffer of `levels().pose_len`), as the FK stage would, without
    /// showing a pose: [`crate::Crowd::prime`] asks the policy from there before the first frame.
    pub fn place_root<S: ClipSource<Clip = C>>(&mut self, src: &S, out: &mut [f32]) {
        let rows = src.pose(&self.cur, self.t, out).min(out.len());
        if rows < 3 {
            return;
        }
        self.root = self.to_world(Vec3::new(out[0], out[1], out[2]));
    }

    /// A point of the current cycle frame in the world: `(x, z) + R_y(h) p` with
    /// `R_y(h) (x, y, z) = (x cos h + z sin h, y, -x sin h + z cos h)`, rotated in single precision
    /// and moved in double ([`CycleFrame::to_world`]), then rounded to single.
    #[inline]
    fn to_world(&self, p: Vec3) -> Vec3 {
        let (sh, ch) = self.heading_sc;
        Vec3::new(
            (self.frame.x + f64::from(p.x * ch + p.z * sh)) as f32,
            p.y,
            (self.frame.z + f64::from(-p.x * sh + p.z * ch)) as f32,
        )
    }

    /// Kernel stage: advance time by `dt`; at each cycle end move the cycle frame by the clip's
    /// root motion, pick controls from the path ahead and build the next clip at `d`, with an
    /// inertialized seam at the first `seam_levels` levels; mid-cycle, rebuild at once when `d` is
    /// finer than the clip held (inertialized likewise), except while `hold_s` (a new crowd's
    /// spread of first builds) runs. `d` is the policy's answer, checked here against the source's
    /// level table ([`LevelTable::check`]). `stock` lends clips and seam transitions ([`Lender`],
    /// with the chunk's seam scratch).
    /// Returns the kernels built and the builds that failed.
    pub fn advance<S: ClipSource<Clip = C>>(
        &mut self,
        src: &S,
        p: &StageParams,
        d: Detail,
        dt: f32,
        stock: &mut Lender<'_, C>,
    ) -> Result<Advance, WalkerFault> {
        let d = p.levels.check(&d).ok_or(WalkerFault::Level(d))?;
        let mut done = Advance::default();
        self.t += dt;
        while self.t >= self.cur_dur {
            let m = self.cur_motion;
            let end = self.cur_dur;
            self.t -= end;
            self.frame = self.frame.next(&m);
            // The heading's and the path's sines once for the cycle frame, the closest point and
            // the controller (the same values each computed before).
            let heading_sc = self.frame.heading.sin_cos();
            self.heading_sc = to_single(heading_sc);
            let rot = self.path.rotation_f64();
            let origin = DVec2::new(self.frame.x, self.frame.z);
            self.s = self.path.closest_param_near_rotated(rot, origin, self.s);
            let held = self.controls;
            self.controls = path_controls_rotated(
                &self.path,
                rot,
                self.s,
                origin,
                (self.frame.heading, heading_sc),
                self.stride,
                self.height,
                &p.bounds,
            )
            .with_style(held.style);
            let seam = Self::seams(p, &d, &self.cur_detail).then_some(p);
            let failed = self.switch(src, d, stock, seam, end, Some(&m), 0.0)?;
            if failed.is_some() {
                // The previous clip plays on: its controls stay the walker's.
                self.controls = held;
            }
            done.count(failed);
            self.hold_s = 0.0;
        }
        if self.hold_s > 0.0 {
            self.hold_s -= dt;
        }
        if done.built + done.faults == 0 && self.hold_s <= 0.0 && d.is_finer_than(&self.cur_detail)
        {
            self.hold_s = 0.0;
            let u = self.t / self.cur_dur;
            let seam = Self::seams(p, &d, &self.cur_detail).then_some(p);
            let t_out = self.t;
            let failed = self.switch(src, d, stock, seam, t_out, None, u)?;
            if failed.is_none() {
                self.t = (u * self.cur_dur).min(self.cur_dur * 0.999_999);
            }
            done.count(failed);
        }
        Ok(done)
    }

    /// Pose stage: the current clip's pose at `t` with the running seam applied (the seam ends
    /// once its offset has decayed); then, for a `visible` walker at one of the first
    /// `foot_lock_levels` accuracy levels with joints, planted feet ([`ClipSource::plant_feet`];
    /// `dt` is the frame step). A walker that leaves those levels or the view releases its lock: its
    /// feet are let go at once (nobody sees it, or its clip switches without a seam there). A seam
    /// that ends and a lock released go back to `stock`; a lock is borrowed from it.
    pub fn pose<S: ClipSource<Clip = C>>(
        &mut self,
        src: &S,
        p: &StageParams,
        dt: f32,
        visible: bool,
        out: &mut [f32],
        stock: &mut Lender<'_, C>,
    ) {
        self.rows = self.displayed(src, self.t, out);
        let clock = self.t - self.seam_start;
        if self
            .seam
            .as_deref_mut()
            .is_some_and(|seam| !seam.finish_after(clock))
        {
            self.clear_seam(stock);
        }
        let near = visible
            && self.cur_detail.accuracy < p.foot_lock_levels
            && self.cur_detail.active_joints > 0;
        if !near {
            if let Some(lock) = take_held(&mut self.lock) {
                stock.give_lock(lock);
            }
            return;
        }
        let frame = self.frame;
        let lock = self.lock.get_or_insert_with(|| stock.lock());
        let rows = self.rows;
        src.plant_feet(&self.cur, &frame, dt, lock, &mut out[..rows]);
    }

    /// FK stage: cycle-frame joint positions from the source, then placed in the world by the
    /// cycle frame (`to_world`).
    pub fn place<S: ClipSource<Clip = C>>(&mut self, src: &S, pose: &[f32], out: &mut [Vec3]) {
        let n = src
            .joints(&self.cur, &pose[..self.rows], out)
            .min(out.len());
        for q in &mut out[..n] {
            *q = self.to_world(*q);
        }
        self.n_joints = n;
        if n > 0 {
            self.root = out[0];
        }
    }
}
