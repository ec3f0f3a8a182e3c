//! `cargo xtask tables`: measures the paper's tables and figures on our data and writes them to
//! `docs/tables.md` and `docs/figures/*.svg`.
//!
//! Every number in the output comes from the run that writes it: the data are loaded and aligned, the
//! hybrid model is built ([`motion_lod::MotionModel::build_with_analysis`], paper defaults), and then
//! 1. storage ([`storage`]): raw samples, every level by ALS, the hybrid key levels and PCA, in f64 and
//!    f32, and the runtime model and model file;
//! 2. Figure 4 ([`timing::figure4`]): time per pose and error per accuracy level for online truncation
//!    ([`online`]), ALS at every level and the hybrid scheme ([`schemes`]);
//! 3. Figure 5 ([`timing::figure5`]): size ratio, time per pose and error against distance under the
//!    distance policy;
//! 4. crowd frame rates with LOD and with naive interpolation ([`crowd`]);
//! 5. leave-one-out accuracy of every method with its storage ([`accuracy`]).
//!
//! The paper's published values stand beside ours in columns labelled "paper (published)"; they are
//! the only numbers not measured by the run.

pub mod accuracy;
pub mod crowd;
pub mod figures;
pub mod gpu;
pub mod markdown;
pub mod measure;
pub mod online;
pub mod progress;
pub mod quality;
pub mod schemes;
pub mod storage;
pub mod timing;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use anyhow::{Context, Result};
use motion_lod::dataset::DataSpec;
use motion_lod::eval::EvalConfig;
use motion_lod::progress::Progress;
use motion_lod::{BuildConfig, MotionModel};

use markdown::{Table, duration_ns, percent, ranks, sig3};
use measure::Budget;

/// Settings of one `cargo xtask tables` run.
#[derive(Debug, Clone, PartialEq)]
pub struct TablesConfig {
    /// BVH folder of the data (`None`: the embedded fixtures).
    pub data: Option<PathBuf>,
    /// Use a deterministic subset of this many cycles.
    pub samples: Option<usize>,
    /// The markdown file to write.
    pub out: PathBuf,
    /// Folder of the SVG figures.
    pub figures: PathBuf,
    /// The model settings.
    pub build: BuildConfig,
    /// Timing budget per measurement.
    pub budget: Budget,
    /// Training samples whose controls drive timings and errors (strided).
    pub error_samples: usize,
    /// Distance step of Figure 5 (m).
    pub distance_step_m: f32,
    /// Crowd sizes.
    pub crowds: Vec<crowd::CrowdSize>,
    /// Crowd sizes whose frame times (median, 99th percentile, worst) are measured on each of
    /// `crowd_threads` ([`crowd::measure_frame_times`]).
    pub frame_time_sizes: Vec<crowd::CrowdSize>,
    /// Skip a baseline or full-detail crowd whose warm-up is predicted to take longer than this (s).
    pub max_naive_warmup_s: f64,
    /// Thread counts of the scaling rows (the model under its policy); the main runs use
    /// [`crowd::MAIN_THREADS`].
    pub crowd_threads: Vec<usize>,
    /// Held-out samples of the leave-one-out evaluation (`None`: all).
    pub loo_samples: Option<usize>,
    /// Folds of the cross-validation by refitting (by take when the data has that many takes).
    pub refit_folds: usize,
    /// Also cross-validate a model conditioned on the takes' styles labelled by this rule.
    pub style: Option<motion_lod::style::StyleSpec>,
    /// Show the progress display on standard error.
    pub show_progress: bool,
    /// The command line that reproduces this run, for the document.
    pub command: String,
}

impl TablesConfig {
    /// The full run: paper model settings, 5 x 10 ms timings, crowds of 100 to 100k walkers.
    pub fn full(data: Option<PathBuf>, out: PathBuf, figures: PathBuf) -> TablesConfig {
        TablesConfig {
            data,
            samples: None,
            out,
            figures,
            build: BuildConfig::default(),
            budget: Budget::full(),
            error_samples: 24,
            distance_step_m: 10.0,
            crowds: crowd::full_sizes(),
            frame_time_sizes: crowd::frame_time_sizes(),
            max_naive_warmup_s: 60.0,
            crowd_threads: vec![1, crowd::MAIN_THREADS],
            loo_samples: None,
            refit_folds: 5,
            style: None,
            show_progress: true,
            command: "cargo xtask tables".into(),
        }
    }

    /// A seconds-long configuration for smoke tests: small ranks, few levels, quick timings, two tiny
    /// crowds.
    pub fn quick(out: PathBuf, figures: PathBuf) -> TablesConfig {
        let mut build = BuildConfig {
            key_levels: 3,
            accuracy_levels: 5,
            max_ranks: [12, 10, 10],
            min_ranks: [7, 4, 4],
            importance_poses: 200,
            error_samples: 4,
            ..BuildConfig::default()
        };
        build.als.max_iter = 10;
        TablesConfig {
            data: None,
            samples: Some(16),
            out,
            figures,
            build,
            budget: Budget::quick(),
            error_samples: 3,
            distance_step_m: 50.0,
            crowds: vec![
                crowd::CrowdSize {
                    walkers: 50,
                    frames: 2,
                },
                crowd::CrowdSize {
                    walkers: 200,
                    frames: 1,
                },
            ],
            frame_time_sizes: vec![crowd::CrowdSize {
                walkers: 300,
                frames: 4,
            }],
            max_naive_warmup_s: 10.0,
            crowd_threads: vec![1, crowd::MAIN_THREADS],
            loo_samples: Some(4),
            refit_folds: 2,
            style: None,
            show_progress: false,
            command: "(smoke test)".into(),
        }
    }
}

/// What is dealt to the folds.
fn fold_plural(by: motion_lod::eval::FoldBy) -> &'static str {
    match by {
        motion_lod::eval::FoldBy::Take => "takes",
        motion_lod::eval::FoldBy::Sample => "cycles",
    }
}

/// The workspace root (parent of this crate).
pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The figures folder that goes with a tables file: `figures/` beside `tables.md`, and
/// `figures/<name>/` beside `tables-<name>.md` (or any other `<name>.md`).
pub fn figures_dir_for(out: &Path) -> PathBuf {
    let parent = out.parent().unwrap_or(Path::new("."));
    let stem = out.file_stem().and_then(|s| s.to_str()).unwrap_or("tables");
    match stem {
        "tables" => parent.join("figures"),
        _ => parent
            .join("figures")
            .join(stem.strip_prefix("tables-").unwrap_or(stem)),
    }
}

/// `target` relative to the folder `from` when it lies below it, else `target` itself (for links).
pub fn relative_link(from: &Path, target: &Path) -> String {
    let norm = |p: &Path| p.components().collect::<PathBuf>();
    match norm(target).strip_prefix(norm(from)) {
        Ok(rel) => rel.to_string_lossy().replace('\\', "/"),
        Err(_) => target.to_string_lossy().into_owned(),
    }
}

/// The machine: CPU model, family and model numbers and vector extensions (from `/proc/cpuinfo`:
/// machines of one name can differ, an "AMD EPYC" with AVX-512 or without), and available threads.
pub fn machine() -> String {
    let info = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    format!(
        "{}, {} hardware thread(s) available, {} {}",
        describe_cpu(&info),
        std::thread::available_parallelism().map_or(1, |n| n.get()),
        std::env::consts::OS,
        std::env::consts::ARCH
    )
}

/// The first processor of a `/proc/cpuinfo` text: `model name (family F, model M; AVX-512)`, the
/// widest of AVX-512 (`avx512f`), AVX2 and SSE2 its flags list; "unknown CPU" without a model name.
pub fn describe_cpu(cpuinfo: &str) -> String {
    let field = |name: &str| {
        cpuinfo
            .lines()
            .take_while(|l| !l.trim().is_empty())
            .find(|l| l.split(':').next().is_some_and(|k| k.trim() == name))
            .and_then(|l| l.split_once(':'))
            .map(|(_, v)| v.trim().to_string())
    };
    let Some(name) = field("model name") else {
        return "unknown CPU".into();
    };
    let flags = field("flags").unwrap_or_default();
    let has = |f: &str| flags.split_whitespace().any(|x| x == f);
    let vector = if has("avx512f") {
        "AVX-512"
    } else if has("avx2") {
        "AVX2, no AVX-512"
    } else {
        "no AVX2"
    };
    match (field("cpu family"), field("model")) {
        (Some(family), Some(model)) => format!("{name} (family {family}, model {model}; {vector})"),
        _ => format!("{name} ({vector})"),
    }
}

/// The commit of the workspace (`git rev-parse --short HEAD`), marked when tracked files differ from it.
/// `XTASK_COMMIT`, where set, stands for it: a copy of the tree without its history (the device
/// kit, `xtask/device/`) names the commit it was made from.
pub fn commit() -> String {
    if let Some(c) = std::env::var("XTASK_COMMIT").ok().filter(|c| !c.is_empty()) {
        return c;
    }
    let root = workspace_root();
    let git = |args: &[&str]| {
        Command::new("git")
            .args(args)
            .current_dir(&root)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    match git(&["rev-parse", "--short", "HEAD"]) {
        // The run's own outputs (docs/) do not count as changes to what was measured.
        Some(hash) => match git(&[
            "status",
            "--porcelain",
            "--untracked-files=no",
            "--",
            ".",
            ":(exclude)docs",
        ]) {
            Some(s) if s.is_empty() => hash,
            _ => format!("{hash} with uncommitted changes"),
        },
        None => "uncommitted (no git history)".into(),
    }
}

/// Runs every measurement and writes the tables and figures.
pub fn run(config: &TablesConfig) -> Result<()> {
    let started = Instant::now();
    let bar = progress::StageBar::new(config.show_progress);
    let progress: &dyn Progress = &bar;

    // Data and model.
    let spec = DataSpec {
        dirs: config.data.iter().cloned().collect(),
        samples: config.samples,
        ..DataSpec::default()
    };
    progress.stage("reading and aligning the data", 1);
    let loaded = spec
        .load_with_default(motion_io::test_data::fixture_takes(), &|_, _| {})
        .with_context(|| format!("loading {}", spec.describe()))?;
    progress.inc(1);
    let build_started = Instant::now();
    let (model, analysis) =
        MotionModel::build_with_analysis(&loaded.training, &config.build, progress)
            .context("building the model")?;
    let build_seconds = build_started.elapsed().as_secs_f64();
    let trunc = schemes::with_lod(&model, schemes::truncation_only(&model)?)?;
    let (als, als_sweeps) = schemes::als_every_level(&analysis, &config.build, progress)?;

    // Measurements.
    let [p, t, s] = analysis.tensor.dims();
    let picks = timing::picked_samples(s, config.error_samples);
    let fig4 = timing::figure4(
        &timing::Schemes {
            hybrid: &model,
            als: &als,
            truncation: &trunc,
        },
        &analysis,
        &picks,
        config.budget,
        progress,
    )?;
    let fig5 = timing::figure5(
        &model,
        &analysis,
        &picks,
        config.distance_step_m,
        config.budget,
        progress,
    )?;
    let eval_config = EvalConfig {
        max_samples: config.loo_samples,
        ..EvalConfig::default()
    };
    let refit = accuracy::refit(
        &loaded.training,
        &config.build,
        config.refit_folds,
        &EvalConfig {
            max_samples: None,
            ..eval_config
        },
        progress,
    )?;
    let styled_refit = match &config.style {
        Some(spec) => {
            let styled = loaded
                .training
                .clone()
                .with_styles(Some(spec))
                .with_context(|| format!("labelling the takes' styles by {}", spec.describe()))?;
            let refit = accuracy::refit(
                &styled,
                &config.build,
                config.refit_folds,
                &EvalConfig {
                    max_samples: None,
                    ..eval_config
                },
                progress,
            )?;
            Some((spec.describe(), refit))
        }
        None => None,
    };
    let loo = accuracy::evaluate(&analysis, &model, &eval_config, progress)?;
    let plain = accuracy::plain_vs_weighted(
        &loaded.training,
        &config.build,
        &loo,
        motion_lod::storage::Storage::of(&model).model_f64,
        &eval_config,
        progress,
    )?;
    let motion_quality = quality::measure(&model, progress)?;
    let crowd_quality = match &motion_quality {
        Some(_) => quality::measure_crowd(&model, progress)?,
        None => Vec::new(),
    };
    let crowds = crowd::measure(
        &model,
        &analysis,
        &config.crowds,
        &config.crowd_threads,
        config.max_naive_warmup_s,
        progress,
    )?;
    let frame_times = crowd::measure_frame_times(
        &model,
        &config.frame_time_sizes,
        &config.crowd_threads,
        progress,
    )?;

    // Output.
    progress.stage("writing tables and figures", 3);
    std::fs::create_dir_all(&config.figures)
        .with_context(|| format!("creating {}", config.figures.display()))?;
    let data_name = match &config.data {
        Some(d) => d
            .file_name()
            .map_or("data".into(), |n| n.to_string_lossy().into_owned()),
        None => "fixtures".into(),
    };
    let fig4_path = config.figures.join("figure4.svg");
    let fig5_path = config.figures.join("figure5.svg");
    figures::figure4(&fig4_path, &fig4, &data_name)?;
    progress.inc(1);
    figures::figure5(&fig5_path, &fig5, &data_name)?;
    progress.inc(1);
    let out_dir = config.out.parent().unwrap_or(Path::new("."));
    let mut doc = String::new();
    let _ = writeln!(doc, "# Measured tables: {}\n", spec.describe());
    let _ = writeln!(
        doc,
        "Written by `{}` ({:.0} s on this machine). Every number below was measured by that run, \
         except the columns labelled **paper (published)**, which quote Mukai and Kuriyama.\n",
        config.command,
        started.elapsed().as_secs_f64()
    );
    let _ = writeln!(doc, "- Machine: {}", machine());
    let _ = writeln!(doc, "- Commit: {}", commit());
    let _ = writeln!(
        doc,
        "- Rerun: `{}` (release build; the progress display is on standard error). The criterion \
         benchmarks: `cargo bench -p motion-lod-benches` (see the last section).",
        config.command
    );
    let _ = writeln!(
        doc,
        "- Timings are medians of {} runs of at least {} ms each, on a machine shared with other work; \
         errors are mean joint position errors after forward kinematics against the data, at the controls \
         of {} of the {s} samples.\n",
        config.budget.runs,
        config.budget.run.as_secs_f64() * 1e3,
        picks.len()
    );
    write_model_section(
        &mut doc,
        &model,
        &analysis,
        &als_sweeps,
        [p, t, s],
        build_seconds,
    );
    let _ = writeln!(doc, "## 1. Storage (paper section 5.1)\n");
    doc.push_str(&storage::section(
        &analysis,
        &model,
        &als,
        eval_config.pca_rank,
    )?);
    write_figure4(&mut doc, &fig4, &relative_link(out_dir, &fig4_path), t);
    write_figure5(&mut doc, &fig5, &relative_link(out_dir, &fig5_path), &model);
    write_crowd(&mut doc, &crowds);
    write_frame_times(
        &mut doc,
        &frame_times,
        "The scenes, density and camera paths are those above.",
    );
    doc.push_str(&gpu::section(&model));
    let _ = writeln!(
        doc,
        "\n## 5. Accuracy: held-out error per method\n\n### By refitting: {}-fold cross-validation by {} \
         (the headline figure)\n\nThe {} are dealt to {} folds; for each fold the whole pipeline (joint \
         order, row weights, key levels, the variogram chosen on the training folds, the RBF smoothing and \
         the PCA basis) is refitted on the other folds, and every method predicts the held-out cycles at \
         their own controls (`motion-lod eval DIR --folds {} --by {}`). Held out per fold: {:?} cycles. \
         Only the time alignment (reference cycle and T) is shared, fixed before the split.\n",
        refit.folds,
        refit.by.name(),
        fold_plural(refit.by),
        refit.folds,
        refit.folds,
        refit.by.name(),
        refit.fold_sizes,
    );
    doc.push_str(&accuracy::refit_table(&refit));
    if let Some((rule, styled)) = &styled_refit {
        let _ = writeln!(
            doc,
            "\n### With style as a control (`motion-lod eval DIR --folds {} --by take --style-from-name ...`)\n\n\
             The same cross-validation with each take's style ({rule}) as a control: a one-hot code per \
             style beside dx, dz, turn and height, its weight chosen on each fold's training takes by their \
             own 5-fold cross-validation. Every method gets the style (the baselines interpolate over the \
             same controls).\n",
            styled.folds
        );
        doc.push_str(&accuracy::refit_table(styled));
        doc.push_str(&accuracy::style_table(&styled.pooled));
    }
    let _ = writeln!(
        doc,
        "\n### Leave-one-out, factors fitted on all samples\n\nA fast check, not a held-out figure: the \
         Tucker factors, the PCA basis, the row weights and the variogram are fitted on all samples, the \
         one held out included (`motion-lod eval DIR`). Each sample in turn (of {} evaluated) is predicted \
         from the others at its controls; the error is against the held-out sample. Raw samples: {}. The \
         paper publishes no per-method numbers here; it states that kriging in the multilinear space is \
         more accurate than the simple restorations, and that PCA needs about four times the storage at \
         similar cost.\n",
        loo.evaluated,
        markdown::mib(loo.raw_bytes)
    );
    doc.push_str(&accuracy::table(&loo));
    let _ = writeln!(
        doc,
        "\n## 6. The paper's plain tensor against the weighted decomposition\n\nThe same data decomposed \
         as the paper does (rows unweighted: metres, radians and mean time increments; ranks from (40, 40, \
         60) to (7, 7, 9) as published, clamped to the data) and as this project does (each row weighted \
         by how far it moves the joints, `R_P` scaled by P / 94; see docs/architecture.md). Leave-one-out \
         error of every key level, as in section 5.\n"
    );
    doc.push_str(&accuracy::plain_vs_weighted_table(&plain));
    let mut figures_written = 2;
    if let Some((reference, points)) = &motion_quality {
        let path = config.figures.join("quality.svg");
        let rows = quality::level_rows(reference, points);
        let level0: Vec<(f64, f64, f64)> = points
            .iter()
            .filter(|p| p.level == 0)
            .map(|p| {
                let m = reference.at_controls(&p.walk.controls);
                (
                    f64::from(p.walk.controls.dx).hypot(f64::from(p.walk.controls.dz)),
                    p.quality.pop_cm / m.pop_cm,
                    p.quality.skate_cm_s / m.skate_cm_s,
                )
            })
            .collect();
        figures::quality_figure(&path, &rows, &level0, &data_name)?;
        figures_written += 1;
        doc.push_str(&quality::section(
            &model,
            reference,
            points,
            &relative_link(out_dir, &path),
        ));
        doc.push_str(&quality::crowd_section(&model, reference, &crowd_quality));
    } else {
        let _ = writeln!(
            doc,
            "\n## 7. Motion quality per accuracy level\n\nNot measured: the build found no feet in \
             the skeleton, so the model has no motion-quality reference.\n"
        );
    }
    write_benches(&mut doc);
    if let Some(dir) = config.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    std::fs::write(&config.out, doc)
        .with_context(|| format!("writing {}", config.out.display()))?;
    progress.inc(1);
    bar.finish();
    if config.show_progress {
        eprintln!(
            "tables: wrote {} and {} figures in {} ({:.0} s)",
            config.out.display(),
            figures_written,
            config.figures.display(),
            started.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

fn write_model_section(
    doc: &mut String,
    model: &MotionModel,
    analysis: &motion_lod::Analysis,
    als_sweeps: &[usize],
    dims: [usize; 3],
    build_seconds: f64,
) {
    let [p, t, s] = dims;
    let _ = writeln!(doc, "## The data and the model\n");
    let _ = writeln!(
        doc,
        "Motion tensor P x T x S = {p} x {t} x {s} (paper: 94 x 100 x 186). {} key levels from {} to {} \
         (paper: N = 10 from 40 x 40 x 60 to 7 x 7 x 9), {} distinct accuracy levels, built in {:.1} s; \
         ALS at every other level took {} HOOI sweeps in total. The rows are weighted by how far they move \
         the joints and `R_P` is scaled by P / 94 (docs/architecture.md; section 6 compares the paper's \
         plain tensor); `E` and the relative error are those of the weighted tensor.\n",
        analysis.keys.levels.len(),
        ranks(analysis.keys.levels[0].ranks),
        ranks(analysis.keys.levels[analysis.keys.levels.len() - 1].ranks),
        model.lod().levels().len(),
        build_seconds,
        als_sweeps.iter().sum::<usize>()
    );
    let mut t = Table::new(&["key", "ranks", ">mse E", ">relative error", ">ALS sweeps"]);
    for (k, key) in analysis.keys.levels.iter().enumerate() {
        t.row(&[
            k.to_string(),
            ranks(key.ranks),
            format!("{:.3e}", key.mse),
            percent(key.rel_error),
            key.iterations.to_string(),
        ]);
    }
    doc.push_str(&t.render());
    doc.push('\n');
}

fn write_figure4(doc: &mut String, fig: &timing::Figure4, link: &str, t: usize) {
    let _ = writeln!(
        doc,
        "\n## 2. Figure 4: time per pose and error per accuracy level\n\n![Figure 4]({link})\n\n\
         Time per pose = clip kernel / T + one pose (T = {t}), all joints. *Online truncation* keeps only \
         key 0 and cuts each level out of it per clip, unfolding the full core each time (Appendix B); \
         *ALS at every level* stores an ALS model per level; *hybrid* is the built model (key levels by \
         ALS, the levels between them truncated from the next larger key).\n\n\
         **paper (published)**: Figure 4 is a plot without values; the text says online truncation costs \
         more because of the unfolding, proportional to the full core, that the hybrid and ALS schemes \
         switch precomputed data, and that ALS slightly improves on truncation's accuracy.\n"
    );
    let mut tab = Table::new(&[
        ">level",
        "ranks",
        ">truncation: kernel",
        ">truncation: per pose",
        ">truncation: error (cm)",
        ">ALS: kernel",
        ">ALS: per pose",
        ">ALS: error (cm)",
        ">hybrid: kernel",
        ">hybrid: per pose",
        ">hybrid: error (cm)",
    ]);
    for ((tr, al), hy) in fig.truncation.iter().zip(&fig.als).zip(&fig.hybrid) {
        tab.row(&[
            hy.level.to_string(),
            ranks(hy.ranks),
            duration_ns(tr.timed.kernel_ns),
            duration_ns(tr.timed.per_pose_ns()),
            format!("{:.3}", tr.error_cm),
            duration_ns(al.timed.kernel_ns),
            duration_ns(al.timed.per_pose_ns()),
            format!("{:.3}", al.error_cm),
            duration_ns(hy.timed.kernel_ns),
            duration_ns(hy.timed.per_pose_ns()),
            format!("{:.3}", hy.error_cm),
        ]);
    }
    doc.push_str(&tab.render());
    let mean = |v: &[timing::LevelPoint]| {
        v.iter().map(|p| p.timed.per_pose_ns()).sum::<f64>() / v.len().max(1) as f64
    };
    let _ = writeln!(
        doc,
        "\nMean over levels of the time per pose: truncation {}, ALS {}, hybrid {}.",
        duration_ns(mean(&fig.truncation)),
        duration_ns(mean(&fig.als)),
        duration_ns(mean(&fig.hybrid))
    );
}

fn write_figure5(doc: &mut String, pts: &[timing::DistancePoint], link: &str, model: &MotionModel) {
    let _ = writeln!(
        doc,
        "\n## 3. Figure 5: level of detail against distance from the camera\n\n![Figure 5]({link})\n\n\
         The distance policy (`lod_policy::DistancePolicy`, defaults): full detail below 30 m, one key \
         level more every 50 m (the levels between keys spread over each step), one joint (3 DOF) fewer \
         every 10 m, root only past the last key step; then the screen check (1 px at 1080p, 60 degrees): \
         where that schedule would show more than a pixel of the level's measured error and foot slide, \
         the cheapest detail that fits and is nowhere coarser than the schedule's, among the levels \
         whose motion quality passes (section 7's *used*). Size ratio = r_P r_T r_S of the level over \
         that of level 0. The model has {} joints.\n\n\
         **paper (published)**: the same schedule (30 m, 50 m, 3 DOF per 10 m) over 10 key tensors from \
         40 x 40 x 60 to 7 x 7 x 9; Figure 5 is a plot without values. The text reports that the error \
         grows monotonically with distance with a jump past 200 m, and that time and key tensor size fall \
         exponentially with distance.\n",
        model.lod().joints()
    );
    let mut tab = Table::new(&[
        ">distance (m)",
        ">level",
        "ranks",
        ">joints",
        ">size ratio",
        ">kernel",
        ">per pose",
        ">error (cm)",
    ]);
    let levels = model.lod().levels();
    for p in pts {
        let r = levels[p.level].ranks;
        tab.row(&[
            format!("{:.0}", p.distance_m),
            p.level.to_string(),
            ranks([r.p, r.t, r.s]),
            if p.detail.active_joints == 0 {
                "root only".to_string()
            } else {
                p.detail.active_joints.min(model.lod().joints()).to_string()
            },
            format!("{:.4}", p.size_ratio),
            duration_ns(p.timed.kernel_ns),
            duration_ns(p.timed.per_pose_ns()),
            format!("{:.3}", p.error_cm),
        ]);
    }
    doc.push_str(&tab.render());
}

/// The paper's crowd frame rates (section 5.2, 100 walkers): worst, mean, best with LOD; mean naive.
const PAPER_FPS: (f64, f64, f64, f64) = (9.5, 12.0, 25.0, 3.9);

fn write_crowd(doc: &mut String, rows: &[crowd::CrowdRow]) {
    use crowd::PolicyKind::{Full, Lod, RootOnly};
    use crowd_sim::Scene;
    let _ = writeln!(
        doc,
        "\n## 4. Crowd frame rates (paper section 5.2)\n\n\
         Walkers at {} per m² (the field grows with the crowd). Two scenes: *ground*, the camera walking \
         inside the crowd (most walkers culled or beyond the last level: root only), and *overview*, the \
         camera circling above the field's edge (most of the crowd in view, at every level). A frame is \
         culling, clip kernels, poses and forward kinematics on {} threads, without rendering; the first \
         {} s (clip builds spread over the first cycle) are a warm-up, timed apart. Mean frames per \
         second (frames / total time).\n\n\
         *LOD policy* is the fair comparison: the paper's distance policy for every source, with the same \
         culling, root-only walkers and joint counts; the model also uses smaller cores with distance, PCA \
         (40 DOF components at full detail) fewer components, and naive (kriging of the raw samples) has \
         no cheaper level. Both baselines use the O(S·D) dual form of kriging. *No level of detail* puts \
         every walker, visible or not, at full detail with every source.\n",
        crowd::DENSITY,
        crowd::MAIN_THREADS,
        crowd::WARMUP_S
    );
    let fps = |r: Option<&crowd::CrowdRow>| match r {
        Some(r) => match (&r.report, &r.skipped) {
            (Some(rep), _) => sig3(rep.fps_mean),
            (None, Some(_)) => "not run".into(),
            _ => "-".into(),
        },
        None => "-".into(),
    };
    let ratio = |a, b| crowd::ratio(a, b).map_or("-".into(), |v| format!("{:.1}x", v));
    let mut sizes: Vec<usize> = rows.iter().map(|r| r.walkers).collect();
    sizes.dedup();
    sizes.sort_unstable();
    sizes.dedup();
    let mut skipped = Vec::new();
    for scene in Scene::ALL {
        let _ = writeln!(doc, "\n### {} camera\n", scene.name());
        let mut tab = Table::new(&[
            ">walkers",
            ">visible",
            ">LOD",
            ">PCA",
            ">naive",
            ">LOD / naive (fair)",
            ">LOD, no LOD",
            ">PCA, no LOD",
            ">naive, no LOD",
            ">LOD / naive, no LOD",
            ">LOD warm-up, slowest frame",
        ]);
        for &w in &sizes {
            let get = |src, pol| crowd::find(rows, scene, w, src, pol);
            let lod = get("lod", Lod);
            if lod.is_none() {
                continue;
            }
            let visible = lod
                .and_then(|r| r.report.as_ref())
                .map_or("-".into(), |r| format!("{:.0}", r.mean_visible()));
            tab.row(&[
                w.to_string(),
                visible,
                fps(lod),
                fps(get("pca", Lod)),
                fps(get("naive", Lod)),
                ratio(lod, get("naive", Lod)),
                fps(get("lod", Full)),
                fps(get("pca", Full)),
                fps(get("naive", Full)),
                ratio(get("lod", Full), get("naive", Full)),
                lod.map_or("-".into(), |r| duration_ns(r.warmup_worst_s * 1e9)),
            ]);
            for r in rows.iter().filter(|r| r.scene == scene && r.walkers == w) {
                if let Some(why) = &r.skipped {
                    let policy = r.policy.label();
                    skipped.push(format!(
                        "{} {} {policy}, {w} walkers: {why}",
                        scene.name(),
                        r.source
                    ));
                }
            }
        }
        doc.push_str(&tab.render());
    }
    if !skipped.is_empty() {
        let _ = writeln!(doc, "\nSkipped runs:\n");
        for s in &skipped {
            let _ = writeln!(doc, "- {s}");
        }
    }
    let _ = writeln!(
        doc,
        "\nStage times of the model under the LOD policy (mean per frame, wall clock) and the same rows \
         for every source and policy, with the paper's published rates for 100 walkers. The last row runs \
         the model's largest ground crowd with the culling tree (`--culling tree`: refit every frame, \
         rebuilt every 240, queried before the pass) instead of the scan inside the pass:\n"
    );
    let mut tab = Table::new(&[
        "camera",
        ">walkers",
        "source",
        "policy",
        ">fps worst",
        ">fps mean",
        ">fps best",
        ">cull / frame",
        ">kernels / frame",
        ">poses / frame",
        ">FK / frame",
        ">clips built / frame",
        "paper (published)",
    ]);
    for r in rows.iter().filter(|r| r.threads == crowd::MAIN_THREADS) {
        let Some(rep) = &r.report else { continue };
        let paper = match (r.scene, r.walkers, r.source, r.policy) {
            (Scene::Ground, 100, "lod", Lod) => {
                format!("{} / {} / {} fps", PAPER_FPS.0, PAPER_FPS.1, PAPER_FPS.2)
            }
            (Scene::Ground, 100, "naive", Full) => format!("mean {} fps", PAPER_FPS.3),
            _ => "-".into(),
        };
        let m = rep.mean_timings();
        let ms = |d: std::time::Duration| duration_ns(d.as_nanos() as f64);
        tab.row(&[
            r.scene.name().to_string(),
            r.walkers.to_string(),
            r.source.to_string(),
            r.label(),
            sig3(rep.fps_worst),
            sig3(rep.fps_mean),
            sig3(rep.fps_best),
            ms(m.cull),
            ms(m.kernels),
            ms(m.poses),
            ms(m.fk),
            format!("{:.0}", rep.kernels_built as f64 / rep.frames.max(1) as f64),
            paper,
        ]);
    }
    doc.push_str(&tab.render());
    let capped: Vec<&crowd::CrowdRow> = rows
        .iter()
        .filter(|r| matches!(r.policy, crowd::PolicyKind::UpToLevel(_)) && r.report.is_some())
        .collect();
    if !capped.is_empty() {
        let _ = writeln!(
            doc,
            "\nWhat each accuracy level saves: the model under the LOD policy with walkers that have joints \
             held to levels 0..k (where the policy would give a coarser level, the finest allowed; root-only \
             walkers unchanged), one row per level the policies use (levels whose motion quality fails \
             serve only root-only walkers: section 7), in one run on {} threads, {} timed frames each. \
             *Saved* is the mean frame time saved against level 0 and root only, in the same scene.\n",
            crowd::MAIN_THREADS,
            crowd::CAPPED_FRAMES
        );
        let mut tab = Table::new(&[
            "camera",
            ">walkers",
            "policy",
            ">fps mean",
            ">ms / frame",
            ">saved against level 0 and root only",
        ]);
        for r in &capped {
            let base = capped.iter().find(|b| {
                b.scene == r.scene
                    && b.walkers == r.walkers
                    && b.policy == crowd::PolicyKind::UpToLevel(0)
            });
            let ms = |r: &crowd::CrowdRow| r.fps().map(|f| 1e3 / f);
            let saved = match (base.and_then(|b| ms(b)), ms(r)) {
                (Some(b), Some(m)) if b > 0.0 => format!("{:.1}%", 100.0 * (b - m) / b),
                _ => "-".into(),
            };
            tab.row(&[
                r.scene.name().to_string(),
                r.walkers.to_string(),
                r.label(),
                fps(Some(r)),
                ms(r).map_or("-".into(), |m| format!("{m:.2}")),
                saved,
            ]);
        }
        doc.push_str(&tab.render());
    }
    let _ = writeln!(
        doc,
        "\nScaling: the model under the LOD policy on each thread count, in walkers animated per second \
         per thread (walkers x mean fps / threads). More threads on a bigger machine: \
         `cargo xtask tables --crowd-threads 1,2,4,8,16`, or one crowd with \
         `RAYON_NUM_THREADS=16 motion-lod crowd MODEL --walkers 100000 --density 0.01 --camera ground`. \
         The last row holds every walker root only, whatever its distance or visibility, on one thread: \
         the cost of a far or culled walker, clip builds at its cycle ends included (issue 16 asks for \
         100 ns; criterion: `crowd_root_only_one_thread` in `benches/model_file.rs`).\n"
    );
    let mut tab = Table::new(&[
        "camera",
        ">walkers",
        "policy",
        ">threads",
        ">fps mean",
        ">walkers / s / thread",
        ">ns / walker-frame",
    ]);
    for r in rows.iter().filter(|r| {
        r.source == "lod"
            && matches!(r.policy, Lod | RootOnly)
            && r.culling == crowd_sim::Culling::Scan
            && r.report.is_some()
    }) {
        tab.row(&[
            r.scene.name().to_string(),
            r.walkers.to_string(),
            r.policy.label().to_string(),
            r.threads.to_string(),
            fps(Some(r)),
            r.walkers_per_thread_s().map_or("-".into(), sig3),
            r.ns_per_walker_frame().map_or("-".into(), sig3),
        ]);
    }
    doc.push_str(&tab.render());
    let _ = writeln!(
        doc,
        "\nThe paper measured on a 2.6 GHz Athlon 64 FX-60 with its own renderer; its rates include \
         drawing, ours do not, so only the ratio LOD / naive compares."
    );
}

/// Settings of `cargo xtask frames`: the tables' frame-time rows alone, for a model file, on any
/// thread counts (issue 35 asks for them on sixteen threads, where a machine has them).
#[derive(Debug, Clone, PartialEq)]
pub struct FramesConfig {
    /// The model file.
    pub model: PathBuf,
    /// Crowd sizes (walkers).
    pub walkers: Vec<usize>,
    /// Rayon thread counts.
    pub threads: Vec<usize>,
    /// Timed frames of each row, after the [`crowd::WARMUP_S`] warm-up.
    pub frames: usize,
    /// Show the progress display on standard error.
    pub show_progress: bool,
    /// The command line that reproduces this run, for the document.
    pub command: String,
}

/// Measures the frame-time rows of `config` (both cameras, each size, each thread count, with the
/// fixed-work control after each row: [`crowd::measure_frame_times`]) and returns them as a
/// Markdown document that names the model, the command, the date, the machine and the commit.
pub fn frames(config: &FramesConfig) -> Result<String> {
    anyhow::ensure!(
        !config.walkers.is_empty() && !config.threads.is_empty(),
        "frames: no crowd size or no thread count given"
    );
    anyhow::ensure!(config.frames > 0, "frames: at least one timed frame a row");
    let model = MotionModel::load(&config.model)
        .with_context(|| format!("loading the model {}", config.model.display()))?;
    let bar = progress::StageBar::new(config.show_progress);
    let sizes: Vec<crowd::CrowdSize> = config
        .walkers
        .iter()
        .map(|&walkers| crowd::CrowdSize {
            walkers,
            frames: config.frames,
        })
        .collect();
    let rows = crowd::measure_frame_times(&model, &sizes, &config.threads, &bar)?;
    bar.finish();
    let [p, t, s] = [model.lod().p(), model.lod().t(), model.lod().s()];
    let mut doc = format!("# Frame times: {}\n\n", config.model.display());
    let _ = writeln!(
        doc,
        "Written by `{}` on {} (the rows of `cargo xtask tables` section 4's frame times, for this \
         model alone: P x T x S = {p} x {t} x {s}, density {} walkers per square metre).\n",
        config.command,
        crate::scaling::today(),
        crowd::DENSITY
    );
    let _ = writeln!(doc, "- Machine: {}", machine());
    let _ = writeln!(doc, "- Commit: {}", commit());
    write_frame_times(
        &mut doc,
        &rows,
        "The scenes are those of `motion-lod crowd --camera ground` (walking inside the crowd) and \
         `--camera overview` (circling above the field's edge), each walker on its own path.",
    );
    Ok(doc)
}

/// Frame times of the model under its policy at the largest crowds: median, 99th percentile and
/// worst against the goal, with the clip builds per frame.
/// `scenes` is the sentence that says where the scenes are described.
fn write_frame_times(doc: &mut String, rows: &[crowd::FrameTimeRow], scenes: &str) {
    if rows.is_empty() {
        return;
    }
    let _ = writeln!(
        doc,
        "\nFrame times: the model under the LOD policy, {} timed frames after the {} s warm-up, on each \
         thread count (`motion-lod crowd --json` reports the same three figures as `frame_ms`). A game \
         drops frames at the slowest one, not at the mean; the goal is the slowest frame at most {}x the \
         median. *Clips built*: clip kernels built per frame, median and most (cycle ends and detail \
         changes; a burst would show as a most far above the median). *Fixed work*: right after each row, \
         the same number of frames of fixed arithmetic on the same pool (equal tasks in the \
         first-level cache, spread by work stealing as the crowd's chunks are; no memory traffic, \
         allocation or lock), sized to the row's median: every such frame does the same work, so its \
         slowest over its median is what the machine itself gives a frame of that length. Where it is \
         above the goal, this machine cannot show the goal met. {scenes}\n",
        rows[0].times.frames,
        crowd::WARMUP_S,
        crowd::WORST_OVER_MEDIAN_GOAL
    );
    let mut tab = Table::new(&[
        "camera",
        ">walkers",
        ">threads",
        ">median (ms)",
        ">p99 (ms)",
        ">worst (ms)",
        ">worst / median",
        "goal",
        ">fixed work: worst / median",
        ">clips built a frame: median / most",
    ]);
    for r in rows {
        let ratio = r.times.worst_over_median();
        tab.row(&[
            r.scene.name().to_string(),
            r.walkers.to_string(),
            r.threads.to_string(),
            format!("{:.2}", r.times.p50_ms),
            format!("{:.2}", r.times.p99_ms),
            format!("{:.2}", r.times.worst_ms),
            format!("{ratio:.2}"),
            if ratio <= crowd::WORST_OVER_MEDIAN_GOAL {
                "met".into()
            } else {
                "not met".into()
            },
            format!("{:.2}", r.fixed_work.worst_over_median()),
            format!("{} / {}", r.builds_median, r.builds_max),
        ]);
    }
    doc.push_str(&tab.render());
}

fn write_benches(doc: &mut String) {
    let _ = writeln!(
        doc,
        "\n## 8. Criterion benchmarks\n\nNot run by this command (they take longer); run them with \
         `cargo bench -p motion-lod-benches --bench <name>`:\n"
    );
    let mut t = Table::new(&["bench", "measures"]);
    for (name, what) in [
        (
            "pose",
            "clip kernels and per-frame poses of a paper-sized runtime model",
        ),
        (
            "model_crowd",
            "clip kernels and poses of the model built from the fixtures, and one crowd frame with it (LOD, naive and PCA)",
        ),
        ("kriging", "kriging set-up and queries"),
        (
            "hosvd",
            "HOSVD, HOOI and the key-level search at 94 x 100 x 186",
        ),
        ("motion_io", "forward kinematics and pose vectors"),
        (
            "crowd",
            "one crowd frame with the procedural source; the culling tree's rebuild, refit and query beside a scan of every box",
        ),
        ("timewarp", "DTW and alignment"),
        (
            "model_file",
            "clip kernels, kriging weights and poses of a model file (`MOTION_LOD_BENCH_MODEL=FILE`, e.g. the Bandai model)",
        ),
        (
            "model_build",
            "the offline build on the embedded data set, and the clip kernel and pose of its model at the first and last accuracy levels",
        ),
        (
            "kriging_geo",
            "geostatistical kriging (`kriging::Krige`) on the problem of PyKrige's and GSTools' timings: 2,000 points, a 100 x 100 grid",
        ),
        (
            "kriging_sgs",
            "sequential Gaussian simulation: 100 realisations of a 200 x 200 grid conditioned on 2,000 points",
        ),
    ] {
        t.row(&[format!("`{name}`"), what.to_string()]);
    }
    doc.push_str(&t.render());
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Section 8 describes every `[[bench]]` of `benches/Cargo.toml`, in any order.
    #[test]
    fn the_bench_table_lists_every_bench() {
        let manifest = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../benches/Cargo.toml"
        ))
        .unwrap();
        // The first `name = "..."` after each `[[bench]]` header line.
        let mut declared = Vec::new();
        let mut in_bench = false;
        for line in manifest.lines().map(str::trim) {
            if line.starts_with('[') {
                in_bench = line == "[[bench]]";
            } else if in_bench && line.starts_with("name") {
                declared.push(line.split('"').nth(1).expect("a quoted name").to_string());
                in_bench = false;
            }
        }
        assert!(declared.len() >= 10, "{declared:?}");
        let mut doc = String::new();
        write_benches(&mut doc);
        let mut listed: Vec<String> = doc
            .lines()
            .filter_map(|l| l.strip_prefix("| `"))
            .map(|l| l.split('`').next().unwrap().to_string())
            .collect();
        declared.sort();
        listed.sort();
        assert_eq!(listed, declared);
    }

    #[test]
    fn the_cpu_is_named_with_its_family_model_and_vector_width() {
        let zen4 = "processor\t: 0\nvendor_id\t: AuthenticAMD\ncpu family\t: 25\nmodel\t\t: 17\n\
                    model name\t: AMD EPYC\nflags\t\t: fpu sse2 avx avx2 avx512f avx512bw\n\n\
                    processor\t: 1\nmodel name\t: other\n";
        assert_eq!(
            describe_cpu(zen4),
            "AMD EPYC (family 25, model 17; AVX-512)"
        );
        let zen3 = zen4.replace(" avx512f avx512bw", "").replace("17", "1");
        assert_eq!(
            describe_cpu(&zen3),
            "AMD EPYC (family 25, model 1; AVX2, no AVX-512)"
        );
        // `model name` is not `model`, and a missing family leaves the numbers out.
        assert_eq!(
            describe_cpu("model name : Some CPU\nflags : sse2\n"),
            "Some CPU (no AVX2)"
        );
        assert_eq!(describe_cpu(""), "unknown CPU");
    }

    #[test]
    fn figures_folder_follows_the_output_name() {
        assert_eq!(
            figures_dir_for(Path::new("docs/tables.md")),
            Path::new("docs/figures")
        );
        assert_eq!(
            figures_dir_for(Path::new("docs/tables-bandai.md")),
            Path::new("docs/figures/bandai")
        );
        assert_eq!(
            figures_dir_for(Path::new("out.md")),
            Path::new("figures/out")
        );
    }

    #[test]
    fn links_are_relative_below_the_document() {
        assert_eq!(
            relative_link(
                Path::new("docs"),
                Path::new("docs/figures/bandai/figure4.svg")
            ),
            "figures/bandai/figure4.svg"
        );
        assert_eq!(
            relative_link(Path::new("docs"), Path::new("/tmp/x.svg")),
            "/tmp/x.svg"
        );
    }
}
