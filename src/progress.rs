//! Progress reporting and cancellation for long computations, shared by the view search,
//! partition histories and renders, so the TUI can show a gauge and the user can cancel.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use crate::error::{Error, Result};

/// Watches a long computation: counts finished units of work, reports the fraction done when its
/// whole percentage changes, and says whether the computation was cancelled.
pub struct Monitor<'a> {
    cancel: Option<&'a AtomicBool>,
    report: Option<&'a (dyn Fn(f64) + Sync)>,
    total: AtomicU64,
    done: AtomicU64,
    percent: AtomicU64,
}

impl<'a> Monitor<'a> {
    /// A monitor with an optional cancellation flag and progress callback (fraction in [0, 1]).
    pub fn new(cancel: Option<&'a AtomicBool>, report: Option<&'a (dyn Fn(f64) + Sync)>) -> Self {
        Self {
            cancel,
            report,
            total: AtomicU64::new(1),
            done: AtomicU64::new(0),
            percent: AtomicU64::new(0),
        }
    }

    /// A monitor that never cancels and reports nowhere.
    pub fn none() -> Monitor<'static> {
        Monitor::new(None, None)
    }

    /// Sets the number of work units the computation will report, and restarts the count.
    pub fn start(&self, total: u64) {
        self.total.store(total.max(1), Ordering::Relaxed);
        self.done.store(0, Ordering::Relaxed);
        self.percent.store(0, Ordering::Relaxed);
    }

    /// Whether cancellation was asked for.
    pub fn is_cancelled(&self) -> bool {
        self.cancel.is_some_and(|c| c.load(Ordering::Relaxed))
    }

    /// Fails with [`Error::Cancelled`] when cancellation was asked for.
    pub fn check(&self) -> Result<()> {
        if self.is_cancelled() {
            Err(Error::Cancelled)
        } else {
            Ok(())
        }
    }

    /// Records `units` finished units; reports when the whole percentage changes; fails when
    /// cancelled.
    pub fn advance(&self, units: u64) -> Result<()> {
        let done = self.done.fetch_add(units, Ordering::Relaxed) + units;
        let total = self.total.load(Ordering::Relaxed);
        let percent = (done.min(total) * 100) / total;
        if let Some(report) = self.report
            && self.percent.fetch_max(percent, Ordering::Relaxed) < percent
        {
            report(done.min(total) as f64 / total as f64);
        }
        self.check()
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Mutex;

    use super::*;

    #[test]
    fn reports_each_whole_percent_once() {
        let seen = Mutex::new(Vec::new());
        let report = |f: f64| seen.lock().unwrap().push(f);
        let m = Monitor::new(None, Some(&report));
        m.start(1000);
        for _ in 0..1000 {
            m.advance(1).unwrap();
        }
        let seen = seen.into_inner().unwrap();
        assert_eq!(seen.len(), 100);
        assert_eq!(seen.last(), Some(&1.0));
    }

    #[test]
    fn cancellation_is_an_error() {
        let flag = AtomicBool::new(false);
        let m = Monitor::new(Some(&flag), None);
        assert!(m.advance(1).is_ok());
        flag.store(true, Ordering::Relaxed);
        assert!(matches!(m.advance(1), Err(Error::Cancelled)));
    }
}
