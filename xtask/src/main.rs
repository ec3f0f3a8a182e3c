//! Project tasks: `cargo xtask fixtures` regenerates `fixtures/` (the synthetic gait set of the
//! procedural walker, see the library part of this crate); `cargo xtask tables` measures the paper's
//! tables and figures into `docs/tables.md` and `docs/figures/`; `cargo xtask imports` fails on an
//! import circle among a crate's source files; `cargo xtask web` builds the viewer's WebAssembly
//! runtime and copies its three.js modules (`--check`: fails when the checked-in ones are stale);
//! `cargo xtask readme` rewrites the figures README.md quotes from their commands (`--check`: fails
//! when one differs).

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::{Args, Parser, Subcommand};
use xtask::{fixtures, imports, readme, scaling, tables, web};

/// Project tasks of the motion-lod workspace.
#[derive(Debug, Parser)]
#[command(name = "xtask", about = "Project tasks of the motion-lod workspace")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// The tasks.
#[derive(Debug, Subcommand)]
enum Command {
    /// Regenerate the synthetic gait set in `fixtures/` (BVH takes, controls.csv, README.md).
    Fixtures(FixturesArgs),
    /// Measure the paper's tables and figures (storage, Figures 4 and 5, crowd frame rates, accuracy)
    /// and write `docs/tables.md` and `docs/figures/*.svg`.
    Tables(TablesArgs),
    /// List the `use crate::` edges among a crate's top-level modules and fail on an import circle
    /// (default: the facade, `crates/motion-lod/src`).
    Imports(ImportsArgs),
    /// Build the viewer's assets: the runtime as WebAssembly (`viewer/wasm/motion_lod.wasm`) and
    /// the three.js modules the pages import (`viewer/vendor/three/`, from `npm ci` in `viewer/`).
    Web(WebArgs),
    /// Measure how the offline build's time and peak memory grow with the number of cycles (sets
    /// grown from a folder of takes by performers of other heights) and the threads, and write
    /// `docs/scaling.md`.
    Scaling(ScalingArgs),
    /// Time crowd frames of a model file under its distance policy in both scenes on each thread
    /// count: median, 99th percentile and worst frame, with the fixed-work control beside each row
    /// (the frame-time rows of `tables`, alone, for a machine with more cores), as Markdown.
    Frames(FramesArgs),
    /// Produce every deterministic figure README.md quotes with the command registered for it in
    /// `docs/readme-figures.toml` and rewrite README's values (`--check`: fail on any difference,
    /// and on a timing that names no date).
    Readme(ReadmeArgs),
}

/// Options of `xtask readme`.
#[derive(Debug, Args)]
struct ReadmeArgs {
    /// Do not write: fail, listing each README figure that differs from what its command prints.
    #[arg(long)]
    check: bool,
    /// The `motion-lod` binary to run (default: `cargo build --release -p motion-lod`, then
    /// `target/release/motion-lod`).
    #[arg(long, value_name = "PATH")]
    bin: Option<PathBuf>,
    /// Do not print each command with its time.
    #[arg(long)]
    quiet: bool,
}

/// Options of `xtask frames`.
#[derive(Debug, Args)]
struct FramesArgs {
    /// The model file (`motion-lod build ... -o FILE.mlod`).
    #[arg(value_name = "MODEL")]
    model: PathBuf,
    /// Crowd sizes, comma-separated.
    #[arg(long, value_name = "N,N,...", value_delimiter = ',', default_value = "100000", value_parser = clap::value_parser!(u32).range(1..=10_000_000))]
    walkers: Vec<u32>,
    /// Thread counts, comma-separated (default: 1, 2, 4, 8 and 16 up to this machine's cores).
    #[arg(long, value_name = "N,N,...", value_delimiter = ',', value_parser = clap::value_parser!(u16).range(1..=1024))]
    threads: Vec<u16>,
    /// Timed frames of each row, after the 1.5 s warm-up.
    #[arg(long, default_value_t = tables::crowd::FRAME_TIME_FRAMES as u32, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    frames: u32,
    /// The Markdown file to write (default: standard output).
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// No progress display.
    #[arg(long)]
    quiet: bool,
}

/// Options of `xtask scaling`.
#[derive(Debug, Args)]
struct ScalingArgs {
    /// Folder of BVH takes to grow the sets from.
    #[arg(
        long,
        value_name = "DIR",
        default_value = "../shared/mocap/bandai-namco-2-walk"
    )]
    data: PathBuf,
    /// Cycle counts, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "800,2000,5000,10000")]
    sizes: Vec<usize>,
    /// Thread counts, comma-separated (default: 1 and this machine's cores, at most 16).
    #[arg(long, value_delimiter = ',')]
    threads: Vec<usize>,
    /// Stop a build after this many seconds.
    #[arg(long, default_value_t = 600)]
    limit_s: u64,
    /// The document to write.
    #[arg(long, default_value = "docs/scaling.md")]
    out: PathBuf,
    /// Build `N` cycles once in this process and print what it measured as one JSON line (what
    /// the runs above do in a child process each).
    #[arg(long, value_name = "N")]
    one: Option<usize>,
}

/// Options of `xtask web`.
#[derive(Debug, Args)]
struct WebArgs {
    /// Do not write: fail if the checked-in assets differ from a build of the current source.
    #[arg(long)]
    check: bool,
}

/// Options of `xtask imports`.
#[derive(Debug, Args)]
struct ImportsArgs {
    /// The crate's `src/` folders to check (default: `crates/motion-lod/src`).
    #[arg(value_name = "SRC")]
    dirs: Vec<PathBuf>,
    /// Print every edge, not only the circles.
    #[arg(long)]
    verbose: bool,
}

/// Options of `xtask tables`.
#[derive(Debug, Args)]
struct TablesArgs {
    /// Folder of BVH takes (default: the embedded fixtures), e.g. `../shared/mocap/bandai-namco-2-walk`.
    #[arg(long, value_name = "DIR")]
    data: Option<PathBuf>,
    /// Use a deterministic subset of N cycles.
    #[arg(long, value_name = "N")]
    samples: Option<usize>,
    /// Markdown file to write (default: `docs/tables.md` at the workspace root). The figures go to
    /// `figures/` beside it, or `figures/NAME/` for `tables-NAME.md`.
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// Folder of the SVG figures (default: derived from `--out`, see above).
    #[arg(long, value_name = "DIR")]
    figures: Option<PathBuf>,
    /// No progress display.
    #[arg(long)]
    quiet: bool,
    /// Thread counts of the crowd scaling rows (default 1,2), e.g. `1,2,4,8,16` on a bigger machine.
    #[arg(long, value_name = "N,N,...", value_delimiter = ',', value_parser = clap::value_parser!(u16).range(1..=1024))]
    crowd_threads: Vec<u16>,
    /// Also cross-validate a model that conditions on style, the takes' styles read from their file
    /// names by this regular expression (its first capture group), e.g. '_([a-z]+)_\d+\.bvh$'
    /// for Bandai: section 5 then has the refitted errors with styles, pooled and per style.
    #[arg(long, value_name = "REGEX")]
    style_from_name: Option<String>,
}

/// Options of `xtask fixtures`.
#[derive(Debug, Args)]
struct FixturesArgs {
    /// Output folder (default: `fixtures/` at the workspace root).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Do not write: fail if the files on disk differ from what the generator produces.
    #[arg(long)]
    check: bool,
}

fn main() -> Result<()> {
    match Cli::parse().command {
        Command::Fixtures(args) => run_fixtures(&args),
        Command::Tables(args) => run_tables(&args),
        Command::Imports(args) => run_imports(&args),
        Command::Readme(args) => {
            let root = tables::workspace_root();
            let root = root.canonicalize().unwrap_or(root);
            readme::run(
                &root,
                &readme::Options {
                    check: args.check,
                    bin: args.bin,
                    quiet: args.quiet,
                },
            )
        }
        Command::Scaling(args) => run_scaling(&args),
        Command::Frames(args) => run_frames(&args),
        Command::Web(args) => {
            let root = tables::workspace_root();
            let root = root.canonicalize().unwrap_or(root);
            for line in web::run(&root, args.check)? {
                println!("{line}");
            }
            Ok(())
        }
    }
}

fn run_scaling(args: &ScalingArgs) -> Result<()> {
    if let Some(n) = args.one {
        let measured = scaling::build_one(&args.data, n)?;
        println!("{}", serde_json::to_string(&measured)?);
        return Ok(());
    }
    let threads = if args.threads.is_empty() {
        default_threads(std::thread::available_parallelism().map_or(1, |n| n.get()))
    } else {
        args.threads.clone()
    };
    let mut command = format!("cargo xtask scaling --sizes {}", comma_list(&args.sizes));
    if !args.threads.is_empty() {
        command.push_str(&format!(" --threads {}", comma_list(&threads)));
    }
    scaling::run(&scaling::ScalingConfig {
        data: args.data.clone(),
        sizes: args.sizes.clone(),
        threads,
        limit: std::time::Duration::from_secs(args.limit_s),
        out: args.out.clone(),
        command,
    })
}

/// `v` as a command line writes it: `1,2,4`.
fn comma_list<T: ToString>(v: &[T]) -> String {
    v.iter().map(T::to_string).collect::<Vec<_>>().join(",")
}

/// 1, 2, 4, 8 and 16, those up to `cores`.
fn default_threads(cores: usize) -> Vec<usize> {
    let mut t = vec![1];
    t.extend([2, 4, 8, 16].into_iter().filter(|&k| k <= cores));
    t
}

fn run_frames(args: &FramesArgs) -> Result<()> {
    let threads: Vec<usize> = if args.threads.is_empty() {
        default_threads(std::thread::available_parallelism().map_or(1, |n| n.get()))
    } else {
        args.threads.iter().map(|&t| usize::from(t)).collect()
    };
    let walkers: Vec<usize> = args.walkers.iter().map(|&w| w as usize).collect();
    let command = format!(
        "cargo xtask frames {} --walkers {} --threads {} --frames {}",
        args.model.display(),
        comma_list(&walkers),
        comma_list(&threads),
        args.frames
    );
    let frames = args.frames as usize;
    // The folder of the document, checked before minutes of measuring.
    if let Some(out) = &args.out
        && let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty())
        && !dir.is_dir()
    {
        bail!("--out {}: no folder {}", out.display(), dir.display());
    }
    let doc = tables::frames(&tables::FramesConfig {
        model: args.model.clone(),
        walkers,
        threads,
        frames,
        show_progress: !args.quiet,
        command,
    })?;
    match &args.out {
        Some(out) => {
            std::fs::write(out, &doc).with_context(|| format!("writing {}", out.display()))?;
            eprintln!("wrote {}", out.display());
        }
        None => print!("{doc}"),
    }
    Ok(())
}

fn run_imports(args: &ImportsArgs) -> Result<()> {
    let dirs = if args.dirs.is_empty() {
        let root = tables::workspace_root();
        vec![
            root.canonicalize()
                .unwrap_or(root)
                .join("crates/motion-lod/src"),
        ]
    } else {
        args.dirs.clone()
    };
    let mut circles = 0;
    for dir in &dirs {
        let graph = imports::ImportGraph::of_crate(dir)?;
        let edges: usize = graph.edges.values().map(|t| t.len()).sum();
        println!(
            "{}: {} modules, {edges} import edges",
            dir.display(),
            graph.edges.len()
        );
        if args.verbose {
            for (a, targets) in &graph.edges {
                for b in targets {
                    println!("  {a} -> {b}");
                }
            }
        }
        for circle in graph.circles() {
            circles += 1;
            println!("import circle: {}", circle.join(", "));
            for edge in graph.edges_within(&circle) {
                println!("  {edge}");
            }
        }
    }
    if circles > 0 {
        bail!("{circles} import circle(s): cut one edge of each");
    }
    println!("no import circles");
    Ok(())
}

fn run_tables(args: &TablesArgs) -> Result<()> {
    let root = tables::workspace_root();
    let root = root.canonicalize().unwrap_or(root);
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| root.join("docs").join("tables.md"));
    let figures = args
        .figures
        .clone()
        .unwrap_or_else(|| tables::figures_dir_for(&out));
    let mut command = String::from("cargo xtask tables");
    if let Some(d) = &args.data {
        command.push_str(&format!(" --data {}", d.display()));
    }
    if let Some(n) = args.samples {
        command.push_str(&format!(" --samples {n}"));
    }
    if let Some(o) = &args.out {
        command.push_str(&format!(" --out {}", o.display()));
    }
    if let Some(f) = &args.figures {
        command.push_str(&format!(" --figures {}", f.display()));
    }
    if !args.crowd_threads.is_empty() {
        command.push_str(&format!(
            " --crowd-threads {}",
            comma_list(&args.crowd_threads)
        ));
    }
    if let Some(p) = &args.style_from_name {
        command.push_str(&format!(" --style-from-name '{p}'"));
    }
    let mut config = tables::TablesConfig::full(args.data.clone(), out, figures);
    config.style = args
        .style_from_name
        .clone()
        .map(motion_lod::style::StyleSpec::Name);
    if !args.crowd_threads.is_empty() {
        config.crowd_threads = args.crowd_threads.iter().map(|&t| usize::from(t)).collect();
    }
    config.samples = args.samples;
    config.show_progress = !args.quiet;
    config.command = command;
    tables::run(&config)
}

fn run_fixtures(args: &FixturesArgs) -> Result<()> {
    let dir = args.out.clone().unwrap_or_else(fixtures::default_dir);
    let dir = dir.canonicalize().unwrap_or(dir);
    let files = fixtures::generate_all(fixtures::SEED)?;
    if args.check {
        let stale = fixtures::check(&dir, &files);
        if !stale.is_empty() {
            bail!(
                "{} file(s) in {} differ from the generator: {}",
                stale.len(),
                dir.display(),
                stale.join(", ")
            );
        }
        println!(
            "fixtures: {} files in {} are up to date",
            files.len(),
            dir.display()
        );
        return Ok(());
    }
    let bytes = fixtures::write(&dir, &files)?;
    println!(
        "fixtures: wrote {} files ({:.2} MB) to {}",
        files.len(),
        bytes as f64 / 1e6,
        dir.display()
    );
    Ok(())
}
