//! Sequential Gaussian simulation at the scale of issue 37's goal: 100 realisations of a 200 x 200
//! grid conditioned on 2,000 points, timed once (the criterion bench is the workspace's
//! `benches/kriging_sgs.rs`; GSTools' time for the same job comes from
//! `scripts/sgs_gstools_timing.py`).
//!
//! Usage: `cargo run --release -p kriging --example sgs_timing -- [k] [realisations] [shared]`
//! (defaults: 16 neighbours, 100 realisations, a path per realisation; `shared` for one path).
//!
//! The job (the same in the Python script): 2,000 Halton points (bases 2 and 3) on
//! [0, 10000]^2, values `sin(x/1500) + cos(y/900) + 1e-4 x`, an exponential variogram without
//! nugget, partial sill 1 and practical range 3000 (GSTools: `Exponential(var=1, len_scale=1000)`),
//! simple kriging with the data mean, targets a 200 x 200 grid over the same square.

use std::time::Instant;

use kriging::faer::Mat;
use kriging::{NestedVariogram, Sgs, SgsPath, VariogramModel};

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
    let args: Vec<String> = std::env::args().skip(1).collect();
    let k: usize = args.first().map(|a| a.parse()).transpose()?.unwrap_or(16);
    let nr: usize = args.get(1).map(|a| a.parse()).transpose()?.unwrap_or(100);
    let shared = args.get(2).is_some_and(|a| a == "shared");
    let n = 2000;
    let coords = Mat::from_fn(n, 2, |i, c| 10000.0 * radical_inverse(i + 1, [2, 3][c]));
    let z: Vec<f64> = (0..n)
        .map(|i| {
            let (x, y) = (coords[(i, 0)], coords[(i, 1)]);
            (x / 1500.0).sin() + (y / 900.0).cos() + 1e-4 * x
        })
        .collect();
    let g: Vec<f64> = (0..200).map(|i| 10000.0 * i as f64 / 199.0).collect();
    let v = NestedVariogram::single(VariogramModel::Exponential, 0.0, 1.0, 3000.0)?;
    let path = if shared {
        SgsPath::Shared
    } else {
        SgsPath::PerRealisation
    };
    let sgs = Sgs::new(v)
        .neighbours(k)
        .path(path)
        .seed(2024)
        .realisations(nr);
    let t = Instant::now();
    let sims = sgs.simulate_grid(coords.as_ref(), &z, &g, &g)?;
    let secs = t.elapsed().as_secs_f64();
    let mean = sims.mean();
    let var = sims.variance();
    let m = mean.len() as f64;
    println!(
        "{nr} realisations of a 200 x 200 grid conditioned on {n} points, {k} neighbours, {} path, \
         {} threads: {secs:.2} s",
        if shared { "shared" } else { "per-realisation" },
        rayon::current_num_threads()
    );
    println!(
        "ensemble: mean of the means {:.4}, mean of the variances {:.4} (data mean {:.4})",
        mean.iter().sum::<f64>() / m,
        var.iter().sum::<f64>() / m,
        z.iter().sum::<f64>() / n as f64
    );
    Ok(())
}
