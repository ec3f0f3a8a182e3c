//! Universal kriging of per-sample values at new controls (paper eq. 8), shared by the baseline clip
//! sources that blend per-sample data directly ([`crate::naive`], [`crate::pca`]).
//!
//! Universal kriging predicts `sum_i l_i(c) M_i` with `l(c) = b(c) + C^+ ([c'; 1] - C b(c))`, where
//! `b(c)` are the kriging weights of the full `(S+1) x (S+1)` system, `C` the `(d+1) x S` matrix of
//! the scaled sample controls with a row of ones, `C^+` its pseudo-inverse and `c'` the scaled controls.
//! [`DualBlend`] evaluates it in the dual form, `O(S D)` per query for `D` values per sample, without
//! forming `b(c)` (`O(S^2)`).

use faer::Mat;
use kriging::Kriging;

/// Largest control dimension handled: the four controls and up to [`lod_policy::MAX_STYLES`]
/// styles.
const MAX_D: usize = lod_policy::CONTROL_VALUES;

/// Universal kriging of per-sample values in its dual form (paper eq. 8 rearranged):
/// `sum_i l_i(c) v_i = Q [gamma(c); 1] + F [c'; 1]`, with `F = V^T C^+` (the trend) and
/// `Q = V^T (I - C^+ C) A^-1[:S, :]` (`D x (S + 1)`, precomputed by [`kriging::ProjectedQuery`]),
/// `V` the `S x D` sample values. A query costs `S` variogram evaluations and `D' (S + d + 2)`
/// multiply-adds for the first `D'` outputs: `O(S D)` instead of the `O(S^2)` kriging weights
/// followed by the `O(S D)` blend. Outputs are ordered by the caller so that the values a
/// cheaper detail needs are a prefix.
#[derive(Debug, Clone)]
pub(crate) struct DualBlend {
    outputs: usize,
    samples: usize,
    /// `Q^T`, `(S + 1) x D` row-major (column `j` of `Q` contiguous), f32.
    q_t: Vec<f32>,
    /// `F`, `D x (d + 1)` row-major.
    trend: Vec<f64>,
    /// Scaled sample controls, `S x dims` row-major.
    params: Vec<f64>,
    scaling: kriging::ParamScaling,
    variogram: kriging::Variogram,
    /// `d`: trend dimensions (the last trend column multiplies 1).
    d: usize,
}

thread_local! {
    /// `[gamma(c); 1]` and the f64 accumulators of [`DualBlend::eval`], per thread.
    static DUAL_SCRATCH: std::cell::RefCell<(Vec<f64>, Vec<f64>)> =
        const { std::cell::RefCell::new((Vec::new(), Vec::new())) };
}

impl DualBlend {
    /// The dual form of `kriging` for `values` (`S x D`, one row per sample).
    pub(crate) fn new(
        kriging: &Kriging,
        values: &Mat<f64>,
    ) -> Result<DualBlend, kriging::KrigingError> {
        let s = kriging.n_samples();
        let c = kriging.augmented_params();
        let cp = kriging.augmented_pinv();
        let vt = values.transpose().to_owned();
        // F = V^T C^+ (D x (d+1)); R^T = V^T - F C (D x S).
        let f = &vt * &cp;
        let rt = &vt - &f * &c;
        let pq = kriging::ProjectedQuery::new(kriging, rt.as_ref())?;
        let outputs = values.ncols();
        let m = pq.matrix();
        let mut q_t = vec![0.0f32; (s + 1) * outputs];
        for (o, row) in m.chunks_exact(s + 1).enumerate() {
            for (j, &v) in row.iter().enumerate() {
                q_t[j * outputs + o] = v as f32;
            }
        }
        let d = c.nrows().saturating_sub(1);
        let trend = (0..outputs)
            .flat_map(|o| (0..=d).map(move |k| (o, k)))
            .map(|(o, k)| f[(o, k)])
            .collect();
        let scaling = pq.scaling();
        Ok(DualBlend {
            outputs,
            samples: s,
            q_t,
            trend,
            params: pq.scaled_params().to_vec(),
            scaling: scaling.clone(),
            variogram: *pq.variogram(),
            d,
        })
    }

    /// The first `out.len()` outputs (at most `D`) at raw controls `c` (the kriging's `d` values,
    /// [`lod_policy::LodModel::control_vector`]). Allocation-free once the
    /// thread's scratch has grown. Runs an AVX2 build of the same operations where the CPU has it
    /// (no fused multiply-add, so the same bits), as the model's kernels do
    /// ([`lod_policy::LodModel::build_kernel`]): the baselines get the same instruction set.
    pub(crate) fn eval(&self, c: &[f64], out: &mut [f32]) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2 (checked just above).
            unsafe { self.eval_avx2(c, out) };
            return;
        }
        self.eval_body(c, out);
    }

    /// [`DualBlend::eval`] by the baseline build (x86-64 SSE2) whatever the CPU.
    #[cfg(test)]
    pub(crate) fn eval_baseline(&self, c: &[f64], out: &mut [f32]) {
        self.eval_body(c, out);
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn eval_avx2(&self, c: &[f64], out: &mut [f32]) {
        self.eval_body(c, out);
    }

    #[inline(always)]
    fn eval_body(&self, c: &[f64], out: &mut [f32]) {
        let n = out.len().min(self.outputs);
        let s = self.samples;
        let dims = self.scaling.offset.len().min(c.len());
        DUAL_SCRATCH.with(|cell| {
            let mut guard = cell.borrow_mut();
            let (x, acc) = &mut *guard;
            x.resize(s + 1, 0.0);
            acc.clear();
            acc.resize(n, 0.0);
            let mut z = [0.0f64; MAX_D + 1];
            for k in 0..dims {
                z[k] = (c[k] - self.scaling.offset[k]) * self.scaling.scale[k];
            }
            // gamma(c), as the kriging crate evaluates it for every query.
            kriging::variogram_column(
                &self.variogram,
                &self.scaling,
                &self.params,
                &c[..dims],
                &mut x[..s],
            );
            x[s] = 1.0;
            for (j, &xj) in x.iter().enumerate() {
                let col = &self.q_t[j * self.outputs..][..n];
                for (a, &q) in acc.iter_mut().zip(col) {
                    *a += f64::from(q) * xj;
                }
            }
            // Trend: F [c'; 1] with c' the scaled controls of the kept dimensions.
            let d = self.d.min(MAX_D);
            let mut zt = [0.0f64; MAX_D + 1];
            zt[..d].copy_from_slice(&z[..d]);
            zt[d] = 1.0;
            for (o, (v, a)) in out[..n].iter_mut().zip(acc.iter()).enumerate() {
                let f = &self.trend[o * (self.d + 1)..][..=d];
                let t: f64 = f.iter().zip(&zt[..=d]).map(|(fk, zk)| fk * zk).sum();
                *v = (a + t) as f32;
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The baselines' AVX2 build gives the same bits as their baseline build (prefixes of every
    /// length, controls inside and beyond the data).
    #[test]
    fn avx2_and_baseline_blends_give_the_same_bits() {
        let (s, d, outputs) = (150usize, 4usize, 70usize);
        let mut rng = lod_policy::SplitMix64::new(0x2545_f491);
        let mut next = move || rng.next_f64();
        // The last control is constant (as the Bandai height is), so it is dropped.
        let params = Mat::from_fn(s, d, |_, k| if k == 3 { 1.3 } else { 2.0 * next() - 1.0 });
        let values = Mat::from_fn(s, outputs, |i, o| {
            (params[(i, 0)] * (o as f64 + 1.0)).sin() + params[(i, 1)] * 0.3 + 0.1 * next()
        });
        let kriging = Kriging::fit(params.as_ref(), values.as_ref(), &Default::default())
            .expect("kriging fits");
        let blend = DualBlend::new(&kriging, &values).expect("dual form");
        for q in 0..20 {
            let c = [
                2.4 * next() - 1.2,
                2.4 * next() - 1.2,
                2.0 * next() - 1.0,
                1.3,
            ];
            for n in [outputs, 38, 7, 1] {
                let (mut a, mut b) = (vec![0.0f32; n], vec![0.0f32; n]);
                blend.eval(&c, &mut a);
                blend.eval_baseline(&c, &mut b);
                let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&a), bits(&b), "query {q}, {n} outputs");
                assert!(a.iter().all(|v| v.is_finite()));
            }
        }
    }
}
