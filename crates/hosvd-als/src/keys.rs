//! The greedy key-tensor search of paper section 4.2.
//!
//! # The rule
//! 1. Ranks are clamped to the mode sizes (reported in [`KeyLevels::clamped`]). `N` levels need
//!    `N - 1` single-rank steps between the max and min triples; if there are fewer, the search
//!    returns as many levels as fit (`KeyLevels::levels.len() < requested_levels`).
//! 2. The maximum and minimum models are computed by HOOI from HOSVD starts ([`crate::hooi`]);
//!    their mean squared errors are `E_1` and `E_N`, and `C_E = E_N / (N E_1)`. The threshold of
//!    key level `l` (1-based) is `l C_E E_1 = l E_N / N`.
//! 3. Key level `l = 2 .. N-1` starts at the previous key's ranks and decrements one rank at a
//!    time. **Which dimension first:** the mode whose trailing core slice (within the current
//!    ranks) carries the least energy per stored number saved, i.e. the smallest
//!    `||Z(.., r_n - 1, ..)||^2 / (prod_{m != n} r_m + I_n)` (ties: the larger saving, then the
//!    lower mode). Dropping that slice raises the squared error by exactly that energy for the
//!    truncated model while saving the most bytes per unit of error, so the walk follows the
//!    steepest storage-per-error descent; for an ordered core the trailing slice is the least
//!    important one of its mode. A mode at its minimum rank is never decremented, and the walk
//!    keeps enough steps in reserve for the remaining levels.
//! 4. Candidate errors are estimated without ALS by truncating the reference model's ordered core:
//!    `E(r) = (||X||^2 - ||Z(0..r)||^2) / (I_0 I_1 I_2)`. The walk stops at the first triple whose
//!    estimate exceeds the threshold; HOOI warm-started from the truncated reference factors then
//!    confirms it (its error is never above the estimate). If the confirmed ALS error is still at
//!    or below the threshold, the ALS model becomes the reference and the walk continues; the
//!    first confirmed triple above the threshold (or the last one the reserve allows) is the key.
//! 5. The last level is the minimum model of step 2.
//!
//! The search terminates: every round decrements at least one rank, and there are at most
//! `sum_n (max_n - min_n)` decrements in total.

use crate::hooi::{hooi, hooi_with_start};
use crate::{AlsOptions, HosvdError, Tucker};
use serde::{Deserialize, Serialize};
use tensor_ops::Tensor3;

/// Parameters of [`key_levels`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct KeySearchConfig {
    /// Number of key levels `N` (at least 1).
    pub levels: usize,
    /// Ranks of the first (most accurate) key level.
    pub max_ranks: [usize; 3],
    /// Ranks of the last key level (componentwise `<= max_ranks`).
    pub min_ranks: [usize; 3],
    /// HOOI stopping rule for every key.
    pub als: AlsOptions,
}

impl Default for KeySearchConfig {
    /// The paper's section 5.1 setting: `N = 10`, `(40, 40, 60)` down to `(7, 7, 9)`.
    fn default() -> Self {
        Self {
            levels: 10,
            max_ranks: [40, 40, 60],
            min_ranks: [7, 7, 9],
            als: AlsOptions::default(),
        }
    }
}

/// One key level: an ALS-optimised, ordered Tucker model.
#[derive(Clone, Debug, PartialEq)]
pub struct KeyLevel {
    /// The rank triple.
    pub ranks: [usize; 3],
    /// The model (ordered core).
    pub tucker: Tucker,
    /// The paper's E: `||X - X~||^2 / (I_0 I_1 I_2)`.
    pub mse: f64,
    /// `||X - X~|| / ||X||`.
    pub rel_error: f64,
    /// HOOI sweeps of the accepted ALS run.
    pub iterations: usize,
    /// The mse threshold `l C_E E_1` this level had to exceed (`None` for the first and last).
    pub threshold: Option<f64>,
    /// ALS runs spent on this level (confirmations of candidate triples).
    pub als_runs: usize,
    /// True when the accepted ALS run met its tolerance; false when it stopped at the iteration
    /// cap ([`AlsOptions::max_iter`]) with the core norm still changing.
    pub converged: bool,
}

impl KeyLevels {
    /// Indices of the key levels whose accepted ALS run stopped at the iteration cap without
    /// meeting its tolerance (empty when every key converged).
    pub fn unconverged(&self) -> Vec<usize> {
        (0..self.levels.len())
            .filter(|&k| !self.levels[k].converged)
            .collect()
    }
}

/// The result of [`key_levels`]: level 0 has the max ranks, the last level the min ranks.
#[derive(Clone, Debug, PartialEq)]
pub struct KeyLevels {
    /// The key levels, ranks strictly decreasing (componentwise `<=`, at least one `<`).
    pub levels: Vec<KeyLevel>,
    /// `C_E = E_N / (N E_1)` (infinite if `E_1 = 0`; `N` = the number of levels returned).
    pub c_e: f64,
    /// The `N` asked for; more than `levels.len()` when the rank range has too few steps.
    pub requested_levels: usize,
    /// Max ranks actually used (after clamping).
    pub max_ranks: [usize; 3],
    /// Min ranks actually used (after clamping).
    pub min_ranks: [usize; 3],
    /// True if a requested rank exceeded its mode size and was clamped.
    pub clamped: bool,
    /// `||X||_F^2` of the data, for errors of truncated levels.
    pub data_squared_norm: f64,
    /// `I_0 I_1 I_2` of the data.
    pub data_len: usize,
}

/// Energy of the trailing slice of mode `n` within the leading block `r` of `core`.
fn trailing_energy(core: &Tensor3, r: [usize; 3], n: usize) -> f64 {
    let mut s = r;
    s[n] -= 1;
    (core.leading_squared_norm(r) - core.leading_squared_norm(s)).max(0.0)
}

/// The mode to decrement next (see the module docs), or `None` if all are at their minimum.
fn pick_mode(core: &Tensor3, r: [usize; 3], min: [usize; 3], dims: [usize; 3]) -> Option<usize> {
    let mut best: Option<(usize, f64, usize)> = None;
    for n in 0..3 {
        if r[n] <= min[n] {
            continue;
        }
        let saved = r[(n + 1) % 3] * r[(n + 2) % 3] + dims[n];
        let score = trailing_energy(core, r, n) / saved as f64;
        let better = match best {
            None => true,
            Some((_, bs, bsaved)) => score < bs || (score == bs && saved > bsaved),
        };
        if better {
            best = Some((n, score, saved));
        }
    }
    best.map(|b| b.0)
}

fn slack(r: [usize; 3], min: [usize; 3]) -> usize {
    (0..3).map(|n| r[n] - min[n]).sum()
}

/// The greedy key-tensor search (paper 4.2; the rule is in the module docs).
///
/// Errors: [`HosvdError::BadKeyConfig`] for `levels == 0`, a zero rank or `min > max` in some
/// mode (after clamping to the dims); otherwise as [`crate::hooi`].
pub fn key_levels(x: &Tensor3, cfg: &KeySearchConfig) -> Result<KeyLevels, HosvdError> {
    crate::hosvd::validate(x, [1, 1, 1])?;
    cfg.als.validate()?;
    if cfg.levels == 0 {
        return Err(HosvdError::BadKeyConfig("levels must be at least 1".into()));
    }
    let d = x.dims();
    for n in 0..3 {
        if cfg.max_ranks[n] == 0 || cfg.min_ranks[n] == 0 {
            return Err(HosvdError::BadKeyConfig(format!(
                "ranks must be positive (mode {n}: max {}, min {})",
                cfg.max_ranks[n], cfg.min_ranks[n]
            )));
        }
    }
    let maxr: [usize; 3] = std::array::from_fn(|n| cfg.max_ranks[n].min(d[n]));
    let minr: [usize; 3] = std::array::from_fn(|n| cfg.min_ranks[n].min(d[n]));
    let clamped = maxr != cfg.max_ranks || minr != cfg.min_ranks;
    if let Some(n) = (0..3).find(|&n| minr[n] > maxr[n]) {
        return Err(HosvdError::BadKeyConfig(format!(
            "min rank {} above max rank {} in mode {n} (after clamping to dims {d:?})",
            minr[n], maxr[n]
        )));
    }
    let n_levels = cfg.levels.min(slack(maxr, minr) + 1);
    let x_norm2 = x.squared_norm();
    let len = x.len();

    let (first, last) = if n_levels > 1 {
        let (a, b) = rayon::join(|| hooi(x, maxr, &cfg.als), || hooi(x, minr, &cfg.als));
        (a?, Some(b?))
    } else {
        (hooi(x, maxr, &cfg.als)?, None)
    };
    let e1 = first.1.mse;
    let en = last.as_ref().map_or(e1, |l| l.1.mse);
    let c_e = if e1 > 0.0 {
        en / (n_levels as f64 * e1)
    } else {
        f64::INFINITY
    };
    let mut levels = vec![KeyLevel {
        ranks: maxr,
        tucker: first.0,
        mse: first.1.mse,
        rel_error: first.1.rel_error,
        iterations: first.1.iterations,
        threshold: None,
        als_runs: 1,
        converged: first.1.converged,
    }];

    for idx in 1..n_levels.saturating_sub(1) {
        let threshold = (idx + 1) as f64 * en / n_levels as f64;
        let reserve = n_levels - 1 - idx;
        let prev = &levels[idx - 1];
        let mut reference = prev.tucker.clone();
        let mut r = prev.ranks;
        let mut als_runs = 0;
        let accepted = loop {
            // Walk on truncation estimates of the reference model.
            while slack(r, minr) > reserve {
                let Some(n) = pick_mode(&reference.core, r, minr, d) else {
                    break;
                };
                r[n] -= 1;
                let est = (x_norm2 - reference.core.leading_squared_norm(r)).max(0.0) / len as f64;
                if est > threshold {
                    break;
                }
            }
            // Confirm with ALS warm-started from the truncated reference.
            let start: [faer::MatRef<'_, f64>; 3] =
                std::array::from_fn(|n| reference.factors[n].as_ref().subcols(0, r[n]));
            let (t, rep) = hooi_with_start(x, start, &cfg.als)?;
            als_runs += 1;
            if rep.mse > threshold || slack(r, minr) <= reserve {
                break (t, rep);
            }
            reference = t;
        };
        levels.push(KeyLevel {
            ranks: r,
            tucker: accepted.0,
            mse: accepted.1.mse,
            rel_error: accepted.1.rel_error,
            iterations: accepted.1.iterations,
            threshold: Some(threshold),
            als_runs,
            converged: accepted.1.converged,
        });
    }
    if let Some((t, rep)) = last {
        levels.push(KeyLevel {
            ranks: minr,
            tucker: t,
            mse: rep.mse,
            rel_error: rep.rel_error,
            iterations: rep.iterations,
            threshold: None,
            als_runs: 1,
            converged: rep.converged,
        });
    }
    Ok(KeyLevels {
        levels,
        c_e,
        requested_levels: cfg.levels,
        max_ranks: maxr,
        min_ranks: minr,
        clamped,
        data_squared_norm: x_norm2,
        data_len: len,
    })
}
