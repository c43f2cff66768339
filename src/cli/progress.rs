//! A progress bar on stderr, drawn only when stderr is a terminal, naming the phase under way.

use std::io::{IsTerminal, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, OnceLock};
use std::time::Duration;

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

/// Raised at the `--timeout`: every long computation of the command stops.
static STOP: AtomicBool = AtomicBool::new(false);

/// The `--timeout` in force, seconds.
static TIMEOUT: OnceLock<f64> = OnceLock::new();

/// Stops the command's long computations `seconds` from now (`--timeout`): they end with
/// [`slabscope::Error::Cancelled`], which [`timed_out`] words.
pub fn stop_after(seconds: f64) {
    if TIMEOUT.set(seconds).is_ok() {
        std::thread::spawn(move || {
            std::thread::sleep(Duration::from_secs_f64(seconds));
            STOP.store(true, Ordering::Relaxed);
        });
    }
}

/// The words for a computation the `--timeout` stopped, when it did.
pub fn timed_out() -> Option<String> {
    let t = TIMEOUT.get()?;
    STOP.load(Ordering::Relaxed)
        .then(|| format!("stopped at the --timeout of {t} s"))
}

/// Runs `work` with a monitor that draws its progress in a bar on stderr and stops at the
/// `--timeout`.
pub fn with_bar<T>(work: impl FnOnce(&Monitor) -> T) -> T {
    let bar = Bar::new();
    let report = |p: Progress| bar.set(p);
    work(&Monitor::new(Some(&STOP), Some(&report)))
}
