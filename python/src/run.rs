//! Long calls from Python: the work runs on a thread of its own while the calling thread, the GIL
//! released between looks, watches it: it hands the latest progress to the user's callback and
//! turns Ctrl-C (or an exception from the callback) into cancellation, so a long search stops
//! within a moment and other Python threads run meanwhile.

use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use slabscope::{Monitor, Progress};

use crate::errors::to_py;

/// How often the watching thread looks at the work.
const LOOK: Duration = Duration::from_millis(20);

/// Runs `work` with a monitor, the GIL released; `progress(phase, fraction)` is called with the
/// latest progress from this thread. Ctrl-C raises `KeyboardInterrupt` once the work has stopped.
pub fn long<T: Send>(
    py: Python<'_>,
    progress: Option<&Bound<'_, PyAny>>,
    work: impl FnOnce(&Monitor) -> slabscope::Result<T> + Send,
) -> PyResult<T> {
    let cancel = AtomicBool::new(false);
    let latest: Mutex<Option<Progress>> = Mutex::new(None);
    let report = |p: Progress| {
        *latest
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner) = Some(p);
    };
    let (result, raised) = std::thread::scope(|s| {
        let worker = s.spawn(|| work(&Monitor::new(Some(&cancel), Some(&report))));
        let mut raised: Option<PyErr> = None;
        let tell = |raised: &mut Option<PyErr>| {
            let last = latest
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner)
                .take();
            if let (Some(callback), Some(p), None) = (progress, last, raised.as_ref())
                && let Err(e) = callback.call1((p.phase, p.fraction))
            {
                cancel.store(true, Ordering::Relaxed);
                *raised = Some(e);
            }
        };
        while !worker.is_finished() {
            py.detach(|| std::thread::sleep(LOOK));
            if raised.is_none()
                && let Err(e) = py.check_signals()
            {
                cancel.store(true, Ordering::Relaxed);
                raised = Some(e);
            }
            tell(&mut raised);
        }
        tell(&mut raised);
        (worker.join(), raised)
    });
    if let Some(e) = raised {
        return Err(e);
    }
    match result {
        Ok(r) => r.map_err(to_py),
        Err(panic) => Err(PyRuntimeError::new_err(format!(
            "slabscope failed inside: {}",
            panic
                .downcast_ref::<&str>()
                .copied()
                .or_else(|| panic.downcast_ref::<String>().map(String::as_str))
                .unwrap_or("a panic")
        ))),
    }
}

/// Runs short work with the GIL released (no progress, no cancellation).
pub fn quick<T: Send>(
    py: Python<'_>,
    work: impl FnOnce() -> slabscope::Result<T> + Send,
) -> PyResult<T> {
    py.detach(work).map_err(to_py)
}
