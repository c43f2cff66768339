//! Long calls from Python: the work runs on a thread of its own while the calling thread, the GIL
//! released between looks, watches it: it hands the latest progress to the user's callback and
//! turns Ctrl-C (or an exception from the callback) into cancellation, so a long search stops
//! within a moment and other Python threads run meanwhile.

use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use pyo3::exceptions::{PyRuntimeError, PyTypeError};
use pyo3::prelude::*;
use pyo3::types::PyBool;
use slabscope::{Cancel, Monitor, Progress};

use crate::errors::{repr, to_py};

/// What `progress=` asks for: the user's `progress(phase, fraction)`, a bar (`True`: tqdm's when
/// installed, else a line on stderr; closed when this is dropped), or nothing (`None`, `False`).
pub struct Reporter<'py> {
    callback: Option<Bound<'py, PyAny>>,
    bar: bool,
}

impl<'py> Reporter<'py> {
    /// The reporter of `call`'s `progress` argument: anything else than a callable, a bool or
    /// `None` is a `TypeError` naming the keyword.
    pub fn new(call: &str, progress: Option<&Bound<'py, PyAny>>) -> PyResult<Self> {
        let none = Self {
            callback: None,
            bar: false,
        };
        let Some(p) = progress.filter(|p| !p.is_none()) else {
            return Ok(none);
        };
        if p.is_instance_of::<PyBool>() {
            if !p.is_truthy()? {
                return Ok(none);
            }
            let bar = p.py().import("slabscope._progress")?.getattr("Bar")?;
            return Ok(Self {
                callback: Some(bar.call0()?),
                bar: true,
            });
        }
        if p.is_callable() {
            return Ok(Self {
                callback: Some(p.clone()),
                bar: false,
            });
        }
        Err(PyTypeError::new_err(format!(
            "{call}(): progress={}: expected a function progress(phase, fraction), True or None",
            repr(p)
        )))
    }

    /// The function to call with the progress, if any.
    pub fn callback(&self) -> Option<&Bound<'py, PyAny>> {
        self.callback.as_ref()
    }
}

impl Drop for Reporter<'_> {
    fn drop(&mut self) {
        if let (true, Some(bar)) = (self.bar, &self.callback) {
            // Closing a bar only writes to stderr: nothing to report if it fails.
            let _ = bar.call_method0("close");
        }
    }
}

thread_local! {
    /// The pool the calls made on this thread run their work in (`threads=`), while a
    /// [`Threads`] guard set it.
    static POOL: RefCell<Option<Arc<rayon::ThreadPool>>> = const { RefCell::new(None) };
}

/// `threads=` of a call: while this lives, [`long`] and [`quick`] run their work in its pool.
/// Without one, the pool of the call around it stays (`render` without an analysis analyses
/// within render's `threads=`), else all threads.
pub struct Threads {
    /// Whether it bound a pool, and the pool it took the place of.
    bound: bool,
    previous: Option<Arc<rayon::ThreadPool>>,
}

impl Threads {
    /// Runs this thread's calls in `pool`, when there is one, until dropped.
    #[must_use]
    pub fn bound(pool: Option<rayon::ThreadPool>) -> Self {
        match pool {
            Some(p) => Self {
                bound: true,
                previous: POOL.replace(Some(Arc::new(p))),
            },
            None => Self {
                bound: false,
                previous: None,
            },
        }
    }
}

impl Drop for Threads {
    fn drop(&mut self) {
        if self.bound {
            POOL.set(self.previous.take());
        }
    }
}

/// The pool this thread's calls run in, if `threads=` bound one.
pub fn pool() -> Option<Arc<rayon::ThreadPool>> {
    POOL.with_borrow(Clone::clone)
}

/// Runs `work` in `pool`, or where it is called without one.
pub fn in_pool<T: Send>(pool: Option<&rayon::ThreadPool>, work: impl FnOnce() -> T + Send) -> T {
    match pool {
        Some(p) => p.install(work),
        None => work(),
    }
}

/// How often the watching thread looks at the work.
const LOOK: Duration = Duration::from_millis(20);

/// Runs `work` with a monitor, the GIL released; `progress(phase, fraction)` is called with the
/// latest progress from this thread. Ctrl-C raises `KeyboardInterrupt` once the work has stopped.
pub fn long<T: Send>(
    py: Python<'_>,
    progress: Option<&Bound<'_, PyAny>>,
    work: impl FnOnce(&Monitor) -> slabscope::Result<T> + Send,
) -> PyResult<T> {
    watched(py, progress, |monitor, _| work(monitor))
}

/// Runs a load, the GIL released, with the cancellation it takes
/// ([`LoadOptions::cancel`](slabscope::LoadOptions)): Ctrl-C raises it, and `KeyboardInterrupt`
/// once the load has stopped between chunks, files or pages.
pub fn loading<T: Send>(
    py: Python<'_>,
    work: impl FnOnce(Cancel) -> slabscope::Result<T> + Send,
) -> PyResult<T> {
    watched(py, None, |_, cancel| work(cancel))
}

/// [`long`]'s work, handed the monitor and the same flag as a load's cancellation.
fn watched<T: Send>(
    py: Python<'_>,
    progress: Option<&Bound<'_, PyAny>>,
    work: impl FnOnce(&Monitor, Cancel) -> slabscope::Result<T> + Send,
) -> PyResult<T> {
    let cancel = Arc::new(AtomicBool::new(false));
    let latest: Mutex<Option<Progress>> = Mutex::new(None);
    let report = |p: Progress| {
        *latest
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner) = Some(p);
    };
    let pool = pool();
    let (result, raised) = std::thread::scope(|s| {
        let worker = s.spawn(|| {
            in_pool(pool.as_deref(), || {
                let monitor = Monitor::new(Some(cancel.as_ref()), Some(&report));
                work(&monitor, Cancel::new(Arc::clone(&cancel)))
            })
        });
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
    let pool = pool();
    py.detach(|| in_pool(pool.as_deref(), work)).map_err(to_py)
}
