//! HOOI or the key-level search on a tensor read from an NPY file, printing JSON.
//!
//! ```text
//! cargo run --release -p hosvd-als --example hooi -- IN.npy --ranks 40,40,60 [--tol 1e-8] [--max-iter 100]
//!   -> {"ranks":[40,40,60],"iterations":N,"rel_error":X,"mse":E,"converged":true,"seconds":S}
//! cargo run --release -p hosvd-als --example hooi -- IN.npy --key-levels 10 --max-ranks 40,40,60 --min-ranks 7,7,9
//!   -> {"c_e":..,"levels":[{"ranks":[..],"mse":..,"rel_error":..,"iterations":..,"bytes_f64":..,"bytes_f32":..}, ..], ..}
//! ```
//! IN.npy is a 3-D f64 or f32 array (C or Fortran order); `a[i, j, k]` is element `(i, j, k)`.

use anyhow::Context;
use clap::Parser;
use hosvd_als::storage::key_levels_bytes;
use hosvd_als::{AlsOptions, KeySearchConfig, hooi, key_levels};
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Parser)]
#[command(about = "HOOI / key-level search on a 3-D NPY tensor; prints JSON")]
struct Args {
    /// Input NPY file (3-D, f8 or f4).
    input: PathBuf,
    /// Rank triple for a single HOOI run, e.g. 40,40,60.
    #[arg(long, value_parser = parse_ranks)]
    ranks: Option<[usize; 3]>,
    /// Relative change of the core norm at which ALS stops.
    #[arg(long, default_value_t = 1e-8)]
    tol: f64,
    /// Maximum ALS sweeps.
    #[arg(long, default_value_t = 100)]
    max_iter: usize,
    /// Number of key levels N for the greedy key search (needs --max-ranks and --min-ranks).
    #[arg(long)]
    key_levels: Option<usize>,
    /// Ranks of the first key level.
    #[arg(long, value_parser = parse_ranks)]
    max_ranks: Option<[usize; 3]>,
    /// Ranks of the last key level.
    #[arg(long, value_parser = parse_ranks)]
    min_ranks: Option<[usize; 3]>,
}

fn parse_ranks(s: &str) -> Result<[usize; 3], String> {
    let v: Vec<usize> = s
        .split(',')
        .map(|p| {
            p.trim()
                .parse::<usize>()
                .map_err(|e| format!("rank '{p}': {e}"))
        })
        .collect::<Result<_, _>>()?;
    v.try_into()
        .map_err(|v: Vec<usize>| format!("expected 3 ranks, got {}", v.len()))
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    let x = tensor_ops::npy::read_tensor(&args.input)
        .with_context(|| format!("reading {}", args.input.display()))?;
    let als = AlsOptions {
        tol: args.tol,
        max_iter: args.max_iter,
    };
    if let Some(n) = args.key_levels {
        let (Some(max_ranks), Some(min_ranks)) = (args.max_ranks, args.min_ranks) else {
            anyhow::bail!("--key-levels needs --max-ranks and --min-ranks");
        };
        let cfg = KeySearchConfig {
            levels: n,
            max_ranks,
            min_ranks,
            als,
        };
        let t0 = Instant::now();
        let keys = key_levels(&x, &cfg)?;
        let seconds = t0.elapsed().as_secs_f64();
        let levels: Vec<_> = keys
            .levels
            .iter()
            .map(|l| {
                json!({
                    "ranks": l.ranks,
                    "mse": l.mse,
                    "rel_error": l.rel_error,
                    "iterations": l.iterations,
                    "als_runs": l.als_runs,
                    "threshold": l.threshold,
                    "bytes_f64": l.tucker.bytes(8),
                    "bytes_f32": l.tucker.bytes(4),
                })
            })
            .collect();
        let out = json!({
            "dims": x.dims(),
            "c_e": if keys.c_e.is_finite() { json!(keys.c_e) } else { json!(null) },
            "requested_levels": keys.requested_levels,
            "clamped": keys.clamped,
            "levels": levels,
            "total_bytes_f64": key_levels_bytes(&keys, 8),
            "total_bytes_f32": key_levels_bytes(&keys, 4),
            "seconds": seconds,
        });
        println!("{out}");
        return Ok(());
    }
    let Some(ranks) = args.ranks else {
        anyhow::bail!("give --ranks R0,R1,R2 or --key-levels N --max-ranks .. --min-ranks ..");
    };
    let t0 = Instant::now();
    let (_, rep) = hooi(&x, ranks, &als)?;
    let seconds = t0.elapsed().as_secs_f64();
    println!(
        "{}",
        json!({
            "ranks": ranks,
            "iterations": rep.iterations,
            "rel_error": rep.rel_error,
            "mse": rep.mse,
            "converged": rep.converged,
            "seconds": seconds,
        })
    );
    Ok(())
}
