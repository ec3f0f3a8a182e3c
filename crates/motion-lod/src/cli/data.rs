//! Options shared by every subcommand that reads training data (`cycles`, `build`, `eval`, `crowd`).

use std::path::PathBuf;

use anyhow::Context as _;
use clap::{Args, ValueEnum};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use motion_io::{SignedAxis, Units};
use motion_lod::dataset::{AlignSpec, DataSpec, LoadedData, Preset, joint_map_from_toml};
use motion_lod::style::StyleSpec;
use timewarp::DtwConfig;

/// Time alignment of the cycles.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum AlignArg {
    /// Dynamic time warping against the medoid cycle.
    Dtw,
    /// Uniform time scaling between the cycle's first and last frame.
    Uniform,
}

/// Contact detection and cycle selection settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum PresetArg {
    /// `cmu` when the first take has the joints of the CMU database's cgspeed conversions
    /// (`lButtock`/`rButtock` or `LHipJoint`/`RHipJoint`), else `default` (said on standard error
    /// when it picks `cmu`).
    Auto,
    /// Defaults tuned on the Bandai data set.
    Default,
    /// CMU (cgspeed) conversions: ignore the first 0.1 s, looser floor height.
    Cmu,
}

/// Length units of the BVH files.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum UnitsArg {
    /// Detect from the skeleton's standing height (bone lengths).
    Auto,
    /// Metres.
    M,
    /// Centimetres.
    Cm,
    /// Millimetres.
    Mm,
    /// Inches.
    In,
    /// The CMU ASF/AMC unit, 1/0.45 inch.
    Cmu,
}

/// Up axis of the BVH files.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum UpArg {
    /// Detect from where the feet stay.
    Auto,
    /// Y up (most exporters).
    Y,
    /// Z up (3ds Max, some Blender and robotics exports).
    Z,
}

/// Where the training data comes from and how it is aligned.
#[derive(Debug, Clone, Args)]
pub struct DataArgs {
    /// Folders of BVH takes (all of one skeleton); without any, the embedded default data set.
    #[arg(value_name = "DIR")]
    pub dirs: Vec<PathBuf>,
    /// Aligned frames per cycle, T (default: the median cycle length in frames; 2..=2000).
    #[arg(long, value_name = "T", value_parser = super::ranges::count(super::ranges::FRAMES))]
    pub frames: Option<usize>,
    /// Time alignment method.
    #[arg(long, value_enum, default_value_t = AlignArg::Dtw)]
    pub align: AlignArg,
    /// DTW band, as a fraction of the cycle length (0 = the diagonal only, 1 = no band; 0..=1).
    #[arg(long, default_value_t = DtwConfig::default().band, value_parser = super::ranges::band)]
    pub band: f64,
    /// DTW slope limit: at most this many consecutive steps along one cycle (0 = diagonal steps
    /// only; 0..=100).
    #[arg(long, default_value_t = DtwConfig::default().max_slope, value_parser = super::ranges::count(super::ranges::MAX_SLOPE))]
    pub max_slope: usize,
    /// Contact detection preset.
    #[arg(long, value_enum, default_value_t = PresetArg::Auto)]
    pub preset: PresetArg,
    /// Use a random subset of N cycles (the paper used 186; 1..=10000000, and at most the cycles the
    /// data gives: more is an error).
    #[arg(long, value_name = "N", value_parser = super::ranges::count(super::ranges::SAMPLES))]
    pub samples: Option<usize>,
    /// Seed of the random subset (any integer 0..=18446744073709551615; the same seed picks the
    /// same cycles).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Length units of the files.
    #[arg(long, value_enum, default_value_t = UnitsArg::Auto)]
    pub units: UnitsArg,
    /// Up axis of the files.
    #[arg(long, value_enum, default_value_t = UpArg::Auto)]
    pub up: UpArg,
    /// A TOML file naming the joints of the feet when neither their names nor the hierarchy find
    /// them: `left_foot`, `right_foot`, and optionally `left_toe`, `right_toe`, `head`.
    #[arg(long, value_name = "FILE")]
    pub joint_map: Option<PathBuf>,
    /// Style of each take from its file name: a regular expression whose first capture group is
    /// the style, e.g. '_([a-z]+)_\d+\.bvh$' for Bandai's `..._elderly_001.bvh`. The model then
    /// conditions on style (`synth --style`, `crowd --style`).
    #[arg(long, value_name = "REGEX", group = "style_source")]
    pub style_from_name: Option<String>,
    /// Style of each take from the name of the folder that holds it (one folder per style).
    #[arg(long, group = "style_source")]
    pub style_from_folder: bool,
    /// Style of each take from a CSV table of `take,style` rows (take: the file name, with or
    /// without `.bvh`).
    #[arg(long, value_name = "CSV", group = "style_source")]
    pub style_table: Option<PathBuf>,
}

impl DataArgs {
    /// Where the takes' styles come from, if a style option was given.
    pub fn style_spec(&self) -> Option<StyleSpec> {
        if let Some(pattern) = &self.style_from_name {
            Some(StyleSpec::Name(pattern.clone()))
        } else if let Some(path) = &self.style_table {
            Some(StyleSpec::Csv(path.clone()))
        } else {
            self.style_from_folder.then_some(StyleSpec::Folder)
        }
    }

    /// The data specification these options describe (reads the joint map).
    pub fn spec(&self) -> anyhow::Result<DataSpec> {
        let joint_map = match &self.joint_map {
            Some(path) => {
                let text = std::fs::read_to_string(path)
                    .with_context(|| format!("reading the joint map {}", path.display()))?;
                joint_map_from_toml(&text)
                    .with_context(|| format!("joint map {}", path.display()))?
            }
            None => Default::default(),
        };
        Ok(DataSpec {
            dirs: self.dirs.clone(),
            frames: self.frames,
            align: match self.align {
                AlignArg::Dtw => AlignSpec::Dtw {
                    band: self.band,
                    max_slope: self.max_slope,
                },
                AlignArg::Uniform => AlignSpec::Uniform,
            },
            preset: match self.preset {
                PresetArg::Default => Preset::Default,
                PresetArg::Cmu => Preset::Cmu,
                PresetArg::Auto => {
                    let files = motion_lod::dataset::list_bvh_files(&self.dirs).unwrap_or_default();
                    let (preset, why) = Preset::detect(&files);
                    if let Some(why) = why {
                        eprintln!(
                            "note: using --preset cmu: {why} (floors that drift, a reference pose \
                             blended in over the first 0.1 s); --preset default overrides"
                        );
                    }
                    preset
                }
            },
            samples: self.samples,
            seed: self.seed,
            units: match self.units {
                UnitsArg::Auto => None,
                UnitsArg::M => Some(Units::Metres),
                UnitsArg::Cm => Some(Units::Centimetres),
                UnitsArg::Mm => Some(Units::Millimetres),
                UnitsArg::In => Some(Units::Inches),
                UnitsArg::Cmu => Some(Units::CmuUnits),
            },
            up: match self.up {
                UpArg::Auto => None,
                UpArg::Y => Some(SignedAxis::Y),
                UpArg::Z => Some(SignedAxis::Z),
            },
            joint_map,
        })
    }
}

/// A progress bar on standard error (hidden when `quiet`).
pub fn bar(quiet: bool) -> anyhow::Result<ProgressBar> {
    let bar = if quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr())
    };
    bar.set_style(
        ProgressStyle::with_template("{msg:18} [{bar:40}] {pos}/{len}")
            .context("progress bar template")?,
    );
    Ok(bar)
}

/// Loads and aligns the data of `spec` with a progress bar, the training set labelled with
/// `style` when given; warns about skipped files on stderr.
pub fn load(spec: &DataSpec, style: Option<&StyleSpec>, quiet: bool) -> anyhow::Result<LoadedData> {
    let bar = bar(quiet)?;
    // Two steps per take: read, then segmented into cycles.
    bar.set_message("steps (2 per take)");
    let loaded = spec
        .load_with_default(super::default_takes::DEFAULT_TAKES, &|_, total| {
            bar.set_length(total as u64);
            bar.inc(1);
        })
        .map_err(|e| {
            // The library names its configuration; the user gave options.
            let no_path = matches!(
                &e,
                motion_lod::dataset::DatasetError::AlignCycle {
                    source: timewarp::TimewarpError::NoPath { .. },
                    ..
                }
            );
            let e = anyhow::Error::new(e);
            if no_path {
                e.context(
                    "--band and --max-slope leave no warping path between two cycles of other \
                     lengths: widen --band or raise --max-slope (or --align uniform)",
                )
            } else {
                e
            }
        })
        .with_context(|| format!("loading {}", spec.describe_data()))?;
    bar.finish_and_clear();
    let mut loaded = loaded;
    if style.is_some() {
        loaded.training = loaded.training.with_styles(style).with_context(|| {
            format!(
                "labelling the takes' styles ({})",
                style.map(StyleSpec::describe).unwrap_or_default()
            )
        })?;
    }
    for f in &loaded.cycles.failed {
        eprintln!("warning: skipped {}: {}", f.path.display(), f.error);
    }
    for t in &loaded.cycles.takes {
        if t.reason.is_none() {
            for s in &t.skipped {
                eprintln!("note: {}: skipped {s}", t.path.display());
            }
        }
    }
    Ok(loaded)
}
