//! The `motion-lod` command line. Each subcommand lives in its own module under `src/cli/`
//! (arguments as a clap `Args` struct and a `run` function); this file only dispatches.

mod cli;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

/// Multilinear motion synthesis with level-of-detail controls.
#[derive(Debug, Parser)]
#[command(
    name = "motion-lod",
    version,
    about = "Walking characters from motion capture at a cost that falls with distance: build a \
             multilinear model from BVH takes, synthesize walks for any controls, run and render crowds \
             with levels of detail.",
    after_help = "Terms in the output (accuracy level, key level, shell error, pop, ...): motion-lod explain TERM"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// One variant per subcommand.
#[derive(Debug, Subcommand)]
enum Command {
    /// Read BVH folders, segment gait cycles, align them and write the motion tensor.
    Cycles(cli::cycles::CyclesArgs),
    /// Build the multilinear model from BVH folders (or the embedded data) and write the model file.
    Build(cli::build::BuildArgs),
    /// Show a model's dimensions, levels, errors and storage.
    Info(cli::info::InfoArgs),
    /// Error of the model at each key level against naive kriging, RBF, PCA and nearest: leave-one-out,
    /// K-fold refits (--folds) or held-out folders (--holdout).
    #[command(
        override_usage = "motion-lod eval [OPTIONS] MODEL.mlod\n       motion-lod eval [OPTIONS] [DIR]...",
        after_help = "MODEL.mlod: its recorded training data and settings are used (--data DIR reads \
                      the data from elsewhere). DIR: folders of BVH takes, with the data and model \
                      options; no DIR: the embedded default data set."
    )]
    Eval(cli::eval::EvalArgs),
    /// Motion quality (pop, foot skate, floor, facing, cadence) of walks over the data's controls.
    Quality(cli::quality::QualityArgs),
    /// Synthesize a walk for given controls and write it as BVH or glTF (`.glb`).
    Synth(cli::synth::SynthArgs),
    /// Animate a crowd with the model's level of detail; time it, render it, compare with naive.
    Crowd(cli::crowd::CrowdArgs),
    /// Serve the web viewer and a .glb on localhost and print the address to open.
    View(cli::view::ViewArgs),
    /// The main job on the embedded data: build, run 1,000 walkers for 10 s, render, report.
    Demo(cli::demo::DemoArgs),
    /// What a term in the output means (accuracy level, shell error, pop, ...); no term lists them.
    Explain(cli::explain::ExplainArgs),
}

/// Runs the command; a user error (anything returned as `Err`) is printed by [`report`] and exits
/// with status 1. Bugs panic and keep Rust's panic message (and backtrace with `RUST_BACKTRACE`).
fn main() -> std::process::ExitCode {
    // Negative numbers are values, not flags, in every subcommand (`--turn -30`, `--fps -30`, which
    // the range check then refuses with its own message).
    let matches = Cli::command()
        .mut_subcommands(|c| c.allow_negative_numbers(true))
        .get_matches();
    let mut cli = match Cli::from_arg_matches(&matches) {
        Ok(cli) => cli,
        Err(e) => e.exit(),
    };
    if let (Command::Eval(args), Some(("eval", sub))) = (&mut cli.command, matches.subcommand()) {
        args.given_settings = cli::eval::given_settings(sub);
    }
    match run(cli) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        // The reader went away (`motion-lod info m.mlod | head -1`): not an error of ours.
        Err(e) if broken_pipe(&e) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprint!("{}", report(&e));
            std::process::ExitCode::from(1)
        }
    }
}

/// True when the error is a write to a closed pipe (anywhere in its chain).
fn broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// A user error as the user reads it: `error: ` and what failed (with where), then each cause once,
/// a cause whose text the line before already holds left out; never a backtrace, whatever
/// `RUST_BACKTRACE` says (user errors are not bugs).
fn report(e: &anyhow::Error) -> String {
    let mut out = format!("error: {e}\n");
    let mut last = e.to_string();
    for cause in e.chain().skip(1) {
        let text = cause.to_string();
        if !last.contains(&text) {
            out.push_str(&format!("  caused by: {text}\n"));
        }
        last = text;
    }
    out
}

fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Cycles(args) => cli::cycles::run(args),
        Command::Build(args) => cli::build::run(args),
        Command::Info(args) => cli::info::run(args),
        Command::Eval(args) => cli::eval::run(args),
        Command::Synth(args) => cli::synth::run(args),
        Command::Quality(args) => cli::quality::run(args),
        Command::Crowd(args) => cli::crowd::run(args),
        Command::Demo(args) => cli::demo::run(args),
        Command::View(args) => cli::view::run(args),
        Command::Explain(args) => cli::explain::run(args),
    }
}

#[cfg(test)]
mod tests {
    use super::report;

    #[test]
    fn causes_print_once_and_without_a_backtrace() {
        let io = std::io::Error::new(std::io::ErrorKind::NotFound, "No such file or directory");
        let e = anyhow::Error::new(io)
            .context("cannot list folder /x: No such file or directory")
            .context("loading /x");
        assert_eq!(
            report(&e),
            "error: loading /x\n  caused by: cannot list folder /x: No such file or directory\n"
        );
    }
}
