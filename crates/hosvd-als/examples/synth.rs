//! Writes a deterministic synthetic tensor (decaying multilinear spectrum plus noise) as NPY, so
//! that the `hooi` example and other tools can be compared on the same input.
//!
//! ```text
//! cargo run --release -p hosvd-als --example synth -- OUT.npy [--dims 94,100,186] [--ranks 60,60,90] [--seed 1]
//! ```

use clap::Parser;
use std::path::PathBuf;

#[derive(Parser)]
#[command(about = "Write a synthetic paper-shaped tensor as a Fortran-ordered f64 NPY file")]
struct Args {
    /// Output NPY file.
    output: PathBuf,
    /// Tensor dims.
    #[arg(long, default_value = "94,100,186")]
    dims: String,
    /// Ranks of the generating core.
    #[arg(long, default_value = "60,60,90")]
    ranks: String,
    /// Spectral decay rate.
    #[arg(long, default_value_t = 6.0)]
    decay: f64,
    /// Relative noise level.
    #[arg(long, default_value_t = 0.01)]
    noise: f64,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

fn triple(s: &str) -> anyhow::Result<[usize; 3]> {
    let v: Vec<usize> = s
        .split(',')
        .map(|p| p.trim().parse())
        .collect::<Result<_, _>>()?;
    v.try_into()
        .map_err(|_| anyhow::anyhow!("expected three comma-separated sizes: {s}"))
}

fn main() -> anyhow::Result<()> {
    let a = Args::parse();
    let x = hosvd_als::synthetic::decaying_tucker(
        triple(&a.dims)?,
        triple(&a.ranks)?,
        a.decay,
        a.noise,
        a.seed,
    )?;
    tensor_ops::npy::write_tensor(&a.output, &x, tensor_ops::npy::NpyDtype::F64)?;
    eprintln!("wrote {} ({:?})", a.output.display(), x.dims());
    Ok(())
}
