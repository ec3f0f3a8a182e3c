//! Conditional simulation: sequential Gaussian simulation (SGS) of a stationary Gaussian random
//! field, honouring the data.
//!
//! # The method
//!
//! `Z(x)` is a Gaussian random field with mean `m` and covariance `C(h) = K - gamma(h)` (`gamma` a
//! bounded variogram, `K = nugget + sum of partial sills` its total sill). The joint law of the
//! field at the targets `x_1 .. x_M` given the data factorises along any order (path) `pi`:
//!
//! ```text
//! p(z_pi(1), .., z_pi(M) | data) = prod_j p(z_pi(j) | data, z_pi(1), .., z_pi(j-1))
//! ```
//!
//! and every factor is Gaussian, with the simple kriging estimate as its mean and the simple
//! kriging variance as its variance. SGS visits the targets along a random path and draws each in
//! turn, conditioning on the data *and the targets simulated before it*, restricted to a moving
//! neighbourhood (the `k` nearest of them, or those within a radius):
//!
//! ```text
//! C lambda = c              C_ij = C(|u_i - u_j|) (C_ii = K), c_i = C(|u_0 - u_i|), i, j neighbours
//! z*(x_0)      = m + lambda^t (y - m)
//! sigma^2(x_0) = K - lambda^t c
//! z(x_0)       = z*(x_0) + sigma(x_0) eps,      eps ~ N(0, 1)
//! ```
//!
//! with `y` the neighbours' values (data or simulated) and `u` the coordinates after the
//! [`Anisotropy`] map. Between distinct points `C(h) = K - nugget - gamma_s(h)` (`gamma_s` the
//! structured part, the same convention as [`crate::Krige`]: the nugget is micro-scale variation,
//! independent between distinct points). With every earlier node in the neighbourhood (`k >=` data
//! plus targets) the realisations are exact draws from the conditional law (ensemble mean: the
//! simple kriging estimate; ensemble variance: the simple kriging variance; ensemble covariance:
//! the conditional covariance); a smaller neighbourhood is the usual approximation (the screening
//! effect makes the far nodes nearly irrelevant for the common models).
//!
//! [`SgsMean::Ordinary`] replaces simple by ordinary kriging at every node (weights summing to
//! one, a Lagrange multiplier `mu`, `[C 1; 1^t 0] [lambda; mu] = [c; 1]`, `z* = lambda^t y`,
//! `sigma^2 = K - lambda^t c - mu`): the mean is re-estimated in each neighbourhood, which follows a
//! drifting mean but does not reproduce the model exactly (the textbook SGS is simple kriging).
//!
//! # The data
//!
//! A target at a data site (within `1e-12` of the largest extent of data and targets) takes the
//! datum exactly; targets at the same place take one simulated value. Simulation honours the data
//! with or without a nugget (exact kriging). SGS assumes Gaussian data: transform skewed data to
//! normal scores first (not done here). Two data at one site are an error
//! ([`KrigingError::CoincidentData`]).
//!
//! # Random numbers and determinism
//!
//! Realisation `r` draws from its own SplitMix64 stream seeded from `(seed, r)` (its path, a
//! Fisher-Yates shuffle, then one standard normal per node by the Box-Muller transform, in path
//! order). Realisations run in parallel (rayon), each from its own stream, and neighbour ties are
//! broken by index: the same seed gives the same bits whatever the number of threads.
//! [`SgsPath::Shared`] draws one path (from a stream of its own) for every realisation: the
//! neighbourhoods and kriging weights are then the same for all realisations and are computed
//! once (in parallel over the nodes), and each realisation only applies them (a dot product and a
//! draw per node); the realisations stay independent draws from the same approximate law, but the
//! neighbourhood's approximation is the same in all of them instead of varying with the path.
//! (The bits are those of this platform's `ln`, `sin` and `cos`; another libm may differ in the
//! last bits.)
//!
//! # Cost
//!
//! A node costs a neighbour search (k-d trees over the data and over the targets; the search for
//! earlier nodes skips every subtree whose nodes all come later on the path), the covariance at
//! `k (k + 1) / 2` pairs and a `k x k` Cholesky factorisation (`k^3 / 6`). With a path per
//! realisation and at least four realisations, each node's nearest data and `8 k` nearest other
//! nodes are found once (about `48 k` bytes per target, up to `2^24` target-neighbour pairs), which
//! settles most later searches without the trees (same neighbours). With a shared path the systems
//! are solved once, and each realisation costs `O(k)` per target. Memory for the result: `8 R M`
//! bytes for `R` realisations of `M` targets.

use faer::MatRef;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::anisotropy::Anisotropy;
use crate::error::KrigingError;
use crate::geo::Neighbourhood;
use crate::kdtree::KdTree;
use crate::nested::NestedVariogram;

/// Smallest `(min L_kk / max L_kk)^2` of a node's Cholesky factor accepted (as [`crate::Krige`]).
const PIVOT_RATIO_MIN: f64 = 1e-14;
/// Path positions per parallel block when the weights of a shared path are computed.
const BLOCK: usize = 256;
/// Leaves of the target tree hold at most this many targets.
const LEAF: usize = 8;
/// Stream index of the shared path (realisations use `0..R`).
const SHARED_PATH_LANE: u64 = u64::MAX;
/// Largest `nodes x k` for which [`Lists`] are built (48 bytes per entry: 768 MiB).
const LISTS_MAX_ENTRIES: usize = 1 << 24;
/// Fewest realisations for which [`Lists`] are built (they cost about two realisations).
const LISTS_MIN_REALISATIONS: usize = 4;
/// Candidates per node in [`Lists`], in multiples of `k`.
const CANDIDATES_PER_K: usize = 8;

/// The mean of the simulated field (which kriging each node uses).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub enum SgsMean {
    /// Simple kriging with this known mean `m`.
    Known(f64),
    /// Simple kriging with the arithmetic mean of the data as `m` (the default; conditional
    /// simulation only).
    #[default]
    DataMean,
    /// Ordinary kriging at every node: the mean is re-estimated in each neighbourhood (weights
    /// summing to one). Needs at least one neighbour per node; conditional simulation only.
    Ordinary,
}

/// How the random path over the targets is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum SgsPath {
    /// A new random path per realisation (the textbook SGS; the default): each realisation solves
    /// one kriging system per target.
    #[default]
    PerRealisation,
    /// One random path for every realisation: the neighbourhoods and weights are computed once and
    /// reused, so each further realisation costs a dot product and a draw per target (much faster
    /// for many realisations). Each realisation is still an independent draw from the same
    /// approximate law.
    Shared,
}

/// Sequential Gaussian simulation, as a builder: the variogram, the mean, the neighbourhood, the
/// anisotropy, the path, the seed and the number of realisations; [`Sgs::simulate`] (conditional),
/// [`Sgs::simulate_grid`] and [`Sgs::simulate_unconditional`] draw the realisations. See the
/// [module docs](crate::simulate) for the method and its formulas.
///
/// Defaults: simple kriging with the data's mean ([`SgsMean::DataMean`]), the 16 nearest data or
/// simulated nodes ([`Neighbourhood::Nearest`]), isotropic, a path per realisation, seed 0, one
/// realisation.
///
/// ```
/// use kriging::faer::Mat;
/// use kriging::{NestedVariogram, Sgs, VariogramModel};
///
/// // Five data along a line and 40 targets on it, two of them at data sites.
/// let x = [2.0, 9.0, 15.5, 22.0, 31.0];
/// let z = [0.4, -0.3, 1.1, 0.8, -0.6];
/// let coords = Mat::from_fn(5, 1, |i, _| x[i]);
/// let targets = Mat::from_fn(40, 1, |i, _| if i == 7 { 9.0 } else if i == 8 { 22.0 } else { i as f64 });
/// let v = NestedVariogram::single(VariogramModel::Exponential, 0.0, 1.0, 12.0)?;
/// let sgs = Sgs::new(v).simple(0.0).neighbours(12).seed(42).realisations(200);
/// let sims = sgs.simulate(coords.as_ref(), &z, targets.as_ref())?;
/// assert_eq!((sims.n_realisations(), sims.n_targets()), (200, 40));
/// // Every realisation honours the data exactly.
/// for r in sims.iter() {
///     assert_eq!((r[7], r[8]), (-0.3, 0.8));
/// }
/// // Far from the data the ensemble spreads over the sill (here 1); next to a datum it does not.
/// let var = sims.variance();
/// assert!(var[39] > 0.6 && var[10] < 0.5);
/// // The same seed gives the same realisations (whatever the number of threads).
/// assert_eq!(sgs.simulate(coords.as_ref(), &z, targets.as_ref())?, sims);
/// # Ok::<(), kriging::KrigingError>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Sgs {
    /// The variogram (bounded: every structure reaches a sill; a pure nugget is allowed).
    pub variogram: NestedVariogram,
    /// The mean, and which kriging each node uses.
    pub mean: SgsMean,
    /// Which data and earlier nodes condition a node: [`Neighbourhood::Nearest`] or
    /// [`Neighbourhood::Radius`] ([`Neighbourhood::Global`] is refused: use `Nearest` with a `k`
    /// at least the number of data plus targets for the exact law).
    pub neighbourhood: Neighbourhood,
    /// Geometric anisotropy of the variogram.
    pub anisotropy: Anisotropy,
    /// A path per realisation, or one shared.
    pub path: SgsPath,
    /// The seed of every random stream.
    pub seed: u64,
    /// Number of realisations, at least one; realisations times targets at most
    /// [`MAX_SIMULATED_VALUES`].
    pub realisations: usize,
}

/// The most values a simulation returns: realisations times targets (`2^30`, 8 GiB of results).
/// A larger request is a [`KrigingError::InvalidConfig`] error before anything is allocated
/// (draw the realisations in batches with different seeds instead).
pub const MAX_SIMULATED_VALUES: usize = 1 << 30;

impl Sgs {
    /// The defaults (see [`Sgs`]) with this variogram (a [`crate::Variogram`] or a
    /// [`NestedVariogram`]; a fitted one is [`crate::KrigeModel::variogram`], with its
    /// [`crate::KrigeModel::anisotropy`] for [`Sgs::anisotropy`]).
    pub fn new(variogram: impl Into<NestedVariogram>) -> Self {
        Sgs {
            variogram: variogram.into(),
            mean: SgsMean::DataMean,
            neighbourhood: Neighbourhood::Nearest { k: 16 },
            anisotropy: Anisotropy::Isotropic,
            path: SgsPath::PerRealisation,
            seed: 0,
            realisations: 1,
        }
    }

    /// Simple kriging with the known mean `mean` ([`SgsMean::Known`]).
    pub fn simple(mut self, mean: f64) -> Self {
        self.mean = SgsMean::Known(mean);
        self
    }

    /// Ordinary kriging at every node ([`SgsMean::Ordinary`]).
    pub fn ordinary(mut self) -> Self {
        self.mean = SgsMean::Ordinary;
        self
    }

    /// Sets the mean ([`SgsMean`]).
    pub fn mean(mut self, mean: SgsMean) -> Self {
        self.mean = mean;
        self
    }

    /// The `k` nearest data or earlier nodes ([`Neighbourhood::Nearest`]).
    pub fn neighbours(mut self, k: usize) -> Self {
        self.neighbourhood = Neighbourhood::Nearest { k };
        self
    }

    /// Sets the neighbourhood (`Nearest` or `Radius`).
    pub fn neighbourhood(mut self, n: Neighbourhood) -> Self {
        self.neighbourhood = n;
        self
    }

    /// Sets the geometric anisotropy.
    pub fn anisotropy(mut self, a: Anisotropy) -> Self {
        self.anisotropy = a;
        self
    }

    /// Sets the path mode ([`SgsPath`]).
    pub fn path(mut self, p: SgsPath) -> Self {
        self.path = p;
        self
    }

    /// Sets the seed.
    pub fn seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// Sets the number of realisations.
    pub fn realisations(mut self, r: usize) -> Self {
        self.realisations = r;
        self
    }

    /// Realisations at the rows of `targets` (m x d) conditioned on the data: `coords` (n x d, one
    /// datum per row, n >= 1) and `values` (n). A target at a data site takes the datum.
    ///
    /// Errors: no data ([`KrigingError::TooFewSamples`]; see [`Sgs::simulate_unconditional`]),
    /// shapes ([`KrigingError::ShapeMismatch`]), NaN or infinity in coordinates, values or targets
    /// ([`KrigingError::NonFinite`] with row and column), two data at one site
    /// ([`KrigingError::CoincidentData`]), zero realisations or more than
    /// [`MAX_SIMULATED_VALUES`] values in all, a global or empty neighbourhood, a
    /// non-finite mean or an anisotropy that does not fit ([`KrigingError::InvalidConfig`]), an
    /// unbounded or invalid variogram ([`KrigingError::InvalidVariogram`] or
    /// [`KrigingError::InvalidConfig`]), and a node whose kriging system fails
    /// ([`KrigingError::SimulationNode`]: singular, or ordinary kriging without neighbours).
    pub fn simulate(
        &self,
        coords: MatRef<'_, f64>,
        values: &[f64],
        targets: MatRef<'_, f64>,
    ) -> Result<Realisations, KrigingError> {
        if coords.nrows() == 0 {
            return Err(KrigingError::TooFewSamples {
                what: "conditional simulation (without data use Sgs::simulate_unconditional)",
                needed: 1,
                got: 0,
            });
        }
        self.run(coords, values, targets)
    }

    /// As [`Sgs::simulate`] on the grid `xs` x `ys` (2-D data): target `j * xs.len() + i` is at
    /// `(xs[i], ys[j])` (x fastest, as [`crate::KrigeModel::predict_grid`]).
    pub fn simulate_grid(
        &self,
        coords: MatRef<'_, f64>,
        values: &[f64],
        xs: &[f64],
        ys: &[f64],
    ) -> Result<Realisations, KrigingError> {
        if coords.ncols() != 2 {
            return Err(KrigingError::ShapeMismatch {
                what: "grid simulation needs 2-D coordinates",
                expected: 2,
                got: coords.ncols(),
            });
        }
        let nx = xs.len();
        let targets = faer::Mat::from_fn(nx * ys.len(), 2, |t, c| {
            if c == 0 { xs[t % nx] } else { ys[t / nx] }
        });
        self.simulate(coords, values, targets.as_ref())
    }

    /// Unconditional realisations at the rows of `targets` (m x d): no data, so the mean must be
    /// known ([`SgsMean::Known`]; anything else is [`KrigingError::InvalidConfig`]). The other
    /// errors are those of [`Sgs::simulate`].
    ///
    /// ```
    /// use kriging::faer::Mat;
    /// use kriging::{NestedVariogram, Sgs, VariogramModel};
    ///
    /// let targets = Mat::from_fn(50, 1, |i, _| i as f64);
    /// let v = NestedVariogram::single(VariogramModel::Spherical, 0.0, 2.0, 10.0)?;
    /// let sims = Sgs::new(v.clone()).simple(5.0).realisations(400).simulate_unconditional(targets.as_ref())?;
    /// // Ensemble mean about 5 and ensemble variance about the sill 2 at every target.
    /// let (mean, var) = (sims.mean(), sims.variance());
    /// assert!(mean.iter().all(|m| (m - 5.0).abs() < 0.4));
    /// assert!(var.iter().all(|s| (s - 2.0).abs() < 0.6));
    /// // Without data there is no data mean to use.
    /// assert!(Sgs::new(v).simulate_unconditional(targets.as_ref()).is_err());
    /// # Ok::<(), kriging::KrigingError>(())
    /// ```
    pub fn simulate_unconditional(
        &self,
        targets: MatRef<'_, f64>,
    ) -> Result<Realisations, KrigingError> {
        if !matches!(self.mean, SgsMean::Known(_)) {
            return Err(KrigingError::InvalidConfig(format!(
                "unconditional simulation needs a known mean (Sgs::simple(mean)), got {:?}",
                self.mean
            )));
        }
        let none = faer::Mat::<f64>::zeros(0, targets.ncols());
        self.run(none.as_ref(), &[], targets)
    }

    fn run(
        &self,
        coords: MatRef<'_, f64>,
        values: &[f64],
        targets: MatRef<'_, f64>,
    ) -> Result<Realisations, KrigingError> {
        let prep = Prepared::new(self, coords, values, targets)?;
        let m = targets.nrows();
        let nr = self.realisations;
        let mut out = vec![0.0; nr * m];
        if m == 0 {
            return Ok(Realisations {
                n_targets: 0,
                n_realisations: nr,
                values: out,
            });
        }
        let (records, lists) = match self.path {
            SgsPath::Shared => (Some(prep.shared_records(self.seed)?), None),
            // Several paths over the same nodes: each node's nearest data and nodes, found once,
            // shortcut its searches on every path (the same neighbours, found faster).
            SgsPath::PerRealisation if nr >= LISTS_MIN_REALISATIONS => (None, prep.lists()),
            SgsPath::PerRealisation => (None, None),
        };
        let results: Vec<Result<(), KrigingError>> = out
            .par_chunks_mut(m)
            .enumerate()
            .map(|(r, chunk)| {
                prep.realisation(self.seed, r, records.as_ref(), lists.as_ref(), chunk)
            })
            .collect();
        for res in results {
            res?;
        }
        Ok(Realisations {
            n_targets: m,
            n_realisations: nr,
            values: out,
        })
    }
}

/// The realisations of a simulation: `n_realisations` vectors of `n_targets` values, in the order
/// of the targets.
#[derive(Debug, Clone, PartialEq)]
pub struct Realisations {
    n_targets: usize,
    n_realisations: usize,
    /// Realisation-major: value of target `t` in realisation `r` at `r * n_targets + t`.
    values: Vec<f64>,
}

impl Realisations {
    /// Number of realisations.
    pub fn n_realisations(&self) -> usize {
        self.n_realisations
    }

    /// Number of targets (values per realisation).
    pub fn n_targets(&self) -> usize {
        self.n_targets
    }

    /// Realisation `r` (one value per target), `None` past the last.
    pub fn realisation(&self, r: usize) -> Option<&[f64]> {
        if r >= self.n_realisations {
            return None;
        }
        self.values
            .get(r * self.n_targets..(r + 1) * self.n_targets)
    }

    /// The realisations in order.
    pub fn iter(&self) -> impl Iterator<Item = &[f64]> {
        (0..self.n_realisations).filter_map(|r| self.realisation(r))
    }

    /// Every value, realisation-major (`r * n_targets + t`).
    pub fn as_slice(&self) -> &[f64] {
        &self.values
    }

    /// Every value, realisation-major (`r * n_targets + t`).
    pub fn into_vec(self) -> Vec<f64> {
        self.values
    }

    /// The ensemble mean at each target, `1/R sum_r z_r(x_t)`.
    pub fn mean(&self) -> Vec<f64> {
        let mut s = vec![0.0; self.n_targets];
        for r in self.iter() {
            for (a, b) in s.iter_mut().zip(r) {
                *a += b;
            }
        }
        let nr = self.n_realisations.max(1) as f64;
        s.iter_mut().for_each(|a| *a /= nr);
        s
    }

    /// The ensemble variance at each target, `1/(R-1) sum_r (z_r(x_t) - mean_t)^2` (0 for a single
    /// realisation).
    pub fn variance(&self) -> Vec<f64> {
        let mean = self.mean();
        let mut s = vec![0.0; self.n_targets];
        for r in self.iter() {
            for ((a, b), m) in s.iter_mut().zip(r).zip(&mean) {
                *a += (b - m) * (b - m);
            }
        }
        let dof = self.n_realisations.saturating_sub(1).max(1) as f64;
        s.iter_mut().for_each(|a| *a /= dof);
        s
    }
}

/// Where a target's value comes from.
#[derive(Debug, Clone, Copy)]
enum Source {
    /// A datum (the target is at its site).
    Datum(usize),
    /// A simulated node (targets at one place share it).
    Node(usize),
}

/// The inputs in simulation form (transformed coordinates, residual values, trees).
struct Prepared {
    d: usize,
    /// Number of data.
    n: usize,
    /// Row-major n x d data coordinates after centring and anisotropy.
    data_pts: Vec<f64>,
    /// The data as given (copied into targets at their sites).
    data_values: Vec<f64>,
    /// `value - shift` per datum.
    data_res: Vec<f64>,
    /// The mean simulated around (simple: the mean; ordinary: the data mean, for precision only).
    shift: f64,
    /// Row-major coordinates of the simulated nodes (distinct targets not at data sites).
    node_pts: Vec<f64>,
    /// The first target of each node (for error messages).
    node_target: Vec<usize>,
    sources: Vec<Source>,
    data_tree: RankTree,
    node_tree: RankTree,
    /// Largest neighbour count.
    k: usize,
    /// Squared search radius (infinite for nearest neighbours).
    r2: f64,
    /// Total sill `K = C(0)`.
    sill: f64,
    /// `K - nugget`: the covariance between distinct points is `psill - gamma_s(h)`.
    psill: f64,
    variogram: NestedVariogram,
    ordinary: bool,
    realisations: usize,
}

impl Prepared {
    fn new(
        sgs: &Sgs,
        coords: MatRef<'_, f64>,
        values: &[f64],
        targets: MatRef<'_, f64>,
    ) -> Result<Self, KrigingError> {
        let (n, d) = coords.shape();
        if values.len() != n {
            return Err(KrigingError::ShapeMismatch {
                what: "values length vs coordinate rows",
                expected: n,
                got: values.len(),
            });
        }
        if d == 0 {
            return Err(KrigingError::ShapeMismatch {
                what: "coordinate dimensions (need at least one)",
                expected: 1,
                got: 0,
            });
        }
        if targets.ncols() != d {
            return Err(KrigingError::ShapeMismatch {
                what: "target columns vs coordinate columns",
                expected: d,
                got: targets.ncols(),
            });
        }
        if sgs.realisations == 0 {
            return Err(KrigingError::InvalidConfig(
                "a simulation needs at least one realisation, got 0".into(),
            ));
        }
        if sgs
            .realisations
            .checked_mul(targets.nrows())
            .is_none_or(|n| n > MAX_SIMULATED_VALUES)
        {
            return Err(KrigingError::InvalidConfig(format!(
                "{} realisations of {} targets do not fit in memory (at most \
                 kriging::MAX_SIMULATED_VALUES = {MAX_SIMULATED_VALUES} values in all)",
                sgs.realisations,
                targets.nrows()
            )));
        }
        let (k, r2) = match sgs.neighbourhood {
            Neighbourhood::Nearest { k } if k >= 1 => (k, f64::INFINITY),
            Neighbourhood::Radius { radius, max }
                if radius.is_finite() && radius > 0.0 && max >= 1 =>
            {
                (max, radius * radius)
            }
            Neighbourhood::Global => {
                return Err(KrigingError::InvalidConfig(
                    "sequential simulation needs a moving neighbourhood (Neighbourhood::Nearest \
                     { k } or Radius); for the exact conditional law use Nearest with k at least \
                     the number of data plus targets"
                        .into(),
                ));
            }
            other => {
                return Err(KrigingError::InvalidConfig(format!(
                    "simulation neighbourhood {other:?}: need at least one neighbour and a finite \
                     radius > 0"
                )));
            }
        };
        let v = &sgs.variogram;
        validate_variogram(v)?;
        let ordinary = sgs.mean == SgsMean::Ordinary;
        match sgs.mean {
            SgsMean::Known(m) if !m.is_finite() => {
                return Err(KrigingError::InvalidConfig(format!(
                    "the mean of the simulation must be finite, got {m}"
                )));
            }
            SgsMean::DataMean | SgsMean::Ordinary if n == 0 => {
                return Err(KrigingError::InvalidConfig(
                    "without data the simulation needs a known mean (Sgs::simple(mean))".into(),
                ));
            }
            _ => {}
        }
        crate::check_finite("coordinates", coords)?;
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(KrigingError::NonFinite {
                what: "values",
                row: i,
                col: 0,
            });
        }
        crate::check_finite("targets", targets)?;
        // Simple kriging: the known mean; ordinary: the data mean (the weights sum to one, so
        // this only centres the values for precision).
        let shift = match sgs.mean {
            SgsMean::Known(m) => m,
            SgsMean::DataMean | SgsMean::Ordinary => values.iter().sum::<f64>() / n as f64,
        };
        let amat = sgs.anisotropy.matrix(d)?;
        let m = targets.nrows();
        // Centre on the data (or the targets without data) for precision.
        let (src, rows) = if n > 0 { (coords, n) } else { (targets, m) };
        let centre: Vec<f64> = (0..d)
            .map(|c| (0..rows).map(|i| src[(i, c)]).sum::<f64>() / rows.max(1) as f64)
            .collect();
        let map = |x: MatRef<'_, f64>| -> Vec<f64> {
            let mut out = vec![0.0; x.nrows() * d];
            for i in 0..x.nrows() {
                for r in 0..d {
                    out[i * d + r] = (0..d)
                        .map(|c| amat[r * d + c] * (x[(i, c)] - centre[c]))
                        .sum();
                }
            }
            out
        };
        let data_pts = map(coords);
        let target_pts = map(targets);
        // Coincidence tolerance: relative to the largest extent of data and targets.
        let mut extent = 0.0f64;
        for c in 0..d {
            let col = data_pts.iter().chain(&target_pts).skip(c).step_by(d);
            let (lo, hi) = col.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
                (lo.min(x), hi.max(x))
            });
            if hi > lo {
                extent = extent.max(hi - lo);
            }
        }
        let tol2 = (1e-12 * extent).powi(2);
        let data_kd = KdTree::new(&data_pts, d);
        let mut nb = Vec::new();
        for i in 0..n {
            data_kd.nearest(
                &data_pts,
                &data_pts[i * d..(i + 1) * d],
                1,
                tol2,
                Some(i),
                &mut nb,
            );
            if let Some(&(_, j)) = nb.first() {
                return Err(KrigingError::CoincidentData {
                    first: i.min(j),
                    second: i.max(j),
                });
            }
        }
        // Targets at data sites take the datum; targets at one place share a node.
        let target_tree = KdTree::new(&target_pts, d);
        let mut sources = Vec::with_capacity(m);
        let mut node_pts = Vec::new();
        let mut node_target = Vec::new();
        for t in 0..m {
            let u = &target_pts[t * d..(t + 1) * d];
            data_kd.nearest(&data_pts, u, 1, tol2, None, &mut nb);
            if let Some(&(_, i)) = nb.first() {
                sources.push(Source::Datum(i));
                continue;
            }
            target_tree.nearest(&target_pts, u, 8, tol2, Some(t), &mut nb);
            let earlier = nb.iter().map(|e| e.1).filter(|&j| j < t).min();
            match earlier.map(|j| sources[j]) {
                Some(src) => sources.push(src),
                None => {
                    sources.push(Source::Node(node_target.len()));
                    node_target.push(t);
                    node_pts.extend_from_slice(u);
                }
            }
        }
        let node_tree = RankTree::new(&node_pts, d);
        let data_tree = RankTree::new(&data_pts, d);
        let sill = v.total_sill();
        // More neighbours than data and nodes cannot be found (the same neighbourhoods).
        let k = k.min(n + node_target.len()).max(1);
        Ok(Prepared {
            d,
            n,
            data_pts,
            data_values: values.to_vec(),
            data_res: values.iter().map(|z| z - shift).collect(),
            shift,
            node_pts,
            node_target,
            sources,
            data_tree,
            node_tree,
            k,
            r2,
            sill,
            psill: sill - v.nugget,
            variogram: v.clone(),
            ordinary,
            realisations: sgs.realisations,
        })
    }

    fn n_nodes(&self) -> usize {
        self.node_target.len()
    }

    /// Covariance between distinct points at distance `h`.
    #[inline]
    fn cov(&self, h: f64) -> f64 {
        self.psill - self.variogram.structured(h)
    }

    /// The neighbours, weights and standard deviation of node `node` conditioned on the data and
    /// the nodes of rank below `limit` on `path`, into `s` (neighbour ids: datum `i`, node
    /// `n + j`). With `lists` ([`Lists`]) the data come from the node's list and the earlier
    /// nodes from its candidates when these settle them (see [`Prepared::merge_candidates`]);
    /// otherwise (and as the fallback) from the trees. The neighbours are the same either way: the
    /// `k` smallest (squared distance, id) keys within the radius.
    fn node_system(
        &self,
        node: usize,
        path: &PathRanks,
        limit: usize,
        lists: Option<&Lists>,
        s: &mut Scratch,
    ) -> Result<(), KrigingError> {
        let d = self.d;
        let q = &self.node_pts[node * d..(node + 1) * d];
        let nodes = TreeQuery {
            point: q,
            k: self.k,
            r2: self.r2,
            ranks: Some((&path.tree, &path.min, limit)),
            offset: self.n,
        };
        if let Some(l) = lists {
            if !self.merge_candidates(node, l, &path.node, limit, s) {
                s.nb.clear();
                s.nb.extend_from_slice(l.data_row(node));
                self.node_tree.search(&nodes, &mut s.nb);
            }
            return self.solve_node(node, s);
        }
        s.nb.clear();
        // The denser set first (the data early on the path, the earlier nodes once they
        // outnumber the data): its near points bound the search of the other.
        let data = TreeQuery {
            ranks: None,
            offset: 0,
            ..nodes
        };
        if limit > self.n {
            self.node_tree.search(&nodes, &mut s.nb);
            self.data_tree.search(&data, &mut s.nb);
        } else {
            self.data_tree.search(&data, &mut s.nb);
            self.node_tree.search(&nodes, &mut s.nb);
        }
        self.solve_node(node, s)
    }

    /// The neighbourhood of `node` from its lists, into `s.nb`: its data and the earlier nodes
    /// (rank below `limit`) among its candidates, merged by (distance, index). Returns whether
    /// the candidates settle it: a node off the list has a larger key than every node on it, so
    /// the scan may stop once `k` keys (data or earlier nodes) are below the next candidate's key
    /// or that candidate is beyond the radius; a list that runs out settles it only when it holds
    /// every other node.
    fn merge_candidates(
        &self,
        node: usize,
        l: &Lists,
        rank: &[usize],
        limit: usize,
        s: &mut Scratch,
    ) -> bool {
        let d = self.d;
        let k = self.k;
        let q = &self.node_pts[node * d..(node + 1) * d];
        let data = l.data_row(node);
        let found = &mut s.found;
        found.clear();
        let mut below = 0; // data with a key below the current candidate's
        let mut settled = l.complete;
        for &j in &l.nodes[node * l.len..(node + 1) * l.len] {
            let j = j as usize;
            let p = &self.node_pts[j * d..(j + 1) * d];
            let dist: f64 = p.iter().zip(q).map(|(a, b)| (a - b) * (a - b)).sum();
            let key = (dist, self.n + j);
            while below < data.len() && data[below] < key {
                below += 1;
            }
            if dist > self.r2 || found.len() + below >= k {
                settled = true;
                break;
            }
            if rank[j] < limit {
                found.push(key);
            }
        }
        if !settled {
            return false;
        }
        // Merge the two sorted lists, the first k keys.
        s.nb.clear();
        let (mut a, mut b) = (0, 0);
        while s.nb.len() < k && (a < data.len() || b < found.len()) {
            if b == found.len() || (a < data.len() && data[a] < found[b]) {
                s.nb.push(data[a]);
                a += 1;
            } else {
                s.nb.push(found[b]);
                b += 1;
            }
        }
        true
    }

    /// The kriging weights and standard deviation of node `node` from its neighbours `s.nb`.
    fn solve_node(&self, node: usize, s: &mut Scratch) -> Result<(), KrigingError> {
        let d = self.d;
        let kk = s.nb.len();
        s.ids.clear();
        s.w.clear();
        if kk == 0 {
            if self.ordinary {
                return Err(KrigingError::QueryNeighbourhood {
                    point: self.node_target[node],
                    needed: 1,
                    got: 0,
                });
            }
            s.sd = self.sill.sqrt();
            return Ok(());
        }
        // Neighbour coordinates, then the lower triangle of C (row-major kk x kk) and c.
        s.xyz.clear();
        for &(_, id) in &s.nb {
            s.ids.push(id);
            let p = if id < self.n {
                &self.data_pts[id * d..(id + 1) * d]
            } else {
                &self.node_pts[(id - self.n) * d..(id - self.n + 1) * d]
            };
            s.xyz.extend_from_slice(p);
        }
        s.a.clear();
        s.a.resize(kk * kk, 0.0);
        s.c.clear();
        for i in 0..kk {
            let pi = &s.xyz[i * d..(i + 1) * d];
            for j in 0..i {
                let pj = &s.xyz[j * d..(j + 1) * d];
                let h2: f64 = pi.iter().zip(pj).map(|(a, b)| (a - b) * (a - b)).sum();
                s.a[i * kk + j] = self.cov(h2.sqrt());
            }
            s.a[i * kk + i] = self.sill;
            s.c.push(self.cov(s.nb[i].0.sqrt()));
        }
        if let Err(ratio) = cholesky(&mut s.a, kk) {
            return Err(KrigingError::Singular {
                what: "a sequential-simulation neighbourhood system",
                size: kk,
                pivot_ratio: ratio,
                residual: f64::NAN,
            });
        }
        // v = L^-1 c; simple: lambda = L^-t v, sigma^2 = K - v.v.
        forward(&s.a, kk, &mut s.c);
        let vv: f64 = s.c.iter().map(|x| x * x).sum();
        s.w.extend_from_slice(&s.c);
        backward(&s.a, kk, &mut s.w);
        let mut var = self.sill - vv;
        if self.ordinary {
            // f_w = L^-1 1, g = L^-t f_w = C^-1 1: lambda = C^-1 c + g (1 - f_w.v) / (f_w.f_w),
            // sigma^2 = K - v.v + (1 - f_w.v)^2 / (f_w.f_w).
            s.g.clear();
            s.g.resize(kk, 1.0);
            forward(&s.a, kk, &mut s.g);
            let ff: f64 = s.g.iter().map(|x| x * x).sum();
            let fv: f64 = s.g.iter().zip(&s.c).map(|(a, b)| a * b).sum();
            backward(&s.a, kk, &mut s.g);
            let t = (1.0 - fv) / ff;
            for (w, g) in s.w.iter_mut().zip(&s.g) {
                *w += t * g;
            }
            var += (1.0 - fv) * (1.0 - fv) / ff;
        }
        s.sd = var.max(0.0).sqrt();
        Ok(())
    }

    /// The weights of every node along the shared path (computed in parallel over fixed blocks of
    /// path positions: the same bits for any thread count).
    fn shared_records(&self, seed: u64) -> Result<Records, KrigingError> {
        let nn = self.n_nodes();
        let mut rng = SplitMix64::stream(seed, SHARED_PATH_LANE);
        let path = random_path(nn, &mut rng);
        let ranks = PathRanks::new(&self.node_tree, &path);
        let blocks: Vec<Result<Records, KrigingError>> = path
            .par_chunks(BLOCK)
            .enumerate()
            .map(|(b, chunk)| {
                let mut rec = Records::default();
                let mut s = Scratch::default();
                for (j, &node) in chunk.iter().enumerate() {
                    self.node_system(node, &ranks, b * BLOCK + j, None, &mut s)
                        .map_err(|e| self.node_error(node, None, e))?;
                    rec.push(&s);
                }
                Ok(rec)
            })
            .collect();
        let mut all = Records {
            path,
            ..Records::default()
        };
        for b in blocks {
            all.append(b?);
        }
        Ok(all)
    }

    fn node_error(&self, node: usize, realisation: Option<usize>, e: KrigingError) -> KrigingError {
        KrigingError::SimulationNode {
            target: self.node_target[node],
            realisation,
            source: Box::new(e),
        }
    }

    /// The neighbour lists of every node ([`Lists`]), in parallel over fixed blocks of nodes;
    /// `None` past [`LISTS_MAX_ENTRIES`] or `u32` indices (the searches then run in full).
    fn lists(&self) -> Option<Lists> {
        let nn = self.n_nodes();
        if nn < 2 || u32::try_from(nn).is_err() || nn.saturating_mul(self.k) > LISTS_MAX_ENTRIES {
            return None;
        }
        let len = (CANDIDATES_PER_K * self.k).min(nn - 1);
        let (d, k) = (self.d, self.k);
        let mut nodes = vec![0u32; nn * len];
        let mut data = vec![(f64::INFINITY, usize::MAX); nn * k];
        let mut data_len = vec![0usize; nn];
        nodes
            .par_chunks_mut(len * BLOCK)
            .zip(data.par_chunks_mut(k * BLOCK))
            .zip(data_len.par_chunks_mut(BLOCK))
            .enumerate()
            .for_each(|(b, ((node_rows, data_rows), lens))| {
                let mut nb = Vec::with_capacity(len + 1);
                let rows = node_rows.chunks_mut(len).zip(data_rows.chunks_mut(k));
                for (r, ((node_row, data_row), dl)) in rows.zip(lens).enumerate() {
                    let i = b * BLOCK + r;
                    let point = &self.node_pts[i * d..(i + 1) * d];
                    let query = TreeQuery {
                        point,
                        k: len + 1,
                        r2: f64::INFINITY,
                        ranks: None,
                        offset: 0,
                    };
                    nb.clear();
                    self.node_tree.search(&query, &mut nb);
                    let others = nb.iter().filter(|e| e.1 != i).take(len);
                    for (slot, e) in node_row.iter_mut().zip(others) {
                        *slot = e.1 as u32;
                    }
                    let query = TreeQuery {
                        k,
                        r2: self.r2,
                        ..query
                    };
                    nb.clear();
                    self.data_tree.search(&query, &mut nb);
                    data_row[..nb.len()].copy_from_slice(&nb);
                    *dl = nb.len();
                }
            });
        Some(Lists {
            nodes,
            len,
            complete: len == nn - 1,
            data,
            data_len,
            k,
        })
    }

    /// Realisation `r` into `out` (one value per target).
    fn realisation(
        &self,
        seed: u64,
        r: usize,
        records: Option<&Records>,
        lists: Option<&Lists>,
        out: &mut [f64],
    ) -> Result<(), KrigingError> {
        debug_assert_eq!(out.len(), self.sources.len());
        debug_assert!(r < self.realisations);
        let nn = self.n_nodes();
        let mut rng = SplitMix64::stream(seed, r as u64);
        // Values of the data (residuals) then of the nodes, indexed as the neighbour ids.
        let mut vals = Vec::with_capacity(self.n + nn);
        vals.extend_from_slice(&self.data_res);
        vals.resize(self.n + nn, 0.0);
        match records {
            Some(rec) => {
                debug_assert_eq!(rec.path.len(), nn);
                for (p, &node) in rec.path.iter().enumerate() {
                    let (lo, hi) = (rec.offsets[p], rec.offsets[p + 1]);
                    let est: f64 = rec.ids[lo..hi]
                        .iter()
                        .zip(&rec.w[lo..hi])
                        .map(|(&i, w)| w * vals[i])
                        .sum();
                    vals[self.n + node] = est + rec.sd[p] * rng.normal();
                }
            }
            None => {
                let path = random_path(nn, &mut rng);
                let ranks = PathRanks::new(&self.node_tree, &path);
                let mut s = Scratch::default();
                for (p, &node) in path.iter().enumerate() {
                    self.node_system(node, &ranks, p, lists, &mut s)
                        .map_err(|e| self.node_error(node, Some(r), e))?;
                    let est: f64 = s.ids.iter().zip(&s.w).map(|(&i, w)| w * vals[i]).sum();
                    vals[self.n + node] = est + s.sd * rng.normal();
                }
            }
        }
        for (o, src) in out.iter_mut().zip(&self.sources) {
            *o = match *src {
                Source::Datum(i) => self.data_values[i],
                Source::Node(j) => self.shift + vals[self.n + j],
            };
        }
        Ok(())
    }
}

/// The variogram must be valid and bounded (a covariance exists); a pure nugget (> 0) is allowed.
fn validate_variogram(v: &NestedVariogram) -> Result<(), KrigingError> {
    if v.structures.is_empty() {
        if v.nugget.is_finite() && v.nugget > 0.0 {
            return Ok(());
        }
        return Err(KrigingError::InvalidConfig(format!(
            "a pure-nugget variogram needs a finite nugget > 0, got {}",
            v.nugget
        )));
    }
    v.validate()?;
    if let Some(s) = v.structures.iter().find(|s| !s.model.has_range()) {
        return Err(KrigingError::InvalidVariogram {
            model: s.model,
            reason: format!(
                "Gaussian simulation needs a bounded variogram (a sill, so that the covariance \
                 C(h) = sill - gamma(h) exists); the {} model is unbounded",
                s.model.name()
            ),
        });
    }
    Ok(())
}

/// Per-thread buffers of one node's system.
#[derive(Debug, Default)]
struct Scratch {
    nb: Vec<(f64, usize)>,
    found: Vec<(f64, usize)>,
    ids: Vec<usize>,
    xyz: Vec<f64>,
    a: Vec<f64>,
    c: Vec<f64>,
    g: Vec<f64>,
    w: Vec<f64>,
    sd: f64,
}

/// Per node, what its searches need that does not depend on the path: its nearest data (the
/// data part of any of its neighbourhoods) and its `len` nearest other nodes (candidates for the
/// earlier ones), both sorted by (squared distance, index), the keys of the searches.
#[derive(Debug)]
struct Lists {
    /// Row `i`: `nodes[i * len..(i + 1) * len]`.
    nodes: Vec<u32>,
    len: usize,
    /// Every row holds all the other nodes.
    complete: bool,
    /// Row `i`: `data[i * k..i * k + data_len[i]]`, the `k` nearest data within the radius.
    data: Vec<(f64, usize)>,
    data_len: Vec<usize>,
    k: usize,
}

impl Lists {
    fn data_row(&self, node: usize) -> &[(f64, usize)] {
        &self.data[node * self.k..node * self.k + self.data_len[node]]
    }
}

/// A path's ranks: per node, in the node tree's order ([`RankTree::ranks`]), and their minimum
/// per tree node ([`RankTree::min_rank`]).
#[derive(Debug)]
struct PathRanks {
    node: Vec<usize>,
    tree: Vec<usize>,
    min: Vec<usize>,
}

impl PathRanks {
    fn new(tree: &RankTree, path: &[usize]) -> Self {
        let mut node = vec![0; path.len()];
        for (p, &i) in path.iter().enumerate() {
            node[i] = p;
        }
        let ranks = tree.ranks(path);
        PathRanks {
            node,
            min: tree.min_rank(&ranks),
            tree: ranks,
        }
    }
}

/// Inserts `key` into the sorted `out`, keeping at most `k` entries.
#[inline]
fn insert_capped(out: &mut Vec<(f64, usize)>, key: (f64, usize), k: usize) {
    if out.len() == k {
        if key >= out[k - 1] {
            return;
        }
        out.pop();
    }
    out.push(key);
    let mut j = out.len() - 1;
    while j > 0 && out[j - 1] > key {
        out[j] = out[j - 1];
        j -= 1;
    }
    out[j] = key;
}

/// The weights of every node along a shared path, by path position.
#[derive(Debug, Default)]
struct Records {
    path: Vec<usize>,
    /// Neighbours of position `p`: `ids[offsets[p]..offsets[p + 1]]`.
    offsets: Vec<usize>,
    ids: Vec<usize>,
    w: Vec<f64>,
    sd: Vec<f64>,
}

impl Records {
    fn push(&mut self, s: &Scratch) {
        if self.offsets.is_empty() {
            self.offsets.push(0);
        }
        self.ids.extend_from_slice(&s.ids);
        self.w.extend_from_slice(&s.w);
        self.offsets.push(self.ids.len());
        self.sd.push(s.sd);
    }

    fn append(&mut self, other: Records) {
        if self.offsets.is_empty() {
            self.offsets.push(0);
        }
        let base = self.ids.len();
        self.offsets
            .extend(other.offsets.iter().skip(1).map(|o| o + base));
        self.ids.extend(other.ids);
        self.w.extend(other.w);
        self.sd.extend(other.sd);
    }
}

/// In-place lower Cholesky factor of the row-major `k x k` matrix `a` (lower triangle read and
/// written); `Err(pivot ratio)` when it is not (numerically) positive definite.
fn cholesky(a: &mut [f64], k: usize) -> Result<(), f64> {
    debug_assert_eq!(a.len(), k * k);
    let (mut lmin, mut lmax) = (f64::INFINITY, 0.0f64);
    for j in 0..k {
        let mut djj = a[j * k + j];
        for p in 0..j {
            djj -= a[j * k + p] * a[j * k + p];
        }
        if djj.is_nan() || djj <= 0.0 {
            return Err(0.0);
        }
        let ljj = djj.sqrt();
        a[j * k + j] = ljj;
        lmin = lmin.min(ljj);
        lmax = lmax.max(ljj);
        for i in j + 1..k {
            let mut s = a[i * k + j];
            for p in 0..j {
                s -= a[i * k + p] * a[j * k + p];
            }
            a[i * k + j] = s / ljj;
        }
    }
    let ratio = (lmin / lmax).powi(2);
    if ratio.is_nan() || ratio < PIVOT_RATIO_MIN {
        return Err(ratio);
    }
    Ok(())
}

/// `x <- L^-1 x` (row-major lower factor).
fn forward(l: &[f64], k: usize, x: &mut [f64]) {
    debug_assert_eq!(x.len(), k);
    for i in 0..k {
        let mut s = x[i];
        for p in 0..i {
            s -= l[i * k + p] * x[p];
        }
        x[i] = s / l[i * k + i];
    }
}

/// `x <- L^-t x` (row-major lower factor).
fn backward(l: &[f64], k: usize, x: &mut [f64]) {
    debug_assert_eq!(x.len(), k);
    for i in (0..k).rev() {
        let mut s = x[i];
        for p in i + 1..k {
            s -= l[p * k + i] * x[p];
        }
        x[i] = s / l[i * k + i];
    }
}

/// A random order of `0..n` (Fisher-Yates).
fn random_path(n: usize, rng: &mut SplitMix64) -> Vec<usize> {
    let mut p: Vec<usize> = (0..n).collect();
    for i in (1..n).rev() {
        let j = rng.below(i as u64 + 1) as usize;
        p.swap(i, j);
    }
    p
}

/// SplitMix64 (Steele, Lea and Flood 2014), the workspace's generator (as in `lod-policy`), with
/// Box-Muller normal draws.
#[derive(Debug, Clone)]
struct SplitMix64 {
    state: u64,
    spare: Option<f64>,
}

/// The SplitMix64 output function (a bijective mix of 64 bits).
#[inline]
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

impl SplitMix64 {
    /// The stream `lane` of `seed`: its state is a mix of both, so streams of neighbouring lanes
    /// or seeds are unrelated.
    fn stream(seed: u64, lane: u64) -> Self {
        SplitMix64 {
            state: mix64(seed ^ mix64(lane.wrapping_add(0x9E37_79B9_7F4A_7C15))),
            spare: None,
        }
    }

    #[inline]
    fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        mix64(self.state)
    }

    /// Uniform in `0..n` (`n > 0`) by the multiply-shift map (bias below `n / 2^64`).
    #[inline]
    fn below(&mut self, n: u64) -> u64 {
        ((self.next_u64() as u128 * n as u128) >> 64) as u64
    }

    /// A standard normal draw (Box-Muller; the second value of each pair is kept for the next
    /// call).
    #[inline]
    fn normal(&mut self) -> f64 {
        if let Some(z) = self.spare.take() {
            return z;
        }
        let scale = 1.0 / (1u64 << 53) as f64;
        let u1 = ((self.next_u64() >> 11) + 1) as f64 * scale; // (0, 1]
        let u2 = (self.next_u64() >> 11) as f64 * scale; // [0, 1)
        let r = (-2.0 * u1.ln()).sqrt();
        let (s, c) = (std::f64::consts::TAU * u2).sin_cos();
        self.spare = Some(r * s);
        r * c
    }
}

/// A k-d tree with bounding boxes that finds the nearest points, optionally only those *earlier
/// on a path*: a search for the points of rank below `limit` skips every subtree whose smallest
/// rank ([`RankTree::min_rank`]) is not below it. The tree keeps its own copy of the points and
/// the ranks in tree order, so that a leaf is a contiguous run of memory.
#[derive(Debug, Clone)]
struct RankTree {
    d: usize,
    /// Point index at each tree position.
    order: Vec<usize>,
    /// Tree position of each point.
    pos_of: Vec<usize>,
    /// Row-major coordinates in tree order.
    pts: Vec<f64>,
    nodes: Vec<TreeNode>,
    /// Per tree node: `lo[0..d]`, `hi[0..d]`.
    bbox: Vec<f64>,
}

#[derive(Debug, Clone, Copy)]
struct TreeNode {
    start: usize,
    end: usize,
    /// Children (`usize::MAX` for a leaf).
    left: usize,
    right: usize,
}

impl RankTree {
    fn new(pts: &[f64], d: usize) -> Self {
        let n = pts.len() / d.max(1);
        let mut t = RankTree {
            d,
            order: (0..n).collect(),
            pos_of: vec![0; n],
            pts: Vec::with_capacity(n * d),
            nodes: Vec::new(),
            bbox: Vec::new(),
        };
        if n > 0 {
            t.build(pts, 0, n);
        }
        for (pos, &i) in t.order.iter().enumerate() {
            t.pos_of[i] = pos;
            t.pts.extend_from_slice(&pts[i * d..(i + 1) * d]);
        }
        t
    }

    fn build(&mut self, pts: &[f64], start: usize, end: usize) -> usize {
        let d = self.d;
        let id = self.nodes.len();
        self.nodes.push(TreeNode {
            start,
            end,
            left: usize::MAX,
            right: usize::MAX,
        });
        let mut lo = vec![f64::INFINITY; d];
        let mut hi = vec![f64::NEG_INFINITY; d];
        for &i in &self.order[start..end] {
            for k in 0..d {
                lo[k] = lo[k].min(pts[i * d + k]);
                hi[k] = hi[k].max(pts[i * d + k]);
            }
        }
        self.bbox.extend_from_slice(&lo);
        self.bbox.extend_from_slice(&hi);
        if end - start <= LEAF {
            return id;
        }
        let (dim, width) = (0..d)
            .map(|k| (k, hi[k] - lo[k]))
            .fold((0, -1.0), |b, c| if c.1 > b.1 { c } else { b });
        if width <= 0.0 {
            return id;
        }
        let mid = start + (end - start) / 2;
        self.order[start..end].select_nth_unstable_by(mid - start, |&a, &b| {
            pts[a * d + dim]
                .total_cmp(&pts[b * d + dim])
                .then(a.cmp(&b))
        });
        let left = self.build(pts, start, mid);
        let right = self.build(pts, mid, end);
        self.nodes[id].left = left;
        self.nodes[id].right = right;
        id
    }

    /// The ranks of a path (`path[p]` has rank `p`) in tree order.
    fn ranks(&self, path: &[usize]) -> Vec<usize> {
        debug_assert_eq!(path.len(), self.order.len());
        let mut out = vec![0; path.len()];
        for (p, &i) in path.iter().enumerate() {
            out[self.pos_of[i]] = p;
        }
        out
    }

    /// The smallest rank under each tree node (`ranks` in tree order; children come after their
    /// parent).
    fn min_rank(&self, ranks: &[usize]) -> Vec<usize> {
        let mut out = vec![usize::MAX; self.nodes.len()];
        for id in (0..self.nodes.len()).rev() {
            let nd = self.nodes[id];
            out[id] = if nd.left == usize::MAX {
                ranks[nd.start..nd.end]
                    .iter()
                    .copied()
                    .min()
                    .unwrap_or(usize::MAX)
            } else {
                out[nd.left].min(out[nd.right])
            };
        }
        out
    }

    #[inline]
    fn box_dist2(&self, id: usize, q: &[f64]) -> f64 {
        let d = self.d;
        let b = &self.bbox[id * 2 * d..(id + 1) * 2 * d];
        let mut s = 0.0;
        for k in 0..d {
            let e = (b[k] - q[k]).max(q[k] - b[d + k]).max(0.0);
            s += e * e;
        }
        s
    }

    /// Merges into `out` (sorted by (squared distance, id), at most `q.k` entries, possibly holding
    /// some already) the points within squared distance `q.r2` of `q.point` (of rank below the
    /// limit when `q.ranks` is given), with ids `q.offset + point index`.
    fn search(&self, q: &TreeQuery<'_>, out: &mut Vec<(f64, usize)>) {
        if self.nodes.is_empty() || q.k == 0 {
            return;
        }
        self.visit(0, self.box_dist2(0, q.point), q, out);
    }

    fn visit(&self, id: usize, lb: f64, q: &TreeQuery<'_>, out: &mut Vec<(f64, usize)>) {
        let k = q.k;
        if lb > q.r2 || (out.len() == k && lb > out[k - 1].0) {
            return;
        }
        if let Some((_, min_rank, limit)) = q.ranks
            && min_rank[id] >= limit
        {
            return;
        }
        let nd = self.nodes[id];
        if nd.left == usize::MAX {
            let d = self.d;
            for pos in nd.start..nd.end {
                if let Some((ranks, _, limit)) = q.ranks
                    && ranks[pos] >= limit
                {
                    continue;
                }
                let p = &self.pts[pos * d..(pos + 1) * d];
                let dist: f64 = p.iter().zip(q.point).map(|(a, b)| (a - b) * (a - b)).sum();
                if dist > q.r2 {
                    continue;
                }
                insert_capped(out, (dist, q.offset + self.order[pos]), k);
            }
            return;
        }
        let (bl, br) = (
            self.box_dist2(nd.left, q.point),
            self.box_dist2(nd.right, q.point),
        );
        if bl <= br {
            self.visit(nd.left, bl, q, out);
            self.visit(nd.right, br, q, out);
        } else {
            self.visit(nd.right, br, q, out);
            self.visit(nd.left, bl, q, out);
        }
    }
}

/// A search of [`RankTree`].
struct TreeQuery<'a> {
    point: &'a [f64],
    /// At most this many neighbours (`out` may hold some already).
    k: usize,
    /// Squared search radius.
    r2: f64,
    /// Only the points earlier on a path: ranks in tree order ([`RankTree::ranks`]), their
    /// [`RankTree::min_rank`], and the limit (the rank of the node being simulated).
    ranks: Option<(&'a [usize], &'a [usize], usize)>,
    /// Added to point indices in the ids (the number of data, for the nodes).
    offset: usize,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rank_tree_matches_brute_force() {
        let (n, d) = (700, 2);
        let mut g = SplitMix64::stream(7, 0);
        // Coarse coordinates so that ties happen.
        let pts: Vec<f64> = (0..n * d).map(|_| g.below(40) as f64).collect();
        let tree = RankTree::new(&pts, d);
        let path = random_path(n, &mut g);
        let mut rank = vec![0; n];
        for (p, &i) in path.iter().enumerate() {
            rank[i] = p;
        }
        let ranks = tree.ranks(&path);
        let min_rank = tree.min_rank(&ranks);
        let mut out = Vec::new();
        for qi in 0..60 {
            let q = [qi as f64 * 0.7, 39.0 - qi as f64 * 0.6];
            for (k, r2, limit) in [
                (1, f64::INFINITY, 5),
                (16, f64::INFINITY, 300),
                (9, 20.0, 650),
            ] {
                out.clear();
                let query = TreeQuery {
                    point: &q,
                    k,
                    r2,
                    ranks: Some((&ranks, &min_rank, limit)),
                    offset: 1000,
                };
                tree.search(&query, &mut out);
                let mut all: Vec<(f64, usize)> = (0..n)
                    .filter(|&i| rank[i] < limit)
                    .map(|i| {
                        let (dx, dy) = (pts[i * 2] - q[0], pts[i * 2 + 1] - q[1]);
                        (dx * dx + dy * dy, 1000 + i)
                    })
                    .filter(|e| e.0 <= r2)
                    .collect();
                all.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                all.truncate(k);
                assert_eq!(out, all, "query {q:?} k {k} limit {limit}");
            }
        }
    }

    /// The neighbour lists are a shortcut only: the same realisations with and without them, for
    /// nearest and radius neighbourhoods, simple and ordinary kriging.
    #[test]
    fn lists_give_the_same_realisations() {
        let mut g = SplitMix64::stream(3, 0);
        let n = 60;
        let coords = faer::Mat::from_fn(n, 2, |_, _| {
            100.0 * (g.next_u64() >> 11) as f64 / (1u64 << 53) as f64
        });
        let z: Vec<f64> = (0..n)
            .map(|i| (coords[(i, 0)] / 20.0).sin() + coords[(i, 1)] / 100.0)
            .collect();
        let targets = faer::Mat::from_fn(900, 2, |t, c| [t % 30, t / 30][c] as f64 * 100.0 / 29.0);
        let v = NestedVariogram::single(crate::VariogramModel::Spherical, 0.05, 1.0, 40.0).unwrap();
        for (nbh, mean) in [
            (Neighbourhood::Nearest { k: 12 }, SgsMean::DataMean),
            (
                Neighbourhood::Radius {
                    radius: 9.0,
                    max: 10,
                },
                SgsMean::Known(0.3),
            ),
            (Neighbourhood::Nearest { k: 7 }, SgsMean::Ordinary),
        ] {
            let sgs = Sgs::new(v.clone())
                .neighbourhood(nbh)
                .mean(mean)
                .seed(5)
                .realisations(3);
            let prep = Prepared::new(&sgs, coords.as_ref(), &z, targets.as_ref()).unwrap();
            let lists = prep.lists().unwrap();
            for r in 0..3 {
                let (mut a, mut b) = (vec![0.0; 900], vec![0.0; 900]);
                prep.realisation(5, r, None, None, &mut a).unwrap();
                prep.realisation(5, r, None, Some(&lists), &mut b).unwrap();
                let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&a), bits(&b), "{nbh:?} {mean:?} realisation {r}");
            }
        }
    }

    #[test]
    fn normal_draws_have_unit_moments() {
        let mut g = SplitMix64::stream(1, 2);
        let n = 200_000;
        let xs: Vec<f64> = (0..n).map(|_| g.normal()).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        let kurt = xs.iter().map(|x| (x - mean).powi(4)).sum::<f64>() / n as f64 / (var * var);
        // Standard errors: mean 1/sqrt(n) = 0.0022, variance sqrt(2/n) = 0.0032, kurtosis
        // sqrt(24/n) = 0.011; five of each.
        assert!(mean.abs() < 0.012, "mean {mean}");
        assert!((var - 1.0).abs() < 0.016, "variance {var}");
        assert!((kurt - 3.0).abs() < 0.055, "kurtosis {kurt}");
    }

    #[test]
    fn cholesky_solves() {
        // A 3 x 3 SPD matrix, row-major (full; the factor reads the lower triangle).
        let a0 = [4.0, 2.0, 0.6, 2.0, 5.0, 1.0, 0.6, 1.0, 3.0];
        let mut l = a0;
        cholesky(&mut l, 3).unwrap();
        let b = [1.0, -2.0, 0.5];
        let mut x = b;
        forward(&l, 3, &mut x);
        backward(&l, 3, &mut x);
        for i in 0..3 {
            let ax: f64 = (0..3).map(|j| a0[i * 3 + j] * x[j]).sum();
            assert!((ax - b[i]).abs() < 1e-12);
        }
        let mut singular = [1.0, 1.0, 1.0, 1.0];
        assert!(cholesky(&mut singular, 2).is_err());
    }
}
