//! Accuracy: leave-one-out mean joint position error per method with its storage
//! ([`motion_lod::eval::leave_one_out`]: multilinear at every key level, naive kriging, RBF, PCA,
//! nearest neighbour).

use anyhow::{Context, Result};
use lod_policy::Precision;
use motion_lod::eval::{EvalConfig, EvalReport, leave_one_out};
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
    let key_bytes: Vec<usize> = (0..model.lod.keys().len())
        .map(|k| model.lod.key_bytes(k, Precision::F64))
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
        t.row(&[
            m.name.clone(),
            m.level.map_or("-".into(), |l| l.to_string()),
            m.ranks.map_or("-".into(), ranks),
            format!("{:.3}", m.error_cm),
            format!("{:.2}", m.shell_cm),
            mib(m.bytes),
            percent(m.bytes as f64 / report.raw_bytes.max(1) as f64),
            kept(&m.name).to_string(),
        ]);
    }
    t.render()
}
