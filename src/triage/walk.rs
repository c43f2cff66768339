//! The walk: which volumes a set of paths holds.

use std::path::{Path, PathBuf};

use super::{Entry, MAX_DEPTH, MAX_VOLUMES};
use crate::error::{Error, Result};
use crate::formats::{Folder, LoadOptions, folder_kind, group, volume_name};

/// The volumes under `paths`, sorted and without repeats: each file named, each folder of
/// slices, each DICOM series, and, walked recursively, every volume in the other folders
/// (symbolic links to folders are not followed, so that no walk loops). A DICOM series is
/// assembled from its files in every folder of the tree walked (each path given is a tree): a
/// series in one folder is named by that folder, one in several folders by the deepest folder
/// holding them all. A path that cannot be read is kept: its row will say why. `opts` says
/// which DICOM images count.
pub fn discover(paths: &[PathBuf], opts: &LoadOptions) -> Result<Vec<Entry>> {
    let mut found = Vec::new();
    for path in paths {
        let meta = std::fs::metadata(path);
        match meta {
            Ok(m) if m.is_dir() => {
                let start = found.len();
                walk(path, 0, opts, &mut found)?;
                super::series::join_spanning(&mut found, start, opts);
            }
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

/// The volumes the files in `dir` make together (DICOM series), one entry each, and each file
/// that cannot be read (its row will say why); the folder alone when it holds no file at all
/// that reads as one of those, or with its problem when it cannot be scanned.
fn push_series(dir: &Path, opts: &LoadOptions, found: &mut Vec<Entry>) -> Result<()> {
    match group::list_in(dir, opts) {
        Ok(listing) if !(listing.volumes.is_empty() && listing.failed.is_empty()) => {
            for (file, _) in listing.failed {
                push(found, Entry::file(file))?;
            }
            let mut notes = listing.notes;
            for (i, s) in listing.volumes.into_iter().enumerate() {
                push(
                    found,
                    Entry {
                        label: Some(s.label),
                        series: Some(s.key),
                        position: Some(i + 1),
                        files: s.files.into(),
                        notes: std::mem::take(&mut notes),
                        ..Entry::file(dir)
                    },
                )?;
            }
            Ok(())
        }
        Ok(_) => push(found, Entry::file(dir)),
        Err(e) => {
            // No volume at all: each file that looks like one of its files is a row of its own, which says
            // what is wrong with it; the folder is the row when it cannot even be listed.
            let files: Vec<PathBuf> = match std::fs::read_dir(dir) {
                Ok(entries) => entries
                    .filter_map(Result::ok)
                    .filter(|e| e.file_type().is_ok_and(|t| t.is_file()))
                    .map(|e| e.path())
                    .filter(|p| !volume_name(p) && group::member(p))
                    .collect(),
                Err(_) => Vec::new(),
            };
            if files.is_empty() {
                return push(found, Entry::failed(dir, problem(&e)));
            }
            files
                .into_iter()
                .try_for_each(|file| push(found, Entry::file(file)))
        }
    }
}

/// What keeps the walk out of a folder, without the folder's name (the row names it).
fn problem(e: &Error) -> String {
    match e {
        Error::Io { error, .. } => format!("cannot read this folder: {error}"),
        other => other.to_string(),
    }
}

/// Walks `dir`: every volume in it and below. A folder it cannot read or nested past the limit
/// is a row of its own, and the walk goes on with the rest.
fn walk(dir: &Path, depth: usize, opts: &LoadOptions, found: &mut Vec<Entry>) -> Result<()> {
    // The folder is read twice, to classify it and to walk it, rather than held: a folder of
    // millions of entries stays out of memory.
    match folder_kind(dir) {
        Ok(Folder::Slices | Folder::Store) => return push(found, Entry::file(dir)),
        Ok(Folder::Series) => return push_series(dir, opts, found),
        Ok(Folder::Collection | Folder::Empty) => {}
        Err(e) => return push(found, Entry::failed(dir, problem(&e))),
    }
    if depth >= MAX_DEPTH {
        return push(
            found,
            Entry::failed(
                dir,
                format!("folders nest deeper than {MAX_DEPTH}: not walked below it"),
            ),
        );
    }
    let entries = match std::fs::read_dir(dir) {
        Ok(entries) => entries,
        Err(e) => return push(found, Entry::failed(dir, problem(&Error::io(dir, e)))),
    };
    let mut grouped = false;
    for entry in entries {
        let entry = match entry {
            Ok(entry) => entry,
            Err(e) => {
                push(found, Entry::failed(dir, problem(&Error::io(dir, e))))?;
                break;
            }
        };
        let path = entry.path();
        let Ok(t) = entry.file_type() else { continue };
        if t.is_dir() {
            walk(&path, depth + 1, opts, found)?;
        } else if volume_name(&path) {
            push(found, Entry::file(path))?;
        } else if !grouped && t.is_file() && group::member(&path) {
            grouped = true;
        }
    }
    if grouped {
        push_series(dir, opts, found)?;
    }
    Ok(())
}

/// For each of `entries`, its position (from 1) in its folder's list of DICOM series, the
/// order `--series N` counts in (`info` and `analyze` alike): as the walk found it, else (an
/// entry of a manifest) from the folder's list; `None` for other volumes.
pub fn series_positions(entries: &[Entry], opts: &LoadOptions) -> Vec<Option<usize>> {
    let mut listed = std::collections::HashMap::<&Path, Vec<String>>::new();
    entries
        .iter()
        .map(|e| {
            let key = e.series.as_deref()?;
            if e.position.is_some() {
                return e.position;
            }
            let keys = listed.entry(&e.path).or_insert_with(|| {
                group::list_in(&e.path, opts)
                    .map(|l| l.volumes.into_iter().map(|s| s.key).collect())
                    .unwrap_or_default()
            });
            keys.iter().position(|k| k == key).map(|i| i + 1)
        })
        .collect()
}

/// The entries of `entries` that are the DICOM series `wanted` names in their folder, as
/// `--series` names one for `info` and `analyze`: its key, its `SeriesInstanceUID`, or its
/// position in the folder's list ([`series_positions`]). Other volumes are left out.
pub fn restrict_to_series(entries: Vec<Entry>, wanted: &str, opts: &LoadOptions) -> Vec<Entry> {
    let position = wanted.parse::<usize>().ok();
    let positions = if position.is_some() {
        series_positions(&entries, opts)
    } else {
        vec![None; entries.len()]
    };
    let (kept, left): (Vec<_>, Vec<_>) = entries.into_iter().zip(positions).partition(|(e, at)| {
        e.series.as_deref().is_some_and(|key| {
            let uid = group::whole(key);
            key == wanted || uid == wanted || (position.is_some() && *at == position)
        })
    });
    let mut kept: Vec<Entry> = kept.into_iter().map(|(e, _)| e).collect();
    // What a folder left out is said on the first of its series kept.
    for (e, _) in left.into_iter().filter(|(e, _)| !e.notes.is_empty()) {
        if let Some(first) = kept.iter_mut().find(|k| k.path == e.path) {
            first.notes.splice(0..0, e.notes);
        }
    }
    kept
}
