//! Nested variograms: a nugget plus a sum of structures, `gamma(h) = n + sum_k s_k f_k(h)`.

use serde::{Deserialize, Serialize};

use crate::error::KrigingError;
use crate::variogram::{Variogram, VariogramModel, shape};

/// One structure of a [`NestedVariogram`]: `sill * f(h; range, exponent)` (see [`VariogramModel`]
/// for the shapes `f`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Structure {
    /// The shape.
    pub model: VariogramModel,
    /// Partial sill of this structure (slope for `Linear`, coefficient for `Power`), `> 0`.
    pub sill: f64,
    /// Range (practical range for spherical, exponential, gaussian; scale for Matérn and
    /// cardinal sine), in the coordinates' units; ignored (0) for `Linear` and `Power`.
    pub range: f64,
    /// Exponent of `Power`, smoothness `nu` of `Matern`; ignored (1) otherwise.
    pub exponent: f64,
}

/// A nested variogram `gamma(h) = nugget + sum_k sill_k f_k(h)` for `h > 0`, `gamma(0) = 0`.
///
/// `nugget` is the discontinuity at the origin (micro-scale variation: kriging stays an exact
/// interpolator, the variance jumps to at least the nugget away from the samples). The total sill of
/// a bounded variogram is `nugget + sum_k sill_k`. A single [`Variogram`] converts with `From`.
///
/// ```
/// use kriging::{NestedVariogram, Variogram, VariogramModel};
///
/// // A short spherical structure plus a long exponential one.
/// let v = NestedVariogram::single(VariogramModel::Spherical, 0.1, 0.5, 50.0)?
///     .with(VariogramModel::Exponential, 1.0, 600.0, 1.0);
/// v.validate()?;
/// assert!(v.is_bounded());
/// assert!((v.total_sill() - 1.6).abs() < 1e-15);
/// let sph = Variogram::new(VariogramModel::Spherical, 0.0, 0.5, 50.0, 1.0)?;
/// let exp = Variogram::new(VariogramModel::Exponential, 0.0, 1.0, 600.0, 1.0)?;
/// for h in [10.0, 50.0, 300.0] {
///     assert!((v.eval(h) - (0.1 + sph.eval(h) + exp.eval(h))).abs() < 1e-12);
/// }
/// assert_eq!(v.eval(0.0), 0.0);
/// assert!(v.as_single().is_none());
/// let one = NestedVariogram::from(sph);
/// assert_eq!(one.as_single(), Some(sph));
/// # Ok::<(), kriging::KrigingError>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NestedVariogram {
    /// Discontinuity at the origin, `>= 0`.
    pub nugget: f64,
    /// The structures, at least one.
    pub structures: Vec<Structure>,
}

impl From<Variogram> for NestedVariogram {
    fn from(v: Variogram) -> Self {
        NestedVariogram {
            nugget: v.nugget,
            structures: vec![Structure {
                model: v.model,
                sill: v.sill,
                range: v.range,
                exponent: v.exponent,
            }],
        }
    }
}

impl NestedVariogram {
    /// A single structure with a nugget (validated).
    pub fn single(
        model: VariogramModel,
        nugget: f64,
        sill: f64,
        range: f64,
    ) -> Result<Self, KrigingError> {
        let v = Variogram::new(model, nugget, sill, range, 1.0)?;
        Ok(v.into())
    }

    /// Adds a structure (builder style; validated by [`NestedVariogram::validate`] at use).
    pub fn with(mut self, model: VariogramModel, sill: f64, range: f64, exponent: f64) -> Self {
        self.structures.push(Structure {
            model,
            sill,
            range: if model.has_range() { range } else { 0.0 },
            exponent: if model.has_exponent() { exponent } else { 1.0 },
        });
        self
    }

    /// Checks every parameter (as [`Variogram::validate`] for each structure with the nugget) and
    /// that there is at least one structure.
    pub fn validate(&self) -> Result<(), KrigingError> {
        let Some(first) = self.structures.first() else {
            return Err(KrigingError::InvalidConfig(
                "a nested variogram needs at least one structure".into(),
            ));
        };
        for (k, s) in self.structures.iter().enumerate() {
            let v = Variogram {
                model: s.model,
                nugget: if k == 0 { self.nugget } else { 0.0 },
                sill: s.sill,
                range: s.range,
                exponent: s.exponent,
            };
            v.validate()?;
        }
        let _ = first;
        Ok(())
    }

    /// `gamma(h)`: 0 at `h <= 0`, `nugget + structured(h)` beyond.
    #[inline]
    pub fn eval(&self, h: f64) -> f64 {
        if h > 0.0 {
            self.nugget + self.structured(h)
        } else {
            0.0
        }
    }

    /// `sum_k sill_k f_k(h)` (continuous, 0 at the origin).
    #[inline]
    pub fn structured(&self, h: f64) -> f64 {
        self.structures
            .iter()
            .map(|s| s.sill * shape(s.model, h, s.range, s.exponent))
            .sum()
    }

    /// Whether every structure has a finite sill.
    pub fn is_bounded(&self) -> bool {
        self.structures.iter().all(|s| s.model.has_range())
    }

    /// `nugget + sum_k sill_k` (the sill of a bounded variogram).
    pub fn total_sill(&self) -> f64 {
        self.nugget + self.structures.iter().map(|s| s.sill).sum::<f64>()
    }

    /// The single-structure [`Variogram`] this is, if it has exactly one structure.
    pub fn as_single(&self) -> Option<Variogram> {
        match self.structures.as_slice() {
            [s] => Some(Variogram {
                model: s.model,
                nugget: self.nugget,
                sill: s.sill,
                range: s.range,
                exponent: s.exponent,
            }),
            _ => None,
        }
    }
}
