//! Project tasks: `cargo xtask fixtures` regenerates `fixtures/` (the synthetic gait set of the
//! procedural walker, see the library part of this crate).

use std::path::PathBuf;

use anyhow::{Result, bail};
use clap::{Args, Parser, Subcommand};
use xtask::fixtures;

/// Project tasks of the motion-lod workspace.
#[derive(Debug, Parser)]
#[command(name = "xtask", about = "Project tasks of the motion-lod workspace")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// The tasks.
#[derive(Debug, Subcommand)]
enum Command {
    /// Regenerate the synthetic gait set in `fixtures/` (BVH takes, controls.csv, README.md).
    Fixtures(FixturesArgs),
}

/// Options of `xtask fixtures`.
#[derive(Debug, Args)]
struct FixturesArgs {
    /// Output folder (default: `fixtures/` at the workspace root).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Do not write: fail if the files on disk differ from what the generator produces.
    #[arg(long)]
    check: bool,
}

fn main() -> Result<()> {
    match Cli::parse().command {
        Command::Fixtures(args) => run_fixtures(&args),
    }
}

fn run_fixtures(args: &FixturesArgs) -> Result<()> {
    let dir = args.out.clone().unwrap_or_else(fixtures::default_dir);
    let dir = dir.canonicalize().unwrap_or(dir);
    let files = fixtures::generate_all(fixtures::SEED)?;
    if args.check {
        let stale = fixtures::check(&dir, &files);
        if !stale.is_empty() {
            bail!(
                "{} file(s) in {} differ from the generator: {}",
                stale.len(),
                dir.display(),
                stale.join(", ")
            );
        }
        println!(
            "fixtures: {} files in {} are up to date",
            files.len(),
            dir.display()
        );
        return Ok(());
    }
    let bytes = fixtures::write(&dir, &files)?;
    println!(
        "fixtures: wrote {} files ({:.2} MB) to {}",
        files.len(),
        bytes as f64 / 1e6,
        dir.display()
    );
    Ok(())
}
