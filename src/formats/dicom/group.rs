//! DICOM series as the volumes of several files a folder holds ([`Groups`]): what triage's walk
//! and a manifest's entries list and read without knowing the format.

use std::path::{Path, PathBuf};

use super::super::reader::{Groups, Listing, Member};
use super::{LoadOptions, Result};
use crate::formats::Loaded;

/// DICOM's series.
pub(crate) struct Series;

impl Groups for Series {
    fn noun(&self) -> &'static str {
        "DICOM series"
    }

    fn member(&self, path: &Path) -> bool {
        super::is_dicom(path)
    }

    fn files_in(&self, dir: &Path) -> Result<Vec<PathBuf>> {
        super::files_in(dir)
    }

    fn files_under(&self, dir: &Path) -> Result<Vec<PathBuf>> {
        super::files_under(dir)
    }

    fn list(&self, files: &[PathBuf], opts: &LoadOptions) -> Result<Listing> {
        super::list_files(files, opts).map(listing)
    }

    fn list_in(&self, dir: &Path, opts: &LoadOptions) -> Result<Listing> {
        super::list_series(dir, opts).map(listing)
    }

    fn read(
        &self,
        folder: &Path,
        files: &[PathBuf],
        key: &str,
        opts: &LoadOptions,
    ) -> Result<Loaded> {
        super::load_series(folder, files, key, opts)
    }

    fn whole<'a>(&self, key: &'a str) -> &'a str {
        key.split('#').next().unwrap_or(key)
    }

    fn is_key(&self, text: &str) -> bool {
        !text.is_empty()
            && text
                .chars()
                .all(|c| c.is_ascii_digit() || c == '.' || c == '#')
    }

    fn pick(&self, opts: &mut LoadOptions, key: &str) {
        opts.dicom.series = Some(key.to_string());
    }

    fn picked<'a>(&self, opts: &'a LoadOptions) -> Option<&'a str> {
        opts.dicom.series.as_deref()
    }
}

/// A DICOM listing as a list of volumes shows it.
fn listing(l: super::Listing) -> Listing {
    Listing {
        volumes: l
            .series
            .into_iter()
            .map(|s| Member {
                key: s.key,
                whole: s.uid,
                label: s.label,
                files: s.files,
            })
            .collect(),
        failed: l.failed,
        notes: l.notes,
    }
}
