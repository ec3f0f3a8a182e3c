//! Helpers shared by the integration tests: smooth synthetic signals and warps.
#![allow(dead_code)]

use timewarp::FrameSeq;

/// A smooth `dim`-dimensional closed curve at normalised time `s in [0, 1]`.
pub fn curve(s: f64, dim: usize, out: &mut [f64]) {
    let tau = std::f64::consts::TAU;
    for (c, o) in out.iter_mut().enumerate().take(dim) {
        let f = 1.0 + (c % 3) as f64;
        let p = 0.7 * c as f64;
        *o = (tau * f * s + p).sin() + 0.3 * (tau * (f + 1.0) * s - p).cos();
    }
}

/// `n` frames of the curve at times `warp(k / (n - 1))`.
pub fn warped(n: usize, dim: usize, warp: impl Fn(f64) -> f64) -> FrameSeq {
    let mut seq = FrameSeq::zeros(dim, n);
    for k in 0..n {
        let s = warp(k as f64 / (n - 1) as f64);
        curve(s, dim, seq.frame_mut(k));
    }
    seq
}

/// A monotone warp of `[0, 1]` onto itself: `s + a sin(pi s) sin(pi s / 2 + b)`-like, strictly
/// increasing for `|a| < 0.25`.
pub fn bump(a: f64) -> impl Fn(f64) -> f64 {
    move |s: f64| s + a * (std::f64::consts::PI * s).sin() / std::f64::consts::PI
}
