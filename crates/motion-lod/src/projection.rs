//! Offline helpers that turn a decomposition and a kriging system into the runtime's parts
//! (`lod_policy`): the kriging projection `Q`, the trend projection `V` (section 3.3), a scaled
//! control space, and the fitted variogram in the runtime's plain form.
//!
//! These run once per model in f64 and allocate freely; the only linear algebra needed is the
//! pseudo-inverse of the small `(d + 1) x (d + 1)` matrix `C C^T`, taken from the `kriging` crate so
//! that a constant (zero-scaled) control dimension is handled exactly as the kriging trend handles it.

use lod_policy::{
    ControlSpace, KeyTensor, ModelError, Ranks, Variogram, VariogramError, VariogramModel,
};

/// Why a fitted variogram cannot go into a runtime model.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum VariogramConversionError {
    /// The runtime does not evaluate this model kind.
    #[error(
        "the runtime cannot evaluate a {model} variogram (it evaluates linear, power, spherical, \
         exponential and gaussian ones); fit one of those"
    )]
    Unsupported {
        /// The fitted model's name.
        model: &'static str,
    },
    /// The parameters are outside the runtime's domain for the model.
    #[error(transparent)]
    Invalid(#[from] VariogramError),
}

/// The runtime's form of a fitted variogram: the same model kind and parameters (the runtime
/// evaluates it to the same bits, and a model file stores the same bytes). Matérn and cardinal
/// sine (hole-effect) variograms are refused: the runtime does not evaluate them.
pub fn runtime_variogram(v: &kriging::Variogram) -> Result<Variogram, VariogramConversionError> {
    let model = match v.model {
        kriging::VariogramModel::Linear => VariogramModel::Linear,
        kriging::VariogramModel::Power => VariogramModel::Power,
        kriging::VariogramModel::Spherical => VariogramModel::Spherical,
        kriging::VariogramModel::Exponential => VariogramModel::Exponential,
        kriging::VariogramModel::Gaussian => VariogramModel::Gaussian,
        other @ (kriging::VariogramModel::Matern | kriging::VariogramModel::CardinalSine) => {
            return Err(VariogramConversionError::Unsupported {
                model: other.name(),
            });
        }
    };
    let out = Variogram {
        model,
        nugget: v.nugget,
        sill: v.sill,
        range: v.range,
        exponent: v.exponent,
    };
    out.validate()?;
    Ok(out)
}

/// One key's ordered Tucker model in f64 (column-major, see [`KeyTensor`] for layouts).
#[derive(Debug, Clone, Copy)]
pub struct KeyFactors<'a> {
    /// Ranks `(R_P, R_T, R_S)`.
    pub ranks: Ranks,
    /// Core `Z`, `R_P x R_T x R_S`.
    pub core: &'a [f64],
    /// `U_P`, `P x R_P`.
    pub u_p: &'a [f64],
    /// `U_T`, `T x R_T`.
    pub u_t: &'a [f64],
    /// `U_S`, `S x R_S`.
    pub u_s: &'a [f64],
}

fn len_check(what: &str, v: &[f64], expected: usize) -> Result<(), ModelError> {
    if v.len() != expected {
        return Err(ModelError::Length {
            what: what.to_string(),
            expected,
            found: v.len(),
        });
    }
    if let Some(index) = v.iter().position(|x| !x.is_finite()) {
        return Err(ModelError::NonFinite {
            what: what.to_string(),
            index,
        });
    }
    Ok(())
}

fn to_f32(v: &[f64]) -> Vec<f32> {
    v.iter().map(|&x| x as f32).collect()
}

/// Moore-Penrose pseudo-inverse of a small symmetric positive semi-definite `n x n` matrix
/// (column-major), by [`kriging::sym_pinv`] so that the trend here is the kriging crate's trend
/// (same eigenvalue tolerance, [`kriging::PINV_RTOL`]).
fn pinv_symmetric(m: &[f64], n: usize) -> Vec<f64> {
    let (p, _) = kriging::sym_pinv(faer::MatRef::from_column_major_slice(m, n, n));
    (0..n)
        .flat_map(|j| (0..n).map(move |i| (i, j)))
        .map(|(i, j)| p[(i, j)])
        .collect()
}

/// Builds a runtime key tensor from an f64 decomposition and the kriging system `kriging` (fitted
/// on the same `S` samples, its scaled controls `C`).
///
/// Computes `Q = U_S^T A^{-1}[:S, :]` ([`kriging::Kriging::project_rows`], `A = [Gamma 1; 1^T 0]`
/// of appendix A) and `V = U_S^T C^+` with `C^+ = C^T (C C^T)^+` (eq. 8's `F = K C^+` then equals
/// `Z_(12) V`), and stores everything in f32.
pub fn key_tensor(
    f: &KeyFactors<'_>,
    p: usize,
    t: usize,
    kriging: &kriging::Kriging,
) -> Result<KeyTensor, ModelError> {
    let r = f.ranks;
    if r.s == 0 {
        return Err(ModelError::ZeroSize { what: "R_S".into() });
    }
    let s = f.u_s.len() / r.s;
    if s == 0 {
        return Err(ModelError::ZeroSize { what: "S".into() });
    }
    len_check("u_s", f.u_s, s * r.s)?;
    len_check("core", f.core, r.core_len())?;
    len_check("u_p", f.u_p, p * r.p)?;
    len_check("u_t", f.u_t, t * r.t)?;
    if kriging.n_samples() != s {
        return Err(ModelError::Length {
            what: "kriging samples (S)".into(),
            expected: s,
            found: kriging.n_samples(),
        });
    }
    // C ((d + 1) x S): column i is [c_i; 1].
    let c = kriging.augmented_params();
    let dc = c.nrows();
    let cmat = |m: usize, i: usize| c[(m, i)];
    let q = projection_rows(
        kriging,
        faer::MatRef::from_column_major_slice(f.u_s, s, r.s),
    )?;

    // M = C C^T, B = C U_S ((d+1) x R_S); V = B^T M^+.
    let mut mm = vec![0.0f64; dc * dc];
    for a in 0..dc {
        for b in 0..dc {
            mm[a + dc * b] = (0..s).map(|i| cmat(a, i) * cmat(b, i)).sum();
        }
    }
    let mp = pinv_symmetric(&mm, dc);
    let mut bmat = vec![0.0f64; dc * r.s];
    for l in 0..r.s {
        for m in 0..dc {
            bmat[m + dc * l] = (0..s).map(|i| cmat(m, i) * f.u_s[i + s * l]).sum();
        }
    }
    let mut v = vec![0.0f64; r.s * dc];
    for l in 0..r.s {
        for m in 0..dc {
            v[l + r.s * m] = (0..dc).map(|n| bmat[n + dc * l] * mp[n + dc * m]).sum();
        }
    }
    Ok(KeyTensor {
        ranks: r,
        core: to_f32(f.core),
        u_p: to_f32(f.u_p),
        u_t: to_f32(f.u_t),
        projection: q,
        trend: to_f32(&v),
    })
}

/// Builds a control space from raw sample controls (`S x d` column-major), a per-dimension
/// `offset` and `scale` (scaled `c'_k = (c_k - offset_k) * scale_k`), and the variogram.
/// The clamping bounds are the raw per-dimension minimum and maximum.
pub fn control_space(
    variogram: Variogram,
    raw: &[f32],
    s: usize,
    offset: Vec<f32>,
    scale: Vec<f32>,
) -> Result<ControlSpace, ModelError> {
    let d = offset.len();
    if s == 0 || d == 0 {
        return Err(ModelError::ZeroSize {
            what: if s == 0 { "S" } else { "d" }.into(),
        });
    }
    if raw.len() != s * d {
        return Err(ModelError::Length {
            what: "raw controls".into(),
            expected: s * d,
            found: raw.len(),
        });
    }
    if scale.len() != d {
        return Err(ModelError::Length {
            what: "controls scale".into(),
            expected: d,
            found: scale.len(),
        });
    }
    if let Some(index) = raw.iter().position(|x| !x.is_finite()) {
        return Err(ModelError::NonFinite {
            what: "raw controls".into(),
            index,
        });
    }
    let mut min = vec![f32::INFINITY; d];
    let mut max = vec![f32::NEG_INFINITY; d];
    let mut samples = vec![0.0f32; s * d];
    for k in 0..d {
        for i in 0..s {
            let v = raw[i + s * k];
            min[k] = min[k].min(v);
            max[k] = max[k].max(v);
            samples[i + s * k] = (v - offset[k]) * scale[k];
        }
    }
    let implied = implied_controls(raw, s, &scale, &min, &max);
    Ok(ControlSpace {
        variogram,
        offset,
        scale,
        samples,
        min,
        max,
        projection: Vec::new(),
        implied,
    })
}

/// Sets [`ControlSpace::projection`] `= C A^{-1}[:S, :]` from the kriging system over the same
/// samples ([`kriging::Kriging::project_rows`] of `C^T`, `C` its scaled controls with a row of
/// ones).
pub fn with_projection(
    mut space: ControlSpace,
    kriging: &kriging::Kriging,
) -> Result<ControlSpace, ModelError> {
    let d = space.offset.len();
    let s = space.samples.len() / d.max(1);
    let scaled = kriging.scaled_params();
    if kriging.n_samples() != s || scaled.ncols() != d {
        return Err(ModelError::Length {
            what: "kriging samples x controls (S x d)".into(),
            expected: s * d,
            found: kriging.n_samples() * scaled.ncols(),
        });
    }
    space.projection = projection_rows(kriging, kriging.augmented_params().transpose())?;
    Ok(space)
}

/// [`kriging::Kriging::project_rows`] of `u` in f32, column-major (`m x (S + 1)`).
fn projection_rows(
    kriging: &kriging::Kriging,
    u: faer::MatRef<'_, f64>,
) -> Result<Vec<f32>, ModelError> {
    let q = kriging.project_rows(u).map_err(|e| ModelError::Length {
        what: format!("kriging projection ({e})"),
        expected: kriging.n_samples(),
        found: u.nrows(),
    })?;
    let (m, n) = q.shape();
    let out: Vec<f32> = (0..n)
        .flat_map(|j| (0..m).map(move |l| (l, j)))
        .map(|(l, j)| q[(l, j)] as f32)
        .collect();
    if let Some(index) = out.iter().position(|x| !x.is_finite()) {
        return Err(ModelError::NonFinite {
            what: "kriging projection".into(),
            index,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::pinv_symmetric;

    #[test]
    fn pinv_of_singular_symmetric_matrix_satisfies_penrose() {
        // Rank-2 3x3 PSD matrix: M = B B^T with B = [[1,2],[0,1],[1,3]].
        let b = [[1.0, 2.0], [0.0, 1.0], [1.0, 3.0]];
        let mut m = vec![0.0; 9];
        for i in 0..3 {
            for j in 0..3 {
                m[i + 3 * j] = b[i][0] * b[j][0] + b[i][1] * b[j][1];
            }
        }
        let mp = pinv_symmetric(&m, 3);
        let mul = |x: &[f64], y: &[f64]| {
            let mut z = vec![0.0; 9];
            for i in 0..3 {
                for j in 0..3 {
                    z[i + 3 * j] = (0..3).map(|k| x[i + 3 * k] * y[k + 3 * j]).sum();
                }
            }
            z
        };
        let mmpm = mul(&mul(&m, &mp), &m);
        let mpmmp = mul(&mul(&mp, &m), &mp);
        for i in 0..9 {
            assert!((mmpm[i] - m[i]).abs() < 1e-9, "M M+ M != M at {i}");
            assert!((mpmmp[i] - mp[i]).abs() < 1e-9, "M+ M M+ != M+ at {i}");
        }
    }
}

/// [`ControlSpace::implied`] (the field): per dimension `k`, `d + 1` coefficients. A kept dimension
/// (`scale_k > 0`) or a constant one gets the identity or its constant; an ignored dimension that
/// varies gets the least-squares fit of its sample values on the kept dimensions and an intercept
/// (normal equations, in f64, with the kept dimensions centred; a singular system falls back to the
/// mean).
fn implied_controls(raw: &[f32], s: usize, scale: &[f32], min: &[f32], max: &[f32]) -> Vec<f32> {
    let d = scale.len();
    let kept: Vec<usize> = (0..d).filter(|&k| scale[k] > 0.0).collect();
    let col = |k: usize| raw[s * k..s * (k + 1)].iter().map(|&v| f64::from(v));
    let mean = |k: usize| col(k).sum::<f64>() / s as f64;
    let mut out = vec![0.0f32; d * (d + 1)];
    for k in 0..d {
        let row = &mut out[k * (d + 1)..(k + 1) * (d + 1)];
        if scale[k] > 0.0 {
            row[k] = 1.0;
            continue;
        }
        let mk = mean(k);
        row[d] = mk as f32;
        if min[k] == max[k] || kept.is_empty() {
            continue;
        }
        // Centred normal equations X^T X beta = X^T y over the kept dimensions.
        let m = kept.len();
        let means: Vec<f64> = kept.iter().map(|&j| mean(j)).collect();
        let mut a = vec![0.0f64; m * m];
        let mut b = vec![0.0f64; m];
        for i in 0..s {
            let y = f64::from(raw[i + s * k]) - mk;
            for (p, &jp) in kept.iter().enumerate() {
                let xp = f64::from(raw[i + s * jp]) - means[p];
                b[p] += xp * y;
                for (q, &jq) in kept.iter().enumerate() {
                    a[p * m + q] += xp * (f64::from(raw[i + s * jq]) - means[q]);
                }
            }
        }
        if let Some(beta) = solve_spd(&mut a, &mut b, m) {
            let mut intercept = mk;
            for (p, &j) in kept.iter().enumerate() {
                row[j] = beta[p] as f32;
                intercept -= beta[p] * means[p];
            }
            row[d] = intercept as f32;
        }
    }
    out
}

/// Solves the small symmetric positive definite system `a x = b` (`m x m`, row-major) by Cholesky;
/// `None` when a pivot is not positive relative to the diagonal (singular or indefinite).
fn solve_spd(a: &mut [f64], b: &mut [f64], m: usize) -> Option<Vec<f64>> {
    let scale = (0..m).map(|i| a[i * m + i]).fold(0.0f64, f64::max);
    for j in 0..m {
        let mut diag = a[j * m + j];
        for k in 0..j {
            diag -= a[j * m + k] * a[j * m + k];
        }
        if diag.is_nan() || diag <= 1e-12 * scale {
            return None;
        }
        let l = diag.sqrt();
        a[j * m + j] = l;
        for i in j + 1..m {
            let mut v = a[i * m + j];
            for k in 0..j {
                v -= a[i * m + k] * a[j * m + k];
            }
            a[i * m + j] = v / l;
        }
    }
    for i in 0..m {
        let mut v = b[i];
        for k in 0..i {
            v -= a[i * m + k] * b[k];
        }
        b[i] = v / a[i * m + i];
    }
    for i in (0..m).rev() {
        let mut v = b[i];
        for k in i + 1..m {
            v -= a[k * m + i] * b[k];
        }
        b[i] = v / a[i * m + i];
    }
    Some(b.to_vec())
}

#[cfg(test)]
mod implied_tests {
    use super::*;

    #[test]
    fn an_ignored_dimension_is_predicted_from_the_kept_ones() {
        // 6 samples, d = 3: dim 0 kept, dim 1 = 2 c0 + 0.5 ignored, dim 2 constant ignored.
        let c0 = [0.0f32, 0.1, 0.2, 0.5, 0.7, 1.0];
        let mut raw = Vec::new();
        raw.extend(c0);
        raw.extend(c0.iter().map(|v| 2.0 * v + 0.5));
        raw.extend([3.0f32; 6]);
        let cs = control_space(
            Variogram::new(VariogramModel::Linear, 0.0, 1.0, 0.0, 1.0).unwrap(),
            &raw,
            6,
            vec![0.0; 3],
            vec![1.0, 0.0, 0.0],
        )
        .unwrap();
        assert!((cs.implied_values(1, &[0.3, 9.0, 0.0]) - 1.1).abs() < 1e-5);
        assert_eq!(cs.implied_values(2, &[0.3, 9.0, 0.0]), 3.0);
        assert_eq!(cs.implied_values(0, &[0.3, 9.0, 0.0]), 0.3);
        // Clamped into the data's range: c0 = 5 reads as 1, giving 2.5.
        assert!((cs.implied_values(1, &[5.0, 0.0, 0.0]) - 2.5).abs() < 1e-5);
    }
}

#[cfg(test)]
mod variogram_tests {
    use super::*;

    #[test]
    fn the_runtime_variogram_evaluates_the_fitted_one_bit_for_bit() {
        for model in kriging::VariogramModel::ALL {
            let fitted = kriging::Variogram::new(model, 0.0347, 0.3472, 8.187, 1.3).unwrap();
            let runtime = runtime_variogram(&fitted).unwrap();
            assert_eq!(runtime.model.name(), model.name());
            for i in 0..2000 {
                let h = f64::from(i) * 0.00731;
                assert_eq!(
                    runtime.eval(h).to_bits(),
                    fitted.eval(h).to_bits(),
                    "{model:?} at h = {h}"
                );
            }
            // The same serialised bytes: a model file does not change.
            let a = bincode::serde::encode_to_vec(fitted, bincode::config::standard()).unwrap();
            let b = bincode::serde::encode_to_vec(runtime, bincode::config::standard()).unwrap();
            assert_eq!(a, b);
        }
    }

    #[test]
    fn models_the_runtime_does_not_evaluate_are_refused_by_name() {
        let fitted =
            kriging::Variogram::new(kriging::VariogramModel::Matern, 0.0, 1.0, 2.0, 1.5).unwrap();
        let e = runtime_variogram(&fitted).unwrap_err();
        assert!(e.to_string().contains("matern"), "{e}");
    }
}
