//! `motion-lod eval MODEL|DIR...`: leave-one-out mean joint position error per method, with storage.

use std::path::Path;

use anyhow::Context as _;
use clap::Args;
use lod_policy::Precision;
use motion_lod::build::Analysis;
use motion_lod::dataset::{align_cycles_to, load_cycles_like};
use motion_lod::eval::{EvalConfig, EvalReport, FoldBy, held_out, k_fold, leave_one_out};
use motion_lod::progress::{NoProgress, Progress};

use super::progress::BarProgress;
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
    /// Held-out BVH folders (same skeleton): predict their cycles from all training cycles instead of
    /// leaving one out.
    #[arg(long, value_name = "DIR", num_args = 1.., conflicts_with = "folds")]
    pub holdout: Vec<std::path::PathBuf>,
    /// K-fold cross-validation by refitting (2..=1000): the whole pipeline (decomposition, row
    /// weights, variogram choice, RBF smoothing, PCA basis) is refitted on K-1 folds and every
    /// method predicts the held-out fold. Without it, the fast leave-one-out with the factors
    /// fitted on all samples.
    #[arg(long, value_name = "K", value_parser = super::ranges::count(super::ranges::FOLDS))]
    pub folds: Option<usize>,
    /// How `--folds` splits the cycles: by take (a take's cycles stay together) or by sample.
    #[arg(long, value_enum, default_value_t = ByArg::Take, requires = "folds")]
    pub by: ByArg,
    /// Evaluate at most this many held-out samples (evenly strided); default all (1..=10000000).
    #[arg(long, value_name = "N", value_parser = super::ranges::count(super::ranges::SAMPLES))]
    pub max_samples: Option<usize>,
    /// Principal DOF directions of the PCA baseline (the paper: 40; 1..=10000).
    #[arg(long, default_value_t = 40, value_parser = super::ranges::count(super::ranges::PCA_RANK))]
    pub pca_rank: usize,
    /// Print one JSON line instead of the table.
    #[arg(long)]
    pub json: bool,
    /// With a model file: read its training data from these folders instead of the ones it records
    /// (which are relative to the model file).
    #[arg(long = "data", value_name = "DIR", num_args = 1..)]
    pub data_dirs: Vec<std::path::PathBuf>,
    /// The model and data options given on the command line (`--levels`, `--frames`, ...), as
    /// `main` finds them: a model file brings its own, so they are refused with one.
    #[arg(skip)]
    pub given_settings: Vec<String>,
}

/// The model and data options (`--levels`, `--frames`, ...) that `matches` (eval's) holds from the
/// command line, as the user spelled them; the positional folders are not among them.
pub fn given_settings(matches: &clap::ArgMatches) -> Vec<String> {
    use clap::Args as _;
    let cmd = DataArgs::augment_args(ModelArgs::augment_args(clap::Command::new("eval")));
    cmd.get_arguments()
        .filter(|a| a.get_long().is_some())
        .filter(|a| {
            matches
                .try_get_raw(a.get_id().as_str())
                .is_ok_and(|v| v.is_some())
                && matches.value_source(a.get_id().as_str())
                    == Some(clap::parser::ValueSource::CommandLine)
        })
        .map(|a| format!("--{}", a.get_long().unwrap_or_default()))
        .collect()
}

/// What the data of a model file's evaluation must match: the model's skeleton.
struct Recorded<'a> {
    /// The model file, for messages.
    path: &'a Path,
    /// Its model.
    model: &'a MotionModel,
}

impl Recorded<'_> {
    /// Refuses data whose skeleton is not shaped as the model's (joint count, parents, channels;
    /// names may differ: the same takes exported under other names are the model's data), and
    /// notes a sample count that differs (the data were added to or cut since the build).
    fn check(&self, loaded: &motion_lod::dataset::LoadedData) -> anyhow::Result<()> {
        let theirs = &loaded.training.layout.skeleton().joints;
        let ours = &self.model.layout.skeleton().joints;
        let differs = if theirs.len() != ours.len() {
            Some(format!(
                "{} joints against the model's {}",
                theirs.len(),
                ours.len()
            ))
        } else {
            theirs
                .iter()
                .zip(ours)
                .enumerate()
                .find(|(_, (a, b))| a.parent != b.parent || a.channels != b.channels)
                .map(|(j, (a, b))| {
                    format!(
                        "joint {j} (`{}`) has another parent or channels than the model's (`{}`)",
                        a.name, b.name
                    )
                })
        };
        if let Some(detail) = differs {
            anyhow::bail!(
                "the data of --data are not {}'s: their skeleton differs ({detail}); --data \
                 names the folders of the model's own takes when they have moved",
                self.path.display()
            );
        }
        let (samples, model_samples) = (loaded.training.controls.len(), self.model.report.samples);
        if samples != model_samples {
            eprintln!(
                "note: --data gives {samples} cycles; {} was built on {model_samples}: the \
                 evaluation is of a model built with its settings on these data",
                self.path.display()
            );
        }
        Ok(())
    }
}

/// `--by` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ByArg {
    /// Whole takes per fold.
    Take,
    /// Sample i in fold i mod K.
    Sample,
}

fn is_model_file(p: &Path) -> bool {
    p.is_file()
}

/// Runs the subcommand.
pub fn run(args: EvalArgs) -> anyhow::Result<()> {
    if let Some(take) = args
        .data
        .dirs
        .iter()
        .find(|p| p.is_file() && p.extension().is_some_and(|e| e.eq_ignore_ascii_case("bvh")))
    {
        anyhow::bail!(
            "{} is a BVH take; eval reads a model file (.mlod) or folders of takes: pass its folder ({})",
            take.display(),
            take.parent()
                .filter(|d| !d.as_os_str().is_empty())
                .unwrap_or(Path::new("."))
                .display()
        );
    }
    let loaded_model;
    let (spec, config, style, recorded) = match args.data.dirs.as_slice() {
        [one] if is_model_file(one) => {
            if !args.given_settings.is_empty() {
                anyhow::bail!(
                    "{} brings its own settings and data options; {} appl{} to folders of takes \
                     only (evaluate the folders to change them)",
                    one.display(),
                    args.given_settings.join(", "),
                    if args.given_settings.len() == 1 {
                        "ies"
                    } else {
                        "y"
                    }
                );
            }
            loaded_model =
                MotionModel::load(one).with_context(|| format!("reading {}", one.display()))?;
            let model = &loaded_model;
            let spec = model.report.data.clone().with_context(|| {
                format!(
                    "{} does not record its training data; evaluate its folders instead",
                    one.display()
                )
            })?;
            let spec = if args.data_dirs.is_empty() {
                spec
            } else {
                motion_lod::dataset::DataSpec {
                    dirs: args.data_dirs.clone(),
                    ..spec
                }
            };
            // The style weight is chosen anew on every fold's training cycles, as the build did.
            let config = model.report.config.clone();
            let recorded = (!args.data_dirs.is_empty()).then_some(Recorded { path: one, model });
            (spec, config, model.style.clone().map(|s| s.spec), recorded)
        }
        _ => {
            if !args.data_dirs.is_empty() {
                anyhow::bail!("--data replaces a model file's data folders; name a model file");
            }
            args.model.check()?;
            (
                args.data.spec()?,
                args.model.config(),
                args.data.style_spec(),
                None,
            )
        }
    };
    if let Some(folds) = args.folds {
        let loaded = load(&spec, style.as_ref(), args.json)?;
        if let Some(r) = &recorded {
            r.check(&loaded)?;
        }
        let bar = BarProgress::new(!args.json);
        let progress: &dyn Progress = if args.json { &NoProgress } else { &bar };
        let by = match args.by {
            ByArg::Take => FoldBy::Take,
            ByArg::Sample => FoldBy::Sample,
        };
        let eval_config = EvalConfig {
            pca_rank: args.pca_rank,
            max_samples: args.max_samples,
        };
        let report = k_fold(&loaded.training, &config, folds, by, &eval_config, progress)
            .context("cross-validation by refitting")?;
        if args.json {
            out!("{}", serde_json::to_string(&report)?);
        } else {
            out!(
                "{folds}-fold cross-validation by {}, every method refitted on the other folds \
                 (held out per fold: {:?})",
                by.name(),
                report.fold_sizes
            );
            let first_training = report.pooled.samples - report.fold_sizes[0];
            out!(
                "{} held-out cycles of {} samples, each predicted by the model of its fold (trained on \
                 the other folds); ranks and bytes are the first fold's model's ({first_training} \
                 training cycles): raw {} bytes (f64), hybrid model {} bytes (f64)",
                report.pooled.evaluated,
                report.pooled.samples,
                report.pooled.raw_bytes,
                report.pooled.model_bytes
            );
            print_methods(&report.pooled)?;
        }
        return Ok(());
    }
    let report = evaluate(
        &spec,
        style.as_ref(),
        &config,
        &args.holdout,
        args.max_samples,
        args.pca_rank,
        args.json,
        recorded.as_ref(),
    )?;
    if args.json {
        out!("{}", serde_json::to_string(&report)?);
    } else {
        if args.holdout.is_empty() {
            out!("leave-one-out with the factors fitted on all samples (--folds K refits them)");
        }
        print(&report)?;
    }
    Ok(())
}

/// Loads the data (checked against `recorded`'s model when given), builds the model and runs the
/// leave-one-out evaluation.
#[allow(clippy::too_many_arguments)]
fn evaluate(
    spec: &motion_lod::dataset::DataSpec,
    style: Option<&motion_lod::style::StyleSpec>,
    config: &BuildConfig,
    holdout: &[std::path::PathBuf],
    max_samples: Option<usize>,
    pca_rank: usize,
    quiet: bool,
    recorded: Option<&Recorded<'_>>,
) -> anyhow::Result<EvalReport> {
    let loaded = load(spec, style, quiet)?;
    if let Some(r) = recorded {
        r.check(&loaded)?;
    }
    let bar = BarProgress::new(!quiet);
    let progress: &dyn Progress = if quiet { &NoProgress } else { &bar };
    let analysis =
        Analysis::run_guarded(&loaded.training, config, progress).context("analysing the data")?;
    let model = analysis
        .runtime_model(config, progress)
        .context("building the runtime model")?;
    let key_bytes: Vec<usize> = (0..model.lod().keys().len())
        .map(|k| model.lod().key_bytes(k, Precision::F64))
        .collect();
    let eval_config = EvalConfig {
        pca_rank,
        max_samples,
    };
    let model_bytes = Storage::of(&model).model_f64;
    if holdout.is_empty() {
        return leave_one_out(&analysis, model_bytes, &key_bytes, &eval_config, progress)
            .context("leave-one-out evaluation");
    }
    let dataset_config = spec.dataset_config();
    let held = load_cycles_like(holdout, &dataset_config, &loaded.cycles, &|_, _| {})
        .context("loading the held-out cycles")?;
    for f in &held.failed {
        eprintln!("warning: skipped {}: {}", f.path.display(), f.error);
    }
    let reference = &loaded.cycles.cycles[loaded.aligned.reference];
    let t = loaded.aligned.tensor.dims()[1];
    let aligned = align_cycles_to(&held, t, spec.align.method(), reference)
        .context("aligning the held-out cycles")?;
    let targets = analysis
        .prepare(&loaded.aligned.layout, &aligned.tensor)
        .context("preparing the held-out cycles")?;
    let controls: Vec<[f64; 4]> = aligned.controls.iter().map(|c| c.to_array()).collect();
    // Held-out takes get their styles by the same rule, and must be styles of the model.
    let styles = match (style, &analysis.styles) {
        (Some(rule), Some(labels)) => {
            let sources: Vec<String> = aligned.sources.iter().map(|s| s.label()).collect();
            let held = rule
                .label_with(&sources, &labels.names)
                .context("labelling the held-out takes' styles")?;
            Some(held)
        }
        _ => None,
    };
    held_out(
        &analysis,
        &targets,
        &controls,
        styles.as_deref(),
        model_bytes,
        &key_bytes,
        &eval_config,
        progress,
    )
    .context("held-out evaluation")
}

fn print(r: &EvalReport) -> std::io::Result<()> {
    out!(
        "{} cycles evaluated against {} training samples; raw samples {} bytes (f64), hybrid model {} bytes (f64)",
        r.evaluated,
        r.samples,
        r.raw_bytes,
        r.model_bytes
    );
    print_methods(r)
}

/// The per-method table of `r`: one multilinear row per key level (`key`), with the accuracy level
/// that key is (`acc.level`, what `--level` and `info` number); `motion-lod explain` defines both.
fn print_methods(r: &EvalReport) -> std::io::Result<()> {
    out!(
        "  method          key  acc.level  ranks           joint error   shell error   bytes (f64)"
    );
    let mut key = 0;
    for m in &r.methods {
        let (key_col, level_col) = match m.level {
            Some(l) => {
                key += 1;
                ((key - 1).to_string(), l.to_string())
            }
            None => ("-".to_string(), "-".to_string()),
        };
        out!(
            "  {:<14}  {:>3}  {:>9}  {:<14}  {:>8.3} cm  {:>9.2} cm  {:>12}",
            m.name,
            key_col,
            level_col,
            m.ranks.map_or("-".to_string(), |r| format!("{r:?}")),
            m.error_cm,
            m.shell_cm,
            m.bytes
        );
    }
    if !r.styles.is_empty() {
        out!("  per style (held-out cycles):   level 0      naive kriging");
        for st in &r.styles {
            out!(
                "  {:<16} {:>5} cycles  {:>7.3} cm   {:>7.3} cm",
                st.style,
                st.evaluated,
                st.level0_cm,
                st.naive_cm
            );
        }
    }
    out!("  (terms: motion-lod explain \"key level\", \"accuracy level\", \"shell error\")");
    Ok(())
}
