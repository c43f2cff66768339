//! DICOM series over a whole tree: the parts of one series the walk found in several folders
//! joined into one entry, and a manifest's series given back the files they are read from.

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::Entry;
use crate::error::Result;
use crate::formats::{LoadOptions, group};

/// The key of the whole series a part's key belongs to (its `SeriesInstanceUID`).
fn uid(key: &str) -> &str {
    group::whole(key)
}

/// Joins the DICOM series of `found[start..]` (one tree's walk) whose `SeriesInstanceUID`
/// appears in several folders: their files are listed again together (the series split anew
/// by orientation, matrix, spacing and echo over all of them), each part an entry named by the
/// deepest folder holding all its folders, as dcm2niix assembles series over the tree it is
/// given. What a folder left out stays said once: on its first series, or, when that one is
/// joined, on the joined series (its first part), as [`resolve`] finds it again.
pub(super) fn join_spanning(found: &mut Vec<Entry>, start: usize, opts: &LoadOptions) {
    let mut folders: BTreeMap<String, BTreeSet<PathBuf>> = BTreeMap::new();
    for e in &found[start..] {
        if let (Some(key), false) = (&e.series, e.files.is_empty()) {
            let set = folders.entry(uid(key).to_string()).or_default();
            set.insert(e.path.clone());
        }
    }
    folders.retain(|_, set| set.len() > 1);
    if folders.is_empty() {
        return;
    }
    let spans = |e: &Entry| {
        !e.files.is_empty()
            && e.series
                .as_deref()
                .is_some_and(|k| folders.contains_key(uid(k)))
    };
    let (mut parts, kept): (Vec<Entry>, Vec<Entry>) = found.drain(start..).partition(spans);
    parts.sort();
    found.extend(kept);
    for (uid_, set) in &folders {
        let mut files = Vec::new();
        let mut notes = Vec::new();
        for part in parts
            .iter()
            .filter(|p| p.series.as_deref().map(uid) == Some(uid_))
        {
            files.extend(part.files.iter().cloned());
            notes.extend(part.notes.iter().cloned());
        }
        files.sort();
        files.dedup();
        let folder = common_ancestor(set);
        found.extend(listed(&folder, &files, notes, Some(uid_), opts));
    }
}

/// The entries of the series (all of them, or only those of `only`'s UID) that DICOM files
/// `files` hold, named by `folder`, the first carrying `notes`; or the folder's error.
fn listed(
    folder: &Path,
    files: &[PathBuf],
    mut notes: Vec<String>,
    only: Option<&str>,
    opts: &LoadOptions,
) -> Vec<Entry> {
    match group::list(files, opts) {
        Ok(listing) => listing
            .volumes
            .into_iter()
            .filter(|s| only.is_none_or(|u| s.whole == u))
            .map(|s| Entry {
                label: Some(s.label),
                series: Some(s.key),
                files: s.files.into(),
                notes: std::mem::take(&mut notes),
                ..Entry::file(folder)
            })
            .collect(),
        Err(e) => vec![Entry::failed(folder, e.to_string())],
    }
}

/// The deepest folder holding every one of `folders`.
fn common_ancestor(folders: &BTreeSet<PathBuf>) -> PathBuf {
    let mut iter = folders.iter();
    let mut common = iter.next().cloned().unwrap_or_default();
    for f in iter {
        while !f.starts_with(&common) {
            if !common.pop() {
                return PathBuf::new();
            }
        }
    }
    common
}

/// Gives each DICOM series of `entries` that does not know its files (a manifest's) the files
/// of that series among the DICOM files in its folder and below (as the walk joins a series
/// over folders), each folder scanned once. What a folder left out goes where the walk put it
/// ([`Entry::notes`]): on its first series, or on the series that joined it. A series found
/// nowhere keeps no files: loading it then says why.
pub fn resolve(entries: &mut [Entry], opts: &LoadOptions) {
    let mut folders: HashMap<PathBuf, Folder> = HashMap::new();
    for e in entries.iter_mut() {
        let Some(key) = &e.series else { continue };
        if !e.files.is_empty() || e.problem.is_some() {
            continue;
        }
        let at = Folder::cached(&mut folders, &e.path, opts);
        let Some(files) = at.below.files.get(key).cloned() else {
            continue;
        };
        if at.direct.files.get(key) == Some(&files) {
            // A series of the folder's own files.
            if at.direct.first.as_deref() == Some(key) {
                e.notes.clone_from(&at.direct.notes);
            }
        } else if uid(key) == key {
            // A joined series' first part: the folders whose first series it joined.
            let holding: BTreeSet<PathBuf> = (at.below.files.iter())
                .filter(|(k, _)| uid(k) == key)
                .flat_map(|(_, files)| files.iter().filter_map(|f| f.parent()))
                .map(Path::to_path_buf)
                .collect();
            for folder in holding {
                let listed = &Folder::cached(&mut folders, &folder, opts).direct;
                if listed.first.as_deref().map(uid) == Some(key.as_str()) {
                    e.notes.extend(listed.notes.iter().cloned());
                }
            }
        }
        e.files = files;
    }
}

/// A folder's DICOM series: of the files directly in it, and of those below it too.
struct Folder {
    direct: Listed,
    below: Listed,
}

impl Folder {
    /// The folder `path`'s listings, scanned the first time asked for.
    fn cached<'a>(
        folders: &'a mut HashMap<PathBuf, Folder>,
        path: &Path,
        opts: &LoadOptions,
    ) -> &'a Folder {
        folders.entry(path.to_path_buf()).or_insert_with(|| {
            let (direct, below) = (group::files_in(path), group::files_under(path));
            let same = matches!((&direct, &below), (Ok(a), Ok(b)) if a == b);
            let direct = Listed::of(direct, opts);
            let below = if same {
                direct.clone()
            } else {
                Listed::of(below, opts)
            };
            Folder { direct, below }
        })
    }
}

/// A scan's series by key, its first series' key and what it left out.
#[derive(Clone, Default)]
struct Listed {
    files: HashMap<String, Arc<[PathBuf]>>,
    first: Option<String>,
    notes: Vec<String>,
}

impl Listed {
    /// The listing of `files` (nothing when they or it cannot be read: loading says why).
    fn of(files: Result<Vec<PathBuf>>, opts: &LoadOptions) -> Self {
        let Ok(listing) = files.and_then(|files| group::list(&files, opts)) else {
            return Self::default();
        };
        Self {
            first: listing.volumes.first().map(|s| s.key.clone()),
            files: listing
                .volumes
                .into_iter()
                .map(|s| (s.key, s.files.into()))
                .collect(),
            notes: listing.notes,
        }
    }
}
