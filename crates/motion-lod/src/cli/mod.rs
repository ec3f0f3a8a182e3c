//! The subcommands of the `motion-lod` binary, one module each. `main.rs` only parses the command
//! line and dispatches to the `run` function of the chosen module.

/// `println!` that returns the write's error from the calling function (`?`) instead of
/// panicking: `motion-lod quality m.mlod | head -1` closes the pipe while the table is printed,
/// and `println!` panicked there (exit 101; found 2026-11-28). `main` takes a broken pipe for
/// success.
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout(), $($arg)*)?
    }};
}

pub mod build;
pub mod crowd;
pub mod cycles;
pub mod data;
pub mod default_takes;
pub mod demo;
pub mod eval;
pub mod explain;
pub mod gpu;
pub mod info;
pub mod progress;
pub mod quality;
pub mod ranges;
pub mod synth;
pub mod view;
