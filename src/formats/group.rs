//! Volumes that several files make together, which one folder may hold several of (a DICOM
//! series; a folder of TIFF slices is one volume, read whole, not such a group): found, listed
//! and read through the reader whose files they are (its `Reader::groups`), so that a walk over
//! folders (triage's) and a manifest's entries know no format. One reader makes such volumes
//! today, DICOM; the registry holds that at most one does (a second would tag the entries its
//! listings give with itself). The keys are the reader's: [`whole`] gives the whole a part's key
//! belongs to.

use std::path::{Path, PathBuf};

use super::reader::Groups;
pub use super::reader::{Listing, Member};
use super::{LoadOptions, Loaded};
use crate::error::{Error, Result};

/// The reader's that makes volumes of several files, when one does.
fn groups() -> Option<&'static dyn Groups> {
    super::registry::groups()
}

/// What one volume of several files is called in messages (`DICOM series`; `volume` when no
/// reader makes such volumes).
pub fn noun() -> &'static str {
    groups().map_or("volume", |g| g.noun())
}

/// Whether the file at `path` is one of the files that make volumes together.
pub fn member(path: &Path) -> bool {
    groups().is_some_and(|g| g.member(path))
}

/// The files directly in folder `dir` that make volumes together, sorted.
pub fn files_in(dir: &Path) -> Result<Vec<PathBuf>> {
    groups().map_or_else(|| Ok(Vec::new()), |g| g.files_in(dir))
}

/// The files in folder `dir` and below it that make volumes together, sorted.
pub fn files_under(dir: &Path) -> Result<Vec<PathBuf>> {
    groups().map_or_else(|| Ok(Vec::new()), |g| g.files_under(dir))
}

/// The volumes the files `files` make together.
pub fn list(files: &[PathBuf], opts: &LoadOptions) -> Result<Listing> {
    groups().map_or_else(|| Ok(Listing::default()), |g| g.list(files, opts))
}

/// The volumes the files directly in folder `dir` make together: an error when it holds none of
/// those files.
pub fn list_in(dir: &Path, opts: &LoadOptions) -> Result<Listing> {
    groups().map_or_else(|| Ok(Listing::default()), |g| g.list_in(dir, opts))
}

/// The volume `key` of the files `files` (as a listing gave them), named `folder` in messages;
/// its notes say nothing of the other files a listing left out.
pub fn read(folder: &Path, files: &[PathBuf], key: &str, opts: &LoadOptions) -> Result<Loaded> {
    match groups() {
        Some(g) => g.read(folder, files, key, opts),
        None => Err(Error::format(
            folder,
            format!("no reader reads the volume {key:?}"),
        )),
    }
}

/// The key of the whole the volume `key` is a part of ([`Member::whole`] for a key alone, as a
/// manifest's line gives it): `key` itself when it is a whole.
pub fn whole(key: &str) -> &str {
    groups().map_or(key, |g| g.whole(key))
}

/// Whether `text` is spelt as the key of a volume of several files (a manifest's line tells a
/// key after a tab from a file name so).
pub fn is_key(text: &str) -> bool {
    groups().is_some_and(|g| g.is_key(text))
}

/// `opts` with the volume `key` of a folder picked.
pub fn pick(opts: &mut LoadOptions, key: &str) {
    if let Some(g) = groups() {
        g.pick(opts, key);
    }
}

/// The volume the options pick among a folder's, as given (`--series`).
pub fn picked(opts: &LoadOptions) -> Option<&str> {
    groups().and_then(|g| g.picked(opts))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The registry's groups are DICOM's series: listed as DICOM lists them, read as `load` reads
    /// the series picked, the scan's notes left to the listing; the keys spelt as DICOM's.
    #[test]
    fn the_groups_are_dicoms_series() {
        let ct = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/dicom/ct");
        let opts = LoadOptions::default();
        let listing = list_in(&ct, &opts).unwrap();
        let dicom = crate::formats::dicom::list_series(&ct, &opts).unwrap();
        let keys = |l: &Listing| -> Vec<(String, String, Vec<PathBuf>)> {
            l.volumes
                .iter()
                .map(|m| (m.key.clone(), m.label.clone(), m.files.clone()))
                .collect()
        };
        let expected: Vec<_> = (dicom.series.iter())
            .map(|s| (s.key.clone(), s.label.clone(), s.files.clone()))
            .collect();
        assert_eq!(keys(&listing), expected);
        assert!(listing.volumes.len() >= 2, "the fixture's series");
        assert_eq!(listing.notes, dicom.notes);
        assert!(!listing.notes.is_empty(), "the localizer left out");
        let first = &listing.volumes[0];
        let mut picked = opts.clone();
        pick(&mut picked, &first.key);
        assert_eq!(super::picked(&picked), Some(first.key.as_str()));
        let read = read(&ct, &first.files, &first.key, &opts).unwrap();
        let loaded = crate::formats::load(&ct, &picked).unwrap();
        assert_eq!(read.volume.dims(), loaded.volume.dims());
        assert_eq!(read.volume.stats().mean, loaded.volume.stats().mean);
        assert!(
            read.notes.iter().all(|n| !listing.notes.contains(n)),
            "{:?}",
            read.notes
        );
        assert_eq!(
            files_in(&ct).unwrap().len(),
            list(&files_in(&ct).unwrap(), &opts)
                .unwrap()
                .volumes
                .iter()
                .map(|m| m.files.len())
                .sum::<usize>()
                + 1
        );
        assert_eq!((whole("1.2.3#2"), whole("1.2.3")), ("1.2.3", "1.2.3"));
        assert!(is_key("1.2.3#2") && !is_key("a.nii") && !is_key(""));
        assert_eq!(noun(), "DICOM series");
        assert!(member(&first.files[0]) && !member(&ct));
    }
}
