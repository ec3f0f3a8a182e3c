//! The dataset pipeline: BVH folders -> gait cycles on one skeleton -> aligned motion tensor.
//!
//! [`load_cycles`] reads every `*.bvh` of the given folders (in parallel, results in folder and
//! file-name order), builds one [`PoseLayout`] for the whole set, segments each take into steady
//! left-contact-to-left-contact cycles (`motion_io::segment_cycles`) and brings every cycle's
//! exponential maps onto the branch nearest the first kept cycle's mean pose, so that the maps are
//! continuous across samples as well as over time (docs/architecture.md).
//!
//! [`align_cycles`] maps every cycle onto `T` frames (DTW against the medoid cycle, or uniform time
//! scaling; `timewarp`) and stacks the aligned pose vectors into the motion tensor `M` of size
//! `P x T x S` (paper section 3.2), with row 6 holding the time increment in seconds to the next
//! aligned frame (the incremental inverse timewarp of section 3.1).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use motion_io::pose::TIME_ROW;
use motion_io::{
    Conventions, CycleConfig, DropReason, DroppedCycle, FootNames, GaitCycle, MeasuredControls,
    Motion, NormalizeOptions, NormalizedTake, PoseError, PoseLayout, SignedAxis, SkippedFrames,
    Units, align_sequence, find_feet, normalize_take, read_bvh, segment_take, standing_height,
};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use tensor_ops::Tensor3;

pub use crate::folds::take_of;
use crate::quality::{self, FootJoints, MotionQuality, QualityReference};
use crate::style::{StyleError, StyleLabels, StyleSpec};
use timewarp::{AlignConfig, AlignMethod, FrameSeq, TimewarpError, align};

/// Aligned training data: the motion tensor and what each sample is (what [`DataSpec::load`]
/// gives and `MotionModel::build` takes).
#[derive(Debug, Clone)]
pub struct TrainingSet {
    /// Pose layout of every sample (rows of the tensor).
    pub layout: PoseLayout,
    /// Motion tensor `P x T x S`; row 6 holds the time increment in seconds.
    pub tensor: Tensor3,
    /// Controls `(dx, dz, turn, height)` per sample (metres, metres, radians, metres).
    pub controls: Vec<[f64; 4]>,
    /// Where each sample came from (file and frame range), for reports.
    pub sources: Vec<String>,
    /// The motion-quality meter on the data's own takes, when they were measured.
    pub quality: Option<QualityReference>,
    /// The style of every sample, when the takes were labelled ([`TrainingSet::with_styles`]);
    /// `None` builds a model without styles.
    pub styles: Option<StyleLabels>,
    /// Where the labels came from (recorded in the model's style report).
    pub style_spec: Option<StyleSpec>,
    /// The motion-quality meter on each take (its file as in `sources`, its quality and floor):
    /// what `quality` pools, and what [`TrainingSet::style_references`] pools per style.
    pub take_quality: Vec<(String, MotionQuality, f64)>,
}

impl TrainingSet {
    /// The set with every sample labelled by `spec` ([`StyleSpec::label`] on its sources), or
    /// without labels for `None`.
    pub fn with_styles(mut self, spec: Option<&StyleSpec>) -> Result<TrainingSet, StyleError> {
        self.styles = spec.map(|s| s.label(&self.sources)).transpose()?;
        self.style_spec = spec.cloned();
        Ok(self)
    }

    /// The motion-quality reference of each style's own takes (in style order; `None` for a style
    /// none of whose takes was measured), pooled as the data's reference is
    /// ([`quality::reference_from_takes`]: the median of the takes, the style's cycles' steps).
    /// `None` without styles or without the data's reference.
    pub fn style_references(&self) -> Option<Vec<Option<QualityReference>>> {
        let (labels, pooled) = (self.styles.as_ref()?, self.quality.as_ref()?);
        let style_of_take: BTreeMap<&str, usize> = self
            .sources
            .iter()
            .zip(&labels.of_sample)
            .map(|(s, &j)| (take_of(s), j))
            .collect();
        let [p, t, _] = self.tensor.dims();
        // Each take's mean step length over its samples.
        let mut steps_of_take: BTreeMap<&str, Vec<f64>> = BTreeMap::new();
        for (s, c) in self.sources.iter().zip(&self.controls) {
            steps_of_take
                .entry(take_of(s))
                .or_default()
                .push(c[0].hypot(c[1]));
        }
        let take_steps: BTreeMap<&str, f64> = steps_of_take
            .iter()
            .filter_map(|(&take, steps)| Some((take, mean_step(steps)?)))
            .collect();
        Some(
            (0..labels.len())
                .map(|j| {
                    let takes: Vec<(MotionQuality, f64, f64)> = self
                        .take_quality
                        .iter()
                        .filter(|(take, _, _)| style_of_take.get(take.as_str()) == Some(&j))
                        .filter_map(|(take, q, floor)| {
                            Some((*q, *floor, *take_steps.get(take.as_str())?))
                        })
                        .collect();
                    let steps = (0..self.controls.len())
                        .filter(|&i| labels.of_sample[i] == j)
                        .map(|i| {
                            let c = self.controls[i];
                            let x = self.tensor.sample(i);
                            let duration: f64 = (0..t).map(|f| x[f * p + TIME_ROW_SECONDS]).sum();
                            (c[0].hypot(c[1]), duration)
                        })
                        .collect();
                    quality::reference_from_takes(&pooled.feet, pooled.stature_m, &takes, steps)
                })
                .collect(),
        )
    }

    /// The posture of each style's cycles ([`crate::posture::style_postures`]); `None` without
    /// styles or without clear knees and head.
    pub fn style_postures(&self) -> Option<Vec<crate::posture::StylePosture>> {
        let labels = self.styles.as_ref()?;
        crate::posture::style_postures(&self.layout, &self.tensor, &labels.names, &labels.of_sample)
    }

    /// The kriging's raw parameters, `S x d`: the four controls of each sample, then its style's
    /// one-hot code when the set has styles.
    pub fn control_matrix(&self) -> faer::Mat<f64> {
        control_matrix(&self.controls, self.styles.as_ref())
    }
}

/// The raw parameter matrix of samples with `controls` and optional style `labels` (`S x d`,
/// `d = 4 + styles`): what the build's kriging and every baseline interpolate over.
pub fn control_matrix(controls: &[[f64; 4]], labels: Option<&StyleLabels>) -> faer::Mat<f64> {
    let n = labels.map_or(0, StyleLabels::len);
    faer::Mat::from_fn(controls.len(), 4 + n, |i, k| {
        if k < 4 {
            controls[i][k]
        } else {
            labels.map_or(0.0, |l| f64::from(u8::from(l.of_sample[i] == k - 4)))
        }
    })
}

/// Row of a training set's pose vectors holding the time increment in seconds.
const TIME_ROW_SECONDS: usize = lod_policy::TIME_ROW;

/// Errors of the dataset pipeline. Failures of single files are not errors: they are reported in
/// [`CycleSet::failed`] and the file is skipped.
#[derive(Debug, thiserror::Error)]
pub enum DatasetError {
    /// A subset of no cycles was asked for ([`DataSpec::samples`] = `Some(0)`); refused before
    /// anything is read.
    #[error("samples = 0: a subset needs at least 1 cycle (leave samples unset to use them all)")]
    NoSamplesAsked,
    /// A subset larger than the data was asked for.
    #[error(
        "{asked} samples asked for, but the data has {available} usable cycles: ask for at most {available} (or build from all of them)"
    )]
    TooManySamples {
        /// The subset size asked for.
        asked: usize,
        /// The cycles kept from the data.
        available: usize,
    },
    /// No folder was given (and no default takes).
    #[error(
        "no input folder given (the default data set is built into the motion-lod binary, not the library)"
    )]
    NoInput,
    /// A folder could not be listed.
    #[error("cannot list folder {}: {source}", path.display())]
    Folder {
        /// The folder.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// One folder was given twice (under two names or the same one): every take would be read
    /// twice, each sample with a twin.
    #[error(
        "{} and {} are the same folder: each take would be read twice; give it once",
        first.display(),
        second.display()
    )]
    SameFolder {
        /// The folder as first given.
        first: PathBuf,
        /// The same folder given again.
        second: PathBuf,
    },
    /// The folders hold no `.bvh` file.
    #[error("no .bvh file in {folders}")]
    NoFiles {
        /// The folders searched, comma-separated.
        folders: String,
    },
    /// Every file failed to read.
    #[error(
        "none of the {failed} .bvh files could be read:{}",
        list_reasons(reasons)
    )]
    NoMotions {
        /// Number of failed files.
        failed: usize,
        /// Every file with its error.
        reasons: Vec<FailedFile>,
    },
    /// Two takes have different skeletons.
    #[error(
        "{} has a different skeleton from {}: {detail}; load one skeleton per data set",
        file.display(),
        reference.display()
    )]
    SkeletonMismatch {
        /// The take that differs.
        file: PathBuf,
        /// The first take, whose skeleton defines the set.
        reference: PathBuf,
        /// Which joint differs and how.
        detail: String,
    },
    /// The pose layout could not be built from the takes.
    #[error("pose layout: {0}")]
    Layout(#[source] PoseError),
    /// No steady cycle was found in any take.
    #[error(
        "no gait cycle kept from {files} takes ({dropped} candidates dropped); every file:{}",
        list_reasons(reasons)
    )]
    NoCycles {
        /// Takes read.
        files: usize,
        /// Candidate cycles dropped.
        dropped: usize,
        /// Every `.bvh` file with the reason it gave no cycle.
        reasons: Vec<FailedFile>,
    },
    /// A cycle's poses could not be brought to the common exp-map branch.
    #[error("cycle {index} ({}): {source}", file.display())]
    Branch {
        /// Index of the cycle in the set.
        index: usize,
        /// Its take.
        file: PathBuf,
        /// The pose error.
        source: PoseError,
    },
    /// A cycle's features do not fit the layout.
    #[error("cycle {index} ({}): features do not fit the pose layout", file.display())]
    Features {
        /// Index of the cycle in the set.
        index: usize,
        /// Its take.
        file: PathBuf,
    },
    /// A joint map could not be parsed.
    #[error("joint map: {0}")]
    JointMap(String),
    /// Time alignment failed.
    #[error("time alignment: {0}")]
    Align(#[from] TimewarpError),
    /// Time alignment failed between one cycle and the reference cycle.
    #[error("time alignment of cycle {cycle} against the reference cycle {reference}: {source}")]
    AlignCycle {
        /// The cycle: its take and frames.
        cycle: String,
        /// The reference cycle: its take and frames.
        reference: String,
        /// What failed.
        #[source]
        source: TimewarpError,
    },
    /// The tensor could not be formed.
    #[error("motion tensor: {0}")]
    Tensor(#[from] tensor_ops::TensorError),
}

/// One line per file, `\n  <file>: <reason>`, for error messages.
fn list_reasons(reasons: &[FailedFile]) -> String {
    reasons
        .iter()
        .map(|f| format!("\n  {}: {}", f.path.display(), f.error))
        .collect()
}

/// Settings of [`load_cycles`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DatasetConfig {
    /// Contact detection and cycle selection (`CycleConfig::cmu()` for the CMU conversions); its
    /// `feet` names are the joint map (names not given are found by name, then by hierarchy).
    pub cycle: CycleConfig,
    /// File length units; `None` detects them from the skeleton's standing height
    /// (`motion_io::normalize`), the most common choice over the takes.
    pub units: Option<Units>,
    /// The files' up axis; `None` detects it per take and uses the most common one.
    pub up: Option<SignedAxis>,
}

/// A file that could not be used, with the reason.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FailedFile {
    /// The file.
    pub path: PathBuf,
    /// Why it was skipped (the error message, which names the line for syntax errors).
    pub error: String,
}

/// Where an aligned sample comes from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CycleSource {
    /// The take.
    pub file: PathBuf,
    /// First frame of the cycle in the take.
    pub first_frame: usize,
    /// Last frame of the cycle in the take (included).
    pub last_frame: usize,
    /// Seconds between the take's frames.
    pub frame_time: f64,
}

impl CycleSource {
    /// The sample's source as training sets record it: `<file> [<first>..=<last>]` ([`take_of`]
    /// gives the file back).
    pub fn label(&self) -> String {
        format!(
            "{} [{}..={}]",
            self.file.display(),
            self.first_frame,
            self.last_frame
        )
    }
}

/// The cycles of a data set, on one skeleton and one exp-map branch.
#[derive(Debug, Clone)]
pub struct CycleSet {
    /// The pose layout shared by every cycle.
    pub layout: PoseLayout,
    /// Kept cycles, in file order then time order.
    pub cycles: Vec<GaitCycle>,
    /// Number of `.bvh` files found.
    pub files: usize,
    /// Files that could not be read or segmented.
    pub failed: Vec<FailedFile>,
    /// Dropped candidate cycles with their take.
    pub dropped: Vec<(PathBuf, DroppedCycle)>,
    /// The motion-quality meter on the data's own takes (the steady stretch of every take that gave
    /// cycles); `None` when the feet cannot be found.
    pub quality: Option<QualityReference>,
    /// What was decided about the files' conventions (units, up axis, root positions, feet), for the
    /// set: the first take's, with the set's units and up axis.
    pub conventions: Option<Conventions>,
    /// Every file read, in file order: its cycles, dropped candidates, skipped frames, and why it gave
    /// no cycle.
    pub takes: Vec<TakeSummary>,
}

/// What one file gave.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TakeSummary {
    /// The file.
    pub path: PathBuf,
    /// Cycles kept.
    pub cycles: usize,
    /// Candidates dropped.
    pub dropped: usize,
    /// Frames left out (reference poses, jumps, standing still).
    pub skipped: Vec<SkippedFrames>,
    /// Why the file gave no cycle (`None` when it gave some).
    pub reason: Option<String>,
    /// The motion-quality meter on the take's steady stretch and the take's floor (m), when it was
    /// measured (what the data's reference pools; a style's reference pools its takes'). Not
    /// written by `cycles --json`.
    #[serde(skip)]
    pub quality: Option<(MotionQuality, f64)>,
}

impl CycleSet {
    /// Number of dropped candidates per reason (see [`drop_reason_name`]), sorted by name.
    pub fn dropped_by_reason(&self) -> BTreeMap<&'static str, usize> {
        let mut counts = BTreeMap::new();
        for (_, d) in &self.dropped {
            *counts.entry(drop_reason_name(&d.reason)).or_insert(0) += 1;
        }
        counts
    }

    /// The pose whose exp-map branches every cycle of the set was brought onto (the first cycle's mean).
    pub fn branch_reference(&self) -> Vec<f64> {
        self.cycles
            .first()
            .map(|c| mean_pose(c, self.layout.dof()))
            .unwrap_or_else(|| vec![0.0; self.layout.dof()])
    }

    /// Median cycle length in frames (the lower median; 0 without cycles).
    pub fn median_length(&self) -> usize {
        let mut lens: Vec<usize> = self.cycles.iter().map(GaitCycle::frame_count).collect();
        lens.sort_unstable();
        lens.get(lens.len().saturating_sub(1) / 2)
            .copied()
            .unwrap_or(0)
    }
}

/// A short name for a drop reason, for counting: `too short`, `too long`, `contact pattern`,
/// `asymmetric`, `start`, `stop`, `not forward`, `sharp turn`.
pub fn drop_reason_name(reason: &DropReason) -> &'static str {
    #[allow(unreachable_patterns)]
    match reason {
        DropReason::TooShort { .. } => "too short",
        DropReason::TooLong { .. } => "too long",
        DropReason::ContactPattern { .. } => "contact pattern",
        DropReason::Asymmetric { .. } => "asymmetric",
        DropReason::Start { .. } => "start",
        DropReason::Stop { .. } => "stop",
        DropReason::NotForward { .. } => "not forward",
        DropReason::SharpTurn { .. } => "sharp turn",
        _ => "other",
    }
}

/// The motion tensor of a data set and what each sample is.
#[derive(Debug, Clone)]
pub struct AlignedSet {
    /// `P x T x S`; sample `k` is a contiguous `P x T` block, one pose vector per aligned frame;
    /// row 6 is the time increment in seconds to the next aligned frame (0 at the last frame), so
    /// each sample's row 6 sums to its cycle's duration.
    pub tensor: Tensor3,
    /// Controls of each sample.
    pub controls: Vec<MeasuredControls>,
    /// Take and frames of each sample.
    pub sources: Vec<CycleSource>,
    /// The pose layout (row meaning).
    pub layout: PoseLayout,
    /// Index of the reference (medoid) sample.
    pub reference: usize,
    /// Method used for the alignment.
    pub method: AlignMethod,
}

/// Lists the `*.bvh` files (case-insensitive, not recursive) of each folder, sorted by name within a
/// folder, folders in the given order. A folder given twice is an error
/// ([`DatasetError::SameFolder`]): `cycles bvh bvh` read every take twice, and the model kept
/// controls by a leave-one-out that left each sample's twin in.
pub fn list_bvh_files(dirs: &[PathBuf]) -> Result<Vec<PathBuf>, DatasetError> {
    let mut all = Vec::new();
    let mut seen: Vec<(PathBuf, &PathBuf)> = Vec::new();
    for dir in dirs {
        let err = |source| DatasetError::Folder {
            path: dir.clone(),
            source,
        };
        let canonical = std::fs::canonicalize(dir).map_err(err)?;
        if let Some((_, first)) = seen.iter().find(|(c, _)| *c == canonical) {
            return Err(DatasetError::SameFolder {
                first: (*first).clone(),
                second: dir.clone(),
            });
        }
        seen.push((canonical, dir));
        let mut paths = Vec::new();
        for entry in std::fs::read_dir(dir).map_err(err)? {
            let p = entry.map_err(err)?.path();
            if p.is_file() && p.extension().is_some_and(|e| e.eq_ignore_ascii_case("bvh")) {
                paths.push(p);
            }
        }
        paths.sort();
        all.extend(paths);
    }
    Ok(all)
}

/// [`list_bvh_files`], or [`DatasetError::NoFiles`] naming the folders when they hold none.
fn list_bvh_files_or_none(dirs: &[PathBuf]) -> Result<Vec<PathBuf>, DatasetError> {
    let paths = list_bvh_files(dirs)?;
    if paths.is_empty() {
        return Err(DatasetError::NoFiles {
            folders: dirs
                .iter()
                .map(|d| d.display().to_string())
                .collect::<Vec<_>>()
                .join(", "),
        });
    }
    Ok(paths)
}

/// Reads every take of `dirs` and segments it into gait cycles (see the module documentation).
///
/// `progress(done, total)` is called once per file after it is read and once per take after it is
/// segmented (`total` = twice the number of files), from worker threads. Files that fail to read or
/// to segment are listed in [`CycleSet::failed`]; the result is the same for any thread count.
///
/// Errors: no folder, an unreadable folder, no `.bvh` file, no readable file, takes with different
/// skeletons, or no cycle kept at all.
pub fn load_cycles(
    dirs: &[PathBuf],
    config: &DatasetConfig,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<CycleSet, DatasetError> {
    if dirs.is_empty() {
        return Err(DatasetError::NoInput);
    }
    let paths = list_bvh_files_or_none(dirs)?;
    let total = 2 * paths.len();
    let done = AtomicUsize::new(0);
    let tick = || progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
    let read: Vec<Result<Motion, String>> = paths
        .par_iter()
        .map(|p| {
            let r = read_bvh(p).map_err(|e| e.to_string());
            tick();
            r
        })
        .collect();
    cycles_from_takes(&paths, read, config, None, &|_, _| tick())
}

/// Loads the gait cycles of BVH folders as [`load_cycles`] does, but on the layout and exp-map branches
/// of an existing cycle set (`like`): for held-out data that must match a model's training data. Takes
/// whose skeleton differs from `like`'s are errors naming the file.
pub fn load_cycles_like(
    dirs: &[PathBuf],
    config: &DatasetConfig,
    like: &CycleSet,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<CycleSet, DatasetError> {
    if dirs.is_empty() {
        return Err(DatasetError::NoInput);
    }
    // An empty held-out folder said "none of the 0 .bvh files could be read".
    let paths = list_bvh_files_or_none(dirs)?;
    let read: Vec<Result<Motion, String>> = paths
        .par_iter()
        .map(|p| read_bvh(p).map_err(|e| e.to_string()))
        .collect();
    cycles_from_takes(&paths, read, config, Some(like), progress)
}

/// Loads the gait cycles of takes held in memory as `(file name, BVH text)` pairs, as [`load_cycles`]
/// does for folders. The takes are named `fixtures/<file>` in sources and reports: this is how the
/// default data set (the procedural walker's takes in the workspace's `fixtures/` folder, regenerated
/// by `cargo xtask fixtures`) is read. No library crate embeds that set; the `motion-lod` binary does,
/// and passes it here.
pub fn load_takes_in_memory(
    takes: &[(&str, &str)],
    config: &DatasetConfig,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<CycleSet, DatasetError> {
    if takes.is_empty() {
        return Err(DatasetError::NoInput);
    }
    let paths: Vec<PathBuf> = takes
        .iter()
        .map(|(name, _)| Path::new("fixtures").join(name))
        .collect();
    let total = 2 * paths.len();
    let done = AtomicUsize::new(0);
    let tick = || progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
    let read: Vec<Result<Motion, String>> = takes
        .par_iter()
        .map(|(_, text)| {
            let r = motion_io::parse_bvh(text).map_err(|e| e.to_string());
            tick();
            r
        })
        .collect();
    cycles_from_takes(&paths, read, config, None, &|_, _| tick())
}

/// Segments already-read takes into cycles on one skeleton (shared by [`load_cycles`] and
/// [`load_takes_in_memory`]); `progress` is called once per segmented take.
fn cycles_from_takes(
    paths: &[PathBuf],
    read: Vec<Result<Motion, String>>,
    config: &DatasetConfig,
    like: Option<&CycleSet>,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<CycleSet, DatasetError> {
    let tick = || progress(0, 0);
    let mut failed = Vec::new();
    let mut read_ok: Vec<(&Path, Motion)> = Vec::new();
    for (p, r) in paths.iter().zip(read) {
        match r {
            Ok(m) if m.frame_count() == 0 => failed.push(FailedFile {
                path: p.clone(),
                error: "no frames".into(),
            }),
            Ok(m) => read_ok.push((p, m)),
            Err(error) => failed.push(FailedFile {
                path: p.clone(),
                error,
            }),
        }
    }
    if read_ok.is_empty() {
        return Err(DatasetError::NoMotions {
            failed: failed.len(),
            reasons: failed,
        });
    }
    check_skeletons(&read_ok)?;
    // Conventions per take; then the set's up axis and units (the most common), and the takes that
    // disagree normalised again with them forced, so that every take shares one skeleton.
    let mut options = NormalizeOptions {
        units: config.units,
        up: config.up,
        feet: config.cycle.feet.clone(),
    };
    if let Some(set) = like {
        if let Some(c) = &set.conventions {
            options.units = Some(c.units);
            options.up = Some(c.up);
            options.feet = c.feet.clone();
        }
    }
    let normalize = |options: &NormalizeOptions| -> Vec<Result<NormalizedTake, String>> {
        read_ok
            .par_iter()
            .map(|(_, m)| normalize_take(m, options).map_err(|e| format!("conventions: {e}")))
            .collect()
    };
    let mut normalized = normalize(&options);
    let majority = |key: &dyn Fn(&NormalizedTake) -> String| -> Option<String> {
        let mut counts: BTreeMap<String, (usize, usize)> = BTreeMap::new();
        for (i, n) in normalized.iter().enumerate() {
            if let Ok(n) = n {
                let e = counts.entry(key(n)).or_insert((0, i));
                e.0 += 1;
            }
        }
        counts
            .into_iter()
            .max_by(|a, b| a.1.0.cmp(&b.1.0).then(b.1.1.cmp(&a.1.1)))
            .map(|(k, _)| k)
    };
    let up = majority(&|n| n.conventions.up.to_string());
    let units = majority(&|n| n.conventions.units.name().to_string());
    let agree = |n: &Result<NormalizedTake, String>| match n {
        Ok(n) => {
            Some(n.conventions.up.to_string()) == up
                && Some(n.conventions.units.name().to_string()) == units
        }
        Err(_) => true,
    };
    if !normalized.iter().all(agree) {
        let first = normalized
            .iter()
            .flatten()
            .find(|n| Some(n.conventions.up.to_string()) == up)
            .map(|n| n.conventions.clone());
        if let Some(c) = first {
            let forced = NormalizeOptions {
                up: Some(c.up),
                units: units.as_deref().and_then(Units::parse),
                ..options.clone()
            };
            normalized = normalize(&forced);
        }
    }
    let mut motions: Vec<(&Path, NormalizedTake)> = Vec::new();
    for ((p, _), n) in read_ok.iter().zip(normalized) {
        match n {
            Ok(n) => motions.push((p, n)),
            Err(error) => failed.push(FailedFile {
                path: p.to_path_buf(),
                error,
            }),
        }
    }
    if motions.is_empty() {
        failed.sort_by(|a, b| a.path.cmp(&b.path));
        return Err(DatasetError::NoCycles {
            files: read_ok.len(),
            dropped: 0,
            reasons: failed,
        });
    }
    let conventions = motions[0].1.conventions.clone();
    // The joints the cycles use: the map's, else those found by name, else by the hierarchy of the
    // first take.
    let mut cycle_config = config.cycle.clone();
    cycle_config.feet = conventions.feet.clone();
    let layout = match like {
        Some(set) => {
            let reference = &set.layout.skeleton().joints;
            for (p, n) in &motions {
                let m = &n.motion;
                let same = m.skeleton.joints.len() == reference.len()
                    && m.skeleton.joints.iter().zip(reference).all(|(a, b)| {
                        a.name == b.name && a.parent == b.parent && a.channels == b.channels
                    });
                if !same {
                    return Err(DatasetError::SkeletonMismatch {
                        file: p.to_path_buf(),
                        reference: set
                            .cycles
                            .first()
                            .map(|c| c.source.clone())
                            .unwrap_or_default(),
                        detail: "the skeleton differs from the training data's".into(),
                    });
                }
            }
            set.layout.clone()
        }
        None => {
            // The layout sees only the frames that are segmented (no reference pose).
            let walking: Vec<std::borrow::Cow<'_, Motion>> =
                motions.iter().map(|(_, n)| walking_frames(n)).collect();
            let refs: Vec<&Motion> = walking.iter().map(|m| m.as_ref()).collect();
            PoseLayout::from_motions(&refs, conventions.units.per_metre()).map_err(|e| match e {
                PoseError::SkeletonMismatch {
                    motion,
                    joint,
                    what,
                } => DatasetError::SkeletonMismatch {
                    file: motions[motion].0.to_path_buf(),
                    reference: motions[0].0.to_path_buf(),
                    detail: format!("joint {joint}: {what}"),
                },
                other => DatasetError::Layout(other),
            })?
        }
    };
    let segmented: Vec<_> = motions
        .par_iter()
        .map(|(p, n)| {
            let r =
                match capture_rate_problem(n.motion.frame_time) {
                    Some(problem) => Err(problem),
                    None => segment_take(&n.motion, &layout, &cycle_config, p, &n.segments)
                        .map_err(|e| e.to_string()),
                }
                .and_then(|report| {
                    // Numbers no walk has (an OFFSET of 1e300) measure infinite controls: the
                    // take is refused here, by name, not the build later by a sample index.
                    match report
                        .cycles
                        .iter()
                        .position(|c| !c.controls.to_array().iter().all(|v| v.is_finite()))
                    {
                        Some(k) => Err(format!(
                            "cycle {} measures controls that are not finite ({:?}): the take's \
                             OFFSETs or positions hold numbers no walk has",
                            k + 1,
                            report.cycles[k].controls.to_array()
                        )),
                        None => match report.cycles.iter().position(|c| {
                            lod_policy::check_stature(c.controls.height as f32).is_err()
                        }) {
                            Some(k) => Err(format!(
                                "cycle {} measures a standing height of {:.1} m, not a body's \
                                 (0.01 to 100 m): the take's OFFSETs or positions hold numbers \
                                 no walk has, or its units are not those of the data (see --units)",
                                k + 1,
                                report.cycles[k].controls.height
                            )),
                            None => Ok(report),
                        },
                    }
                });
            tick();
            r
        })
        .collect();
    let mut cycles = Vec::new();
    let mut dropped = Vec::new();
    let found = find_feet(layout.skeleton(), &cycle_config.feet).ok();
    let feet = found.as_ref().map(FootJoints::from_feet);
    // The layout's skeleton is the first take's: its standing height, measured as each cycle's
    // height control is, scales the bones of every other take's body (the meter draws each take
    // as the model draws a character of that height).
    let stature_m = found
        .as_ref()
        .map(|f| standing_height(layout.skeleton(), f) / layout.units_per_metre())
        .filter(|h| h.is_finite() && *h > 0.0);
    let measured: Vec<Option<(MotionQuality, f64)>> = motions
        .par_iter()
        .zip(&segmented)
        .map(|((_, n), r)| {
            let (feet, report) = (feet.as_ref()?, r.as_ref().ok()?);
            let height = report.cycles.first()?.controls.height;
            let scale = stature_m.map_or(1.0, |s| height / s);
            take_quality(&layout.scaled(scale).ok()?, feet, &n.motion, &report.cycles)
        })
        .collect();
    // Each measured take's figures, floor and mean step length (what the reference pools by step).
    let takes_quality: Vec<(MotionQuality, f64, f64)> = measured
        .iter()
        .zip(&segmented)
        .filter_map(|(q, r)| {
            let (q, floor) = (*q)?;
            let cycles = &r.as_ref().ok()?.cycles;
            let steps: Vec<f64> = cycles
                .iter()
                .map(|c| c.controls.dx.hypot(c.controls.dz))
                .collect();
            Some((q, floor, mean_step(&steps)?))
        })
        .collect();
    let mut takes: Vec<TakeSummary> = failed
        .iter()
        .map(|f| TakeSummary {
            path: f.path.clone(),
            cycles: 0,
            dropped: 0,
            skipped: Vec::new(),
            reason: Some(f.error.clone()),
            quality: None,
        })
        .collect();
    for (((p, n), r), q) in motions.iter().zip(segmented).zip(measured) {
        match r {
            Ok(report) => {
                let reason = report
                    .cycles
                    .is_empty()
                    .then(|| no_cycle_reason(&report.dropped, &n.skipped));
                takes.push(TakeSummary {
                    path: p.to_path_buf(),
                    cycles: report.cycles.len(),
                    dropped: report.dropped.len(),
                    skipped: n.skipped.clone(),
                    reason,
                    quality: q,
                });
                cycles.extend(report.cycles);
                dropped.extend(report.dropped.into_iter().map(|d| (p.to_path_buf(), d)));
            }
            Err(e) => {
                let error = e.clone();
                takes.push(TakeSummary {
                    path: p.to_path_buf(),
                    cycles: 0,
                    dropped: 0,
                    skipped: n.skipped.clone(),
                    reason: Some(error.clone()),
                    quality: None,
                });
                failed.push(FailedFile {
                    path: p.to_path_buf(),
                    error,
                })
            }
        }
    }
    // Keep the failures in file order whatever stage they come from.
    failed.sort_by(|a, b| a.path.cmp(&b.path));
    takes.sort_by(|a, b| a.path.cmp(&b.path));
    if cycles.is_empty() {
        return Err(DatasetError::NoCycles {
            files: motions.len(),
            dropped: dropped.len(),
            reasons: takes
                .iter()
                .map(|t| FailedFile {
                    path: t.path.clone(),
                    error: t.reason.clone().unwrap_or_default(),
                })
                .collect(),
        });
    }
    let reference = match like {
        Some(set) => set.branch_reference(),
        None => mean_pose(&cycles[0], layout.dof()),
    };
    unify_branches(&mut cycles, &reference)?;
    let steps = cycles
        .iter()
        .map(|c| (c.controls.dx.hypot(c.controls.dz), c.duration()))
        .collect();
    let quality = feet
        .as_ref()
        .and_then(|f| quality::reference_from_takes(f, stature_m, &takes_quality, steps));
    Ok(CycleSet {
        layout,
        cycles,
        files: paths.len(),
        failed,
        dropped,
        quality,
        conventions: Some(conventions),
        takes,
    })
}

/// The mean of a take's cycle step lengths (m); `None` without cycles.
fn mean_step(steps: &[f64]) -> Option<f64> {
    (!steps.is_empty()).then(|| steps.iter().sum::<f64>() / steps.len() as f64)
}

/// The take restricted to its walking segments (the whole take, borrowed, when nothing is skipped).
fn walking_frames(n: &NormalizedTake) -> std::borrow::Cow<'_, Motion> {
    let nf = n.motion.frame_count();
    if let [only] = n.segments.as_slice() {
        if only.start == 0 && only.end == nf {
            return std::borrow::Cow::Borrowed(&n.motion);
        }
    }
    let c = n.motion.skeleton.channel_count();
    let mut frames = Vec::new();
    for r in &n.segments {
        frames.extend_from_slice(&n.motion.frames[r.start * c..r.end.min(nf) * c]);
    }
    if frames.is_empty() {
        return std::borrow::Cow::Borrowed(&n.motion);
    }
    std::borrow::Cow::Owned(Motion {
        skeleton: n.motion.skeleton.clone(),
        frame_time: n.motion.frame_time,
        frames,
    })
}

/// The capture rates a walk is taken at: frame times from 1e-4 s (10,000 frames per second) to
/// 0.25 s (4 frames per second; a step then spans two frames).
pub const CAPTURE_FRAME_TIME_S: (f64, f64) = (1e-4, 0.25);

/// Why a take's `Frame Time` (s) is no capture rate of a walk (outside [`CAPTURE_FRAME_TIME_S`]),
/// with a hint when it reads as milliseconds; `None` when it is one. The BVH reader refuses only
/// what no file can hold (zero, negative, not finite); this is the walk's own bound.
pub fn capture_rate_problem(frame_time: f64) -> Option<String> {
    let (lo, hi) = CAPTURE_FRAME_TIME_S;
    if (lo..=hi).contains(&frame_time) {
        return None;
    }
    // 33.3333 as written; 1e300 rather than its 301 digits.
    let show = |v: f64| {
        if (1e-4..1e6).contains(&v) {
            format!("{}", (v * 1e6).round() / 1e6)
        } else {
            // Four significant digits, trailing zeros left out: 1e300, 1.235e-5.
            let text = format!("{v:.3e}");
            match text.split_once('e') {
                Some((m, e)) if m.contains('.') => {
                    format!("{}e{e}", m.trim_end_matches('0').trim_end_matches('.'))
                }
                _ => text,
            }
        }
    };
    let hint = if (lo..=hi).contains(&(frame_time / 1000.0)) {
        format!(
            "; Frame Time is in seconds, and read as milliseconds it would be {} s ({} frames \
             per second)",
            show(frame_time / 1000.0),
            show(1000.0 / frame_time)
        )
    } else {
        String::new()
    };
    Some(format!(
        "Frame Time {} s ({} frames per second) is not a capture rate of a walk ({lo} to {hi} s, \
         4 to 10,000 frames per second){hint}",
        show(frame_time),
        show(1.0 / frame_time)
    ))
}

/// Why a take that read and segmented gave no cycle: its dropped candidates by reason, or no
/// candidate at all (fewer than two left contacts), and its skipped frames.
fn no_cycle_reason(dropped: &[DroppedCycle], skipped: &[SkippedFrames]) -> String {
    let mut text = if dropped.is_empty() {
        "no cycle candidate (fewer than two left foot contacts: not a walk, or the feet or up axis \
         are wrong; see --joint-map and --up)"
            .to_string()
    } else {
        let mut counts: BTreeMap<&str, usize> = BTreeMap::new();
        for d in dropped {
            *counts.entry(drop_reason_name(&d.reason)).or_insert(0) += 1;
        }
        let list: Vec<String> = counts.iter().map(|(r, n)| format!("{n} {r}")).collect();
        format!(
            "every candidate cycle dropped ({}; first: {})",
            list.join(", "),
            dropped[0].reason
        )
    };
    for s in skipped {
        text.push_str(&format!("; skipped {s}"));
    }
    text
}

/// The meter on the steady stretch of one take (from its first kept cycle's start to its last kept
/// cycle's end), against the take's own floor, and that floor (m); `None` when the take gave no cycle.
fn take_quality(
    layout: &PoseLayout,
    feet: &FootJoints,
    motion: &Motion,
    cycles: &[GaitCycle],
) -> Option<(MotionQuality, f64)> {
    let first = cycles.iter().map(|c| c.first_frame).min()?;
    let last = cycles.iter().map(|c| c.last_frame).max()?;
    let mut durations: Vec<f64> = cycles.iter().map(GaitCycle::duration).collect();
    let cycle_s = quality::median(&mut durations);
    let dof = layout.dof();
    let mut poses = vec![0.0; (last - first + 1) * dof];
    for (f, row) in (first..=last).zip(poses.chunks_exact_mut(dof)) {
        layout.pose_from_frame(motion, f, row).ok()?;
    }
    let dt = motion.frame_time;
    let q = quality::measure(layout, feet, &poses, dt, None, cycle_s, &[]).ok()?;
    let floor = quality::floor_of(layout, feet, &poses, dt, cycle_s).ok()?;
    Some((q, floor))
}

/// Checks that every take has the first take's joint names (in order), for a clear message.
fn check_skeletons(motions: &[(&Path, Motion)]) -> Result<(), DatasetError> {
    let (ref_path, first) = (&motions[0].0, &motions[0].1.skeleton);
    for (p, m) in &motions[1..] {
        let sk = &m.skeleton;
        let detail = if sk.joints.len() != first.joints.len() {
            Some(format!(
                "{} joints instead of {}",
                sk.joints.len(),
                first.joints.len()
            ))
        } else {
            sk.joints
                .iter()
                .zip(&first.joints)
                .enumerate()
                .find(|(_, (a, b))| a.name != b.name)
                .map(|(j, (a, b))| format!("joint {j} is `{}` instead of `{}`", a.name, b.name))
        };
        if let Some(detail) = detail {
            return Err(DatasetError::SkeletonMismatch {
                file: p.to_path_buf(),
                reference: ref_path.to_path_buf(),
                detail,
            });
        }
    }
    Ok(())
}

/// Mean pose of one cycle (`dof` rows).
fn mean_pose(cycle: &GaitCycle, dof: usize) -> Vec<f64> {
    let frames = cycle.frame_count() as f64;
    let mut mean = vec![0.0; dof];
    for pose in cycle.poses.chunks_exact(dof) {
        for (m, v) in mean.iter_mut().zip(pose) {
            *m += v / frames;
        }
    }
    mean
}

/// Brings every cycle onto the exp-map branch nearest `reference` (`motion_io::align_sequence`: the
/// first frame to the reference, then continuity over time).
fn unify_branches(cycles: &mut [GaitCycle], reference: &[f64]) -> Result<(), DatasetError> {
    cycles
        .par_iter_mut()
        .enumerate()
        .try_for_each(|(index, c)| {
            align_sequence(&mut c.poses, reference).map_err(|source| DatasetError::Branch {
                index,
                file: c.source.clone(),
                source,
            })
        })
}

/// Aligns every cycle of `set` onto `frames` aligned frames (`None`: the median cycle length) with
/// `method`, against the medoid cycle (chosen on the features `GaitCycle::features`: joint
/// positions in the root frame), and forms the `P x T x S` motion tensor with the time increment
/// at row 6 (see [`AlignedSet::tensor`]).
///
/// Errors: fewer than 2 aligned frames, cycles whose features or poses do not fit the layout,
/// or an alignment failure (for example a DTW band too narrow for the cycle lengths).
pub fn align_cycles(
    set: &CycleSet,
    frames: Option<usize>,
    method: AlignMethod,
) -> Result<AlignedSet, DatasetError> {
    let t_frames = frames.unwrap_or_else(|| set.median_length().max(2));
    align_with_reference(set, t_frames, method, None)
}

/// Aligns every cycle of `set` onto `frames` aligned frames against an external reference cycle (for
/// held-out data: the training set's reference, `training.cycles[aligned.reference]`), so that the
/// result lines up with the training tensor. `set` must use the training layout (see
/// [`load_cycles_like`]).
pub fn align_cycles_to(
    set: &CycleSet,
    frames: usize,
    method: AlignMethod,
    reference: &GaitCycle,
) -> Result<AlignedSet, DatasetError> {
    align_with_reference(set, frames, method, Some(reference))
}

fn align_with_reference(
    set: &CycleSet,
    t_frames: usize,
    method: AlignMethod,
    reference: Option<&GaitCycle>,
) -> Result<AlignedSet, DatasetError> {
    let p = set.layout.dof();
    debug_assert!(p > TIME_ROW);
    let all: Vec<&GaitCycle> = reference.into_iter().chain(set.cycles.iter()).collect();
    let (features, values): (Vec<FrameSeq>, Vec<FrameSeq>) = all
        .par_iter()
        .enumerate()
        .map(|(index, c)| {
            let n = c.frame_count();
            let f = c.features(&set.layout);
            if f.is_empty() || f.len() % n != 0 || c.poses.len() != n * p {
                return Err(DatasetError::Features {
                    index,
                    file: c.source.clone(),
                });
            }
            let feat = FrameSeq::new(f.len() / n, f)?;
            // The pose vector without its (empty) time row: align() inserts the increment there.
            let mut v = Vec::with_capacity(n * (p - 1));
            for pose in c.poses.chunks_exact(p) {
                v.extend_from_slice(&pose[..TIME_ROW]);
                v.extend_from_slice(&pose[TIME_ROW + 1..]);
            }
            Ok((feat, FrameSeq::new(p - 1, v)?))
        })
        .collect::<Result<Vec<_>, DatasetError>>()?
        .into_iter()
        .unzip();
    let frame_time: Vec<f64> = all.iter().map(|c| c.frame_time).collect();
    let mut config = AlignConfig::new(t_frames, method);
    config.increment_row = Some(TIME_ROW);
    if reference.is_some() {
        config.reference = Some(0);
    }
    let label = |c: &GaitCycle| {
        format!(
            "{} frames {}..={}",
            c.source.display(),
            c.first_frame,
            c.last_frame
        )
    };
    let alignment = align(&features, &values, &frame_time, &config).map_err(|e| match e {
        TimewarpError::Pair {
            index,
            reference,
            source,
        } if index < all.len() && reference < all.len() => DatasetError::AlignCycle {
            cycle: label(all[index]),
            reference: label(all[reference]),
            source: *source,
        },
        other => DatasetError::Align(other),
    })?;
    debug_assert_eq!(alignment.increment_col, TIME_ROW);
    let skip = usize::from(reference.is_some());
    let s = set.cycles.len();
    let mut data = Vec::with_capacity(p * t_frames * s);
    for a in &alignment.aligned[skip..] {
        debug_assert_eq!(a.dim, p);
        data.extend_from_slice(&a.frames);
    }
    let tensor = Tensor3::from_vec([p, t_frames, s], data)?;
    Ok(AlignedSet {
        tensor,
        controls: set.cycles.iter().map(|c| c.controls).collect(),
        sources: set
            .cycles
            .iter()
            .map(|c| CycleSource {
                file: c.source.clone(),
                first_frame: c.first_frame,
                last_frame: c.last_frame,
                frame_time: c.frame_time,
            })
            .collect(),
        layout: set.layout.clone(),
        reference: alignment.reference.saturating_sub(skip),
        method,
    })
}

/// Contact-detection presets of the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum Preset {
    /// Defaults tuned on the Bandai data set (and the procedural fixtures).
    #[default]
    Default,
    /// CMU (cgspeed) conversions: ignore the first 0.1 s, looser floor height.
    Cmu,
}

impl Preset {
    /// The preset the takes' conventions call for, with the reason: [`Preset::Cmu`] when the first
    /// take (in file order) has the joints of the CMU database's cgspeed BVH conversions (`lButtock`
    /// and `rButtock` in the Daz/Poser-friendly release, `LHipJoint` and `RHipJoint` in the
    /// MotionBuilder-friendly one), else [`Preset::Default`] (`None` reason). Reads only the first
    /// take's HIERARCHY; a file that cannot be read gives the default (loading reports it).
    pub fn detect(files: &[PathBuf]) -> (Preset, Option<String>) {
        let Some(first) = files.first() else {
            return (Preset::Default, None);
        };
        let Ok(text) = std::fs::read_to_string(first) else {
            return (Preset::Default, None);
        };
        let hierarchy = text.split("MOTION").next().unwrap_or("");
        let joints: Vec<&str> = hierarchy
            .lines()
            .filter_map(|l| {
                let mut w = l.split_whitespace();
                matches!(w.next(), Some("JOINT" | "ROOT"))
                    .then(|| w.next())
                    .flatten()
            })
            .collect();
        for pair in [["lButtock", "rButtock"], ["LHipJoint", "RHipJoint"]] {
            if pair.iter().all(|j| joints.contains(j)) {
                return (
                    Preset::Cmu,
                    Some(format!(
                        "{} has the joints {} and {} of the CMU database's cgspeed BVH conversions",
                        first.display(),
                        pair[0],
                        pair[1]
                    )),
                );
            }
        }
        (Preset::Default, None)
    }

    /// The cycle settings of the preset.
    pub fn cycle_config(self) -> CycleConfig {
        match self {
            Preset::Default => CycleConfig::default(),
            Preset::Cmu => CycleConfig::cmu(),
        }
    }
}

/// Where training data comes from and how it is prepared: recorded in every model so that `eval` and
/// `crowd --compare-naive` can rebuild exactly the same training set.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DataSpec {
    /// BVH folders; empty means the default data set, which the caller supplies
    /// ([`DataSpec::load_with_default`]).
    pub dirs: Vec<PathBuf>,
    /// Aligned frames per cycle `T` (`None`: the median cycle length).
    pub frames: Option<usize>,
    /// Time alignment (`None` band: uniform time scaling).
    pub align: AlignSpec,
    /// Contact detection preset.
    pub preset: Preset,
    /// Build from a random subset of this many cycles (`None`: all; `Some(0)` is refused,
    /// [`DatasetError::NoSamplesAsked`]).
    pub samples: Option<usize>,
    /// Seed of the subset.
    pub seed: u64,
    /// Length units of the files (`None`: detected from the skeleton's standing height).
    pub units: Option<Units>,
    /// Up axis of the files (`None`: detected).
    pub up: Option<SignedAxis>,
    /// Joint names of the feet (a joint map; unset names are found by name, then by hierarchy).
    pub joint_map: FootNames,
}

/// Serializable form of [`AlignMethod`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum AlignSpec {
    /// Dynamic time warping against the medoid cycle.
    Dtw {
        /// Band as a fraction of the cycle length.
        band: f64,
        /// At most this many consecutive steps along one cycle.
        max_slope: usize,
    },
    /// Uniform time scaling.
    Uniform,
}

impl AlignSpec {
    /// The timewarp method.
    pub fn method(self) -> AlignMethod {
        match self {
            AlignSpec::Dtw { band, max_slope } => {
                AlignMethod::Dtw(timewarp::DtwConfig { band, max_slope })
            }
            AlignSpec::Uniform => AlignMethod::Uniform,
        }
    }
}

impl Default for DataSpec {
    /// The default data set (no folders), DTW alignment with the default band, all cycles.
    fn default() -> Self {
        let dtw = timewarp::DtwConfig::default();
        DataSpec {
            dirs: Vec::new(),
            frames: None,
            align: AlignSpec::Dtw {
                band: dtw.band,
                max_slope: dtw.max_slope,
            },
            preset: Preset::Default,
            samples: None,
            seed: 1,
            units: None,
            up: None,
            joint_map: FootNames::default(),
        }
    }
}

/// The result of [`DataSpec::load`]: the cycles (with counts and drop reasons), their alignment and the
/// training set (possibly a subset) ready for `MotionModel::build`.
#[derive(Debug, Clone)]
pub struct LoadedData {
    /// Every kept cycle and what was dropped.
    pub cycles: CycleSet,
    /// All kept cycles aligned.
    pub aligned: AlignedSet,
    /// The training set (`samples` of them when a subset was asked for).
    pub training: TrainingSet,
}

impl DataSpec {
    /// The dataset settings of this specification.
    pub fn dataset_config(&self) -> DatasetConfig {
        let mut cycle = self.preset.cycle_config();
        cycle.feet = self.joint_map.clone();
        DatasetConfig {
            cycle,
            units: self.units,
            up: self.up,
        }
    }

    /// The same specification with every relative folder made relative to `base` (the folder of a
    /// model file) instead of the working directory, for storing in the model. Absolute folders stay
    /// absolute; a folder that cannot be resolved is kept as given.
    pub fn relative_to(&self, base: &Path) -> DataSpec {
        let mut spec = self.clone();
        let Ok(base) = std::fs::canonicalize(base) else {
            return spec;
        };
        for d in &mut spec.dirs {
            if d.is_absolute() {
                continue;
            }
            if let Ok(full) = std::fs::canonicalize(&*d) {
                if let Some(rel) = relative_path(&full, &base) {
                    *d = rel;
                }
            }
        }
        spec
    }

    /// The specification as read from a model file in folder `base`: relative folders joined to it.
    pub fn resolved_from(&self, base: &Path) -> DataSpec {
        let mut spec = self.clone();
        for d in &mut spec.dirs {
            if d.is_relative() {
                *d = base.join(&*d);
            }
        }
        spec
    }

    /// Reads, segments and aligns the data of the folders; `progress(done, total)` is called per take
    /// read and per take segmented. A specification without folders names the default data set,
    /// which this library does not hold: it fails with [`DatasetError::NoInput`] (see
    /// [`DataSpec::load_with_default`]).
    pub fn load(
        &self,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<LoadedData, DatasetError> {
        self.load_with_default(&[], progress)
    }

    /// As [`DataSpec::load`], with `default_takes` (`(file name, BVH text)` pairs, see
    /// [`load_takes_in_memory`]) read when the specification has no folders. The `motion-lod` binary
    /// passes the default data set embedded in it; tests pass the workspace's `fixtures/`.
    pub fn load_with_default(
        &self,
        default_takes: &[(&str, &str)],
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<LoadedData, DatasetError> {
        if self.samples == Some(0) {
            return Err(DatasetError::NoSamplesAsked);
        }
        let config = self.dataset_config();
        let cycles = if self.dirs.is_empty() {
            load_takes_in_memory(default_takes, &config, progress)?
        } else {
            load_cycles(&self.dirs, &config, progress)?
        };
        let aligned = align_cycles(&cycles, self.frames, self.align.method())?;
        let mut all = aligned.training_set();
        all.quality = cycles.quality.clone();
        all.take_quality = cycles
            .takes
            .iter()
            .filter_map(|t| {
                let (q, floor) = t.quality?;
                Some((t.path.display().to_string(), q, floor))
            })
            .collect();
        let training = match self.samples {
            Some(n) if n > all.tensor.dims()[2] => {
                return Err(DatasetError::TooManySamples {
                    asked: n,
                    available: all.tensor.dims()[2],
                });
            }
            Some(n) => all.subset(n, self.seed),
            None => all,
        };
        Ok(LoadedData {
            cycles,
            aligned,
            training,
        })
    }

    /// The data alone: the folders, or "embedded fixtures" (what an error while loading names).
    pub fn describe_data(&self) -> String {
        if self.dirs.is_empty() {
            "embedded fixtures".to_string()
        } else {
            self.dirs
                .iter()
                .map(|d| d.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        }
    }

    /// A short description for reports: the folders (or "embedded fixtures") and the options.
    pub fn describe(&self) -> String {
        let data = self.describe_data();
        let align = match self.align {
            AlignSpec::Dtw { band, max_slope } => format!("dtw (band {band}, slope {max_slope})"),
            AlignSpec::Uniform => "uniform".into(),
        };
        let subset = match self.samples {
            Some(n) => format!(", {n} samples (seed {})", self.seed),
            None => String::new(),
        };
        format!("{data}; {align}{subset}")
    }
}

/// The contents of a joint-map file (TOML): the joint names of the feet; unset roles are found by
/// name or hierarchy.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct JointMapFile {
    left_foot: Option<String>,
    right_foot: Option<String>,
    left_toe: Option<String>,
    right_toe: Option<String>,
    head: Option<String>,
}

/// Parses a joint map (TOML, keys `left_foot`, `right_foot`, `left_toe`, `right_toe` and `head`, each
/// a joint name as written in the BVH files), e.g.
///
/// ```toml
/// left_foot = "Bip01 L Foot"
/// right_foot = "Bip01 R Foot"
/// ```
///
/// Errors name the line and the unknown or mistyped key.
pub fn joint_map_from_toml(text: &str) -> Result<FootNames, DatasetError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let map: JointMapFile =
        toml::from_str(text).map_err(|e| DatasetError::JointMap(e.to_string()))?;
    Ok(FootNames {
        left_foot: map.left_foot,
        right_foot: map.right_foot,
        left_toe: map.left_toe,
        right_toe: map.right_toe,
        head: map.head,
    })
}

/// `path` relative to `base` (both absolute and canonical): `..` for every component of `base` past
/// their common prefix, then the rest of `path`. `None` on different roots (Windows drives).
fn relative_path(path: &Path, base: &Path) -> Option<PathBuf> {
    let p: Vec<_> = path.components().collect();
    let b: Vec<_> = base.components().collect();
    if p.first() != b.first() {
        return None;
    }
    let common = p.iter().zip(&b).take_while(|(x, y)| x == y).count();
    let mut out = PathBuf::new();
    for _ in common..b.len() {
        out.push("..");
    }
    for c in &p[common..] {
        out.push(c.as_os_str());
    }
    if out.as_os_str().is_empty() {
        out.push(".");
    }
    Some(out)
}

impl AlignedSet {
    /// The training set of every aligned sample, for `MotionModel::build`; each source reads
    /// `<file> [<first>..=<last>]` ([`take_of`] gives the file back).
    pub fn training_set(&self) -> TrainingSet {
        TrainingSet {
            layout: self.layout.clone(),
            tensor: self.tensor.clone(),
            controls: self.controls.iter().map(|c| c.to_array()).collect(),
            quality: None,
            styles: None,
            style_spec: None,
            take_quality: Vec::new(),
            sources: self.sources.iter().map(CycleSource::label).collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_parameters_are_the_controls_then_the_style_code() {
        let labels = StyleLabels {
            names: vec!["elderly".into(), "normal".into()],
            of_sample: vec![1, 0, 1],
        };
        let params = control_matrix(&[[0.5, 1.0, 0.1, 1.7]; 3], Some(&labels));
        let row = |i: usize| {
            (0..params.ncols())
                .map(|k| params[(i, k)])
                .collect::<Vec<_>>()
        };
        assert_eq!(row(1), [0.5, 1.0, 0.1, 1.7, 1.0, 0.0]);
        assert_eq!(row(2), [0.5, 1.0, 0.1, 1.7, 0.0, 1.0]);
        assert_eq!(control_matrix(&[[0.5, 1.0, 0.1, 1.7]], None).ncols(), 4);
    }
}
