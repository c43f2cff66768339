//! Progress reporting and cancellation for long computations, shared by the view search,
//! partition histories and renders, so the TUI can show a gauge and the user can cancel.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use crate::error::{Error, Result};

/// Where a long computation is: the phase it is in ("view search", "slicing", "bottom-up", ...)
/// and the fraction of that phase done.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Progress {
    /// The phase, in words a user reads.
    pub phase: &'static str,
    /// The fraction of the phase done, 0 to 1; it never goes down within a phase.
    pub fraction: f64,
}

/// The callback that receives progress.
pub type Report<'a> = &'a (dyn Fn(Progress) + Sync);

/// Watches a long computation: counts finished units of work, reports the phase and the fraction
/// done when its whole percentage changes, and says whether the computation was cancelled.
pub struct Monitor<'a> {
    cancel: Option<&'a AtomicBool>,
    report: Option<Report<'a>>,
    phase: std::sync::Mutex<&'static str>,
    total: AtomicU64,
    done: AtomicU64,
    percent: AtomicU64,
}

impl<'a> Monitor<'a> {
    /// A monitor with an optional cancellation flag and progress callback (fraction in [0, 1]).
    pub fn new(cancel: Option<&'a AtomicBool>, report: Option<Report<'a>>) -> Self {
        Self {
            cancel,
            report,
            phase: std::sync::Mutex::new(""),
            total: AtomicU64::new(1),
            done: AtomicU64::new(0),
            percent: AtomicU64::new(0),
        }
    }

    /// A monitor that never cancels and reports nowhere.
    pub fn none() -> Monitor<'static> {
        Monitor::new(None, None)
    }

    /// Starts `phase`, which will report `total` units of work, and reports it at 0%.
    pub fn start(&self, phase: &'static str, total: u64) {
        *self
            .phase
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner) = phase;
        self.total.store(total.max(1), Ordering::Relaxed);
        self.done.store(0, Ordering::Relaxed);
        self.percent.store(0, Ordering::Relaxed);
        if let Some(report) = self.report {
            report(Progress {
                phase,
                fraction: 0.0,
            });
        }
    }

    /// The phase under way.
    pub fn phase(&self) -> &'static str {
        *self
            .phase
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
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

    /// The units recorded in the phase under way, and the total it announced.
    #[cfg(test)]
    pub(crate) fn counted(&self) -> (u64, u64) {
        (
            self.done.load(Ordering::Relaxed),
            self.total.load(Ordering::Relaxed),
        )
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
            report(Progress {
                phase: self.phase(),
                fraction: percent as f64 / 100.0,
            });
        }
        self.check()
    }
}

/// The cancellation flag a load looks at between its units of work (a Zarr chunk, a DICOM
/// series' file, a TIFF page), carried by [`LoadOptions`](crate::LoadOptions): raised, the load
/// stops with [`Error::Cancelled`]. A front end raises it at its timeout, on Ctrl-C, or when the
/// user moves on; by default no flag, and a load runs to its end.
#[derive(Clone, Debug, Default)]
pub struct Cancel(Option<Arc<AtomicBool>>);

impl Cancel {
    /// A load stopped when `flag` is raised.
    #[must_use]
    pub fn new(flag: Arc<AtomicBool>) -> Self {
        Self(Some(flag))
    }

    /// A load that runs to its end.
    #[must_use]
    pub fn never() -> Self {
        Self(None)
    }

    /// The flag, for a [`Monitor`] of the same work.
    #[must_use]
    pub fn flag(&self) -> Option<&AtomicBool> {
        self.0.as_deref()
    }

    /// Whether cancellation was asked for.
    #[must_use]
    pub fn is_cancelled(&self) -> bool {
        self.0.as_ref().is_some_and(|c| c.load(Ordering::Relaxed))
    }

    /// Fails with [`Error::Cancelled`] when cancellation was asked for.
    pub fn check(&self) -> Result<()> {
        if self.is_cancelled() {
            Err(Error::Cancelled)
        } else {
            Ok(())
        }
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Mutex;

    use super::*;

    #[test]
    fn reports_each_whole_percent_once() {
        let seen = Mutex::new(Vec::new());
        let report = |p: Progress| seen.lock().unwrap().push(p);
        let m = Monitor::new(None, Some(&report));
        m.start("counting", 1000);
        for _ in 0..1000 {
            m.advance(1).unwrap();
        }
        m.start("second", 10);
        let seen = seen.into_inner().unwrap();
        assert_eq!(
            seen.len(),
            102,
            "0% and each whole percent of the first phase, then 0%"
        );
        assert_eq!(
            seen[100],
            Progress {
                phase: "counting",
                fraction: 1.0
            }
        );
        assert!(
            seen[..101]
                .windows(2)
                .all(|w| w[0].fraction < w[1].fraction)
        );
        assert_eq!(
            seen[101],
            Progress {
                phase: "second",
                fraction: 0.0
            }
        );
    }

    #[test]
    fn cancellation_is_an_error() {
        let flag = AtomicBool::new(false);
        let m = Monitor::new(Some(&flag), None);
        assert!(m.advance(1).is_ok());
        flag.store(true, Ordering::Relaxed);
        assert!(matches!(m.advance(1), Err(Error::Cancelled)));
    }

    #[test]
    fn a_load_is_cancelled_through_its_shared_flag() {
        assert!(Cancel::never().check().is_ok());
        assert!(Cancel::default().flag().is_none());
        let flag = Arc::new(AtomicBool::new(false));
        let cancel = Cancel::new(Arc::clone(&flag));
        let copy = cancel.clone();
        assert!(copy.check().is_ok());
        flag.store(true, Ordering::Relaxed);
        assert!(matches!(copy.check(), Err(Error::Cancelled)));
        assert!(cancel.flag().is_some_and(|f| f.load(Ordering::Relaxed)));
    }
}
