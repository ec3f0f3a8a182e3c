//! Clip kernels: the per-clip part of pose synthesis (kriging weights, blended core, `G(c)`, time
//! table) and the per-frame pose evaluation.
//!
//! For controls `c` at an accuracy level with ranks `(r_P, r_T, r_S)` of key `(Z, U_P, U_T, Q, V)`:
//! 1. `gamma_i(c) = variogram(|scale(c) - c_i|)` and `[U_S^T b ; C b] = Q [gamma(c) ; 1]`
//!    (appendix A, with `b(c)` the kriging weights);
//! 2. `w = U_S^T b + V ([c ; 1] - C b)`, so that eq. 8, `K(c) = F [c;1] + sum_i b_i (K_i - F [c_i;1])`
//!    with `F = K C^+`, becomes `K(c) = Z x_3 w`;
//! 3. `G(c) = U_P[:P', :] K(c)` (`P' x r_T`, eq. 7);
//! 4. per frame `pose(tau) = G w_T`, `w_T = (1 - a) U_T[i, :] + a U_T[i + 1, :]` (eq. 5).
//!
//! A truncated accuracy level uses the leading blocks `Z[:r_P, :r_T, :r_S]`, `U_P[:, :r_P]`,
//! `U_T[:, :r_T]` and the first `r_S` rows of the `U_S^T` part of `Q` and of `V` (all `d + 1` rows
//! of the `C` part are kept). This equals the paper's universal kriging of the truncated sample
//! cores, with the trend refitted to them: `F_trunc = Z_t(12) U_S[:, :r_S]^T C^+`.

use serde::{Deserialize, Serialize};

use crate::error::KernelError;
use timewarp::TimeTable;

use crate::chain::{RootMotion, exp_map_to_quat};
use crate::model::{LodModel, Ranks, TIME_ROW};

/// Index of the control that is a clip's travel turn (radians, + = left): the heading of the
/// direction of travel changes by it over one cycle (the data's definition; the pelvis may turn by more
/// or less on cycles that enter or leave a turn).
pub const TURN_CONTROL: usize = 2;

/// Heading (yaw about +y, radians, 0 = +z, + = towards +x) of a root orientation given as an
/// exponential map.
pub fn yaw_of_exp_map(v: &[f32]) -> f32 {
    let f = exp_map_to_quat(glam::Vec3::new(v[0], v[1], v[2])) * glam::Vec3::Z;
    f.x.atan2(f.z)
}

/// Level of detail of one clip: an accuracy level and the number of evaluated joints.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Detail {
    /// Index into the model's accuracy levels (0 = most accurate), or [`Detail::SMALLEST`].
    pub accuracy: usize,
    /// Joints evaluated after the always-evaluated root rows; values above the model's joint
    /// count mean all joints.
    pub active_joints: usize,
}

impl Detail {
    /// Sentinel accuracy index selecting the model's smallest (last) accuracy level.
    pub const SMALLEST: usize = usize::MAX;

    /// Full detail: the most accurate level and every joint.
    pub const fn full() -> Detail {
        Detail {
            accuracy: 0,
            active_joints: usize::MAX,
        }
    }

    /// Root only: rows `0..7` (root position, root orientation, time increment) at the smallest
    /// accuracy level; every other row takes the mean pose.
    pub const fn root_only() -> Detail {
        Detail {
            accuracy: Detail::SMALLEST,
            active_joints: 0,
        }
    }

    /// Builds a detail.
    pub const fn new(accuracy: usize, active_joints: usize) -> Detail {
        Detail {
            accuracy,
            active_joints,
        }
    }

    /// The accuracy level index this detail selects in `model` (resolving [`Detail::SMALLEST`]),
    /// or `None` when it is out of range.
    pub fn level_in(&self, model: &LodModel) -> Option<usize> {
        let n = model.levels().len();
        if self.accuracy == Detail::SMALLEST {
            Some(n - 1)
        } else if self.accuracy < n {
            Some(self.accuracy)
        } else {
            None
        }
    }
}

/// Caller-owned working memory for [`LodModel::build_kernel`], sized for the largest level.
#[derive(Debug, Clone)]
pub struct KernelScratch {
    /// `[gamma(c) ; 1]`, length `S + 1`.
    x: Vec<f64>,
    /// `Q [gamma ; 1]` restricted to the used rows: `r_S` then `d + 1`.
    y: Vec<f64>,
    /// Scaled controls `[c' ; 1]`, length `d + 1`.
    c: Vec<f64>,
    /// Sample-mode weights `w`, length `max R_S`.
    w: Vec<f32>,
    /// Blended core `K(c)`, `r_P x r_T` column-major.
    k: Vec<f32>,
}

impl KernelScratch {
    /// Allocates scratch for every level of `model`.
    pub fn new(model: &LodModel) -> KernelScratch {
        let r = model.max_ranks();
        KernelScratch {
            x: vec![0.0; model.s() + 1],
            y: vec![0.0; r.s + model.d() + 1],
            c: vec![0.0; model.d() + 1],
            w: vec![0.0; r.s],
            k: vec![0.0; r.p * r.t],
        }
    }

    fn fits(&self, model: &LodModel) -> Result<(), KernelError> {
        let r = model.max_ranks();
        let ok = self.x.len() == model.s() + 1
            && self.y.len() > r.s + model.d()
            && self.c.len() == model.d() + 1
            && self.w.len() >= r.s
            && self.k.len() >= r.p * r.t;
        if ok {
            Ok(())
        } else {
            Err(KernelError::Capacity {
                what: "scratch",
                detail: format!(
                    "model S = {}, d = {}, max ranks {:?}",
                    model.s(),
                    model.d(),
                    r
                ),
            })
        }
    }
}

/// A clip kernel: `G(c)` for the evaluated rows and the clip's playback time table.
///
/// Allocated once per model with [`ClipKernel::new`] (for the largest level) and refilled by
/// [`LodModel::build_kernel`] without allocation.
#[derive(Debug, Clone, PartialEq)]
pub struct ClipKernel {
    p: usize,
    t: usize,
    detail: Detail,
    level: usize,
    ranks: Ranks,
    rows: usize,
    clamped: bool,
    /// `G(c)`, `rows x r_T` column-major (capacity `P x max R_T`).
    g: Vec<f32>,
    /// Playback times of the `T` aligned frames (incremental inverse timewarp).
    times: TimeTable,
    /// Root motion from the first to the last aligned frame ([`crate::chain`]).
    root_motion: RootMotion,
}

impl ClipKernel {
    /// Preallocates a kernel for the largest level of `model`. Until it is built it holds the
    /// smallest level with `G = 0` (every row then reads as zero; the time table is flat).
    pub fn new(model: &LodModel) -> ClipKernel {
        let r = model.max_ranks();
        let last = model.levels().len() - 1;
        ClipKernel {
            p: model.p(),
            t: model.t(),
            detail: Detail::root_only(),
            level: last,
            ranks: model.levels()[last].ranks,
            rows: model.always_rows(),
            clamped: false,
            g: vec![0.0; model.p() * r.t],
            times: TimeTable::with_capacity(model.t()),
            root_motion: RootMotion::default(),
        }
    }

    /// The detail this kernel was built with (as requested).
    pub fn detail(&self) -> Detail {
        self.detail
    }
    /// The resolved accuracy level index.
    pub fn level(&self) -> usize {
        self.level
    }
    /// Ranks of the resolved accuracy level.
    pub fn ranks(&self) -> Ranks {
        self.ranks
    }
    /// Number of evaluated rows `P'`.
    pub fn rows(&self) -> usize {
        self.rows
    }
    /// True when some control was outside the data range and was clamped.
    pub fn clamped(&self) -> bool {
        self.clamped
    }
    /// `G(c)` as a `rows x r_T` column-major matrix.
    pub fn g(&self) -> &[f32] {
        &self.g[..self.rows * self.ranks.t]
    }
    /// The clip's root motion: the root's ground displacement `(dx, dz)` from the first to the last
    /// aligned frame in the cycle frame, and the travel turn (the clamped turn control,
    /// [`TURN_CONTROL`]; when the model ignores turn, the turn the data imply for the other controls,
    /// [`crate::ControlSpace::implied`]; the pelvis's yaw change for a model without a turn
    /// dimension). The next cycle frame
    /// follows from it ([`crate::chain`]).
    pub fn root_motion(&self) -> RootMotion {
        self.root_motion
    }
    /// The clip's time table: playback time (seconds) of each aligned frame, built from the
    /// time-increment row (row 6) of `G(c)` at every aligned frame (`timewarp::TimeTable`: the
    /// increment of the last frame is unused, increments below `timewarp::MIN_INCREMENT` are
    /// raised to it). Empty until the kernel is built.
    pub fn time_table(&self) -> &TimeTable {
        &self.times
    }
    /// Playback duration of the clip in seconds: the time of aligned frame `T - 1`.
    pub fn duration(&self) -> f64 {
        self.times.duration()
    }
    /// Phase (fractional aligned frame in `[0, T - 1]`) at playback time `seconds` (clamped to
    /// `[0, duration]`, NaN gives 0), by inverting the piecewise linear time table: with
    /// `t_j <= seconds < t_{j+1}`, `phase = j + (seconds - t_j) / (t_{j+1} - t_j)`.
    pub fn phase_at(&self, seconds: f64) -> f32 {
        self.times.phase_at(seconds) as f32
    }
}

impl LodModel {
    fn check_kernel(&self, kernel: &ClipKernel) -> Result<(), KernelError> {
        if kernel.p != self.p()
            || kernel.t != self.t()
            || kernel.g.len() < self.p() * self.max_ranks().t
            || kernel.level >= self.levels().len()
        {
            return Err(KernelError::Capacity {
                what: "kernel",
                detail: format!(
                    "kernel P = {}, T = {}; model P = {}, T = {}",
                    kernel.p,
                    kernel.t,
                    self.p(),
                    self.t()
                ),
            });
        }
        Ok(())
    }

    /// Builds the clip kernel for raw `controls` (length `d`) at `detail`, into `out`, without
    /// allocating.
    ///
    /// Controls outside the data's `[min, max]` are clamped (reported by
    /// [`ClipKernel::clamped`]); NaN or infinite controls, a wrong length or an unknown accuracy
    /// level are errors. Active joints above the model's count mean all joints. Cost
    /// `O((R_S + d) S + r_P r_T r_S + P' r_P r_T + T r_T)`, see [`LodModel::kernel_cost`].
    pub fn build_kernel(
        &self,
        controls: &[f32],
        detail: Detail,
        scratch: &mut KernelScratch,
        out: &mut ClipKernel,
    ) -> Result<(), KernelError> {
        let (p, t, s, d) = (self.p(), self.t(), self.s(), self.d());
        if controls.len() != d {
            return Err(KernelError::ControlLength {
                expected: d,
                found: controls.len(),
            });
        }
        if let Some(index) = controls.iter().position(|v| !v.is_finite()) {
            return Err(KernelError::NonFiniteControl {
                index,
                value: controls[index],
            });
        }
        let level = detail.level_in(self).ok_or(KernelError::Level {
            level: detail.accuracy,
            levels: self.levels().len(),
        })?;
        scratch.fits(self)?;
        self.check_kernel(out)?;

        let lv = self.levels()[level];
        let key = &self.keys()[lv.key];
        let big = key.ranks;
        let r = lv.ranks;
        let rows = self.active_rows(detail.active_joints);
        debug_assert!(rows <= p && r.fits_in(&big));

        // 1. Clamp and scale the controls: c'_k = (clamp(c_k) - offset_k) * scale_k.
        let cs = self.controls();
        let mut clamped = false;
        for (k, &raw) in controls.iter().enumerate() {
            let v = raw.clamp(cs.min[k], cs.max[k]);
            clamped |= v != raw;
            scratch.c[k] = (f64::from(v) - f64::from(cs.offset[k])) * f64::from(cs.scale[k]);
        }
        scratch.c[d] = 1.0;

        // 2. x = [gamma(c) ; 1], gamma_i = variogram(|c' - c_i|).
        for i in 0..s {
            let mut h2 = 0.0f64;
            for k in 0..d {
                let diff = scratch.c[k] - f64::from(cs.samples[i + s * k]);
                h2 += diff * diff;
            }
            scratch.x[i] = cs.variogram.eval(h2.sqrt());
        }
        scratch.x[s] = 1.0;

        // 3. y = [U_S^T b (first r_S rows) ; C b] = [Q x ; P_C x], Q column-major R_S x (S + 1) (the
        //    key's), P_C column-major (d + 1) x (S + 1) (the control space's, shared by every key).
        let y = &mut scratch.y[..r.s + d + 1];
        y.fill(0.0);
        let (y_top, y_c) = y.split_at_mut(r.s);
        for (j, col) in key.projection.chunks_exact(big.s).enumerate() {
            let xj = scratch.x[j];
            for (yl, &q) in y_top.iter_mut().zip(&col[..r.s]) {
                *yl += f64::from(q) * xj;
            }
        }
        for (j, col) in cs.projection.chunks_exact(d + 1).enumerate() {
            let xj = scratch.x[j];
            for (ym, &q) in y_c.iter_mut().zip(col) {
                *ym += f64::from(q) * xj;
            }
        }

        // 4. w = U_S^T b + V ([c' ; 1] - C b), V column-major R_S x (d + 1).
        for l in 0..r.s {
            let mut acc = y[l];
            for m in 0..=d {
                acc += f64::from(key.trend[l + big.s * m]) * (scratch.c[m] - y[r.s + m]);
            }
            scratch.w[l] = acc as f32;
        }

        // 5. K(c) = Z[:r_P, :r_T, :r_S] x_3 w, stored r_P x r_T column-major.
        let kmat = &mut scratch.k[..r.p * r.t];
        kmat.fill(0.0);
        for (l, &wl) in scratch.w[..r.s].iter().enumerate() {
            for b in 0..r.t {
                let zcol = &key.core[big.p * (b + big.t * l)..][..r.p];
                let kcol = &mut kmat[r.p * b..][..r.p];
                for (kv, &z) in kcol.iter_mut().zip(zcol) {
                    *kv += wl * z;
                }
            }
        }

        // 6. G(c) = U_P[:rows, :r_P] K(c), rows x r_T column-major.
        let g = &mut out.g[..rows * r.t];
        g.fill(0.0);
        for b in 0..r.t {
            let gcol = &mut g[rows * b..][..rows];
            for a in 0..r.p {
                let kab = kmat[a + r.p * b];
                let ucol = &key.u_p[p * a..][..rows];
                for (gv, &u) in gcol.iter_mut().zip(ucol) {
                    *gv += kab * u;
                }
            }
        }

        // 7. Time table from the time-increment row at every aligned frame:
        //    dt_j = G[6, :] . U_T[j, :r_T] / time_scale.
        let g = &*g;
        let inv_scale = 1.0 / self.parts().time_scale;
        out.times.fill_from_iter((0..t).map(|j| {
            inv_scale
                * (0..r.t)
                    .map(|b| f64::from(g[TIME_ROW + rows * b]) * f64::from(key.u_t[j + t * b]))
                    .sum::<f64>()
        }));

        out.detail = detail;
        out.level = level;
        out.ranks = r;
        out.rows = rows;
        out.clamped = clamped;

        // 8. Root motion: the root's ground displacement from the first to the last aligned frame, and
        //    the travel turn (the clamped turn control; when the model ignores turn, the turn the data
        //    imply for the other controls, `ControlSpace::implied`; the pelvis's yaw change for a model
        //    without a turn dimension).
        let mut ends = [[0.0f32; 6]; 2];
        for (e, phase) in ends.iter_mut().zip([0.0, (t - 1) as f32]) {
            self.pose_rows(out, phase, e)?;
        }
        let [start, end] = ends;
        out.root_motion = cs.root_motion(controls, &start, &end);
        Ok(())
    }

    /// Writes the pose at `phase` (fractional aligned frame, clamped to `[0, T - 1]`) into `out`
    /// (length `P`): rows `0..P'` from the kernel, `G w_T` with
    /// `w_T = (1 - a) U_T[i, :r_T] + a U_T[i + 1, :r_T]`, `i = floor(phase)`, `a = phase - i`
    /// (eq. 4-5), and rows `P'..P` from the mean pose. `O(P' r_T)`, no allocation.
    pub fn pose(
        &self,
        kernel: &ClipKernel,
        phase: f32,
        out: &mut [f32],
    ) -> Result<(), KernelError> {
        if out.len() != self.p() {
            return Err(KernelError::OutputLength {
                expected: self.p(),
                found: out.len(),
            });
        }
        self.pose_rows(kernel, phase, out)
    }

    /// Writes the first `out.len()` rows (at most `P`) of the pose at `phase`, as [`LodModel::pose`]
    /// does for all of them: rows the kernel evaluated from `G w_T`, later rows from the mean pose.
    /// With `out.len() = 7` it evaluates only the root and the time increment, `O(7 r_T)`.
    pub fn pose_rows(
        &self,
        kernel: &ClipKernel,
        phase: f32,
        out: &mut [f32],
    ) -> Result<(), KernelError> {
        let (p, t) = (self.p(), self.t());
        self.check_kernel(kernel)?;
        if out.len() > p {
            return Err(KernelError::OutputLength {
                expected: p,
                found: out.len(),
            });
        }
        if !phase.is_finite() {
            return Err(KernelError::NonFinitePhase { phase });
        }
        let key = &self.keys()[self.levels()[kernel.level].key];
        let rows = kernel.rows;
        let used = rows.min(out.len());
        let rt = kernel.ranks.t;
        let ph = phase.clamp(0.0, (t - 1) as f32);
        let i = (ph.floor() as usize).min(t.saturating_sub(2));
        let i1 = (i + 1).min(t - 1);
        let a = ph - i as f32;
        let (head, tail) = out.split_at_mut(used);
        head.fill(0.0);
        for b in 0..rt {
            let wb = (1.0 - a) * key.u_t[i + t * b] + a * key.u_t[i1 + t * b];
            let gcol = &kernel.g[rows * b..][..used];
            for (o, &gv) in head.iter_mut().zip(gcol) {
                *o += wb * gv;
            }
        }
        let n = tail.len();
        tail.copy_from_slice(&self.mean_pose()[used..used + n]);
        Ok(())
    }
}
