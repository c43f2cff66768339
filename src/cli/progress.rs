//! A progress bar on stderr, drawn only when stderr is a terminal.

use std::io::{IsTerminal, Write};
use std::sync::Mutex;

/// Characters of the bar.
const WIDTH: usize = 30;

/// Draws `[#####.....]  45% label` on stderr, redrawn in place; nothing when stderr is not a
/// terminal. The line is cleared when the bar is dropped.
pub struct Bar {
    label: &'static str,
    shown: Mutex<bool>,
    enabled: bool,
}

impl Bar {
    /// A bar for the step `label`.
    pub fn new(label: &'static str) -> Self {
        Self {
            label,
            shown: Mutex::new(false),
            enabled: std::io::stderr().is_terminal(),
        }
    }

    /// Redraws the bar at `fraction` (0 to 1).
    pub fn set(&self, fraction: f64) {
        if !self.enabled {
            return;
        }
        let filled = ((fraction.clamp(0.0, 1.0) * WIDTH as f64) as usize).min(WIDTH);
        let mut shown = self
            .shown
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        *shown = true;
        let mut err = std::io::stderr().lock();
        let _ = write!(
            err,
            "\r[{}{}] {:3.0}% {}",
            "#".repeat(filled),
            ".".repeat(WIDTH - filled),
            fraction * 100.0,
            self.label
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
