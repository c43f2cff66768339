//! `slabscope.triage` and `slabscope.list_volumes`: many volumes, one row each, as
//! `slabscope triage --json` prints them (rows as dicts, in the same order), and the volumes a
//! run would take as the lines `triage --list` prints (for spreading a run over a cluster).

use std::path::PathBuf;
use std::sync::Mutex;
use std::sync::mpsc::{Receiver, RecvTimeoutError, sync_channel};
use std::time::Duration;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use slabscope::error::names::controls;
use slabscope::error::shown;
use slabscope::params::{Terms, table};
use slabscope::triage::{
    Entry, MANIFEST_HEADER, Source, TriagePlan, look_all, parse_manifest, select,
};

use crate::analysis::parse;
use crate::errors::OrPy;
use crate::params::{Kwargs, analysis_params, given, load_options};

/// Volumes looked at at once, as the CLI does.
const WORKERS: usize = 2;

/// The rows of a triage run as they come, in order: an iterator of dicts (`len()` is the
/// number of volumes). Closing it early (or dropping it) stops the run after the volumes under
/// way. Pickling (or a deep copy) waits for the run to end and carries the rows not yet taken:
/// both it and its copy then give them.
#[pyclass(module = "slabscope")]
pub struct Triage {
    rows: Mutex<Receiver<String>>,
    count: usize,
}

/// The paths of `given`: one path, or a list of them.
fn paths(given: &Bound<'_, PyAny>) -> PyResult<Vec<PathBuf>> {
    if let Ok(one) = crate::params::path(given) {
        return Ok(vec![one]);
    }
    given
        .try_iter()?
        .map(|p| crate::params::path(&p?))
        .collect()
}

/// `Err` (`FileNotFoundError` in Python) when not one of `paths` exists: there is no volume under
/// them. A missing path beside others is a row of its own, as on the CLI.
fn none_missing(paths: &[PathBuf]) -> slabscope::Result<()> {
    let missing =
        |p: &PathBuf| std::fs::metadata(p).is_err_and(|e| e.kind() == std::io::ErrorKind::NotFound);
    if paths.is_empty() || !paths.iter().all(missing) {
        return Ok(());
    }
    let shown: Vec<String> = paths.iter().map(|p| shown(p)).collect();
    Err(slabscope::Error::NotFound(format!(
        "no volumes found under {}: no such file or folder",
        shown.join(", ")
    )))
}

/// The entries a run takes: from `entries` (lines as `list_volumes` gives them), a manifest
/// file, or the paths walked; then the shard.
fn entries(
    py: Python<'_>,
    kw: &Kwargs<'_>,
    given: Option<&Bound<'_, PyAny>>,
    opts: &slabscope::LoadOptions,
) -> PyResult<Vec<Entry>> {
    let manifest: Option<PathBuf> = kw.get("manifest")?;
    let lines: Option<Vec<String>> = kw.get("entries")?;
    let shard = crate::params::given(kw, &[&table::SHARD])?
        .shard()
        .or_py()?;
    let given = given.map(paths).transpose()?;
    match (given, manifest, lines) {
        (None, None, Some(lines)) => {
            let text = std::iter::once(MANIFEST_HEADER.to_string())
                .chain(lines)
                .collect::<Vec<_>>()
                .join("\n");
            let mut all =
                parse_manifest(std::path::Path::new("entries"), text.as_bytes()).or_py()?;
            if let Some((k, n)) = shard {
                all = slabscope::triage::shard(&all, k, n).to_vec();
            }
            Ok(all)
        }
        (Some(paths), None, None) => Ok(py
            .detach(|| {
                none_missing(&paths)?;
                select(Source::Paths(&paths), opts, shard)
            })
            .or_py()?
            .volumes),
        (None, Some(m), None) => Ok(py
            .detach(|| select(Source::Manifest(&m), opts, shard))
            .or_py()?
            .volumes),
        _ => Err(PyValueError::new_err(
            "give one of paths, manifest= or entries=",
        )),
    }
}

/// Every volume under `paths` (folders walked, files, or a list of both), or those of
/// `manifest=` or `entries=`, one row each, as `triage --json` gives them: an iterator of
/// dicts. Keywords as the CLI's: `shard=(K, N)`, `full`, `timeout=60`, the loader's and the
/// analysis' (`series`, `max_memory`, `slabs`, `method`, ...): the library's entries.
#[pyfunction]
#[pyo3(signature = (paths=None, **options))]
pub fn triage(
    py: Python<'_>,
    paths: Option<&Bound<'_, PyAny>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Triage> {
    let kw = Kwargs::new(py, "triage", options)?;
    let (load, pool) = load_options(&kw)?;
    let (params, _) = analysis_params(&kw)?;
    let own = given(&kw, &[&table::FULL, &table::TRIAGE_TIMEOUT])?;
    let how = TriagePlan::given(&own, load, params, false).or_py()?;
    let volumes = entries(py, &kw, paths, &how.load)?;
    kw.finish()?;
    let count = volumes.len();
    let (tx, rx) = sync_channel::<String>(WORKERS);
    std::thread::spawn(move || {
        let describe = |path: &std::path::Path, e: slabscope::Error| {
            controls(&e.in_terms_within(Terms::Keywords, path)).into_owned()
        };
        look_all(
            &volumes,
            &how,
            WORKERS,
            pool.as_ref(),
            &describe,
            |_, looked| {
                slabscope::report::to_json_line(&looked.row).is_ok_and(|row| tx.send(row).is_ok())
            },
        );
    });
    Ok(Triage {
        rows: Mutex::new(rx),
        count,
    })
}

/// The volumes `triage` would take, as the lines `triage --list` prints after its header (names
/// escaped, so that no name is lost): for `entries=` of runs spread over many workers.
#[pyfunction]
#[pyo3(signature = (paths=None, **options))]
pub fn list_volumes(
    py: Python<'_>,
    paths: Option<&Bound<'_, PyAny>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Vec<String>> {
    let kw = Kwargs::new(py, "list_volumes", options)?;
    let (load, _) = load_options(&kw)?;
    let volumes = entries(py, &kw, paths, &load)?;
    kw.finish()?;
    Ok(volumes.iter().map(Entry::line).collect())
}

/// The rows `rows` as a receiver that ends after them.
fn replay(rows: Vec<String>) -> Receiver<String> {
    let (tx, rx) = sync_channel::<String>(rows.len());
    for row in rows {
        // The channel holds every row: no send blocks or fails while `rx` lives.
        let _ = tx.send(row);
    }
    rx
}

/// Unpickles a triage run: the rows not yet taken (JSON lines) of a run of `count` volumes.
#[pyfunction]
pub fn _triage_of(rows: Vec<String>, count: usize) -> Triage {
    Triage {
        rows: Mutex::new(replay(rows)),
        count,
    }
}

impl Triage {
    /// The next row's JSON line, waiting for it with the GIL released; `None` when the run is
    /// over. Ctrl-C raises `KeyboardInterrupt` meanwhile.
    fn next_line(&self, py: Python<'_>) -> PyResult<Option<String>> {
        loop {
            let next = py.detach(|| {
                self.rows
                    .lock()
                    .unwrap_or_else(std::sync::PoisonError::into_inner)
                    .recv_timeout(Duration::from_millis(50))
            });
            match next {
                Ok(row) => return Ok(Some(row)),
                Err(RecvTimeoutError::Timeout) => py.check_signals()?,
                Err(RecvTimeoutError::Disconnected) => return Ok(None),
            }
        }
    }
}

#[pymethods]
impl Triage {
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let mut rows = Vec::new();
        let put_back = |rows: Vec<String>| {
            *self
                .rows
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner) = replay(rows);
        };
        loop {
            match self.next_line(py) {
                Ok(Some(row)) => rows.push(row),
                Ok(None) => break,
                // Interrupted: the rows taken so far stay this run's (the rest are dropped, as
                // by `close()`).
                Err(e) => {
                    put_back(rows);
                    return Err(e);
                }
            }
        }
        put_back(rows.clone());
        let args = (rows, self.count);
        crate::pickle::reduced(py, "_triage_of", args)
    }

    fn __iter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    fn __next__<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.next_line(py)?.map(|row| parse(py, &row)).transpose()
    }

    fn __len__(&self) -> usize {
        self.count
    }

    /// Stops the run after the volumes under way; the rows not yet taken are dropped.
    fn close(&self) {
        let mut rows = self
            .rows
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        let (_, empty) = sync_channel(0);
        *rows = empty;
    }
}
