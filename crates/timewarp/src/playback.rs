//! Playback: an aligned sequence with a time-increment column turned back into frames at a fixed
//! output rate (the inverse timewarp of the paper's section 3.1).

use crate::error::TimewarpError;
use crate::frame_seq::{FrameSeq, split_position};

/// Smallest time increment, in seconds, that playback accepts: an increment that is smaller than
/// this, negative, NaN or infinite is replaced by it, so that playback time always increases
/// strictly (1 microsecond; real increments are tens of milliseconds). The runtime's clip time
/// tables use the same bound (`lod_policy::MIN_INCREMENT`; a test checks they agree).
pub const MIN_INCREMENT: f64 = 1e-6;

/// Fills `times` with the cumulative playback times of `T` increments (the incremental inverse
/// timewarp of the paper's section 3.1):
///
/// `t_0 = 0`, `t_k = t_{k-1} + max(dt_{k-1}, MIN_INCREMENT)` for `k in 1..T`,
///
/// where `dt_k` is the increment from aligned frame `k` to `k + 1`; the last increment is not used
/// (it is 0 in aligned data). Reuses the buffer.
pub fn fill_times(times: &mut Vec<f64>, increments: impl IntoIterator<Item = f64>) {
    times.clear();
    let mut t = 0.0;
    let mut pending: Option<f64> = None;
    for dt in increments {
        if let Some(prev) = pending {
            t += if prev.is_finite() && prev >= MIN_INCREMENT {
                prev
            } else {
                MIN_INCREMENT
            };
        }
        times.push(t);
        pending = Some(dt);
    }
}

/// Fractional aligned frame `phi` in `[0, T - 1]` at playback time `t` seconds for the cumulative
/// `times` of [`fill_times`] (`t` clamped to `[0, duration]`; NaN gives 0): with
/// `t_k <= t < t_{k+1}` found by binary search, `phi = k + (t - t_k) / (t_{k+1} - t_k)`. 0 for
/// fewer than two entries.
pub fn phase_at(times: &[f64], t: f64) -> f64 {
    let n = times.len();
    if n < 2 {
        return 0.0;
    }
    let t = t.max(0.0).min(times[n - 1]);
    let k = times.partition_point(|&x| x <= t).clamp(1, n - 1) - 1;
    let (t0, t1) = (times[k], times[k + 1]);
    let f = ((t - t0) / (t1 - t0)).clamp(0.0, 1.0);
    k as f64 + f
}

/// Frames of `aligned` at times `m / fps`, `m = 0, 1, ...` up to its duration, with the increment
/// column dropped (see [`playback_into`] for the formulas).
///
/// Errors: an empty, ragged or non-finite sequence, fewer than two columns, `increment_col >= dim`,
/// or an `fps` that is not
/// finite and positive.
pub fn playback(
    aligned: &FrameSeq,
    increment_col: usize,
    fps: f64,
) -> Result<FrameSeq, TimewarpError> {
    let mut times = Vec::with_capacity(aligned.len());
    let mut out = FrameSeq::zeros(1, 0);
    playback_into(aligned, increment_col, fps, &mut times, &mut out)?;
    Ok(out)
}

/// [`playback`] into caller-owned buffers (`out` is resized; no allocation once its capacity and
/// that of `times` suffice).
///
/// `times` is filled from the increment column ([`fill_times`]), the number of output frames
/// is `floor(duration * fps) + 1` (with a relative tolerance of 1e-9 so that a duration that is a
/// whole number of output periods includes its last frame), and output frame `m` is `aligned`
/// linearly interpolated at phase [`phase_at`]`(m / fps)`, without the increment column.
pub fn playback_into(
    aligned: &FrameSeq,
    increment_col: usize,
    fps: f64,
    times: &mut Vec<f64>,
    out: &mut FrameSeq,
) -> Result<(), TimewarpError> {
    aligned.check(0, 1)?;
    if aligned.dim < 2 {
        return Err(TimewarpError::InvalidConfig {
            what: "dim",
            value: aligned.dim.to_string(),
            reason: "playback needs a value column besides the increment column",
        });
    }
    if increment_col >= aligned.dim {
        return Err(TimewarpError::InvalidConfig {
            what: "increment_col",
            value: increment_col.to_string(),
            reason: "must be a column of the aligned sequence",
        });
    }
    if !fps.is_finite() || fps <= 0.0 {
        return Err(TimewarpError::InvalidConfig {
            what: "fps",
            value: fps.to_string(),
            reason: "must be finite and positive",
        });
    }
    let dim = aligned.dim;
    let n = aligned.len();
    fill_times(
        times,
        (0..n).map(|k| aligned.frames[k * dim + increment_col]),
    );
    let duration = times.last().copied().unwrap_or(0.0);
    let steps = duration * fps;
    let count = (steps * (1.0 + 1e-9) + 1e-9).floor() as usize + 1;
    out.dim = dim - 1;
    out.frames.clear();
    out.frames.resize(count * (dim - 1), 0.0);
    for m in 0..count {
        let t = (m as f64 / fps).min(duration);
        let (k, f) = split_position(phase_at(times, t), n);
        let a = aligned.frame(k);
        let row = out.frame_mut(m);
        let values = a
            .iter()
            .enumerate()
            .filter(|&(c, _)| c != increment_col)
            .map(|(_, &x)| x);
        if f == 0.0 {
            for (o, x) in row.iter_mut().zip(values) {
                *o = x;
            }
        } else {
            let b = aligned
                .frame(k + 1)
                .iter()
                .enumerate()
                .filter(|&(c, _)| c != increment_col)
                .map(|(_, &y)| y);
            for ((o, x), y) in row.iter_mut().zip(values).zip(b) {
                *o = x + f * (y - x);
            }
        }
    }
    Ok(())
}
