//! The variogram `gamma(h)` of the control space, as plain data the runtime evaluates.
//!
//! The offline build fits it (the `kriging` crate) and converts the fitted model into this form; the
//! runtime only evaluates it. Only the model kinds the motion build can choose are here. Variant
//! order and field order are those of the offline variogram, so a model file stores the same bytes
//! either way.

use serde::{Deserialize, Serialize};

use crate::error::VariogramError;

/// The shape of a variogram. With nugget `n`, (partial) sill `s`, range `a` and exponent `e`, for
/// `h > 0`:
/// - `Linear`: `n + s h` (`s` is the slope; no range),
/// - `Power`: `n + s h^e`, `0 < e < 2` (no range),
/// - `Spherical`: `n + s (3t/2 - t^3/2)` with `t = min(h/a, 1)` (the sill from the range on),
/// - `Exponential`: `n + s (1 - exp(-3h/a))` (`a` is the practical range, 95 % of the sill),
/// - `Gaussian`: `n + s (1 - exp(-3h^2/a^2))` (practical range).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum VariogramModel {
    /// Unbounded, proportional to the distance.
    Linear,
    /// Unbounded, a power of the distance.
    Power,
    /// Bounded, reaches the sill at the range.
    Spherical,
    /// Bounded asymptotically.
    Exponential,
    /// Bounded asymptotically, smooth (parabolic) at the origin.
    Gaussian,
}

impl VariogramModel {
    /// Every model the runtime evaluates, in the order of the file format.
    pub const ALL: [VariogramModel; 5] = [
        VariogramModel::Linear,
        VariogramModel::Power,
        VariogramModel::Spherical,
        VariogramModel::Exponential,
        VariogramModel::Gaussian,
    ];

    /// Lower-case name (`"linear"`, `"power"`, `"spherical"`, `"exponential"`, `"gaussian"`).
    pub fn name(self) -> &'static str {
        match self {
            VariogramModel::Linear => "linear",
            VariogramModel::Power => "power",
            VariogramModel::Spherical => "spherical",
            VariogramModel::Exponential => "exponential",
            VariogramModel::Gaussian => "gaussian",
        }
    }

    /// Whether the model has a range parameter (the bounded ones: all but `Linear` and `Power`).
    pub fn has_range(self) -> bool {
        !matches!(self, VariogramModel::Linear | VariogramModel::Power)
    }
}

/// A variogram `gamma(h)` (see [`VariogramModel`] for the shapes).
///
/// `gamma(0) = 0`; the nugget applies for `h > 0`. `sill` is the partial sill of a bounded model or
/// the coefficient of `h` (`h^e`) of `Linear` (`Power`); `range` is 0 and unused for `Linear` and
/// `Power`; `exponent` is used by `Power` only (1 otherwise).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Variogram {
    /// The model shape.
    pub model: VariogramModel,
    /// Discontinuity at the origin, `>= 0`.
    pub nugget: f64,
    /// Partial sill (or slope), `> 0`.
    pub sill: f64,
    /// Practical range of bounded models, `> 0` for them.
    pub range: f64,
    /// Exponent of the power model, in `(0, 2)`.
    pub exponent: f64,
}

impl Variogram {
    /// A validated variogram; `range` is stored as 0 for the unbounded models and `exponent` as 1
    /// for every model but `Power`.
    pub fn new(
        model: VariogramModel,
        nugget: f64,
        sill: f64,
        range: f64,
        exponent: f64,
    ) -> Result<Variogram, VariogramError> {
        let v = Variogram {
            model,
            nugget,
            sill,
            range: if model.has_range() { range } else { 0.0 },
            exponent: if model == VariogramModel::Power {
                exponent
            } else {
                1.0
            },
        };
        v.validate()?;
        Ok(v)
    }

    /// Checks that every parameter the model uses is finite and inside its domain: nugget
    /// `>= 0`, sill `> 0`, range `> 0` (bounded models), exponent in `(0, 2)` (`Power`).
    pub fn validate(&self) -> Result<(), VariogramError> {
        let (n, s, a, e) = (self.nugget, self.sill, self.range, self.exponent);
        let power = self.model == VariogramModel::Power;
        let rules = [
            ("nugget", n, n.is_finite() && n >= 0.0, "finite and >= 0"),
            ("sill", s, s.is_finite() && s > 0.0, "finite and > 0"),
            (
                "range",
                a,
                !self.model.has_range() || (a.is_finite() && a > 0.0),
                "finite and > 0",
            ),
            ("exponent", e, !power || (e > 0.0 && e < 2.0), "in (0, 2)"),
        ];
        match rules.into_iter().find(|&(_, _, ok, _)| !ok) {
            Some((name, value, _, rule)) => Err(VariogramError {
                model: self.model.name(),
                reason: format!("{name} {value} must be {rule}"),
            }),
            None => Ok(()),
        }
    }

    /// `gamma(h)`: 0 for `h <= 0` (and NaN), `nugget + sill f(h)` beyond, with `f` the unit shape
    /// of the model.
    #[inline]
    pub fn eval(&self, h: f64) -> f64 {
        if h > 0.0 {
            self.nugget + self.sill * self.unit(h)
        } else {
            0.0
        }
    }

    /// The unit shape `f(h)` for `h > 0`. The spherical model clamps `h / range` to 1 instead of
    /// branching at the range: at and beyond the range `1.5 - 0.5 = 1` exactly.
    #[inline]
    fn unit(&self, h: f64) -> f64 {
        let a = self.range;
        match self.model {
            VariogramModel::Linear => h,
            VariogramModel::Power => h.powf(self.exponent),
            VariogramModel::Spherical => {
                // `h * (1 / a)` rather than `h / a`: the batch form then needs no division per
                // distance (one per batch), and the two stay bitwise equal.
                let t = (h * (1.0 / a)).min(1.0);
                1.5 * t - 0.5 * t * t * t
            }
            VariogramModel::Exponential => 1.0 - (-3.0 * h / a).exp(),
            VariogramModel::Gaussian => {
                let ratio = h / a;
                1.0 - (-3.0 * ratio * ratio).exp()
            }
        }
    }

    /// `x_i <- gamma(sqrt(x_i))` for squared distances `x`: [`Variogram::eval`] of each distance,
    /// bit for bit. The spherical and linear models, the ones the motion data choose, run in a
    /// branch-free loop that vectorises; the others call `eval`.
    #[inline(always)]
    pub fn eval_squared(&self, x: &mut [f64]) {
        match self.squared_form() {
            Some(SquaredForm::Spherical {
                nugget,
                sill,
                inv_range,
            }) => {
                for g in x.iter_mut() {
                    *g = spherical_of_squared(*g, nugget, sill, inv_range);
                }
            }
            Some(SquaredForm::Linear { nugget, sill }) => {
                for g in x.iter_mut() {
                    *g = linear_of_squared(*g, nugget, sill);
                }
            }
            None => {
                for g in x.iter_mut() {
                    *g = self.eval(g.sqrt());
                }
            }
        }
    }

    /// The branch-free form of this variogram of a squared distance, where it has one (spherical
    /// with a positive range, linear): what [`Variogram::eval_squared`] runs, and what a caller
    /// that computes the squared distances can apply to each as it goes.
    #[inline(always)]
    pub(crate) fn squared_form(&self) -> Option<SquaredForm> {
        let (nugget, sill, range) = (self.nugget, self.sill, self.range);
        match self.model {
            VariogramModel::Spherical if range > 0.0 => Some(SquaredForm::Spherical {
                nugget,
                sill,
                inv_range: 1.0 / range,
            }),
            VariogramModel::Linear => Some(SquaredForm::Linear { nugget, sill }),
            _ => None,
        }
    }
}

/// A variogram's branch-free form over squared distances ([`Variogram::squared_form`]):
/// [`spherical_of_squared`] or [`linear_of_squared`] with these parameters equals
/// [`Variogram::eval`] of the distance bit for bit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum SquaredForm {
    /// The spherical model, `1 / range` taken once.
    Spherical {
        /// The nugget.
        nugget: f64,
        /// The partial sill.
        sill: f64,
        /// `1 / range`.
        inv_range: f64,
    },
    /// The linear model.
    Linear {
        /// The nugget.
        nugget: f64,
        /// The slope.
        sill: f64,
    },
}

/// The spherical variogram of the squared distance `h2`: with `h = sqrt(h2)` and
/// `t = min(h / range, 1)`, `nugget + sill (1.5 t - 0.5 t^3)` for `h > 0`, and 0 at `h = 0`.
#[inline(always)]
pub(crate) fn spherical_of_squared(h2: f64, nugget: f64, sill: f64, inv_range: f64) -> f64 {
    let h = h2.sqrt();
    let t = (h * inv_range).min(1.0);
    let y = nugget + sill * (1.5 * t - 0.5 * t * t * t);
    if h > 0.0 { y } else { 0.0 }
}

/// The linear variogram of the squared distance `h2`: `nugget + sill sqrt(h2)` for `h2 > 0`,
/// and 0 at 0.
#[inline(always)]
pub(crate) fn linear_of_squared(h2: f64, nugget: f64, sill: f64) -> f64 {
    let h = h2.sqrt();
    let y = nugget + sill * h;
    if h > 0.0 { y } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn branch_free_variogram_equals_eval_bitwise() {
        let h2: Vec<f64> = (0..400)
            .map(|i| {
                let x = i as f64 * 0.037;
                x * x
            })
            .chain([0.0, 1e-300, 8.187 * 8.187, 1e6])
            .collect();
        for model in VariogramModel::ALL {
            let v = Variogram::new(model, 0.0347, 0.3472, 8.187, 1.3).unwrap();
            let mut got = h2.clone();
            v.eval_squared(&mut got);
            for (&g, &x) in got.iter().zip(&h2) {
                let want = v.eval(x.sqrt());
                assert_eq!(
                    g.to_bits(),
                    want.to_bits(),
                    "{model:?} at h^2 = {x}: {g} vs {want}"
                );
            }
        }
    }

    #[test]
    fn spherical_reaches_the_sill_at_the_range_and_stays() {
        let v = Variogram::new(VariogramModel::Spherical, 0.1, 2.0, 3.0, 1.0).unwrap();
        assert_eq!(v.eval(0.0), 0.0);
        assert_eq!(v.eval(3.0), 2.1);
        assert_eq!(v.eval(30.0), 2.1);
        assert!(v.eval(1.5) < 2.1 && v.eval(1.5) > 0.1);
    }

    #[test]
    fn bad_parameters_name_the_model_and_value() {
        let e = Variogram::new(VariogramModel::Power, 0.0, 1.0, 0.0, 2.5).unwrap_err();
        assert!(
            e.to_string().contains("power") && e.to_string().contains("2.5"),
            "{e}"
        );
        let e = Variogram::new(VariogramModel::Gaussian, 0.0, 1.0, -1.0, 1.0).unwrap_err();
        assert!(e.to_string().contains("range"), "{e}");
        let e = Variogram::new(VariogramModel::Linear, f64::NAN, 1.0, 0.0, 1.0).unwrap_err();
        assert!(e.to_string().contains("nugget"), "{e}");
        // Unused parameters are normalised, so they cannot fail.
        let v = Variogram::new(VariogramModel::Linear, 0.0, 1.0, f64::NAN, 9.0).unwrap();
        assert_eq!((v.range, v.exponent), (0.0, 1.0));
    }
}
