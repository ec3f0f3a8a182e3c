//! [`TimeTable`]: playback times of an aligned sequence from its time-increment channel (the
//! incremental inverse timewarp of the paper's section 3.1). A clip kernel fills one per clip
//! ([`crate::ClipKernel::time_table`]); the offline `timewarp` crate plays aligned data back with
//! the same table (it re-exports this module's items).

/// Smallest time increment, in seconds, that [`TimeTable`] accepts: a synthesized increment that is
/// smaller than this, negative, NaN or infinite is replaced by it, so that playback time always
/// increases strictly (1 microsecond; real increments are tens of milliseconds).
pub const MIN_INCREMENT: f64 = 1e-6;

/// Cumulative playback times of the `T` aligned frames of one sequence:
///
/// `t_0 = 0`, `t_k = t_{k-1} + max(dt_{k-1}, MIN_INCREMENT)` for `k in 1..T`,
///
/// where `dt_k` is the increment from aligned frame `k` to `k + 1`. The last increment (from frame
/// `T - 1` onwards) is not used: it is 0 in aligned data. [`TimeTable::phase_at`] inverts the table.
/// A sum that would overflow saturates at `f64::MAX` (increments near `1e308`, which no data have),
/// so every time is finite.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TimeTable {
    times: Vec<f64>,
}

impl TimeTable {
    /// An empty table.
    pub fn new() -> Self {
        Self::default()
    }

    /// An empty table with room for `frames` entries, so that [`TimeTable::fill_from`] with up to
    /// that many increments does not allocate.
    pub fn with_capacity(frames: usize) -> Self {
        Self {
            times: Vec::with_capacity(frames),
        }
    }

    /// A table from the `T` increments of one aligned sequence.
    pub fn from_increments(increments: &[f64]) -> Self {
        let mut table = Self::with_capacity(increments.len());
        table.fill_from(increments);
        table
    }

    /// Refills the table from `T` increments, reusing its buffer (no allocation when the capacity
    /// suffices). Clamps each used increment to at least [`MIN_INCREMENT`].
    pub fn fill_from(&mut self, increments: &[f64]) {
        self.fill_from_iter(increments.iter().copied());
    }

    /// As [`TimeTable::fill_from`] from any sequence of increments (for example a strided column).
    pub fn fill_from_iter<I: IntoIterator<Item = f64>>(&mut self, increments: I) {
        self.times.clear();
        let mut t = 0.0;
        let mut pending: Option<f64> = None;
        for dt in increments {
            if let Some(prev) = pending {
                // (`min` is the identity for every finite sum: the same bits.)
                t = (t + clamp_increment(prev)).min(f64::MAX);
            }
            self.times.push(t);
            pending = Some(dt);
        }
    }

    /// As [`TimeTable::fill_from_iter`] of the increments `scale * increments[k]`, written in
    /// place (the same additions, the same bits; the kernel's per-clip table, without a push per
    /// entry).
    pub(crate) fn fill_scaled(&mut self, increments: &[f64], scale: f64) {
        self.times.resize(increments.len(), 0.0);
        let mut t = 0.0;
        for (out, &dt) in self.times.iter_mut().zip(increments) {
            *out = t;
            t += clamp_increment(scale * dt);
        }
    }

    /// Empties the table (keeping its buffer).
    pub(crate) fn clear(&mut self) {
        self.times.clear();
    }

    /// Number of entries `T`.
    pub fn len(&self) -> usize {
        self.times.len()
    }

    /// Whether the table is empty.
    pub fn is_empty(&self) -> bool {
        self.times.is_empty()
    }

    /// The cumulative times `t_k` in seconds.
    pub fn times(&self) -> &[f64] {
        &self.times
    }

    /// Duration `t_{T-1}` in seconds (0 for an empty table).
    pub fn duration(&self) -> f64 {
        self.times.last().copied().unwrap_or(0.0)
    }

    /// Fractional aligned frame `phi` in `[0, T - 1]` at playback time `t` seconds (clamped to
    /// `[0, duration]`; NaN gives 0): with `t_k <= t < t_{k+1}` found by binary search,
    /// `phi = k + (t - t_k) / (t_{k+1} - t_k)`. Returns 0 for tables of fewer than two entries.
    pub fn phase_at(&self, t: f64) -> f64 {
        let n = self.times.len();
        if n < 2 {
            return 0.0;
        }
        let t = t.max(0.0).min(self.duration());
        let k = self.times.partition_point(|&x| x <= t).clamp(1, n - 1) - 1;
        let (t0, t1) = (self.times[k], self.times[k + 1]);
        k as f64 + interval_fraction(t, t0, t1)
    }

    /// Playback time in seconds at fractional aligned frame `phi` (clamped to `[0, T - 1]`), the
    /// inverse of [`TimeTable::phase_at`]: `t = t_k + f (t_{k+1} - t_k)` with `k + f = phi`.
    pub fn time_at(&self, phase: f64) -> f64 {
        let n = self.times.len();
        if n < 2 {
            return 0.0;
        }
        let (k, f) = split_phase(phase, n);
        if f == 0.0 {
            self.times[k]
        } else {
            let (t0, t1) = (self.times[k], self.times[k + 1]);
            let step = t1 - t0;
            // (A step that overflows, between times near `f64::MAX` of a hand-filled table: the
            // interval's end, as the saturated table has it.)
            if step.is_finite() { t0 + f * step } else { t1 }
        }
    }
}

/// Splits a fractional frame position into `(k, f)` with `k + f = phase` clamped to
/// `[0, frames - 1]`, `0 <= f < 1` and `k + 1 < frames` whenever `f > 0` (NaN gives `(0, 0)`).
/// The rule by which [`TimeTable::time_at`] (and the offline crates' resampling) interpolate
/// between frames. `frames = 0` (no frame to land on) is read as 1: the result is `(0, 0)`.
pub fn split_phase(phase: f64, frames: usize) -> (usize, f64) {
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

/// Where `t` lies in the interval `[t0, t1]` of a table, in `[0, 1]`: `(t - t0) / (t1 - t0)`,
/// clamped. An interval of length zero (times that no longer grow, near `f64::MAX`) gives 1 when
/// `t` is at or past its end, else 0, instead of NaN. The same bits as the
/// plain quotient wherever that is a number.
#[inline]
pub(crate) fn interval_fraction(t: f64, t0: f64, t1: f64) -> f64 {
    let f = ((t - t0) / (t1 - t0)).clamp(0.0, 1.0);
    if f.is_nan() {
        if t >= t1 { 1.0 } else { 0.0 }
    } else {
        f
    }
}

#[inline]
fn clamp_increment(dt: f64) -> f64 {
    if dt.is_finite() && dt >= MIN_INCREMENT {
        dt
    } else {
        MIN_INCREMENT
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scaled_fill_equals_the_iterator_fill_bitwise() {
        // Ordinary increments, ones below the minimum, zero, negative and non-finite ones, and
        // tables of 0, 1 and 2 entries.
        let incs: Vec<f64> = (0..40)
            .map(|k| match k % 9 {
                0 => 1e-9,
                1 => -0.01,
                2 => f64::NAN,
                3 => f64::INFINITY,
                4 => 0.0,
                _ => 0.031 + 0.0007 * k as f64,
            })
            .collect();
        for n in [0, 1, 2, 9, 40] {
            for scale in [1.0, 1.0 / 1.37, 3.0] {
                let mut want = TimeTable::default();
                want.fill_from_iter(incs[..n].iter().map(|&d| scale * d));
                let mut got = TimeTable::default();
                // From a table of another length.
                got.fill_from(&[0.5; 7]);
                got.fill_scaled(&incs[..n], scale);
                let bits =
                    |t: &TimeTable| t.times().iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&got), bits(&want), "{n} entries, scale {scale}");
            }
        }
    }
}
