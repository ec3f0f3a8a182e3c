//! Online truncation of the full key tensor (the "simple truncation" of the paper's Figure 4).
//!
//! Only the full (level-0) key `(Z, U_P, U_T, Q, V)` is stored. Per clip at accuracy ranks
//! `(r_P, r_T, r_S)` the kernel follows the four steps of the paper's Appendix B for the 3-mode product
//! with the kriging weights:
//! 1. unfold the *full* core along the sample mode, `Z_(3)` (`R_S x R_P R_T`), a copy whose cost is
//!    `R_P R_T R_S` whatever the truncation;
//! 2. take the sub-matrix of its first `r_S` rows and of the columns with `i < r_P`, `j < r_T`;
//! 3. multiply the kriging weights by it, `K(c) = w^T Z_(3)[:r_S, sub]` (eq. 8);
//! 4. fold the result into the `r_P x r_T` matrix `K(c)`.
//!
//! The rest is the runtime model's kernel ([`lod_policy::LodModel::build_kernel`]): the weights
//! `w = U_S^T b + V ([c;1] - C b)` from the first `r_S` rows of `Q` and `V` (computed by the runtime,
//! [`lod_policy::LodModel::kriging_weights_reference`]), `G(c) = U_P[:P', :r_P] K(c)`
//! and the clip's time table; per frame `pose = G w_T` (eq. 4-5). Everything writes into buffers
//! allocated once by [`OnlineTruncation::new`].

use lod_policy::TimeTable;
use lod_policy::{KernelScratch, LodModel, Ranks, TIME_ROW};

/// The online-truncation kernel over key 0 of a model, with its preallocated buffers.
#[derive(Debug, Clone)]
pub struct OnlineTruncation<'m> {
    model: &'m LodModel,
    /// Mode-3 unfolding of the full core, `R_S x (R_P R_T)` column-major.
    unfolded: Vec<f32>,
    /// The sub-matrix `r_S x (r_P r_T)` column-major.
    sub: Vec<f32>,
    /// The runtime's working memory for the kriging weights.
    scratch: KernelScratch,
    k: Vec<f32>,
    /// `G(c)`, `rows x r_T` column-major.
    g: Vec<f32>,
    ranks: Ranks,
    rows: usize,
    times: TimeTable,
}

impl<'m> OnlineTruncation<'m> {
    /// Buffers for truncations of `model`'s key 0.
    pub fn new(model: &'m LodModel) -> OnlineTruncation<'m> {
        let r = model.keys()[0].ranks;
        OnlineTruncation {
            model,
            unfolded: vec![0.0; r.core_len()],
            sub: vec![0.0; r.core_len()],
            scratch: KernelScratch::new(model),
            k: vec![0.0; r.p * r.t],
            g: vec![0.0; model.p() * r.t],
            ranks: r,
            rows: model.p(),
            times: TimeTable::with_capacity(model.t()),
        }
    }

    /// `G(c)` of the last kernel, `rows x r_T` column-major.
    pub fn g(&self) -> &[f32] {
        &self.g[..self.rows * self.ranks.t]
    }

    /// Playback duration of the last kernel (seconds).
    pub fn duration(&self) -> f64 {
        self.times.duration()
    }

    /// Builds the kernel for raw `controls` (length `d`, clamped to the data range) at `ranks` (each at
    /// most key 0's, clamped) for the first `rows` pose rows (at least 7, at most `P`).
    pub fn build(&mut self, controls: &lod_policy::Controls, ranks: Ranks, rows: usize) {
        let m = self.model;
        let key = &m.keys()[0];
        let big = key.ranks;
        let r = Ranks::new(
            ranks.p.clamp(1, big.p),
            ranks.t.clamp(1, big.t),
            ranks.s.clamp(1, big.s),
        );
        let rows = rows.clamp(lod_policy::ALWAYS_ROWS, m.p());
        let (p, t) = (m.p(), m.t());

        // Appendix B, step 1: unfold the full core along the sample mode (l fastest).
        let plane = big.p * big.t;
        for (l, slab) in key.core.chunks_exact(plane).enumerate() {
            for (col, &z) in slab.iter().enumerate() {
                self.unfolded[l + big.s * col] = z;
            }
        }
        // Step 2: the sub-matrix of rows l < r_S and columns (i, j), i < r_P, j < r_T.
        let mut n = 0;
        for j in 0..r.t {
            for i in 0..r.p {
                let col = i + big.p * j;
                self.sub[n..n + r.s].copy_from_slice(&self.unfolded[big.s * col..][..r.s]);
                n += r.s;
            }
        }

        // Kriging weights of key 0's first r_S sample components: the runtime's own (its reference
        // summation order, the runtime kernel's steps 1-4).
        let w = m
            .kriging_weights_reference(&controls.to_array(), 0, r.s, &mut self.scratch)
            .expect("online truncation: controls of the model's length, finite");

        // Steps 3-4: K(c) = w^T Z_(3)[:r_S, sub], folded to r_P x r_T (column order (i, j) = i + r_P j).
        for (kv, col) in self.k[..r.p * r.t]
            .iter_mut()
            .zip(self.sub[..r.s * r.p * r.t].chunks_exact(r.s))
        {
            *kv = col.iter().zip(w).map(|(&z, &wl)| z * wl).sum();
        }

        // G(c) = U_P[:rows, :r_P] K(c).
        let g = &mut self.g[..rows * r.t];
        g.fill(0.0);
        for b in 0..r.t {
            let gcol = &mut g[rows * b..][..rows];
            for a in 0..r.p {
                let kab = self.k[a + r.p * b];
                let ucol = &key.u_p[p * a..][..rows];
                for (gv, &u) in gcol.iter_mut().zip(ucol) {
                    *gv += kab * u;
                }
            }
        }
        // Time table from the time-increment row.
        let g = &*g;
        let inv_scale = 1.0 / m.parts().time_scale;
        self.times.fill_from_iter((0..t).map(|j| {
            inv_scale
                * (0..r.t)
                    .map(|b| f64::from(g[TIME_ROW + rows * b]) * f64::from(key.u_t[j + t * b]))
                    .sum::<f64>()
        }));
        self.ranks = r;
        self.rows = rows;
    }

    /// The pose at `phase` (aligned frame, clamped to `[0, T - 1]`) of the last kernel into `out`
    /// (length `P`): rows `0..P'` are `G w_T`, the rest the mean pose.
    pub fn pose(&self, phase: f32, out: &mut [f32]) {
        let m = self.model;
        let key = &m.keys()[0];
        let t = m.t();
        let rows = self.rows.min(out.len());
        let ph = phase.clamp(0.0, (t - 1) as f32);
        let i = (ph.floor() as usize).min(t.saturating_sub(2));
        let i1 = (i + 1).min(t - 1);
        let a = ph - i as f32;
        let (head, tail) = out.split_at_mut(rows);
        head.fill(0.0);
        for b in 0..self.ranks.t {
            let wb = (1.0 - a) * key.u_t[i + t * b] + a * key.u_t[i1 + t * b];
            let gcol = &self.g[self.rows * b..][..rows];
            for (o, &gv) in head.iter_mut().zip(gcol) {
                *o += wb * gv;
            }
        }
        let n = tail.len();
        tail.copy_from_slice(&m.mean_pose()[rows..rows + n]);
    }
}
