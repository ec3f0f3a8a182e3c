//! The command line's progress bar: the library's [`Progress`] stages drawn by `indicatif` on
//! standard error.

use std::sync::Mutex;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use motion_lod::progress::Progress;

/// An `indicatif` bar on standard error, hidden when standard error is not a terminal.
#[derive(Debug)]
pub struct BarProgress {
    bar: Mutex<Option<ProgressBar>>,
    hidden: bool,
}

impl BarProgress {
    /// A bar that draws only when `visible` is true and standard error is a terminal.
    pub fn new(visible: bool) -> BarProgress {
        BarProgress {
            bar: Mutex::new(None),
            hidden: !visible,
        }
    }
}

impl Progress for BarProgress {
    fn stage(&self, name: &str, total: u64) {
        let mut guard = self.bar.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(old) = guard.take() {
            old.finish_and_clear();
        }
        let bar = ProgressBar::new(total);
        if self.hidden {
            bar.set_draw_target(ProgressDrawTarget::hidden());
        } else {
            bar.set_draw_target(ProgressDrawTarget::stderr());
        }
        if let Ok(style) =
            ProgressStyle::with_template("{spinner} {msg:<22} [{bar:30}] {pos}/{len} {elapsed}")
        {
            bar.set_style(style.progress_chars("=> "));
        }
        bar.set_message(name.to_owned());
        *guard = Some(bar);
    }

    fn inc(&self, n: u64) {
        if let Some(bar) = self.bar.lock().unwrap_or_else(|e| e.into_inner()).as_ref() {
            bar.inc(n);
        }
    }
}

impl Drop for BarProgress {
    fn drop(&mut self) {
        if let Some(bar) = self.bar.lock().unwrap_or_else(|e| e.into_inner()).take() {
            bar.finish_and_clear();
        }
    }
}
