//! Looking at volumes: each loaded and analysed within its timeout and share of the budget.

use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, PoisonError, RwLock};
use std::time::Duration;

use super::{Entry, TriageRow};
use crate::analysis::AnalysisParams;
use crate::budget::Budget;
use crate::error::Error;
use crate::formats::{LoadOptions, group, load};
use crate::params::{Given, table};
use crate::progress::{Cancel, Monitor, Progress};
use crate::request::{Analysed, AnalysisRequest, Level};
use crate::volume::Volume;

/// The coarse lattice of the fast path: rays and samples this many smallest voxel spacings
/// apart, an eighth of the samples.
pub const COARSE: f64 = 2.0;

/// The fast path applies to volumes at least this many voxels along every axis.
pub const COARSE_MIN_DIM: usize = 32;

/// The most lattice phases the fast path ranks by.
pub const COARSE_PHASES: usize = 4;

/// How triage looks at each volume.
#[derive(Clone, Debug)]
pub struct TriagePlan {
    /// How to read files.
    pub load: LoadOptions,
    /// How to analyse them.
    pub params: AnalysisParams,
    /// The most time an analysis may take.
    pub timeout: Duration,
    /// The fast path: the view search on a lattice [`COARSE`] times coarser than the voxels,
    /// ranked over at most [`COARSE_PHASES`] phases (where the parameters name no spacing and
    /// the volume has [`COARSE_MIN_DIM`] voxels a side); the partition at full resolution.
    pub fast: bool,
    /// Draw each volume's contact-sheet cell, with tiles of this many pixels.
    pub tile: Option<u32>,
}

impl TriagePlan {
    /// The plan of the values `given` (the entries `timeout`, `full` and `tile`): volumes read
    /// with `load` and analysed with `params`, and with `sheet` each drawn as a sheet's cell.
    pub fn given(
        given: &Given,
        load: LoadOptions,
        params: AnalysisParams,
        sheet: bool,
    ) -> crate::error::Result<Self> {
        Ok(Self {
            load,
            params,
            timeout: Duration::from_secs_f64(given.number(&table::TRIAGE_TIMEOUT)?),
            fast: !given.switch(&table::FULL)?,
            tile: if sheet {
                Some(given.number(&table::TILE)?)
            } else {
                None
            },
        })
    }
}

/// What triage gives of one volume: its row, and its contact-sheet cell when asked for and the
/// volume could be drawn.
pub struct TriageOutcome {
    /// The row.
    pub row: TriageRow,
    /// The cell.
    pub cell: Option<tiny_skia::Pixmap>,
}

/// One volume's row: loaded and analysed as `how` says (stopped at its timeout, the progress
/// reported as a fraction), or the error of either as `describe` words it; and its cell.
pub fn look(
    entry: &Entry,
    how: &TriagePlan,
    progress: &(dyn Fn(f64) + Sync),
    describe: &dyn Fn(Error) -> String,
) -> TriageOutcome {
    let failed = |row: TriageRow| TriageOutcome { row, cell: None };
    let timeout = how.timeout;
    let name = crate::error::shown(&entry.path);
    if let Some(problem) = &entry.problem {
        let e = Error::format(&entry.path, problem.clone());
        return failed(TriageRow::failed(&name, describe(e)));
    }
    // The load and the analysis share the time.
    let watchdog = Watchdog::start(timeout);
    let cancel = &watchdog.flag;
    let opts = LoadOptions {
        cancel: Cancel::new(Arc::clone(cancel)),
        ..entry.options(&how.load)
    };
    let loaded = match load_entry(entry, &opts) {
        Ok(l) => l,
        Err(e) => {
            let words = match e {
                Error::Cancelled => format!(
                    "loading took longer than the {} s timeout",
                    timeout.as_secs_f64()
                ),
                e => describe(e),
            };
            let mut row = TriageRow::failed(&name, words);
            row.series.clone_from(&entry.series);
            return failed(row);
        }
    };
    let mut row = TriageRow::loaded(&name, &loaded);
    row.series.clone_from(&entry.series);
    let report = |p: Progress| progress(p.fraction);
    let monitor = Monitor::new(Some(cancel.as_ref()), Some(&report));
    let result = analysed(&loaded.volume, how, opts.max_memory, &monitor).and_then(|analysed| {
        let cell = match how.tile {
            Some(tile) => Some(crate::render::sheet::cell(
                analysed.level(),
                &analysed.analysis.partition,
                tile,
                &monitor,
            )?),
            None => None,
        };
        Ok((analysed.analysis, cell))
    });
    watchdog.stop();
    match result {
        Ok((analysis, cell)) => TriageOutcome {
            row: row.analysed(&analysis),
            cell,
        },
        Err(Error::Cancelled) => failed(row.with_error(format!(
            "the analysis took longer than the {} s timeout",
            timeout.as_secs_f64()
        ))),
        Err(e) => failed(row.with_error(describe(e))),
    }
}

/// The analysis of `volume` as `how` says, by the library's request: beyond its share of the
/// budget (`max_memory`) on the pyramid level a picture is drawn from ([`Level::Picture`]), with
/// the fast path's coarse lattice where it applies to that level.
fn analysed(
    volume: &Volume,
    how: &TriagePlan,
    max_memory: u64,
    monitor: &Monitor,
) -> crate::error::Result<Analysed> {
    let mut request = AnalysisRequest {
        params: how.params.clone(),
        level: Level::Picture,
        budget: Budget::new(max_memory),
        given: None,
    };
    if how.fast {
        // The level is made once, when first planned: the plan again is a lookup.
        let level = Arc::clone(&request.plan(volume)?.plan.partition);
        fast_path(&mut request.params, &level);
    }
    request.plan(volume)?.run(monitor)
}

/// The fast path's parameters for `level`: where they name no spacing and it has
/// [`COARSE_MIN_DIM`] voxels a side, the view search on a lattice [`COARSE`] times coarser than
/// its voxels, ranked over at most [`COARSE_PHASES`] phases.
fn fast_path(params: &mut AnalysisParams, level: &Volume) {
    let sampling = &mut params.view.sampling;
    let unset = sampling.ray_spacing.is_none() && sampling.sample_spacing.is_none();
    if unset && level.dims().iter().all(|&n| n >= COARSE_MIN_DIM) {
        let coarse = COARSE * crate::geometry::min_spacing(level.spacing());
        (sampling.ray_spacing, sampling.sample_spacing) = (Some(coarse), Some(coarse));
        params.view.phases = params.view.phases.min(COARSE_PHASES);
    }
}

/// Raises its flag at a timeout, unless stopped first (when the work is done).
struct Watchdog {
    flag: Arc<AtomicBool>,
    done: std::sync::mpsc::Sender<()>,
    thread: std::thread::JoinHandle<()>,
}

impl Watchdog {
    fn start(timeout: Duration) -> Self {
        let flag = Arc::new(AtomicBool::new(false));
        let (done, finished) = std::sync::mpsc::channel::<()>();
        let raised = Arc::clone(&flag);
        let thread = std::thread::spawn(move || {
            if finished.recv_timeout(timeout).is_err() {
                raised.store(true, Ordering::Relaxed);
            }
        });
        Self { flag, done, thread }
    }

    fn stop(self) {
        let _ = self.done.send(());
        let _ = self.thread.join();
    }
}

/// Loads `entry`: a volume of several files (a DICOM series) whose files the walk (or a
/// manifest's resolution) found is read from them alone, with what its folder left out said as
/// the entry says it (once for the folder).
fn load_entry(entry: &Entry, opts: &LoadOptions) -> crate::error::Result<crate::formats::Loaded> {
    match &entry.series {
        Some(key) if !entry.files.is_empty() => group::read(&entry.path, &entry.files, key, opts)
            .map(|mut l| {
                l.notes.splice(0..0, entry.notes.iter().cloned());
                l
            }),
        _ => load(&entry.path, opts),
    }
}

/// Looks at every one of `volumes` as `how` says, `workers` at a time, and hands the results to
/// `emit` in order, as they complete, until `emit` returns false (the looks under way then
/// finish, and no other starts). The volumes looked at together share the memory budget:
/// each loads within its share, and one that needs more is looked at again alone, with the
/// whole budget. `describe` words an error of a volume. With a `pool`, each worker's work runs
/// in it (a caller's thread count); else in rayon's global pool.
pub fn look_all(
    volumes: &[Entry],
    how: &TriagePlan,
    workers: usize,
    pool: Option<&rayon::ThreadPool>,
    describe: &(dyn Fn(&Path, Error) -> String + Sync),
    mut emit: impl FnMut(usize, TriageOutcome) -> bool,
) {
    let workers = workers.min(volumes.len()).max(1);
    let next = AtomicUsize::new(0);
    // Read: looking within a share of the budget; write: alone, with all of it.
    let gate = RwLock::new(());
    let shared = TriagePlan {
        load: LoadOptions {
            max_memory: how.load.max_memory / workers as u64,
            ..how.load.clone()
        },
        ..how.clone()
    };
    let (tx, rx) = std::sync::mpsc::channel::<(usize, TriageOutcome)>();
    std::thread::scope(|scope| {
        for _ in 0..workers {
            let (tx, next, gate, shared) = (tx.clone(), &next, &gate, &shared);
            scope.spawn(move || {
                let work = || {
                    loop {
                        let i = next.fetch_add(1, Ordering::Relaxed);
                        let Some(entry) = volumes.get(i) else { break };
                        let path = entry.path.as_path();
                        let too_large = std::cell::Cell::new(false);
                        let words = |e: Error| {
                            too_large.set(too_large.get() || matches!(e, Error::TooLarge { .. }));
                            describe(path, e)
                        };
                        let reading = gate.read().unwrap_or_else(PoisonError::into_inner);
                        let mut looked = look(entry, shared, &|_| {}, &words);
                        drop(reading);
                        if too_large.get() && workers > 1 {
                            let _alone = gate.write().unwrap_or_else(PoisonError::into_inner);
                            looked = look(entry, how, &|_| {}, &|e| describe(path, e));
                        }
                        if tx.send((i, looked)).is_err() {
                            break;
                        }
                    }
                };
                match pool {
                    Some(p) => p.install(work),
                    None => work(),
                }
            });
        }
        drop(tx);
        let mut waiting = std::collections::BTreeMap::new();
        let mut due = 0;
        'rows: for (i, looked) in rx {
            waiting.insert(i, looked);
            while let Some(looked) = waiting.remove(&due) {
                if !emit(due, looked) {
                    next.store(volumes.len(), Ordering::Relaxed);
                    break 'rows;
                }
                due += 1;
            }
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_plan_takes_the_entries_given_or_their_defaults() {
        let load = LoadOptions::default;
        let params = AnalysisParams::default;
        let plan = TriagePlan::given(&Given::new(), load(), params(), false).unwrap();
        assert_eq!(
            (plan.timeout, plan.fast, plan.tile),
            (Duration::from_secs(60), true, None)
        );
        let plan = TriagePlan::given(&Given::new(), load(), params(), true).unwrap();
        assert_eq!(plan.tile, Some(160));
        let given = Given::new()
            .with(&table::TRIAGE_TIMEOUT, "2.5")
            .with(&table::FULL, "true")
            .with(&table::TILE, "64");
        let plan = TriagePlan::given(&given, load(), params(), true).unwrap();
        assert_eq!(
            (plan.timeout, plan.fast, plan.tile),
            (Duration::from_millis(2500), false, Some(64))
        );
        let e = TriagePlan::given(
            &Given::new().with(&table::TRIAGE_TIMEOUT, "0.05"),
            load(),
            params(),
            false,
        )
        .unwrap_err();
        assert_eq!(
            e.to_string(),
            "timeout 0.05: expected a number from 0.1 to 86400"
        );
        let e = TriagePlan::given(
            &Given::new().with(&table::TILE, "31"),
            load(),
            params(),
            true,
        )
        .unwrap_err();
        assert_eq!(e.to_string(), "tile 31: expected 32 to 1024");
    }
}
