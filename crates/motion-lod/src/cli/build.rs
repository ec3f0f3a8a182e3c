//! `motion-lod build DIR... -o model.mlod`: build the multilinear model and write the model file.

use std::path::PathBuf;

use anyhow::{Context as _, bail};
use clap::Args;
use motion_lod::build::RowWeights;
use motion_lod::progress::{NoProgress, Progress};

use super::progress::BarProgress;
use motion_lod::{BuildConfig, MotionModel};

use super::data::{DataArgs, load};

/// Model settings shared by `build` and `eval`.
#[derive(Debug, Clone, Args)]
pub struct ModelArgs {
    /// Key levels N (paper: 10; 1..=100).
    #[arg(long, default_value_t = BuildConfig::default().key_levels,
          value_parser = super::ranges::count(super::ranges::KEY_LEVELS))]
    pub levels: usize,
    /// Accuracy levels N_A (at least N; 1..=1000; default 28); levels between keys are
    /// truncations of the larger key.
    #[arg(long, value_name = "NA",
          value_parser = super::ranges::count(super::ranges::ACCURACY_LEVELS))]
    pub accuracy_levels: Option<usize>,
    /// Ranks (R_P, R_T, R_S) of the first key level, clamped to the data (paper: 40,40,60; each
    /// 1..=10000).
    #[arg(long, value_parser = parse_ranks, default_value = "40,40,60")]
    pub max_ranks: [usize; 3],
    /// Ranks of the last key level (paper: 7,7,9; each 1..=10000).
    #[arg(long, value_parser = parse_ranks, default_value = "7,7,9")]
    pub min_ranks: [usize; 3],
    /// The DOF count the ranks are meant for: R_P of --max-ranks and --min-ranks is scaled by
    /// P / this (the paper's ranks are for P = 94); 0 uses them as given (0..=10000).
    #[arg(long, value_name = "P", default_value_t = motion_lod::build::PAPER_DOF,
          value_parser = super::ranges::count(super::ranges::DOF_REFERENCE))]
    pub dof_rank_reference: usize,
    /// Weights of the DOF rows in the decomposition: `position` weighs each row by how far it moves
    /// the joints (the tensor error then follows the joint position error); `unit` is the paper's plain
    /// tensor.
    #[arg(long, value_enum, default_value_t = Weights::Position)]
    pub row_weights: Weights,
    /// A varying control stays in the model unless leaving it out lowers the error of 5-fold
    /// cross-validation by take by more than this fraction (0.01 = 1%; 0 to 1); with fewer than
    /// 10 takes, only when leaving it out raises the kriging's leave-one-out error by more than it ...
    #[arg(long, value_name = "FRACTION", default_value_t = BuildConfig::default().control_margin, value_parser = super::ranges::control_margin)]
    pub control_margin: f64,
    /// ... and (leave-one-out only) when that rise is beyond noise: its paired t statistic over the
    /// samples reaches this value (1 = about 84% one-sided, 2 = about 97.5%; 0 tests the margin
    /// alone; at most 100).
    #[arg(long, value_name = "T", default_value_t = BuildConfig::default().control_min_t, value_parser = super::ranges::control_min_t)]
    pub control_min_t: f64,
    /// Keep every control that varies over the data (no selection, no quality guard).
    #[arg(long)]
    pub keep_controls: bool,
}

/// `--row-weights` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Weights {
    /// By joint-position sensitivity.
    Position,
    /// None (the paper).
    Unit,
}

impl ModelArgs {
    /// Checks what can be checked before any data are read, in the numbers the user gave: each of
    /// `--min-ranks` at most the same mode's `--max-ranks` (both are scaled and clamped alike
    /// later, which keeps their order).
    pub fn check(&self) -> anyhow::Result<()> {
        const MODES: [&str; 3] = ["DOF", "time", "samples"];
        let show = |r: [usize; 3]| format!("{},{},{}", r[0], r[1], r[2]);
        for (n, mode) in MODES.iter().enumerate() {
            let (lo, hi) = (self.min_ranks[n], self.max_ranks[n]);
            if lo > hi {
                bail!(
                    "--min-ranks {} is above --max-ranks {} in mode {n} ({mode}): {lo} > {hi}; \
                     the last key level's ranks cannot exceed the first's",
                    show(self.min_ranks),
                    show(self.max_ranks),
                );
            }
        }
        Ok(())
    }

    /// The build configuration these options describe.
    pub fn config(&self) -> BuildConfig {
        BuildConfig {
            key_levels: self.levels,
            accuracy_levels: self
                .accuracy_levels
                .unwrap_or(BuildConfig::default().accuracy_levels),
            max_ranks: self.max_ranks,
            min_ranks: self.min_ranks,
            dof_rank_reference: (self.dof_rank_reference > 0).then_some(self.dof_rank_reference),
            row_weights: match self.row_weights {
                Weights::Position => RowWeights::JointPosition,
                Weights::Unit => RowWeights::Unit,
            },
            control_margin: self.control_margin,
            control_min_t: self.control_min_t,
            select_controls: !self.keep_controls,
            ..BuildConfig::default()
        }
    }
}

/// Parses `a,b,c` into a rank triple.
pub fn parse_ranks(s: &str) -> Result<[usize; 3], String> {
    let v: Vec<usize> = s
        .split(',')
        .map(|x| x.trim().parse::<usize>())
        .collect::<Result<_, _>>()
        .map_err(|e| format!("`{s}`: {e} (expected three numbers like 40,40,60)"))?;
    let (lo, hi) = super::ranges::RANK;
    let ok = |r: usize| (lo..=hi).contains(&(r as u64));
    match v.as_slice() {
        &[a, b, c] if ok(a) && ok(b) && ok(c) => Ok([a, b, c]),
        _ => Err(format!(
            "`{s}`: expected three numbers in {lo}..={hi} like 40,40,60"
        )),
    }
}

/// Arguments of `motion-lod build`.
#[derive(Debug, Args)]
pub struct BuildArgs {
    /// Training data.
    #[command(flatten)]
    pub data: DataArgs,
    /// Model settings.
    #[command(flatten)]
    pub model: ModelArgs,
    /// The model file to write (written atomically).
    #[arg(short, long, value_name = "FILE")]
    pub output: PathBuf,
    /// Print one JSON line (dimensions, levels, bytes) instead of the report.
    #[arg(long)]
    pub json: bool,
}

/// Loads the data of `data` and builds a model with `model`'s settings (progress on stderr unless quiet).
pub fn build_model(data: &DataArgs, model: &ModelArgs, quiet: bool) -> anyhow::Result<MotionModel> {
    model.check()?;
    let spec = data.spec()?;
    let loaded = load(&spec, data.style_spec().as_ref(), quiet)?;
    let bar = BarProgress::new(!quiet);
    let progress: &dyn Progress = if quiet { &NoProgress } else { &bar };
    let mut built = MotionModel::build(&loaded.training, &model.config(), progress)
        .context("building the model")?;
    built.report.data = Some(spec);
    let config = model.config();
    let made = built.lod().levels().len();
    let keys = built.lod().keys().len();
    // Said when the user asked for a count: the defaults are targets the data may not meet.
    if model.levels != BuildConfig::default().key_levels && keys != model.levels {
        eprintln!(
            "note: --levels {}: the model has {keys} key levels (each key level lowers at least \
             one rank, and the ranks from --max-ranks down to --min-ranks, scaled and clamped to \
             this data, leave room for no more)",
            model.levels
        );
    }
    if model.accuracy_levels.is_some() && made != config.accuracy_levels {
        let why = if config.accuracy_levels < keys {
            format!("every one of the {keys} key levels is an accuracy level")
        } else {
            "levels between key levels whose ranks would repeat are merged; the ranks between \
             --max-ranks and --min-ranks leave room for no more"
                .to_string()
        };
        eprintln!(
            "note: --accuracy-levels {}: the model has {made} accuracy levels ({why})",
            config.accuracy_levels
        );
    }
    Ok(built)
}

/// The extension of `path`'s file name, lower-cased: what follows its last dot, even when the name is
/// nothing else (`.glb`, which [`std::path::Path::extension`] reads as a hidden file without one).
pub fn suffix(path: &std::path::Path) -> Option<String> {
    let name = path.file_name()?.to_string_lossy().to_ascii_lowercase();
    name.rsplit_once('.').map(|(_, ext)| ext.to_string())
}

/// Checks that a file can be created beside `path` (its folder exists and takes new files), by
/// creating and removing an empty probe file there, and that `path` is not a folder; nothing at
/// `path` itself is touched.
pub fn check_writable(path: &std::path::Path) -> anyhow::Result<()> {
    if path.is_dir() {
        bail!("cannot write {}: it is a folder", path.display());
    }
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => std::path::Path::new("."),
    };
    let name = path
        .file_name()
        .map_or("model".into(), |n| n.to_string_lossy().into_owned());
    let probe = dir.join(format!(".{name}.probe-{}", std::process::id()));
    std::fs::File::create(&probe).with_context(|| {
        format!(
            "cannot write {}: its folder does not take new files",
            path.display()
        )
    })?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

/// Refuses an output that is one of the command's inputs, `inputs` being `(what it is, path)`:
/// `synth m.mlod -o m.mlod` replaced the model with a BVH (found 2026-11-28).
pub fn check_not_input(
    output: &std::path::Path,
    inputs: &[(&str, &std::path::Path)],
) -> anyhow::Result<()> {
    if let Some((what, _)) = inputs.iter().find(|(_, input)| same_file(output, input)) {
        bail!(
            "{} is {what}: writing there would replace it; choose another output",
            output.display()
        );
    }
    Ok(())
}

/// Whether two paths name one file: the same canonical path (links followed, as the writer
/// follows them), or for a file not there yet the same canonical folder and name (`out.npy` and
/// `./out.npy`); a folder that does not exist compares as written.
pub fn same_file(a: &std::path::Path, b: &std::path::Path) -> bool {
    let canonical = |p: &std::path::Path| {
        if let Ok(file) = std::fs::canonicalize(p) {
            return file;
        }
        let folder = match p.parent() {
            Some(f) if !f.as_os_str().is_empty() => f,
            _ => std::path::Path::new("."),
        };
        let folder = std::fs::canonicalize(folder).unwrap_or_else(|_| folder.to_path_buf());
        folder.join(p.file_name().unwrap_or_default())
    };
    canonical(a) == canonical(b)
}

/// Runs the subcommand.
pub fn run(args: BuildArgs) -> anyhow::Result<()> {
    // Say now, not after the build, when the model cannot be written where asked.
    check_writable(&args.output)?;
    let started = std::time::Instant::now();
    let model = build_model(&args.data, &args.model, args.json)?;
    // The build time goes to stdout only: the file holds what the data and settings determine.
    let seconds = started.elapsed().as_secs_f64();
    model
        .save(&args.output)
        .with_context(|| format!("writing {}", args.output.display()))?;
    for w in model.report.warnings() {
        eprintln!("warning: {w}");
    }
    if args.json {
        let mut line = serde_json::to_value(motion_lod::info::summary(&model))?;
        line["seconds"] = serde_json::json!(seconds);
        out!("{line}");
    } else {
        motion_lod::info::write_report(&mut std::io::stdout().lock(), &model)?;
        out!("built in {seconds:.1} s; wrote {}", args.output.display());
    }
    Ok(())
}
