//! Equivalent sample weights of universal kriging at new controls (paper eq. 8), shared by the baseline
//! clip sources that blend per-sample data directly ([`crate::naive`], [`crate::pca`]).
//!
//! Universal kriging predicts `sum_i l_i(c) M_i` with `l(c) = b(c) + C^+ ([c'; 1] - C b(c))`, where
//! `b(c)` are the kriging weights of the full `(S+1) x (S+1)` system, `C` the `(d+1) x S` matrix of the
//! scaled sample controls with a row of ones, `C^+` its pseudo-inverse and `c'` the scaled controls.
//! Cost per evaluation: `O(S^2)` for `b(c)`, `O(S (d+1))` for the trend correction.

use faer::Mat;
use kriging::Kriging;

/// Largest control dimension handled (the project uses `d = 4`).
const MAX_D: usize = 7;

/// `C` and `C^+` of a kriging fit, row-major, ready for [`SampleWeights::compute`].
#[derive(Debug, Clone)]
pub(crate) struct SampleWeights {
    /// `C^+`, `S x (d + 1)` row-major.
    c_pinv: Vec<f64>,
    /// `C`, `(d + 1) x S` row-major.
    c: Vec<f64>,
    s: usize,
    d: usize,
}

fn row_major(m: &Mat<f64>) -> Vec<f64> {
    (0..m.nrows())
        .flat_map(|i| (0..m.ncols()).map(move |j| (i, j)))
        .map(|(i, j)| m[(i, j)])
        .collect()
}

impl SampleWeights {
    /// The matrices of `kriging` (`S` samples, `d` control dimensions).
    pub(crate) fn new(kriging: &Kriging) -> SampleWeights {
        let c = kriging.augmented_params();
        let cp = kriging.augmented_pinv();
        debug_assert_eq!(c.nrows(), cp.ncols());
        debug_assert_eq!(c.ncols(), cp.nrows());
        SampleWeights {
            s: c.ncols(),
            d: c.nrows().saturating_sub(1),
            c_pinv: row_major(&cp),
            c: row_major(&c),
        }
    }

    /// Writes `l(c) = b(c) + C^+ ([c'; 1] - C b(c))` (eq. 8) into `l`, using `b` (length `S`) as
    /// scratch for the kriging weights. When the kriging system cannot be solved at `c` (non-finite
    /// controls) `b` falls back to the uniform weights `1 / S`. Allocation-free.
    pub(crate) fn compute(&self, kriging: &Kriging, c: &[f64; 4], b: &mut [f64], l: &mut [f64]) {
        let (s, d) = (self.s, self.d);
        debug_assert!(b.len() == s && l.len() == s && d <= MAX_D && d <= c.len());
        if kriging.weights(c, b).is_err() {
            b.fill(1.0 / s as f64);
        }
        // z = [c'; 1] - C b with c' the scaled controls; l = b + C^+ z.
        let scaling = kriging.scaling();
        let mut z = [0.0f64; MAX_D + 1];
        for (k, zk) in z.iter_mut().enumerate().take(d + 1) {
            let ck = if k < d {
                (c[k] - scaling.offset[k]) * scaling.scale[k]
            } else {
                1.0
            };
            let cb: f64 = (0..s).map(|i| self.c[k * s + i] * b[i]).sum();
            *zk = ck - cb;
        }
        for (i, li) in l.iter_mut().enumerate() {
            let corr: f64 = (0..=d).map(|k| self.c_pinv[i * (d + 1) + k] * z[k]).sum();
            *li = b[i] + corr;
        }
    }
}

/// A crowd's controls as the `(dx, dz, turn, height)` the kriging takes.
pub(crate) fn control_vector(controls: &crowd_sim::Controls) -> [f64; 4] {
    [
        f64::from(controls.dx),
        f64::from(controls.dz),
        f64::from(controls.turn),
        f64::from(controls.height),
    ]
}
