//! Kriging of a large scattered data set with a moving neighbourhood: memory stays `O(n)`.
//!
//! Usage: `cargo run --release -p kriging --example neighbourhood -- [n] [k] [grid]`
//! (defaults 50000 points, 32 neighbours, a 200 x 200 grid). Measure the peak memory with
//! `/usr/bin/time -v target/release/examples/neighbourhood 50000 32 200`.
//!
//! Steps: the variogram is fitted (best of spherical, exponential, gaussian; the empirical variogram
//! streams over the pairs without storing them), ordinary kriging with the 32 nearest samples
//! predicts the grid with variances, and leave-one-out runs over every sample (each predicted from
//! its own 32 neighbours).

use std::time::Instant;

use kriging::faer::Mat;
use kriging::{Krige, Neighbourhood};

fn radical_inverse(mut i: usize, b: usize) -> f64 {
    let (mut f, mut r) = (1.0, 0.0);
    while i > 0 {
        f /= b as f64;
        r += f * (i % b) as f64;
        i /= b;
    }
    r
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .map(|a| a.parse())
        .collect::<Result<_, _>>()?;
    let n = args.first().copied().unwrap_or(50_000);
    let k = args.get(1).copied().unwrap_or(32);
    let grid = args.get(2).copied().unwrap_or(200);
    // Scattered points over a 100 km square (map coordinates with a large offset).
    let (x0, y0) = (1.8e5, 3.3e5);
    let coords = Mat::from_fn(n, 2, |i, c| {
        let b = if c == 0 { 2 } else { 3 };
        let o = if c == 0 { x0 } else { y0 };
        o + 1e5 * radical_inverse(i + 1, b)
    });
    let z: Vec<f64> = (0..n)
        .map(|i| {
            let (x, y) = (coords[(i, 0)] - x0, coords[(i, 1)] - y0);
            (x / 7000.0).sin() + (y / 4000.0).cos() + 0.3 * ((x + y) / 1500.0).sin()
        })
        .collect();
    let t = Instant::now();
    let model = Krige::new()
        .neighbourhood(Neighbourhood::Nearest { k })
        .fit(coords.as_ref(), &z)?;
    let t_fit = t.elapsed();
    println!(
        "n = {n}, {k} nearest neighbours: variogram fitted and model built in {:.2} s: {:?}",
        t_fit.as_secs_f64(),
        model.variogram()
    );
    let g: Vec<f64> = (0..grid)
        .map(|i| 1e5 * i as f64 / (grid - 1) as f64)
        .collect();
    let xs: Vec<f64> = g.iter().map(|v| x0 + v).collect();
    let ys: Vec<f64> = g.iter().map(|v| y0 + v).collect();
    let t = Instant::now();
    let p = model.predict_grid(&xs, &ys)?;
    let t_grid = t.elapsed();
    let mean_var = p.variances.iter().sum::<f64>() / p.variances.len() as f64;
    println!(
        "{grid} x {grid} grid with variances in {:.2} s (mean prediction {:.6}, mean variance {:.6})",
        t_grid.as_secs_f64(),
        p.values.iter().sum::<f64>() / p.values.len() as f64,
        mean_var
    );
    let t = Instant::now();
    let loo = model.leave_one_out()?;
    println!(
        "leave-one-out over all {n} samples in {:.2} s: RMSE {:.5}, mean squared standardised error {:.3}",
        t.elapsed().as_secs_f64(),
        loo.rmse,
        loo.msse
    );
    Ok(())
}
