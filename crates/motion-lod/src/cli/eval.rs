//! `motion-lod eval MODEL|DIR...`: leave-one-out mean joint position error per method, with storage.

use std::path::Path;

use anyhow::Context as _;
use clap::Args;
use lod_policy::Precision;
use motion_lod::build::Analysis;
use motion_lod::eval::{EvalConfig, EvalReport, leave_one_out};
use motion_lod::progress::{BarProgress, NoProgress, Progress};
use motion_lod::storage::Storage;
use motion_lod::{BuildConfig, MotionModel};

use super::build::ModelArgs;
use super::data::{DataArgs, load};

/// Arguments of `motion-lod eval`.
#[derive(Debug, Args)]
pub struct EvalArgs {
    /// A model file (`*.mlod`: its recorded training data and settings are used) or BVH folders (the
    /// data options below apply); nothing means the embedded default data set.
    #[command(flatten)]
    pub data: DataArgs,
    /// Model settings (for folders; a model file brings its own).
    #[command(flatten)]
    pub model: ModelArgs,
    /// Evaluate at most this many held-out samples (evenly strided); default all.
    #[arg(long, value_name = "N")]
    pub max_samples: Option<usize>,
    /// Principal DOF directions of the PCA baseline (the paper: 40).
    #[arg(long, default_value_t = 40)]
    pub pca_rank: usize,
    /// Print one JSON line instead of the table.
    #[arg(long)]
    pub json: bool,
}

fn is_model_file(p: &Path) -> bool {
    p.is_file()
}

/// Runs the subcommand.
pub fn run(args: EvalArgs) -> anyhow::Result<()> {
    let (spec, config) = match args.data.dirs.as_slice() {
        [one] if is_model_file(one) => {
            let model =
                MotionModel::load(one).with_context(|| format!("reading {}", one.display()))?;
            let spec = model.report.data.clone().with_context(|| {
                format!(
                    "{} does not record its training data; evaluate its folders instead",
                    one.display()
                )
            })?;
            (spec, model.report.config.clone())
        }
        _ => (args.data.spec(), args.model.config()),
    };
    let report = evaluate(&spec, &config, args.max_samples, args.pca_rank, args.json)?;
    if args.json {
        println!("{}", serde_json::to_string(&report)?);
    } else {
        print(&report);
    }
    Ok(())
}

/// Loads the data, builds the model and runs the leave-one-out evaluation.
pub fn evaluate(
    spec: &motion_lod::dataset::DataSpec,
    config: &BuildConfig,
    max_samples: Option<usize>,
    pca_rank: usize,
    quiet: bool,
) -> anyhow::Result<EvalReport> {
    let loaded = load(spec, quiet)?;
    let bar = BarProgress::new(!quiet);
    let progress: &dyn Progress = if quiet { &NoProgress } else { &bar };
    let analysis =
        Analysis::run(&loaded.training, config, progress).context("analysing the data")?;
    let model = analysis
        .runtime_model(config, progress)
        .context("building the runtime model")?;
    let key_bytes: Vec<usize> = (0..model.lod.keys().len())
        .map(|k| model.lod.key_bytes(k, Precision::F64))
        .collect();
    let eval_config = EvalConfig {
        pca_rank,
        max_samples,
    };
    leave_one_out(
        &analysis,
        Storage::of(&model).model_f64,
        &key_bytes,
        &eval_config,
        progress,
    )
    .context("leave-one-out evaluation")
}

fn print(r: &EvalReport) {
    println!(
        "leave-one-out over {} of {} samples; raw samples {} bytes (f64), hybrid model {} bytes (f64)",
        r.evaluated, r.samples, r.raw_bytes, r.model_bytes
    );
    println!("  method          level  ranks           joint error   shell error   bytes (f64)");
    for m in &r.methods {
        println!(
            "  {:<14}  {:>5}  {:<14}  {:>8.3} cm  {:>9.2} cm  {:>12}",
            m.name,
            m.level.map_or("-".to_string(), |l| l.to_string()),
            m.ranks.map_or("-".to_string(), |r| format!("{r:?}")),
            m.error_cm,
            m.shell_cm,
            m.bytes
        );
    }
}
