//! `motion-lod cycles DIR...`: read BVH folders, segment gait cycles, align them, report counts and
//! optionally write the motion tensor (NPY, shape `(P, T, S)`) and the controls (CSV).

use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Context as _;
use clap::Args;
use motion_io::{FootNames, RootPositions};
use motion_lod::dataset::{AlignedSet, CycleSet, DatasetError, FailedFile, TakeSummary};
use motion_lod::model_file::write_atomic;
use serde::Serialize;
use tensor_ops::npy::{NpyArray, NpyDtype, to_npy_bytes};

use super::data::{AlignArg, DataArgs, load};

/// Arguments of `motion-lod cycles`.
#[derive(Debug, Args)]
pub struct CyclesArgs {
    /// Training data.
    #[command(flatten)]
    pub data: DataArgs,
    /// Write the motion tensor here as NPY (f64, shape (P, T, S), Fortran order).
    #[arg(long, value_name = "FILE")]
    pub tensor: Option<PathBuf>,
    /// Write the controls here as CSV (one row per cycle).
    #[arg(long, value_name = "FILE")]
    pub controls: Option<PathBuf>,
    /// Print one JSON line of counts instead of the report (no progress bar).
    #[arg(long)]
    pub json: bool,
}

/// The `--json` line.
#[derive(Debug, Serialize)]
struct Summary {
    /// `.bvh` files found.
    files: usize,
    /// Files skipped (unreadable or not segmentable).
    failed_files: usize,
    /// Cycles kept.
    cycles: usize,
    /// Candidate cycles dropped.
    dropped: usize,
    #[serde(rename = "P")]
    p: usize,
    #[serde(rename = "T")]
    t: usize,
    #[serde(rename = "S")]
    s: usize,
    /// Length units used (`m`, `cm`, `mm`, `in`, `cmu`) and whether they were detected.
    units: Option<String>,
    units_detected: Option<bool>,
    /// The files' up axis (`+y`, `+z`, ...) and whether it was detected.
    up: Option<String>,
    up_detected: Option<bool>,
    /// The axis the skeleton faces at a zero root rotation (from the direction of travel).
    forward: Option<String>,
    /// Root position channels: `Absolute`, `Relative` or `Same` (first take).
    root_positions: Option<RootPositions>,
    /// The feet's joints used and whether they were found from the hierarchy.
    feet: Option<FootNames>,
    feet_by_hierarchy: Option<bool>,
    /// Every file: cycles, dropped candidates, skipped frames and why it gave no cycle.
    takes: Vec<TakeSummary>,
    /// With a style option: each style with its cycles and takes (left out without one).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    styles: Vec<motion_lod::info::StyleSummary>,
}

/// Each style of the training set with its cycles and takes (empty without labels).
fn style_counts(training: &motion_lod::TrainingSet) -> Vec<motion_lod::info::StyleSummary> {
    let Some(labels) = &training.styles else {
        return Vec::new();
    };
    let takes = motion_lod::style::StyleReport::takes_per_style(labels, &training.sources);
    labels
        .names
        .iter()
        .zip(labels.counts())
        .zip(takes)
        .map(|((name, cycles), takes)| motion_lod::info::StyleSummary {
            name: name.clone(),
            cycles,
            takes,
        })
        .collect()
}

/// The `--json` line when nothing could be used: the error and every file's reason.
#[derive(Debug, Serialize)]
struct Failure {
    error: String,
    files: Vec<FailedFile>,
}

/// Runs the subcommand.
pub fn run(args: CyclesArgs) -> anyhow::Result<()> {
    // Say now, not after the data are read and aligned, when an output cannot be written.
    for (flag, path) in [("--tensor", &args.tensor), ("--controls", &args.controls)] {
        if let Some(path) = path {
            super::build::check_writable(path).context(flag)?;
        }
    }
    if let (Some(tensor), Some(controls)) = (&args.tensor, &args.controls)
        && super::build::same_file(tensor, controls)
    {
        anyhow::bail!(
            "--tensor and --controls both name {}: the controls would replace the tensor",
            tensor.display()
        );
    }
    let loaded = match load(
        &args.data.spec()?,
        args.data.style_spec().as_ref(),
        args.json,
    ) {
        Ok(l) => l,
        Err(e) => {
            if args.json {
                let files = e
                    .chain()
                    .find_map(|c| c.downcast_ref::<DatasetError>())
                    .map(|d| match d {
                        DatasetError::NoCycles { reasons, .. }
                        | DatasetError::NoMotions { reasons, .. } => reasons.clone(),
                        _ => Vec::new(),
                    })
                    .unwrap_or_default();
                let line = Failure {
                    error: format!("{e:#}"),
                    files,
                };
                out!("{}", serde_json::to_string(&line)?);
            }
            return Err(e);
        }
    };
    let (set, aligned) = (&loaded.cycles, &loaded.aligned);
    if let Some(path) = &args.tensor {
        let bytes = to_npy_bytes(&NpyArray::from_tensor(&aligned.tensor), NpyDtype::F64)
            .context("encoding the tensor")?;
        write_atomic(path, &bytes)
            .with_context(|| format!("writing the tensor to {}", path.display()))?;
    }
    if let Some(path) = &args.controls {
        write_controls_csv(path, aligned)
            .with_context(|| format!("writing the controls to {}", path.display()))?;
    }
    let [p, t, s] = aligned.tensor.dims();
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    if args.json {
        let summary = Summary {
            files: set.files,
            failed_files: set.failed.len(),
            cycles: set.cycles.len(),
            dropped: set.dropped.len(),
            p,
            t,
            s,
            units: set.conventions.as_ref().map(|c| c.units.name().to_string()),
            units_detected: set.conventions.as_ref().map(|c| c.units_detected),
            up: set.conventions.as_ref().map(|c| c.up.to_string()),
            up_detected: set.conventions.as_ref().map(|c| c.up_detected),
            forward: set
                .conventions
                .as_ref()
                .and_then(|c| c.forward.map(|f| f.to_string())),
            root_positions: set.conventions.as_ref().map(|c| c.root_positions),
            feet: set.conventions.as_ref().map(|c| c.feet.clone()),
            feet_by_hierarchy: set.conventions.as_ref().map(|c| c.feet_by_hierarchy),
            takes: set.takes.clone(),
            styles: style_counts(&loaded.training),
        };
        writeln!(out, "{}", serde_json::to_string(&summary)?)?;
    } else {
        print_report(&mut out, set, aligned, &args)?;
        let styles = style_counts(&loaded.training);
        if !styles.is_empty() {
            writeln!(
                out,
                "styles ({}, from {}): {}",
                styles.len(),
                args.data
                    .style_spec()
                    .map(|s| s.describe())
                    .unwrap_or_default(),
                styles
                    .iter()
                    .map(|s| format!("{} {} cycles/{} takes", s.name, s.cycles, s.takes))
                    .collect::<Vec<_>>()
                    .join(", ")
            )?;
        }
    }
    Ok(())
}

fn print_report(
    out: &mut impl std::io::Write,
    set: &CycleSet,
    aligned: &AlignedSet,
    args: &CyclesArgs,
) -> anyhow::Result<()> {
    let [p, t, s] = aligned.tensor.dims();
    writeln!(
        out,
        "files: {} found, {} read, {} skipped",
        set.files,
        set.files - set.failed.len(),
        set.failed.len()
    )?;
    if let Some(c) = &set.conventions {
        writeln!(
            out,
            "conventions: units {} ({}; standing height {:.3} m), up {} ({}), forward {}, root positions {}{}",
            c.units,
            if c.units_detected {
                "detected"
            } else {
                "given"
            },
            c.standing_height / c.units.per_metre(),
            c.up,
            if c.up_detected { "detected" } else { "given" },
            c.forward.map_or("unknown".to_string(), |f| f.to_string()),
            c.root_positions,
            if c.feet_by_hierarchy {
                format!(
                    ", feet from the hierarchy ({} / {})",
                    c.feet.left_foot.as_deref().unwrap_or("?"),
                    c.feet.right_foot.as_deref().unwrap_or("?")
                )
            } else {
                String::new()
            }
        )?;
    }
    // Skipped frames of the takes that gave cycles are noted on stderr while loading.
    for t in &set.takes {
        if let Some(reason) = &t.reason {
            writeln!(out, "  no cycle from {}: {reason}", t.path.display())?;
        }
    }
    writeln!(
        out,
        "cycles: {} kept, {} dropped",
        set.cycles.len(),
        set.dropped.len()
    )?;
    for (reason, count) in set.dropped_by_reason() {
        writeln!(out, "  dropped ({reason}): {count}")?;
    }
    let r = &aligned.sources[aligned.reference];
    writeln!(
        out,
        "tensor: P = {p}, T = {t}, S = {s}; alignment {}; reference cycle {} ({} frames {}..={})",
        match args.data.align {
            AlignArg::Dtw => "dtw",
            AlignArg::Uniform => "uniform",
        },
        aligned.reference,
        r.file.display(),
        r.first_frame,
        r.last_frame
    )?;
    let lengths: Vec<usize> = set.cycles.iter().map(|c| c.frame_count()).collect();
    writeln!(
        out,
        "cycle length: {}..={} frames, median {}",
        lengths.iter().min().copied().unwrap_or(0),
        lengths.iter().max().copied().unwrap_or(0),
        set.median_length()
    )?;
    let range = |f: &dyn Fn(&motion_io::MeasuredControls) -> f64| {
        aligned
            .controls
            .iter()
            .map(f)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v), hi.max(v))
            })
    };
    let (dx, dz) = (range(&|c| c.dx), range(&|c| c.dz));
    let (turn, height) = (range(&|c| c.turn.to_degrees()), range(&|c| c.height));
    writeln!(
        out,
        "controls: dx [{:.3}, {:.3}] m, dz [{:.3}, {:.3}] m, turn [{:.1}, {:.1}] deg, height [{:.3}, {:.3}] m",
        dx.0, dx.1, dz.0, dz.1, turn.0, turn.1, height.0, height.1
    )?;
    if let Some(path) = &args.tensor {
        writeln!(out, "wrote {} (f64, shape ({p}, {t}, {s}))", path.display())?;
    }
    if let Some(path) = &args.controls {
        writeln!(out, "wrote {} ({s} rows)", path.display())?;
    }
    Ok(())
}

/// One row per sample: source file, first and last frame, dx, dz, turn, height.
fn write_controls_csv(path: &Path, aligned: &AlignedSet) -> anyhow::Result<()> {
    let mut text = String::from("source,first_frame,last_frame,dx_m,dz_m,turn_rad,height_m\n");
    for (src, c) in aligned.sources.iter().zip(&aligned.controls) {
        text.push_str(&format!(
            "{},{},{},{},{},{},{}\n",
            csv_field(&src.file.display().to_string()),
            src.first_frame,
            src.last_frame,
            c.dx,
            c.dz,
            c.turn,
            c.height
        ));
    }
    write_atomic(path, text.as_bytes())?;
    Ok(())
}

/// Quotes a CSV field when it holds a comma, a quote or a line break (RFC 4180).
fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}
