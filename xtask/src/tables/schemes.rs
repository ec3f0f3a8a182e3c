//! The three accuracy-control schemes of the paper's Figure 4 (section 4.1-4.2), as runtime models.
//!
//! - **Hybrid** (the real [`MotionModel`]): `N` ALS key tensors, the levels between keys truncate the
//!   nearest larger key.
//! - **ALS at every level**: one ALS-optimised (HOOI) Tucker model per accuracy level, each a key of
//!   its own ([`als_every_level`]), so no level is a truncation.
//! - **Online truncation**: only the full (level-0) key is stored and every level is a truncation of
//!   it ([`truncation_only`], used for its errors); its runtime cost is measured with
//!   [`crate::tables::online::OnlineTruncation`], which redoes the unfolding per clip.

use anyhow::{Context, Result};
use hosvd_als::{KeyLevel, KeyLevels};
use lod_policy::{AccuracyLevel, LodModel, Ranks};
use motion_lod::progress::{NoProgress, Progress};
use motion_lod::{Analysis, BuildConfig, MotionModel};

/// `model` with its runtime part replaced by `lod` (same skeleton and report), for synthesis and error
/// measurement with [`MotionModel::synthesize_aligned`].
pub fn with_lod(model: &MotionModel, lod: LodModel) -> Result<MotionModel> {
    model
        .with_lod(lod)
        .context("a scheme's model does not fit the skeleton")
}

/// The runtime model of the online-truncation scheme: the hybrid model's key 0 only, and every accuracy
/// level of the hybrid model as a leading sub-block truncation of it (ranks clamped to key 0's).
pub fn truncation_only(model: &MotionModel) -> Result<LodModel> {
    let mut parts = model.lod().parts().clone();
    let full = parts.keys[0].ranks;
    parts.keys.truncate(1);
    parts.levels = parts
        .levels
        .iter()
        .map(|l| AccuracyLevel {
            key: 0,
            ranks: Ranks::new(
                l.ranks.p.min(full.p),
                l.ranks.t.min(full.t),
                l.ranks.s.min(full.s),
            ),
        })
        .collect();
    parts.level_errors.clear();
    parts.joint_errors.clear();
    LodModel::new(parts).context("truncation-only model")
}

/// The runtime model of the ALS-at-every-level scheme: for every accuracy level of `analysis`, an ALS
/// (HOOI) Tucker model at exactly that level's ranks (a key level's own model when the ranks are a
/// key's), each its own key tensor with its own kriging projection. Returns the model and the HOOI
/// sweeps spent per level (0 for reused keys).
pub fn als_every_level(
    analysis: &Analysis,
    config: &BuildConfig,
    progress: &dyn Progress,
) -> Result<(MotionModel, Vec<usize>)> {
    progress.stage("ALS at every level", analysis.levels.len() as u64);
    let mut levels = Vec::with_capacity(analysis.levels.len());
    let mut sweeps = Vec::with_capacity(analysis.levels.len());
    for (l, level) in analysis.levels.iter().enumerate() {
        let key = &analysis.keys.levels[level.key];
        let reused = analysis.keys.levels.iter().find(|k| k.ranks == level.ranks);
        let kl = match reused {
            Some(k) => {
                sweeps.push(0);
                k.clone()
            }
            None => {
                let (tucker, report) = analysis
                    .decompose(level.ranks, &config.als)
                    .with_context(|| format!("HOOI at level {l}, ranks {:?}", level.ranks))?;
                sweeps.push(report.iterations);
                KeyLevel {
                    ranks: level.ranks,
                    tucker,
                    mse: report.mse,
                    rel_error: report.rel_error,
                    iterations: report.iterations,
                    threshold: None,
                    als_runs: 1,
                    converged: report.converged,
                }
            }
        };
        debug_assert!(kl.ranks.iter().zip(&key.ranks).all(|(a, b)| a <= b));
        levels.push(kl);
        progress.inc(1);
    }
    let mut every = analysis.clone();
    every.levels = levels
        .iter()
        .enumerate()
        .map(|(i, k)| hosvd_als::HybridLevel {
            key: i,
            ranks: k.ranks,
        })
        .collect();
    every.keys = KeyLevels {
        levels,
        ..analysis.keys.clone()
    };
    let model = every
        .runtime_model(config, &NoProgress)
        .context("runtime model of ALS at every level")?;
    Ok((model, sweeps))
}
