//! Alignment of many sequences to a reference at `T` frames, with the incremental inverse timewarp
//! channel (the paper's section 3.1, after Park et al., reference [22]).
//!
//! For each sequence `s` (`n_s` frames, `frame_time_s` seconds per frame) a monotone time map
//! `u_s: [0, n_r - 1] -> [0, n_s - 1]` from reference frames to fractional source frames is built,
//! with `u_s(0) = 0` and `u_s(n_r - 1) = n_s - 1`:
//! - [`AlignMethod::Uniform`]: `u_s(x) = x (n_s - 1) / (n_r - 1)` (uniform time scaling; it does
//!   not depend on the reference).
//! - [`AlignMethod::Dtw`]: from the DTW path between the reference and `s` (features): each
//!   reference frame `i` gets the mean `jbar_i` of the source frames matched to it; every maximal run
//!   of equal `jbar` becomes one knot `(mean i of the run, jbar)`, the end knots are pinned to
//!   `(0, 0)` and `(n_r - 1, n_s - 1)`, and `u_s` is the piecewise-linear curve through the knots,
//!   strictly increasing by construction.
//!
//! Aligned frame `k in 0..T` sits at reference time `x_k = k (n_r - 1) / (T - 1)` and source time
//! `u_k = u_s(x_k)`. Its values are the source values linearly interpolated at `u_k` (the caller
//! keeps exponential maps continuous, so linear interpolation is adequate), and its time increment is
//!
//! `dt_k = (u_{k+1} - u_k) frame_time_s` for `k < T - 1`, `dt_{T-1} = 0`,
//!
//! so `sum_k dt_k = (n_s - 1) frame_time_s`, the sequence's true duration. The increment is the
//! column `increment_col` of each aligned frame (appended last unless
//! [`AlignConfig::increment_row`] asks for another position, e.g. row 6 of the pose vector).

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::dtw::{DtwConfig, WarpPath, dtw};
use crate::error::TimewarpError;
use crate::frame_seq::{FrameSeq, check_buffer};
use crate::medoid::{check_set, median_length, medoid, uniform_medoid};

/// Most aligned frames `T` that [`align`] accepts (`1_000_000`: over nine hours at 30 fps for one
/// sequence; the usual `T` is a median clip length of tens to hundreds of frames). Larger values
/// are refused with [`TimewarpError::InvalidConfig`] instead of attempting the allocation.
pub const MAX_ALIGN_FRAMES: usize = 1_000_000;

/// How each sequence's time is mapped onto the reference's.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum AlignMethod {
    /// Dynamic time warping of the features against the reference.
    Dtw(DtwConfig),
    /// Uniform time scaling between the first and the last frame.
    Uniform,
}

/// Parameters of [`align`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AlignConfig {
    /// Number of aligned frames `T` (at least 2, at most [`MAX_ALIGN_FRAMES`]). The usual choice
    /// is the median sequence length, see [`AlignConfig::for_data`] and [`median_length`].
    pub frames: usize,
    /// Time mapping method.
    pub method: AlignMethod,
    /// Reference sequence; `None` picks the medoid ([`medoid`] for DTW, [`uniform_medoid`] for
    /// uniform scaling).
    pub reference: Option<usize>,
    /// Column of the time increment in each aligned frame: `None` appends it after the values
    /// (column `values dim`); `Some(r)` inserts it before value column `r` (`r <= values dim`), so
    /// that `Some(6)` yields the pose-vector layout of `docs/architecture.md`.
    pub increment_row: Option<usize>,
}

impl AlignConfig {
    /// `T` frames with `method`, the medoid as reference, the increment appended.
    pub fn new(frames: usize, method: AlignMethod) -> Self {
        Self {
            frames,
            method,
            reference: None,
            increment_row: None,
        }
    }

    /// As [`AlignConfig::new`] with `T` = the median length of `features` (at least 2).
    pub fn for_data(features: &[FrameSeq], method: AlignMethod) -> Self {
        Self::new(median_length(features).max(2), method)
    }
}

/// The result of [`align`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Alignment {
    /// Index of the reference sequence.
    pub reference: usize,
    /// Number of aligned frames `T`.
    pub frames: usize,
    /// Column of the time increment (seconds) in every aligned frame.
    pub increment_col: usize,
    /// One sequence per input, each `T` frames of `values dim + 1` columns.
    pub aligned: Vec<FrameSeq>,
    /// For each input, the fractional source frame `u_k` of each aligned frame (`T` values).
    pub source_frames: Vec<Vec<f64>>,
}

/// Aligns every sequence to a reference at `config.frames` frames (see the module documentation).
///
/// `features[s]` drives the time map (DTW); `values[s]` (same number of frames) is resampled;
/// `frame_time[s]` is the source frame period in seconds. Sequences are processed in parallel;
/// the result does not depend on the thread count.
///
/// Errors: empty input, mismatched counts, dimensions or frame counts, sequences shorter than two
/// frames, NaN or infinite values, a non-positive frame time, a duration `(n_s - 1) frame_time_s`
/// that overflows ([`TimewarpError::DurationOverflow`]), `frames < 2` or above
/// [`MAX_ALIGN_FRAMES`], an output of more than [`MAX_BUFFER_VALUES`](crate::MAX_BUFFER_VALUES)
/// values in all ([`TimewarpError::TooLarge`]), a reference or increment row out of range, or a
/// DTW failure ([`TimewarpError::Pair`]).
pub fn align(
    features: &[FrameSeq],
    values: &[FrameSeq],
    frame_time: &[f64],
    config: &AlignConfig,
) -> Result<Alignment, TimewarpError> {
    let count = features.len();
    if values.len() != count {
        return Err(TimewarpError::CountMismatch {
            features: count,
            values: values.len(),
        });
    }
    if frame_time.len() != count {
        return Err(TimewarpError::CountMismatch {
            features: count,
            values: frame_time.len(),
        });
    }
    check_set(features, 2)?;
    check_set(values, 2)?;
    for (index, (f, v)) in features.iter().zip(values).enumerate() {
        if f.len() != v.len() {
            return Err(TimewarpError::FrameCountMismatch {
                index,
                features: f.len(),
                values: v.len(),
            });
        }
    }
    if let Some(index) = frame_time.iter().position(|t| !t.is_finite() || *t <= 0.0) {
        return Err(TimewarpError::BadFrameTime {
            index,
            value: frame_time[index],
        });
    }
    for (index, (v, &ft)) in values.iter().zip(frame_time).enumerate() {
        // The increments sum to this duration; each is at most it.
        if !((v.len() - 1) as f64 * ft).is_finite() {
            return Err(TimewarpError::DurationOverflow {
                index,
                frames: v.len(),
                frame_time: ft,
            });
        }
    }
    let t_frames = config.frames;
    if t_frames < 2 {
        return Err(TimewarpError::InvalidConfig {
            what: "frames",
            value: t_frames.to_string(),
            reason: "at least 2 aligned frames are needed",
        });
    }
    if t_frames > MAX_ALIGN_FRAMES {
        return Err(TimewarpError::InvalidConfig {
            what: "frames",
            value: t_frames.to_string(),
            reason: "at most MAX_ALIGN_FRAMES (1 000 000) aligned frames",
        });
    }
    let vdim = values[0].dim;
    let increment_col = config.increment_row.unwrap_or(vdim);
    if increment_col > vdim {
        return Err(TimewarpError::InvalidConfig {
            what: "increment_row",
            value: increment_col.to_string(),
            reason: "must not exceed the value dimension",
        });
    }
    check_buffer(
        "aligned values (sequences x frames x (values dim + 1))",
        &[count, t_frames, vdim + 1],
    )?;
    if let AlignMethod::Dtw(dtw_config) = &config.method {
        dtw_config.validate()?;
    }
    let reference = match config.reference {
        Some(r) if r >= count => {
            return Err(TimewarpError::ReferenceOutOfRange {
                reference: r,
                count,
            });
        }
        Some(r) => r,
        None => match &config.method {
            AlignMethod::Dtw(c) => medoid(features, c)?,
            AlignMethod::Uniform => uniform_medoid(features)?,
        },
    };
    let n_ref = features[reference].len();
    let maps: Vec<Vec<f64>> = (0..count)
        .into_par_iter()
        .map(|s| -> Result<Vec<f64>, TimewarpError> {
            let n_src = features[s].len();
            match &config.method {
                AlignMethod::Dtw(c) if s != reference => {
                    let path = dtw(&features[reference], &features[s], c).map_err(|e| {
                        TimewarpError::Pair {
                            index: s,
                            reference,
                            source: Box::new(e),
                        }
                    })?;
                    let knots = knots_from_path(&path, n_ref, n_src);
                    Ok(sample_map(&knots, n_ref, t_frames))
                }
                _ => Ok(uniform_map(n_src, t_frames)),
            }
        })
        .collect::<Result<_, _>>()?;
    let aligned = maps
        .par_iter()
        .zip(values.par_iter().zip(frame_time.par_iter()))
        .map(|(u, (v, &dt))| resample_with_increments(v, u, dt, increment_col))
        .collect();
    Ok(Alignment {
        reference,
        frames: t_frames,
        increment_col,
        aligned,
        source_frames: maps,
    })
}

/// `u_k = k (n - 1) / (T - 1)`: uniform time scaling onto `T` frames.
fn uniform_map(n: usize, t_frames: usize) -> Vec<f64> {
    let step = (n - 1) as f64 / (t_frames - 1) as f64;
    let mut u: Vec<f64> = (0..t_frames).map(|k| k as f64 * step).collect();
    u[t_frames - 1] = (n - 1) as f64;
    u
}

/// Strictly increasing knots `(x, y)` of the time map from a DTW path (see the module docs).
fn knots_from_path(path: &WarpPath, n_ref: usize, n_src: usize) -> Vec<(f64, f64)> {
    // Mean matched source frame per reference frame (the path visits every reference frame).
    let mut sum = vec![0.0; n_ref];
    let mut cnt = vec![0usize; n_ref];
    for &(i, j) in &path.pairs {
        sum[i] += j as f64;
        cnt[i] += 1;
    }
    let jbar: Vec<f64> = sum
        .iter()
        .zip(&cnt)
        .map(|(&s, &c)| s / c.max(1) as f64)
        .collect();
    let mut knots: Vec<(f64, f64)> = Vec::with_capacity(n_ref + 2);
    let mut start = 0;
    while start < n_ref {
        let mut end = start;
        while end + 1 < n_ref && jbar[end + 1] == jbar[start] {
            end += 1;
        }
        knots.push(((start + end) as f64 * 0.5, jbar[start]));
        start = end + 1;
    }
    let (x_end, y_end) = ((n_ref - 1) as f64, (n_src - 1) as f64);
    let first = knots[0];
    if first.0 == 0.0 {
        knots[0].1 = 0.0;
    } else if first.1 == 0.0 {
        knots[0].0 = 0.0;
    } else {
        knots.insert(0, (0.0, 0.0));
    }
    let last_idx = knots.len() - 1;
    let last = knots[last_idx];
    if last.0 == x_end {
        knots[last_idx].1 = y_end;
    } else if last.1 == y_end {
        knots[last_idx].0 = x_end;
    } else {
        knots.push((x_end, y_end));
    }
    debug_assert!(knots.windows(2).all(|w| w[0].0 < w[1].0 && w[0].1 < w[1].1));
    knots
}

/// The piecewise-linear map through `knots` at `x_k = k (n_ref - 1) / (T - 1)`, `k in 0..T`.
fn sample_map(knots: &[(f64, f64)], n_ref: usize, t_frames: usize) -> Vec<f64> {
    let step = (n_ref - 1) as f64 / (t_frames - 1) as f64;
    let mut seg = 0;
    let mut u = Vec::with_capacity(t_frames);
    for k in 0..t_frames {
        let x = if k + 1 == t_frames {
            (n_ref - 1) as f64
        } else {
            k as f64 * step
        };
        while seg + 2 < knots.len() && knots[seg + 1].0 <= x {
            seg += 1;
        }
        let (x0, y0) = knots[seg];
        let (x1, y1) = knots[seg + 1];
        let f = ((x - x0) / (x1 - x0)).clamp(0.0, 1.0);
        u.push(y0 + f * (y1 - y0));
    }
    u
}

/// Values of `v` at source frames `u`, with the time increment inserted at `increment_col`.
fn resample_with_increments(
    v: &FrameSeq,
    u: &[f64],
    frame_time: f64,
    increment_col: usize,
) -> FrameSeq {
    let vdim = v.dim;
    let dim = vdim + 1;
    let t_frames = u.len();
    let mut out = FrameSeq::zeros(dim, t_frames);
    let mut buf = vec![0.0; vdim];
    for k in 0..t_frames {
        v.sample_at(u[k], &mut buf);
        let dt = if k + 1 < t_frames {
            (u[k + 1] - u[k]) * frame_time
        } else {
            0.0
        };
        let row = out.frame_mut(k);
        row[..increment_col].copy_from_slice(&buf[..increment_col]);
        row[increment_col] = dt;
        row[increment_col + 1..].copy_from_slice(&buf[increment_col..]);
    }
    out
}
