//! [`FrameSeq`]: a row-major sequence of fixed-size frames, and linear interpolation between frames.

use serde::{Deserialize, Serialize};

use crate::error::TimewarpError;

/// A sequence of frames, each `dim` values, stored row-major (`frames[i * dim + c]` is column `c` of
/// frame `i`).
///
/// The fields are public so that callers can build and take apart sequences without copies; every
/// function of this crate validates a sequence (see [`FrameSeq::check`]) before using it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrameSeq {
    /// Number of values per frame.
    pub dim: usize,
    /// The values, `len() * dim` of them, frame after frame.
    pub frames: Vec<f64>,
}

impl FrameSeq {
    /// A sequence from a flat row-major buffer.
    ///
    /// Errors: [`TimewarpError::ZeroDim`] when `dim == 0`, [`TimewarpError::RaggedFrames`] when the
    /// buffer length is not a multiple of `dim` (both reported as sequence 0).
    pub fn new(dim: usize, frames: Vec<f64>) -> Result<Self, TimewarpError> {
        let seq = Self { dim, frames };
        seq.check_shape(0)?;
        Ok(seq)
    }

    /// A sequence of `len` frames of `dim` zeros.
    pub fn zeros(dim: usize, len: usize) -> Self {
        Self {
            dim,
            frames: vec![0.0; dim * len],
        }
    }

    /// Number of frames (`frames.len() / dim`, 0 when `dim == 0`).
    pub fn len(&self) -> usize {
        self.frames.len().checked_div(self.dim).unwrap_or(0)
    }

    /// Whether the sequence has no frames.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Frame `i` as a slice of `dim` values.
    ///
    /// # Panics
    /// When `i >= len()`, like slice indexing.
    pub fn frame(&self, i: usize) -> &[f64] {
        &self.frames[i * self.dim..(i + 1) * self.dim]
    }

    /// Frame `i` as a mutable slice of `dim` values.
    ///
    /// # Panics
    /// When `i >= len()`, like slice indexing.
    pub fn frame_mut(&mut self, i: usize) -> &mut [f64] {
        &mut self.frames[i * self.dim..(i + 1) * self.dim]
    }

    /// Checks `dim > 0` and that the buffer holds whole frames; `index` names the sequence in errors.
    pub fn check_shape(&self, index: usize) -> Result<(), TimewarpError> {
        if self.dim == 0 {
            return Err(TimewarpError::ZeroDim { index });
        }
        if self.frames.len() % self.dim != 0 {
            return Err(TimewarpError::RaggedFrames {
                index,
                len: self.frames.len(),
                dim: self.dim,
            });
        }
        Ok(())
    }

    /// Checks the shape (see [`FrameSeq::check_shape`]), that there are at least `min_frames` frames
    /// and that every value is finite; `index` names the sequence in errors.
    pub fn check(&self, index: usize, min_frames: usize) -> Result<(), TimewarpError> {
        self.check_shape(index)?;
        if self.len() < min_frames {
            return Err(TimewarpError::TooShort {
                index,
                frames: self.len(),
                needed: min_frames,
            });
        }
        if let Some(pos) = self.frames.iter().position(|v| !v.is_finite()) {
            return Err(TimewarpError::NonFinite {
                index,
                frame: pos / self.dim,
                column: pos % self.dim,
                value: self.frames[pos],
            });
        }
        Ok(())
    }

    /// Linear interpolation at a fractional frame position `t` (clamped to `[0, len - 1]`), written
    /// into `out` (`dim` values): `out = (1 - f) x_k + f x_{k+1}` with `k = floor(t)`, `f = t - k`.
    ///
    /// Does nothing when the sequence is empty. `out.len()` must equal `dim` (debug-asserted).
    pub fn sample_at(&self, t: f64, out: &mut [f64]) {
        debug_assert_eq!(out.len(), self.dim);
        let n = self.len();
        if n == 0 {
            return;
        }
        let (k, f) = split_position(t, n);
        let a = self.frame(k);
        if f == 0.0 {
            out.copy_from_slice(a);
            return;
        }
        let b = self.frame(k + 1);
        for ((o, &x), &y) in out.iter_mut().zip(a).zip(b) {
            *o = x + f * (y - x);
        }
    }
}

/// Most `f64` values one buffer of this crate may hold: `2^30` (8 GiB). Larger requests, which
/// no real alignment needs, fail with [`TimewarpError::TooLarge`] instead of aborting the process
/// on a failed allocation: a DTW table ([`dtw`](crate::dtw): `n m (2 max_slope + 2)` values), all
/// aligned sequences of one [`align`](crate::align) call together
/// (`sequences * frames * (values dim + 1)`), and the output of
/// [`playback`](crate::playback) (`frames * (dim - 1)`).
pub const MAX_BUFFER_VALUES: usize = 1 << 30;

/// The product of `factors` when it is at most [`MAX_BUFFER_VALUES`], else
/// [`TimewarpError::TooLarge`] naming `what` (the product printed approximately when it
/// overflows `usize`).
pub(crate) fn check_buffer(what: &'static str, factors: &[usize]) -> Result<usize, TimewarpError> {
    let exact = factors
        .iter()
        .try_fold(1usize, |acc, &f| acc.checked_mul(f));
    match exact {
        Some(values) if values <= MAX_BUFFER_VALUES => Ok(values),
        _ => Err(TimewarpError::TooLarge {
            what,
            requested: match exact {
                Some(values) => values.to_string(),
                None => format!("{:e}", factors.iter().map(|&f| f as f64).product::<f64>()),
            },
            limit: MAX_BUFFER_VALUES,
        }),
    }
}

/// Splits a fractional frame position into `(k, f)` with `k + f = phase` clamped to
/// `[0, frames - 1]`, `0 <= f < 1` and `k + 1 < frames` whenever `f > 0` (NaN gives `(0, 0)`):
/// the rule by which resampling and playback interpolate between frames (the runtime's
/// `lod_policy::offline::split_phase` is the same rule; a test checks they agree). `frames`
/// must be at least 1.
pub(crate) fn split_position(phase: f64, frames: usize) -> (usize, f64) {
    debug_assert!(frames >= 1);
    let n = frames.max(1);
    let last = (n - 1) as f64;
    // NaN maps to 0 through `max`.
    let t = phase.max(0.0).min(last);
    let k = (t.floor() as usize).min(n - 1);
    let f = t - k as f64;
    if k + 1 >= n || f <= 0.0 {
        (k, 0.0)
    } else {
        (k, f)
    }
}

/// Squared Euclidean distance `sum_c (a_c - b_c)^2` between two frames of equal length.
#[inline]
pub(crate) fn squared_distance(a: &[f64], b: &[f64]) -> f64 {
    debug_assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| {
            let d = x - y;
            d * d
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::split_position;

    /// The offline frame split is the runtime's rule, to the bit.
    #[test]
    fn split_position_is_the_runtime_split_phase() {
        for frames in [1, 2, 5, 40] {
            for k in -20..=500 {
                let phase = k as f64 * 0.0973;
                let (a, f) = split_position(phase, frames);
                let (b, g) = lod_policy::offline::split_phase(phase, frames);
                assert_eq!((a, f.to_bits()), (b, g.to_bits()), "{phase} of {frames}");
            }
            assert_eq!(
                split_position(f64::NAN, frames),
                lod_policy::offline::split_phase(f64::NAN, frames)
            );
        }
    }
}
