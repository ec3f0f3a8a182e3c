//! The data's control hull: whether a walk's controls lie among the training samples' (inside the
//! convex hull of their step, turn and height) or beyond them, where the model extrapolates.
//!
//! Each control may lie inside its own range while the combination does not: a turn of -70 degrees
//! at the longest step is in range for both, yet no take turns that sharply at that speed. The
//! hull is the convex hull of the training samples' controls, each standardised by its spread over
//! the samples (so that a tolerance reads in standard deviations); the controls the model ignores
//! (constant over the data or dropped) and the style code take no part.

use lod_policy::Controls;

use crate::model::MotionModel;

/// How far beyond the hull (in standard deviations of the samples' controls) a point still counts
/// as inside: rounding of the hull distance, and walks on its faces.
pub const HULL_TOLERANCE: f64 = 0.05;

/// The convex hull of a model's training controls (see the module docs).
#[derive(Debug, Clone)]
pub struct ControlHull {
    /// The controls that span the hull (indices into `Controls::to_array`).
    dims: Vec<usize>,
    /// Per hull dimension: mean and standard deviation of the raw sample values.
    mean: Vec<f64>,
    std: Vec<f64>,
    /// Standardised sample points, `S x dims.len()` row-major.
    points: Vec<f64>,
}

impl ControlHull {
    /// The hull of `model`'s training controls over the controls the kriging uses (of dx, dz, turn
    /// and height, those with a spread).
    pub fn of(model: &MotionModel) -> ControlHull {
        let lod = model.lod();
        let cs = lod.controls();
        let s = lod.s();
        let d = lod.d().min(Controls::COUNT);
        let dims: Vec<usize> = (0..d).filter(|&k| cs.scale[k] > 0.0).collect();
        let raw = |i: usize, k: usize| -> f64 {
            f64::from(cs.samples[i + s * k]) / f64::from(cs.scale[k]) + f64::from(cs.offset[k])
        };
        let mut mean = Vec::with_capacity(dims.len());
        let mut std = Vec::with_capacity(dims.len());
        for &k in &dims {
            let m = (0..s).map(|i| raw(i, k)).sum::<f64>() / s.max(1) as f64;
            let v = (0..s).map(|i| (raw(i, k) - m).powi(2)).sum::<f64>() / s.max(1) as f64;
            mean.push(m);
            std.push(if v > 0.0 { v.sqrt() } else { 1.0 });
        }
        let mut points = Vec::with_capacity(s * dims.len());
        for i in 0..s {
            for (j, &k) in dims.iter().enumerate() {
                points.push((raw(i, k) - mean[j]) / std[j]);
            }
        }
        ControlHull {
            dims,
            mean,
            std,
            points,
        }
    }

    /// The controls that span the hull (indices into [`Controls::to_array`]: 0 dx, 1 dz, 2 turn,
    /// 3 height).
    pub fn dims(&self) -> &[usize] {
        &self.dims
    }

    fn standardised(&self, controls: &Controls) -> Vec<f64> {
        let a = controls.to_array();
        self.dims
            .iter()
            .enumerate()
            .map(|(j, &k)| (f64::from(a[k]) - self.mean[j]) / self.std[j])
            .collect()
    }

    /// Euclidean distance, in standard deviations of the samples' controls, from `controls` to the
    /// hull (0 inside): the nearest point of the hull by non-negative least squares (Lawson and
    /// Hanson's active set) on `min |X lambda - q|^2 + M^2 (1 - sum lambda)^2` over `lambda >= 0`,
    /// with the weight `M = 1000` holding the weights' sum to 1; the distance is measured to
    /// `X lambda / sum lambda`, a point of the hull, so it is never below the true distance.
    pub fn distance(&self, controls: &Controls) -> f64 {
        let m = self.dims.len();
        if m == 0 || self.points.is_empty() {
            return 0.0;
        }
        let q = self.standardised(controls);
        let n = self.points.len() / m;
        const WEIGHT: f64 = 1000.0;
        // Column j of A: (x_j, M); b = (q, M).
        let col = |j: usize, r: usize| {
            if r < m {
                self.points[j * m + r]
            } else {
                WEIGHT
            }
        };
        let rows = m + 1;
        let mut b = q.clone();
        b.push(WEIGHT);
        let mut lambda = vec![0.0f64; n];
        let mut passive: Vec<usize> = Vec::with_capacity(rows + 1);
        let residual = |lambda: &[f64], passive: &[usize]| -> Vec<f64> {
            let mut r = b.clone();
            for &j in passive {
                for (i, ri) in r.iter_mut().enumerate() {
                    *ri -= col(j, i) * lambda[j];
                }
            }
            r
        };
        for _ in 0..4 * n {
            let r = residual(&lambda, &passive);
            // The most promising column not yet in the passive set.
            let best = (0..n)
                .filter(|j| !passive.contains(j))
                .map(|j| (j, (0..rows).map(|i| col(j, i) * r[i]).sum::<f64>()))
                .max_by(|a, b| a.1.total_cmp(&b.1));
            let Some((t, w)) = best else { break };
            if w <= 1e-9 * WEIGHT {
                break;
            }
            passive.push(t);
            for _ in 0..4 * rows {
                let z = least_squares(&passive, rows, &col, &b);
                if z.iter().all(|&v| v > 0.0) {
                    for (&j, &v) in passive.iter().zip(&z) {
                        lambda[j] = v;
                    }
                    break;
                }
                // Step from lambda towards z until the first weight reaches zero; drop it.
                let alpha = passive
                    .iter()
                    .zip(&z)
                    .filter(|&(_, &v)| v <= 0.0)
                    .map(|(&j, &v)| lambda[j] / (lambda[j] - v))
                    .fold(1.0f64, f64::min);
                for (&j, &v) in passive.iter().zip(&z) {
                    lambda[j] += alpha * (v - lambda[j]);
                }
                passive.retain(|&j| {
                    let keep = lambda[j] > 1e-14;
                    if !keep {
                        lambda[j] = 0.0;
                    }
                    keep
                });
            }
        }
        let total: f64 = passive.iter().map(|&j| lambda[j]).sum();
        if total.is_nan() || total <= 0.0 {
            return f64::INFINITY;
        }
        (0..m)
            .map(|i| {
                let x = passive
                    .iter()
                    .map(|&j| self.points[j * m + i] * lambda[j])
                    .sum::<f64>()
                    / total;
                (x - q[i]).powi(2)
            })
            .sum::<f64>()
            .sqrt()
    }

    /// Whether `controls` lie inside the hull (within [`HULL_TOLERANCE`]).
    pub fn contains(&self, controls: &Controls) -> bool {
        self.distance(controls) <= HULL_TOLERANCE
    }

    /// The point where the hull ends on the way from `from` (which should be inside) along control
    /// `k` in the direction of `sign`, found by bisection to 1e-4 of the control's range `span`:
    /// the last point inside. `from` itself when it is not inside or `k` spans no hull dimension.
    pub fn edge(&self, from: Controls, k: usize, sign: f32, span: f32) -> Controls {
        let along = |t: f32| {
            let mut a = from.to_array();
            a[k] += sign * t;
            Controls::from_array(a).with_style(from.style)
        };
        if !self.dims.contains(&k) || !self.contains(&from) || span.is_nan() || span <= 0.0 {
            return from;
        }
        let (mut lo, mut hi) = (0.0f32, span);
        if self.contains(&along(hi)) {
            return along(hi);
        }
        while hi - lo > 1e-4 * span {
            let mid = 0.5 * (lo + hi);
            if self.contains(&along(mid)) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        along(lo)
    }
}

/// `argmin_z |A_P z - b|` for the columns `passive` of `A` (`col(j, i)`: row `i` of column `j`,
/// `rows` rows), by the normal equations with partial pivoting (at most `rows + 1` columns, well
/// conditioned in practice; a singular system gives the weights found so far).
fn least_squares(
    passive: &[usize],
    rows: usize,
    col: &dyn Fn(usize, usize) -> f64,
    b: &[f64],
) -> Vec<f64> {
    let k = passive.len();
    let mut a = vec![0.0f64; k * (k + 1)];
    for (r, &jr) in passive.iter().enumerate() {
        for (c, &jc) in passive.iter().enumerate() {
            a[r * (k + 1) + c] = (0..rows).map(|i| col(jr, i) * col(jc, i)).sum();
        }
        a[r * (k + 1) + k] = (0..rows).map(|i| col(jr, i) * b[i]).sum();
    }
    for p in 0..k {
        let piv = (p..k)
            .max_by(|&x, &y| {
                a[x * (k + 1) + p]
                    .abs()
                    .total_cmp(&a[y * (k + 1) + p].abs())
            })
            .unwrap_or(p);
        if a[piv * (k + 1) + p].abs() < 1e-12 {
            continue;
        }
        for c in 0..=k {
            a.swap(p * (k + 1) + c, piv * (k + 1) + c);
        }
        for r in 0..k {
            if r != p {
                let f = a[r * (k + 1) + p] / a[p * (k + 1) + p];
                for c in p..=k {
                    a[r * (k + 1) + c] -= f * a[p * (k + 1) + c];
                }
            }
        }
    }
    (0..k)
        .map(|r| {
            let d = a[r * (k + 1) + r];
            if d.abs() < 1e-12 {
                0.0
            } else {
                a[r * (k + 1) + k] / d
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hull(points: &[[f64; 2]]) -> ControlHull {
        ControlHull {
            dims: vec![0, 1],
            mean: vec![0.0, 0.0],
            std: vec![1.0, 1.0],
            points: points.iter().flatten().copied().collect(),
        }
    }

    #[test]
    fn distance_to_a_square_by_hand() {
        let h = hull(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [0.5, 0.5]]);
        let c = |x: f32, z: f32| Controls::from_array([x, z, 0.0, 0.0]);
        assert!(h.distance(&c(0.5, 0.25)) < 1e-6);
        assert!(h.distance(&c(0.999, 0.999)) < 1e-6);
        assert!((h.distance(&c(2.0, 0.5)) - 1.0).abs() < 1e-4);
        assert!((h.distance(&c(2.0, 2.0)) - 2f64.sqrt()).abs() < 1e-4);
        assert!((h.distance(&c(-0.3, 0.5)) - 0.3).abs() < 1e-4);
        assert!(h.contains(&c(0.2, 0.7)) && !h.contains(&c(0.2, 1.2)));
    }

    #[test]
    fn a_corner_beyond_both_ranges_is_outside_a_triangle() {
        // Both coordinates in range, the combination not: the diagonal's far side of a triangle.
        let h = hull(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]);
        let c = Controls::from_array([0.9, 0.9, 0.0, 0.0]);
        assert!((h.distance(&c) - 0.8 / 2f64.sqrt()).abs() < 1e-4);
        assert!(!h.contains(&c));
        // The edge along x from (0, 0.5) is the hypotenuse, x = 0.5.
        let e = h.edge(Controls::from_array([0.0, 0.5, 0.0, 0.0]), 0, 1.0, 2.0);
        assert!(
            (e.dx - 0.5 - HULL_TOLERANCE as f32 * 2f32.sqrt()).abs() < 1e-3,
            "{e:?}"
        );
    }
}
