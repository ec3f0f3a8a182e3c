//! What `motion-lod info` prints about a model: the JSON summary and the human-readable report.
//! In the library so that every consumer (the CLI, the fuzz targets, tools) shows a model the same way.

use std::io::Write;

use lod_policy::Precision;
use serde::Serialize;

use crate::MotionModel;
use crate::storage::Storage;

/// One accuracy level in the JSON summary.
#[derive(Debug, Serialize)]
pub struct LevelSummary {
    /// Key level it truncates.
    pub key: usize,
    /// Ranks (R_P, R_T, R_S).
    pub ranks: [usize; 3],
    /// Mean joint position error against full detail (cm).
    pub error_cm: f32,
    /// Shell error against full detail (cm).
    pub shell_cm: f32,
    /// Foot slide per stance beyond full detail's (cm).
    pub slide_cm: f32,
    /// The nearest distance (m) at which the larger of the shell error and the foot slide covers at
    /// most one pixel (1920 x 1080, 60 degree vertical field of view): the distance policy's screen
    /// check uses the level no nearer.
    pub one_pixel_from_m: f32,
    /// Largest pop over the quality grid's walks (every joint, seams inertialized, feet locked), as
    /// a multiple of the data's at the walk's step ([`crate::quality::QualityReference::at_step`];
    /// 0: not measured).
    pub pop_x: f32,
    /// Largest foot skate over the same walks, as a multiple of the data's at the walk's step (0:
    /// not measured).
    pub skate_x: f32,
    /// Largest floor offset over the same walks, cm (either side; 0: not measured).
    pub floor_cm: f32,
    /// Largest facing against travel outside the data's range over the same walks, degrees (0:
    /// inside, or not measured).
    pub facing_out_deg: f32,
    /// Whether the policies give this level to walkers with joints: level 0, or a level whose
    /// measured motion quality passes (`lod_policy::LevelError::passes_quality`).
    pub used: bool,
}

/// The JSON summary of a model.
#[derive(Debug, Serialize)]
pub struct Summary {
    /// Joint DOF.
    #[serde(rename = "P")]
    pub p: usize,
    /// Aligned frames.
    #[serde(rename = "T")]
    pub t: usize,
    /// Samples.
    #[serde(rename = "S")]
    pub s: usize,
    /// Rotating joints.
    pub joints: usize,
    /// Key levels.
    pub key_levels: usize,
    /// Accuracy levels.
    pub levels: Vec<LevelSummary>,
    /// Storage in bytes.
    pub storage: Storage,
    /// The styles the model conditions on, with their training cycles and takes (empty without
    /// style labels; left out of the JSON then).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub styles: Vec<StyleSummary>,
    /// The scale of the style code, when the model has styles (left out of the JSON otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub style_weight: Option<f64>,
}

/// One style of the model in the JSON summary.
#[derive(Debug, Serialize)]
pub struct StyleSummary {
    /// Its name.
    pub name: String,
    /// Training cycles of that style.
    pub cycles: usize,
    /// Takes of that style.
    pub takes: usize,
}

/// The style lines of the report: where the labels came from, each style with its cycles and
/// takes, and how the weight of the code was chosen. Empty without styles.
pub fn style_notes(model: &MotionModel) -> Vec<String> {
    let Some(st) = &model.style else {
        return Vec::new();
    };
    let mut lines = vec![format!(
        "styles ({}, from {}): {}",
        st.names.len(),
        st.spec.describe(),
        st.names
            .iter()
            .zip(&st.cycles)
            .zip(&st.takes)
            .map(|((n, c), t)| format!("{n} {c} cycles/{t} takes"))
            .collect::<Vec<_>>()
            .join(", ")
    )];
    if st.trials.is_empty() {
        lines.push(format!("style weight {} (given)", st.weight));
    } else {
        lines.push(format!(
            "style weight {} (chosen by {}-fold cross-validation by take, RMSE of the held-out cycles: {})",
            st.weight,
            crate::config::STYLE_FOLDS,
            st.trials
                .iter()
                .map(|t| format!("{} -> {:.4}", t.weight, t.rmse))
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    lines
}

/// The nearest distance (m) at which `e`'s visible error (the larger of shell error and foot slide,
/// with the policies' [`lod_policy::ERROR_MARGIN`]) covers at most one pixel of the default view
/// ([`lod_policy::ViewParams::default`]): where the policies' screen check admits the level.
pub fn one_pixel_from_m(e: &lod_policy::LevelError) -> f32 {
    lod_policy::ERROR_MARGIN * e.visible_m(true)
        / lod_policy::ViewParams::default().metres_per_pixel(1.0)
}

/// The JSON summary of `model`.
pub fn summary(model: &MotionModel) -> Summary {
    let lod = model.lod();
    let errors = lod.level_errors();
    Summary {
        p: lod.p(),
        t: lod.t(),
        s: lod.s(),
        joints: lod.joints(),
        key_levels: lod.keys().len(),
        levels: lod
            .levels()
            .iter()
            .enumerate()
            .map(|(l, lv)| LevelSummary {
                key: lv.key,
                ranks: [lv.ranks.p, lv.ranks.t, lv.ranks.s],
                error_cm: errors.get(l).map_or(f32::NAN, |e| e.mean_joint_cm),
                shell_cm: errors.get(l).map_or(f32::NAN, |e| e.shell_cm),
                slide_cm: errors.get(l).map_or(f32::NAN, |e| e.slide_cm),
                one_pixel_from_m: errors.get(l).map_or(f32::NAN, one_pixel_from_m),
                pop_x: errors.get(l).map_or(f32::NAN, |e| e.pop_x),
                skate_x: errors.get(l).map_or(f32::NAN, |e| e.skate_x),
                floor_cm: errors.get(l).map_or(f32::NAN, |e| e.floor_cm),
                facing_out_deg: errors.get(l).map_or(f32::NAN, |e| e.facing_out_deg),
                used: lod.level_serves_joints(l),
            })
            .collect(),
        storage: Storage::of(model),
        styles: model.style.as_ref().map_or_else(Vec::new, |st| {
            st.names
                .iter()
                .zip(&st.cycles)
                .zip(&st.takes)
                .map(|((name, &cycles), &takes)| StyleSummary {
                    name: name.clone(),
                    cycles,
                    takes,
                })
                .collect()
        }),
        style_weight: model.style.as_ref().map(|st| st.weight),
    }
}

/// Writes the human-readable report of `model`.
pub fn write_report(out: &mut impl Write, model: &MotionModel) -> std::io::Result<()> {
    let lod = model.lod();
    let r = &model.report;
    writeln!(
        out,
        "model: P = {} DOF ({} rotating joints), T = {} frames, S = {} samples, d = {} controls",
        lod.p(),
        lod.joints(),
        lod.t(),
        lod.s(),
        lod.d()
    )?;
    if let Some(spec) = &r.data {
        writeln!(out, "data: {}", spec.describe())?;
    }
    let range = model.control_range();
    writeln!(
        out,
        "controls: dx [{:.3}, {:.3}] m, dz [{:.3}, {:.3}] m, turn [{:.1}, {:.1}] deg, height [{:.3}, {:.3}] m",
        range[0].0,
        range[0].1,
        range[1].0,
        range[1].1,
        range[2].0.to_degrees(),
        range[2].1.to_degrees(),
        range[3].0,
        range[3].1
    )?;
    for line in control_notes(r).into_iter().chain(style_notes(model)) {
        writeln!(out, "{line}")?;
    }
    if let Some(stature) = model.stature_m() {
        let scale = |h: f32| {
            let mut c = lod_policy::Controls::from_array(range.map(|(lo, _)| lo));
            c.height = h;
            model.body_scale(&c)
        };
        writeln!(
            out,
            "skeleton: stature {stature:.3} m; characters drawn at body scale {:.3} to {:.3} (their height over it)",
            scale(range[3].0),
            scale(range[3].1)
        )?;
    }
    writeln!(
        out,
        "variogram: {:?}, nugget {:.4}, sill {:.4}, range {:.3}",
        r.variogram.model, r.variogram.nugget, r.variogram.sill, r.variogram.range
    )?;
    if !r.static_joints.is_empty() {
        let names: Vec<String> = r
            .static_joints
            .iter()
            .map(|j| format!("{} ({:.2} deg)", j.name, j.rms_deg))
            .collect();
        writeln!(
            out,
            "static joints (RMS rotation about the mean below {} deg; held, not counted): {}",
            r.config.static_rms_deg,
            names.join(", ")
        )?;
    }
    if let Some(note) = &r.order_note {
        writeln!(out, "joint order: {note}")?;
    }
    writeln!(
        out,
        "joints in evaluation order (legs before arms, left/right adjacent; error when held at the mean):"
    )?;
    let names: Vec<String> = r
        .importance
        .iter()
        .map(|j| format!("{} {:.1} cm", j.name, j.error_cm))
        .collect();
    writeln!(out, "  {}", names.join(", "))?;
    writeln!(out, "{}", describe_weights(r))?;
    writeln!(out, "key levels (ALS):")?;
    for w in r.warnings() {
        writeln!(out, "  warning: {w}")?;
    }
    writeln!(
        out,
        "  key  ranks          rel.error  MSE        sweeps  bytes (f32)"
    )?;
    for (k, key) in r.keys.iter().enumerate() {
        writeln!(
            out,
            "  {k:>3}  {:<13}  {:>9.5}  {:>9.3e}  {:>6}  {:>10}",
            format!("{:?}", key.ranks),
            key.rel_error,
            key.mse,
            key.iterations,
            lod.key_bytes(k, Precision::F32)
        )?;
    }
    writeln!(
        out,
        "accuracy levels (error against full detail: pose at the training controls, foot slide per \
         stance over the quality walks with the foot lock; 1 px from: the nearest distance where both, \
         with the policies' margin, cover one pixel at 1080p, 60 deg; pop and skate: the worst of the \
         quality walks, x the data at each walk's step length; facing: degrees the walks face against \
         travel beyond the data's range; used: whether the policies give the level to walkers with \
         joints, which needs pop <= {}, skate <= {}, the feet within {} cm of the floor and facing {}):",
        lod_policy::QUALITY_POP_LIMIT,
        lod_policy::QUALITY_SKATE_LIMIT,
        lod_policy::QUALITY_FLOOR_CM,
        lod_policy::QUALITY_FACING_OUT_DEG
    )?;
    writeln!(
        out,
        "  level  key  ranks          joint error  shell error  foot slide  1 px from    pop  skate     floor  facing  used"
    )?;
    let errors = lod.level_errors();
    for (l, lv) in lod.levels().iter().enumerate() {
        let e = errors.get(l).copied().unwrap_or_default();
        let used = lod.level_serves_joints(l);
        writeln!(
            out,
            "  {l:>5}  {:>3}  {:<13}  {:>8.3} cm  {:>8.3} cm  {:>7.2} cm  {:>6.1} m  {:>5.2}  {:>5.2}  {:>5.2} cm  {:>6.2}  {}",
            lv.key,
            format!("[{}, {}, {}]", lv.ranks.p, lv.ranks.t, lv.ranks.s),
            e.mean_joint_cm,
            e.shell_cm,
            e.slide_cm,
            one_pixel_from_m(&e),
            e.pop_x,
            e.skate_x,
            e.floor_cm,
            e.facing_out_deg,
            if used { "yes" } else { "no" }
        )?;
    }
    let st = Storage::of(model);
    writeln!(out, "storage:")?;
    writeln!(out, "  raw samples (f64)        {:>12} bytes", st.raw_f64)?;
    writeln!(
        out,
        "  hybrid model (f64)       {:>12} bytes  ({:.1}% of raw)",
        st.model_f64,
        100.0 * st.model_f64 as f64 / st.raw_f64 as f64
    )?;
    writeln!(
        out,
        "  hybrid model (f32)       {:>12} bytes  ({:.1}% of raw)",
        st.model_f32,
        100.0 * st.model_f32 as f64 / st.raw_f64 as f64
    )?;
    Ok(())
}

/// One line on the DOF row weights the decomposition used.
fn describe_weights(r: &crate::BuildReport) -> String {
    use crate::build::RowWeights;
    let w = &r.row_weights;
    match r.config.row_weights {
        RowWeights::Unit => "row weights: none (the paper's plain tensor)".to_string(),
        RowWeights::JointPosition if w.len() > crate::TIME_ROW + 1 => {
            let joints = &w[crate::TIME_ROW + 1..];
            let (lo, hi) = joints.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &v| {
                (lo.min(v), hi.max(v))
            });
            format!(
                "row weights (joint displacement per unit): root position {:.2}, root rotation {:.3}-{:.3} m/rad, \
                 joints {lo:.3}-{hi:.3} m/rad, time {:.4} m per mean increment",
                w[0],
                w[3].min(w[4]).min(w[5]),
                w[3].max(w[4]).max(w[5]),
                w[crate::TIME_ROW]
            )
        }
        RowWeights::JointPosition => format!("row weights: {w:?}"),
    }
}

/// One line per control: ignored because constant over the data, ignored because the selection
/// dropped it, dropped by the quality guard, or used, with the errors that decided it (RMSE of the
/// weighted samples, whose squared error approximates the squared joint displacement in metres:
/// of 5-fold cross-validation by take, or of leave-one-out when the data have too few takes, which
/// a first line then says).
pub fn control_notes(r: &crate::BuildReport) -> Vec<String> {
    use kriging::DimDecision;
    let mut lines = Vec::new();
    let by_loo = r.control_decisions.iter().any(|d| match d {
        DimDecision::Kept { loo_with, .. } => !loo_with.is_nan(),
        DimDecision::NoSignal { .. } => true,
        _ => false,
    });
    // Controls kept with nothing to compare against: the selection's first (one), or every varying
    // control when none could be fitted alone (`kriging::select_dims`).
    let kept_unmeasured = r
        .control_decisions
        .iter()
        .filter(|d| matches!(d, DimDecision::Kept { loo_without, .. } if loo_without.is_infinite()))
        .count();
    if by_loo {
        let takes = crate::folds::distinct_takes(&r.sources).len();
        lines.push(format!(
            "control selection by leave-one-out: {takes} {} fewer than 2 per fold of {}-fold \
             cross-validation by take",
            if takes == 1 { "take is" } else { "takes are" },
            crate::config::CONTROL_FOLDS
        ));
    }
    for (k, name) in crate::CONTROL_NAMES.iter().enumerate() {
        match r.control_decisions.get(k) {
            Some(DimDecision::Constant) if r.dropped_for_samples.contains(&k) => {
                lines.push(format!(
                    "control {name} ignored: too few samples ({}) for a trend over it too",
                    r.samples
                ));
            }
            Some(DimDecision::Constant) => {
                lines.push(format!("control {name} ignored: constant over the data"));
            }
            Some(DimDecision::NoSignal { loo_with, .. }) if !loo_with.is_finite() => {
                lines.push(format!(
                    "control {name} ignored: the kriging with it added could not be fitted"
                ));
            }
            Some(DimDecision::NoSignal {
                loo_with,
                loo_without,
                t,
            }) => lines.push(format!(
                "control {name} ignored: no signal beyond noise (leave-one-out RMSE {loo_without:.4} \
                 without it, {loo_with:.4} with it, t = {t:.2}; kept only above {:.1}% and t >= {})",
                100.0 * r.config.control_margin,
                r.config.control_min_t
            )),
            Some(DimDecision::Kept { loo_with, .. }) if loo_with.is_nan() => {
                lines.push(format!("control {name} used (no selection)"));
            }
            Some(DimDecision::Kept {
                loo_with,
                loo_without,
                ..
            }) if loo_without.is_infinite() => lines.push(if kept_unmeasured > 1 {
                format!(
                    "control {name} used: no control could be fitted alone, so every varying one \
                     is (leave-one-out RMSE {loo_with:.4})"
                )
            } else {
                format!(
                    "control {name} used: the first control kept, which the kriging needs \
                     (leave-one-out RMSE {loo_with:.4})"
                )
            }),
            Some(DimDecision::Kept {
                loo_with,
                loo_without,
                t,
            }) => lines.push(format!(
                "control {name} used: leave-one-out RMSE {loo_with:.4} with it, {loo_without:.4} \
                 without, t = {t:.2}"
            )),
            Some(DimDecision::KeptByFolds {
                cv_with,
                cv_without,
                folds,
            }) if cv_without.is_infinite() => lines.push(format!(
                "control {name} used: the only control left ({folds}-fold cross-validation by take \
                 RMSE {cv_with:.4})"
            )),
            Some(DimDecision::KeptByFolds {
                cv_with,
                cv_without,
                folds,
            }) => lines.push(format!(
                "control {name} used: {folds}-fold cross-validation by take RMSE {cv_with:.4} with \
                 it, {cv_without:.4} without"
            )),
            Some(DimDecision::DroppedByFolds {
                cv_with,
                cv_without,
                folds,
            }) => lines.push(format!(
                "control {name} ignored: leaving it out lowers the error of {folds}-fold \
                 cross-validation by take (RMSE {cv_with:.4} with it, {cv_without:.4} without; kept \
                 unless more than {:.1}% lower)",
                100.0 * r.config.control_margin
            )),
            Some(DimDecision::Overruled {
                cv_with,
                cv_without,
                folds,
            }) => lines.push(format!(
                "control {name} dropped: kept by {folds}-fold cross-validation by take (RMSE \
                 {cv_with:.4} with it, {cv_without:.4} without) but level-0 walks with it fail the \
                 motion-quality thresholds ({}; the quality guard)",
                r.overruled_quality
                    .as_ref()
                    .map_or_else(|| "figures not kept".to_string(), crate::model::quality_failures)
            )),
            None if r.dropped_controls.contains(&k) => {
                lines.push(format!("control {name} ignored: constant over the data"));
            }
            None => {}
        }
    }
    lines
}
