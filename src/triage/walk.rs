//! The walk: which volumes a set of paths holds.

use std::path::{Path, PathBuf};

use super::{Entry, MAX_DEPTH, MAX_VOLUMES};
use crate::error::{Error, Result};
use crate::volume::io::{Folder, LoadOptions, dicom, folder_kind, volume_name};

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
    super::dedupe(&mut found);
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
