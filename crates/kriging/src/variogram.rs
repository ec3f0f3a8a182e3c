//! Theoretical variogram models (paper appendix A: the function gamma fitted to the binned averages).

use serde::{Deserialize, Serialize};

use crate::error::KrigingError;

/// The shape of a theoretical variogram.
///
/// With nugget `n`, (partial) sill `s`, range `a` and exponent `e`, for `h > 0`:
/// - `Linear`: `n + s h` (`s` is the slope; no range),
/// - `Power`: `n + s h^e`, `0 < e < 2` (no range),
/// - `Spherical`: `n + s (3h/(2a) - h^3/(2a^3))` for `h < a`, `n + s` beyond,
/// - `Exponential`: `n + s (1 - exp(-3h/a))` (`a` is the practical range, 95 % of the sill),
/// - `Gaussian`: `n + s (1 - exp(-3h^2/a^2))` (practical range),
/// - `Matern`: `n + s (1 - 2^(1-nu)/Gamma(nu) t^nu K_nu(t))`, `t = h/a`, smoothness `nu = e > 0`
///   (`a` is the *scale* parameter, as in gstat's `"Mat"`: `nu = 1/2` gives `n + s (1 - exp(-h/a))`,
///   `nu -> infinity` tends to a gaussian shape; the practical range grows with `nu`, about `3a` at
///   `nu = 1/2`, `4.7a` at `nu = 3/2`),
/// - `CardinalSine`: `n + s (1 - sin(t)/t)`, `t = h/a` (the cardinal sine or *wave* model, one of
///   the hole-effect family; valid in up to three dimensions; the variogram crosses the sill at
///   `h = pi a`, peaks at `h = 4.49 a` (21.7 % of the partial sill above it) and oscillates around
///   it with a decaying amplitude). This is *not*
///   PyKrige's `"hole-effect"` model, which is `n + s (1 - (1 - 3h/a) exp(-3h/a))`. Before this
///   crate named it for its formula the variant was called `HoleEffect`: that name remains as an
///   alias ([`VariogramModel::HoleEffect`], serde name `"HoleEffect"`, and `"hole-effect"` in
///   [`VariogramModel::from_name`]).
///
/// New variants are appended at the end so that serialised variograms keep their meaning.
///
/// ```
/// use kriging::{Variogram, VariogramModel};
///
/// // Spherical: reaches nugget + partial sill at the range and stays there.
/// let sph = Variogram::new(VariogramModel::Spherical, 0.1, 2.0, 100.0, 1.0)?;
/// assert_eq!(sph.eval(0.0), 0.0); // gamma(0) = 0: the nugget is a jump at the origin
/// assert!((sph.eval(50.0) - (0.1 + 2.0 * (0.75 - 0.0625))).abs() < 1e-12);
/// assert_eq!(sph.eval(100.0), 2.1);
/// assert_eq!(sph.eval(500.0), 2.1);
/// // Cardinal sine: overshoots the sill (the "hole"), first maximum at h = 4.4934 a.
/// let sinc = Variogram::new(VariogramModel::CardinalSine, 0.0, 1.0, 10.0, 1.0)?;
/// let t: f64 = 4.4934;
/// assert!((sinc.eval(10.0 * t) - (1.0 - t.sin() / t)).abs() < 1e-12);
/// assert!(sinc.eval(10.0 * t) > 1.2);
/// // Names print and parse; the old name still parses to the same model.
/// assert_eq!(VariogramModel::from_name("cardinal-sine"), Some(VariogramModel::CardinalSine));
/// assert_eq!(VariogramModel::from_name("hole-effect"), Some(VariogramModel::CardinalSine));
/// assert_eq!(VariogramModel::HoleEffect, VariogramModel::CardinalSine);
/// # Ok::<(), kriging::KrigingError>(())
/// ```
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
    /// Bounded asymptotically, smoothness set by the exponent `nu` (Matérn class).
    Matern,
    /// Bounded, damped oscillation around the sill: `1 - sin(t)/t` (cardinal sine, or *wave*,
    /// model). Serialised as `"CardinalSine"`; the older `"HoleEffect"` is read as this.
    #[serde(alias = "HoleEffect")]
    CardinalSine,
}

#[allow(non_upper_case_globals)]
impl VariogramModel {
    /// The old name of [`VariogramModel::CardinalSine`] (`1 - sin(h/a)/(h/a)`), kept so that code
    /// and files that use it go on working. It is not PyKrige's `"hole-effect"` model
    /// (`1 - (1 - 3h/a) exp(-3h/a)`), which this crate does not provide.
    pub const HoleEffect: VariogramModel = VariogramModel::CardinalSine;
}

impl VariogramModel {
    /// The models automatic selection of [`crate::Kriging`] tries, in order (ties go to the earlier
    /// one). Kept to the paper's five so that the motion model's choice does not change; see
    /// [`VariogramModel::EVERY`] for every model.
    pub const ALL: [VariogramModel; 5] = [
        VariogramModel::Linear,
        VariogramModel::Power,
        VariogramModel::Spherical,
        VariogramModel::Exponential,
        VariogramModel::Gaussian,
    ];

    /// Every model, including the [`VariogramModel::Matern`] and [`VariogramModel::CardinalSine`]
    /// shapes that automatic selection does not try.
    pub const EVERY: [VariogramModel; 7] = [
        VariogramModel::Linear,
        VariogramModel::Power,
        VariogramModel::Spherical,
        VariogramModel::Exponential,
        VariogramModel::Gaussian,
        VariogramModel::Matern,
        VariogramModel::CardinalSine,
    ];

    /// Lower-case name (`"linear"`, `"power"`, `"spherical"`, `"exponential"`, `"gaussian"`,
    /// `"matern"`, `"cardinal-sine"`).
    pub fn name(self) -> &'static str {
        match self {
            VariogramModel::Linear => "linear",
            VariogramModel::Power => "power",
            VariogramModel::Spherical => "spherical",
            VariogramModel::Exponential => "exponential",
            VariogramModel::Gaussian => "gaussian",
            VariogramModel::Matern => "matern",
            VariogramModel::CardinalSine => "cardinal-sine",
        }
    }

    /// Parses a name as printed by [`VariogramModel::name`] (case-insensitive); the old name
    /// `"hole-effect"` and `"wave"` also give [`VariogramModel::CardinalSine`].
    pub fn from_name(name: &str) -> Option<Self> {
        if name.eq_ignore_ascii_case("hole-effect") || name.eq_ignore_ascii_case("wave") {
            return Some(VariogramModel::CardinalSine);
        }
        Self::EVERY
            .into_iter()
            .find(|m| m.name().eq_ignore_ascii_case(name))
    }

    /// Whether the model has a range parameter (every model but `Linear` and `Power`); these are
    /// also the bounded models (a finite sill).
    pub fn has_range(self) -> bool {
        !matches!(self, VariogramModel::Linear | VariogramModel::Power)
    }

    /// Whether the model uses [`Variogram::exponent`] (`Power`: the exponent; `Matern`: `nu`).
    pub fn has_exponent(self) -> bool {
        matches!(self, VariogramModel::Power | VariogramModel::Matern)
    }
}

/// A theoretical variogram `gamma(h)` (see [`VariogramModel`] for the formulas).
///
/// `gamma(0) = 0`; the nugget applies for `h > 0`. `sill` is the partial sill (the total sill of a
/// bounded model is `nugget + sill`); for `Linear` and `Power` it is the coefficient of `h` or `h^e`.
/// `range` is unused (0) for `Linear` and `Power`; `exponent` is used by `Power` (the exponent) and
/// `Matern` (the smoothness `nu`) only (1 otherwise).
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
    /// Exponent of the power model, in `(0, 2)`; smoothness `nu` of the Matérn model, in
    /// `[0.05, 50]`.
    pub exponent: f64,
}

impl Variogram {
    /// A validated variogram; `range` is ignored (stored as 0) for unbounded models and `exponent`
    /// is ignored (stored as 1) for every model but `Power` and `Matern`.
    pub fn new(
        model: VariogramModel,
        nugget: f64,
        sill: f64,
        range: f64,
        exponent: f64,
    ) -> Result<Self, KrigingError> {
        let v = Variogram {
            model,
            nugget,
            sill,
            range: if model.has_range() { range } else { 0.0 },
            exponent: if model.has_exponent() { exponent } else { 1.0 },
        };
        v.validate()?;
        Ok(v)
    }

    /// Checks that every parameter is finite and inside its domain.
    pub fn validate(&self) -> Result<(), KrigingError> {
        let bad = |reason: String| KrigingError::InvalidVariogram {
            model: self.model,
            reason,
        };
        if !(self.nugget.is_finite() && self.nugget >= 0.0) {
            return Err(bad(format!(
                "nugget {} must be finite and >= 0",
                self.nugget
            )));
        }
        if !(self.sill.is_finite() && self.sill > 0.0) {
            return Err(bad(format!("sill {} must be finite and > 0", self.sill)));
        }
        if self.model.has_range() && !(self.range.is_finite() && self.range > 0.0) {
            return Err(bad(format!("range {} must be finite and > 0", self.range)));
        }
        if self.model == VariogramModel::Power && !(self.exponent > 0.0 && self.exponent < 2.0) {
            return Err(bad(format!("exponent {} must be in (0, 2)", self.exponent)));
        }
        if self.model == VariogramModel::Matern && !(self.exponent >= 0.05 && self.exponent <= 50.0)
        {
            return Err(bad(format!(
                "smoothness nu = {} must be in [0.05, 50]",
                self.exponent
            )));
        }
        Ok(())
    }

    /// `gamma(h)`: 0 at `h <= 0`, `nugget + sill * shape(h)` for `h > 0`.
    #[inline]
    pub fn eval(&self, h: f64) -> f64 {
        if h > 0.0 {
            self.nugget + self.structured(h)
        } else {
            0.0
        }
    }

    /// The structured part `sill * shape(h)` without the nugget (continuous, 0 at `h = 0`).
    #[inline]
    pub fn structured(&self, h: f64) -> f64 {
        self.sill * shape(self.model, h, self.range, self.exponent)
    }

    /// The variogram between two *distinct* samples at distance `h`: `nugget + structured(h)`,
    /// also at `h = 0` (duplicate parameter points). This is the entry of the matrix Gamma; it
    /// keeps the kriging system regular for duplicates when the nugget is positive (the nugget is
    /// read as independent noise on each sample).
    #[inline]
    pub fn between_samples(&self, h: f64) -> f64 {
        self.nugget + self.structured(h)
    }
}

/// The unit shape `f(h)` of a model (0 at `h = 0`), so that `gamma(h) = nugget + sill f(h)`.
///
/// ```
/// use kriging::{shape, VariogramModel};
///
/// assert_eq!(shape(VariogramModel::Spherical, 50.0, 100.0, 1.0), 0.6875);
/// assert_eq!(shape(VariogramModel::Spherical, 150.0, 100.0, 1.0), 1.0);
/// // Exponential and gaussian: 95 % of the sill at the (practical) range.
/// assert!((shape(VariogramModel::Exponential, 100.0, 100.0, 1.0) - (1.0 - (-3f64).exp())).abs() < 1e-15);
/// assert_eq!(shape(VariogramModel::Power, 4.0, 0.0, 1.5), 8.0);
/// let pi = std::f64::consts::PI;
/// assert!((shape(VariogramModel::CardinalSine, pi, 1.0, 1.0) - 1.0).abs() < 1e-15); // sin(pi) = 0
/// ```
#[inline]
pub fn shape(model: VariogramModel, h: f64, range: f64, exponent: f64) -> f64 {
    if h <= 0.0 {
        return 0.0;
    }
    match model {
        VariogramModel::Linear => h,
        VariogramModel::Power => h.powf(exponent),
        VariogramModel::Spherical => {
            // `t = min(h / a, 1)` with the division taken as a product by `1 / a` (the form the
            // runtime evaluates over many distances at once, bit for bit): at and beyond the range
            // `1.5 - 0.5 = 1` exactly.
            let t = (h * (1.0 / range)).min(1.0);
            1.5 * t - 0.5 * t * t * t
        }
        VariogramModel::Exponential => 1.0 - (-3.0 * h / range).exp(),
        VariogramModel::Gaussian => {
            let t = h / range;
            1.0 - (-3.0 * t * t).exp()
        }
        VariogramModel::Matern => 1.0 - crate::special::matern_correlation(h / range, exponent),
        VariogramModel::CardinalSine => {
            let t = h / range;
            if t < 1e-4 {
                // 1 - sin(t)/t = t^2/6 - t^4/120 + ...
                t * t / 6.0 - t * t * t * t / 120.0
            } else if t == f64::INFINITY {
                // sin(inf) / inf is NaN; the limit is 0 (a tiny range or a huge lag).
                1.0
            } else {
                1.0 - t.sin() / t
            }
        }
    }
}
