//! An independent, deliberately naive implementation used as the reference in the tests:
//! plain Vec<Vec<f64>>, Gaussian elimination, formulas typed again from the paper.
#![allow(clippy::needless_range_loop)]

pub mod gstools_points;

use faer::Mat;
use kriging::{Variogram, VariogramModel};

/// gamma(h) typed again from the formulas (0 at h = 0).
pub fn gamma(v: &Variogram, h: f64) -> f64 {
    if h == 0.0 {
        return 0.0;
    }
    gamma_pair(v, h)
}

/// Variogram between distinct samples (nugget included even at h = 0).
pub fn gamma_pair(v: &Variogram, h: f64) -> f64 {
    let a = v.range;
    let f = match v.model {
        VariogramModel::Linear => h,
        VariogramModel::Power => h.powf(v.exponent),
        VariogramModel::Spherical => {
            if h < a {
                1.5 * (h / a) - 0.5 * (h / a).powi(3)
            } else {
                1.0
            }
        }
        VariogramModel::Exponential => 1.0 - (-3.0 * h / a).exp(),
        VariogramModel::Gaussian => 1.0 - (-3.0 * (h / a).powi(2)).exp(),
        // Only the half-integer closed forms (the crate's general-nu path is unit tested).
        VariogramModel::Matern if v.exponent == 1.5 => 1.0 - (1.0 + h / a) * (-h / a).exp(),
        VariogramModel::Matern => panic!("naive Matern only for nu = 3/2"),
        VariogramModel::CardinalSine => 1.0 - (h / a).sin() / (h / a),
    };
    v.nugget + v.sill * f
}

pub fn dist(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt()
}

/// Solves a x = b by Gaussian elimination with partial pivoting.
pub fn solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Vec<f64> {
    let n = b.len();
    for col in 0..n {
        let p = (col..n)
            .max_by(|&i, &j| a[i][col].abs().partial_cmp(&a[j][col].abs()).unwrap())
            .unwrap();
        a.swap(col, p);
        b.swap(col, p);
        for r in col + 1..n {
            let f = a[r][col] / a[col][col];
            for k in col..n {
                a[r][k] -= f * a[col][k];
            }
            b[r] -= f * b[col];
        }
    }
    let mut x = vec![0.0; n];
    for i in (0..n).rev() {
        let s: f64 = (i + 1..n).map(|k| a[i][k] * x[k]).sum();
        x[i] = (b[i] - s) / a[i][i];
    }
    x
}

/// Ordinary kriging weights at c (appendix A system).
pub fn ok_weights(p: &[Vec<f64>], v: &Variogram, c: &[f64]) -> Vec<f64> {
    let s = p.len();
    let mut a = vec![vec![0.0; s + 1]; s + 1];
    for i in 0..s {
        for j in 0..s {
            a[i][j] = if i == j {
                0.0
            } else {
                gamma_pair(v, dist(&p[i], &p[j]))
            };
        }
        a[i][s] = 1.0;
        a[s][i] = 1.0;
    }
    let mut rhs: Vec<f64> = p.iter().map(|pi| gamma(v, dist(c, pi))).collect();
    rhs.push(1.0);
    let mut x = solve(a, rhs);
    x.truncate(s);
    x
}

/// Least-squares trend F (D x (d+1)) by the normal equations (full rank only).
pub fn trend(p: &[Vec<f64>], x: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let d = p[0].len();
    let z: Vec<Vec<f64>> = p
        .iter()
        .map(|pi| pi.iter().copied().chain([1.0]).collect())
        .collect();
    let dv = x[0].len();
    (0..dv)
        .map(|j| {
            let g: Vec<Vec<f64>> = (0..=d)
                .map(|a| {
                    (0..=d)
                        .map(|b| z.iter().map(|zi| zi[a] * zi[b]).sum())
                        .collect()
                })
                .collect();
            let rhs: Vec<f64> = (0..=d)
                .map(|a| z.iter().zip(x).map(|(zi, xi)| zi[a] * xi[j]).sum())
                .collect();
            solve(g, rhs)
        })
        .collect()
}

/// Ordinary (trend = None) or regression kriging prediction at c.
pub fn predict(
    p: &[Vec<f64>],
    x: &[Vec<f64>],
    v: &Variogram,
    regression: bool,
    c: &[f64],
) -> Vec<f64> {
    let dv = x[0].len();
    let b = ok_weights(p, v, c);
    if !regression {
        return (0..dv)
            .map(|j| b.iter().zip(x).map(|(bi, xi)| bi * xi[j]).sum())
            .collect();
    }
    let f = trend(p, x);
    let lin = |fj: &Vec<f64>, q: &[f64]| -> f64 {
        q.iter().zip(fj).map(|(a, b)| a * b).sum::<f64>() + fj[q.len()]
    };
    (0..dv)
        .map(|j| {
            let r: f64 = b
                .iter()
                .zip(p.iter().zip(x))
                .map(|(bi, (pi, xi))| bi * (xi[j] - lin(&f[j], pi)))
                .sum();
            lin(&f[j], c) + r
        })
        .collect()
}

/// The rows of `v` without row `k` (the data of a leave-one-out refit).
pub fn without(v: &[Vec<f64>], k: usize) -> Vec<Vec<f64>> {
    v.iter()
        .enumerate()
        .filter(|(i, _)| *i != k)
        .map(|(_, q)| q.clone())
        .collect()
}

/// Leave-one-out errors by refitting S times.
pub fn loo(p: &[Vec<f64>], x: &[Vec<f64>], v: &Variogram, regression: bool) -> Vec<Vec<f64>> {
    (0..p.len())
        .map(|k| {
            let (pk, xk) = (without(p, k), without(x, k));
            let pred = predict(&pk, &xk, v, regression, &p[k]);
            x[k].iter().zip(&pred).map(|(a, b)| a - b).collect()
        })
        .collect()
}

/// Empirical variogram of appendix A: (centres, gamma, counts).
pub fn empirical(p: &[Vec<f64>], x: &[Vec<f64>], bins: usize) -> (Vec<f64>, Vec<f64>, Vec<usize>) {
    let s = p.len();
    let mut hmax: f64 = 0.0;
    for i in 0..s {
        for j in i + 1..s {
            hmax = hmax.max(dist(&p[i], &p[j]));
        }
    }
    let dh = hmax / bins as f64;
    let mut sum = vec![0.0; bins];
    let mut cnt = vec![0usize; bins];
    for i in 0..s {
        for j in i + 1..s {
            let u = ((dist(&p[i], &p[j]) / dh).floor() as usize).min(bins - 1);
            let sq: f64 = x[i].iter().zip(&x[j]).map(|(a, b)| (a - b).powi(2)).sum();
            sum[u] += sq / 2.0;
            cnt[u] += 1;
        }
    }
    let g = sum
        .iter()
        .zip(&cnt)
        .map(|(s, &n)| if n > 0 { s / n as f64 } else { 0.0 })
        .collect();
    let c = (0..bins).map(|u| dh * (u as f64 + 0.5)).collect();
    (c, g, cnt)
}

/// Deterministic pseudo-random numbers in [0, 1) (xorshift).
pub struct Rng(pub u64);
impl Rng {
    pub fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A smooth nonlinear test field with D = 3 outputs.
pub fn field(c: &[f64]) -> Vec<f64> {
    let s: f64 = c.iter().sum();
    vec![
        (2.0 * c[0]).sin() + 0.5 * s,
        c.iter().map(|v| v * v).sum::<f64>(),
        (c[c.len() - 1] * 1.7).cos() - c[0],
    ]
}

/// `n` random points in [0, 1]^d with the field values.
pub fn data(n: usize, d: usize, seed: u64) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let mut r = Rng(seed);
    let p: Vec<Vec<f64>> = (0..n).map(|_| (0..d).map(|_| r.next()).collect()).collect();
    let x = p.iter().map(|c| field(c)).collect();
    (p, x)
}

pub fn to_mat(v: &[Vec<f64>]) -> Mat<f64> {
    Mat::from_fn(v.len(), v[0].len(), |i, j| v[i][j])
}

pub fn var(model: VariogramModel, nugget: f64) -> Variogram {
    Variogram::new(model, nugget, 1.3, 0.9, 1.4).unwrap()
}

/// Deterministic uniform numbers in [-1, 1) (a 64-bit LCG).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

/// The control-selection tests' data: 60 samples (`seed` of the LCG) over three parameters, `a` and
/// `b` spread over [-1, 1], `c` constant (2.5); four values, a smooth function of `a`, plus `b_weight`
/// times one of `b`, plus independent noise (0.05).
pub fn selection_data(seed: u64, b_weight: f64) -> (Mat<f64>, Mat<f64>) {
    let mut rng = Lcg(seed);
    let s = 60;
    let rows: Vec<[f64; 3]> = (0..s).map(|_| [rng.next(), rng.next(), 2.5]).collect();
    let params = Mat::from_fn(s, 3, |i, k| rows[i][k]);
    let noise: Vec<f64> = (0..s * 4).map(|_| 0.05 * rng.next()).collect();
    let values = Mat::from_fn(s, 4, |i, j| {
        let [a, b, _] = rows[i];
        let signal = (1.0 + j as f64) * (1.5 * a).sin() + 0.3 * a * a;
        signal + b_weight * ((j as f64 - 1.5) * b + 0.5 * b * b) + noise[i * 4 + j]
    });
    (params, values)
}
