//! The subcommands of the `motion-lod` binary, one module each. `main.rs` only parses the command
//! line and dispatches to the `run` function of the chosen module.

pub mod build;
pub mod cycles;
pub mod data;
pub mod info;
