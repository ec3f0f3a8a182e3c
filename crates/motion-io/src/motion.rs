//! A skeleton with its frames of channel values.

use serde::{Deserialize, Serialize};

use crate::skeleton::Skeleton;

/// A take: a skeleton and its frames (row-major, `frames x channel_count`), Euler channel values
/// in degrees and positions in file units, as in the BVH file.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Motion {
    /// The hierarchy.
    pub skeleton: Skeleton,
    /// Seconds between frames.
    pub frame_time: f64,
    /// Channel values, `frame_count() * skeleton.channel_count()` of them, one frame after another.
    pub frames: Vec<f64>,
}

impl Motion {
    /// Number of frames (`frames.len() / channel_count`, 0 when the skeleton has no channel).
    pub fn frame_count(&self) -> usize {
        let n = self.skeleton.channel_count();
        self.frames.len().checked_div(n).unwrap_or(0)
    }

    /// The channel values of frame `i`.
    ///
    /// # Panics
    /// If `i >= self.frame_count()`.
    pub fn frame(&self, i: usize) -> &[f64] {
        let n = self.skeleton.channel_count();
        &self.frames[i * n..(i + 1) * n]
    }

    /// Mutable channel values of frame `i`.
    ///
    /// # Panics
    /// If `i >= self.frame_count()`.
    pub fn frame_mut(&mut self, i: usize) -> &mut [f64] {
        let n = self.skeleton.channel_count();
        &mut self.frames[i * n..(i + 1) * n]
    }

    /// Frames per second (`1 / frame_time`).
    pub fn fps(&self) -> f64 {
        1.0 / self.frame_time
    }

    /// Duration in seconds (`frame_count * frame_time`).
    pub fn duration(&self) -> f64 {
        self.frame_count() as f64 * self.frame_time
    }
}
