//! A precomputed projection of the kriging weights for hot paths: `L b(c)` in `R (S+1)`
//! multiply-adds plus S variogram evaluations.

use faer::MatRef;
use serde::{Deserialize, Serialize};

use crate::error::KrigingError;
use crate::kriging::{Kriging, check_query, check_result, variogram_column};
use crate::scaling::ParamScaling;
use crate::variogram::Variogram;

/// `Q = L A^-1[:S, :]` (R x (S+1)) for a caller's fixed linear map `L` (R x S), so that
/// `L b(c) = Q [gamma(c); 1]` (appendix A weights projected; DESIGN: `Q = U_S^t A^-1[:S, :]`).
///
/// Everything is stored in plain vectors so that a runtime can copy it into its own (f32) arrays:
/// [`ProjectedQuery::matrix`] is **row-major** (row r holds `Q[r, 0..=S]`, the last entry of each row
/// multiplies the constant 1), [`ProjectedQuery::scaled_params`] is row-major S x d.
///
/// ```
/// use kriging::faer::Mat;
/// use kriging::{Kriging, KrigingConfig, ModelChoice, ProjectedQuery, VariogramModel};
///
/// let c = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [0.4, 0.7], [0.8, 0.2]];
/// let params = Mat::from_fn(6, 2, |i, k| c[i][k]);
/// let values = Mat::from_fn(6, 1, |i, _| c[i][0] * c[i][0] + c[i][1]);
/// let config = KrigingConfig {
///     model: ModelChoice::Fixed(VariogramModel::Gaussian),
///     ..KrigingConfig::default() // regression kriging, standardised parameters
/// };
/// let k = Kriging::fit(params.as_ref(), values.as_ref(), &config)?;
/// // L (R x S = 2 x 6): e.g. two basis vectors the values were projected on.
/// let l = Mat::from_fn(2, 6, |r, i| if r == 0 { 1.0 } else { i as f64 - 2.5 });
/// let pq = ProjectedQuery::new(&k, l.as_ref())?;
/// let (mut scratch, mut out) = (vec![0.0; 7], [0.0; 2]);
/// pq.query(&[0.3, 0.6], &mut scratch, &mut out)?;
/// // The same as L times the weights b(c), without forming them.
/// let mut b = [0.0; 6];
/// k.weights(&[0.3, 0.6], &mut b)?;
/// for r in 0..2 {
///     let lb: f64 = (0..6).map(|i| l[(r, i)] * b[i]).sum();
///     assert!((out[r] - lb).abs() < 1e-10);
/// }
/// assert!((out[0] - 1.0).abs() < 1e-10); // the weights sum to one
/// # Ok::<(), kriging::KrigingError>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ProjectedQuery {
    rows: usize,
    samples: usize,
    matrix: Vec<f64>,
    scaled_params: Vec<f64>,
    variogram: Variogram,
    scaling: ParamScaling,
}

impl ProjectedQuery {
    /// Precomputes `L A^-1[:S, :]` for `l` (R x S) and copies the scaled sample parameters, the
    /// variogram and the scaling of `kriging`.
    pub fn new(kriging: &Kriging, l: MatRef<'_, f64>) -> Result<Self, KrigingError> {
        let s = kriging.n_samples();
        if l.ncols() != s {
            return Err(KrigingError::ShapeMismatch {
                what: "projection columns vs samples",
                expected: s,
                got: l.ncols(),
            });
        }
        crate::check_finite("projection", l)?;
        let ainv = kriging.system_inverse();
        let q = crate::linalg::matmul(l, ainv.subrows(0, s));
        let rows = l.nrows();
        let mut matrix = Vec::with_capacity(rows * (s + 1));
        for r in 0..rows {
            for j in 0..=s {
                matrix.push(q[(r, j)]);
            }
        }
        let p = kriging.scaled_params();
        let mut scaled_params = Vec::with_capacity(s * p.ncols());
        for i in 0..s {
            for k in 0..p.ncols() {
                scaled_params.push(p[(i, k)]);
            }
        }
        Ok(ProjectedQuery {
            rows,
            samples: s,
            matrix,
            scaled_params,
            variogram: *kriging.variogram(),
            scaling: kriging.scaling().clone(),
        })
    }

    /// `out = L b(c) = Q [gamma(c); 1]`. `gamma_scratch` must hold S+1 entries (it receives
    /// `[gamma(c); 1]`), `out` R entries. No allocation.
    ///
    /// Errors: a query of the wrong dimension or not finite, buffers of the wrong length, and a
    /// result that is not finite ([`KrigingError::Overflow`], a query so far from the samples that
    /// the variogram overflows; `out` then holds what was computed).
    pub fn query(
        &self,
        c: &[f64],
        gamma_scratch: &mut [f64],
        out: &mut [f64],
    ) -> Result<(), KrigingError> {
        let s = self.samples;
        check_query(c, self.scaling.dims(), out.len(), self.rows)?;
        if gamma_scratch.len() != s + 1 {
            return Err(KrigingError::ShapeMismatch {
                what: "gamma scratch length (S + 1)",
                expected: s + 1,
                got: gamma_scratch.len(),
            });
        }
        variogram_column(
            &self.variogram,
            &self.scaling,
            &self.scaled_params,
            c,
            &mut gamma_scratch[..s],
        );
        gamma_scratch[s] = 1.0;
        for (o, row) in out.iter_mut().zip(self.matrix.chunks_exact(s + 1)) {
            *o = dot(row, gamma_scratch);
        }
        check_result("the projected weights", out)
    }

    /// Number of rows R of `L`.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Number of samples S.
    pub fn n_samples(&self) -> usize {
        self.samples
    }

    /// `Q = L A^-1[:S, :]`, row-major R x (S+1).
    pub fn matrix(&self) -> &[f64] {
        &self.matrix
    }

    /// The scaled sample parameters, row-major S x d.
    pub fn scaled_params(&self) -> &[f64] {
        &self.scaled_params
    }

    /// The variogram `gamma`.
    pub fn variogram(&self) -> &Variogram {
        &self.variogram
    }

    /// The parameter scaling applied to a query before distances are taken.
    pub fn scaling(&self) -> &ParamScaling {
        &self.scaling
    }
}

/// Dot product with four interleaved partial sums (vectorisable; fixed order, so deterministic).
#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    debug_assert_eq!(a.len(), b.len());
    let mut acc = [0.0f64; 4];
    let split = a.len() / 4 * 4;
    let (a4, ar) = a.split_at(split);
    let (b4, br) = b.split_at(split);
    for (x, y) in a4.chunks_exact(4).zip(b4.chunks_exact(4)) {
        for k in 0..4 {
            acc[k] += x[k] * y[k];
        }
    }
    let mut s = (acc[0] + acc[1]) + (acc[2] + acc[3]);
    for (x, y) in ar.iter().zip(br) {
        s += x * y;
    }
    s
}
