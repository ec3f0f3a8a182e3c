//! Hybrid accuracy levels between key levels (paper 4.2, Figure 2).

use crate::{HosvdError, KeyLevels, Tucker};
use serde::{Deserialize, Serialize};

/// One accuracy level of the hybrid model as the offline decomposition schedules it: the key level it
/// is truncated from and its rank triple `[R_P, R_T, R_S]` as the Tucker models index ranks. The
/// motion model's builder turns each into the runtime's accuracy level (same key and ranks), the
/// one the model file stores.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct HybridLevel {
    /// Index of the key level whose model is truncated (the nearest larger key).
    pub key: usize,
    /// The rank triple of this level (componentwise `<=` the key's ranks).
    pub ranks: [usize; 3],
}

/// Most accuracy levels [`hybrid_levels`] makes: `65_536` (2 MiB of levels; models use tens).
/// A larger `accuracy_levels` is lowered to it, as [`crate::key_levels`] lowers `levels` to what
/// the rank range allows.
pub const MAX_ACCURACY_LEVELS: usize = 1 << 16;

/// The `N_A` accuracy levels of the hybrid scheme for `N` key levels.
///
/// Key `i` sits at accuracy level `p_i = round(i (N_A - 1) / (N - 1))` (evenly spread; level 0 is
/// key 0, the last level the last key). The `m = p_{i+1} - p_i - 1` levels between two keys step
/// down by rounded linear interpolation, `r(t) = round(r_i + (r_{i+1} - r_i) t / (m + 1))` for
/// `t = 1..m`, componentwise, and are truncations of key `i`, the nearest *larger* key tensor
/// (paper 4.2). Ranks never increase with the level; they strictly decrease when the key ranks
/// leave room for it. `accuracy_levels < N` is raised to `N` (every key level is an accuracy
/// level), `accuracy_levels > MAX_ACCURACY_LEVELS` lowered to [`MAX_ACCURACY_LEVELS`] (or `N`
/// if that is larger); a single key gives a single level; no keys give none.
pub fn hybrid_levels(keys: &KeyLevels, accuracy_levels: usize) -> Vec<HybridLevel> {
    let n = keys.levels.len();
    if n <= 1 {
        return keys
            .levels
            .iter()
            .map(|l| HybridLevel {
                key: 0,
                ranks: l.ranks,
            })
            .collect();
    }
    let na = accuracy_levels.min(MAX_ACCURACY_LEVELS).max(n);
    let step = (na - 1) as f64 / (n - 1) as f64;
    let pos: Vec<usize> = (0..n).map(|i| (i as f64 * step).round() as usize).collect();
    let mut out = Vec::with_capacity(na);
    for i in 0..n - 1 {
        let (a, b) = (keys.levels[i].ranks, keys.levels[i + 1].ranks);
        out.push(HybridLevel { key: i, ranks: a });
        let m = pos[i + 1] - pos[i] - 1;
        for t in 1..=m {
            let f = t as f64 / (m + 1) as f64;
            let ranks = std::array::from_fn(|k| {
                let r = a[k] as f64 + (b[k] as f64 - a[k] as f64) * f;
                (r.round() as usize).clamp(b[k].min(a[k]), a[k])
            });
            out.push(HybridLevel { key: i, ranks });
        }
    }
    out.push(HybridLevel {
        key: n - 1,
        ranks: keys.levels[n - 1].ranks,
    });
    debug_assert_eq!(out.len(), na);
    out
}

impl KeyLevels {
    /// The model at an accuracy level: key `level.key` truncated to `level.ranks`.
    ///
    /// Errors: [`HosvdError::BadKeyConfig`] for a key index out of range, a rank error if the
    /// ranks exceed the key's.
    pub fn model_at(&self, level: &HybridLevel) -> Result<Tucker, HosvdError> {
        let key = self.levels.get(level.key).ok_or_else(|| {
            HosvdError::BadKeyConfig(format!(
                "accuracy level refers to key {} but there are {} keys",
                level.key,
                self.levels.len()
            ))
        })?;
        key.tucker.truncate(level.ranks)
    }

    /// `(mse, rel_error)` of an accuracy level, from norms only: the truncated key core is the
    /// projection of the data on the truncated factors, so `||X - X~||^2 = ||X||^2 - ||Z_r||^2`.
    ///
    /// Errors: as [`KeyLevels::model_at`].
    pub fn level_errors(&self, level: &HybridLevel) -> Result<(f64, f64), HosvdError> {
        let key = self.levels.get(level.key).ok_or_else(|| {
            HosvdError::BadKeyConfig(format!(
                "key {} out of range ({} keys)",
                level.key,
                self.levels.len()
            ))
        })?;
        tensor_ops::check_ranks(key.ranks, level.ranks)?;
        let z2 = key.tucker.core.leading_squared_norm(level.ranks);
        Ok(crate::hooi::projection_errors(
            self.data_squared_norm,
            z2,
            self.data_len,
        ))
    }
}
