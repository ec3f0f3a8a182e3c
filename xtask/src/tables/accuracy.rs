//! Accuracy: mean joint position error per method with its storage (multilinear at every key level,
//! naive kriging, RBF, PCA, nearest neighbour), held out by refitting
//! ([`motion_lod::eval::k_fold`], the headline figure) and by the fast leave-one-out
//! ([`motion_lod::eval::leave_one_out`], factors fitted on all samples).

use anyhow::{Context, Result};
use lod_policy::Precision;
use motion_lod::eval::{EvalConfig, EvalReport, FoldBy, FoldReport, k_fold, leave_one_out};
use motion_lod::progress::Progress;
use motion_lod::storage::Storage;
use motion_lod::{Analysis, MotionModel};

use super::markdown::{Table, mib, percent, ranks};

/// Runs the leave-one-out evaluation of every method on the data `model` was built from.
pub fn evaluate(
    analysis: &Analysis,
    model: &MotionModel,
    config: &EvalConfig,
    progress: &dyn Progress,
) -> Result<EvalReport> {
    let key_bytes: Vec<usize> = (0..model.lod().keys().len())
        .map(|k| model.lod().key_bytes(k, Precision::F64))
        .collect();
    leave_one_out(
        analysis,
        Storage::of(model).model_f64,
        &key_bytes,
        config,
        progress,
    )
    .context("leave-one-out evaluation")
}

/// K-fold cross-validation by refitting the whole pipeline on each training split
/// ([`k_fold`]): by take when the data has at least `folds` takes, else by sample (the report says
/// which).
pub fn refit(
    training: &motion_lod::TrainingSet,
    build: &motion_lod::BuildConfig,
    folds: usize,
    config: &EvalConfig,
    progress: &dyn Progress,
) -> Result<FoldReport> {
    let by = match motion_lod::eval::fold_of_samples(&training.sources, folds, FoldBy::Take) {
        Ok(_) => FoldBy::Take,
        Err(_) => FoldBy::Sample,
    };
    k_fold(training, build, folds, by, config, progress)
        .with_context(|| format!("{folds}-fold cross-validation by refitting"))
}

/// The per-style rows of a report with styles: each style's held-out cycles and their error at
/// level 0 and by naive kriging (empty without styles).
pub fn style_table(report: &motion_lod::eval::EvalReport) -> String {
    if report.styles.is_empty() {
        return String::new();
    }
    let mut t = Table::new(&[
        "style",
        ">held-out cycles",
        ">multilinear level 0 (cm)",
        ">naive kriging (cm)",
    ]);
    for st in &report.styles {
        t.row(&[
            st.style.clone(),
            st.evaluated.to_string(),
            format!("{:.3}", st.level0_cm),
            format!("{:.3}", st.naive_cm),
        ]);
    }
    format!("\nPer style:\n\n{}", t.render())
}

/// The refit table in markdown: every method's error over all held-out cycles, and the first
/// fold's ranks and bytes.
pub fn refit_table(report: &FoldReport) -> String {
    let pooled = &report.pooled;
    let mut t = Table::new(&[
        "method",
        ">level",
        "ranks (first fold)",
        ">held-out joint error (cm)",
        ">worst shell error (cm)",
        ">storage, f64 (first fold)",
    ]);
    for m in &pooled.methods {
        t.row(&method_cells(m));
    }
    let mut out = t.render();
    let error = |name: &str, level: Option<usize>| {
        pooled
            .methods
            .iter()
            .find(|m| m.name == name && (level.is_none() || m.level == level))
            .map(|m| m.error_cm)
    };
    if let (Some(ml), Some(naive)) = (error("multilinear", Some(0)), error("naive-kriging", None)) {
        out.push_str(&format!(
            "
Refitted, multilinear level 0 is {:+.1}% from naive kriging ({ml:.3} against {naive:.3} \
             cm).\n",
            100.0 * (ml / naive - 1.0)
        ));
    }
    out
}

/// The cells both accuracy tables share: method, level, ranks, joint error, shell error, bytes.
fn method_cells(m: &motion_lod::eval::MethodError) -> [String; 6] {
    [
        m.name.clone(),
        m.level.map_or("-".into(), |l| l.to_string()),
        m.ranks.map_or("-".into(), ranks),
        format!("{:.3}", m.error_cm),
        format!("{:.2}", m.shell_cm),
        mib(m.bytes),
    ]
}

/// What each method keeps, for the table's storage column.
fn kept(name: &str) -> &'static str {
    match name {
        "multilinear" => "that key tensor (core, U_P, U_T, kriging projection)",
        "pca" => "projected samples and the DOF basis",
        _ => "every aligned sample",
    }
}

/// The accuracy table in markdown.
pub fn table(report: &EvalReport) -> String {
    let mut t = Table::new(&[
        "method",
        ">level",
        "ranks",
        ">LOO joint error (cm)",
        ">worst shell error (cm)",
        ">storage, f64",
        ">of raw",
        "storage holds",
    ]);
    for m in &report.methods {
        let mut cells = method_cells(m).to_vec();
        cells.push(percent(m.bytes as f64 / report.raw_bytes.max(1) as f64));
        cells.push(kept(&m.name).to_string());
        t.row(&cells);
    }
    t.render()
}

/// The paper's decomposition (rows unweighted, the ranks as published) beside the built one, level by
/// level: leave-one-out error and the bytes of each key tensor.
pub struct PlainVsWeighted {
    /// Leave-one-out report of the paper's plain tensor.
    pub plain: EvalReport,
    /// Hybrid model bytes (f64) of the paper's plain tensor.
    pub plain_bytes: usize,
    /// The built model's report.
    pub weighted: EvalReport,
    /// Hybrid model bytes (f64) of the built model.
    pub weighted_bytes: usize,
}

/// Builds the paper's plain decomposition of the same training data (`RowWeights::Unit`, no rank
/// scaling) and evaluates it as [`evaluate`] does.
pub fn plain_vs_weighted(
    training: &motion_lod::TrainingSet,
    config: &motion_lod::BuildConfig,
    weighted: &EvalReport,
    weighted_bytes: usize,
    eval: &EvalConfig,
    progress: &dyn Progress,
) -> Result<PlainVsWeighted> {
    let plain_config = motion_lod::BuildConfig {
        row_weights: motion_lod::build::RowWeights::Unit,
        dof_rank_reference: None,
        ..config.clone()
    };
    let (model, analysis) = MotionModel::build_with_analysis(training, &plain_config, progress)
        .context("building the paper's plain model")?;
    let plain = evaluate(&analysis, &model, eval, progress)?;
    Ok(PlainVsWeighted {
        plain_bytes: Storage::of(&model).model_f64,
        plain,
        weighted: weighted.clone(),
        weighted_bytes,
    })
}

/// The side-by-side table in markdown: key level by key level.
pub fn plain_vs_weighted_table(c: &PlainVsWeighted) -> String {
    let levels = |r: &EvalReport| -> Vec<(Option<[usize; 3]>, f64, usize)> {
        r.methods
            .iter()
            .filter(|m| m.name == "multilinear")
            .map(|m| (m.ranks, m.error_cm, m.bytes))
            .collect()
    };
    let (plain, ours) = (levels(&c.plain), levels(&c.weighted));
    let mut t = Table::new(&[
        ">key",
        "paper: ranks",
        ">LOO (cm)",
        ">key bytes, f64",
        "weighted: ranks",
        ">LOO (cm)",
        ">key bytes, f64",
    ]);
    for k in 0..plain.len().max(ours.len()) {
        let cell = |v: Option<&(Option<[usize; 3]>, f64, usize)>| match v {
            Some((r, e, b)) => [r.map_or("-".into(), ranks), format!("{e:.3}"), mib(*b)],
            None => ["-".into(), "-".into(), "-".into()],
        };
        let [pr, pe, pb] = cell(plain.get(k));
        let [wr, we, wb] = cell(ours.get(k));
        t.row(&[k.to_string(), pr, pe, pb, wr, we, wb]);
    }
    let naive = c
        .weighted
        .methods
        .iter()
        .find(|m| m.name == "naive-kriging")
        .map_or(f64::NAN, |m| m.error_cm);
    let mut out = t.render();
    out.push_str(&format!(
        "\nWhole hybrid model: paper {} ({} of raw), weighted {} ({} of raw); naive kriging of the raw \
         samples {naive:.3} cm.\n",
        mib(c.plain_bytes),
        percent(c.plain_bytes as f64 / c.plain.raw_bytes.max(1) as f64),
        mib(c.weighted_bytes),
        percent(c.weighted_bytes as f64 / c.weighted.raw_bytes.max(1) as f64),
    ));
    out
}
