//! The problem of the kriging benches (`kriging_geo`, `kriging_sgs`) and of the kriging crate's
//! Python timings (`crates/kriging/scripts/`): `n` Halton points on `[0, 10000]^2` (bases 2 and 3,
//! from index 1) with the values `sin(x/1500) + cos(y/900) + 1e-4 x`.

use kriging::faer::Mat;

/// The van der Corput radical inverse of `i` in base `b`.
fn radical_inverse(mut i: usize, b: usize) -> f64 {
    let (mut f, mut r) = (1.0, 0.0);
    while i > 0 {
        f /= b as f64;
        r += f * (i % b) as f64;
        i /= b;
    }
    r
}

/// The `n x 2` points and their values.
pub fn problem(n: usize) -> (Mat<f64>, Vec<f64>) {
    let coords = Mat::from_fn(n, 2, |i, c| 10000.0 * radical_inverse(i + 1, [2, 3][c]));
    let z = (0..n)
        .map(|i| {
            let (x, y) = (coords[(i, 0)], coords[(i, 1)]);
            (x / 1500.0).sin() + (y / 900.0).cos() + 1e-4 * x
        })
        .collect();
    (coords, z)
}
