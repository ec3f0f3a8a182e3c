//! Deterministic synthetic test tensors with a decaying multilinear spectrum (for tests,
//! benchmarks and examples; not a motion model).

use faer::Mat;
use tensor_ops::{Tensor3, TensorError};

/// SplitMix64: a small deterministic generator, uniform in `[-1, 1)`.
#[derive(Clone, Debug)]
pub struct SplitMix(u64);

impl SplitMix {
    /// A generator seeded with `seed`.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// The next value, uniform in `[-1, 1)`.
    pub fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

/// `X = G x_0 A x_1 B x_2 C + noise`: a random core `G` (`R_0 x R_1 x R_2`) whose entries are
/// scaled by `exp(-decay (a / R_0 + b / R_1 + c / R_2))`, random non-orthogonal factors `A, B, C`
/// (`I_n x R_n`, entries uniform in `[-1, 1)`), and uniform noise of relative size `noise`
/// (per element, relative to the RMS of the noiseless tensor). Same arguments, same bytes.
///
/// Errors: [`TensorError::BadRank`] if `ranks` is zero somewhere (ranks above dims are allowed);
/// [`TensorError::NonFinite`] if a value is NaN or infinite: a `decay` or `noise` that is not
/// finite, or values that overflow (a result that [`Tensor3::from_vec`] would reject is never
/// returned).
pub fn decaying_tucker(
    dims: [usize; 3],
    ranks: [usize; 3],
    decay: f64,
    noise: f64,
    seed: u64,
) -> Result<Tensor3, TensorError> {
    if let Some(mode) = (0..3).find(|&n| ranks[n] == 0) {
        return Err(TensorError::BadRank {
            mode,
            rank: 0,
            size: dims[mode],
        });
    }
    let mut rng = SplitMix::new(seed);
    let g = Tensor3::from_fn(ranks, |a, b, c| {
        let s =
            a as f64 / ranks[0] as f64 + b as f64 / ranks[1] as f64 + c as f64 / ranks[2] as f64;
        rng.next_f64() * (-decay * s).exp()
    })?;
    let f: [Mat<f64>; 3] =
        std::array::from_fn(|n| Mat::from_fn(dims[n], ranks[n], |_, _| rng.next_f64()));
    let mut x = tensor_ops::try_reconstruct(&g, [f[0].as_ref(), f[1].as_ref(), f[2].as_ref()])?;
    let rms = (x.squared_norm() / x.len().max(1) as f64).sqrt();
    for v in x.as_mut_slice() {
        *v += noise * rms * rng.next_f64();
    }
    x.check_finite()?;
    Ok(x)
}
