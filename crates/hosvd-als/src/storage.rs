//! Storage accounting in bytes, counted as the paper does (section 5.1).
//!
//! A Tucker model stores its core and its three factor matrices:
//! `bytes = (R_0 R_1 R_2 + I_0 R_0 + I_1 R_1 + I_2 R_2) * size_of(element)`. The hybrid model
//! stores every key level this way; storing every accuracy level by ALS stores each of them.
//! The paper's "13.34 MB for all motion samples" is `94 * 100 * 186 * 8` bytes in MiB
//! (2^20 bytes); [`mib`] converts.

use crate::{HybridLevel, KeyLevels};

/// Bytes of one Tucker model of `value_bytes`-byte elements (8 for f64, 4 for f32):
/// `(R_0 R_1 R_2 + sum_n I_n R_n) * value_bytes`, saturating at `usize::MAX` (no real model comes
/// near it; the byte counts of this module never wrap).
pub fn tucker_bytes(dims: [usize; 3], ranks: [usize; 3], value_bytes: usize) -> usize {
    let core = ranks[0].saturating_mul(ranks[1]).saturating_mul(ranks[2]);
    let factors = (0..3).fold(0usize, |acc, n| {
        acc.saturating_add(dims[n].saturating_mul(ranks[n]))
    });
    core.saturating_add(factors).saturating_mul(value_bytes)
}

/// Bytes of the hybrid model: every key level's core and factors (paper: "all key tensors and
/// basic matrices", 1.45 MB for N = 10 at 94 x 100 x 186).
pub fn key_levels_bytes(keys: &KeyLevels, value_bytes: usize) -> usize {
    keys.levels
        .iter()
        .map(|l| tucker_bytes(l.tucker.dims(), l.ranks, value_bytes))
        .fold(0, usize::saturating_add)
}

/// Bytes needed if every accuracy level were stored as its own ALS model (the paper's
/// "9.7 MB when all reduced core tensors are computed by ALS"), for data of shape `dims`.
pub fn all_levels_bytes(dims: [usize; 3], levels: &[HybridLevel], value_bytes: usize) -> usize {
    levels
        .iter()
        .map(|l| tucker_bytes(dims, l.ranks, value_bytes))
        .fold(0, usize::saturating_add)
}

/// Bytes of the dense data tensor `I_0 I_1 I_2 * value_bytes` (the paper's "naive interpolation"),
/// saturating at `usize::MAX`.
pub fn dense_bytes(dims: [usize; 3], value_bytes: usize) -> usize {
    dims[0]
        .saturating_mul(dims[1])
        .saturating_mul(dims[2])
        .saturating_mul(value_bytes)
}

/// Bytes to mebibytes (`/ 2^20`), the unit of the paper's MB figures.
pub fn mib(bytes: usize) -> f64 {
    bytes as f64 / (1u64 << 20) as f64
}
