//! Figures 4 and 5: time to synthesize a pose and its error, per accuracy level for the three schemes
//! (Figure 4) and against the distance from the camera under the distance policy (Figure 5).
//!
//! Time per pose is the clip kernel amortised over the `T` aligned frames of one cycle plus one
//! per-frame pose: `kernel / T + pose`, each the median of several timed runs
//! ([`super::measure::median_ns`]). The error is the mean joint position error (cm, after forward
//! kinematics, [`motion_lod::metrics::ErrorMeter`]) of the synthesized cycles against the data at the
//! training controls of a strided subset of the samples.

use std::collections::HashMap;
use std::hint::black_box;

use anyhow::{Context, Result};
use lod_policy::{
    ClipKernel, Detail, DistancePolicy, KernelScratch, LevelPolicy, LodModel, ViewParams,
};
use motion_lod::metrics::ErrorMeter;
use motion_lod::progress::Progress;
use motion_lod::{Analysis, MotionModel};

use super::measure::{Budget, median_ns};
use super::online::OnlineTruncation;

/// Samples whose controls drive the timing and the error measurement: every `stride`-th, at most `max`.
pub fn picked_samples(s: usize, max: usize) -> Vec<usize> {
    let stride = s.div_ceil(max.max(1)).max(1);
    (0..s).step_by(stride).collect()
}

/// Mean joint position error (cm) of `model` at `detail` against the data of `analysis` at the controls
/// of the samples `picks`.
pub fn data_error(
    model: &MotionModel,
    analysis: &Analysis,
    picks: &[usize],
    detail: Detail,
) -> Result<f64> {
    let mut meter = ErrorMeter::new(&analysis.layout);
    for &k in picks {
        let c = lod_policy::Controls::from_f64(analysis.controls[k]);
        let poses = model
            .synthesize_aligned(&c, detail)
            .with_context(|| format!("synthesizing sample {k} at {detail:?}"))?;
        meter.compare_sequences(analysis.tensor.sample(k), &poses);
    }
    Ok(meter.total().mean_joint_cm)
}

/// Measured kernel and pose times of one detail.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Timed {
    /// Median nanoseconds to build one clip kernel.
    pub kernel_ns: f64,
    /// Median nanoseconds of one per-frame pose.
    pub pose_ns: f64,
    /// Aligned frames per cycle `T`.
    pub t: usize,
}

impl Timed {
    /// `kernel / T + pose`: the cost of one pose with the kernel amortised over a cycle.
    pub fn per_pose_ns(&self) -> f64 {
        self.kernel_ns / self.t.max(1) as f64 + self.pose_ns
    }
}

/// Times kernels (cycling over `controls`) and poses (over the `T` aligned frames) of a runtime model.
pub fn time_lod(
    lod: &LodModel,
    controls: &[lod_policy::Controls],
    detail: Detail,
    budget: Budget,
) -> Result<Timed> {
    let mut scratch = KernelScratch::new(lod);
    let mut kernel = ClipKernel::new(lod);
    let mut pose = vec![0.0f32; lod.p()];
    lod.build_kernel(&controls[0], detail, &mut scratch, &mut kernel)
        .with_context(|| format!("kernel at {detail:?}"))?;
    let mut i = 0usize;
    let kernel_ns = median_ns(budget, || {
        i = (i + 1) % controls.len();
        let r = lod.build_kernel(black_box(&controls[i]), detail, &mut scratch, &mut kernel);
        black_box(r.is_ok());
    });
    lod.build_kernel(&controls[0], detail, &mut scratch, &mut kernel)
        .with_context(|| format!("kernel at {detail:?}"))?;
    let t = lod.t();
    let cycle_ns = median_ns(budget, || {
        for tau in 0..t {
            let r = lod.pose(&kernel, black_box(tau as f32), &mut pose);
            black_box(r.is_ok());
            black_box(&pose);
        }
    });
    Ok(Timed {
        kernel_ns,
        pose_ns: cycle_ns / t as f64,
        t,
    })
}

/// Times the online-truncation kernel and pose at level `level` of `lod` (ranks of that level, every
/// row).
pub fn time_online(
    lod: &LodModel,
    controls: &[lod_policy::Controls],
    level: usize,
    budget: Budget,
) -> Timed {
    let ranks = lod.levels()[level].ranks;
    let rows = lod.p();
    let mut online = OnlineTruncation::new(lod);
    let mut pose = vec![0.0f32; lod.p()];
    let mut i = 0usize;
    let kernel_ns = median_ns(budget, || {
        i = (i + 1) % controls.len();
        online.build(black_box(&controls[i]), ranks, rows);
        black_box(online.g().first());
    });
    online.build(&controls[0], ranks, rows);
    let t = lod.t();
    let cycle_ns = median_ns(budget, || {
        for tau in 0..t {
            online.pose(black_box(tau as f32), &mut pose);
            black_box(&pose);
        }
    });
    Timed {
        kernel_ns,
        pose_ns: cycle_ns / t as f64,
        t,
    }
}

/// One point of Figure 4.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LevelPoint {
    /// Accuracy level.
    pub level: usize,
    /// Ranks of the level.
    pub ranks: [usize; 3],
    /// Times.
    pub timed: Timed,
    /// Mean joint position error against the data (cm).
    pub error_cm: f64,
}

/// Figure 4: every accuracy level for each scheme.
#[derive(Debug, Clone, PartialEq)]
pub struct Figure4 {
    /// Online truncation of the full key tensor.
    pub truncation: Vec<LevelPoint>,
    /// ALS at every level.
    pub als: Vec<LevelPoint>,
    /// The hybrid model.
    pub hybrid: Vec<LevelPoint>,
}

/// The models Figure 4 compares (see [`super::schemes`]).
pub struct Schemes<'a> {
    /// The hybrid model.
    pub hybrid: &'a MotionModel,
    /// ALS at every level.
    pub als: &'a MotionModel,
    /// Truncations of key 0 (errors of online truncation).
    pub truncation: &'a MotionModel,
}

/// Measures Figure 4.
pub fn figure4(
    schemes: &Schemes<'_>,
    analysis: &Analysis,
    picks: &[usize],
    budget: Budget,
    progress: &dyn Progress,
) -> Result<Figure4> {
    let controls: Vec<lod_policy::Controls> = picks
        .iter()
        .map(|&k| lod_policy::Controls::from_f64(analysis.controls[k]))
        .collect();
    let n = schemes.hybrid.lod().levels().len();
    progress.stage("figure 4: three schemes", 3 * n as u64);
    let mut out = Figure4 {
        truncation: Vec::with_capacity(n),
        als: Vec::with_capacity(n),
        hybrid: Vec::with_capacity(n),
    };
    for level in 0..n {
        let detail = Detail::new(level, schemes.hybrid.lod().joints());
        let point = |m: &MotionModel, timed: Timed| -> Result<LevelPoint> {
            let r = m.lod().levels()[level].ranks;
            Ok(LevelPoint {
                level,
                ranks: [r.p, r.t, r.s],
                timed,
                error_cm: data_error(m, analysis, picks, detail)?,
            })
        };
        let tr = schemes.truncation.lod();
        out.truncation.push(point(
            schemes.truncation,
            time_online(tr, &controls, level, budget),
        )?);
        progress.inc(1);
        out.als.push(point(
            schemes.als,
            time_lod(schemes.als.lod(), &controls, detail, budget)?,
        )?);
        progress.inc(1);
        out.hybrid.push(point(
            schemes.hybrid,
            time_lod(schemes.hybrid.lod(), &controls, detail, budget)?,
        )?);
        progress.inc(1);
    }
    Ok(out)
}

/// One point of Figure 5.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DistancePoint {
    /// Distance from the camera (m).
    pub distance_m: f32,
    /// The policy's detail.
    pub detail: Detail,
    /// Resolved accuracy level.
    pub level: usize,
    /// Evaluated rows `P'`.
    pub rows: usize,
    /// `r_P r_T r_S` of the level over that of level 0 (the key tensor's size ratio to the maximum).
    pub size_ratio: f64,
    /// Times.
    pub timed: Timed,
    /// Mean joint position error against the data (cm).
    pub error_cm: f64,
}

/// Distances of Figure 5: every `step_m` from 0 to one key step past the last key group.
pub fn distances(lod: &LodModel, step_m: f32) -> Vec<f32> {
    let cfg = lod_policy::DistanceConfig::default();
    let mut groups = 0;
    let mut last = usize::MAX;
    for l in lod.levels() {
        if l.key != last {
            groups += 1;
            last = l.key;
        }
    }
    let end = cfg.near_m + cfg.key_step_m * (groups as f32 + 1.0);
    let n = (end / step_m).floor() as usize;
    (0..=n).map(|i| i as f32 * step_m).collect()
}

/// Measures Figure 5 with the paper's distance policy (section 5.1) on the hybrid model.
pub fn figure5(
    model: &MotionModel,
    analysis: &Analysis,
    picks: &[usize],
    step_m: f32,
    budget: Budget,
    progress: &dyn Progress,
) -> Result<Vec<DistancePoint>> {
    let lod = model.lod();
    let controls: Vec<lod_policy::Controls> = picks
        .iter()
        .map(|&k| lod_policy::Controls::from_f64(analysis.controls[k]))
        .collect();
    let policy = DistancePolicy::for_model(lod);
    let view = ViewParams::default();
    let ds = distances(lod, step_m);
    progress.stage("figure 5: distance policy", ds.len() as u64);
    let full = lod.levels()[0].ranks.core_len() as f64;
    let mut cache: HashMap<Detail, (Timed, f64)> = HashMap::new();
    let mut out = Vec::with_capacity(ds.len());
    for &d in &ds {
        let detail = policy.detail(d, true, &view);
        let level = lod
            .check_detail(detail)
            .with_context(|| format!("policy detail {detail:?} at {d} m"))?
            .accuracy;
        let (timed, error_cm) = match cache.get(&detail) {
            Some(v) => *v,
            None => {
                let v = (
                    time_lod(lod, &controls, detail, budget)?,
                    data_error(model, analysis, picks, detail)?,
                );
                cache.insert(detail, v);
                v
            }
        };
        out.push(DistancePoint {
            distance_m: d,
            detail,
            level,
            rows: lod.active_rows(detail.active_joints),
            size_ratio: lod.levels()[level].ranks.core_len() as f64 / full,
            timed,
            error_cm,
        });
        progress.inc(1);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn picked_samples_are_strided_and_bounded() {
        assert_eq!(picked_samples(10, 4), vec![0, 3, 6, 9]);
        assert_eq!(picked_samples(3, 16), vec![0, 1, 2]);
        assert_eq!(picked_samples(800, 16).len(), 16);
    }

    #[test]
    fn per_pose_amortises_the_kernel_over_the_cycle() {
        let t = Timed {
            kernel_ns: 1000.0,
            pose_ns: 5.0,
            t: 100,
        };
        assert!((t.per_pose_ns() - 15.0).abs() < 1e-12);
    }
}
