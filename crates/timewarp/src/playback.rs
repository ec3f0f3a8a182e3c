//! Playback: an aligned sequence with a time-increment column turned back into frames at a fixed
//! output rate (the inverse timewarp of the paper's section 3.1).

use crate::error::TimewarpError;
use crate::frame_seq::{FrameSeq, check_buffer, split_position};

/// Smallest time increment, in seconds, that playback accepts: an increment that is smaller than
/// this, negative, NaN or infinite is replaced by it, so that playback time always increases
/// strictly (1 microsecond; real increments are tens of milliseconds). The runtime's clip time
/// tables use the same bound (`lod_policy::MIN_INCREMENT`; a test checks they agree).
pub const MIN_INCREMENT: f64 = 1e-6;

/// Most output frames [`playback`] produces: `100_000_000` (over 230 hours at 120 fps). A
/// duration and rate that ask for more are refused with [`TimewarpError::TooLarge`] instead of
/// attempting the allocation.
pub const MAX_PLAYBACK_FRAMES: usize = 100_000_000;

/// Fills `times` with the cumulative playback times of `T` increments (the incremental inverse
/// timewarp of the paper's section 3.1):
///
/// `t_0 = 0`, `t_k = t_{k-1} + max(dt_{k-1}, MIN_INCREMENT)` for `k in 1..T`,
///
/// where `dt_k` is the increment from aligned frame `k` to `k + 1`; the last increment is not used
/// (it is 0 in aligned data). Reuses the buffer.
///
/// The times increase strictly as long as every added increment survives the rounding of the sum
/// (real durations: `MIN_INCREMENT` is absorbed only from about `1e10` s on); increments so large
/// that the sum absorbs the next ones (e.g. `[1e300, 1e-3, 1e-3, 0]`) or overflows it to infinity
/// give repeated or infinite times. This is the runtime's rule to the bit, so it is kept as is;
/// [`playback`] checks the times and reports such increments as
/// [`TimewarpError::PlaybackTimes`].
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
///
/// `times` must be finite and strictly increasing, as [`fill_times`] makes them for increments
/// of real durations; for repeated or infinite times (see [`fill_times`]) the result may be NaN.
/// This is the runtime's rule to the bit (`lod_policy::TimeTable::phase_at`), so it is not
/// changed; [`playback`] checks the times first.
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
/// an `fps` that is not finite and positive, increments whose cumulative times are not finite or
/// not strictly increasing ([`TimewarpError::PlaybackTimes`]), or more than
/// [`MAX_PLAYBACK_FRAMES`] output frames or [`MAX_BUFFER_VALUES`](crate::MAX_BUFFER_VALUES)
/// output values ([`TimewarpError::TooLarge`]).
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
/// that of `times` suffice). Errors as [`playback`]; on error `out` is left unchanged.
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
    // Increments that overflow the sum or are absorbed by it (see `fill_times`).
    if let Some(frame) =
        (0..times.len()).find(|&k| !times[k].is_finite() || (k > 0 && times[k] <= times[k - 1]))
    {
        return Err(TimewarpError::PlaybackTimes {
            frame,
            time: times[frame],
        });
    }
    let duration = times.last().copied().unwrap_or(0.0);
    let steps = duration * fps;
    let whole = (steps * (1.0 + 1e-9) + 1e-9).floor();
    // `whole + 1` frames (`steps` is in `[0, inf]`, so `whole` is never NaN).
    if whole >= MAX_PLAYBACK_FRAMES as f64 {
        return Err(TimewarpError::TooLarge {
            what: "playback frames (floor(duration * fps) + 1)",
            requested: format!("{:e}", whole + 1.0),
            limit: MAX_PLAYBACK_FRAMES,
        });
    }
    let count = whole as usize + 1;
    let len = check_buffer(
        "playback output values (frames x (dim - 1))",
        &[count, dim - 1],
    )?;
    out.dim = dim - 1;
    out.frames.clear();
    out.frames.resize(len, 0.0);
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
