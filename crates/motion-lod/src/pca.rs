//! The PCA baseline as a crowd clip source: the samples reduced to their leading principal joint-DOF
//! directions, blended with the kriging weights, with the number of components lowered per accuracy
//! level (paper section 5.1, last paragraph: "The data dimensionality of joint DOF is decreased from
//! P = 94 to R_P,max = 40 by truncating higher-dimensional principal components that are analyzed by a
//! matrix SVD. The number of principal components R_P < R_P,max is adaptively reduced in the runtime
//! computation of a pose vector synthesis").
//!
//! Offline ([`PcaSource::new`]): `U` (`P x R`) holds the first `R = min(R_max, P)` left singular vectors
//! of the DOF-mode unfolding `X_(1)` (`P x T S`, uncentred, time row scaled as in the analysis; computed
//! by [`pca_basis`], which the leave-one-out PCA baseline of [`crate::eval`] uses too), and every sample
//! keeps its coefficients `Y_i = U^T M_i` (`R x T`). Storage: `P R + S T R` values ([`PcaSource::bytes`]).
//!
//! Accuracy levels: as many as the model has (`L`); level `l` keeps the `r_l` leading components,
//! decreasing linearly from `R` at level 0 to the model's last-level `R_P` (clamped into `1..=R`):
//! `r_l = R - round((R - R_P,last) l / (L - 1))`. A root-only walker uses the last level, as the
//! model's [`crate::LodSource`] does.
//!
//! Per clip: `Y(c) = sum_i l_i(c) Y_i[:r_l, :]` with `l(c)` the equivalent kriging sample weights of
//! eq. 8, evaluated in the dual form of universal kriging as [`crate::NaiveSource`] does
//! (`S` variogram values and `O(S T r_l)` multiply-adds, no `O(S^2)` kriging weights), the time table
//! from the time row of `U Y(c)` (`O(T r_l)`) and the root motion from frames `0` and `T-1`. Per frame: `y = (1-a) y_k + a y_{k+1}`
//! from two frames of `Y(c)`, expanded as `U[:P', :r_l] y` into the caller's slice (`O(P' r_l)`, no
//! allocation), with `P'` the rows of the active joints (the 7 root rows for a root-only walker).

use crowd_sim::{ClipError, ClipSource, LevelTable};
use faer::Mat;
use glam::Vec3;
use lod_policy::TimeTable;
use lod_policy::{ALWAYS_ROWS, ControlRange, Controls, Detail, Precision, RootMotion};
use tensor_ops::Tensor3;

use crate::build::{Analysis, BuildError};
use crate::model::{MotionModel, TIME_ROW};
use crate::sample_weights::DualBlend;
use crate::source::{bones_of, write_joints};

/// Components interpolated at once in [`ClipSource::pose`] (a stack buffer; any rank is handled in
/// chunks of this size).
const CHUNK: usize = 64;

/// The first `rank` (clamped into `1..=P`) principal directions of the DOF mode of `x` (`P x T x S`):
/// the leading left singular vectors of the unfolding `X_(1)` (`P x T S`), without centring, as the
/// paper's matrix SVD (section 5.1), columns by decreasing singular value. Returned as `P x R`.
///
/// Computed as the DOF factor of the truncated HOSVD at ranks `(R, T, S)` (eq. 3), whose mode-1 factor
/// is exactly that matrix SVD's; errors come from the decomposition (empty or non-finite tensor).
pub fn pca_basis(x: &Tensor3, rank: usize) -> Result<Mat<f64>, BuildError> {
    let [p, t, s] = x.dims();
    let r = rank.clamp(1, p.max(1));
    let [u, _, _] = hosvd_als::hosvd(x, [r, t, s])?.factors;
    debug_assert_eq!((u.nrows(), u.ncols()), (p, r));
    Ok(u)
}

/// One walker's PCA clip: the blended coefficients `Y(c)` of its level and its time table.
#[derive(Debug, Clone)]
pub struct PcaClip {
    /// `rank x T` blended coefficients, component-major (component `j`'s frames at `j T`).
    coeffs: Vec<f32>,
    /// Components used by this clip (`r_l`).
    rank: usize,
    /// Pose rows written by `pose` (`P'`).
    rows: usize,
    /// Joints after the root drawn by `joints`.
    active_joints: usize,
    times: TimeTable,
    root_motion: RootMotion,
    /// The body scale of the clip's controls ([`crate::MotionModel::body_scale`]).
    body_scale: f32,
}

impl PcaClip {
    /// Principal components this clip uses (`r_l` of its level).
    pub fn rank(&self) -> usize {
        self.rank
    }

    /// Pose rows this clip writes (`P'`).
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// The clip's time table (aligned frame to seconds), from the time row of `U Y(c)`.
    pub fn times(&self) -> &TimeTable {
        &self.times
    }
}

/// The samples reduced by PCA and blended with the kriging weights, as a crowd clip source.
#[derive(Debug)]
pub struct PcaSource<'m> {
    model: &'m MotionModel,
    /// Universal kriging of the coefficients in dual form, outputs component by component
    /// (`j T + frame`), so that the first `r_l` components are a prefix.
    blend: DualBlend,
    /// `D^-1 U`, `P x R` row-major: `U` with its time row divided by `time_scale`, so that `D^-1 U y`
    /// holds seconds in the time row.
    basis: Vec<f32>,
    /// `Y_i = U^T M_i` of every sample: `S` blocks of `T x R`, frame-major.
    coeffs: Vec<f32>,
    /// `R`.
    rank: usize,
    /// `r_l` per accuracy level.
    level_ranks: Vec<usize>,
    /// The rest rows joints fade to and from at seams ([`ClipSource::rest_rows`]).
    rest: Vec<f32>,
    bones: Vec<(usize, usize)>,
}

/// `r_l = R - round((R - r_last) l / (L - 1))` for `l` in `0..L` (`R` alone when `L <= 1`).
fn level_schedule(r: usize, r_last: usize, levels: usize) -> Vec<usize> {
    let r_last = r_last.clamp(1, r);
    let span = levels.saturating_sub(1);
    (0..levels.max(1))
        .map(|l| r - ((r - r_last) * l + span / 2).checked_div(span).unwrap_or(0))
        .collect()
}

impl<'m> PcaSource<'m> {
    /// A PCA source with `rank_max` components (the paper: 40; clamped into `1..=P`) over the samples of
    /// `analysis` (the data `model` was built from).
    ///
    /// Errors: [`BuildError::Data`] when the analysis's tensor does not have the model's `P x T x S`
    /// shape or its time scale is not a positive number; [`BuildError::Decomposition`] when the
    /// basis cannot be computed (non-finite data).
    pub fn new(
        model: &'m MotionModel,
        analysis: &'m Analysis,
        rank_max: usize,
    ) -> Result<PcaSource<'m>, BuildError> {
        let lod = model.lod();
        let [p, t, s] = analysis.tensor.dims();
        if [p, t, s] != [lod.p(), lod.t(), lod.s()] {
            return Err(BuildError::Data(format!(
                "analysis tensor {:?} does not match the model's P x T x S = {:?}",
                [p, t, s],
                [lod.p(), lod.t(), lod.s()]
            )));
        }
        if analysis.kriging.n_samples() != s {
            return Err(BuildError::Data(format!(
                "kriging over {} samples for {s} samples",
                analysis.kriging.n_samples()
            )));
        }
        if !(analysis.time_scale.is_finite() && analysis.time_scale > 0.0) {
            return Err(BuildError::Data(format!(
                "time scale {} is not a positive number",
                analysis.time_scale
            )));
        }
        let u = pca_basis(&analysis.tensor, rank_max)?;
        let r = u.ncols();
        let inv_scale = 1.0 / analysis.time_scale;
        let mut basis = Vec::with_capacity(p * r);
        for row in 0..p {
            let scale = if row == TIME_ROW { inv_scale } else { 1.0 };
            basis.extend((0..r).map(|j| (u[(row, j)] * scale) as f32));
        }
        // Y_i = U^T M_i on the analysis's tensor (time row scaled), frame by frame, in f64.
        let mut coeffs = Vec::with_capacity(s * t * r);
        for pose in analysis.tensor.as_slice().chunks_exact(p) {
            coeffs.extend((0..r).map(|j| {
                let y: f64 = pose
                    .iter()
                    .enumerate()
                    .map(|(row, &v)| u[(row, j)] * v)
                    .sum();
                y as f32
            }));
        }
        let r_last = lod.levels().last().map_or(r, |l| l.ranks.p);
        let values = Mat::from_fn(s, r * t, |i, o| {
            let (j, f) = (o / t, o % t);
            f64::from(coeffs[(i * t + f) * r + j])
        });
        Ok(PcaSource {
            model,
            blend: DualBlend::new(&analysis.kriging, &values)?,
            basis,
            coeffs,
            rank: r,
            level_ranks: level_schedule(r, r_last, lod.levels().len()),
            bones: bones_of(&model.layout),
            rest: crate::source::rest_rows_of(model),
        })
    }

    /// Components kept offline, `R`.
    pub fn rank(&self) -> usize {
        self.rank
    }

    /// Components `r_l` used at each accuracy level (non-increasing, from `R` to the model's last `R_P`).
    pub fn level_ranks(&self) -> &[usize] {
        &self.level_ranks
    }

    /// The basis as used at runtime, `P x R` row-major: the orthonormal `U` of [`pca_basis`] with its
    /// time row ([`TIME_ROW`]) divided by the analysis's `time_scale`, so that expanded poses hold
    /// seconds in the time row like every other source.
    pub fn basis(&self) -> &[f32] {
        &self.basis
    }

    /// Bytes the source keeps to synthesize at `precision`: `U` and every sample's coefficients,
    /// `(P R + S T R) x value bytes` (the kriging data, shared with the other sources, is not counted).
    pub fn bytes(&self, precision: Precision) -> usize {
        (self.basis.len() + self.coeffs.len()) * precision.value_bytes()
    }

    fn dims(&self) -> (usize, usize, usize) {
        let lod = self.model.lod();
        (lod.p(), lod.t(), lod.s())
    }

    /// Rows `0..out.len()` of `D^-1 U[:, :rank] y` into `out`, `y` frame `frame` of the
    /// component-major coefficients `coeffs` (`rank x T`).
    fn expand(&self, coeffs: &[f32], t: usize, rank: usize, frame: usize, out: &mut [f32]) {
        for (row, o) in out.iter_mut().enumerate() {
            let u = &self.basis[row * self.rank..][..rank];
            *o = u
                .iter()
                .enumerate()
                .map(|(j, a)| a * coeffs[j * t + frame])
                .sum();
        }
    }
}

impl ClipSource for PcaSource<'_> {
    type Clip = PcaClip;

    fn levels(&self) -> LevelTable {
        LevelTable {
            accuracy_levels: self.level_ranks.len(),
            joints: self.model.lod().joints(),
            pose_len: self.model.lod().p(),
        }
    }

    fn control_range(&self) -> ControlRange {
        crate::source::control_range(self.model)
    }

    fn new_clip(&self) -> PcaClip {
        let (p, t, _) = self.dims();
        PcaClip {
            coeffs: vec![0.0; t * self.rank],
            rank: self.rank,
            rows: p,
            active_joints: self.model.lod().joints(),
            times: TimeTable::with_capacity(t),
            root_motion: RootMotion::default(),
            body_scale: 1.0,
        }
    }

    /// Builds the clip at `detail` (a root-only detail at the last level, as
    /// [`lod_policy::LodModel::evaluated`] does); an unknown level or joint count is refused before
    /// anything is written.
    fn build_clip(
        &self,
        controls: &Controls,
        detail: Detail,
        clip: &mut PcaClip,
    ) -> Result<(), ClipError> {
        let (p, t, _) = self.dims();
        let lod = self.model.lod();
        let levels = self.level_ranks.len();
        let d = if detail.is_root_only() {
            Detail::new(levels.saturating_sub(1), 0)
        } else {
            detail
        };
        if !d.fits(levels, lod.joints()) {
            return Err(ClipError(format!(
                "PCA source: no detail {detail:?} (it has {levels} accuracy levels and {} joints)",
                lod.joints()
            )));
        }
        let r = self.level_ranks[d.accuracy];
        clip.rank = r;
        clip.active_joints = d.active_joints;
        clip.rows = lod.active_rows(clip.active_joints).min(p);
        // Y(c): the first r components of every frame, component-major.
        let coeffs = &mut clip.coeffs[..r * t];
        let mut raw = [0.0f32; lod_policy::CONTROL_VALUES];
        let d = lod
            .control_vector(controls, &mut raw)
            .map_err(|e| ClipError(e.to_string()))?;
        let raw = raw.map(f64::from);
        self.blend.eval(&raw[..d], coeffs);
        let big_r = self.rank;
        let time_basis = &self.basis[TIME_ROW * big_r..][..r];
        clip.times.fill_from_iter((0..t).map(|f| {
            f64::from(
                time_basis
                    .iter()
                    .enumerate()
                    .map(|(j, a)| a * coeffs[j * t + f])
                    .sum::<f32>(),
            )
        }));
        // The root rows (position, exponential map, time row) read for the root motion.
        let root = ALWAYS_ROWS.min(p);
        let (mut start, mut end) = ([0.0f32; ALWAYS_ROWS], [0.0f32; ALWAYS_ROWS]);
        self.expand(coeffs, t, r, 0, &mut start[..root]);
        self.expand(coeffs, t, r, t - 1, &mut end[..root]);
        clip.root_motion = lod.controls().root_motion(controls, &start, &end);
        clip.body_scale = self.model.body_scale(controls);
        Ok(())
    }

    fn clip_duration(&self, clip: &PcaClip) -> f32 {
        (clip.times.duration() as f32).max(1e-3)
    }

    fn clip_root_motion(&self, clip: &PcaClip) -> RootMotion {
        clip.root_motion
    }

    fn pose(&self, clip: &PcaClip, t_seconds: f32, out: &mut [f32]) -> usize {
        let (_, t, _) = self.dims();
        let phase = clip
            .times
            .phase_at(f64::from(t_seconds))
            .clamp(0.0, (t - 1) as f64);
        let k = (phase.floor() as usize).min(t.saturating_sub(2));
        let k1 = (k + 1).min(t - 1);
        let a = (phase - k as f64) as f32;
        let r = clip.rank;
        // A buffer shorter than the clip's rows is a clip fault (0 rows), not a panic.
        let Some(out) = out.get_mut(..clip.rows) else {
            return 0;
        };
        out.fill(0.0);
        let mut y = [0.0f32; CHUNK];
        for first in (0..r).step_by(CHUNK) {
            let n = CHUNK.min(r - first);
            for (j, v) in y[..n].iter_mut().enumerate() {
                let comp = &clip.coeffs[(first + j) * t..][..t];
                *v = (1.0 - a) * comp[k] + a * comp[k1];
            }
            for (row, o) in out.iter_mut().enumerate() {
                let u = &self.basis[row * self.rank + first..][..n];
                *o += u.iter().zip(&y[..n]).map(|(b, v)| b * v).sum::<f32>();
            }
        }
        clip.rows
    }

    fn plant_feet(
        &self,
        clip: &PcaClip,
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

    fn joints(&self, clip: &PcaClip, pose: &[f32], out: &mut [Vec3]) -> usize {
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

#[cfg(test)]
mod tests {
    use super::level_schedule;

    #[test]
    fn schedule_decreases_linearly_from_r_to_the_last_rank() {
        assert_eq!(level_schedule(40, 10, 4), vec![40, 30, 20, 10]);
        assert_eq!(level_schedule(40, 40, 3), vec![40, 40, 40]);
        assert_eq!(
            level_schedule(5, 0, 3),
            vec![5, 3, 1],
            "at least one component"
        );
        assert_eq!(level_schedule(8, 20, 2), vec![8, 8], "clamped to R");
        assert_eq!(level_schedule(8, 2, 1), vec![8]);
        assert_eq!(level_schedule(8, 2, 0), vec![8], "at least one level");
    }
}
