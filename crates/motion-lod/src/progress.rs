//! Progress reporting for long offline work, decoupled from any terminal library.
//!
//! Library code reports stages and steps through [`Progress`]; the `motion-lod` command line shows
//! them with a terminal bar, tests and `--json` runs use [`NoProgress`].

/// Receives progress of long work: a named stage with a number of steps, then the steps done.
pub trait Progress: Sync {
    /// A new stage begins with `total` steps.
    fn stage(&self, name: &str, total: u64);
    /// `n` more steps of the current stage are done.
    fn inc(&self, n: u64);
}

/// Reports nothing.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoProgress;

impl Progress for NoProgress {
    fn stage(&self, _name: &str, _total: u64) {}
    fn inc(&self, _n: u64) {}
}
