//! Test fixtures: a small random model built from a random Tucker decomposition, random controls
//! and a kriging system solved here, plus an independent direct f64 evaluation of eq. 4/7/8.
#![allow(dead_code, clippy::needless_range_loop)]

use lod_policy::{AccuracyLevel, ControlSpace, KeyTensor, LevelError, ModelParts, Ranks};
use lod_policy::{LodModel, Variogram};

/// SplitMix64: deterministic, dependency-free.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed)
    }
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [lo, hi).
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
    }
}

/// Random `n x r` column-major matrix with orthonormal columns (modified Gram-Schmidt).
pub fn orthonormal(rng: &mut Rng, n: usize, r: usize) -> Vec<f64> {
    let mut m: Vec<f64> = (0..n * r).map(|_| rng.uniform(-1.0, 1.0)).collect();
    for j in 0..r {
        for k in 0..j {
            let dot: f64 = (0..n).map(|i| m[i + n * j] * m[i + n * k]).sum();
            for i in 0..n {
                m[i + n * j] -= dot * m[i + n * k];
            }
        }
        let norm: f64 = (0..n).map(|i| m[i + n * j].powi(2)).sum::<f64>().sqrt();
        for i in 0..n {
            m[i + n * j] /= norm;
        }
    }
    m
}

/// Gaussian elimination with partial pivoting: solves `a x = b` (a is `n x n` column-major).
pub fn solve(a: &[f64], b: &[f64], n: usize) -> Vec<f64> {
    let mut m = a.to_vec();
    let mut x = b.to_vec();
    for col in 0..n {
        let piv = (col..n)
            .max_by(|&i, &j| m[i + n * col].abs().total_cmp(&m[j + n * col].abs()))
            .unwrap();
        assert!(m[piv + n * col].abs() > 1e-14, "singular test system");
        if piv != col {
            for k in 0..n {
                m.swap(col + n * k, piv + n * k);
            }
            x.swap(col, piv);
        }
        for i in col + 1..n {
            let f = m[i + n * col] / m[col + n * col];
            if f != 0.0 {
                for k in col..n {
                    m[i + n * k] -= f * m[col + n * k];
                }
                x[i] -= f * x[col];
            }
        }
    }
    for col in (0..n).rev() {
        let mut v = x[col];
        for k in col + 1..n {
            v -= m[col + n * k] * x[k];
        }
        x[col] = v / m[col + n * col];
    }
    x
}

/// Everything the direct evaluation needs, in f64.
pub struct Truth {
    pub p: usize,
    pub t: usize,
    pub s: usize,
    pub d: usize,
    pub keys: Vec<KeyF64>,
    pub levels: Vec<AccuracyLevel>,
    /// Scaled sample controls `S x d`.
    pub controls: Vec<f64>,
    pub offset: Vec<f64>,
    pub scale: Vec<f64>,
    pub min: Vec<f64>,
    pub max: Vec<f64>,
    pub variogram: Variogram,
    pub mean_pose: Vec<f64>,
}

pub struct KeyF64 {
    pub ranks: Ranks,
    pub core: Vec<f64>,
    pub u_p: Vec<f64>,
    pub u_t: Vec<f64>,
    pub u_s: Vec<f64>,
}

pub const JOINTS: usize = 4;
pub const P: usize = 7 + 3 * JOINTS;
pub const T: usize = 12;
pub const S: usize = 16;
pub const D: usize = 2;

/// The kriging matrix `A = [Gamma 1; 1^T 0]` over scaled controls, column-major `(S+1)^2`.
pub fn kriging_matrix(truth: &Truth) -> Vec<f64> {
    let (s, d) = (truth.s, truth.d);
    let n = s + 1;
    let mut a = vec![0.0; n * n];
    for i in 0..s {
        for j in 0..s {
            let h: f64 = (0..d)
                .map(|k| (truth.controls[i + s * k] - truth.controls[j + s * k]).powi(2))
                .sum::<f64>()
                .sqrt();
            a[i + n * j] = truth.variogram.eval(h);
        }
        a[i + n * s] = 1.0;
        a[s + n * i] = 1.0;
    }
    a
}

/// Random truth with two keys and four accuracy levels.
pub fn random_truth(seed: u64, nugget: f64) -> Truth {
    random_truth_with(seed, nugget, D, lod_policy::VariogramModel::Exponential)
}

/// [`random_truth`] with `d` controls and a variogram of the given model (sill 1, range 0.7,
/// exponent 1).
pub fn random_truth_with(
    seed: u64,
    nugget: f64,
    d: usize,
    model: lod_policy::VariogramModel,
) -> Truth {
    let mut rng = Rng::new(seed);
    let (p, t, s) = (P, T, S);
    let key_ranks = [Ranks::new(6, 5, 8), Ranks::new(4, 4, 5)];
    let keys = key_ranks
        .iter()
        .map(|&r| KeyF64 {
            ranks: r,
            core: (0..r.core_len()).map(|_| rng.uniform(-2.0, 2.0)).collect(),
            u_p: orthonormal(&mut rng, p, r.p),
            u_t: orthonormal(&mut rng, t, r.t),
            u_s: orthonormal(&mut rng, s, r.s),
        })
        .collect();
    let levels = vec![
        AccuracyLevel {
            key: 0,
            ranks: key_ranks[0],
        },
        AccuracyLevel {
            key: 0,
            ranks: Ranks::new(5, 4, 6),
        },
        AccuracyLevel {
            key: 1,
            ranks: key_ranks[1],
        },
        AccuracyLevel {
            key: 1,
            ranks: Ranks::new(3, 2, 3),
        },
    ];
    let raw: Vec<f64> = (0..s * d)
        .map(|i| {
            if i < s {
                rng.uniform(-0.5, 0.5)
            } else {
                rng.uniform(0.5, 2.0)
            }
        })
        .collect();
    let mut min = vec![f64::INFINITY; d];
    let mut max = vec![f64::NEG_INFINITY; d];
    for k in 0..d {
        for i in 0..s {
            min[k] = min[k].min(raw[i + s * k] as f32 as f64);
            max[k] = max[k].max(raw[i + s * k] as f32 as f64);
        }
    }
    let offset: Vec<f64> = (0..d)
        .map(|k| ((min[k] + max[k]) / 2.0) as f32 as f64)
        .collect();
    let scale: Vec<f64> = (0..d)
        .map(|k| (1.0 / (max[k] - min[k])) as f32 as f64)
        .collect();
    // Scaled as the runtime does it (raw and parameters rounded to f32 first).
    let controls: Vec<f64> = (0..s * d)
        .map(|i| {
            let k = i / s;
            ((raw[i] as f32 as f64) - offset[k]) * scale[k]
        })
        .map(|v| v as f32 as f64)
        .collect();
    let variogram = Variogram::new(model, nugget, 1.0, 0.7, 1.0).unwrap();
    let mean_pose = (0..p).map(|_| rng.uniform(-1.0, 1.0)).collect();
    Truth {
        p,
        t,
        s,
        d,
        keys,
        levels,
        controls,
        offset,
        scale,
        min,
        max,
        variogram,
        mean_pose,
    }
}

fn f32v(v: &[f64]) -> Vec<f32> {
    v.iter().map(|&x| x as f32).collect()
}

/// Entry `(row, i)` of `C`, the `(d + 1) x S` matrix of columns `[c_i; 1]` (scaled controls).
pub fn c_entry(truth: &Truth, row: usize, i: usize) -> f64 {
    if row < truth.d {
        truth.controls[i + truth.s * row]
    } else {
        1.0
    }
}

/// `C C^T`, `(d + 1) x (d + 1)` column-major.
pub fn c_gram(truth: &Truth) -> Vec<f64> {
    let dc = truth.d + 1;
    let mut cct = vec![0.0; dc * dc];
    for x in 0..dc {
        for y in 0..dc {
            cct[x + dc * y] = (0..truth.s)
                .map(|i| c_entry(truth, x, i) * c_entry(truth, y, i))
                .sum();
        }
    }
    cct
}

/// Builds the runtime model from the truth (kriging inverse by solving A X = I here).
pub fn build_model(truth: &Truth) -> LodModel {
    let s = truth.s;
    let n = s + 1;
    let a = kriging_matrix(truth);
    // A^{-1}[:S, :]: column j of the inverse solves A x = e_j; keep its first S entries.
    let mut rows = vec![0.0; s * n];
    for j in 0..n {
        let mut e = vec![0.0; n];
        e[j] = 1.0;
        let x = solve(&a, &e, n);
        rows[s * j..s * (j + 1)].copy_from_slice(&x[..s]);
    }
    // C = [c_i; 1] ((d + 1) x S, scaled controls) and (C C^T).
    let dc = truth.d + 1;
    let cm = |row: usize, i: usize| c_entry(truth, row, i);
    let cct = c_gram(truth);
    let keys: Vec<KeyTensor> = truth
        .keys
        .iter()
        .map(|k| {
            let rs = k.ranks.s;
            // Q = U_S^T A^{-1}[:S, :] (R_S x (S + 1)).
            let mut q = vec![0.0; rs * n];
            for j in 0..n {
                for l in 0..rs {
                    q[l + rs * j] = (0..s).map(|i| k.u_s[i + s * l] * rows[i + s * j]).sum();
                }
            }
            // V = U_S^T C^T (C C^T)^{-1} (R_S x (d + 1)): row l solves (C C^T) v = C U_S[:, l].
            let mut v = vec![0.0; rs * dc];
            for l in 0..rs {
                let rhs: Vec<f64> = (0..dc)
                    .map(|x| (0..s).map(|i| cm(x, i) * k.u_s[i + s * l]).sum())
                    .collect();
                for (m, vm) in solve(&cct, &rhs, dc).into_iter().enumerate() {
                    v[l + rs * m] = vm;
                }
            }
            KeyTensor {
                ranks: k.ranks,
                core: f32v(&k.core),
                u_p: f32v(&k.u_p),
                u_t: f32v(&k.u_t),
                projection: f32v(&q),
                trend: f32v(&v),
            }
        })
        .collect();
    // C A^{-1}[:S, :] ((d + 1) x (S + 1)).
    let mut pc = vec![0.0; dc * n];
    for j in 0..n {
        for x in 0..dc {
            pc[x + dc * j] = (0..s).map(|i| cm(x, i) * rows[i + s * j]).sum();
        }
    }
    let controls = ControlSpace {
        variogram: truth.variogram,
        offset: f32v(&truth.offset),
        scale: f32v(&truth.scale),
        samples: f32v(&truth.controls),
        min: f32v(&truth.min),
        max: f32v(&truth.max),
        projection: f32v(&pc),
        implied: Vec::new(),
    };
    LodModel::new(ModelParts {
        p: truth.p,
        t: truth.t,
        s,
        d: truth.d,
        always_rows: 7,
        rows_per_joint: 3,
        keys,
        levels: truth.levels.clone(),
        controls,
        time_scale: 1.0,
        mean_pose: f32v(&truth.mean_pose),
        level_errors: vec![
            LevelError {
                mean_joint_cm: 0.1,
                shell_cm: 0.2,
                slide_cm: 0.0,
                ..LevelError::default()
            },
            LevelError {
                mean_joint_cm: 0.5,
                shell_cm: 0.9,
                slide_cm: 0.0,
                ..LevelError::default()
            },
            LevelError {
                mean_joint_cm: 1.5,
                shell_cm: 2.5,
                slide_cm: 0.0,
                ..LevelError::default()
            },
            LevelError {
                mean_joint_cm: 4.0,
                shell_cm: 7.0,
                slide_cm: 0.0,
                ..LevelError::default()
            },
        ],
        joint_errors: (0..=JOINTS)
            .map(|j| {
                let e = 3.0 * (JOINTS - j) as f32;
                LevelError {
                    mean_joint_cm: e,
                    shell_cm: 1.5 * e,
                    slide_cm: 0.0,
                    ..LevelError::default()
                }
            })
            .collect(),
    })
    .unwrap()
}

/// Direct f64 evaluation of eq. 4/7/8 at accuracy level `level` for raw controls `c`, returning
/// the full pose vector at fractional aligned frame `phase` (all P rows evaluated).
pub fn direct_pose(truth: &Truth, level: usize, c: &[f64], phase: f64) -> Vec<f64> {
    let (p, t, s, d) = (truth.p, truth.t, truth.s, truth.d);
    let lv = truth.levels[level];
    let key = &truth.keys[lv.key];
    let big = key.ranks;
    let r = lv.ranks;
    // Scaled, clamped controls.
    let cs: Vec<f64> = (0..d)
        .map(|k| {
            let v = (c[k] as f32).clamp(truth.min[k] as f32, truth.max[k] as f32) as f64;
            (v - truth.offset[k]) * truth.scale[k]
        })
        .collect();
    // Kriging weights: solve A [b; lambda] = [gamma(c); 1].
    let a = kriging_matrix(truth);
    let mut rhs = vec![1.0; s + 1];
    for i in 0..s {
        let h: f64 = (0..d)
            .map(|k| (cs[k] - truth.controls[i + s * k]).powi(2))
            .sum::<f64>()
            .sqrt();
        rhs[i] = truth.variogram.eval(h);
    }
    let bl = solve(&a, &rhs, s + 1);
    let b = &bl[..s];
    // Truncated per-sample cores K_i = Z_t x_3 u_{S,i} (r_P r_T vectors), and K (r_P r_T x S).
    let m = r.p * r.t;
    let mut kmat = vec![0.0; m * s];
    for i in 0..s {
        for l in 0..r.s {
            let u = key.u_s[i + s * l];
            for bb in 0..r.t {
                for aa in 0..r.p {
                    kmat[aa + r.p * bb + m * i] += key.core[aa + big.p * (bb + big.t * l)] * u;
                }
            }
        }
    }
    // F = K C^+ = K C^T (C C^T)^{-1}: solve (C C^T) F^T = C K^T.
    let dc = d + 1;
    let cm = |row: usize, i: usize| c_entry(truth, row, i);
    let cct = c_gram(truth);
    let mut f = vec![0.0; m * dc]; // m x dc column-major
    for e in 0..m {
        let rhs: Vec<f64> = (0..dc)
            .map(|x| (0..s).map(|i| cm(x, i) * kmat[e + m * i]).sum())
            .collect();
        let row = solve(&cct, &rhs, dc);
        for x in 0..dc {
            f[e + m * x] = row[x];
        }
    }
    // K(c) = F [c;1] + sum_i b_i (K_i - F [c_i;1]).
    let cvec: Vec<f64> = cs.iter().copied().chain(std::iter::once(1.0)).collect();
    let mut kc = vec![0.0; m];
    for e in 0..m {
        let mut v: f64 = (0..dc).map(|x| f[e + m * x] * cvec[x]).sum();
        for i in 0..s {
            let trend_i: f64 = (0..dc).map(|x| f[e + m * x] * cm(x, i)).sum();
            v += b[i] * (kmat[e + m * i] - trend_i);
        }
        kc[e] = v;
    }
    // w_T (eq. 5) and pose = U_P K(c) w_T.
    let ph = phase.clamp(0.0, (t - 1) as f64);
    let i0 = (ph.floor() as usize).min(t - 2);
    let al = ph - i0 as f64;
    let wt: Vec<f64> = (0..r.t)
        .map(|bb| (1.0 - al) * key.u_t[i0 + t * bb] + al * key.u_t[i0 + 1 + t * bb])
        .collect();
    (0..p)
        .map(|row| {
            let mut v = 0.0;
            for bb in 0..r.t {
                for aa in 0..r.p {
                    v += key.u_p[row + p * aa] * kc[aa + r.p * bb] * wt[bb];
                }
            }
            v
        })
        .collect()
}

/// Largest absolute difference between `got` and `want` relative to `max |want|`.
pub fn rel_err(got: &[f32], want: &[f64]) -> f64 {
    let scale = want.iter().fold(0.0f64, |a, &b| a.max(b.abs())).max(1e-12);
    got.iter()
        .zip(want)
        .map(|(&g, &w)| (g as f64 - w).abs())
        .fold(0.0, f64::max)
        / scale
}
