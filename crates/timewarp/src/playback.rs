//! Playback: an aligned sequence with a time-increment column turned back into frames at a fixed
//! output rate (the inverse timewarp of the paper's section 3.1).

use crate::error::TimewarpError;
use crate::frame_seq::FrameSeq;
use lod_policy::time_table::TimeTable;

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
    let mut table = TimeTable::with_capacity(aligned.len());
    let mut out = FrameSeq::zeros(1, 0);
    playback_into(aligned, increment_col, fps, &mut table, &mut out)?;
    Ok(out)
}

/// [`playback`] into caller-owned buffers (`out` is resized; no allocation once its capacity and
/// the table's suffice).
///
/// The table is filled from the increment column (see [`TimeTable`]), the number of output frames
/// is `floor(duration * fps) + 1` (with a relative tolerance of 1e-9 so that a duration that is a
/// whole number of output periods includes its last frame), and output frame `m` is `aligned`
/// linearly interpolated at phase `phase_at(m / fps)`, without the increment column.
pub fn playback_into(
    aligned: &FrameSeq,
    increment_col: usize,
    fps: f64,
    table: &mut TimeTable,
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
    table.fill_from_iter((0..n).map(|k| aligned.frames[k * dim + increment_col]));
    let duration = table.duration();
    let steps = duration * fps;
    let count = (steps * (1.0 + 1e-9) + 1e-9).floor() as usize + 1;
    out.dim = dim - 1;
    out.frames.clear();
    out.frames.resize(count * (dim - 1), 0.0);
    for m in 0..count {
        let t = (m as f64 / fps).min(duration);
        let (k, f) = crate::frame_seq::split_position(table.phase_at(t), n);
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
