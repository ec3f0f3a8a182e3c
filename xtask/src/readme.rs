//! `cargo xtask readme`: the deterministic figures README.md quotes, each produced by a command.
//!
//! The registry, `docs/readme-figures.toml`, lists the commands (the release `motion-lod` binary,
//! or another program) and the figures: a figure is a piece of README text with placeholders
//! (`{name}`), and each placeholder's value comes from a command's output, by a JSON path or a
//! regular expression, formatted as README writes it. `--check` runs every command once, fills
//! every figure and fails with the list of figures whose README text differs (README's text beside
//! the expected one); without `--check` the README's quoted values are rewritten in place.
//!
//! A figure is found in README by its text with every placeholder read as a number, so README's
//! current values are located (and replaced) without markers in the prose. A figure that README
//! no longer contains, or contains twice, is an error of its own: the registry must follow README.
//!
//! Timing figures (fps, ms, µs, ns, minutes) depend on the machine and are not checked; instead
//! [`undated_timings`] requires every paragraph or table that quotes one to name its run's date (or
//! to say "date not recorded").
//!
//! ```
//! use xtask::readme::{Figure, compare, expected_text, locate};
//! let figure = Figure::literal("cycles", "{files} takes, {kept} cycles");
//! let values = [("files", "15"), ("kept", "60")].map(|(k, v)| (k.to_string(), v.to_string()));
//! let expected = expected_text(&figure, &values.into())?;
//! assert_eq!(expected, "15 takes, 60 cycles");
//! assert_eq!(locate(&figure, "the walker (15 takes, 60 cycles)")?.len(), 1);
//! let ok = compare(&[(&figure, expected.clone())], "the walker (15 takes, 60 cycles)");
//! assert!(ok.is_empty());
//! let stale = compare(&[(&figure, expected)], "the walker (15 takes, 61 cycles)");
//! assert_eq!(stale.len(), 1);
//! # Ok::<(), anyhow::Error>(())
//! ```

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use anyhow::{Context, Result, anyhow, bail};
use regex_lite::Regex;
use serde::Deserialize;
use serde_json::Value;

/// The registry file, relative to the workspace root.
pub const REGISTRY: &str = "docs/readme-figures.toml";

/// What a placeholder matches in README when the figure is located: a number as README writes
/// it (a sign, thousands separators, decimals, an exponent), or `inf`.
const NUMBER: &str = r"(-?(?:[0-9]+(?:,[0-9]{3})*(?:\.[0-9]+)?(?:e-?[0-9]+)?|inf))";

/// The whole registry: folders to prepare, commands to run, figures to check and the figures
/// README quotes that are knowingly not checked.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Registry {
    /// Folders of symbolic links to some of a data set's files (a split by take).
    #[serde(default)]
    pub folder: Vec<FolderSpec>,
    /// The commands, run in this order (a command that reads a model comes after its build).
    #[serde(default)]
    pub command: Vec<CommandSpec>,
    /// The checked figures.
    #[serde(default)]
    pub figure: Vec<Figure>,
    /// Figures README quotes that no command here checks, each with the reason.
    #[serde(default)]
    pub unchecked: Vec<Unchecked>,
}

/// `{work}/NAME`: links to the files of `from` whose names match `files`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FolderSpec {
    /// Folder name under the work folder.
    pub name: String,
    /// Source folder (placeholders as in commands).
    pub from: String,
    /// Regular expression over file names.
    pub files: String,
}

/// One command whose output figures are read from.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CommandSpec {
    /// Its name, used by figures.
    pub name: String,
    /// Program (default: the release `motion-lod` binary).
    #[serde(default)]
    pub program: Option<String>,
    /// Arguments; `{mocap}` is `../shared/mocap`, `{work}` the work folder under `target/`,
    /// `{root}` the workspace root.
    pub args: Vec<String>,
    /// Needs the shared motion capture (skipped when absent, unless data are required).
    #[serde(default)]
    pub data: bool,
}

/// A README figure: its text with placeholders and where each value comes from.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Figure {
    /// Identifier (section and what it is).
    pub id: String,
    /// The README heading (its start, e.g. `### Storage`) under which the figure stands: it is
    /// looked for from that heading to the next one (default: the whole README).
    #[serde(default)]
    pub section: Option<String>,
    /// The README text, `{name}` for each value.
    pub text: String,
    /// Default command of the values (and of `line`).
    #[serde(default)]
    pub command: Option<String>,
    /// A regular expression over the command's output (multi-line mode) whose named groups fill
    /// the placeholders of the same names, as printed.
    #[serde(default)]
    pub line: Option<String>,
    /// The other placeholders' values.
    #[serde(default)]
    pub values: BTreeMap<String, ValueSpec>,
}

/// Where one value comes from and how README writes it.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ValueSpec {
    /// Command (default: the figure's).
    #[serde(default)]
    pub command: Option<String>,
    /// A path into the command's JSON output: `/`-separated keys and indices, `*` for every
    /// element, `key=value` for the first element whose field (dotted path) is `value`,
    /// `key^=prefix` for every element whose field starts so.
    #[serde(default)]
    pub json: Option<String>,
    /// A regular expression over the output (multi-line mode); the value is capture group
    /// `group` (default 1) of the first match, or of every match with `agg`.
    #[serde(default)]
    pub re: Option<String>,
    /// The capture group of `re`.
    #[serde(default)]
    pub group: Option<usize>,
    /// Size in bytes of a file (relative to the workspace root).
    #[serde(default)]
    pub file_size: Option<String>,
    /// `min`, `max`, `sum`, `count` or `distinct` (the number of different values) over several
    /// matches.
    #[serde(default)]
    pub agg: Option<String>,
    /// Divided by this value (a percentage with `scale = 100`).
    #[serde(default)]
    pub over: Option<Box<ValueSpec>>,
    /// Added after the division by `over` (`-1` for a relative difference).
    #[serde(default)]
    pub add: Option<f64>,
    /// Multiplied by this, after `over` and `add`.
    #[serde(default)]
    pub scale: Option<f64>,
    /// Absolute value.
    #[serde(default)]
    pub abs: bool,
    /// Decimals to print.
    #[serde(default)]
    pub decimals: Option<usize>,
    /// Thousands separators (`14,579,200`).
    #[serde(default)]
    pub commas: bool,
}

/// A figure README quotes that is not checked, and why.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Unchecked {
    /// The README text quoted.
    pub text: String,
    /// Why no command checks it.
    pub reason: String,
}

impl Figure {
    /// A figure with a text and no sources (for tests and examples).
    pub fn literal(id: &str, text: &str) -> Figure {
        Figure {
            id: id.to_string(),
            section: None,
            text: text.to_string(),
            command: None,
            line: None,
            values: BTreeMap::new(),
        }
    }

    /// The placeholder names of the text, in order.
    pub fn placeholders(&self) -> Vec<String> {
        let mut names = Vec::new();
        let mut rest = self.text.as_str();
        while let Some(open) = rest.find('{') {
            let Some(close) = rest[open..].find('}') else {
                break;
            };
            names.push(rest[open + 1..open + close].to_string());
            rest = &rest[open + close + 1..];
        }
        names
    }

    /// The commands this figure reads.
    fn commands(&self) -> BTreeSet<String> {
        let mut set = BTreeSet::new();
        if let Some(c) = &self.command {
            set.insert(c.clone());
        }
        fn add(spec: &ValueSpec, set: &mut BTreeSet<String>) {
            if let Some(c) = &spec.command {
                set.insert(c.clone());
            }
            if let Some(o) = &spec.over {
                add(o, set);
            }
        }
        for v in self.values.values() {
            add(v, &mut set);
        }
        set
    }
}

/// Parses the registry.
pub fn parse_registry(text: &str) -> Result<Registry> {
    let registry: Registry = toml::from_str(text).context("parsing the figure registry")?;
    let names: BTreeSet<&str> = registry.command.iter().map(|c| c.name.as_str()).collect();
    let mut ids = BTreeSet::new();
    for f in &registry.figure {
        if !ids.insert(f.id.as_str()) {
            bail!("figure `{}` is registered twice", f.id);
        }
        for c in f.commands() {
            if !names.contains(c.as_str()) {
                bail!(
                    "figure `{}` reads command `{c}`, which is not registered",
                    f.id
                );
            }
        }
        let groups: BTreeSet<String> = match &f.line {
            Some(line) => {
                let re = Regex::new(line).with_context(|| format!("figure `{}`: line", f.id))?;
                re.capture_names().flatten().map(str::to_string).collect()
            }
            None => BTreeSet::new(),
        };
        for name in f.placeholders() {
            if !groups.contains(&name) && !f.values.contains_key(&name) {
                bail!("figure `{}`: placeholder `{{{name}}}` has no source", f.id);
            }
        }
        if f.values
            .values()
            .any(|v| v.command.is_none() && v.file_size.is_none())
            && f.command.is_none()
        {
            bail!(
                "figure `{}`: a value without a command and no default",
                f.id
            );
        }
    }
    Ok(registry)
}

/// The regular expression that finds a figure in README, whatever its values.
fn locator(figure: &Figure) -> Result<Regex> {
    let mut pattern = String::new();
    let mut rest = figure.text.as_str();
    while let Some(open) = rest.find('{') {
        let close = rest[open..]
            .find('}')
            .ok_or_else(|| anyhow!("figure `{}`: an unclosed `{{`", figure.id))?;
        pattern.push_str(&regex_lite::escape(&rest[..open]));
        pattern.push_str(NUMBER);
        rest = &rest[open + close + 1..];
    }
    pattern.push_str(&regex_lite::escape(rest));
    Regex::new(&pattern).with_context(|| format!("figure `{}`: locator", figure.id))
}

/// The byte range of README's section that starts with the heading `heading`: to the next
/// heading (`## ` or `### `).
pub fn section_range(readme: &str, heading: &str) -> Result<std::ops::Range<usize>> {
    let mut start = None;
    let mut offset = 0;
    for line in readme.split_inclusive('\n') {
        let is_heading = line.starts_with("## ") || line.starts_with("### ");
        match start {
            None if line.starts_with(heading) => start = Some(offset),
            Some(s) if is_heading => return Ok(s..offset),
            _ => {}
        }
        offset += line.len();
    }
    start
        .map(|s| s..readme.len())
        .ok_or_else(|| anyhow!("README has no heading `{heading}`"))
}

/// The byte ranges of README where the figure's text stands (with any values), within its
/// section.
pub fn locate(figure: &Figure, readme: &str) -> Result<Vec<std::ops::Range<usize>>> {
    let region = match &figure.section {
        Some(h) => section_range(readme, h)?,
        None => 0..readme.len(),
    };
    Ok(locator(figure)?
        .find_iter(&readme[region.clone()])
        .map(|m| m.start() + region.start..m.end() + region.start)
        .collect())
}

/// The figure's text with its values.
pub fn expected_text(figure: &Figure, values: &HashMap<String, String>) -> Result<String> {
    let mut out = String::new();
    let mut rest = figure.text.as_str();
    while let Some(open) = rest.find('{') {
        let close = rest[open..]
            .find('}')
            .ok_or_else(|| anyhow!("figure `{}`: an unclosed `{{`", figure.id))?;
        out.push_str(&rest[..open]);
        let name = &rest[open + 1..open + close];
        let value = values
            .get(name)
            .ok_or_else(|| anyhow!("figure `{}`: no value for `{name}`", figure.id))?;
        out.push_str(value);
        rest = &rest[open + close + 1..];
    }
    out.push_str(rest);
    Ok(out)
}

/// One figure whose README text is not what its command produces.
#[derive(Debug, Clone, PartialEq)]
pub struct Mismatch {
    /// The figure's id.
    pub id: String,
    /// What README says (or why it cannot be read).
    pub readme: String,
    /// What the commands produce.
    pub expected: String,
}

/// Compares README with each figure's expected text: figures README does not contain (or
/// contains more than once) and figures whose values differ.
pub fn compare(figures: &[(&Figure, String)], readme: &str) -> Vec<Mismatch> {
    let mut out = Vec::new();
    for (figure, expected) in figures {
        match locate(figure, readme) {
            Err(e) => out.push(Mismatch {
                id: figure.id.clone(),
                readme: format!("(bad registry entry: {e:#})"),
                expected: expected.clone(),
            }),
            Ok(found) if found.len() == 1 => {
                let have = &readme[found[0].clone()];
                if have != expected {
                    out.push(Mismatch {
                        id: figure.id.clone(),
                        readme: have.to_string(),
                        expected: expected.clone(),
                    });
                }
            }
            Ok(found) => out.push(Mismatch {
                id: figure.id.clone(),
                readme: format!(
                    "(the figure's text, with any numbers, is found {} times, not once; README's \
                     prose around it changed: update {REGISTRY})",
                    found.len()
                ),
                expected: expected.clone(),
            }),
        }
    }
    out
}

/// README with every located figure replaced by its expected text; the figures that could not
/// be located are returned with it (left as they are).
pub fn rewrite(figures: &[(&Figure, String)], readme: &str) -> (String, Vec<Mismatch>) {
    let mut spans = Vec::new();
    let mut missing = Vec::new();
    for (figure, expected) in figures {
        match locate(figure, readme) {
            Ok(found) if found.len() == 1 => spans.push((found[0].clone(), expected.clone())),
            other => missing.push(Mismatch {
                id: figure.id.clone(),
                readme: match other {
                    Ok(found) => format!("(found {} times, not once)", found.len()),
                    Err(e) => format!("({e:#})"),
                },
                expected: expected.clone(),
            }),
        }
    }
    spans.sort_by_key(|(r, _)| std::cmp::Reverse(r.start));
    let mut text = readme.to_string();
    for (range, expected) in spans {
        text.replace_range(range, &expected);
    }
    (text, missing)
}

/// README's current values of a figure (for tests: a registry checked against README itself).
pub fn readme_values(figure: &Figure, readme: &str) -> Result<HashMap<String, String>> {
    let re = locator(figure)?;
    let span = locate(figure, readme)?
        .into_iter()
        .next()
        .ok_or_else(|| anyhow!("figure `{}` is not in README", figure.id))?;
    let caps = re
        .captures(&readme[span])
        .ok_or_else(|| anyhow!("figure `{}` is not in README", figure.id))?;
    Ok(figure
        .placeholders()
        .into_iter()
        .enumerate()
        .map(|(i, name)| (name, caps[i + 1].to_string()))
        .collect())
}

/// Paragraphs and tables of README that quote a timing (fps, ms, µs, ns, minutes, a duration in
/// seconds) without a date (`2026-11-27`) or "date not recorded": a table is dated by the
/// paragraph before it. Returns each one's first line.
pub fn undated_timings(readme: &str) -> Vec<String> {
    let timing = Regex::new(
        r"[0-9][0-9,.]*\s?(?:fps|ms|µs|us|ns)\b|frames/s|[0-9]+ min [0-9]+ s\b|[0-9.]+ s (?:instead|against|without)|, [0-9]+ s\)",
    )
    .expect("valid");
    let date = Regex::new(r"20[0-9]{2}-[0-9]{2}-[0-9]{2}|date not recorded").expect("valid");
    let mut blocks: Vec<String> = Vec::new();
    let mut current = String::new();
    let mut in_code = false;
    for line in readme.lines() {
        if line.trim_start().starts_with("```") {
            in_code = !in_code;
        }
        if line.trim().is_empty() && !in_code {
            if !current.is_empty() {
                blocks.push(std::mem::take(&mut current));
            }
        } else {
            current.push_str(line);
            current.push('\n');
        }
    }
    if !current.is_empty() {
        blocks.push(current);
    }
    // A frame rate of data or of a simulation (`at 30 fps`, `(30 fps)`) is not a timing.
    let quotes_timing = |block: &str| {
        timing.find_iter(block).any(|m| {
            let before = &block[..m.start()];
            !(before.ends_with("at ") || before.ends_with('('))
        })
    };
    let mut out = Vec::new();
    for (i, block) in blocks.iter().enumerate() {
        if block.starts_with("```") || !quotes_timing(block) || date.is_match(block) {
            continue;
        }
        // A table is dated by the paragraph before it (over any tables between).
        if block.starts_with('|') {
            let before = blocks[..i].iter().rev().find(|b| !b.starts_with('|'));
            if before.is_some_and(|b| date.is_match(b)) {
                continue;
            }
        }
        out.push(block.lines().next().unwrap_or_default().to_string());
    }
    out
}

/// Where the commands run and what they read.
pub struct Places {
    /// Workspace root.
    pub root: PathBuf,
    /// The `motion-lod` binary.
    pub bin: PathBuf,
    /// `../shared/mocap`, when present.
    pub mocap: Option<PathBuf>,
    /// Work folder (models, split folders).
    pub work: PathBuf,
}

impl Places {
    fn expand(&self, arg: &str) -> String {
        let mocap = self
            .mocap
            .clone()
            .unwrap_or_else(|| self.root.join("../shared/mocap"));
        arg.replace("{mocap}", &mocap.display().to_string())
            .replace("{work}", &self.work.display().to_string())
            .replace("{root}", &self.root.display().to_string())
    }
}

/// What one command printed.
#[derive(Debug, Default)]
pub struct Output {
    /// Standard output then standard error.
    pub text: String,
    /// Standard output read as JSON, when it is.
    pub json: Option<Value>,
    /// The command line, for messages.
    pub line: String,
}

/// Runs the registry's commands (in registry order: a command reads the models the ones before it
/// wrote) and prepares its folders. Commands that need data are skipped when the data are absent.
pub fn run_commands(
    registry: &Registry,
    cx: &Places,
    quiet: bool,
) -> Result<HashMap<String, Output>> {
    std::fs::create_dir_all(&cx.work)?;
    for folder in &registry.folder {
        if cx.mocap.is_none() && folder.from.contains("{mocap}") {
            continue;
        }
        let dir = cx.work.join(&folder.name);
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir)?;
        let from = PathBuf::from(cx.expand(&folder.from));
        let re = Regex::new(&folder.files)?;
        let mut n = 0;
        for entry in std::fs::read_dir(&from).with_context(|| format!("{}", from.display()))? {
            let entry = entry?;
            let name = entry.file_name().to_string_lossy().to_string();
            if re.is_match(&name) {
                link_or_copy(&entry.path(), &dir.join(&name))?;
                n += 1;
            }
        }
        if n == 0 {
            bail!(
                "folder {}: no file of {} matches",
                folder.name,
                from.display()
            );
        }
    }
    let mut outputs = HashMap::new();
    for spec in &registry.command {
        if spec.data && cx.mocap.is_none() {
            continue;
        }
        let program = match &spec.program {
            Some(p) => PathBuf::from(cx.expand(p)),
            None => cx.bin.clone(),
        };
        let args: Vec<String> = spec.args.iter().map(|a| cx.expand(a)).collect();
        let line = format!(
            "{} {}",
            spec.program.as_deref().unwrap_or("motion-lod"),
            spec.args.join(" ")
        );
        let started = Instant::now();
        let out = Command::new(&program)
            .args(&args)
            .current_dir(&cx.work)
            .output()
            .with_context(|| format!("running {line}"))?;
        if !out.status.success() {
            bail!(
                "`{line}` failed ({}):\n{}",
                out.status,
                String::from_utf8_lossy(&out.stderr)
            );
        }
        if !quiet {
            eprintln!("  {:>6.1} s  {line}", started.elapsed().as_secs_f64());
        }
        let stdout = String::from_utf8_lossy(&out.stdout).to_string();
        let json = serde_json::from_str(stdout.trim()).ok();
        let text = format!("{stdout}\n{}", String::from_utf8_lossy(&out.stderr));
        outputs.insert(spec.name.clone(), Output { text, json, line });
    }
    Ok(outputs)
}

fn link_or_copy(from: &Path, to: &Path) -> Result<()> {
    #[cfg(unix)]
    {
        if std::os::unix::fs::symlink(from, to).is_ok() {
            return Ok(());
        }
    }
    std::fs::copy(from, to)?;
    Ok(())
}

/// The value of a JSON field for `key=value` selectors: strings as they are, others as JSON.
fn field_text(v: &Value, dotted: &str) -> Option<String> {
    let mut cur = v;
    for k in dotted.split('.') {
        cur = cur.get(k)?;
    }
    Some(match cur {
        Value::String(s) => s.clone(),
        other => other.to_string(),
    })
}

/// Every value a path selects.
pub fn select<'a>(root: &'a Value, path: &str) -> Result<Vec<&'a Value>> {
    let mut cur = vec![root];
    for seg in path.split('/').filter(|s| !s.is_empty()) {
        let mut next = Vec::new();
        for v in cur {
            if seg == "*" {
                match v {
                    Value::Array(a) => next.extend(a.iter()),
                    Value::Object(o) => next.extend(o.values()),
                    _ => bail!("`*` over a scalar in {path}"),
                }
            } else if let Some((key, prefix)) = seg.split_once("^=") {
                let a = v.as_array().ok_or_else(|| anyhow!("{seg}: not an array"))?;
                next.extend(
                    a.iter()
                        .filter(|e| field_text(e, key).is_some_and(|t| t.starts_with(prefix))),
                );
            } else if let Some((key, want)) = seg.split_once('=') {
                let a = v.as_array().ok_or_else(|| anyhow!("{seg}: not an array"))?;
                let e = a
                    .iter()
                    .find(|e| field_text(e, key).as_deref() == Some(want))
                    .ok_or_else(|| anyhow!("no element with {key} = {want} in {path}"))?;
                next.push(e);
            } else if let (Ok(i), Value::Array(a)) = (seg.parse::<usize>(), v) {
                next.push(
                    a.get(i)
                        .ok_or_else(|| anyhow!("index {i} beyond {} in {path}", a.len()))?,
                );
            } else {
                next.push(v.get(seg).ok_or_else(|| anyhow!("no `{seg}` in {path}"))?);
            }
        }
        cur = next;
    }
    Ok(cur)
}

/// A raw value before formatting.
#[derive(Debug, Clone)]
enum Raw {
    Num(f64),
    Text(String),
}

impl Raw {
    fn num(&self) -> Result<f64> {
        match self {
            Raw::Num(x) => Ok(*x),
            Raw::Text(t) => t
                .replace(',', "")
                .parse::<f64>()
                .map_err(|_| anyhow!("`{t}` is not a number")),
        }
    }
}

fn aggregate(items: Vec<Raw>, agg: Option<&str>) -> Result<Raw> {
    match agg {
        None => match items.len() {
            1 => Ok(items.into_iter().next().expect("one")),
            n => bail!("{n} values where one was expected (use agg)"),
        },
        Some("count") => Ok(Raw::Num(items.len() as f64)),
        Some("distinct") => {
            let set: BTreeSet<String> = items
                .iter()
                .map(|r| match r {
                    Raw::Num(x) => x.to_string(),
                    Raw::Text(t) => t.clone(),
                })
                .collect();
            Ok(Raw::Num(set.len() as f64))
        }
        Some(op) => {
            if items.is_empty() {
                bail!("{op} over no values");
            }
            let nums = items.iter().map(Raw::num).collect::<Result<Vec<_>>>()?;
            Ok(Raw::Num(match op {
                "min" => nums.iter().copied().fold(f64::INFINITY, f64::min),
                "max" => nums.iter().copied().fold(f64::NEG_INFINITY, f64::max),
                "sum" => nums.iter().sum(),
                _ => bail!("unknown agg `{op}`"),
            }))
        }
    }
}

fn raw_value(
    spec: &ValueSpec,
    default_command: Option<&str>,
    outputs: &HashMap<String, Output>,
    root: &Path,
) -> Result<Raw> {
    let output = || -> Result<&Output> {
        let name = spec
            .command
            .as_deref()
            .or(default_command)
            .ok_or_else(|| anyhow!("no command"))?;
        outputs
            .get(name)
            .ok_or_else(|| anyhow!("command `{name}` did not run"))
    };
    let raw = if let Some(path) = &spec.json {
        let out = output()?;
        let json = out
            .json
            .as_ref()
            .ok_or_else(|| anyhow!("`{}` printed no JSON", out.line))?;
        let items = select(json, path)?
            .into_iter()
            .map(|v| match v {
                Value::Number(n) => Raw::Num(n.as_f64().unwrap_or(f64::NAN)),
                Value::String(s) => Raw::Text(s.clone()),
                other => Raw::Text(other.to_string()),
            })
            .collect();
        aggregate(items, spec.agg.as_deref()).with_context(|| format!("json {path}"))?
    } else if let Some(re) = &spec.re {
        let out = output()?;
        let re = Regex::new(&format!("(?m){re}"))?;
        let group = spec.group.unwrap_or(1);
        let items: Vec<Raw> = re
            .captures_iter(&out.text)
            .filter_map(|c| c.get(group).map(|m| Raw::Text(m.as_str().to_string())))
            .collect();
        if items.is_empty() {
            bail!("`{re}` matches nothing in the output of `{}`", out.line);
        }
        let items = if spec.agg.is_none() {
            items.into_iter().take(1).collect()
        } else {
            items
        };
        aggregate(items, spec.agg.as_deref())?
    } else if let Some(file) = &spec.file_size {
        Raw::Num(std::fs::metadata(root.join(file))?.len() as f64)
    } else {
        bail!("a value needs json, re or file_size");
    };
    let numeric = spec.over.is_some()
        || spec.add.is_some()
        || spec.scale.is_some()
        || spec.abs
        || spec.decimals.is_some()
        || spec.commas;
    if !numeric {
        return Ok(raw);
    }
    let mut x = raw.num()?;
    if let Some(over) = &spec.over {
        x /= raw_value(over, default_command, outputs, root)?.num()?;
    }
    if let Some(a) = spec.add {
        x += a;
    }
    if let Some(s) = spec.scale {
        x *= s;
    }
    if spec.abs {
        x = x.abs();
    }
    Ok(Raw::Num(x))
}

/// Formats a value as README writes it.
fn format_value(raw: Raw, spec: &ValueSpec) -> String {
    match raw {
        Raw::Text(t) => t,
        Raw::Num(x) => {
            let s = match spec.decimals {
                Some(d) => format!("{x:.d$}"),
                None if x.fract() == 0.0 && x.abs() < 1e15 => format!("{x:.0}"),
                None => format!("{x}"),
            };
            // No negative zero in README.
            let s = if s.starts_with('-') && s[1..].chars().all(|c| c == '0' || c == '.') {
                s[1..].to_string()
            } else {
                s
            };
            if spec.commas { with_commas(&s) } else { s }
        }
    }
}

/// `14579200` -> `14,579,200` (the integer part only).
pub fn with_commas(s: &str) -> String {
    let (sign, rest) = s.strip_prefix('-').map_or(("", s), |r| ("-", r));
    let (int, frac) = rest
        .split_once('.')
        .map_or((rest, None), |(a, b)| (a, Some(b)));
    let mut out = String::new();
    for (i, c) in int.chars().enumerate() {
        if i > 0 && (int.len() - i) % 3 == 0 {
            out.push(',');
        }
        out.push(c);
    }
    match frac {
        Some(f) => format!("{sign}{out}.{f}"),
        None => format!("{sign}{out}"),
    }
}

/// The values of a figure's placeholders from the commands' outputs.
pub fn figure_values(
    figure: &Figure,
    outputs: &HashMap<String, Output>,
    root: &Path,
) -> Result<HashMap<String, String>> {
    let mut values = HashMap::new();
    if let Some(line) = &figure.line {
        let name = figure
            .command
            .as_deref()
            .ok_or_else(|| anyhow!("`line` needs the figure's command"))?;
        let out = outputs
            .get(name)
            .ok_or_else(|| anyhow!("command `{name}` did not run"))?;
        let re = Regex::new(&format!("(?m){line}"))?;
        let caps = re
            .captures(&out.text)
            .ok_or_else(|| anyhow!("`{line}` matches nothing in the output of `{}`", out.line))?;
        for name in re.capture_names().flatten() {
            if let Some(m) = caps.name(name) {
                values.insert(name.to_string(), m.as_str().to_string());
            }
        }
    }
    for (name, spec) in &figure.values {
        let raw = raw_value(spec, figure.command.as_deref(), outputs, root)
            .with_context(|| format!("figure `{}`, value `{name}`", figure.id))?;
        values.insert(name.clone(), format_value(raw, spec));
    }
    Ok(values)
}

/// Options of a run.
pub struct Options {
    /// Only compare; do not write README.
    pub check: bool,
    /// The binary to use instead of building `target/release/motion-lod`.
    pub bin: Option<PathBuf>,
    /// No per-command timings.
    pub quiet: bool,
}

/// `cargo xtask readme [--check]`.
pub fn run(root: &Path, options: &Options) -> Result<()> {
    let started = Instant::now();
    let registry_path = root.join(REGISTRY);
    let registry = parse_registry(
        &std::fs::read_to_string(&registry_path)
            .with_context(|| format!("reading {}", registry_path.display()))?,
    )?;
    let readme_path = root.join("README.md");
    let readme = std::fs::read_to_string(&readme_path)?;

    let undated = undated_timings(&readme);
    let bin = match &options.bin {
        Some(b) => b.clone(),
        None => {
            let status = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
                .args(["build", "--release", "-q", "-p", "motion-lod"])
                .current_dir(root)
                .status()
                .context("cargo build --release -p motion-lod")?;
            if !status.success() {
                bail!("cargo build --release -p motion-lod failed");
            }
            root.join("target/release/motion-lod")
        }
    };
    let bin = bin.canonicalize().unwrap_or(bin);
    let mocap = root.join("../shared/mocap");
    let mocap = mocap
        .is_dir()
        .then(|| mocap.canonicalize().unwrap_or(mocap));
    let require = std::env::var("MOTION_LOD_REQUIRE_DATA").is_ok_and(|v| v == "1");
    if mocap.is_none() {
        if require {
            bail!("../shared/mocap not found (MOTION_LOD_REQUIRE_DATA=1)");
        }
        println!("skipped: ../shared/mocap not found (the figures from the real data)");
    }
    let cx = Places {
        root: root.to_path_buf(),
        bin,
        mocap,
        work: root.join("target/readme-figures"),
    };
    let data_commands: BTreeSet<&str> = registry
        .command
        .iter()
        .filter(|c| c.data)
        .map(|c| c.name.as_str())
        .collect();
    let figures: Vec<&Figure> = registry
        .figure
        .iter()
        .filter(|f| {
            cx.mocap.is_some()
                || f.commands()
                    .iter()
                    .all(|c| !data_commands.contains(c.as_str()))
        })
        .collect();
    let outputs = run_commands(&registry, &cx, options.quiet)?;
    let mut produced = Vec::new();
    let mut errors = Vec::new();
    for f in &figures {
        match figure_values(f, &outputs, root).and_then(|v| expected_text(f, &v)) {
            Ok(text) => produced.push((*f, text)),
            Err(e) => errors.push(format!("{}: {e:#}", f.id)),
        }
    }
    let seconds = started.elapsed().as_secs_f64();
    let mut report = String::new();
    for e in &errors {
        let _ = writeln!(report, "figure not produced: {e}");
    }
    if options.check {
        let mismatches = compare(&produced, &readme);
        for m in &mismatches {
            let _ = writeln!(
                report,
                "README figure `{}` is stale:\n    README:   {}\n    expected: {}",
                m.id, m.readme, m.expected
            );
        }
        for u in &undated {
            let _ = writeln!(
                report,
                "README quotes a timing without the date of its run (add `measured ... on \
                 YYYY-MM-DD` or `date not recorded`): {u}"
            );
        }
        if !report.is_empty() {
            print!("{report}");
            bail!(
                "README.md disagrees with {} of {} figures ({} not produced, {} undated timing \
                 blocks); `cargo xtask readme` rewrites the figures from the commands",
                mismatches.len(),
                produced.len() + errors.len(),
                errors.len(),
                undated.len()
            );
        }
        println!(
            "README.md: {} figures checked against their commands, {} listed as unchecked in \
             {REGISTRY}; every timing names its date ({seconds:.0} s)",
            produced.len(),
            registry.unchecked.len()
        );
        return Ok(());
    }
    let (text, missing) = rewrite(&produced, &readme);
    let changed = compare(&produced, &readme).len() - missing.len();
    if text != readme {
        std::fs::write(&readme_path, &text)?;
    }
    for m in &missing {
        let _ = writeln!(
            report,
            "README figure `{}` not found {}; expected: {}",
            m.id, m.readme, m.expected
        );
    }
    for u in &undated {
        let _ = writeln!(report, "timing without a date: {u}");
    }
    print!("{report}");
    println!(
        "README.md: {changed} of {} figures rewritten ({seconds:.0} s)",
        produced.len()
    );
    if !errors.is_empty() || !missing.is_empty() {
        bail!("some figures could not be produced or found (above)");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn registry() -> Registry {
        let root = crate::tables::workspace_root();
        parse_registry(&std::fs::read_to_string(root.join(REGISTRY)).unwrap()).unwrap()
    }

    fn readme() -> String {
        std::fs::read_to_string(crate::tables::workspace_root().join("README.md")).unwrap()
    }

    #[test]
    fn every_registered_figure_stands_once_in_readme() {
        let readme = readme();
        let lost: Vec<String> = registry()
            .figure
            .iter()
            .filter_map(|f| {
                let n = locate(f, &readme).unwrap().len();
                (n != 1).then(|| format!("`{}` found {n} times: {}", f.id, f.text))
            })
            .collect();
        assert!(lost.is_empty(), "{}", lost.join("\n"));
    }

    /// The acceptance of issue 36: a changed figure in README fails the check. Each registered
    /// figure, filled with README's own values, passes; the same README with one digit of that
    /// figure changed fails, naming the figure.
    #[test]
    fn changing_any_quoted_figure_fails_the_check() {
        let readme = readme();
        let registry = registry();
        let produced: Vec<(&Figure, String)> = registry
            .figure
            .iter()
            .map(|f| {
                let values = readme_values(f, &readme).unwrap();
                (f, expected_text(f, &values).unwrap())
            })
            .collect();
        assert!(compare(&produced, &readme).is_empty());
        for (f, _) in &produced {
            let span = locate(f, &readme).unwrap()[0].clone();
            let values = readme_values(f, &readme).unwrap();
            let first = f.placeholders()[0].clone();
            let old = &values[&first];
            let digit = old.find(|c: char| c.is_ascii_digit()).unwrap();
            let mut new = old.clone();
            let d = old.as_bytes()[digit];
            new.replace_range(digit..digit + 1, if d == b'9' { "8" } else { "9" });
            let mut altered_values = values.clone();
            altered_values.insert(first.clone(), new);
            let altered = readme[..span.start].to_string()
                + &expected_text(f, &altered_values).unwrap()
                + &readme[span.end..];
            let stale = compare(&produced, &altered);
            assert_eq!(stale.len(), 1, "figure `{}`: {stale:?}", f.id);
            assert_eq!(stale[0].id, f.id);
            // And the rewrite puts it back.
            let (back, missing) = rewrite(&produced, &altered);
            assert!(missing.is_empty());
            assert_eq!(back, readme, "figure `{}`", f.id);
        }
    }

    #[test]
    fn a_figure_that_readme_lost_or_repeats_is_reported() {
        let f = Figure::literal("x", "error {e} cm");
        let produced = [(&f, "error 3.977 cm".to_string())];
        assert_eq!(compare(&produced, "no figure here").len(), 1);
        assert_eq!(
            compare(&produced, "error 3.977 cm, error 3.977 cm").len(),
            1
        );
        assert!(compare(&produced, "an error 3.977 cm.").is_empty());
        assert_eq!(
            compare(&produced, "an error 3.978 cm.")[0].readme,
            "error 3.978 cm"
        );
        assert_eq!(compare(&produced, "an error 14,579,200 cm.").len(), 1);
    }

    #[test]
    fn values_are_formatted_as_readme_writes_them() {
        let spec = ValueSpec {
            commas: true,
            ..ValueSpec::default()
        };
        assert_eq!(format_value(Raw::Num(14579200.0), &spec), "14,579,200");
        let spec = ValueSpec {
            decimals: Some(2),
            ..ValueSpec::default()
        };
        assert_eq!(format_value(Raw::Num(-0.785), &spec), "-0.79");
        assert_eq!(format_value(Raw::Num(-0.001), &spec), "0.00");
        assert_eq!(with_commas("1234.5"), "1,234.5");
        assert_eq!(with_commas("-999"), "-999");
        let json: Value = serde_json::from_str(
            r#"{"m":[{"name":"a","e":1},{"name":"b","e":2.5},{"name":"ab","e":4}]}"#,
        )
        .unwrap();
        assert_eq!(select(&json, "/m/name=b/e").unwrap()[0], &Value::from(2.5));
        assert_eq!(select(&json, "m/name^=a/e").unwrap().len(), 2);
        assert_eq!(select(&json, "m/*/e").unwrap().len(), 3);
    }

    #[test]
    fn every_timing_in_readme_names_its_date() {
        assert_eq!(undated_timings(&readme()), Vec::<String>::new());
        assert_eq!(
            undated_timings("It ran 120 fps.\n\nIt ran 120 fps on 2026-11-27.\n"),
            vec!["It ran 120 fps.".to_string()]
        );
    }
}
