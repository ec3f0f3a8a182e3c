//! Style labels of the takes: what each performance is ("elderly", "youthful", ...), read from
//! the folder that holds the take, a CSV table or the file name, and what the build records of them.
//!
//! The model conditions on style as extra control dimensions (a one-hot code per style, scaled by
//! a weight chosen by cross-validation, see [`crate::build`]); the runtime carries the style in
//! [`lod_policy::Controls::style`] ([`StyleMix`]). Data sets name their styles the same way:
//! Bandai's `dataset-2_walk_elderly_001.bvh` gives `elderly` with the pattern
//! `_([a-z]+)_\d+\.bvh$` ([`StyleSpec::Name`]). This module is not for choosing the weight or
//! fitting anything: it only labels samples and parses the command line's blends.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use lod_policy::{MAX_STYLES, StyleMix, style_name_problem};
use serde::{Deserialize, Serialize};

use crate::folds::take_of;

/// Where the style of each take comes from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum StyleSpec {
    /// The name of the folder that holds the take (one folder per style).
    Folder,
    /// A CSV file of `take,style` rows (a header row `take,style` and `#` comments allowed); the
    /// take is the file's name, with or without `.bvh`.
    Csv(PathBuf),
    /// A regular expression searched in the take's file name (without its folder); its first
    /// capture group is the style, e.g. `_([a-z]+)_\d+\.bvh$`.
    Name(String),
}

/// Why the takes could not be labelled.
#[derive(Debug, thiserror::Error)]
pub enum StyleError {
    /// The file-name pattern is not a regular expression or has no capture group.
    #[error("style pattern {pattern:?}: {message}")]
    Pattern {
        /// The pattern given.
        pattern: String,
        /// What is wrong with it.
        message: String,
    },
    /// The CSV table could not be read or has a malformed row.
    #[error("style table {path}: {message}")]
    Table {
        /// The table.
        path: PathBuf,
        /// What is wrong, with the line number.
        message: String,
    },
    /// A take has no style under the rule.
    #[error("take {take}: {why}")]
    Unlabelled {
        /// The take.
        take: String,
        /// Why it has no style.
        why: String,
    },
    /// The styles found cannot condition a model (one style, too many, a bad name).
    #[error("styles: {0}")]
    Styles(String),
    /// A style or blend asked for is not the model's, or is malformed.
    #[error("style {given:?}: {why}")]
    Request {
        /// What was asked for.
        given: String,
        /// Why it cannot be played.
        why: String,
    },
}

/// The style of every sample of a training set.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StyleLabels {
    /// The styles, sorted by name: the order of the model's style dimensions and of
    /// [`StyleMix`]'s weights.
    pub names: Vec<String>,
    /// The style (index into `names`) of each sample.
    pub of_sample: Vec<usize>,
}

impl StyleSpec {
    /// A short description for reports: `folder names`, `table FILE`, `file names matching P`.
    pub fn describe(&self) -> String {
        match self {
            StyleSpec::Folder => "folder names".into(),
            StyleSpec::Csv(path) => format!("table {}", path.display()),
            StyleSpec::Name(pattern) => format!("file names matching {pattern}"),
        }
    }

    /// The labels of samples whose sources are `sources` (as [`crate::TrainingSet::sources`]
    /// writes them; [`take_of`] gives the take). Every take must get a style, there must be 2 to
    /// [`MAX_STYLES`] styles, and each name must be a valid style name
    /// ([`lod_policy::style_name_problem`]).
    pub fn label(&self, sources: &[String]) -> Result<StyleLabels, StyleError> {
        let of_take = self.styles_of_takes(sources)?;
        let mut names: Vec<String> = of_take.values().cloned().collect();
        names.sort();
        names.dedup();
        if names.len() < 2 {
            return Err(StyleError::Styles(format!(
                "every take is {}: a model conditions on style only when the data hold at least \
                 two (leave the style option out to build without styles)",
                names.first().map_or("unlabelled", String::as_str)
            )));
        }
        if names.len() > MAX_STYLES {
            return Err(StyleError::Styles(format!(
                "{} styles ({}): a model holds at most {MAX_STYLES}",
                names.len(),
                names.join(", ")
            )));
        }
        for name in &names {
            if let Some(why) = style_name_problem(name) {
                return Err(StyleError::Styles(format!("{name:?}: {why}")));
            }
        }
        let of_sample = sources
            .iter()
            .map(|s| {
                let style = &of_take[take_of(s)];
                names.binary_search(style).expect("a style found above")
            })
            .collect();
        Ok(StyleLabels { names, of_sample })
    }
}

impl StyleSpec {
    /// The style of each sample from `sources` as an index into `names` (a model's styles): for
    /// held-out takes, labelled by the rule the model was built with. A take whose style the model
    /// does not have is an error naming it.
    pub fn label_with(
        &self,
        sources: &[String],
        names: &[String],
    ) -> Result<Vec<usize>, StyleError> {
        let of_take = self.styles_of_takes(sources)?;
        sources
            .iter()
            .map(|s| {
                let take = take_of(s);
                let style = &of_take[take];
                names
                    .iter()
                    .position(|n| n == style)
                    .ok_or_else(|| StyleError::Unlabelled {
                        take: take.to_string(),
                        why: format!(
                            "its style {style:?} is not one of the model's ({})",
                            names.join(", ")
                        ),
                    })
            })
            .collect()
    }
}

impl StyleSpec {
    /// The style of each distinct take among `sources` (the rule applied once per take).
    fn styles_of_takes<'a>(
        &self,
        sources: &'a [String],
    ) -> Result<BTreeMap<&'a str, String>, StyleError> {
        let rule = Rule::new(self)?;
        let mut of_take = BTreeMap::new();
        for source in sources {
            let take = take_of(source);
            if !of_take.contains_key(take) {
                of_take.insert(take, rule.style_of(Path::new(take))?);
            }
        }
        Ok(of_take)
    }
}

/// A [`StyleSpec`] made ready to label takes (the pattern compiled, the table read).
enum Rule {
    Folder,
    Table(PathBuf, BTreeMap<String, String>),
    Name(String, regex_lite::Regex),
}

impl Rule {
    fn new(spec: &StyleSpec) -> Result<Rule, StyleError> {
        Ok(match spec {
            StyleSpec::Folder => Rule::Folder,
            StyleSpec::Name(pattern) => {
                let re = regex_lite::Regex::new(pattern).map_err(|e| StyleError::Pattern {
                    pattern: pattern.clone(),
                    message: e.to_string(),
                })?;
                if re.captures_len() < 2 {
                    return Err(StyleError::Pattern {
                        pattern: pattern.clone(),
                        message: "it has no capture group: put the style in parentheses, e.g. \
                                  _([a-z]+)_\\d+\\.bvh$"
                            .into(),
                    });
                }
                Rule::Name(pattern.clone(), re)
            }
            StyleSpec::Csv(path) => {
                let text = std::fs::read_to_string(path).map_err(|e| StyleError::Table {
                    path: path.clone(),
                    message: e.to_string(),
                })?;
                Rule::Table(
                    path.clone(),
                    parse_table(&text).map_err(|message| StyleError::Table {
                        path: path.clone(),
                        message,
                    })?,
                )
            }
        })
    }

    fn style_of(&self, take: &Path) -> Result<String, StyleError> {
        let file = take
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let unlabelled = |why: String| StyleError::Unlabelled {
            take: take.display().to_string(),
            why,
        };
        match self {
            Rule::Folder => take
                .parent()
                .and_then(Path::file_name)
                .map(|n| n.to_string_lossy().into_owned())
                .filter(|n| !n.is_empty())
                .ok_or_else(|| unlabelled("it is not in a named folder".into())),
            Rule::Name(pattern, re) => re
                .captures(&file)
                .and_then(|c| c.get(1))
                .map(|m| m.as_str().to_string())
                .filter(|s| !s.is_empty())
                .ok_or_else(|| {
                    unlabelled(format!(
                        "its file name {file:?} does not match {pattern} (or the group is empty)"
                    ))
                }),
            Rule::Table(path, table) => {
                let stem = file
                    .strip_suffix(".bvh")
                    .or_else(|| file.strip_suffix(".BVH"))
                    .unwrap_or(&file);
                table
                    .get(&file)
                    .or_else(|| table.get(stem))
                    .cloned()
                    .ok_or_else(|| {
                        unlabelled(format!("{} has no row for {stem:?}", path.display()))
                    })
            }
        }
    }
}

/// Parses `take,style` rows: blank lines and `#` comments skipped, an optional header
/// `take,style`, the take keyed without `.bvh`. Errors name the line.
fn parse_table(text: &str) -> Result<BTreeMap<String, String>, String> {
    // A UTF-8 byte-order mark (a spreadsheet's CSV export) is not part of the first name.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut table = BTreeMap::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let Some((take, style)) = line.split_once(',') else {
            return Err(format!("line {}: {line:?} is not `take,style`", n + 1));
        };
        let (take, style) = (take.trim(), style.trim());
        if n == 0 && take.eq_ignore_ascii_case("take") && style.eq_ignore_ascii_case("style") {
            continue;
        }
        if take.is_empty() || style.is_empty() || style.contains(',') {
            return Err(format!(
                "line {}: {line:?} is not `take,style` (two non-empty fields)",
                n + 1
            ));
        }
        let key = take
            .strip_suffix(".bvh")
            .or_else(|| take.strip_suffix(".BVH"))
            .unwrap_or(take);
        let key = Path::new(key)
            .file_name()
            .map_or(key.to_string(), |f| f.to_string_lossy().into_owned());
        if let Some(old) = table.insert(key.clone(), style.to_string())
            && old != style
        {
            return Err(format!(
                "line {}: take {key:?} is both {old:?} and {style:?}",
                n + 1
            ));
        }
    }
    if table.is_empty() {
        return Err("no `take,style` row".into());
    }
    Ok(table)
}

impl StyleLabels {
    /// Number of styles.
    pub fn len(&self) -> usize {
        self.names.len()
    }

    /// Whether there are no styles (never, for labels made by [`StyleSpec::label`]).
    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }

    /// Samples per style, in style order.
    pub fn counts(&self) -> Vec<usize> {
        let mut counts = vec![0; self.names.len()];
        for &j in &self.of_sample {
            counts[j] += 1;
        }
        counts
    }

    /// The labels of the samples at `indices`, in that order (the same style names).
    pub fn select(&self, indices: &[usize]) -> StyleLabels {
        StyleLabels {
            names: self.names.clone(),
            of_sample: indices.iter().map(|&i| self.of_sample[i]).collect(),
        }
    }
}

/// Parses a style request against a model's `styles`: one name (`elderly`), a blend of named
/// weights (`elderly=0.5,youthful=0.5`, normalised by the kernel), or `data` for the data's own mix.
/// Names match exactly, or by a unique prefix. Errors name the style and list the model's.
pub fn parse_style_mix(styles: &[String], text: &str) -> Result<StyleMix, StyleError> {
    parse_style_mix_split(styles, text, &[','])
}

/// [`parse_style_mix`] with the blend's parts split at any of `separators` (a track's CSV cell
/// writes `elderly=0.5;youthful=0.5`); errors quote `text` as given.
pub fn parse_style_mix_split(
    styles: &[String],
    text: &str,
    separators: &[char],
) -> Result<StyleMix, StyleError> {
    let err = |why: String| StyleError::Request {
        given: text.to_string(),
        why,
    };
    if styles.is_empty() {
        return Err(err(
            "the model has no styles (build it with --style-from-name, --style-from-folder or \
             --style-table)"
                .into(),
        ));
    }
    let known = || styles.join(", ");
    let trimmed = text.trim();
    if trimmed == "data" {
        return Ok(StyleMix::DATA_MIX);
    }
    let find = |name: &str| -> Result<usize, StyleError> {
        if let Some(j) = styles.iter().position(|s| s == name) {
            return Ok(j);
        }
        let matches: Vec<usize> = (0..styles.len())
            .filter(|&j| styles[j].starts_with(name) && !name.is_empty())
            .collect();
        match matches.as_slice() {
            [j] => Ok(*j),
            [] => Err(err(format!(
                "the model has no style {name:?}; its styles are {}",
                known()
            ))),
            _ => Err(err(format!(
                "{name:?} could be {}",
                matches
                    .iter()
                    .map(|&j| styles[j].as_str())
                    .collect::<Vec<_>>()
                    .join(" or ")
            ))),
        }
    };
    if !trimmed.contains('=') {
        return Ok(StyleMix::one(find(trimmed)?));
    }
    let mut mix = StyleMix::DATA_MIX;
    let mut given = vec![false; styles.len()];
    let sep = separators.first().copied().unwrap_or(',');
    for part in trimmed.split(separators) {
        let Some((name, w)) = part.split_once('=') else {
            return Err(err(format!(
                "{part:?} is not NAME=WEIGHT (a blend reads elderly=0.5{sep}youthful=0.5)"
            )));
        };
        let j = find(name.trim())?;
        let given_w = w.trim();
        let w: f64 = given_w.parse().map_err(|_| {
            err(format!(
                "weight {given_w:?} of {} is not a number",
                styles[j]
            ))
        })?;
        // Checked before the cast: 1e39 would read as an infinite f32.
        if !(w.is_finite() && w >= 0.0 && w <= f64::from(f32::MAX)) {
            return Err(err(format!(
                "weight {given_w} of {} must be finite, >= 0 and at most 3.4e38",
                styles[j]
            )));
        }
        let w = w as f32;
        if std::mem::replace(&mut given[j], true) {
            return Err(err(format!("{} is given twice", styles[j])));
        }
        mix.weights[j] = w;
    }
    if mix.is_data_mix() {
        return Err(err(
            "every weight is 0: give a positive weight (or `data` for the data's mix)".into(),
        ));
    }
    Ok(mix)
}

/// The style part of a build report, written to the model file's style section
/// ([`crate::model_file::STYLE_SECTION`]) by a model built with style labels.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StyleReport {
    /// Where the labels came from (what `eval` relabels a rebuilt training set with).
    pub spec: StyleSpec,
    /// The styles, in the model's order.
    pub names: Vec<String>,
    /// Training cycles per style.
    pub cycles: Vec<usize>,
    /// Takes per style.
    pub takes: Vec<usize>,
    /// The scale of the one-hot code in the kriging's (standardised) control space.
    pub weight: f64,
    /// How the weight was chosen: each weight tried with its cross-validated error (empty when the
    /// weight was given).
    pub trials: Vec<WeightTrial>,
    /// The posture of each style's training cycles (knee extension, head pitch;
    /// [`crate::posture`]); empty when the skeleton has no clear knees and head.
    pub posture: Vec<crate::posture::StylePosture>,
    /// The motion-quality reference of each style's own takes, in style order
    /// ([`crate::TrainingSet::style_references`]); empty when the data's takes were not measured.
    pub quality: Vec<Option<crate::quality::QualityReference>>,
}

impl StyleReport {
    /// The motion-quality reference a walk of `mix` is held to: the reference of its heaviest
    /// style's takes (a style alone: that style's), falling back to `pooled` (the data's) when that
    /// style has none. `mix` all 0 (the data's mix) gives `pooled`.
    pub fn reference_for<'a>(
        &'a self,
        mix: &StyleMix,
        pooled: Option<&'a crate::quality::QualityReference>,
    ) -> Option<&'a crate::quality::QualityReference> {
        let n = self.names.len().min(MAX_STYLES);
        let heaviest = (0..n)
            .filter(|&j| mix.weights[j] > 0.0)
            .max_by(|&a, &b| mix.weights[a].total_cmp(&mix.weights[b]).then(b.cmp(&a)));
        heaviest
            .and_then(|j| self.quality.get(j))
            .and_then(Option::as_ref)
            .or(pooled)
    }
}

/// One weight of the style code tried by the build's cross-validation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct WeightTrial {
    /// The weight.
    pub weight: f64,
    /// Root-mean-square error of the held-out cycles' (row-weighted) pose values, predicted by
    /// universal kriging refitted without their take's fold.
    pub rmse: f64,
}

impl StyleReport {
    /// Takes per style of `labels` for samples from `sources`.
    pub fn takes_per_style(labels: &StyleLabels, sources: &[String]) -> Vec<usize> {
        let mut seen: BTreeMap<&str, usize> = BTreeMap::new();
        for (i, s) in sources.iter().enumerate() {
            seen.insert(take_of(s), labels.of_sample[i]);
        }
        let mut takes = vec![0; labels.len()];
        for &j in seen.values() {
            takes[j] += 1;
        }
        takes
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sources(files: &[&str]) -> Vec<String> {
        files.iter().map(|f| format!("{f} [0..=30]")).collect()
    }

    #[test]
    fn file_names_give_styles_in_name_order() {
        let s = sources(&[
            "/d/dataset-2_walk_normal_001.bvh",
            "/d/dataset-2_walk_elderly_002.bvh",
            "/d/dataset-2_walk_normal_001.bvh",
        ]);
        let labels = StyleSpec::Name(r"_([a-z]+)_\d+\.bvh$".into())
            .label(&s)
            .unwrap();
        assert_eq!(labels.names, ["elderly", "normal"]);
        assert_eq!(labels.of_sample, [1, 0, 1]);
        assert_eq!(labels.counts(), [1, 2]);
        assert_eq!(StyleReport::takes_per_style(&labels, &s), [1, 1]);
    }

    #[test]
    fn folders_and_tables_label_takes() {
        let s = sources(&["/data/old/a.bvh", "/data/young/b.bvh"]);
        let labels = StyleSpec::Folder.label(&s).unwrap();
        assert_eq!(labels.names, ["old", "young"]);
        let table = parse_table("take,style\n# comment\na.bvh, slow\n\nb,fast\n").unwrap();
        assert_eq!(table["a"], "slow");
        assert_eq!(table["b"], "fast");
        let dir = std::env::temp_dir().join(format!("mlod-style-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let csv = dir.join("styles.csv");
        std::fs::write(&csv, "a,slow\nb,fast\n").unwrap();
        let labels = StyleSpec::Csv(csv.clone()).label(&s).unwrap();
        assert_eq!(
            (labels.names.clone(), labels.of_sample),
            (vec!["fast".to_string(), "slow".into()], vec![1, 0])
        );
        std::fs::write(&csv, "a,slow\n").unwrap();
        let e = StyleSpec::Csv(csv).label(&s).unwrap_err().to_string();
        assert!(e.contains("b.bvh") && e.contains("no row"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn bad_rules_and_data_are_clear_errors() {
        let s = sources(&["/d/x_normal_1.bvh", "/d/y.bvh"]);
        let e = StyleSpec::Name(r"_([a-z]+)_\d+\.bvh$".into())
            .label(&s)
            .unwrap_err();
        assert!(
            e.to_string().contains("y.bvh") && e.to_string().contains("does not match"),
            "{e}"
        );
        let e = StyleSpec::Name("[".into()).label(&s).unwrap_err();
        assert!(matches!(e, StyleError::Pattern { .. }), "{e}");
        let e = StyleSpec::Name(r"_[a-z]+_".into()).label(&s).unwrap_err();
        assert!(e.to_string().contains("capture group"), "{e}");
        let one = sources(&["/d/x_normal_1.bvh", "/d/y_normal_2.bvh"]);
        let e = StyleSpec::Name(r"_([a-z]+)_\d+\.bvh$".into())
            .label(&one)
            .unwrap_err();
        assert!(e.to_string().contains("at least two"), "{e}");
        let many: Vec<String> = (0..9)
            .map(|i| format!("/d/x_s{}_1.bvh [0..=1]", (b'a' + i) as char))
            .collect();
        let e = StyleSpec::Name(r"_([a-z0-9]+)_\d+\.bvh$".into())
            .label(&many)
            .unwrap_err();
        assert!(e.to_string().contains("at most 8"), "{e}");
        for bad in ["a,b,c\n", "a\n", "", "a,x\na,y\n"] {
            assert!(parse_table(bad).is_err(), "{bad:?}");
        }
    }

    #[test]
    fn requests_name_one_style_or_a_blend() {
        let styles: Vec<String> = ["elderly", "exhausted", "normal"]
            .map(String::from)
            .to_vec();
        assert_eq!(
            parse_style_mix(&styles, "normal").unwrap(),
            StyleMix::one(2)
        );
        assert_eq!(parse_style_mix(&styles, "eld").unwrap(), StyleMix::one(0));
        assert_eq!(
            parse_style_mix(&styles, "data").unwrap(),
            StyleMix::DATA_MIX
        );
        let blend = parse_style_mix(&styles, "elderly=0.5, normal=0.5").unwrap();
        assert_eq!(blend.weights[..3], [0.5, 0.0, 0.5]);
        for (bad, says) in [
            ("e", "could be elderly or exhausted"),
            ("youthful", "its styles are elderly, exhausted, normal"),
            ("elderly=x", "not a number"),
            ("elderly=-1", ">= 0"),
            ("elderly=0", "every weight is 0"),
            ("elderly=1,elderly=1", "twice"),
            // A first weight of 0 is given all the same, and a prefix names the same style.
            ("elderly=0,elderly=0.5", "twice"),
            ("eld=0.2,elderly=0.3", "twice"),
            ("elderly=1,normal", "NAME=WEIGHT"),
            // The weight as written: it said "weight inf" (found 2026-11-28).
            (
                "elderly=1e39,normal=1",
                "weight 1e39 of elderly must be finite",
            ),
        ] {
            let e = parse_style_mix(&styles, bad).unwrap_err().to_string();
            assert!(e.contains(says), "{bad}: {e}");
        }
        // A track's blend, split at `;`, is quoted as written (it was echoed with `,`).
        assert_eq!(
            parse_style_mix_split(&styles, "elderly=0.5;normal=0.5", &[';']).unwrap(),
            blend
        );
        let e = parse_style_mix_split(&styles, "elderly;normal", &[';'])
            .unwrap_err()
            .to_string();
        assert!(e.contains("\"elderly;normal\""), "{e}");
        assert!(
            parse_style_mix(&[], "normal")
                .unwrap_err()
                .to_string()
                .contains("no styles")
        );
    }
}
