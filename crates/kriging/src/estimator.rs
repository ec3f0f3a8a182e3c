//! Directional and robust empirical variograms of a scalar field (GSTools' `vario_estimate` with
//! `direction`, `angles_tol`, `bandwidth` and `estimator`, plus Dowd's estimator).

use faer::MatRef;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::anisotropy::Anisotropy;
use crate::empirical::{Binning, EmpiricalVariogram, MaxLag};
use crate::error::KrigingError;
use crate::fit::{FitOptions, FittedVariogram, fit_range_fixed, fit_variogram};
use crate::variogram::VariogramModel;

/// Below this many `S^2 d` operations the pairs are binned on one thread.
const PARALLEL_MIN_WORK: usize = 1 << 22;

/// How the values of the pairs in a distance interval are reduced to a semi-variance.
///
/// With `dz_k = z(x_i) - z(x_j)` over the `n` pairs `k` of an interval:
/// - `Matheron`: `gamma = 1/(2n) sum_k dz_k^2` (the method of moments; GSTools `"matheron"`);
/// - `CressieHawkins`: `gamma = 1/2 (1/n sum_k |dz_k|^(1/2))^4 / (0.457 + 0.494/n + 0.045/n^2)`
///   (Cressie and Hawkins 1980; GSTools `"cressie"`, same constants), robust to outliers;
/// - `Dowd`: `gamma = 2.198 median_k(|dz_k|)^2 / 2 = 1.099 median_k(|dz_k|)^2` (Dowd 1984:
///   `2 gamma = 2.198 median^2`; the median of an even count is the mean of the two middle values),
///   the most robust of the three. Neither PyKrige nor GSTools has it.
///
/// Every estimator gives `gamma = 0` for an empty interval (and reports its count as 0).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum Estimator {
    /// Matheron's method of moments.
    #[default]
    Matheron,
    /// Cressie and Hawkins' robust estimator (fourth power of the mean square-root difference).
    CressieHawkins,
    /// Dowd's median estimator.
    Dowd,
}

/// A direction for a directional variogram: a pair `(x_i, x_j)` with separation `e = x_j - x_i`
/// counts when the angle between the line of `e` and the direction `u` (unit vector) is below the
/// tolerance, `acos(|e . u| / |e|) < tolerance` (pairs at distance 0 always pass), and, with a
/// bandwidth `b`, its distance from the direction line is below it, `|e - (e . u) u| < b`. Both
/// tests are strict, as in GSTools (`angles_tol`, `bandwidth`); a direction and its opposite are
/// the same.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Direction {
    /// The direction vector, one entry per coordinate (normalised before use; not zero).
    pub vector: Vec<f64>,
    /// Angular tolerance in degrees, in `(0, 90]` (90 takes every pair).
    pub tolerance: f64,
    /// Largest distance of the separation vector from the direction line (`None`: no limit).
    pub bandwidth: Option<f64>,
}

impl Direction {
    /// A direction in the plane at `angle` degrees counter-clockwise from the x axis (the
    /// convention of [`crate::Anisotropy::TwoD`] and of GSTools' `angles` in 2-D), with an angular
    /// tolerance in degrees and no bandwidth: `vector = [cos(angle), sin(angle)]`.
    pub fn planar(angle: f64, tolerance: f64) -> Self {
        let (s, c) = angle.to_radians().sin_cos();
        Direction {
            vector: vec![c, s],
            tolerance,
            bandwidth: None,
        }
    }

    /// The same direction with a bandwidth (largest distance from the direction line).
    pub fn with_bandwidth(mut self, bandwidth: f64) -> Self {
        self.bandwidth = Some(bandwidth);
        self
    }
}

/// Options of [`EmpiricalVariogram::estimate`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct EstimateOptions {
    /// The estimator (default Matheron).
    pub estimator: Estimator,
    /// A direction (default: none, every pair: the omnidirectional variogram).
    pub direction: Option<Direction>,
    /// `Some(R)`: the coordinates are latitude and longitude in degrees (columns 0 and 1) and the
    /// distance of a pair is the great-circle distance `R alpha` on a sphere of radius `R`
    /// ([`crate::great_circle_distance`]; GSTools' `latlon=True, geo_scale=R`). Not with a
    /// direction or [`MaxLag::DiagonalFraction`]. Default `None`: Euclidean distances.
    pub great_circle: Option<f64>,
}

/// The largest lag of `binning` over the points `pts` (row-major, `s x d`).
pub(crate) fn max_lag(
    binning: &Binning,
    pts: &[f64],
    s: usize,
    d: usize,
) -> Result<f64, KrigingError> {
    let pair = |i: usize, j: usize| -> f64 {
        let (a, b) = (&pts[i * d..(i + 1) * d], &pts[j * d..(j + 1) * d]);
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y) * (x - y))
            .sum::<f64>()
            .sqrt()
    };
    let h = match binning.max_lag {
        MaxLag::Largest => (0..s)
            .into_par_iter()
            .map(|i| (i + 1..s).map(|j| pair(i, j)).fold(0.0f64, f64::max))
            .collect::<Vec<f64>>()
            .into_iter()
            .fold(0.0f64, f64::max),
        MaxLag::DiagonalFraction(f) => {
            if !(f.is_finite() && f > 0.0) {
                return Err(KrigingError::InvalidConfig(format!(
                    "maximum lag fraction {f} must be finite and > 0"
                )));
            }
            let mut diag = 0.0;
            for k in 0..d {
                let (lo, hi) = (0..s).fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), i| {
                    (l.min(pts[i * d + k]), h.max(pts[i * d + k]))
                });
                diag += (hi - lo) * (hi - lo);
            }
            f * diag.sqrt()
        }
        MaxLag::Distance(h) => {
            if !(h.is_finite() && h > 0.0) {
                return Err(KrigingError::InvalidConfig(format!(
                    "maximum lag {h} must be finite and > 0"
                )));
            }
            h
        }
    };
    if h.is_nan() || h <= 0.0 {
        return Err(KrigingError::NoSpread { samples: s });
    }
    check_max_lag(h)?;
    Ok(h)
}

/// [`KrigingError::Overflow`] for an infinite largest lag: finite coordinates so far apart that
/// their distance overflows (or a maximum lag fraction that overflows the diagonal).
fn check_max_lag(h: f64) -> Result<(), KrigingError> {
    if h.is_infinite() {
        return Err(KrigingError::Overflow {
            what: "coordinates".into(),
            reason: "the largest lag of the empirical variogram is inf".into(),
        });
    }
    Ok(())
}

/// Per-interval accumulator: sums and counts, or the absolute differences (Dowd).
struct Acc {
    sums: Vec<f64>,
    counts: Vec<usize>,
    diffs: Vec<Vec<f64>>,
}

impl EmpiricalVariogram {
    /// The empirical variogram of the scalar `values` over the rows of `coords` (S x d) with the
    /// given binning, estimator and (optionally) direction; see [`Estimator`] for the formulas and
    /// [`Direction`] for the pair selection. Intervals are those of
    /// [`EmpiricalVariogram::compute_binned`]: `[u dh, (u+1) dh)` with `dh = max_lag / bins`,
    /// centres `dh (u + 1/2)`, the pair at exactly `max_lag` in the last interval (GSTools leaves
    /// it out; its bins are half-open), and [`MaxLag::Largest`] is the largest distance over all
    /// pairs, whatever the direction. With the Matheron estimator and no direction the result is
    /// that of `compute_binned` up to rounding. With [`EstimateOptions::great_circle`] the
    /// coordinates are latitude/longitude and the distances great-circle distances.
    ///
    /// Errors: shapes that do not match, fewer than two samples, NaN or infinite input, zero bins,
    /// a bad maximum lag, a direction of the wrong length, zero or non-finite, a tolerance outside
    /// `(0, 90]` degrees, a bandwidth that is not finite and positive; with great-circle distances
    /// a latitude outside `[-90, 90]`, a bad radius, a direction or a diagonal-fraction maximum lag.
    ///
    /// ```
    /// use kriging::faer::Mat;
    /// use kriging::{Binning, Direction, EmpiricalVariogram, EstimateOptions, Estimator, MaxLag};
    ///
    /// // z = x on a 5 x 5 grid: pairs along y have equal values, pairs along x differ by their lag.
    /// let coords = Mat::from_fn(25, 2, |i, k| if k == 0 { (i % 5) as f64 } else { (i / 5) as f64 });
    /// let z: Vec<f64> = (0..25).map(|i| (i % 5) as f64).collect();
    /// let binning = Binning { bins: 2, max_lag: MaxLag::Distance(2.5) };
    /// let along_x = EstimateOptions { direction: Some(Direction::planar(0.0, 10.0)), ..Default::default() };
    /// let ex = EmpiricalVariogram::estimate(coords.as_ref(), &z, &binning, &along_x)?;
    /// assert_eq!(ex.counts, [20, 15]); // lags 1 and 2 along x in 5 rows
    /// assert_eq!(ex.gamma, [0.5, 2.0]); // h^2 / 2
    /// let along_y = EstimateOptions { direction: Some(Direction::planar(90.0, 10.0)), ..Default::default() };
    /// let ey = EmpiricalVariogram::estimate(coords.as_ref(), &z, &binning, &along_y)?;
    /// assert_eq!((ey.counts.clone(), ey.gamma.clone()), (vec![20, 15], vec![0.0, 0.0]));
    /// // Dowd: 1.099 median(|dz|)^2 per interval.
    /// let dowd = EstimateOptions { estimator: Estimator::Dowd, ..along_x };
    /// let ed = EmpiricalVariogram::estimate(coords.as_ref(), &z, &binning, &dowd)?;
    /// assert!((ed.gamma[1] - 1.099 * 4.0).abs() < 1e-12);
    /// # Ok::<(), kriging::KrigingError>(())
    /// ```
    pub fn estimate(
        coords: MatRef<'_, f64>,
        values: &[f64],
        binning: &Binning,
        opts: &EstimateOptions,
    ) -> Result<Self, KrigingError> {
        let (s, d) = coords.shape();
        crate::empirical::check_inputs(
            coords,
            MatRef::from_column_major_slice(values, values.len(), 1),
            binning,
        )?;
        let bins = binning.bins;
        // The direction, normalised; the tests are GSTools' (acos of the cosine, strict).
        let dir = match &opts.direction {
            None => None,
            Some(dr) => {
                if dr.vector.len() != d {
                    return Err(KrigingError::ShapeMismatch {
                        what: "direction length vs coordinate columns",
                        expected: d,
                        got: dr.vector.len(),
                    });
                }
                let norm = dr.vector.iter().map(|v| v * v).sum::<f64>().sqrt();
                if !(norm.is_finite() && norm > 0.0) {
                    return Err(KrigingError::InvalidConfig(format!(
                        "direction {:?} must be finite and not zero",
                        dr.vector
                    )));
                }
                if !(dr.tolerance > 0.0 && dr.tolerance <= 90.0) {
                    return Err(KrigingError::InvalidConfig(format!(
                        "angular tolerance {} must be in (0, 90] degrees",
                        dr.tolerance
                    )));
                }
                if let Some(b) = dr.bandwidth
                    && !(b.is_finite() && b > 0.0)
                {
                    return Err(KrigingError::InvalidConfig(format!(
                        "bandwidth {b} must be finite and > 0"
                    )));
                }
                let u: Vec<f64> = dr.vector.iter().map(|v| v / norm).collect();
                Some((u, dr.tolerance.to_radians(), dr.bandwidth))
            }
        };
        if let Some(radius) = opts.great_circle {
            crate::sphere::check_latlon_coords(coords, radius)?;
            if opts.direction.is_some() {
                return Err(KrigingError::InvalidConfig(
                    "directional variograms take planar coordinates, not latitude/longitude".into(),
                ));
            }
            if matches!(binning.max_lag, MaxLag::DiagonalFraction(_)) {
                return Err(KrigingError::InvalidConfig(
                    "a maximum lag as a fraction of the bounding-box diagonal has no meaning for \
                     latitude/longitude: give MaxLag::Distance or MaxLag::Largest"
                        .into(),
                ));
            }
        }
        let pts: Vec<f64> = (0..s)
            .flat_map(|i| (0..d).map(move |k| (i, k)))
            .map(|(i, k)| coords[(i, k)])
            .collect();
        let arc = |i: usize, j: usize, r: f64| {
            crate::sphere::great_circle_distance(
                [pts[i * d], pts[i * d + 1]],
                [pts[j * d], pts[j * d + 1]],
                r,
            )
        };
        let hmax = match (opts.great_circle, binning.max_lag) {
            (Some(r), MaxLag::Largest) => {
                let h = (0..s)
                    .flat_map(|i| (i + 1..s).map(move |j| (i, j)))
                    .map(|(i, j)| arc(i, j, r))
                    .fold(0.0f64, f64::max);
                if h.is_nan() || h <= 0.0 {
                    return Err(KrigingError::NoSpread { samples: s });
                }
                h
            }
            _ => max_lag(binning, &pts, s, d)?,
        };
        check_max_lag(hmax)?;
        let dh = hmax / bins as f64;
        let max2 = hmax * hmax;
        let est = opts.estimator;
        let in_direction = |e: &[f64], h: f64| -> bool {
            let Some((u, tol, band)) = &dir else {
                return true;
            };
            let sp: f64 = e.iter().zip(u).map(|(a, b)| a * b).sum();
            if let Some(b) = band {
                let off: f64 = e
                    .iter()
                    .zip(u)
                    .map(|(a, c)| (a - sp * c) * (a - sp * c))
                    .sum();
                if off.sqrt() >= *b {
                    return false;
                }
            }
            if h > 0.0 {
                let t = sp.abs() / h;
                if t < 1.0 {
                    return t.acos() < *tol;
                }
            }
            true
        };
        let row = |i: usize| -> Acc {
            let mut acc = Acc {
                sums: vec![0.0; bins],
                counts: vec![0; bins],
                diffs: if est == Estimator::Dowd {
                    vec![Vec::new(); bins]
                } else {
                    Vec::new()
                },
            };
            let pi = &pts[i * d..(i + 1) * d];
            let mut e = vec![0.0; d];
            for (j, pj) in pts.chunks_exact(d).enumerate().skip(i + 1) {
                for k in 0..d {
                    e[k] = pj[k] - pi[k];
                }
                let h = match opts.great_circle {
                    Some(r) => {
                        let h = arc(i, j, r);
                        if h > hmax {
                            continue;
                        }
                        h
                    }
                    None => {
                        let h2: f64 = e.iter().map(|v| v * v).sum();
                        if h2 > max2 {
                            continue;
                        }
                        let h = h2.sqrt();
                        if !in_direction(&e, h) {
                            continue;
                        }
                        h
                    }
                };
                let u = ((h / dh) as usize).min(bins - 1);
                let dz = values[j] - values[i];
                acc.counts[u] += 1;
                match est {
                    Estimator::Matheron => acc.sums[u] += dz * dz,
                    Estimator::CressieHawkins => acc.sums[u] += dz.abs().sqrt(),
                    Estimator::Dowd => acc.diffs[u].push(dz.abs()),
                }
            }
            acc
        };
        let mut sums = vec![0.0; bins];
        let mut counts = vec![0usize; bins];
        let mut diffs: Vec<Vec<f64>> =
            vec![Vec::new(); if est == Estimator::Dowd { bins } else { 0 }];
        let parallel = s * s * (d + 1) >= PARALLEL_MIN_WORK;
        crate::empirical::fold_rows(s, bins, parallel, row, |a| {
            for u in 0..bins {
                sums[u] += a.sums[u];
                counts[u] += a.counts[u];
            }
            for (all, mut part) in diffs.iter_mut().zip(a.diffs) {
                all.append(&mut part);
            }
        });
        let gamma: Vec<f64> = (0..bins)
            .map(|u| {
                let n = counts[u];
                if n == 0 {
                    return 0.0;
                }
                let nf = n as f64;
                match est {
                    Estimator::Matheron => sums[u] / (2.0 * nf),
                    Estimator::CressieHawkins => {
                        0.5 * (sums[u] / nf).powi(4) / (0.457 + 0.494 / nf + 0.045 / (nf * nf))
                    }
                    Estimator::Dowd => 1.099 * median(&mut diffs[u]).powi(2),
                }
            })
            .collect();
        crate::empirical::check_gamma(&gamma)?;
        Ok(EmpiricalVariogram {
            bin_width: dh,
            centers: (0..bins).map(|u| dh * (u as f64 + 0.5)).collect(),
            gamma,
            counts,
        })
    }
}

/// Median of a non-empty slice (mean of the two middle values for an even length); reorders it.
fn median(v: &mut [f64]) -> f64 {
    let n = v.len();
    v.sort_unstable_by(f64::total_cmp);
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Options of [`estimate_anisotropy`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AnisotropyOptions {
    /// The model whose range is fitted per direction (bounded: not linear or power).
    pub model: VariogramModel,
    /// Number of directions, evenly spread over 180 degrees from 0 (at least 3; default 4:
    /// 0, 45, 90 and 135 degrees counter-clockwise from the x axis).
    pub directions: usize,
    /// Angular tolerance of each directional variogram in degrees (default 22.5).
    pub tolerance: f64,
    /// Bandwidth of each directional variogram (default none).
    pub bandwidth: Option<f64>,
    /// The estimator (default Matheron).
    pub estimator: Estimator,
    /// Options of the fits (nugget, weights).
    pub fit: FitOptions,
}

impl Default for AnisotropyOptions {
    fn default() -> Self {
        AnisotropyOptions {
            model: VariogramModel::Exponential,
            directions: 4,
            tolerance: 22.5,
            bandwidth: None,
            estimator: Estimator::Matheron,
            fit: FitOptions::default(),
        }
    }
}

/// One direction of an [`AnisotropyEstimate`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DirectionalRange {
    /// Direction in degrees counter-clockwise from the x axis.
    pub angle: f64,
    /// The fitted range along it (nugget and sill of the omnidirectional fit held fixed).
    pub range: f64,
    /// Whether the range ended at a bound of its search interval.
    pub at_bound: bool,
    /// The directional empirical variogram.
    pub variogram: EmpiricalVariogram,
}

/// A 2-D geometric anisotropy estimated from directional variograms by [`estimate_anisotropy`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AnisotropyEstimate {
    /// The estimate, ready for [`crate::Krige::anisotropy`]: major-axis angle in `[0, 180)`
    /// degrees and `ratio = minor / major` range.
    pub anisotropy: Anisotropy,
    /// Range along the major axis (from the ellipse fit).
    pub major_range: f64,
    /// Range along the minor axis.
    pub minor_range: f64,
    /// The omnidirectional fit whose nugget and partial sill every direction shares.
    pub omnidirectional: FittedVariogram,
    /// Per direction: the fitted range and the empirical variogram.
    pub directions: Vec<DirectionalRange>,
}

/// Estimates a 2-D geometric anisotropy (major-axis angle and range ratio) from directional
/// variograms.
///
/// Steps: (1) fit `opts.model` to the omnidirectional variogram (nugget `n`, partial sill `s`,
/// exponent); (2) for each of the `m` directions `theta_k = 180 k / m` degrees, the directional
/// variogram ([`EmpiricalVariogram::estimate`], tolerance and bandwidth of `opts`) and its range
/// `r_k` by weighted least squares with `n`, `s` and the exponent fixed (geometric anisotropy: one
/// sill, ranges that vary with the direction); (3) the ranges of a geometric anisotropy lie on an
/// ellipse, `1 / r(theta)^2 = u(theta)^t M u(theta)` with `u = (cos theta, sin theta)` and `M`
/// symmetric positive definite; `M` is fitted by least squares to `1 / r_k^2` (linear in its three
/// entries); its eigenvalues `l_1 <= l_2` give the major range `1 / sqrt(l_1)` along the
/// eigenvector of `l_1` (the angle) and `ratio = sqrt(l_1 / l_2)`.
///
/// Neither PyKrige nor GSTools estimates the angle (GSTools fits the ranges along given main axes);
/// the result is checked on simulated anisotropic fields (`tests/variogram_fit.rs`). Directional
/// ranges that end at a bound are reported in [`DirectionalRange::at_bound`].
///
/// Errors: coordinates that are not 2-D, fewer than 3 directions, an unbounded model, the errors
/// of [`EmpiricalVariogram::estimate`] and [`fit_variogram`], a direction without pairs, and ranges
/// that fit no ellipse (`M` not positive definite).
///
/// ```
/// use kriging::faer::Mat;
/// use kriging::{estimate_anisotropy, AnisotropyOptions, Binning, MaxLag};
///
/// // z varies 4 times faster along y than along x: the major axis is x (angle 0), the minor
/// // range clearly shorter (the field is not exactly geometric-anisotropic: about 0.54 here).
/// let n = 400;
/// let coords = Mat::from_fn(n, 2, |i, k| {
///     let step = [0.618_033_988_749_895, 0.754_877_666_246_693][k];
///     100.0 * ((i as f64 + 0.5) * step).fract()
/// });
/// let z: Vec<f64> = (0..n)
///     .map(|i| (coords[(i, 0)] / 40.0).sin() + (coords[(i, 1)] / 10.0).sin())
///     .collect();
/// let binning = Binning { bins: 10, max_lag: MaxLag::Distance(40.0) };
/// let est = estimate_anisotropy(coords.as_ref(), &z, &binning, &AnisotropyOptions::default())?;
/// let kriging::Anisotropy::TwoD { angle, ratio } = est.anisotropy else { unreachable!() };
/// assert!(angle.min(180.0 - angle) < 10.0, "{angle}");
/// assert!(ratio < 0.75, "{ratio}");
/// # Ok::<(), kriging::KrigingError>(())
/// ```
pub fn estimate_anisotropy(
    coords: MatRef<'_, f64>,
    values: &[f64],
    binning: &Binning,
    opts: &AnisotropyOptions,
) -> Result<AnisotropyEstimate, KrigingError> {
    if coords.ncols() != 2 {
        return Err(KrigingError::ShapeMismatch {
            what: "coordinate columns for a 2-D anisotropy estimate",
            expected: 2,
            got: coords.ncols(),
        });
    }
    if opts.directions < 3 {
        return Err(KrigingError::InvalidConfig(format!(
            "an anisotropy estimate needs at least 3 directions, got {}",
            opts.directions
        )));
    }
    if !opts.model.has_range() {
        return Err(KrigingError::InvalidConfig(format!(
            "an anisotropy estimate needs a bounded model, got {}",
            opts.model.name()
        )));
    }
    let omni_opts = EstimateOptions {
        estimator: opts.estimator,
        ..EstimateOptions::default()
    };
    let omni_emp = EmpiricalVariogram::estimate(coords, values, binning, &omni_opts)?;
    let omni = fit_variogram(&omni_emp, opts.model, &opts.fit)?;
    let mut directions = Vec::with_capacity(opts.directions);
    // Normal equations of 1/r^2 = p c^2 + 2 q c s + t s^2.
    let mut ata = [[0.0f64; 3]; 3];
    let mut atb = [0.0f64; 3];
    for k in 0..opts.directions {
        let angle = 180.0 * k as f64 / opts.directions as f64;
        let mut dir = Direction::planar(angle, opts.tolerance);
        dir.bandwidth = opts.bandwidth;
        let o = EstimateOptions {
            estimator: opts.estimator,
            direction: Some(dir),
            great_circle: None,
        };
        let emp = EmpiricalVariogram::estimate(coords, values, binning, &o)?;
        if emp.nonempty() == 0 {
            return Err(KrigingError::VariogramFit {
                model: Some(opts.model),
                reason: format!("no pair in direction {angle} degrees (widen the tolerance)"),
            });
        }
        let (range, _, at_bound) = fit_range_fixed(&emp, &omni.variogram, &opts.fit)?;
        let (s, c) = angle.to_radians().sin_cos();
        let row = [c * c, 2.0 * c * s, s * s];
        let y = 1.0 / (range * range);
        for i in 0..3 {
            atb[i] += row[i] * y;
            for j in 0..3 {
                ata[i][j] += row[i] * row[j];
            }
        }
        directions.push(DirectionalRange {
            angle,
            range,
            at_bound,
            variogram: emp,
        });
    }
    let [p, q, t] = solve3(ata, atb).ok_or_else(|| {
        KrigingError::InvalidConfig("the directions do not determine an ellipse".into())
    })?;
    // Eigenvalues of [[p, q], [q, t]].
    let mean = 0.5 * (p + t);
    let rad = (0.25 * (p - t) * (p - t) + q * q).sqrt();
    let (l1, l2) = (mean - rad, mean + rad);
    if !(l1 > 0.0 && l2.is_finite()) {
        return Err(KrigingError::VariogramFit {
            model: Some(opts.model),
            reason: format!(
                "the directional ranges {:?} fit no ellipse (no geometric anisotropy)",
                directions.iter().map(|d| d.range).collect::<Vec<_>>()
            ),
        });
    }
    // Eigenvector of l1: (q, l1 - p) or (l1 - t, q).
    let (vx, vy) = if (l1 - t).abs() + q.abs() > 0.0 {
        (l1 - t, q)
    } else {
        (1.0, 0.0)
    };
    let mut angle = vy.atan2(vx).to_degrees().rem_euclid(180.0);
    if angle >= 180.0 {
        angle = 0.0;
    }
    Ok(AnisotropyEstimate {
        anisotropy: Anisotropy::TwoD {
            angle,
            ratio: (l1 / l2).sqrt(),
        },
        major_range: 1.0 / l1.sqrt(),
        minor_range: 1.0 / l2.sqrt(),
        omnidirectional: omni,
        directions,
    })
}

/// Solves a 3 x 3 system by Cramer's rule; `None` when (nearly) singular.
fn solve3(a: [[f64; 3]; 3], b: [f64; 3]) -> Option<[f64; 3]> {
    let det = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(a);
    let scale = a.iter().flatten().fold(0.0f64, |s, v| s.max(v.abs()));
    if d.is_nan() || d.abs() <= 1e-12 * scale * scale * scale {
        return None;
    }
    let mut x = [0.0; 3];
    for (k, xk) in x.iter_mut().enumerate() {
        let mut m = a;
        for i in 0..3 {
            m[i][k] = b[i];
        }
        *xk = det(m) / d;
    }
    Some(x)
}
