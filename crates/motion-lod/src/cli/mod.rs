//! The subcommands of the `motion-lod` binary, one module each. `main.rs` only parses the command
//! line and dispatches to the `run` function of the chosen module.

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
