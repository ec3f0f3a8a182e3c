//! Folds of a cross-validation: which held-out group each training sample belongs to, by take
//! (whole source files together) or by sample. Used by `eval --folds` and by the build's choice
//! of the style weight; it fits nothing.

use serde::{Deserialize, Serialize};

/// How a cross-validation (`crate::eval::k_fold`, the build's choice of the style weight) splits
/// the samples.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum FoldBy {
    /// Whole takes (source files) stay together: no cycle is predicted from cycles of its own take.
    Take,
    /// Sample `i` goes to fold `i mod K`.
    Sample,
}

impl FoldBy {
    /// The name the CLI's `--by` takes (`take`, `sample`).
    pub fn name(self) -> &'static str {
        match self {
            FoldBy::Take => "take",
            FoldBy::Sample => "sample",
        }
    }
}

/// The fold of every sample: by take, the distinct takes in name order dealt round-robin to the
/// `folds` folds; by sample, `i mod folds`. Errors when there are fewer takes (or samples) than
/// folds.
pub fn fold_of_samples(sources: &[String], folds: usize, by: FoldBy) -> Result<Vec<usize>, String> {
    if folds < 2 {
        return Err(format!("{folds} folds: cross-validation needs at least 2"));
    }
    match by {
        FoldBy::Sample => {
            if sources.len() < folds {
                return Err(format!(
                    "{} samples cannot fill {folds} folds",
                    sources.len()
                ));
            }
            Ok((0..sources.len()).map(|i| i % folds).collect())
        }
        FoldBy::Take => {
            let takes = distinct_takes(sources);
            if takes.len() < folds {
                return Err(format!(
                    "{} takes cannot fill {folds} folds (use fewer folds or split by sample)",
                    takes.len()
                ));
            }
            Ok(sources
                .iter()
                .map(|s| {
                    let take = take_of(s);
                    takes.binary_search(&take).map_or(0, |t| t % folds)
                })
                .collect())
        }
    }
}

/// The distinct takes ([`take_of`]) among `sources`, sorted by name.
pub fn distinct_takes(sources: &[String]) -> Vec<&str> {
    let mut takes: Vec<&str> = sources.iter().map(|s| take_of(s)).collect();
    takes.sort_unstable();
    takes.dedup();
    takes
}

/// The take (source file) of a training sample's source as [`crate::dataset::AlignedSet::training_set`] writes it
/// (`<file> [<first>..=<last>]`): the file part, or the whole string when it has no frame range.
pub fn take_of(source: &str) -> &str {
    match source.rsplit_once(" [") {
        Some((file, range)) if range.ends_with(']') => file,
        _ => source,
    }
}
