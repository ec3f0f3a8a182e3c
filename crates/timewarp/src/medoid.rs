//! Choice of the reference sequence: the medoid under the DTW cost.
//!
//! The exact medoid `argmin_r sum_{s != r} DTW(x_r, x_s)` needs `S (S - 1)` DTWs, which is too slow
//! for `S ~ 800`. When there are more sequences than `candidates`, the candidates are first narrowed
//! with the uniform-resample distance: every sequence is resampled linearly to `L` frames (`L` = the
//! median length) and, since `sum_s ||u_r - u_s||^2 = S ||u_r - mean||^2 + const`, the medoid under
//! that distance is the sequence nearest to the mean. The `candidates` sequences nearest to the mean
//! are then ranked by their exact summed DTW cost to all others (`candidates x (S - 1)` DTWs, run in
//! parallel). With `S <= candidates` the result is the exact DTW medoid.

use rayon::prelude::*;

use crate::dtw::{DtwConfig, DtwWorkspace, dtw_cost_unchecked};
use crate::error::TimewarpError;
use crate::frame_seq::{FrameSeq, squared_distance};

/// Number of candidates [`medoid`] scores with exact DTW sums.
pub const DEFAULT_MEDOID_CANDIDATES: usize = 24;

/// Index of the reference sequence: the medoid under the summed DTW cost, exact for up to
/// [`DEFAULT_MEDOID_CANDIDATES`] sequences, preselected by the uniform-resample distance above that
/// (see the module documentation). Ties go to the smaller index.
///
/// Errors: no sequences, empty, ragged or non-finite sequences, different dimensions, an invalid
/// band, or [`TimewarpError::Pair`] when no candidate has a warping path to every other sequence
/// (its source is [`TimewarpError::NoPath`], or [`TimewarpError::NonFiniteCost`] when the costs
/// overflow) or when a DTW table exceeds the size limit ([`TimewarpError::TooLarge`]).
pub fn medoid(features: &[FrameSeq], config: &DtwConfig) -> Result<usize, TimewarpError> {
    medoid_with_candidates(features, config, DEFAULT_MEDOID_CANDIDATES)
}

/// [`medoid`] with an explicit number of DTW-scored candidates (at least 1).
pub fn medoid_with_candidates(
    features: &[FrameSeq],
    config: &DtwConfig,
    candidates: usize,
) -> Result<usize, TimewarpError> {
    config.validate()?;
    if candidates == 0 {
        return Err(TimewarpError::InvalidConfig {
            what: "candidates",
            value: "0".into(),
            reason: "must be at least 1",
        });
    }
    check_set(features, 1)?;
    let count = features.len();
    if count == 1 {
        return Ok(0);
    }
    let mut chosen: Vec<usize> = if count <= candidates {
        (0..count).collect()
    } else {
        let mut ranked = rank_by_uniform_distance(features);
        ranked.truncate(candidates);
        ranked.sort_unstable();
        ranked
    };
    chosen.dedup();
    let pair = |index: usize, reference: usize, e: TimewarpError| TimewarpError::Pair {
        index,
        reference,
        source: Box::new(e),
    };
    let sums: Vec<Result<f64, TimewarpError>> = chosen
        .par_iter()
        .map_init(DtwWorkspace::new, |ws, &r| {
            let mut sum = 0.0;
            for (s, seq) in features.iter().enumerate() {
                if s == r {
                    continue;
                }
                let c =
                    dtw_cost_unchecked(&features[r], seq, config, ws).map_err(|e| pair(s, r, e))?;
                sum += c;
                if !sum.is_finite() {
                    // Finite costs whose sum overflows: the values are too large.
                    return Err(pair(
                        s,
                        r,
                        TimewarpError::NonFiniteCost {
                            len_a: features[r].len(),
                            len_b: seq.len(),
                        },
                    ));
                }
            }
            Ok(sum)
        })
        .collect();
    // A table over the size limit is no property of one candidate: report it.
    if let Some(Err(e)) = sums.iter().find(|res| {
        matches!(res, Err(TimewarpError::Pair { source, .. })
            if matches!(**source, TimewarpError::TooLarge { .. }))
    }) {
        return Err(e.clone());
    }
    let mut best: Option<(usize, f64)> = None;
    for (&r, res) in chosen.iter().zip(&sums) {
        if let Ok(sum) = *res
            && best.is_none_or(|(_, b)| sum < b)
        {
            best = Some((r, sum));
        }
    }
    match best {
        Some((r, _)) => Ok(r),
        // No candidate has a finite summed cost: the first candidate's failure.
        None => match sums.into_iter().next() {
            Some(Err(e)) => Err(e),
            _ => Err(TimewarpError::NoSequences),
        },
    }
}

/// Index of the sequence nearest to the mean of all sequences uniformly resampled to the median
/// length: the medoid under the uniform-resample distance
/// `D(r, s) = sum_k ||x_r(k (n_r - 1)/(L - 1)) - x_s(k (n_s - 1)/(L - 1))||^2`.
///
/// Errors: as [`medoid`], except for the DTW ones.
pub fn uniform_medoid(features: &[FrameSeq]) -> Result<usize, TimewarpError> {
    check_set(features, 1)?;
    Ok(rank_by_uniform_distance(features)[0])
}

/// Median number of frames of the sequences (the lower median for an even count); 0 when empty.
pub fn median_length(seqs: &[FrameSeq]) -> usize {
    let mut lens: Vec<usize> = seqs.iter().map(FrameSeq::len).collect();
    if lens.is_empty() {
        return 0;
    }
    lens.sort_unstable();
    lens[(lens.len() - 1) / 2]
}

/// Checks a non-empty set of sequences with one frame dimension, each at least `min_frames` long.
pub(crate) fn check_set(seqs: &[FrameSeq], min_frames: usize) -> Result<(), TimewarpError> {
    let first = seqs.first().ok_or(TimewarpError::NoSequences)?;
    for (index, seq) in seqs.iter().enumerate() {
        seq.check(index, min_frames)?;
        if seq.dim != first.dim {
            return Err(TimewarpError::DimMismatch {
                index,
                expected: first.dim,
                found: seq.dim,
            });
        }
    }
    Ok(())
}

/// Sequence indices ordered by the distance of their uniform resampling to the mean resampling
/// (ties by index).
fn rank_by_uniform_distance(features: &[FrameSeq]) -> Vec<usize> {
    let len = median_length(features).max(1);
    let dim = features[0].dim;
    let resampled: Vec<Vec<f64>> = features
        .par_iter()
        .map(|seq| resample_uniform(seq, len))
        .collect();
    let mut mean = vec![0.0; len * dim];
    for r in &resampled {
        for (m, v) in mean.iter_mut().zip(r) {
            *m += v;
        }
    }
    let inv = 1.0 / features.len() as f64;
    mean.iter_mut().for_each(|m| *m *= inv);
    let dist: Vec<f64> = resampled
        .iter()
        .map(|r| squared_distance(r, &mean))
        .collect();
    let mut order: Vec<usize> = (0..features.len()).collect();
    order.sort_by(|&a, &b| dist[a].total_cmp(&dist[b]).then(a.cmp(&b)));
    order
}

/// `seq` linearly resampled to `len` frames at positions `k (n - 1) / (len - 1)`, row-major.
pub(crate) fn resample_uniform(seq: &FrameSeq, len: usize) -> Vec<f64> {
    let n = seq.len();
    let mut out = vec![0.0; len * seq.dim];
    let step = if len > 1 {
        (n - 1) as f64 / (len - 1) as f64
    } else {
        0.0
    };
    for (k, frame) in out.chunks_exact_mut(seq.dim).enumerate() {
        seq.sample_at(k as f64 * step, frame);
    }
    out
}
