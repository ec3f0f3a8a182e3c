//! `motion-lod info model.mlod`: dimensions, levels with ranks, error and bytes, storage table.

use std::path::PathBuf;

use anyhow::Context as _;
use clap::Args;
use motion_lod::MotionModel;
use motion_lod::info::{summary, write_report};

/// Arguments of `motion-lod info`.
#[derive(Debug, Args)]
pub struct InfoArgs {
    /// The model file.
    #[arg(value_name = "MODEL")]
    pub model: PathBuf,
    /// Print one JSON line instead of the report.
    #[arg(long)]
    pub json: bool,
}

/// Runs the subcommand.
pub fn run(args: InfoArgs) -> anyhow::Result<()> {
    let model = MotionModel::load(&args.model)
        .with_context(|| format!("reading {}", args.model.display()))?;
    if args.json {
        out!("{}", serde_json::to_string(&summary(&model))?);
    } else {
        write_report(&mut std::io::stdout().lock(), &model)?;
    }
    Ok(())
}
