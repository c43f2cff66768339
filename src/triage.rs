//! Many volumes at once: what a set of paths holds (folders walked; a folder of TIFF slices is
//! one volume), in a stable order that shards split, and one row per volume with what a first
//! look needs: the format and geometry, the problems, the most structured axis and the slabs
//! along it.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, PoisonError, RwLock};
use std::time::Duration;

use serde::Serialize;

use crate::analysis::{Analysis, AnalysisParams, analyze, within_memory};
use crate::error::{Error, Result};
use crate::progress::{Monitor, Progress};
use crate::report::SCHEMA_VERSION;
use crate::volume::io::{DicomSeries, Loaded, dicom, volume_name};
pub use crate::volume::io::{Folder, folder_kind};
use crate::volume::io::{LoadOptions, load};

/// The most volumes a walk collects: a bound on the memory a folder tree can claim.
pub const MAX_VOLUMES: usize = 1 << 20;

/// The deepest a walk goes below a folder it was given.
pub const MAX_DEPTH: usize = 64;

/// One volume triage looks at: a file or a folder, and for DICOM the series in it.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Entry {
    /// The file, or the folder.
    pub path: PathBuf,
    /// The DICOM series' key (its `SeriesInstanceUID`) in a folder of DICOM files.
    pub series: Option<String>,
    /// How a list names the series: number and description (not in manifests).
    pub label: Option<String>,
}

impl Entry {
    /// The entry of a file or folder that is one volume.
    pub fn file(path: impl Into<PathBuf>) -> Self {
        Self {
            path: path.into(),
            series: None,
            label: None,
        }
    }

    /// The entry as a manifest line: the path, and a tab and the series key for DICOM.
    pub fn line(&self) -> String {
        match &self.series {
            Some(key) => format!("{}\t{key}", self.path.display()),
            None => self.path.display().to_string(),
        }
    }

    /// The entry a manifest line names (as [`Entry::line`] writes it).
    pub fn parse(line: &str) -> Self {
        match line.rsplit_once('\t') {
            Some((path, key)) if is_series_key(key) => Self {
                path: path.into(),
                series: Some(key.to_string()),
                label: None,
            },
            _ => Self::file(line),
        }
    }

    /// The entry's name in messages and lists: the path, with the series after it.
    pub fn name(&self) -> String {
        self.name_under(Path::new(""))
    }

    /// [`Entry::name`] with the path relative to the folder `root`.
    pub fn name_under(&self, root: &Path) -> String {
        let path = crate::error::shown(self.path.strip_prefix(root).unwrap_or(&self.path));
        let series = match (&self.label, &self.series) {
            (Some(label), _) => format!("[{label}]"),
            (None, Some(key)) => format!("[series {key}]"),
            (None, None) => return path,
        };
        if path.is_empty() {
            series
        } else {
            format!("{path} {series}")
        }
    }
}

/// Whether `text` is a series key: a UID (digits and dots), maybe with `#N` after it.
fn is_series_key(text: &str) -> bool {
    !text.is_empty()
        && text
            .chars()
            .all(|c| c.is_ascii_digit() || c == '.' || c == '#')
}

/// The volumes under `paths`, sorted and without repeats: each file named, each folder of
/// slices, each series of a folder of DICOM files, and, walked recursively, every volume in the
/// other folders (symbolic links to folders are not followed, so that no walk loops). A path
/// that cannot be read is kept: its row will say why. `opts` says which DICOM images count.
pub fn discover(paths: &[PathBuf], opts: &LoadOptions) -> Result<Vec<Entry>> {
    let mut found = Vec::new();
    for path in paths {
        let meta = std::fs::metadata(path);
        match meta {
            Ok(m) if m.is_dir() => walk(path, 0, opts, &mut found)?,
            _ => push(&mut found, Entry::file(path.clone()))?,
        }
    }
    found.sort();
    found.dedup();
    Ok(found)
}

fn push(found: &mut Vec<Entry>, entry: Entry) -> Result<()> {
    if found.len() >= MAX_VOLUMES {
        return Err(Error::format(
            &entry.path,
            format!("more than {MAX_VOLUMES} volumes: name fewer folders, or shard a manifest"),
        ));
    }
    found.push(entry);
    Ok(())
}

/// The series of the DICOM files in `dir`, one entry each, and each file that cannot be read
/// (its row will say why); the folder alone when it cannot be scanned or holds no series.
fn push_series(dir: &Path, opts: &LoadOptions, found: &mut Vec<Entry>) -> Result<()> {
    match dicom::list_series(dir, opts) {
        Ok((series, failed)) if !series.is_empty() => {
            for (file, _) in failed {
                push(found, Entry::file(file))?;
            }
            for s in series {
                push(
                    found,
                    Entry {
                        path: dir.to_path_buf(),
                        label: Some(s.label.clone()),
                        series: Some(s.key),
                    },
                )?;
            }
            Ok(())
        }
        _ => push(found, Entry::file(dir)),
    }
}

fn walk(dir: &Path, depth: usize, opts: &LoadOptions, found: &mut Vec<Entry>) -> Result<()> {
    // The folder is read twice, to classify it and to walk it, rather than held: a folder of
    // millions of entries stays out of memory.
    match folder_kind(dir)? {
        Folder::Slices => return push(found, Entry::file(dir)),
        Folder::Dicom => return push_series(dir, opts, found),
        Folder::Collection | Folder::Empty => {}
    }
    if depth >= MAX_DEPTH {
        return Err(Error::format(
            dir,
            format!("folders nest deeper than {MAX_DEPTH}"),
        ));
    }
    let mut dicom_files = false;
    for entry in std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))? {
        let entry = entry.map_err(|e| Error::io(dir, e))?;
        let path = entry.path();
        let Ok(t) = entry.file_type() else { continue };
        if t.is_dir() {
            walk(&path, depth + 1, opts, found)?;
        } else if volume_name(&path) {
            push(found, Entry::file(path))?;
        } else if !dicom_files && t.is_file() && dicom::is_dicom(&path) {
            dicom_files = true;
        }
    }
    if dicom_files {
        push_series(dir, opts, found)?;
    }
    Ok(())
}

/// Block `k` (from 1) of `n` contiguous blocks of `items`: the volumes one machine of `n` takes,
/// so that the blocks of `k = 1..=n` are the whole list, each item in exactly one.
pub fn shard<T>(items: &[T], k: usize, n: usize) -> &[T] {
    if n == 0 || k == 0 || k > n {
        return &[];
    }
    let len = items.len();
    &items[(k - 1) * len / n..k * len / n]
}

/// One volume's row: what it is, what is wrong with it, and its most structured axis and slabs.
/// Rows carry no timings, so that the rows of shards concatenate to those of one run.
#[derive(Clone, Debug, Serialize)]
pub struct TriageRow {
    /// [`SCHEMA_VERSION`].
    pub schema_version: u32,
    /// The file or folder as found, escaped by the one rule of [`crate::error::names`].
    pub path: String,
    /// The DICOM series' key (its `SeriesInstanceUID`) in a folder of DICOM files.
    pub series: Option<String>,
    /// What the DICOM series is (number, description, modality, transfer syntax; patient
    /// fields only when they were asked for).
    pub dicom: Option<DicomSeries>,
    /// The format read (null when loading failed).
    pub format: Option<String>,
    /// `[nx, ny, nz]`.
    pub dims: Option<[usize; 3]>,
    /// `[sx, sy, sz]`, mm.
    pub spacing: Option<[f64; 3]>,
    /// Orientation codes (`RAS`, `LPS`, ...), null when the file states none.
    pub orientation: Option<String>,
    /// The voxel type in the file.
    #[serde(rename = "type")]
    pub voxel_type: Option<String>,
    /// Smallest and largest finite voxel.
    pub range: Option<[f32; 2]>,
    /// Voxels that were NaN or infinite.
    pub missing: Option<usize>,
    /// What the loader and the analysis noticed (a 4D file, a coarsened lattice, ...).
    pub problems: Vec<String>,
    /// Why the volume could not be looked at, on one line; null when it could.
    pub error: Option<String>,
    /// The most structured axis (null when no view search ran or it failed).
    pub best_axis: Option<[f64; 3]>,
    /// Its anatomical name, when the orientation names it.
    pub anatomy: Option<String>,
    /// Its entropy rate, bits (the mean over lattice phases where the ranking used it).
    pub entropy_rate: Option<f64>,
    /// Whether another axis is a contender (null on the paper's single lattice).
    pub uncertain: Option<bool>,
    /// The axis partitioned along.
    pub axis: Option<[f64; 3]>,
    /// The slabs along it, `[start, end)` slice indices.
    pub slabs: Option<Vec<[usize; 2]>>,
}

impl TriageRow {
    /// The row of a volume that could not be looked at.
    pub fn failed(path: &str, error: String) -> Self {
        Self {
            schema_version: SCHEMA_VERSION,
            path: path.to_string(),
            series: None,
            dicom: None,
            format: None,
            dims: None,
            spacing: None,
            orientation: None,
            voxel_type: None,
            range: None,
            missing: None,
            problems: Vec::new(),
            error: Some(error),
            best_axis: None,
            anatomy: None,
            entropy_rate: None,
            uncertain: None,
            axis: None,
            slabs: None,
        }
    }

    /// The row of `loaded`, found at `path`, without its analysis (yet).
    pub fn loaded(path: &str, loaded: &Loaded) -> Self {
        let v = &loaded.volume;
        let s = v.stats();
        Self {
            format: Some(loaded.format.name().to_string()),
            dims: Some(v.dims()),
            spacing: Some(v.spacing()),
            orientation: v.transform().axcodes(),
            voxel_type: Some(v.voxel_type().to_string()),
            range: (s.finite > 0).then_some([s.min, s.max]),
            missing: Some(s.missing),
            problems: loaded.notes.clone(),
            dicom: loaded.dicom.clone(),
            error: None,
            ..Self::failed(path, String::new())
        }
    }

    /// The volume's name: its path, with the DICOM series after it.
    pub fn name(&self) -> String {
        let series = match (&self.dicom, &self.series) {
            (Some(d), _) => match (d.number, d.description.is_empty()) {
                (Some(n), false) => format!(" [series {n} \"{}\"]", d.description),
                (Some(n), true) => format!(" [series {n}]"),
                (None, _) => format!(" [series {}]", d.key),
            },
            (None, Some(key)) => format!(" [series {key}]"),
            (None, None) => String::new(),
        };
        format!("{}{series}", self.path)
    }

    /// Adds what the analysis found.
    #[must_use]
    pub fn analysed(mut self, analysis: &Analysis) -> Self {
        if let Some(views) = &analysis.views {
            let best = views.best();
            self.best_axis = Some(best.axis);
            self.anatomy.clone_from(&best.world.anatomy);
            self.entropy_rate = Some(crate::view::score(best));
            self.uncertain = views.uncertain;
        }
        let p = &analysis.partition;
        if self.anatomy.is_none() {
            self.anatomy.clone_from(&p.world.anatomy);
        }
        self.axis = Some(p.axis);
        self.slabs = Some(p.slabs.iter().map(|&(a, b)| [a, b]).collect());
        self.problems.extend(analysis.notes.iter().cloned());
        self
    }

    /// The best axis in few characters: its anatomical plane (`I→S`), else `x`, `y` or `z`, else
    /// its components; none without a view search.
    pub fn axis_name(&self) -> Option<String> {
        if let Some(name) = &self.anatomy {
            return name.split(',').next().map(str::to_string);
        }
        let a = self.best_axis?;
        Some(match crate::geometry::coordinate_axis(a) {
            Some(m) => ["x", "y", "z"][m].to_string(),
            None => format!("[{:.2},{:.2},{:.2}]", a[0] + 0.0, a[1] + 0.0, a[2] + 0.0),
        })
    }

    /// The row with `error` (the analysis failed after the volume loaded).
    #[must_use]
    pub fn with_error(mut self, error: String) -> Self {
        self.error = Some(error);
        self
    }
}

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
    let opts = LoadOptions {
        series: entry.series.clone().or_else(|| how.load.series.clone()),
        ..how.load.clone()
    };
    let name = crate::error::shown(&entry.path);
    let loaded = match load(&entry.path, &opts) {
        Ok(l) => l,
        Err(e) => {
            let mut row = TriageRow::failed(&name, describe(e));
            row.series.clone_from(&entry.series);
            return failed(row);
        }
    };
    let mut row = TriageRow::loaded(&name, &loaded);
    row.series.clone_from(&entry.series);
    // A watchdog raises the cancel flag at the timeout, unless told first that the work is done.
    let cancel = Arc::new(AtomicBool::new(false));
    let (done, finished) = std::sync::mpsc::channel::<()>();
    let watchdog = {
        let cancel = Arc::clone(&cancel);
        std::thread::spawn(move || {
            if finished.recv_timeout(timeout).is_err() {
                cancel.store(true, Ordering::Relaxed);
            }
        })
    };
    let report = |p: Progress| progress(p.fraction);
    let monitor = Monitor::new(Some(&cancel), Some(&report));
    // Beyond its share of the budget, a volume is analysed on a pyramid level.
    let (level, budget_note) = match within_memory(&loaded.volume, 0, opts.max_memory) {
        Ok(fit) => fit,
        Err(e) => return failed(row.with_error(describe(e))),
    };
    let v = level.as_ref();
    let mut params = how.params.clone();
    let sampling = &mut params.view.sampling;
    let unset = sampling.ray_spacing.is_none() && sampling.sample_spacing.is_none();
    if how.fast && unset && v.dims().iter().all(|&n| n >= COARSE_MIN_DIM) {
        let coarse = COARSE * crate::geometry::min_spacing(v.spacing());
        (sampling.ray_spacing, sampling.sample_spacing) = (Some(coarse), Some(coarse));
        params.view.phases = params.view.phases.min(COARSE_PHASES);
    }
    let result = analyze(v, &params, &monitor).and_then(|mut analysis| {
        analysis.notes.splice(0..0, budget_note);
        let cell = match how.tile {
            Some(tile) => Some(crate::render::sheet::cell(
                v,
                &analysis.partition,
                tile,
                &monitor,
            )?),
            None => None,
        };
        Ok((analysis, cell))
    });
    let _ = done.send(());
    let _ = watchdog.join();
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

/// Looks at every one of `volumes` as `how` says, `workers` at a time, and hands the results to
/// `emit` in order, as they complete. The volumes looked at together share the memory budget:
/// each loads within its share, and one that needs more is looked at again alone, with the
/// whole budget. `describe` words an error of a volume.
pub fn look_all(
    volumes: &[Entry],
    how: &TriagePlan,
    workers: usize,
    describe: &(dyn Fn(&Path, Error) -> String + Sync),
    mut emit: impl FnMut(usize, TriageOutcome),
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
            });
        }
        drop(tx);
        let mut waiting = std::collections::BTreeMap::new();
        let mut due = 0;
        for (i, looked) in rx {
            waiting.insert(i, looked);
            while let Some(looked) = waiting.remove(&due) {
                emit(due, looked);
                due += 1;
            }
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axes_are_named_in_few_characters() {
        let mut row = TriageRow::failed("a", String::new());
        assert_eq!(row.axis_name(), None);
        row.best_axis = Some([-0.0, 1.0, 0.0]);
        assert_eq!(row.axis_name().as_deref(), Some("y"));
        row.best_axis = Some([0.6, -0.0, 0.8]);
        assert_eq!(row.axis_name().as_deref(), Some("[0.60,0.00,0.80]"));
        row.anatomy = Some("I→S, axial".into());
        assert_eq!(row.axis_name().as_deref(), Some("I→S"));
    }

    #[test]
    fn shards_split_a_list_into_contiguous_blocks_that_cover_it_once() {
        let items: Vec<usize> = (0..10).collect();
        for n in 1..=12 {
            let joined: Vec<usize> = (1..=n).flat_map(|k| shard(&items, k, n).to_vec()).collect();
            assert_eq!(joined, items, "{n} shards");
        }
        assert!(shard(&items, 0, 3).is_empty() && shard(&items, 4, 3).is_empty());
    }
}
