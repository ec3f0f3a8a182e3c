//! The naive baseline as a crowd clip source: the aligned samples blended directly with the kriging
//! weights (paper eq. 1 with the universal kriging kernel of eq. 8), no tensor and no accuracy levels.
//!
//! Per clip it evaluates universal kriging of the raw samples in its dual form
//! (`sample_weights::DualBlend`): `S` variogram values and `O(S D')` multiply-adds for the
//! `D' = P' T` values of the clip's rows (`P'` the rows of its active joints, 7 for a root-only
//! clip), the same result as computing the kriging weights `b(c)` (`O(S^2)`), the equivalent sample
//! weights `l(c) = b + C^+ ([c'; 1] - C b)` and the blend `sum_i l_i M_i`, without the `O(S^2)` step.
//! Per frame it interpolates two aligned frames of those rows (`O(P')`).
//!
//! It gets the same culling and root-only policy as the model ([`crate::LodSource`]): it reports the
//! model's accuracy levels so that the crowd's policy applies unchanged, evaluates only the rows of the
//! active joints (root only beyond the last level or outside the view) and runs forward kinematics of
//! those joints only; it has no cheaper accuracy level, so every clip with joints blends the full
//! samples. What the paper compares its LOD against ("naive interpolation", 3.9 fps for 100 walkers)
//! is this source with every walker at full detail ([`lod_policy::FullDetail`]).

use crowd_sim::{ClipError, ClipSource, LevelTable};
use faer::Mat;
use glam::Vec3;
use lod_policy::TimeTable;
use lod_policy::{ControlRange, Controls, Detail, RootMotion};

use crate::build::{Analysis, BuildError};
use crate::model::{MotionModel, TIME_ROW};
use crate::sample_weights::DualBlend;
use crate::source::{bones_of, write_joints};

/// One walker's naive clip: the blended rows of its detail over the aligned frames, and its time
/// table.
#[derive(Debug, Clone)]
pub struct NaiveClip {
    /// `rows x T` blended values, row-major (row `r`'s frames at `r T`; time row in seconds).
    /// A buffer of `P x T` entries or more (a clip of class 1, with joints:
    /// [`ClipSource::new_clip_of_class`]) is kept whatever the clip holds, so that building into
    /// it never allocates.
    values: Vec<f32>,
    /// Pose rows held (`P'`).
    rows: usize,
    /// Joints after the root drawn by `joints`.
    active_joints: usize,
    times: TimeTable,
    root_motion: RootMotion,
    /// The body scale of the clip's controls ([`crate::MotionModel::body_scale`]).
    body_scale: f32,
}

impl NaiveClip {
    /// The clip's time table (aligned frame to seconds), from the blended time row.
    pub fn times(&self) -> &TimeTable {
        &self.times
    }

    /// Pose rows this clip holds and writes (`P'`).
    pub fn rows(&self) -> usize {
        self.rows
    }
}

/// Naive kriging interpolation of the raw samples, as a crowd clip source.
#[derive(Debug)]
pub struct NaiveSource<'m> {
    model: &'m MotionModel,
    /// The samples' universal kriging in dual form, outputs ordered row by row (`r T + frame`).
    blend: DualBlend,
    /// The rest rows joints fade to and from at seams ([`ClipSource::rest_rows`]).
    rest: Vec<f32>,
    bones: Vec<(usize, usize)>,
}

impl<'m> NaiveSource<'m> {
    /// A naive source over the samples of `analysis` (the data `model` was built from).
    ///
    /// Errors: [`BuildError::Data`] when the analysis's tensor does not have the model's `P x T x S`
    /// shape; [`BuildError::Kriging`] when the dual form cannot be set up (non-finite samples).
    pub fn new(
        model: &'m MotionModel,
        analysis: &'m Analysis,
    ) -> Result<NaiveSource<'m>, BuildError> {
        let lod = model.lod();
        let [p, t, s] = analysis.tensor.dims();
        if [p, t, s] != [lod.p(), lod.t(), lod.s()] || analysis.kriging.n_samples() != s {
            return Err(BuildError::Data(format!(
                "analysis tensor {:?} ({} kriging samples) does not match the model's P x T x S = {:?}",
                [p, t, s],
                analysis.kriging.n_samples(),
                [lod.p(), lod.t(), lod.s()]
            )));
        }
        let inv_scale = 1.0 / analysis.time_scale;
        let x = analysis.tensor.as_slice();
        // Sample i, pose row r, frame f at output r T + f (time row in seconds).
        let values = Mat::from_fn(s, p * t, |i, o| {
            let (r, f) = (o / t, o % t);
            let v = x[(i * t + f) * p + r];
            if r == TIME_ROW { v * inv_scale } else { v }
        });
        Ok(NaiveSource {
            model,
            blend: DualBlend::new(&analysis.kriging, &values)?,
            bones: bones_of(&model.layout),
            rest: crate::source::rest_rows_of(model),
        })
    }

    fn dims(&self) -> (usize, usize) {
        let lod = self.model.lod();
        (lod.p(), lod.t())
    }

    /// Rows `0..out.len()` of the clip's pose at fractional aligned frame `phase`.
    fn frame(&self, clip: &NaiveClip, phase: f64, out: &mut [f32]) {
        let (_, t) = self.dims();
        let phase = phase.clamp(0.0, (t - 1) as f64);
        let i = (phase.floor() as usize).min(t.saturating_sub(2));
        let i1 = (i + 1).min(t - 1);
        let a = (phase - i as f64) as f32;
        for (o, row) in out.iter_mut().zip(clip.values.chunks_exact(t)) {
            *o = (1.0 - a) * row[i] + a * row[i1];
        }
    }
}

impl ClipSource for NaiveSource<'_> {
    type Clip = NaiveClip;

    fn levels(&self) -> LevelTable {
        crate::source::level_table(self.model)
    }

    fn control_range(&self) -> ControlRange {
        crate::source::control_range(self.model)
    }

    fn new_clip(&self) -> NaiveClip {
        let (_, t) = self.dims();
        let rows = self.model.lod().always_rows();
        NaiveClip {
            values: vec![0.0; rows * t],
            rows,
            active_joints: 0,
            times: TimeTable::with_capacity(t),
            root_motion: RootMotion::default(),
            body_scale: 1.0,
        }
    }

    /// Clips come in two size classes: root-only (`7 x T` values) and with joints (`P x T`).
    fn clip_classes(&self) -> usize {
        2
    }

    fn clip_class(&self, detail: &Detail) -> usize {
        usize::from(detail.active_joints > 0)
    }

    fn new_clip_of_class(&self, class: usize) -> NaiveClip {
        let mut clip = self.new_clip();
        if class == 0 {
            return clip;
        }
        let (p, t) = self.dims();
        clip.values.reserve_exact(p * t - clip.values.len());
        clip
    }

    fn build_clip(
        &self,
        controls: &Controls,
        detail: Detail,
        clip: &mut NaiveClip,
    ) -> Result<(), ClipError> {
        let (p, t) = self.dims();
        let lod = self.model.lod();
        clip.active_joints = detail.active_joints.min(lod.joints());
        clip.rows = lod.active_rows(clip.active_joints).min(p);
        // Sized for the clip's rows (a root-only clip holds 7 T values); a buffer of all `P T`
        // values (a clip for joints) is kept.
        let need = clip.rows * t;
        let cap = clip.values.capacity();
        if cap < need || (cap > 2 * need && cap < p * t) {
            clip.values = Vec::with_capacity(need);
        }
        clip.values.resize(need, 0.0);
        let mut raw = [0.0f32; lod_policy::CONTROL_VALUES];
        let d = lod
            .control_vector(controls, &mut raw)
            .map_err(|e| ClipError(e.to_string()))?;
        let raw = raw.map(f64::from);
        self.blend.eval(&raw[..d], &mut clip.values);
        clip.times.fill_from_iter(
            clip.values[TIME_ROW * t..][..t]
                .iter()
                .map(|&v| f64::from(v)),
        );
        let (mut start, mut end) = ([0.0f32; 6], [0.0f32; 6]);
        self.frame(clip, 0.0, &mut start);
        self.frame(clip, (t - 1) as f64, &mut end);
        clip.root_motion = lod.controls().root_motion(controls, &start, &end);
        clip.body_scale = self.model.body_scale(controls);
        Ok(())
    }

    fn clip_duration(&self, clip: &NaiveClip) -> f32 {
        (clip.times.duration() as f32).max(1e-3)
    }

    fn clip_root_motion(&self, clip: &NaiveClip) -> RootMotion {
        clip.root_motion
    }

    fn pose(&self, clip: &NaiveClip, t_seconds: f32, out: &mut [f32]) -> usize {
        let phase = clip.times.phase_at(f64::from(t_seconds));
        let rows = clip.rows.min(out.len());
        self.frame(clip, phase, &mut out[..rows]);
        rows
    }

    fn plant_feet(
        &self,
        clip: &NaiveClip,
        frame: &lod_policy::CycleFrame,
        dt: f32,
        lock: &mut lod_policy::FootLock,
        pose: &mut [f32],
    ) {
        crate::source::plant_feet(
            self.model,
            clip.active_joints,
            clip.body_scale,
            frame,
            dt,
            lock,
            pose,
        );
    }

    fn joints(&self, clip: &NaiveClip, pose: &[f32], out: &mut [Vec3]) -> usize {
        write_joints(
            &self.model.layout,
            pose,
            clip.active_joints,
            clip.body_scale,
            out,
        )
    }

    fn rest_rows(&self) -> &[f32] {
        &self.rest
    }

    fn bones(&self) -> &[(usize, usize)] {
        &self.bones
    }
}
