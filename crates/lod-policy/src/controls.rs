//! The runtime's controls: what a gait cycle is asked to do, `c = (dx, dz, turn, height)` and,
//! for a model built with style labels, the performer's style ([`StyleMix`]).
//!
//! Mukai and Kuriyama parameterise each sample of the motion tensor by the controls of one gait
//! cycle (two steps): where the root goes over the cycle, how much the heading turns, and the
//! character's body height. Every runtime consumer (clip kernels, the crowd, `synth`, the CLI)
//! speaks [`Controls`]; the offline cycle analysis measures them in `f64`
//! (`motion_io::MeasuredControls`), and [`Controls::from_f64`] is the one conversion.
//!
//! Conventions (`docs/architecture.md`): metres and radians, y up, +z forward, +x to the
//! character's left, positive turn = turn left (a positive rotation about +y). The model's own
//! scaling of the control space (offsets, scales, variogram) is [`ControlSpace`], a different
//! thing: plain data of the kriging, not a request.

use serde::{Deserialize, Serialize};

use crate::model::ControlSpace;

/// Controls of one gait cycle (two steps), the paper's `c`; the model's control dimensions in this
/// order ([`Controls::NAMES`]), then the style.
///
/// The style weighs the model's styles ([`crate::RuntimeModel::styles`]); a model without styles
/// ignores it, and the default (every weight 0) asks for the data's own mix of styles.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Controls {
    /// Root displacement to the character's left over the cycle, in the start heading frame (m).
    pub dx: f32,
    /// Root displacement forward over the cycle, in the start heading frame (m).
    pub dz: f32,
    /// Heading change of the direction of travel over the cycle (rad, positive = left).
    pub turn: f32,
    /// Standing height of the character's skeleton (m).
    pub height: f32,
    /// The performer's style: a weight per style of the model ([`StyleMix`]).
    #[serde(default)]
    pub style: StyleMix,
}

/// The most styles a model holds (the style weights of [`Controls`] are a fixed array, so that
/// controls stay plain `Copy` data an engine and the C ABI pass by value).
pub const MAX_STYLES: usize = 8;

/// The style of a walk: a non-negative weight per style of the model, in the model's style order
/// ([`crate::RuntimeModel::styles`]). The kernel normalises the weights to sum 1 (a blend of
/// styles); every weight 0, the default, is the data's own mix of styles (each style weighted by
/// its share of the training cycles). Weights beyond the model's style count are ignored.
///
/// The model conditions on style as extra control dimensions: style `j` is dimension
/// `Controls::COUNT + j` of the control space, `1` for a sample of that style and `0` otherwise
/// (a one-hot code), scaled by the build's style weight; a blend is a point between the corners.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct StyleMix {
    /// Weight of each style (finite, `>= 0`).
    pub weights: [f32; MAX_STYLES],
}

impl StyleMix {
    /// The data's own mix of styles (every weight 0).
    pub const DATA_MIX: StyleMix = StyleMix {
        weights: [0.0; MAX_STYLES],
    };

    /// Style `index` alone (`index < MAX_STYLES`; a larger one gives [`StyleMix::DATA_MIX`]).
    pub fn one(index: usize) -> StyleMix {
        let mut weights = [0.0; MAX_STYLES];
        if let Some(w) = weights.get_mut(index) {
            *w = 1.0;
        }
        StyleMix { weights }
    }

    /// Whether every weight is 0: the data's mix.
    pub fn is_data_mix(&self) -> bool {
        self.weights.iter().all(|&w| w == 0.0)
    }

    /// The first problem of the weights as a phrase, if any: a weight NaN, infinite or negative.
    pub fn problem(&self) -> Option<String> {
        self.weights
            .iter()
            .enumerate()
            .find(|(_, w)| !(w.is_finite() && **w >= 0.0))
            .map(|(j, w)| format!("style weight {j} is {w} (weights are finite and >= 0)"))
    }

    /// The normalised weights of the first `n` styles (`n <= MAX_STYLES`) into `out[..n]`: the
    /// weights over their sum, or `data_mix` when they are all 0. `None` when a weight is not
    /// finite and non-negative ([`StyleMix::problem`]), or when `n > MAX_STYLES` or `out` or
    /// `data_mix` is shorter than `n` (nothing is written then).
    pub fn normalised(&self, n: usize, data_mix: &[f32], out: &mut [f32]) -> Option<()> {
        if n > MAX_STYLES || out.len() < n || data_mix.len() < n {
            return None;
        }
        let w = &self.weights[..n];
        if w.iter().any(|v| !(v.is_finite() && *v >= 0.0)) {
            return None;
        }
        let sum: f32 = w.iter().sum();
        if sum.is_infinite() {
            // Finite weights whose sum overflows (two of 2e38): over the largest first, so that
            // the sum is at most `n` (every weight over an infinite sum gave 0, no style at all).
            let largest = w.iter().fold(0.0f32, |a, &v| a.max(v));
            let sum: f32 = w.iter().map(|&v| v / largest).sum();
            for (o, &v) in out.iter_mut().zip(w) {
                *o = v / largest / sum;
            }
        } else if sum > 0.0 {
            for (o, &v) in out.iter_mut().zip(w) {
                *o = v / sum;
            }
        } else {
            out[..n].copy_from_slice(&data_mix[..n]);
        }
        Some(())
    }
}

impl Controls {
    /// Number of control dimensions.
    pub const COUNT: usize = 4;
    /// Name of each dimension, in array order.
    pub const NAMES: [&'static str; 4] = ["dx", "dz", "turn", "height"];
    /// Unit of each dimension, in array order.
    pub const UNITS: [&'static str; 4] = ["m", "m", "rad", "m"];
    /// `name (unit)` of each dimension, in array order, for tables and reports.
    pub const LABELS: [&'static str; 4] = ["dx (m)", "dz (m)", "turn (rad)", "height (m)"];

    /// Controls from `[dx, dz, turn, height]`.
    /// The style is the data's mix ([`StyleMix::DATA_MIX`]); see [`Controls::with_style`].
    pub const fn from_array(a: [f32; 4]) -> Controls {
        Controls {
            dx: a[0],
            dz: a[1],
            turn: a[2],
            height: a[3],
            style: StyleMix::DATA_MIX,
        }
    }

    /// These controls with the style `style`.
    pub const fn with_style(mut self, style: StyleMix) -> Controls {
        self.style = style;
        self
    }

    /// Controls from `[dx, dz, turn, height]` in `f64`, as the offline analysis measures them
    /// (`motion_io::MeasuredControls::to_array`, `motion_lod::Analysis::controls`), rounded to `f32`: the
    /// one conversion from measured to runtime controls.
    pub fn from_f64(a: [f64; 4]) -> Controls {
        Controls::from_array(a.map(|v| v as f32))
    }

    /// `[dx, dz, turn, height]`: the first four dimensions of the raw control vector the kernel
    /// takes ([`LodModel::build_kernel`](crate::LodModel::build_kernel); the style dimensions
    /// follow them).
    pub const fn to_array(&self) -> [f32; 4] {
        [self.dx, self.dz, self.turn, self.height]
    }
}

/// Clamps one control value into `[lo, hi]`; NaN becomes the midpoint. The one clamp of controls
/// into a model's range ([`ControlRange::clamp`]). Never panics: for a valid range this is
/// `f32::clamp` bit for bit (the same two comparisons, so `-0.0` and `+0.0` are kept as they
/// come); an inverted range (`lo > hi`) gives `hi`, and a NaN bound is ignored.
pub fn clamp_control(v: f32, lo: f32, hi: f32) -> f32 {
    if v.is_nan() {
        0.5 * (lo + hi)
    } else {
        clamp_unchecked(v, lo, hi)
    }
}

/// `f32::clamp`'s comparisons without its assertion (`lo <= hi`, neither NaN): the same bits for
/// a valid range, no panic for another.
#[inline]
pub(crate) fn clamp_unchecked(v: f32, lo: f32, hi: f32) -> f32 {
    let mut x = v;
    if x < lo {
        x = lo;
    }
    if x > hi {
        x = hi;
    }
    x
}

/// A per-dimension range of controls, e.g. what a model's training data cover.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct ControlRange {
    /// Smallest value of each control.
    pub min: Controls,
    /// Largest value of each control.
    pub max: Controls,
}

impl ControlRange {
    /// Each control clamped into `[min, max]` ([`clamp_control`]: NaN becomes the midpoint; never
    /// panics, also for an inverted or NaN range, see [`ControlRange::problem`]); the style is kept
    /// as it is.
    pub fn clamp(&self, c: &Controls) -> Controls {
        let (v, lo, hi) = (c.to_array(), self.min.to_array(), self.max.to_array());
        Controls::from_array(std::array::from_fn(|k| clamp_control(v[k], lo[k], hi[k])))
            .with_style(c.style)
    }

    /// Whether every control lies in `[min, max]` (false for NaN).
    pub fn contains(&self, c: &Controls) -> bool {
        let (v, lo, hi) = (c.to_array(), self.min.to_array(), self.max.to_array());
        (0..Controls::COUNT).all(|k| lo[k] <= v[k] && v[k] <= hi[k])
    }

    /// The first problem of the range as a phrase, if any: a non-finite bound or `min > max`.
    pub fn problem(&self) -> Option<&'static str> {
        let (lo, hi) = (self.min.to_array(), self.max.to_array());
        if lo.iter().chain(&hi).any(|v| !v.is_finite()) {
            Some("a bound is NaN or infinite")
        } else if (0..Controls::COUNT).any(|k| lo[k] > hi[k]) {
            Some("min > max")
        } else {
            None
        }
    }
}

impl ControlSpace {
    /// The range of the raw sample controls as [`Controls`] (the four of [`Controls::NAMES`]; the
    /// style dimensions after them are not part of it), or `None` when the model does not have
    /// those four control dimensions.
    pub fn range(&self) -> Option<ControlRange> {
        let n = Controls::COUNT;
        if self.min.len() < n || self.max.len() < n || self.min.len() > n + MAX_STYLES {
            return None;
        }
        let (lo, hi) = (
            <[f32; 4]>::try_from(&self.min[..n]).ok()?,
            <[f32; 4]>::try_from(&self.max[..n]).ok()?,
        );
        Some(ControlRange {
            min: Controls::from_array(lo),
            max: Controls::from_array(hi),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn range() -> ControlRange {
        ControlRange {
            min: Controls::from_array([-0.3, 0.5, -1.0, 1.5]),
            max: Controls::from_array([0.3, 1.8, 1.0, 1.9]),
        }
    }

    #[test]
    fn array_round_trip_keeps_the_named_order() {
        let c = Controls::from_array([0.1, 1.2, -0.3, 1.7]);
        assert_eq!((c.dx, c.dz, c.turn, c.height), (0.1, 1.2, -0.3, 1.7));
        assert_eq!(c.to_array(), [0.1, 1.2, -0.3, 1.7]);
        for (k, label) in Controls::LABELS.iter().enumerate() {
            assert_eq!(
                *label,
                format!("{} ({})", Controls::NAMES[k], Controls::UNITS[k])
            );
        }
    }

    #[test]
    fn clamp_limits_each_dimension_and_replaces_nan() {
        let r = range();
        let c = r.clamp(&Controls::from_array([5.0, -1.0, f32::NAN, 1.7]));
        assert_eq!(c, Controls::from_array([0.3, 0.5, 0.0, 1.7]));
        assert!(r.contains(&c));
        assert!(!r.contains(&Controls::from_array([0.0, 1.0, f32::NAN, 1.7])));
    }

    #[test]
    fn style_weights_normalise_or_read_the_data_mix() {
        let mix = [0.5, 0.25, 0.25];
        let mut out = [0.0; 3];
        StyleMix::DATA_MIX.normalised(3, &mix, &mut out).unwrap();
        assert_eq!(out, mix);
        let mut w = StyleMix::DATA_MIX;
        w.weights[0] = 3.0;
        w.weights[2] = 1.0;
        w.weights[5] = 9.0; // beyond the model's 3 styles: ignored
        w.normalised(3, &mix, &mut out).unwrap();
        assert_eq!(out, [0.75, 0.0, 0.25]);
        assert_eq!(StyleMix::one(1).weights[..3], [0.0, 1.0, 0.0]);
        assert!(StyleMix::one(99).is_data_mix());
        for bad in [f32::NAN, -0.5, f32::INFINITY] {
            w.weights[1] = bad;
            assert!(w.normalised(3, &mix, &mut out).is_none());
            assert!(w.problem().unwrap().contains("style weight 1"));
        }
        // Finite weights whose sum overflows are the same blend as small ones (over an infinite
        // sum every weight was 0: no style at all), at any scale up to the largest float.
        for (big, want) in [
            ([2e38, 2e38, 0.0], [0.5, 0.5, 0.0]),
            (
                [f32::MAX, f32::MAX, f32::MAX],
                [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0],
            ),
            ([f32::MAX, 0.0, f32::MAX / 4.0], [0.8, 0.0, 0.2]),
        ] {
            let mut w = StyleMix::DATA_MIX;
            w.weights[..3].copy_from_slice(&big);
            w.normalised(3, &mix, &mut out).unwrap();
            for (o, e) in out.iter().zip(want) {
                assert!((o - e).abs() <= 1e-6, "{big:?} -> {out:?}");
            }
        }
        // The clamp of the four controls keeps the style.
        let c = Controls::from_array([0.0, 1.0, 0.0, 1.7]).with_style(StyleMix::one(2));
        assert_eq!(range().clamp(&c).style, StyleMix::one(2));
    }

    #[test]
    fn problem_names_bad_ranges() {
        assert_eq!(range().problem(), None);
        let mut r = range();
        r.max.turn = f32::INFINITY;
        assert!(r.problem().is_some());
        let mut r = range();
        r.min.dz = 3.0;
        assert_eq!(r.problem(), Some("min > max"));
    }
}
