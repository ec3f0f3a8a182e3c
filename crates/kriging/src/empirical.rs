//! The empirical (binned) variogram of appendix A.

use faer::MatRef;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::KrigingError;

/// Below this many `S^2 D` operations the pairwise value distances run on one thread.
const PARALLEL_MIN_WORK: usize = 1 << 24;

/// The most intervals an empirical variogram may have ([`EmpiricalVariogram::compute`],
/// [`Binning::bins`], [`crate::KrigingConfig::bins`]); more is a
/// [`KrigingError::InvalidConfig`] error. A million intervals is far more than any variogram
/// fit uses (tens), and keeps the per-interval sums and counts within about 16 MB per row being
/// binned.
pub const MAX_BINS: usize = 1_000_000;

/// Per-row interval sums held at once while binning (rows `ROW_BLOCK_ENTRIES / bins` at a time),
/// so that memory does not grow with the number of samples times the number of intervals.
const ROW_BLOCK_ENTRIES: usize = 1 << 22;

/// The checks on an interval count: at least one, at most [`MAX_BINS`].
pub(crate) fn check_bins(bins: usize) -> Result<(), KrigingError> {
    if bins == 0 {
        return Err(KrigingError::InvalidConfig(
            "the empirical variogram needs at least one bin".into(),
        ));
    }
    if bins > MAX_BINS {
        return Err(KrigingError::InvalidConfig(format!(
            "the empirical variogram takes at most {MAX_BINS} bins (kriging::MAX_BINS), got {bins}"
        )));
    }
    Ok(())
}

/// Runs `row` over the rows `0..s` (in parallel when `parallel`) and hands the results to `add`
/// in row order, at most `ROW_BLOCK_ENTRIES / bins` rows' results held at a time. The order of
/// the additions is the row order whatever the blocks, so the sums have the same bits as one
/// pass over all rows.
pub(crate) fn fold_rows<A: Send>(
    s: usize,
    bins: usize,
    parallel: bool,
    row: impl Fn(usize) -> A + Sync + Send,
    mut add: impl FnMut(A),
) {
    let block = (ROW_BLOCK_ENTRIES / bins.max(1)).max(1);
    let mut start = 0;
    while start < s {
        let end = s.min(start + block);
        if parallel {
            let part: Vec<A> = (start..end).into_par_iter().map(&row).collect();
            part.into_iter().for_each(&mut add);
        } else {
            (start..end).map(&row).for_each(&mut add);
        }
        start = end;
    }
}

/// The empirical variogram of `bins` intervals of width `dh` whose semi-variance sums and pair
/// counts each row `0..s` gives (`row_bins`, folded in row order by [`fold_rows`]): each
/// interval's mean, 0 where it holds no pair, checked finite ([`check_gamma`]).
fn interval_means(
    s: usize,
    bins: usize,
    dh: f64,
    parallel: bool,
    row_bins: impl Fn(usize) -> (Vec<f64>, Vec<usize>) + Sync + Send,
) -> Result<EmpiricalVariogram, KrigingError> {
    let mut sums = vec![0.0; bins];
    let mut counts = vec![0usize; bins];
    fold_rows(s, bins, parallel, row_bins, |(rs, rc)| {
        for u in 0..bins {
            sums[u] += rs[u];
            counts[u] += rc[u];
        }
    });
    let gamma: Vec<f64> = sums
        .iter()
        .zip(&counts)
        .map(|(&sm, &n)| if n > 0 { sm / n as f64 } else { 0.0 })
        .collect();
    check_gamma(&gamma)?;
    Ok(EmpiricalVariogram {
        bin_width: dh,
        centers: (0..bins).map(|u| dh * (u as f64 + 0.5)).collect(),
        gamma,
        counts,
    })
}

/// [`KrigingError::Overflow`] when an interval's semi-variance is not finite: finite values whose
/// squared differences (or their sums) overflow.
pub(crate) fn check_gamma(gamma: &[f64]) -> Result<(), KrigingError> {
    match gamma.iter().position(|g| !g.is_finite()) {
        None => Ok(()),
        Some(u) => Err(KrigingError::Overflow {
            what: "values".into(),
            reason: format!(
                "the semi-variance of interval {u} of the empirical variogram is {}",
                gamma[u]
            ),
        }),
    }
}

/// Pairwise Euclidean distances between the rows of a parameter matrix, packed (upper triangle).
#[derive(Debug, Clone)]
pub(crate) struct PairDistances {
    n: usize,
    /// Row i holds the distances to j = i+1 .. n, rows one after the other.
    packed: Vec<f64>,
    max: f64,
}

impl PairDistances {
    /// Distances between the rows of `params` (S x d).
    pub(crate) fn new(params: MatRef<'_, f64>) -> Self {
        let (n, d) = params.shape();
        let mut packed = Vec::with_capacity(n * n.saturating_sub(1) / 2);
        let mut max = 0.0f64;
        for i in 0..n {
            for j in i + 1..n {
                let mut s = 0.0;
                for k in 0..d {
                    let t = params[(i, k)] - params[(j, k)];
                    s += t * t;
                }
                let h = s.sqrt();
                max = max.max(h);
                packed.push(h);
            }
        }
        PairDistances { n, packed, max }
    }

    /// Start of row `i` in `packed`.
    #[inline]
    fn row_start(&self, i: usize) -> usize {
        // sum_{r < i} (n - 1 - r)
        i * (2 * self.n - i - 1) / 2
    }

    /// Distance between samples `i != j`.
    #[inline]
    pub(crate) fn get(&self, i: usize, j: usize) -> f64 {
        debug_assert!(i != j && i < self.n && j < self.n);
        let (a, b) = if i < j { (i, j) } else { (j, i) };
        self.packed[self.row_start(a) + (b - a - 1)]
    }

    /// Largest distance.
    pub(crate) fn max(&self) -> f64 {
        self.max
    }

    /// The first pair (i < j, in row order) whose distance is at most `tol`.
    pub(crate) fn first_duplicate(&self, tol: f64) -> Option<(usize, usize)> {
        for i in 0..self.n {
            let start = self.row_start(i);
            for j in i + 1..self.n {
                if self.packed[start + (j - i - 1)] <= tol {
                    return Some((i, j));
                }
            }
        }
        None
    }

    /// Relative tolerance under which two points count as duplicates.
    pub(crate) fn duplicate_tol(&self) -> f64 {
        1e-12 * self.max
    }
}

/// Binned averages of the semi-variance (appendix A).
///
/// The distance range `[0, h_max]` is split into `S_I` intervals of width `dh = h_max / S_I`
/// with centres `h_u = dh (u - 1/2)`; interval `u` averages `|x_i - x_j|^2 / 2` (squared Euclidean
/// norm for vector values) over the `n(I_u)` pairs whose parameter distance falls in it (the pair
/// at `h_max` goes to the last interval).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EmpiricalVariogram {
    /// Interval width `dh`.
    pub bin_width: f64,
    /// Interval centres `h_u`.
    pub centers: Vec<f64>,
    /// Mean semi-variance per interval (0 where the interval is empty).
    pub gamma: Vec<f64>,
    /// Pair count `n(I_u)` per interval.
    pub counts: Vec<usize>,
}

impl EmpiricalVariogram {
    /// Computes the empirical variogram of `values` (S x D, one sample per row) over the rows of
    /// `params` (S x d, already scaled) with `bins` intervals.
    ///
    /// Errors: shapes that do not match, fewer than two samples, NaN or infinite input, `bins` 0
    /// or above [`MAX_BINS`], all samples at one point ([`KrigingError::NoSpread`]), and
    /// [`KrigingError::Overflow`] when finite parameters or values are so large that a distance
    /// or a semi-variance overflows.
    ///
    /// ```
    /// use kriging::faer::Mat;
    /// use kriging::EmpiricalVariogram;
    ///
    /// // z = x on 10 points 1 apart: every pair at lag h has semi-variance h^2 / 2.
    /// let x = Mat::from_fn(10, 1, |i, _| i as f64);
    /// let emp = EmpiricalVariogram::compute(x.as_ref(), x.as_ref(), 3)?;
    /// assert_eq!(emp.centers.len(), 3);
    /// assert_eq!(emp.counts.len(), 3);
    /// for u in 0..3 {
    ///     // Each interval averages h^2 / 2 over the lags inside it, so it lies between the
    ///     // values at the interval's ends.
    ///     let (lo, hi) = (u as f64 * emp.bin_width, (u + 1) as f64 * emp.bin_width);
    ///     assert!(emp.counts[u] > 0);
    ///     assert!(emp.gamma[u] >= lo * lo / 2.0 && emp.gamma[u] <= hi * hi / 2.0);
    /// }
    /// # Ok::<(), kriging::KrigingError>(())
    /// ```
    pub fn compute(
        params: MatRef<'_, f64>,
        values: MatRef<'_, f64>,
        bins: usize,
    ) -> Result<Self, KrigingError> {
        if params.nrows() != values.nrows() {
            return Err(KrigingError::ShapeMismatch {
                what: "values rows vs parameter rows",
                expected: params.nrows(),
                got: values.nrows(),
            });
        }
        crate::check_finite("params", params)?;
        crate::check_finite("values", values)?;
        let dist = PairDistances::new(params);
        Self::from_distances(&dist, values, bins)
    }

    /// Same as [`EmpiricalVariogram::compute`] with precomputed parameter distances.
    pub(crate) fn from_distances(
        dist: &PairDistances,
        values: MatRef<'_, f64>,
        bins: usize,
    ) -> Result<Self, KrigingError> {
        let s = values.nrows();
        if s < 2 {
            return Err(KrigingError::TooFewSamples {
                what: "empirical variogram",
                needed: 2,
                got: s,
            });
        }
        check_bins(bins)?;
        let hmax = dist.max();
        if hmax.is_nan() || hmax <= 0.0 {
            return Err(KrigingError::NoSpread { samples: s });
        }
        if hmax.is_infinite() {
            return Err(KrigingError::Overflow {
                what: "parameters".into(),
                reason: "the largest distance between two samples is inf".into(),
            });
        }
        let dh = hmax / bins as f64;
        let dcols = values.ncols();
        // Row-major copy so that each sample is contiguous.
        let rows: Vec<f64> = (0..s)
            .flat_map(|i| (0..dcols).map(move |k| (i, k)))
            .map(|(i, k)| values[(i, k)])
            .collect();
        let row_bins = |i: usize| {
            let mut sums = vec![0.0; bins];
            let mut counts = vec![0usize; bins];
            let xi = &rows[i * dcols..(i + 1) * dcols];
            for j in i + 1..s {
                let xj = &rows[j * dcols..(j + 1) * dcols];
                let sq: f64 = xi.iter().zip(xj).map(|(a, b)| (a - b) * (a - b)).sum();
                let u = ((dist.get(i, j) / dh) as usize).min(bins - 1);
                sums[u] += 0.5 * sq;
                counts[u] += 1;
            }
            (sums, counts)
        };
        // Rows are independent: the parallel and the sequential loop give the same bits. Small
        // problems stay sequential (waking the pool costs more than the work).
        let parallel = s * s * dcols >= PARALLEL_MIN_WORK;
        interval_means(s, bins, dh, parallel, row_bins)
    }

    /// Number of non-empty intervals.
    pub fn nonempty(&self) -> usize {
        self.counts.iter().filter(|&&n| n > 0).count()
    }
}

/// The largest lag of an empirical variogram.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum MaxLag {
    /// Up to the largest distance between two samples (the paper's appendix A).
    Largest,
    /// A fraction of the diagonal of the samples' bounding box (gstat's default is 1/3).
    DiagonalFraction(f64),
    /// A distance in the coordinates' units.
    Distance(f64),
}

/// How pairs are binned into an empirical variogram: `bins` intervals of equal width over
/// `[0, max_lag]`; pairs farther apart than the maximum lag are left out.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Binning {
    /// Number of equal-width intervals, at least 1 and at most [`MAX_BINS`].
    pub bins: usize,
    /// The largest lag binned.
    pub max_lag: MaxLag,
}

impl Default for Binning {
    /// 15 intervals up to a third of the bounding-box diagonal (gstat's defaults, suited to maps).
    fn default() -> Self {
        Binning {
            bins: 15,
            max_lag: MaxLag::DiagonalFraction(1.0 / 3.0),
        }
    }
}

impl EmpiricalVariogram {
    /// The empirical variogram of `values` (S x D) over the rows of `coords` (S x d) with the given
    /// binning. Distances are computed on the fly (memory `O(S d + bins)`, time `O(S^2 (d + D))`,
    /// rows in parallel with a fixed reduction order, so the result does not depend on the number
    /// of threads). Interval `u` covers `[u dh, (u+1) dh)` with `dh = max_lag / bins` (the pair at
    /// exactly `max_lag` goes to the last interval); its centre is reported as `h_u = dh (u + 1/2)`.
    ///
    /// ```
    /// use kriging::faer::Mat;
    /// use kriging::{Binning, EmpiricalVariogram, MaxLag};
    ///
    /// // z = x on 10 points 1 apart: every pair at lag h has semi-variance h^2 / 2.
    /// let x = Mat::from_fn(10, 1, |i, _| i as f64);
    /// let binning = Binning { bins: 4, max_lag: MaxLag::Distance(4.5) }; // one lag per interval
    /// let emp = EmpiricalVariogram::compute_binned(x.as_ref(), x.as_ref(), &binning)?;
    /// assert_eq!(emp.counts, [9, 8, 7, 6]); // pairs at lags 1, 2, 3, 4 (lags 5-9 left out)
    /// assert_eq!(emp.gamma, [0.5, 2.0, 4.5, 8.0]);
    /// assert_eq!(emp.bin_width, 1.125);
    /// assert_eq!(emp.centers[0], 0.5625);
    /// # Ok::<(), kriging::KrigingError>(())
    /// ```
    pub fn compute_binned(
        coords: MatRef<'_, f64>,
        values: MatRef<'_, f64>,
        binning: &Binning,
    ) -> Result<Self, KrigingError> {
        let (s, d) = coords.shape();
        check_inputs(coords, values, binning)?;
        let bins = binning.bins;
        let pts: Vec<f64> = (0..s)
            .flat_map(|i| (0..d).map(move |k| (i, k)))
            .map(|(i, k)| coords[(i, k)])
            .collect();
        let dv = values.ncols();
        let vals: Vec<f64> = (0..s)
            .flat_map(|i| (0..dv).map(move |k| (i, k)))
            .map(|(i, k)| values[(i, k)])
            .collect();
        // One rule for the largest lag, with the directional estimator's (checks and spread).
        let max_lag = crate::estimator::max_lag(binning, &pts, s, d)?;
        let dh = max_lag / bins as f64;
        let max2 = max_lag * max_lag;
        let row_bins = |i: usize| {
            let mut sums = vec![0.0; bins];
            let mut counts = vec![0usize; bins];
            let xi = &vals[i * dv..(i + 1) * dv];
            let pi = &pts[i * d..(i + 1) * d];
            for (j, pj) in pts.chunks_exact(d).enumerate().skip(i + 1) {
                // Squared distance first: most pairs of a large set lie beyond the maximum lag.
                let h2: f64 = pi.iter().zip(pj).map(|(a, b)| (a - b) * (a - b)).sum();
                if h2 > max2 {
                    continue;
                }
                let h = h2.sqrt();
                let xj = &vals[j * dv..(j + 1) * dv];
                let sq: f64 = xi.iter().zip(xj).map(|(a, b)| (a - b) * (a - b)).sum();
                let u = ((h / dh) as usize).min(bins - 1);
                sums[u] += 0.5 * sq;
                counts[u] += 1;
            }
            (sums, counts)
        };
        let parallel = s * s * (d + dv) >= PARALLEL_MIN_WORK;
        interval_means(s, bins, dh, parallel, row_bins)
    }
}

/// The input checks of every empirical variogram ([`EmpiricalVariogram::compute_binned`] and the
/// directional estimator): one row of `values` per coordinate row, at least two samples, finite
/// coordinates and values, at least one bin.
pub(crate) fn check_inputs(
    coords: MatRef<'_, f64>,
    values: MatRef<'_, f64>,
    binning: &Binning,
) -> Result<(), KrigingError> {
    let s = coords.nrows();
    if s != values.nrows() {
        return Err(KrigingError::ShapeMismatch {
            what: "values rows vs coordinate rows",
            expected: s,
            got: values.nrows(),
        });
    }
    if s < 2 {
        return Err(KrigingError::TooFewSamples {
            what: "empirical variogram",
            needed: 2,
            got: s,
        });
    }
    crate::check_finite("coordinates", coords)?;
    crate::check_finite("values", values)?;
    check_bins(binning.bins)
}
