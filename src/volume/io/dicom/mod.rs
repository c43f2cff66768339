//! DICOM: a file, or a folder of files, read as a volume. Each file is walked safely first
//! (`read`), its header parsed by dicom-object and described per frame (`header`); the
//! frames are grouped into series and laid out along the slice normal (`assemble`); native
//! pixels are read straight from the files, compressed ones decoded by dicom-pixeldata, and
//! both turned into values the same way (`pixels`).

mod assemble;
mod header;
mod pixels;
mod read;

use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use dicom_core::value::PixelFragmentSequence;
use dicom_core::{DataElement, VR};
use dicom_dictionary_std::tags;
use dicom_encoding::TransferSyntaxIndex;
use dicom_object::InMemDicomObject;
use dicom_object::meta::FileMetaTableBuilder;
use dicom_pixeldata::PixelDecoder;
use rayon::prelude::*;
use serde::Serialize;

use self::assemble::Series;
use self::header::{Image, PixelFormat};
use self::pixels::Decode;
use self::read::{Pixels, Syntax};
use super::data::{check_budget, voxel_buffer};
use super::{LoadOptions, Read0};
use crate::error::{Error, Result};
use crate::geometry::WorldTransform;
use crate::volume::{Volume, VoxelType};

/// Bytes charged per image (frame) described while scanning.
const IMAGE_COST: u64 = 512;

/// The most files of one folder scanned.
pub const MAX_FILES: usize = 1 << 18;

/// Whether the file at `path` is DICOM, by its content (`DICM` after the preamble or at the
/// start, or a file meta group), or by a `.dcm` name.
pub fn is_dicom(path: &Path) -> bool {
    let named = path.extension().is_some_and(|e| {
        ["dcm", "dicom", "ima"]
            .iter()
            .any(|x| e.eq_ignore_ascii_case(x))
    });
    if named {
        return true;
    }
    let mut head = Vec::with_capacity(132);
    File::open(path)
        .and_then(|f| f.take(132).read_to_end(&mut head))
        .is_ok_and(|_| read::sniff(&head))
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
}

/// The DICOM files directly in folder `dir` (other files ignored), sorted.
pub fn files_in(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))? {
        let entry = entry.map_err(|e| Error::io(dir, e))?;
        if entry.file_type().is_ok_and(|t| t.is_file()) && is_dicom(&entry.path()) {
            if files.len() >= MAX_FILES {
                return Err(Error::format(
                    dir,
                    format!("more than {MAX_FILES} DICOM files in one folder"),
                ));
            }
            files.push(entry.path());
        }
    }
    files.sort();
    Ok(files)
}

/// A file's part of a scan: what is needed to read its pixels again.
struct Scanned {
    path: PathBuf,
    syntax: Syntax,
    pixels: Pixels,
}

/// What a scan of some files found.
struct Scan {
    files: Vec<Scanned>,
    images: Vec<Image>,
    /// Files that could not be read, with why.
    skipped: Failures,
    /// Images found, before any is left out.
    images_found: usize,
    /// The first file's patient fields, when asked for.
    patient: Vec<(String, String)>,
}

/// A file scanned: what reads its pixels, its images, and its patient fields (when asked for).
type Described = (Scanned, Vec<Image>, Vec<(String, String)>);

/// Files that could not be read, each with its error.
pub type Failures = Vec<(PathBuf, Error)>;

/// Walks and parses the header of each of `paths` (in parallel), stopping at the pixel data.
fn scan(paths: &[PathBuf], opts: &LoadOptions) -> Result<Scan> {
    let budget = opts.max_memory;
    // The images' descriptions, charged as each file is described, before it is.
    let spent = std::sync::atomic::AtomicU64::new(0);
    let results: Vec<Result<Described>> = paths
        .par_iter()
        .map(|path| {
            let part = read::read(path, budget, false)?;
            let obj = parse(path, &part.dataset, &part.syntax)?;
            // A file without pixels (a DICOMDIR, a report, a presentation state) has no image.
            let images = if matches!(part.pixels, Pixels::None) {
                Vec::new()
            } else {
                let format = header::pixel_format(&obj);
                check_frames(path, &format, &part.pixels)?;
                let cost = u64::from(format.frames).saturating_mul(IMAGE_COST);
                let total = spent.fetch_add(cost, std::sync::atomic::Ordering::Relaxed);
                if total.saturating_add(cost) > budget {
                    return Err(Error::TooLarge {
                        path: path.clone(),
                        what: format!("the descriptions of {} frames", format.frames),
                        needed: total.saturating_add(cost),
                        limit: budget,
                    });
                }
                header::images(&obj)
            };
            let patient = if opts.show_phi {
                header::patient(&obj)
            } else {
                Vec::new()
            };
            let scanned = Scanned {
                path: path.clone(),
                syntax: part.syntax,
                pixels: part.pixels,
            };
            Ok((scanned, images, patient))
        })
        .collect();
    let mut out = Scan {
        files: Vec::new(),
        images: Vec::new(),
        skipped: Vec::new(),
        images_found: 0,
        patient: Vec::new(),
    };
    for (r, path) in results.into_iter().zip(paths) {
        match r {
            Ok((scanned, images, patient)) => {
                out.images_found += images.len();
                if out.patient.is_empty() {
                    out.patient = patient;
                }
                // Images refer to files by their index among the files kept.
                let index = out.files.len();
                out.images.extend(images.into_iter().map(|mut im| {
                    im.file = index;
                    im
                }));
                out.files.push(scanned);
            }
            // One file alone failing is the error, and so is the budget running out; in a
            // folder a file that cannot be read is left out and said.
            Err(e) if paths.len() == 1 || matches!(e, Error::TooLarge { .. }) => return Err(e),
            Err(e) => out.skipped.push((path.clone(), e)),
        }
    }
    Ok(out)
}

/// Checks the frames a header claims against the pixel data there is (native) or could be
/// (each compressed frame is at least one 8-byte fragment header).
fn check_frames(path: &Path, format: &PixelFormat, pixels: &Pixels) -> Result<()> {
    let frames = u64::from(format.frames);
    let bytes = frames.saturating_mul(format.frame_bytes());
    match pixels {
        Pixels::Native { len, .. } if bytes > *len => {
            return Err(Error::Truncated {
                path: path.to_path_buf(),
                expected: bytes,
                found: *len,
            });
        }
        Pixels::Encapsulated => {
            let size = std::fs::metadata(path)
                .map_err(|e| Error::io(path, e))?
                .len();
            if frames.saturating_mul(8) > size {
                return Err(Error::format(
                    path,
                    format!("{frames} frames claimed by a file of {size} bytes"),
                ));
            }
        }
        _ => {}
    }
    Ok(())
}

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
    let mut out: String = line
        .chars()
        .take(120)
        .flat_map(char::escape_default)
        .collect();
    if line.chars().count() > 120 {
        out.push('…');
    }
    out
}

/// The series the files in `paths` hold, sorted by series number then UID; localizers and
/// derived images are left out unless `opts` includes them.
fn series_of(paths: &[PathBuf], opts: &LoadOptions) -> Result<(Scan, Vec<Series>, Vec<String>)> {
    let mut scan = scan(paths, opts)?;
    let images = std::mem::take(&mut scan.images);
    let (series, left) = assemble::group(images, opts.include_localizers);
    let mut notes = Vec::new();
    let counted = |n: usize, what: &str| match n {
        0 => None,
        1 => Some(format!("1 {what} image")),
        n => Some(format!("{n} {what} images")),
    };
    let left: Vec<String> = [
        counted(left.localizers, "localizer"),
        counted(left.derived, "derived"),
    ]
    .into_iter()
    .flatten()
    .collect();
    if !left.is_empty() {
        notes.push(format!("left out {}", left.join(" and ")));
    }
    if let Some((first, _)) = scan.skipped.first() {
        let name = first.file_name().unwrap_or_default().to_string_lossy();
        notes.push(match scan.skipped.len() {
            1 => format!("left out {name}, which could not be read"),
            n => format!("left out {n} files that could not be read ({name} and others)"),
        });
    }
    Ok((scan, series, notes))
}

/// The files a path names: the file, or the DICOM files of the folder.
fn paths_of(path: &Path) -> Result<Vec<PathBuf>> {
    if path.is_dir() {
        let files = files_in(path)?;
        if files.is_empty() {
            return Err(Error::format(path, "folder holds no DICOM files"));
        }
        Ok(files)
    } else {
        Ok(vec![path.to_path_buf()])
    }
}

/// The series in the DICOM file or folder at `path`, as a list shows them, and the files that
/// could not be read, each with its error.
pub fn list_series(path: &Path, opts: &LoadOptions) -> Result<(Vec<SeriesSummary>, Failures)> {
    let files = paths_of(path)?;
    let (mut scan, series, _) = series_of(&files, opts)?;
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
        })
        .collect();
    Ok((summaries, failed))
}

fn name(scan: &Scan, im: &Image) -> String {
    let path = &scan.files[im.file].path;
    let file = path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into(),
    );
    if im.format.frames > 1 {
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

/// Loads the DICOM file or folder at `path` as a volume.
pub(super) fn load(path: &Path, opts: &LoadOptions) -> Result<Read0> {
    let files = paths_of(path)?;
    let (scan, series, mut notes) = series_of(&files, opts)?;
    if series.is_empty() {
        return Err(no_series(path, &scan));
    }
    let series = pick(path, &series, opts.series.as_deref())?;
    let layout =
        assemble::layout(series, &|im| name(&scan, im)).map_err(|m| Error::format(path, m))?;
    super::data::pick_volume(path, layout.volumes, opts.volume, &mut notes)?;
    let first = &series.images[0];
    check_pixels(path, &scan, series, &mut notes)?;
    notes.extend(layout.notes.iter().cloned());
    let resample = opts.resample && layout.needs_resampling();
    let [cols, rows] = layout.plane;
    let (slices, lps) = if resample {
        layout.resampled()
    } else {
        (layout.slices, layout.lps)
    };
    let dims = [cols, rows, slices];
    check_budget(path, dims, opts.max_memory)?;
    let order = &layout.order[opts.volume];
    let voxels = if resample {
        // The source slices and the resampled volume are held at once.
        check_budget(path, [cols, rows, layout.slices + slices], opts.max_memory)?;
        let planes = read_slices(&scan, series, order, layout.plane, opts.max_memory)?;
        let mut out = voxel_buffer(path, dims, opts.max_memory)?;
        let step = layout.spacing[2];
        out.par_chunks_mut(cols * rows)
            .enumerate()
            .for_each(|(k, plane)| {
                let depth = k as f64 * step;
                pixels::resample_slice(
                    &planes,
                    &layout.depths,
                    &layout.shifts,
                    layout.plane,
                    depth,
                    plane,
                );
            });
        let undone = if layout.tilt.is_some() {
            ", the tilt undone"
        } else {
            ""
        };
        notes.push(format!(
            "resampled to {slices} evenly spaced slices {step:.3} mm apart{undone}"
        ));
        out
    } else {
        let mut out = voxel_buffer(path, dims, opts.max_memory)?;
        let planes: Vec<&mut [f32]> = out.chunks_mut(cols * rows).collect();
        fill(&scan, series, order, planes, opts.max_memory)?;
        out
    };
    let mut volume = Volume::new(dims, layout.spacing, VoxelType::F32, voxels)
        .map_err(|e| e.reached_from(path))?;
    let ty = voxel_type(series, &volume.stats());
    volume = volume.with_voxel_type(ty);
    if let Some((m, origin)) = lps {
        volume = volume.with_transform(WorldTransform::lps(m, origin));
    }
    if !resample {
        notes.extend(layout.problems.iter().cloned());
    }
    let sources = order
        .iter()
        .map(|&i| scan.files[series.images[i].file].path.clone())
        .collect::<std::collections::BTreeSet<_>>()
        .into_iter()
        .collect();
    Ok(Read0 {
        volume,
        notes,
        sources,
        dicom: Some(super::DicomSeries {
            key: series.key.clone(),
            number: series.number,
            description: series.description.clone(),
            modality: series.modality.clone(),
            syntax: scan.files[first.file].syntax.name(),
            patient: scan.patient.clone(),
        }),
    })
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

/// Reads the slices `order` names into planes of their own (for resampling).
fn read_slices(
    scan: &Scan,
    series: &Series,
    order: &[usize],
    plane: [usize; 2],
    budget: u64,
) -> Result<Vec<Vec<f32>>> {
    let mut planes: Vec<Vec<f32>> = vec![vec![0.0; plane[0] * plane[1]]; order.len()];
    let refs: Vec<&mut [f32]> = planes.iter_mut().map(Vec::as_mut_slice).collect();
    fill(scan, series, order, refs, budget)?;
    Ok(planes)
}

/// Decodes slice `k` of `order` into `planes[k]`, file by file in parallel.
fn fill(
    scan: &Scan,
    series: &Series,
    order: &[usize],
    planes: Vec<&mut [f32]>,
    budget: u64,
) -> Result<()> {
    let mut by_file: std::collections::BTreeMap<usize, Vec<(&Image, &mut [f32])>> =
        std::collections::BTreeMap::new();
    for (&i, plane) in order.iter().zip(planes) {
        let im = &series.images[i];
        by_file.entry(im.file).or_default().push((im, plane));
    }
    by_file
        .into_iter()
        .collect::<Vec<_>>()
        .into_par_iter()
        .try_for_each(|(file, frames)| read_frames(&scan.files[file], frames, budget))
}

/// Decodes `frames` of one file.
fn read_frames(file: &Scanned, frames: Vec<(&Image, &mut [f32])>, budget: u64) -> Result<()> {
    let path = file.path.as_path();
    let big = file.syntax.big;
    match &file.pixels {
        Pixels::None => Err(Error::format(path, "no pixel data")),
        Pixels::Native { offset, len } => {
            let mut f = File::open(path).map_err(|e| Error::io(path, e))?;
            let size = f.metadata().map_err(|e| Error::io(path, e))?.len();
            let mut buf = Vec::new();
            for (im, plane) in frames {
                let bytes = im.format.frame_bytes();
                let start = u64::from(im.frame) * bytes;
                let available = (*len).min(size.saturating_sub(*offset));
                if start + bytes > available {
                    return Err(Error::Truncated {
                        path: path.to_path_buf(),
                        expected: start + bytes,
                        found: available,
                    });
                }
                buf.resize(bytes as usize, 0);
                f.seek(SeekFrom::Start(offset + start))
                    .and_then(|_| f.read_exact(&mut buf))
                    .map_err(|e| Error::io(path, e))?;
                Decode::new(&im.format, big, im.rescale).frame(&buf, plane);
            }
            Ok(())
        }
        Pixels::Deflated | Pixels::Inflated(_) | Pixels::Encapsulated | Pixels::Fragments(..) => {
            let part = read::read(path, budget, true)?;
            match part.pixels {
                Pixels::Inflated(data) => {
                    for (im, plane) in frames {
                        let bytes = im.format.frame_bytes();
                        let start = u64::from(im.frame) * bytes;
                        let src = data
                            .get(start as usize..(start + bytes) as usize)
                            .ok_or_else(|| Error::Truncated {
                                path: path.to_path_buf(),
                                expected: start + bytes,
                                found: data.len() as u64,
                            })?;
                        Decode::new(&im.format, false, im.rescale).frame(src, plane);
                    }
                    Ok(())
                }
                Pixels::Fragments(table, fragments) => {
                    decode_fragments(path, &part.dataset, &file.syntax, table, fragments, frames)
                }
                _ => Err(Error::format(path, "no pixel data")),
            }
        }
    }
}

/// Decodes `frames` of encapsulated pixel data through dicom-pixeldata.
fn decode_fragments(
    path: &Path,
    dataset: &[u8],
    syntax: &Syntax,
    table: Vec<u32>,
    fragments: Vec<Vec<u8>>,
    frames: Vec<(&Image, &mut [f32])>,
) -> Result<()> {
    let format = &frames[0].0.format;
    check_jpeg(path, syntax, format, &fragments)?;
    let mut obj = parse(path, dataset, syntax)?;
    obj.put(DataElement::new(
        tags::PIXEL_DATA,
        VR::OB,
        PixelFragmentSequence::new(table, fragments),
    ));
    let meta = FileMetaTableBuilder::new()
        .transfer_syntax(syntax.uid.as_str())
        .media_storage_sop_class_uid("1.2.840.10008.5.1.4.1.1.7")
        .media_storage_sop_instance_uid("2.25.0");
    let obj = obj
        .with_meta(meta)
        .map_err(|e| Error::format(path, format!("DICOM header: {}", quoted(&e))))?;
    for (im, plane) in frames {
        let decoded = obj.decode_pixel_data_frame(im.frame).map_err(|e| {
            Error::format(
                path,
                format!(
                    "{} pixel data: {}",
                    read::syntax_name(&syntax.uid),
                    quoted(&e)
                ),
            )
        })?;
        let src = decoded.frame_data(0).map_err(|e| {
            Error::format(path, format!("decoded frame {}: {}", im.frame, quoted(&e)))
        })?;
        // The decoders give interleaved RGB for colour.
        let mut f = im.format.clone();
        f.planar = false;
        if f.colour() {
            f.photometric = "RGB".into();
        }
        Decode::new(&f, false, im.rescale).frame(src, plane);
    }
    Ok(())
}

/// Checks the frame size and precision each JPEG fragment states before a decoder sizes its
/// buffers by them: larger than the image, or 12-bit extended JPEG, is an error.
fn check_jpeg(
    path: &Path,
    syntax: &Syntax,
    format: &PixelFormat,
    fragments: &[Vec<u8>],
) -> Result<()> {
    if !syntax.uid.starts_with("1.2.840.10008.1.2.4.") {
        return Ok(());
    }
    for fragment in fragments {
        let Some((precision, height, width)) = jpeg_frame(fragment) else {
            continue;
        };
        if syntax.uid == "1.2.840.10008.1.2.4.51" && precision > 8 {
            return Err(Error::unsupported(
                path,
                format!(
                    "transfer syntax {}: {precision}-bit extended JPEG, which the pure-Rust JPEG \
                     decoder does not read",
                    read::syntax_name(&syntax.uid)
                ),
            ));
        }
        if height > format.rows || width > format.cols || precision > 16 {
            return Err(Error::format(
                path,
                format!(
                    "a JPEG fragment of {width}x{height} pixels at {precision} bits in an image \
                     of {}x{}",
                    format.cols, format.rows
                ),
            ));
        }
    }
    Ok(())
}

/// The precision, height and width a JPEG stream's start-of-frame marker states.
fn jpeg_frame(data: &[u8]) -> Option<(u8, u16, u16)> {
    let mut i = 2;
    if !data.starts_with(&[0xFF, 0xD8]) {
        return None;
    }
    while i + 4 <= data.len() {
        if data[i] != 0xFF {
            return None;
        }
        let marker = data[i + 1];
        let len = usize::from(u16::from_be_bytes([data[i + 2], data[i + 3]]));
        if (0xC0..=0xCF).contains(&marker) && !matches!(marker, 0xC4 | 0xC8 | 0xCC) {
            let f = data.get(i + 4..i + 9)?;
            return Some((
                f[0],
                u16::from_be_bytes([f[1], f[2]]),
                u16::from_be_bytes([f[3], f[4]]),
            ));
        }
        i += 2 + len;
    }
    None
}
