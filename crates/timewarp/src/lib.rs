//! Dynamic time warping and the incremental inverse timewarp.
//!
//! This crate is for: aligning many frame sequences to a reference at a fixed number of frames, and
//! playing an aligned sequence back at any frame rate through its time-increment channel. It works on
//! plain feature and value sequences. It is not for: reading motion files or computing pose features
//! (see `motion-io`).
//!
//! The pieces, in pipeline order (Mukai and Kuriyama, section 3.1):
//! - [`dtw`]: dynamic time warping with a Sakoe-Chiba band and a slope limit over the squared
//!   Euclidean distance between feature frames (Kovar and Gleicher's point-cloud distance when the
//!   features are joint positions in the root frame, without their rigid fit).
//! - [`medoid`]: the reference sequence (smallest summed DTW cost to all others; preselected with a
//!   uniform-resample distance when there are many sequences).
//! - [`align`]: every sequence mapped onto the reference's time at `T` frames by DTW or by uniform
//!   scaling ([`AlignMethod`]), values resampled by linear interpolation, plus one column of time
//!   increments in seconds that sum to each sequence's true duration.
//! - [`fill_times`], [`phase_at`] and [`playback`]: a (synthesized) aligned sequence back to frames
//!   at any rate through the cumulative times of its increment column.
//!
//! ```
//! use timewarp::{AlignConfig, AlignMethod, DtwConfig, FrameSeq, align, playback};
//!
//! // Two 1-D "cycles" with the same shape and different timing, sampled at 30 fps.
//! let slow: Vec<f64> = (0..41).map(|i| (i as f64 / 40.0 * 6.283).sin()).collect();
//! let fast: Vec<f64> = (0..31).map(|i| (i as f64 / 30.0 * 6.283).sin()).collect();
//! let seqs = vec![FrameSeq::new(1, slow)?, FrameSeq::new(1, fast)?];
//! let config = AlignConfig::new(35, AlignMethod::Dtw(DtwConfig::default()));
//! let al = align(&seqs, &seqs, &[1.0 / 30.0; 2], &config)?;
//! assert_eq!(al.aligned[1].len(), 35);
//! // The increment column sums to the true duration: 30 frames at 30 fps.
//! let total: f64 = (0..35).map(|k| al.aligned[1].frame(k)[al.increment_col]).sum();
//! assert!((total - 1.0).abs() < 1e-9);
//! // Back to 60 fps: 61 frames over one second.
//! let poses = playback(&al.aligned[1], al.increment_col, 60.0)?;
//! assert_eq!(poses.len(), 61);
//! # Ok::<(), timewarp::TimewarpError>(())
//! ```

#![warn(missing_docs)]

mod align;
mod dtw;
mod error;
mod frame_seq;
mod medoid;
mod playback;

pub use align::{AlignConfig, AlignMethod, Alignment, MAX_ALIGN_FRAMES, align};
pub use dtw::{DtwConfig, DtwWorkspace, WarpPath, dtw, dtw_cost_with, dtw_with};
pub use error::TimewarpError;
pub use frame_seq::{FrameSeq, MAX_BUFFER_VALUES};
pub use medoid::{
    DEFAULT_MEDOID_CANDIDATES, median_length, medoid, medoid_with_candidates, uniform_medoid,
};
pub use playback::{
    MAX_PLAYBACK_FRAMES, MIN_INCREMENT, fill_times, phase_at, playback, playback_into,
};
