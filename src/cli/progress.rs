//! A progress bar on stderr, drawn only when stderr is a terminal, naming the phase under way.

use std::io::{IsTerminal, Write};
use std::sync::Mutex;

use slabscope::{Monitor, Progress};

/// Characters of the bar.
const WIDTH: usize = 30;

/// Draws `[#####.....]  45% view search` on stderr, redrawn in place; nothing when stderr is not
/// a terminal. The line is cleared when the bar is dropped.
pub struct Bar {
    shown: Mutex<bool>,
    enabled: bool,
}

impl Bar {
    /// A bar, drawn from the first progress on.
    pub fn new() -> Self {
        Self {
            shown: Mutex::new(false),
            enabled: std::io::stderr().is_terminal(),
        }
    }

    /// Redraws the bar at `progress`.
    pub fn set(&self, progress: Progress) {
        if !self.enabled {
            return;
        }
        let fraction = progress.fraction;
        let filled = ((fraction.clamp(0.0, 1.0) * WIDTH as f64) as usize).min(WIDTH);
        let mut shown = self
            .shown
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        *shown = true;
        let mut err = std::io::stderr().lock();
        let _ = write!(
            err,
            "\r\x1b[2K[{}{}] {:3.0}% {}",
            "#".repeat(filled),
            ".".repeat(WIDTH - filled),
            fraction * 100.0,
            progress.phase
        );
        let _ = err.flush();
    }
}

impl Drop for Bar {
    fn drop(&mut self) {
        if self.shown.get_mut().is_ok_and(|s| *s) {
            let _ = write!(std::io::stderr(), "\r\x1b[2K");
        }
    }
}

/// Runs `work` with a monitor that draws its progress in a bar on stderr.
pub fn with_bar<T>(work: impl FnOnce(&Monitor) -> T) -> T {
    let bar = Bar::new();
    let report = |p: Progress| bar.set(p);
    work(&Monitor::new(None, Some(&report)))
}
