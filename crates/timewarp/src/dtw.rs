//! Dynamic time warping with a Sakoe-Chiba band and a slope constraint.
//!
//! A warping path between sequences `a` (`n` frames) and `b` (`m` frames) is a list of index pairs
//! `(i, j)` from `(0, 0)` to `(n - 1, m - 1)` where each step is one of `(1, 1)` (diagonal),
//! `(1, 0)` (a step along `a`) or `(0, 1)` (a step along `b`). Its cost is the sum of the local
//! distances of its pairs,
//!
//! `C(path) = sum_{(i, j) in path} d(a_i, b_j)`,  `d(x, y) = ||x - y||^2`,
//!
//! and DTW returns the path of least cost (Kovar and Gleicher, "Flexible automatic motion blending
//! with registration curves", 2003; the paper's reference [16], section 3.1). The caller passes as
//! features the joint positions in the root frame, so `d` is Kovar and Gleicher's point-cloud
//! distance *without* their rigid 2D fit: the root frame already removes the heading and the
//! horizontal position.
//!
//! Constraints:
//! - band: a pair is allowed only when `|i / (n - 1) - j / (m - 1)| <= band` (normalised times;
//!   Sakoe-Chiba). The band is never narrower than half a frame of the shorter sequence,
//!   `0.5 / (min(n, m) - 1)`, so that the staircase closest to the diagonal always fits; a sequence
//!   of one frame has no band.
//! - slope: at most `max_slope` consecutive steps along one axis (`(1, 0)` or `(0, 1)` steps in a
//!   row). `max_slope = 0` allows diagonal steps only.
//!
//! The constrained dynamic programme keeps, for every cell, the best cost for each "state" (last
//! step diagonal, or a run of `k <= max_slope` steps along `a` or along `b`):
//!
//! `D(i, j, diag) = d(i, j) + min_s D(i - 1, j - 1, s)`,
//! `D(i, j, a_1) = d(i, j) + min(D(i - 1, j, diag), min_k D(i - 1, j, b_k))`,
//! `D(i, j, a_k) = d(i, j) + D(i - 1, j, a_{k-1})` for `k > 1`, and symmetrically for `b`.
//!
//! When `max_slope >= max(n, m) - 1` the slope cannot bind and the usual three-way recursion
//! `D(i, j) = d(i, j) + min(D(i-1, j-1), D(i-1, j), D(i, j-1))` is used instead.
//! Time `O(n m (dim + 2 max_slope + 1))`, memory `O(n m (2 max_slope + 2))` in a reusable
//! [`DtwWorkspace`]. Ties are broken in a fixed order (diagonal, then along `a`, then along `b`), so
//! results are deterministic.
//!
//! Limits: the tables hold `n m (2 max_slope + 2)` values with a binding slope, `2 n m` without;
//! above [`MAX_BUFFER_VALUES`](crate::MAX_BUFFER_VALUES) values (8 GiB) the call fails with
//! [`TimewarpError::TooLarge`] instead of attempting the allocation. A cost that overflows `f64`
//! (feature values around `1e154` and above) is reported as [`TimewarpError::NonFiniteCost`],
//! distinct from [`TimewarpError::NoPath`].

use serde::{Deserialize, Serialize};

use crate::error::TimewarpError;
use crate::frame_seq::{FrameSeq, check_buffer, squared_distance};

/// Band and slope constraints of [`dtw`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DtwConfig {
    /// Sakoe-Chiba band half-width as a fraction of the sequence length (normalised time);
    /// `>= 1` means no band. Must be finite and non-negative.
    pub band: f64,
    /// At most this many consecutive steps along one axis.
    pub max_slope: usize,
}

impl Default for DtwConfig {
    /// `band = 0.15`, `max_slope = 2` (a local slope between 1/3 and 3, as Kovar and Gleicher).
    fn default() -> Self {
        Self {
            band: 0.15,
            max_slope: 2,
        }
    }
}

impl DtwConfig {
    /// Checks that `band` is finite and non-negative.
    pub fn validate(&self) -> Result<(), TimewarpError> {
        if !self.band.is_finite() || self.band < 0.0 {
            return Err(TimewarpError::InvalidConfig {
                what: "band",
                value: self.band.to_string(),
                reason: "must be finite and >= 0",
            });
        }
        Ok(())
    }

    /// The band actually applied between sequences of `n` and `m` frames:
    /// `max(band, 0.5 / (min(n, m) - 1))`, infinite when either sequence has one frame.
    pub fn effective_band(&self, n: usize, m: usize) -> f64 {
        let short = n.min(m);
        if short <= 1 {
            f64::INFINITY
        } else {
            self.band.max(0.5 / (short - 1) as f64)
        }
    }

    /// Whether the pair `(i, j)` lies inside the band between sequences of `n` and `m` frames:
    /// `|i / (n - 1) - j / (m - 1)| <= effective_band(n, m)` (with a tolerance of 1e-12).
    pub fn allows(&self, n: usize, m: usize, i: usize, j: usize) -> bool {
        let w = self.effective_band(n, m);
        if w.is_infinite() {
            return true;
        }
        let x = i as f64 / (n - 1) as f64;
        let y = j as f64 / (m - 1) as f64;
        (x - y).abs() <= w + 1e-12
    }
}

/// The result of [`dtw`]: the optimal path and its cost.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WarpPath {
    /// Matched frame pairs `(i in a, j in b)`, from `(0, 0)` to `(n - 1, m - 1)`, each step
    /// `(1, 1)`, `(1, 0)` or `(0, 1)`.
    pub pairs: Vec<(usize, usize)>,
    /// Sum of the squared Euclidean distances of the matched frames.
    pub cost: f64,
}

/// Reusable buffers for [`dtw_with`] and [`dtw_cost_with`]; they grow to the largest problem seen.
#[derive(Debug, Clone, Default)]
pub struct DtwWorkspace {
    dist: Vec<f64>,
    cost: Vec<f64>,
}

impl DtwWorkspace {
    /// An empty workspace.
    pub fn new() -> Self {
        Self::default()
    }
}

/// Optimal warping path between `a` and `b` under `config` (see the module documentation for the
/// recursion). Allocates its buffers; use [`dtw_with`] to reuse them.
///
/// Errors: empty, ragged or non-finite sequences (`a` is sequence 0, `b` sequence 1), different
/// frame dimensions, an invalid band, [`TimewarpError::NoPath`] when the constraints admit no path,
/// [`TimewarpError::NonFiniteCost`] when the cost overflows (values too large), or
/// [`TimewarpError::TooLarge`] when the tables would exceed
/// [`MAX_BUFFER_VALUES`](crate::MAX_BUFFER_VALUES) (see the module documentation).
pub fn dtw(a: &FrameSeq, b: &FrameSeq, config: &DtwConfig) -> Result<WarpPath, TimewarpError> {
    dtw_with(a, b, config, &mut DtwWorkspace::new())
}

/// [`dtw`] with caller-owned buffers (errors as [`dtw`]).
pub fn dtw_with(
    a: &FrameSeq,
    b: &FrameSeq,
    config: &DtwConfig,
    ws: &mut DtwWorkspace,
) -> Result<WarpPath, TimewarpError> {
    check_pair(a, b, config)?;
    let grid = Grid::new(a.len(), b.len(), config.max_slope)?;
    fill_distances(a, b, config, &grid, ws);
    let cost = run_dp(&grid, ws);
    if !cost.is_finite() {
        return Err(failure(a, b, config, &grid, ws));
    }
    let pairs = backtrack(&grid, &ws.cost);
    Ok(WarpPath { pairs, cost })
}

/// The cost of the optimal path only (no backtracking, no allocation once `ws` is large enough;
/// errors as [`dtw`]).
pub fn dtw_cost_with(
    a: &FrameSeq,
    b: &FrameSeq,
    config: &DtwConfig,
    ws: &mut DtwWorkspace,
) -> Result<f64, TimewarpError> {
    check_pair(a, b, config)?;
    dtw_cost_unchecked(a, b, config, ws)
}

/// Cost of the optimal path for already validated sequences: [`TimewarpError::NoPath`] when there
/// is no path, [`TimewarpError::NonFiniteCost`] when the cost overflows,
/// [`TimewarpError::TooLarge`] for tables over the limit.
pub(crate) fn dtw_cost_unchecked(
    a: &FrameSeq,
    b: &FrameSeq,
    config: &DtwConfig,
    ws: &mut DtwWorkspace,
) -> Result<f64, TimewarpError> {
    let grid = Grid::new(a.len(), b.len(), config.max_slope)?;
    fill_distances(a, b, config, &grid, ws);
    let cost = run_dp(&grid, ws);
    if !cost.is_finite() {
        return Err(failure(a, b, config, &grid, ws));
    }
    Ok(cost)
}

/// Why the optimal cost is not finite: the programme is run again with a local distance of 0 in
/// every cell of the band, so it finds a (finite) path exactly when the constraints admit one; if
/// they do, the real cost overflowed ([`TimewarpError::NonFiniteCost`]), else
/// [`TimewarpError::NoPath`]. Only called on failure (it overwrites the workspace).
fn failure(
    a: &FrameSeq,
    b: &FrameSeq,
    config: &DtwConfig,
    grid: &Grid,
    ws: &mut DtwWorkspace,
) -> TimewarpError {
    let (n, m) = (grid.n, grid.m);
    for i in 0..n {
        for j in 0..m {
            ws.dist[i * m + j] = if config.allows(n, m, i, j) {
                0.0
            } else {
                f64::INFINITY
            };
        }
    }
    if run_dp(grid, ws).is_finite() {
        TimewarpError::NonFiniteCost {
            len_a: a.len(),
            len_b: b.len(),
        }
    } else {
        no_path(a, b, config)
    }
}

fn check_pair(a: &FrameSeq, b: &FrameSeq, config: &DtwConfig) -> Result<(), TimewarpError> {
    config.validate()?;
    a.check(0, 1)?;
    b.check(1, 1)?;
    if a.dim != b.dim {
        return Err(TimewarpError::DimMismatch {
            index: 1,
            expected: a.dim,
            found: b.dim,
        });
    }
    Ok(())
}

fn no_path(a: &FrameSeq, b: &FrameSeq, config: &DtwConfig) -> TimewarpError {
    TimewarpError::NoPath {
        len_a: a.len(),
        len_b: b.len(),
        band: config.band,
        max_slope: config.max_slope,
    }
}

/// Sizes of the dynamic programme: `n x m` cells, `states` per cell.
struct Grid {
    n: usize,
    m: usize,
    /// Run-length limit that binds (`None`: unconstrained three-way recursion).
    k: Option<usize>,
    states: usize,
}

impl Grid {
    /// The sizes for sequences of `n` and `m` frames; [`TimewarpError::TooLarge`] when the
    /// distance and cost tables together (`n m (states + 1)` values) exceed
    /// [`MAX_BUFFER_VALUES`](crate::MAX_BUFFER_VALUES).
    fn new(n: usize, m: usize, max_slope: usize) -> Result<Self, TimewarpError> {
        let longest_run = n.max(m) - 1;
        let grid = if max_slope >= longest_run {
            Self {
                n,
                m,
                k: None,
                states: 1,
            }
        } else {
            Self {
                n,
                m,
                k: Some(max_slope),
                states: 1 + 2 * max_slope,
            }
        };
        check_buffer(
            "DTW table values (n m (2 max_slope + 2), or 2 n m when the slope cannot bind)",
            &[n, m, grid.states + 1],
        )?;
        Ok(grid)
    }

    #[inline]
    fn at(&self, i: usize, j: usize) -> usize {
        (i * self.m + j) * self.states
    }
}

/// Fills the local distances (infinite outside the band).
fn fill_distances(
    a: &FrameSeq,
    b: &FrameSeq,
    config: &DtwConfig,
    grid: &Grid,
    ws: &mut DtwWorkspace,
) {
    let (n, m) = (grid.n, grid.m);
    ws.dist.clear();
    ws.dist.resize(n * m, f64::INFINITY);
    for i in 0..n {
        let fa = a.frame(i);
        for j in 0..m {
            if config.allows(n, m, i, j) {
                ws.dist[i * m + j] = squared_distance(fa, b.frame(j));
            }
        }
    }
}

/// Fills the cost table from the local distances of [`fill_distances`]; returns the best final
/// cost (infinite if none).
fn run_dp(grid: &Grid, ws: &mut DtwWorkspace) -> f64 {
    let (n, m) = (grid.n, grid.m);
    ws.cost.clear();
    ws.cost.resize(n * m * grid.states, f64::INFINITY);
    let dist = &ws.dist;
    let cost = &mut ws.cost;
    match grid.k {
        None => {
            for i in 0..n {
                for j in 0..m {
                    let d = dist[i * m + j];
                    if d.is_infinite() {
                        continue;
                    }
                    let best = if i == 0 && j == 0 {
                        0.0
                    } else {
                        let mut best = f64::INFINITY;
                        if i > 0 && j > 0 {
                            best = cost[(i - 1) * m + j - 1];
                        }
                        if i > 0 {
                            best = best.min(cost[(i - 1) * m + j]);
                        }
                        if j > 0 {
                            best = best.min(cost[i * m + j - 1]);
                        }
                        best
                    };
                    cost[i * m + j] = d + best;
                }
            }
            cost[n * m - 1]
        }
        Some(k) => {
            let s = grid.states;
            for i in 0..n {
                for j in 0..m {
                    let d = dist[i * m + j];
                    if d.is_infinite() {
                        continue;
                    }
                    let here = grid.at(i, j);
                    if i == 0 && j == 0 {
                        cost[here] = d;
                        continue;
                    }
                    if i > 0 && j > 0 {
                        let p = grid.at(i - 1, j - 1);
                        let best = min_of(&cost[p..p + s]);
                        cost[here] = d + best;
                    }
                    if k > 0 && i > 0 {
                        // Steps along a: from (i - 1, j).
                        let p = grid.at(i - 1, j);
                        let first = cost[p].min(min_of(&cost[p + 1 + k..p + 1 + 2 * k]));
                        cost[here + 1] = d + first;
                        for r in 2..=k {
                            cost[here + r] = d + cost[p + r - 1];
                        }
                    }
                    if k > 0 && j > 0 {
                        // Steps along b: from (i, j - 1).
                        let p = grid.at(i, j - 1);
                        let first = cost[p].min(min_of(&cost[p + 1..p + 1 + k]));
                        cost[here + 1 + k] = d + first;
                        for r in 2..=k {
                            cost[here + k + r] = d + cost[p + k + r - 1];
                        }
                    }
                }
            }
            let last = grid.at(n - 1, m - 1);
            min_of(&cost[last..last + s])
        }
    }
}

#[inline]
fn min_of(v: &[f64]) -> f64 {
    v.iter().copied().fold(f64::INFINITY, f64::min)
}

/// Index of the first minimum of `v` (ties: the first).
#[inline]
fn argmin(v: &[f64]) -> usize {
    let mut best = 0;
    for (idx, &x) in v.iter().enumerate() {
        if x < v[best] {
            best = idx;
        }
    }
    best
}

/// Walks back from `(n - 1, m - 1)` through the cost table (which holds a finite final cost).
fn backtrack(grid: &Grid, cost: &[f64]) -> Vec<(usize, usize)> {
    let (n, m) = (grid.n, grid.m);
    let mut pairs = Vec::with_capacity(n + m);
    let (mut i, mut j) = (n - 1, m - 1);
    match grid.k {
        None => {
            pairs.push((i, j));
            while i > 0 || j > 0 {
                let diag = if i > 0 && j > 0 {
                    cost[(i - 1) * m + j - 1]
                } else {
                    f64::INFINITY
                };
                let up = if i > 0 {
                    cost[(i - 1) * m + j]
                } else {
                    f64::INFINITY
                };
                let left = if j > 0 {
                    cost[i * m + j - 1]
                } else {
                    f64::INFINITY
                };
                if diag <= up && diag <= left {
                    i -= 1;
                    j -= 1;
                } else if up <= left {
                    i -= 1;
                } else {
                    j -= 1;
                }
                pairs.push((i, j));
            }
        }
        Some(k) => {
            let s = grid.states;
            let last = grid.at(i, j);
            let mut state = argmin(&cost[last..last + s]);
            pairs.push((i, j));
            while i > 0 || j > 0 {
                if state == 0 {
                    i -= 1;
                    j -= 1;
                    let p = grid.at(i, j);
                    state = argmin(&cost[p..p + s]);
                } else if state <= k {
                    // Run along a of length `state`.
                    i -= 1;
                    let p = grid.at(i, j);
                    state = if state > 1 {
                        state - 1
                    } else {
                        let b_best = argmin(&cost[p + 1 + k..p + 1 + 2 * k]);
                        if cost[p] <= cost[p + 1 + k + b_best] {
                            0
                        } else {
                            1 + k + b_best
                        }
                    };
                } else {
                    let r = state - k;
                    j -= 1;
                    let p = grid.at(i, j);
                    state = if r > 1 {
                        state - 1
                    } else {
                        let a_best = argmin(&cost[p + 1..p + 1 + k]);
                        if cost[p] <= cost[p + 1 + a_best] {
                            0
                        } else {
                            1 + a_best
                        }
                    };
                }
                pairs.push((i, j));
            }
        }
    }
    pairs.reverse();
    debug_assert_eq!(pairs.first(), Some(&(0, 0)));
    pairs
}
