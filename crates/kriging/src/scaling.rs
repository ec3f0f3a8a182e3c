//! Per-dimension scaling of the parameter space before any distance is taken.

use faer::MatRef;
use serde::{Deserialize, Serialize};

use crate::error::KrigingError;

/// An affine map of each parameter dimension: `scaled_k = (c_k - offset_k) * scale_k`.
///
/// A scale of 0 drops a dimension: it no longer contributes to distances nor to the trend.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParamScaling {
    /// Subtracted from each dimension.
    pub offset: Vec<f64>,
    /// Multiplies each dimension after the offset (0 = dropped).
    pub scale: Vec<f64>,
}

/// How [`crate::Kriging::fit`] and [`crate::Rbf::fit`] scale the parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub enum ScalingChoice {
    /// Use the parameters as they are.
    None,
    /// Zero mean and unit (population) standard deviation per dimension; constant dimensions are
    /// dropped (scale 0).
    #[default]
    Standardise,
    /// A scaling chosen by the caller.
    Given(ParamScaling),
}

impl ParamScaling {
    /// The identity on `d` dimensions.
    pub fn none(d: usize) -> Self {
        ParamScaling {
            offset: vec![0.0; d],
            scale: vec![1.0; d],
        }
    }

    /// Standardises each column of `params` (S x d): offset = mean, scale = 1 / standard deviation
    /// (population). A column whose standard deviation is at most `1e-12 * max(1, |mean|)` is
    /// constant: scale 0 (dropped). Fails on an empty matrix or a non-finite entry, and with
    /// [`KrigingError::Overflow`] naming the column when its mean or variance overflows (finite
    /// entries near `1e154` and beyond), instead of dropping the column as constant.
    ///
    /// ```
    /// use kriging::faer::Mat;
    /// use kriging::ParamScaling;
    ///
    /// // Column 0 has mean 2 and standard deviation 1; column 1 is constant.
    /// let p = Mat::from_fn(2, 2, |i, k| if k == 0 { [1.0, 3.0][i] } else { 7.0 });
    /// let s = ParamScaling::standardise(p.as_ref())?;
    /// assert_eq!((s.offset.as_slice(), s.scale.as_slice()), ([2.0, 7.0].as_slice(), [1.0, 0.0].as_slice()));
    /// assert_eq!(s.dropped(), [1]);
    /// let mut out = [0.0; 2];
    /// s.apply(&[4.0, 100.0], &mut out); // (c - offset) * scale
    /// assert_eq!(out, [2.0, 0.0]);
    /// # Ok::<(), kriging::KrigingError>(())
    /// ```
    pub fn standardise(params: MatRef<'_, f64>) -> Result<Self, KrigingError> {
        let (s, d) = params.shape();
        if s == 0 {
            return Err(KrigingError::TooFewSamples {
                what: "standardise",
                needed: 1,
                got: 0,
            });
        }
        crate::check_finite("params", params)?;
        let mut offset = vec![0.0; d];
        let mut scale = vec![0.0; d];
        for k in 0..d {
            let mean = (0..s).map(|i| params[(i, k)]).sum::<f64>() / s as f64;
            let var = (0..s)
                .map(|i| {
                    let t = params[(i, k)] - mean;
                    t * t
                })
                .sum::<f64>()
                / s as f64;
            if !(mean.is_finite() && var.is_finite()) {
                return Err(KrigingError::Overflow {
                    what: format!("params column {k}"),
                    reason: format!("its mean is {mean} and its variance {var}"),
                });
            }
            let sd = var.sqrt();
            offset[k] = mean;
            scale[k] = if sd > 1e-12 * mean.abs().max(1.0) {
                1.0 / sd
            } else {
                0.0
            };
        }
        Ok(ParamScaling { offset, scale })
    }

    /// A caller-given scaling; both vectors must have the same length and finite entries, scales
    /// must be `>= 0`.
    pub fn given(offset: Vec<f64>, scale: Vec<f64>) -> Result<Self, KrigingError> {
        let s = ParamScaling { offset, scale };
        s.validate()?;
        Ok(s)
    }

    /// Checks lengths and entries (see [`ParamScaling::given`]).
    pub fn validate(&self) -> Result<(), KrigingError> {
        if self.offset.len() != self.scale.len() {
            return Err(KrigingError::ShapeMismatch {
                what: "scaling offset length vs scale length",
                expected: self.scale.len(),
                got: self.offset.len(),
            });
        }
        for (k, (&o, &s)) in self.offset.iter().zip(&self.scale).enumerate() {
            if !o.is_finite() {
                return Err(KrigingError::InvalidScaling {
                    dim: k,
                    reason: format!("offset {o} is not finite"),
                });
            }
            if !(s.is_finite() && s >= 0.0) {
                return Err(KrigingError::InvalidScaling {
                    dim: k,
                    reason: format!("scale {s} must be finite and >= 0"),
                });
            }
        }
        Ok(())
    }

    /// Number of dimensions.
    pub fn dims(&self) -> usize {
        self.scale.len()
    }

    /// `out_k = (c_k - offset_k) * scale_k`. `c` and `out` must have [`ParamScaling::dims`] entries.
    #[inline]
    pub fn apply(&self, c: &[f64], out: &mut [f64]) {
        debug_assert_eq!(c.len(), self.scale.len());
        debug_assert_eq!(out.len(), self.scale.len());
        for ((o, &x), (&off, &sc)) in out
            .iter_mut()
            .zip(c)
            .zip(self.offset.iter().zip(&self.scale))
        {
            *o = (x - off) * sc;
        }
    }

    /// The dimensions with scale 0 (dropped), in increasing order.
    pub fn dropped(&self) -> Vec<usize> {
        self.scale
            .iter()
            .enumerate()
            .filter(|(_, s)| **s == 0.0)
            .map(|(k, _)| k)
            .collect()
    }

    /// Resolves a [`ScalingChoice`] for `params` (S x d).
    pub fn from_choice(
        choice: &ScalingChoice,
        params: MatRef<'_, f64>,
    ) -> Result<Self, KrigingError> {
        let d = params.ncols();
        let s = match choice {
            ScalingChoice::None => ParamScaling::none(d),
            ScalingChoice::Standardise => ParamScaling::standardise(params)?,
            ScalingChoice::Given(s) => {
                s.validate()?;
                s.clone()
            }
        };
        if s.dims() != d {
            return Err(KrigingError::ShapeMismatch {
                what: "scaling dimensions vs parameter columns",
                expected: d,
                got: s.dims(),
            });
        }
        Ok(s)
    }

    /// Applies the scaling to every row of `params` (S x d).
    ///
    /// # Panics
    ///
    /// When `params` has more columns than the scaling has dimensions ([`ParamScaling::dims`]);
    /// [`ParamScaling::from_choice`] returns a scaling with one dimension per column.
    pub fn apply_rows(&self, params: MatRef<'_, f64>) -> faer::Mat<f64> {
        assert!(
            params.ncols() <= self.dims(),
            "ParamScaling::apply_rows: {} columns for a scaling of {} dimensions",
            params.ncols(),
            self.dims()
        );
        faer::Mat::from_fn(params.nrows(), params.ncols(), |i, k| {
            (params[(i, k)] - self.offset[k]) * self.scale[k]
        })
    }
}
