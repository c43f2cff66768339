//! DICOM: a file, or a folder of files, read as a volume. Each file is walked safely first
//! (`read`), its header parsed by dicom-object (its elements' values read by `elements`, the
//! pixel format by `format`) and described per frame (`header`); the frames (a Siemens mosaic's
//! tiles, `mosaic`, from its CSA headers, `csa` and `protocol`) are grouped into series and laid
//! out along the slice normal (`assemble`); native pixels are read straight from the files,
//! compressed ones decoded by dicom-pixeldata, and both turned into values the same way
//! (`pixels`). The scan of files to series is `scan`, the reading of a series' frames into a
//! volume's voxels `voxels`.

mod assemble;
mod codestream;
mod csa;
mod details;
mod elements;
mod format;
mod group;
mod header;
mod mosaic;
mod pixels;
mod protocol;
mod read;
mod scan;
mod voxels;

use std::path::{Path, PathBuf};

use dicom_encoding::TransferSyntaxIndex;
use dicom_object::InMemDicomObject;
use serde::Serialize;

use self::assemble::{Layout, Series};
pub use self::details::DicomReport;
use self::format::PixelFormat;
use self::header::Image;
use self::read::Syntax;
use self::scan::{Scan, paths_of, series_of};
use super::reader::{Reader, Sniff};
use super::{Folder, Format, LoadOptions, Read0, Source};
use crate::error::{Error, Result};
use crate::geometry::WorldTransform;
use crate::volume::{Volume, VoxelType};

/// The most files of one folder scanned.
pub const MAX_FILES: usize = 1 << 18;

/// The options of a DICOM read.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct DicomOptions {
    /// Which series of a folder: its position in the list (from 1) or its UID.
    pub series: Option<String>,
    /// Keep localizer and derived images (left out by default).
    pub include_localizers: bool,
    /// Resample a series with uneven spacing or gantry tilt to an even, orthogonal grid.
    pub resample: bool,
    /// Read the patient-identifying fields (never read otherwise).
    pub show_phi: bool,
}

/// The DICOM reader: a file, or a folder of files (one series, or the one named).
pub(crate) struct Dicom;

impl Reader for Dicom {
    fn format(&self) -> Format {
        Format::Dicom
    }

    fn title(&self) -> &'static str {
        "DICOM"
    }

    /// `DICM` after the preamble (first of all: some DICOM files carry a TIFF header in theirs).
    fn sniff(&self, head: &[u8]) -> Sniff {
        if head.get(128..132) == Some(b"DICM") {
            Sniff::Mine
        } else {
            Sniff::No
        }
    }

    fn probe(&self, source: &Source) -> bool {
        is_dicom_source(source)
    }

    fn series_file(&self, path: &Path) -> bool {
        is_dicom(path)
    }

    fn picks_in_folder(&self, opts: &LoadOptions) -> bool {
        opts.dicom.series.is_some()
    }

    fn reads_folder(&self, kind: Folder, opts: &LoadOptions) -> bool {
        // A series may be named in a folder of DICOM files and other volumes.
        kind == Folder::Series || (kind == Folder::Collection && self.picks_in_folder(opts))
    }

    fn volumes(&self) -> bool {
        true
    }

    fn groups(&self) -> Option<&'static dyn super::reader::Groups> {
        Some(&group::Series)
    }

    fn details_key(&self) -> Option<&'static str> {
        Some("dicom")
    }

    fn in_rows(&self) -> bool {
        true
    }

    /// Reads the file, or the series found among the files of a folder (or below it), each file
    /// read through its own [`Source`]: the folder is walked by its path, a series being many
    /// files, never one source's bytes.
    fn read(&self, source: &Source, opts: &LoadOptions) -> Result<Read0> {
        load(source.path(), opts)
    }
}

/// Whether the file at `path` is DICOM, by its content (`DICM` after the preamble or at the
/// start, or a file meta group), or by a `.dcm` name.
pub fn is_dicom(path: &Path) -> bool {
    is_dicom_source(&Source::new(path))
}

/// Whether the file `source` is DICOM (see [`is_dicom`]).
fn is_dicom_source(source: &Source) -> bool {
    let name = source.name();
    let named = Path::new(&name).extension().is_some_and(|e| {
        ["dcm", "dicom", "ima"]
            .iter()
            .any(|x| e.eq_ignore_ascii_case(x))
    });
    named || source.head(132).is_ok_and(|head| read::sniff(&head))
}

/// What a DICOM volume is, beyond its geometry: never a patient-identifying field unless they
/// were asked for.
#[derive(Clone, Debug, Default, Serialize)]
pub struct DicomSeries {
    /// The series' key: its `SeriesInstanceUID` (with `#2`, ... on the parts of a split series).
    pub key: String,
    /// `SeriesNumber`.
    pub number: Option<i64>,
    /// `SeriesDescription`.
    pub description: String,
    /// Modality.
    pub modality: String,
    /// The transfer syntax, named.
    pub syntax: String,
    /// Patient-identifying fields, read only when asked for (empty otherwise).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub patient: Vec<(String, String)>,
}

/// One series of a DICOM folder, as a list shows it (no patient-identifying field).
#[derive(Clone, Debug, Serialize)]
pub struct SeriesSummary {
    /// The key that picks it: its `SeriesInstanceUID` (with `#2`, ... on the parts of a series
    /// split by orientation, matrix, spacing or echo).
    pub key: String,
    /// How a list names it: `series 3 "Abdomen"`.
    pub label: String,
    /// `SeriesNumber`.
    pub number: Option<i64>,
    /// `SeriesDescription`.
    pub description: String,
    /// Modality.
    pub modality: String,
    /// Images (frames) in it.
    pub images: usize,
    /// Columns, rows and slices (positions), when it lays out as a volume.
    pub dims: Option<[usize; 3]>,
    /// `SeriesInstanceUID` (the key without its `#N`).
    #[serde(skip)]
    pub uid: String,
    /// The files its images are read from, sorted: what [`load_series`] reads it from again.
    #[serde(skip)]
    pub files: Vec<PathBuf>,
}

/// What a scan of DICOM files found: their series, the files that could not be read, and what
/// the scan left out (localizers, derived images, unreadable files) in notes, said once for
/// all the files.
#[derive(Debug)]
pub struct Listing {
    /// The series, as a list shows them (sorted by UID: the order `--series N` counts in).
    pub series: Vec<SeriesSummary>,
    /// Files that could not be read, each with its error.
    pub failed: Failures,
    /// What was left out.
    pub notes: Vec<String>,
}

/// The deepest [`files_under`] goes below the folder it is given.
pub const MAX_DEPTH: usize = 64;

/// The DICOM files directly in folder `dir` (other files ignored), sorted.
pub fn files_in(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    collect(dir, dir, 0, false, &mut files)?;
    files.sort();
    Ok(files)
}

/// The DICOM files in folder `dir` and in every folder below it (symbolic links to folders not
/// followed, at most [`MAX_DEPTH`] deep, at most [`MAX_FILES`] in all), sorted: where a series
/// named by its UID is looked for, since one series may lie in several folders.
pub fn files_under(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    collect(dir, dir, 0, true, &mut files)?;
    files.sort();
    Ok(files)
}

/// Adds the DICOM files of `dir` (below `root`) to `files`, and with `deep` those below it.
fn collect(
    root: &Path,
    dir: &Path,
    depth: usize,
    deep: bool,
    files: &mut Vec<PathBuf>,
) -> Result<()> {
    for entry in std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))? {
        let entry = entry.map_err(|e| Error::io(dir, e))?;
        let Ok(t) = entry.file_type() else { continue };
        if deep && t.is_dir() && depth < MAX_DEPTH {
            collect(root, &entry.path(), depth + 1, deep, files)?;
        } else if t.is_file() && is_dicom(&entry.path()) {
            if files.len() >= MAX_FILES {
                return Err(Error::format(
                    root,
                    format!(
                        "more than {MAX_FILES} DICOM files {}",
                        ["in one folder", "below"][usize::from(deep)]
                    ),
                ));
            }
            files.push(entry.path());
        }
    }
    Ok(())
}

/// Files that could not be read, each with its error.
pub type Failures = Vec<(PathBuf, Error)>;

/// Parses a walked `dataset`, encoded as `syntax` says, with dicom-object.
fn parse(path: &Path, dataset: &[u8], syntax: &Syntax) -> Result<InMemDicomObject> {
    let uid = syntax.dataset_uid();
    let ts = dicom_transfer_syntax_registry::TransferSyntaxRegistry
        .get(uid)
        .ok_or_else(|| Error::unsupported(path, read::syntax_name(uid)))?;
    InMemDicomObject::read_dataset_with_ts(dataset, ts)
        .map_err(|e| Error::format(path, format!("DICOM header: {}", quoted(&e))))
}

/// A dicom-rs error as a message may quote it: on one line, control characters escaped, and
/// short (it must not carry a header's values out, such as a patient's name).
fn quoted(e: &dyn std::fmt::Display) -> String {
    let text = e.to_string();
    let line = text.lines().next().unwrap_or_default();
    let short: String = line.chars().take(120).collect();
    let mut out = crate::error::names::text(&short);
    if line.chars().count() > 120 {
        out.push('…');
    }
    out
}

/// The series in the DICOM file or folder at `path` (the files directly in it), as a list
/// shows them, with what was left out.
pub fn list_series(path: &Path, opts: &LoadOptions) -> Result<Listing> {
    list_files(&paths_of(path, false)?, opts)
}

/// The series the DICOM files `files` hold, as a list shows them, with what was left out:
/// each file's header read once.
pub fn list_files(files: &[PathBuf], opts: &LoadOptions) -> Result<Listing> {
    let (mut scan, series, notes) = series_of(files, opts)?;
    let failed = std::mem::take(&mut scan.skipped);
    let summaries = series
        .iter()
        .map(|s| SeriesSummary {
            key: s.key.clone(),
            label: s.label(),
            number: s.number,
            description: s.description.clone(),
            modality: s.modality.clone(),
            images: s.images.len(),
            dims: assemble::layout(s, &|im| name(&scan, im))
                .ok()
                .map(|l| [l.plane[0], l.plane[1], l.slices]),
            uid: s.uid.clone(),
            files: sources(&scan, s, &(0..s.images.len()).collect::<Vec<_>>()),
        })
        .collect();
    Ok(Listing {
        series: summaries,
        failed,
        notes,
    })
}

/// Loads the series `key` from the DICOM files `files` alone (as a listing gave them), named
/// `path` (its folder) in messages: the same volume as [`crate::load`] of `path` with that
/// series, without reading the other files of the folder. Notes say nothing of the images the
/// scan left out (localizers, derived images, files that could not be read: a listing of the
/// folder says that, once).
pub fn load_series(
    path: &Path,
    files: &[PathBuf],
    key: &str,
    opts: &LoadOptions,
) -> Result<super::Loaded> {
    super::check_input(path)?;
    // The files of one part of a split series group alone as that UID's only part.
    let uid = key.split('#').next().unwrap_or(key);
    let mut opts = opts.clone();
    opts.dicom.series = Some(uid.to_string());
    let read = load_from(path, files, &opts, Some(key)).map_err(|e| e.reached_from(path))?;
    super::finish(path, super::Format::Dicom, read)
}

/// Whether `series` names a series by its position in a folder's list, not by UID.
fn by_position(series: &str) -> bool {
    series.bytes().all(|b| b.is_ascii_digit())
}

fn name(scan: &Scan, im: &Image) -> String {
    let path = &scan.files[im.file].path;
    let file = crate::error::shown(path.file_name().map_or(path.as_path(), Path::new));
    if let Some(tile) = &im.tile {
        let frame = if im.format.frames > 1 {
            format!(" frame {}", im.frame)
        } else {
            String::new()
        };
        format!("{file}{frame} tile {}", tile.index)
    } else if im.format.frames > 1 {
        format!("{file} frame {}", im.frame)
    } else {
        file
    }
}

/// Picks the series `wanted` names (a 1-based position in the list, or a key or UID), or the
/// only one.
fn pick<'s>(path: &Path, series: &'s [Series], wanted: Option<&str>) -> Result<&'s Series> {
    let listing = || {
        series
            .iter()
            .enumerate()
            .map(|(i, s)| format!("{}: {} ({} images)", i + 1, s.label(), s.images.len()))
            .collect::<Vec<_>>()
            .join("; ")
    };
    match wanted {
        None if series.len() == 1 => Ok(&series[0]),
        None => Err(Error::Series {
            path: path.to_path_buf(),
            message: format!("{} series: {}", series.len(), listing()),
            localizers: false,
        }),
        Some(w) => {
            let by_key: Vec<&Series> = series.iter().filter(|s| s.key == w).collect();
            let by_uid: Vec<&Series> = series.iter().filter(|s| s.uid == w).collect();
            if let Some(s) = by_key.first() {
                return Ok(s);
            }
            if let Some(s) = by_uid.first() {
                return Ok(s);
            }
            match w.parse::<usize>() {
                Ok(n) if (1..=series.len()).contains(&n) => Ok(&series[n - 1]),
                _ => Err(Error::Series {
                    path: path.to_path_buf(),
                    message: format!("no series {w:?}; the series are: {}", listing()),
                    localizers: false,
                }),
            }
        }
    }
}

/// Why a scan found no series.
fn no_series(path: &Path, scan: &Scan) -> Error {
    if scan.images_found == 0 && scan.skipped.is_empty() {
        Error::format(
            path,
            "no images: no pixel data (a report, a plan, a waveform, a directory)",
        )
    } else if scan.images_found == 0 {
        Error::format(path, "no readable images")
    } else {
        Error::Series {
            path: path.to_path_buf(),
            message: "no image series: only localizer images, which are left out".into(),
            localizers: true,
        }
    }
}

/// Loads the DICOM file or folder at `path` as a volume: of a folder, the files directly in
/// it, or, for a series named by its UID, every DICOM file below it too (a series may lie in
/// several folders).
fn load(path: &Path, opts: &LoadOptions) -> Result<Read0> {
    let deep = opts
        .dicom
        .series
        .as_deref()
        .is_some_and(|s| !by_position(s));
    load_from(path, &paths_of(path, deep)?, opts, None)
}

/// Loads the series `opts` picks of the DICOM files `files`, named `path` in messages, and
/// called `key` (a part of a split series) where that is given.
fn load_from(
    path: &Path,
    files: &[PathBuf],
    opts: &LoadOptions,
    key: Option<&str>,
) -> Result<Read0> {
    let (scan, series, scan_notes) = series_of(files, opts)?;
    // What the scan left out is the listing's to say when one series is read from its files.
    let mut notes = if key.is_some() {
        Vec::new()
    } else {
        scan_notes
    };
    if series.is_empty() {
        return Err(no_series(path, &scan));
    }
    let series = pick(path, &series, opts.dicom.series.as_deref())?;
    let layout =
        assemble::layout(series, &|im| name(&scan, im)).map_err(|m| Error::format(path, m))?;
    super::data::pick_volume(path, layout.volumes, opts.part.volume, &mut notes)?;
    check_pixels(path, &scan, series, &mut notes)?;
    notes.extend(layout.notes.iter().cloned());
    let resample = opts.dicom.resample && layout.needs_resampling();
    let [cols, rows] = layout.plane;
    let (slices, lps) = if resample {
        layout.resampled()
    } else {
        (layout.slices, layout.lps)
    };
    let dims = [cols, rows, slices];
    opts.room().check(path, dims)?;
    let order = &layout.order[opts.part.volume];
    let (voxels, rounded) = if resample {
        let read = voxels::resampled(path, &scan, series, &layout, order, slices, opts.room())?;
        notes.push(resampled_note(&layout, slices));
        read
    } else {
        voxels::as_they_lie(path, &scan, series, order, dims, opts.room())?
    };
    notes.extend(rounded.note(&samples_name(series)));
    let mut volume = Volume::from_voxels(dims, layout.spacing, VoxelType::F32, voxels)
        .map_err(|e| e.reached_from(path))?;
    let ty = voxel_type(series, &volume.stats());
    volume = volume.with_voxel_type(ty);
    if let Some((m, origin)) = lps {
        let lps = Some(WorldTransform::lps(m, origin));
        volume = super::placement::place(volume, lps, &mut notes);
    }
    if !resample {
        notes.extend(layout.problems.iter().cloned());
    }
    Ok(Read0 {
        volume,
        notes,
        sources: sources(&scan, series, order),
        details: Some(std::sync::Arc::new(described(&scan, series, key))),
        format_version: None,
    })
}

/// How a note names the samples of `series`: their type, `rescaled` when a slice is.
fn samples_name(series: &Series) -> String {
    let first = &series.images[0];
    let rescale = series
        .images
        .iter()
        .map(|im| im.rescale)
        .find(|&r| r != (1.0, 0.0))
        .unwrap_or((1.0, 0.0));
    pixels::Decode::new(&first.format, false, rescale).name()
}

/// What a load says of resampling `layout` to `slices` evenly spaced slices.
fn resampled_note(layout: &Layout, slices: usize) -> String {
    let step = layout.spacing[2];
    let undone = if layout.tilt.is_some() {
        ", the tilt undone"
    } else {
        ""
    };
    format!("resampled to {slices} evenly spaced slices {step:.3} mm apart{undone}")
}

/// The files slices `order` of `series` are read from, each once, sorted.
fn sources(scan: &Scan, series: &Series, order: &[usize]) -> Vec<PathBuf> {
    order
        .iter()
        .map(|&i| scan.files[series.images[i].file].path.clone())
        .collect::<std::collections::BTreeSet<_>>()
        .into_iter()
        .collect()
}

/// What the volume loaded from `series` is, beyond its geometry: the series' fields (its key
/// `key` where that is given), its first file's transfer syntax and (when asked for) the
/// patient's fields.
fn described(scan: &Scan, series: &Series, key: Option<&str>) -> DicomSeries {
    let first = &series.images[0];
    DicomSeries {
        key: key.unwrap_or(&series.key).to_string(),
        number: series.number,
        description: series.description.clone(),
        modality: series.modality.clone(),
        syntax: scan.files[first.file].syntax.name(),
        patient: scan.patient.clone(),
    }
}

/// Fails unless the series' pixels can be read alike; notes how they are turned into values.
fn check_pixels(path: &Path, scan: &Scan, series: &Series, notes: &mut Vec<String>) -> Result<()> {
    let first = &series.images[0];
    let f = &first.format;
    if let Some(problem) = f.problem() {
        return Err(Error::unsupported(path, problem));
    }
    let alike = |g: &PixelFormat| {
        (g.allocated, g.samples, &g.photometric) == (f.allocated, f.samples, &f.photometric)
    };
    if let Some(other) = series.images.iter().find(|im| !alike(&im.format)) {
        return Err(Error::unsupported(
            path,
            format!(
                "the images store their pixels differently ({} and {})",
                name(scan, first),
                name(scan, other)
            ),
        ));
    }
    if f.colour() {
        notes.push(format!(
            "colour images ({}) read as their luminance",
            f.photometric
        ));
    }
    if f.inverted() {
        notes.push("MONOCHROME1: values inverted so that higher is brighter".into());
    }
    if series.images.iter().any(|im| im.rescale != first.rescale) {
        notes.push("the rescale slope and intercept vary by slice: applied per slice".into());
    }
    Ok(())
}

/// The voxel type the values have: the smallest integer type that holds them all (`stats`)
/// when every rescale keeps them integers, else f32.
fn voxel_type(series: &Series, stats: &crate::volume::Stats) -> VoxelType {
    let integral = series.images.iter().all(|im| {
        let (slope, intercept) = im.rescale;
        slope.fract() == 0.0 && intercept.fract() == 0.0 && !im.format.colour()
    });
    let (lo, hi) = (f64::from(stats.min), f64::from(stats.max));
    [
        VoxelType::U8,
        VoxelType::I8,
        VoxelType::U16,
        VoxelType::I16,
        VoxelType::U32,
        VoxelType::I32,
    ]
    .into_iter()
    .find(|t| {
        let (tlo, thi) = t.range();
        integral && tlo <= lo && hi <= thi
    })
    .unwrap_or(VoxelType::F32)
}
