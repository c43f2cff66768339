//! The volumes a triage run takes: from a manifest or a walk, sorted, one entry per file, a
//! series restricted to where asked, then its shard. Shared by every front end (CLI, Python,
//! a cluster's workers) so that the same arguments select the same volumes everywhere.

use std::io::Read;
use std::path::{Path, PathBuf};

use super::{Entry, dedupe, discover, parse_manifest, resolve, restrict_to_series, shard};
use crate::error::{Error, Result, names, shown};
use crate::formats::LoadOptions;

/// The longest manifest read, bytes.
pub const MAX_MANIFEST: u64 = 256 << 20;

/// Where the volumes come from.
#[derive(Clone, Copy, Debug)]
pub enum Source<'a> {
    /// Folders (walked) and files.
    Paths(&'a [PathBuf]),
    /// A manifest: as `manifest_lines` writes it, or one path a line.
    Manifest(&'a Path),
}

/// The volumes selected, and what a user should know about the selection.
#[derive(Clone, Debug, Default)]
pub struct Selection {
    /// The volumes, in the order rows are given.
    pub volumes: Vec<Entry>,
    /// How many volumes there were before the shard was taken.
    pub total: usize,
    /// A note: an empty shard of some volumes.
    pub note: Option<String>,
}

/// The volumes of `source` (a series of each folder only, with `opts.series`), then block `k`
/// of `n` of them (see [`shard`]) with `shard_of = Some((k, n))`, a manifest's DICOM series
/// given their files ([`resolve`]). No volume at all is an error
/// naming the source; an empty shard of some is said in [`Selection::note`].
pub fn select(
    source: Source<'_>,
    opts: &LoadOptions,
    shard_of: Option<(u64, u64)>,
) -> Result<Selection> {
    let mut all = match source {
        Source::Manifest(m) => read_manifest(m)?,
        Source::Paths(paths) => discover(paths, opts)?,
    };
    dedupe(&mut all);
    let series = crate::formats::group::picked(opts);
    if let Some(wanted) = series {
        all = restrict_to_series(all, wanted, opts);
    }
    if all.is_empty() {
        let what = series.map_or_else(
            || "volumes".to_string(),
            |w| format!("{} {}", crate::formats::group::noun(), names::text(w)),
        );
        return Err(match source {
            Source::Manifest(m) => Error::format(m, format!("no {what} found in the manifest")),
            Source::Paths(paths) => {
                let paths: Vec<String> = paths.iter().map(|p| shown(p)).collect();
                Error::NotFound(format!("no {what} found under {}", paths.join(", ")))
            }
        });
    }
    let total = all.len();
    let Some((k, n)) = shard_of else {
        resolve(&mut all, opts);
        return Ok(Selection {
            volumes: all,
            total,
            note: None,
        });
    };
    let mut volumes = shard(&all, k, n).to_vec();
    resolve(&mut volumes, opts);
    let note = volumes
        .is_empty()
        .then(|| format!("shard {k}/{n} of {total} volumes is empty (more shards than volumes)"));
    Ok(Selection {
        volumes,
        total,
        note,
    })
}

/// Reads a manifest (as `manifest_lines` writes it, or one path a line, for a DICOM series a tab
/// and its UID): see [`parse_manifest`]. At most [`MAX_MANIFEST`] bytes.
pub fn read_manifest(path: &Path) -> Result<Vec<Entry>> {
    crate::formats::check_input(path)?;
    let file = crate::formats::open_regular(path).map_err(|e| Error::io(path, e))?;
    let len = file.metadata().map_err(|e| Error::io(path, e))?.len();
    if len > MAX_MANIFEST {
        return Err(Error::format(
            path,
            format!("a manifest of {len} bytes; at most {MAX_MANIFEST} are read"),
        ));
    }
    let mut text = Vec::new();
    file.take(MAX_MANIFEST)
        .read_to_end(&mut text)
        .map_err(|e| Error::io(path, e))?;
    parse_manifest(path, &text)
}
