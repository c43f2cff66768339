//! The scan of a DICOM file or folder: each file walked and its header parsed (in parallel)
//! up to the pixel data, its frames described, what cannot be read left out and said, and the
//! images grouped into series.

use std::path::{Path, PathBuf};

use rayon::prelude::*;

use super::assemble::{self, Series};
use super::format::{self, PixelFormat};
use super::header::{self, Image};
use super::mosaic;
use super::read::{self, Pixels, Syntax};
use super::{Failures, LoadOptions, files_in, files_under, parse};
use crate::error::{Error, Result};

/// Bytes charged per image (frame) described while scanning.
const IMAGE_COST: u64 = 512;

/// A file's part of a scan: what is needed to read its pixels again.
pub(super) struct Scanned {
    /// The file.
    pub path: PathBuf,
    /// Its transfer syntax.
    pub syntax: Syntax,
    /// Where its pixel data is.
    pub pixels: Pixels,
}

/// What a scan of some files found.
pub(super) struct Scan {
    /// The files read, in the order of the paths.
    pub files: Vec<Scanned>,
    /// Their images (frames), each naming its file by its index in `files`.
    pub images: Vec<Image>,
    /// Files that could not be read, with why.
    pub skipped: Failures,
    /// Images found, before any is left out.
    pub images_found: usize,
    /// The first file's patient fields, when asked for.
    pub patient: Vec<(String, String)>,
    /// The load's cancellation, looked at before each file is read (scanned, then decoded).
    pub cancel: crate::progress::Cancel,
}

/// A file scanned: what reads its pixels, its images, and its patient fields (when asked for).
type Described = (Scanned, Vec<Image>, Vec<(String, String)>);

/// Walks and parses the header of each of `paths` (in parallel), stopping at the pixel data.
fn scan(paths: &[PathBuf], opts: &LoadOptions) -> Result<Scan> {
    let budget = opts.max_memory;
    // The images' descriptions, charged as each file is described, before it is.
    let spent = std::sync::atomic::AtomicU64::new(0);
    let results: Vec<Result<Described>> = paths
        .par_iter()
        .map(|path| {
            opts.cancel.check()?;
            let part = read::read(path, budget, false)?;
            let obj = parse(path, &part.dataset, &part.syntax)?;
            // A file without pixels (a DICOMDIR, a report, a presentation state) has no image.
            let images = if matches!(part.pixels, Pixels::None) {
                Vec::new()
            } else {
                let format = format::pixel_format(&obj);
                check_frames(path, &format, &part.pixels)?;
                let mosaic = mosaic::of(&obj, &format).map_err(|m| Error::format(path, m))?;
                let tiles = mosaic.as_ref().map_or(1, |m| m.tiles);
                let images = u64::from(format.frames).saturating_mul(u64::from(tiles));
                let cost = images.saturating_mul(IMAGE_COST);
                let total = spent.fetch_add(cost, std::sync::atomic::Ordering::Relaxed);
                if total.saturating_add(cost) > budget {
                    return Err(Error::TooLarge {
                        path: path.clone(),
                        what: format!("the descriptions of {images} images"),
                        needed: total.saturating_add(cost),
                        limit: budget,
                        machine: false,
                        disk: false,
                    });
                }
                header::images(&obj, mosaic.as_ref())
            };
            let patient = if opts.dicom.show_phi {
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
        cancel: opts.cancel.clone(),
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
            // One file alone failing is the error, and so is the budget running out or the load
            // cancelled; in a folder a file that cannot be read is left out and said.
            Err(e)
                if paths.len() == 1 || matches!(e, Error::TooLarge { .. } | Error::Cancelled) =>
            {
                return Err(e);
            }
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

/// The series the files in `paths` hold, sorted by series number then UID; localizers and
/// derived images are left out unless `opts` includes them.
pub(super) fn series_of(
    paths: &[PathBuf],
    opts: &LoadOptions,
) -> Result<(Scan, Vec<Series>, Vec<String>)> {
    let mut scan = scan(paths, opts)?;
    let images = std::mem::take(&mut scan.images);
    let (series, left) = assemble::group(images, opts.dicom.include_localizers);
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
        let name = crate::error::shown(Path::new(first.file_name().unwrap_or_default()));
        notes.push(match scan.skipped.len() {
            1 => format!("left out {name}, which could not be read"),
            n => format!("left out {n} files that could not be read ({name} and others)"),
        });
    }
    Ok((scan, series, notes))
}

/// The files a path names: the file, or the DICOM files of the folder (with `deep`, of its
/// whole tree).
pub(super) fn paths_of(path: &Path, deep: bool) -> Result<Vec<PathBuf>> {
    if path.is_dir() {
        let files = if deep {
            files_under(path)?
        } else {
            files_in(path)?
        };
        if files.is_empty() {
            return Err(Error::format(path, "folder holds no DICOM files"));
        }
        Ok(files)
    } else {
        Ok(vec![path.to_path_buf()])
    }
}
