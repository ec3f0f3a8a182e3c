//! The progress display of `cargo xtask tables` on standard error: one bar per stage (spinner and
//! elapsed time ticking), and a line with the stage's wall-clock time when it ends.

use std::sync::Mutex;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use motion_lod::progress::Progress;

/// Stage bars on standard error; silent when `visible` is false.
#[derive(Debug)]
pub struct StageBar {
    current: Mutex<Option<(ProgressBar, String, Instant)>>,
    visible: bool,
    started: Instant,
}

impl StageBar {
    /// A display that draws only when `visible`.
    pub fn new(visible: bool) -> StageBar {
        StageBar {
            current: Mutex::new(None),
            visible,
            started: Instant::now(),
        }
    }

    /// Ends the current stage (prints its time) without starting another.
    pub fn finish(&self) {
        let mut guard = self.current.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((bar, name, t0)) = guard.take() {
            bar.finish_and_clear();
            if self.visible {
                eprintln!(
                    "  {name:<34} {:>7.1} s   (total {:.0} s)",
                    t0.elapsed().as_secs_f64(),
                    self.started.elapsed().as_secs_f64()
                );
            }
        }
    }
}

impl Progress for StageBar {
    fn stage(&self, name: &str, total: u64) {
        self.finish();
        let bar = if self.visible {
            ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr())
        } else {
            ProgressBar::hidden()
        };
        if let Ok(style) =
            ProgressStyle::with_template("{spinner} {msg:<34} [{bar:30}] {pos}/{len} {elapsed}")
        {
            bar.set_style(style.progress_chars("=> "));
        }
        bar.set_message(name.to_owned());
        if self.visible {
            bar.enable_steady_tick(Duration::from_millis(200));
        }
        *self.current.lock().unwrap_or_else(|e| e.into_inner()) =
            Some((bar, name.to_owned(), Instant::now()));
    }

    fn inc(&self, n: u64) {
        if let Some((bar, _, _)) = self
            .current
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .as_ref()
        {
            bar.inc(n);
        }
    }
}

impl Drop for StageBar {
    fn drop(&mut self) {
        self.finish();
    }
}
