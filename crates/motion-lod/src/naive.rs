//! The naive baseline as a crowd clip source: the aligned samples blended directly with the kriging
//! weights (paper eq. 1 with the universal kriging kernel of eq. 8), no tensor and no level of detail.
//!
//! Per clip it computes the kriging weights `b(c)` from the full `(S+1) x (S+1)` system (`O(S^2)`), the
//! equivalent sample weights of eq. 8, `l(c) = C^+ [c; 1] + (I - C^+ C) b(c)`, and the blended cycle
//! `sum_i l_i M_i` (`O(P T S)`); per frame it interpolates two aligned frames (`O(P)`). This is what the
//! paper compares its LOD against ("naive interpolation", 3.9 fps for 100 walkers).

use crowd_sim::{
    ClipSource, ControlBounds, Controls, Detail as CrowdDetail, LevelTable, RootMotion,
};
use glam::Vec3;
use kriging::Kriging;
use timewarp::TimeTable;

use crate::build::Analysis;
use crate::model::{MotionModel, TIME_ROW};
use crate::sample_weights::SampleWeights;
use crate::source::{bones_of, write_joints};

/// One walker's naive clip: the blended aligned cycle and its time table.
#[derive(Debug, Clone)]
pub struct NaiveClip {
    /// `T x P` blended poses (row-major, time row in seconds).
    poses: Vec<f32>,
    times: TimeTable,
    /// Sample weights `b(c)` (scratch, length S).
    b: Vec<f64>,
    /// Equivalent sample weights `l(c)` (scratch, length S).
    l: Vec<f64>,
    root_motion: RootMotion,
}

impl NaiveClip {
    /// The clip's time table (aligned frame to seconds), from the blended time row.
    pub fn times(&self) -> &TimeTable {
        &self.times
    }
}

/// Naive kriging interpolation of the raw samples, as a crowd clip source.
#[derive(Debug)]
pub struct NaiveSource<'m> {
    model: &'m MotionModel,
    kriging: &'m Kriging,
    /// Samples, `S` blocks of `T x P` f32 (time row in seconds).
    samples: Vec<f32>,
    /// `C` and `C^+` of the kriging trend, for the sample weights of eq. 8.
    weights: SampleWeights,
    bones: Vec<(usize, usize)>,
}

impl<'m> NaiveSource<'m> {
    /// A naive source over the samples of `analysis` (the data `model` was built from).
    pub fn new(model: &'m MotionModel, analysis: &'m Analysis) -> NaiveSource<'m> {
        let [p, t, s] = analysis.tensor.dims();
        let inv_scale = 1.0 / analysis.time_scale;
        let mut samples = Vec::with_capacity(p * t * s);
        for pose in analysis.tensor.as_slice().chunks_exact(p) {
            samples.extend(pose.iter().enumerate().map(|(r, &v)| {
                if r == TIME_ROW {
                    (v * inv_scale) as f32
                } else {
                    v as f32
                }
            }));
        }
        NaiveSource {
            model,
            kriging: &analysis.kriging,
            samples,
            weights: SampleWeights::new(&analysis.kriging),
            bones: bones_of(&model.layout),
        }
    }

    fn dims(&self) -> (usize, usize, usize, usize) {
        let lod = &self.model.lod;
        (lod.p(), lod.t(), lod.s(), lod.d())
    }
}

impl ClipSource for NaiveSource<'_> {
    type Clip = NaiveClip;

    fn levels(&self) -> LevelTable {
        LevelTable {
            accuracy_levels: 1,
            joints: self.model.lod.joints(),
            pose_len: self.model.lod.p(),
        }
    }

    fn control_bounds(&self) -> ControlBounds {
        crate::source::LodSource::new(self.model).control_bounds()
    }

    fn new_clip(&self) -> NaiveClip {
        let (p, t, s, _) = self.dims();
        NaiveClip {
            poses: vec![0.0; p * t],
            times: TimeTable::with_capacity(t),
            b: vec![0.0; s],
            l: vec![0.0; s],
            root_motion: RootMotion::default(),
        }
    }

    fn build_clip(&self, controls: &Controls, _detail: CrowdDetail, clip: &mut NaiveClip) {
        let (p, t, _, _) = self.dims();
        let c = crate::sample_weights::control_vector(controls);
        self.weights
            .compute(self.kriging, &c, &mut clip.b, &mut clip.l);
        clip.poses.fill(0.0);
        let block = p * t;
        for (i, &w) in clip.l.iter().enumerate() {
            let w = w as f32;
            for (o, &v) in clip
                .poses
                .iter_mut()
                .zip(&self.samples[i * block..(i + 1) * block])
            {
                *o += w * v;
            }
        }
        clip.times
            .fill_from_iter((0..t).map(|k| f64::from(clip.poses[k * p + TIME_ROW])));
        clip.root_motion = root_motion_between(
            self.model,
            controls,
            &clip.poses[..p],
            &clip.poses[(t - 1) * p..],
        );
    }

    fn clip_duration(&self, clip: &NaiveClip) -> f32 {
        (clip.times.duration() as f32).max(1e-3)
    }

    fn clip_root_motion(&self, clip: &NaiveClip) -> RootMotion {
        clip.root_motion
    }

    fn pose(&self, clip: &NaiveClip, t_seconds: f32, out: &mut [f32]) -> usize {
        let (p, t, _, _) = self.dims();
        let phase = clip
            .times
            .phase_at(f64::from(t_seconds))
            .clamp(0.0, (t - 1) as f64);
        let i = (phase.floor() as usize).min(t.saturating_sub(2));
        let a = (phase - i as f64) as f32;
        let (f0, f1) = (
            &clip.poses[i * p..(i + 1) * p],
            &clip.poses[(i + 1).min(t - 1) * p..][..p],
        );
        for ((o, &x), &y) in out[..p].iter_mut().zip(f0).zip(f1) {
            *o = (1.0 - a) * x + a * y;
        }
        p
    }

    fn joints(&self, _clip: &NaiveClip, pose: &[f32], out: &mut [Vec3]) -> usize {
        write_joints(&self.model.layout, pose, usize::MAX, out)
    }

    fn bones(&self) -> &[(usize, usize)] {
        &self.bones
    }
}

/// Root motion of a clip built for `controls` from its first and last pose: the model's one rule
/// ([`lod_policy::ControlSpace::root_motion`]).
pub(crate) fn root_motion_between(
    model: &MotionModel,
    controls: &Controls,
    start: &[f32],
    end: &[f32],
) -> RootMotion {
    let c = [controls.dx, controls.dz, controls.turn, controls.height];
    model.lod.controls().root_motion(&c, start, end)
}
