//! `cargo xtask scaling`: how the offline build's time and peak memory grow with the number of
//! cycles and with the threads it is given (issue 35, item 3), written to `docs/scaling.md`.
//!
//! The shared sets hold 800 (Bandai) and 33 (CMU) cycles. Larger sets are grown from one of them
//! ([`grown`]): after the data's own cycles come copies of them as walked by performers `s` times
//! as tall, for `s` spread around 1 in steps of 2%, geometrically and dynamically similar (every
//! length, the root's path and the `dx`, `dz` and height controls times `s`, every joint rotation
//! the same, time times `sqrt(s)`: the same Froude number, as people of other heights walk). Each
//! copy of a take is a take of its own (its own performer) for the folds and the reports.
//!
//! Every build runs in a child process (`xtask scaling --one N`, with `RAYON_NUM_THREADS`), so that
//! its peak resident memory (`VmHWM`) is its own: it includes reading and aligning the data and
//! growing the set. A build that runs past the time limit is stopped and reported as such.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use motion_lod::dataset::{DataSpec, TrainingSet};
use motion_lod::progress::Progress;
use motion_lod::{BuildConfig, MotionModel};
use serde::{Deserialize, Serialize};

/// Relative height step between two grown copies of the data.
pub const SCALE_STEP: f64 = 0.02;

/// The scale of copy `k` (copy 0 is the data itself): 1, 1.02, 0.98, 1.04, 0.96, ...
pub fn copy_scale(k: usize) -> f64 {
    if k == 0 {
        return 1.0;
    }
    let step = k.div_ceil(2) as f64 * SCALE_STEP;
    if k % 2 == 1 { 1.0 + step } else { 1.0 - step }
}

/// `set` grown to `n` cycles: its own cycles first, then whole copies at [`copy_scale`] 1, 2, ...
/// (the last copy cut at `n`). Rows 0..3 of each sample (the root's position) and the time row
/// (6) are scaled, the rotations kept; the controls `dx`, `dz` and height scale with the body, the
/// turn does not. Styles and the data's quality reference are kept for the data's own cycles only
/// (a grown set has no style labels).
pub fn grown(set: &TrainingSet, n: usize) -> Result<TrainingSet> {
    let [p, t, s] = set.tensor.dims();
    if s == 0 {
        bail!("no cycles to grow from");
    }
    if n <= s {
        bail!("{n} cycles asked, the data has {s}: grow only beyond it");
    }
    let mut data = Vec::with_capacity(p * t * n);
    let (mut controls, mut sources) = (Vec::with_capacity(n), Vec::with_capacity(n));
    for i in 0..n {
        let (k, j) = (i / s, i % s);
        let scale = copy_scale(k);
        let time = scale.sqrt();
        let sample = set.tensor.sample(j);
        data.extend(sample.iter().enumerate().map(|(e, &v)| match e % p {
            0..=2 => v * scale,
            6 => v * time,
            _ => v,
        }));
        let [dx, dz, turn, height] = set.controls[j];
        controls.push([dx * scale, dz * scale, turn, height * scale]);
        let source = &set.sources[j];
        sources.push(if k == 0 {
            source.clone()
        } else {
            let take = motion_lod::folds::take_of(source);
            let rest = &source[take.len()..];
            format!("{take} (x{scale:.2}){rest}")
        });
    }
    Ok(TrainingSet {
        layout: set.layout.clone(),
        tensor: motion_lod::tensor_ops::Tensor3::from_vec([p, t, n], data)?,
        controls,
        sources,
        quality: set.quality.clone(),
        styles: None,
        style_spec: None,
        take_quality: set.take_quality.clone(),
    })
}

/// What one build measured.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Measured {
    /// Cycles built from.
    pub cycles: usize,
    /// Rayon threads.
    pub threads: usize,
    /// Seconds reading and aligning the data (and growing the set).
    pub load_s: f64,
    /// Seconds of `MotionModel::build`.
    pub build_s: f64,
    /// Peak resident memory of the process, bytes (`VmHWM`).
    pub peak_bytes: u64,
    /// Each build stage and its seconds, in order.
    pub stages: Vec<(String, f64)>,
}

/// A [`Progress`] that keeps when each stage began.
#[derive(Debug, Default)]
struct StageClock {
    starts: Mutex<Vec<(String, Instant)>>,
}

impl Progress for StageClock {
    fn stage(&self, name: &str, _total: u64) {
        if let Ok(mut s) = self.starts.lock() {
            s.push((name.to_string(), Instant::now()));
        }
    }
    fn inc(&self, _n: u64) {}
}

impl StageClock {
    /// Each stage with its seconds, the last one ending at `end`.
    fn durations(self, end: Instant) -> Vec<(String, f64)> {
        let starts = self.starts.into_inner().unwrap_or_default();
        let mut out = Vec::with_capacity(starts.len());
        for (k, (name, at)) in starts.iter().enumerate() {
            let until = starts.get(k + 1).map_or(end, |s| s.1);
            out.push((name.clone(), (until - *at).as_secs_f64()));
        }
        out
    }
}

/// The process's peak resident memory, bytes: `VmHWM` of `/proc/self/status`, or where that file
/// has none (gVisor's, on the machines the device kit runs on, lists only `VmSize`, `VmRSS` and
/// `VmData`) `getrusage`'s `ru_maxrss`.
pub fn peak_resident_bytes() -> Result<u64> {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    match status.lines().find(|l| l.starts_with("VmHWM:")) {
        Some(line) => parse_kb(line, "VmHWM:"),
        None => max_rss_bytes().context("no VmHWM in /proc/self/status, and no ru_maxrss"),
    }
}

/// A `/proc/self/status` line `PREFIX   123 kB` in bytes.
pub fn parse_kb(line: &str, prefix: &str) -> Result<u64> {
    let kb: u64 = line
        .trim_start_matches(prefix)
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .with_context(|| format!("reading {line:?}"))?;
    Ok(kb * 1024)
}

/// `getrusage(RUSAGE_SELF)`'s `ru_maxrss` (kilobytes on Linux) in bytes; `None` when the call
/// fails or reports 0.
pub fn max_rss_bytes() -> Option<u64> {
    // SAFETY: `getrusage` writes one `rusage` into the zeroed value it is given and reads nothing.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let rc = unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut usage) };
    let kb = u64::try_from(usage.ru_maxrss)
        .ok()
        .filter(|&kb| rc == 0 && kb > 0)?;
    Some(kb * 1024)
}

/// One build of `n` cycles grown from the takes in `data`, in this process, with the default
/// settings: what `xtask scaling --one N` prints (one JSON line).
pub fn build_one(data: &Path, n: usize) -> Result<Measured> {
    let started = Instant::now();
    let spec = DataSpec {
        dirs: vec![data.to_path_buf()],
        ..DataSpec::default()
    };
    let loaded = spec
        .load(&|_, _| {})
        .with_context(|| format!("loading {}", data.display()))?;
    let own = loaded.training.tensor.dims()[2];
    let set = if n == own {
        loaded.training
    } else {
        grown(&loaded.training, n)?
    };
    let load_s = started.elapsed().as_secs_f64();
    let clock = StageClock::default();
    let building = Instant::now();
    MotionModel::build(&set, &BuildConfig::default(), &clock).context("building the model")?;
    let end = Instant::now();
    Ok(Measured {
        cycles: n,
        threads: rayon::current_num_threads(),
        load_s,
        build_s: (end - building).as_secs_f64(),
        peak_bytes: peak_resident_bytes()?,
        stages: clock.durations(end),
    })
}

/// A run of [`build_one`] in a child process, or why it has no figures.
#[derive(Debug, Clone)]
pub enum Outcome {
    /// It finished.
    Done(Measured),
    /// It ran past the limit and was stopped.
    TimedOut(Duration),
}

/// Runs `xtask scaling --one n --data data` as a child on `threads` threads, stopped after
/// `limit`.
pub fn run_child(data: &Path, n: usize, threads: usize, limit: Duration) -> Result<Outcome> {
    let exe = std::env::current_exe().context("the xtask binary")?;
    let mut child = Command::new(exe)
        .args(["scaling", "--one", &n.to_string(), "--data"])
        .arg(data)
        .env("RAYON_NUM_THREADS", threads.to_string())
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .context("starting a build")?;
    let started = Instant::now();
    loop {
        if let Some(status) = child.try_wait()? {
            let mut out = String::new();
            if let Some(mut s) = child.stdout.take() {
                std::io::Read::read_to_string(&mut s, &mut out)?;
            }
            if !status.success() {
                bail!("the build of {n} cycles on {threads} threads failed ({status})");
            }
            let line = out.lines().last().context("no output")?;
            return Ok(Outcome::Done(serde_json::from_str(line)?));
        }
        if started.elapsed() > limit {
            child.kill()?;
            child.wait()?;
            return Ok(Outcome::TimedOut(limit));
        }
        std::thread::sleep(Duration::from_millis(200));
    }
}

/// Settings of a scaling run.
#[derive(Debug, Clone)]
pub struct ScalingConfig {
    /// The takes to grow from.
    pub data: PathBuf,
    /// Cycle counts to build.
    pub sizes: Vec<usize>,
    /// Thread counts.
    pub threads: Vec<usize>,
    /// Longest a build may run.
    pub limit: Duration,
    /// The document to write.
    pub out: PathBuf,
    /// The command line that reproduces it.
    pub command: String,
}

/// Builds every size on every thread count (larger sizes stop once one times out on that thread
/// count) and writes the table.
pub fn run(config: &ScalingConfig) -> Result<()> {
    let mut rows = Vec::new();
    for &threads in &config.threads {
        let mut stopped = false;
        for &n in &config.sizes {
            if stopped {
                rows.push((n, threads, None));
                continue;
            }
            eprintln!("scaling: {n} cycles on {threads} threads");
            let outcome = run_child(&config.data, n, threads, config.limit)?;
            if let Outcome::Done(m) = &outcome {
                eprintln!(
                    "  build {:.1} s, peak {:.0} MB",
                    m.build_s,
                    m.peak_bytes as f64 / 1e6
                );
            } else {
                stopped = true;
            }
            rows.push((n, threads, Some(outcome)));
        }
    }
    let figure = figure_path(&config.out);
    let points: Vec<(usize, usize, f64, f64)> = rows
        .iter()
        .filter_map(|(n, t, o)| match o {
            Some(Outcome::Done(m)) => Some((*n, *t, m.build_s, m.peak_bytes as f64 / 1e9)),
            _ => None,
        })
        .collect();
    if let Some(dir) = figure.parent() {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let name = config
        .data
        .file_name()
        .map_or_else(|| "data".into(), |n| n.to_string_lossy().into_owned());
    crate::tables::figures::scaling_figure(&figure, &points, &name)?;
    let doc = document(config, &rows);
    std::fs::write(&config.out, doc).with_context(|| format!("writing {}", config.out.display()))
}

/// The curve's SVG beside the document: `figures/scaling.svg` in its folder.
fn figure_path(out: &Path) -> PathBuf {
    out.parent()
        .unwrap_or_else(|| Path::new("."))
        .join("figures")
        .join("scaling.svg")
}

fn document(config: &ScalingConfig, rows: &[(usize, usize, Option<Outcome>)]) -> String {
    let mut doc = String::new();
    let _ = writeln!(
        doc,
        "# How the offline build scales\n\n\
         Written by `{}` on {} ({}; commit {}). Each row is one `MotionModel::build` with the default \
         settings in a process of its own (`RAYON_NUM_THREADS` threads): *build* is the build's wall \
         time, *load* reading, aligning and growing the data before it, *peak* the process's \
         largest resident memory (load and build). The data: `{}`; sets beyond its cycles are grown \
         from it: copies of every take as walked by performers 2%, 4%, ... taller and shorter, every \
         length and the `dx`, `dz` and height controls scaled, time by the square root \
         (`xtask/src/scaling.rs`). *Longest stages*: the build's three longest progress stages. \
         Issue 35's goal: 10,000 cycles in under 2 minutes on two cores, in under 4 GB. A build \
         longer than {} s is stopped. Above 1,000 cycles the kriging stage works on its value \
         columns compressed to their leading directions and keeps the system's LU factors instead \
         of its inverse; above 1,200 the control selection decides on whole takes holding at most \
         1,200 cycles (`crates/motion-lod/src/build.rs`, module documentation).\n",
        config.command,
        today(),
        crate::tables::machine(),
        crate::tables::commit(),
        config.data.display(),
        config.limit.as_secs()
    );
    let _ = writeln!(
        doc,
        "![Build time and peak memory against the cycles, per thread count](figures/scaling.svg)\n"
    );
    let _ = writeln!(
        doc,
        "| cycles | threads | build (s) | load (s) | peak (MB) | longest stages |\n| ---: | ---: | ---: | ---: | ---: | --- |"
    );
    for (n, threads, outcome) in rows {
        match outcome {
            Some(Outcome::Done(m)) => {
                let mut stages = m.stages.clone();
                stages.sort_by(|a, b| b.1.total_cmp(&a.1));
                let longest: Vec<String> = stages
                    .iter()
                    .take(3)
                    .map(|(name, s)| format!("{name} {s:.1} s"))
                    .collect();
                let _ = writeln!(
                    doc,
                    "| {n} | {threads} | {:.1} | {:.1} | {:.0} | {} |",
                    m.build_s,
                    m.load_s,
                    m.peak_bytes as f64 / 1e6,
                    longest.join("; ")
                );
            }
            Some(Outcome::TimedOut(limit)) => {
                let _ = writeln!(
                    doc,
                    "| {n} | {threads} | over {} | - | - | stopped |",
                    limit.as_secs()
                );
            }
            None => {
                let _ = writeln!(
                    doc,
                    "| {n} | {threads} | - | - | - | not run (a smaller set timed out) |"
                );
            }
        }
    }
    doc
}

/// Today's date (UTC) as `YYYY-MM-DD`.
pub fn today() -> String {
    let days = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs() / 86_400) as i64;
    // Civil from days (Howard Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!("{y:04}-{m:02}-{d:02}")
}
