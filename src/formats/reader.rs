//! The one trait every format's reader implements: how it is recognised (by content, by a
//! deeper look, by name), what it says of a folder and of the options, what it can hold
//! (volumes, channels, arrays), how it is read, and the key of what it tells besides the volume
//! ([`Details`](super::Details)). Every method but `format`, `title` and `read` has a default
//! that says "not this reader's". A reader whose volumes are made of several files, which one
//! folder holds several of (DICOM's series), gives its [`Groups`] too, and the [`Listing`] of
//! [`Member`]s they list, which `formats::group` asks for through the registry. The registry
//! ([`super::registry`]) asks the readers in its order; it knows no format itself.

use std::path::{Path, PathBuf};

use super::{Folder, Format, LoadOptions, Loaded, Read0, Source};
use crate::error::{Error, Result};

/// What a reader says of a file's first bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Sniff {
    /// Not this reader's: ask the next.
    No,
    /// This reader's.
    Mine,
    /// A wrapper only this reader opens (a gzip stream, for NIfTI) around what is not its: no
    /// reader's, and no later reader is asked.
    Nobody,
}

/// A format's reader. Each format's module holds one (a unit value), listed once in
/// [`super::registry`]; adding a format touches its module, that list and the docs.
pub(crate) trait Reader: Sync {
    /// The format it reads.
    fn format(&self) -> Format;

    /// The format's name in messages (`NIfTI`).
    fn title(&self) -> &'static str;

    /// How the sentence of what slabscope reads (which every refusal of a file no reader reads
    /// ends with) names this format: by default its [`title`](Self::title); `None` for a reader
    /// that another reader of its kind names (TIFF slices, under TIFF stacks).
    fn reads(&self) -> Option<&'static str> {
        Some(self.title())
    }

    /// Whether it reads any file it is told how to read (raw data given its dimensions), what is
    /// read when no other format is: the sentence of what slabscope reads names it last.
    fn fallback(&self) -> bool {
        false
    }

    /// Whether the options name this format whatever the file holds (raw data given its
    /// dimensions).
    fn forced(&self, _opts: &LoadOptions) -> bool {
        false
    }

    /// What the file's first bytes (up to 4096) say.
    fn sniff(&self, _head: &[u8]) -> Sniff {
        Sniff::No
    }

    /// A look deeper than the first bytes, asked only when no reader's [`sniff`](Self::sniff)
    /// knew them (DICOM without its preamble).
    fn probe(&self, _source: &Source) -> bool {
        false
    }

    /// Whether the name (lowercased) makes a file this format's when its content did not say
    /// (VolumeShop's `.dat`, raw data's extensions and names with dimensions).
    fn claims_name(&self, _name: &str) -> bool {
        false
    }

    /// The endings of this format's names that do not make a file one by themselves: a file so
    /// named whose content is not this format's is refused saying so.
    fn extensions(&self) -> &'static [&'static str] {
        &[]
    }

    /// Whether a file so named (lowercased) is one of this format's volumes to a folder's walk
    /// (its content decides when it is read): by default, one of its
    /// [`extensions`](Self::extensions).
    fn volume_name(&self, name: &str) -> bool {
        self.extensions().iter().any(|e| name.ends_with(e))
    }

    /// Fails when the options ask of the file or folder at `path` what only this format holds
    /// and it is not this format's (a label image of a Zarr store named for another file):
    /// asked of every reader before any reads.
    fn check_options(&self, _path: &Path, _is_dir: bool, _opts: &LoadOptions) -> Result<()> {
        Ok(())
    }

    /// Whether the folder `dir` is one volume this reader reads whole, never walked into (a
    /// Zarr store): a [`Folder::Store`].
    fn store(&self, _dir: &Path) -> bool {
        false
    }

    /// Whether a file so named is a slice of a folder of slices, one volume (a TIFF slice): by
    /// name alone, asked first of a folder's entries.
    fn slice_name(&self, _path: &Path) -> bool {
        false
    }

    /// Whether the file at `path`, which no reader's name rules call a volume, is one of files
    /// that make volumes together (DICOM): by content, asked last of a folder's entries.
    fn series_file(&self, _path: &Path) -> bool {
        false
    }

    /// Whether the options pick one volume among a folder's files (a DICOM series by
    /// `--series`): the folder is then read, not listed.
    fn picks_in_folder(&self, _opts: &LoadOptions) -> bool {
        false
    }

    /// Whether a folder of this `kind` is this reader's (asked with the options: a DICOM series
    /// may be named in a folder of other volumes).
    fn reads_folder(&self, _kind: Folder, _opts: &LoadOptions) -> bool {
        false
    }

    /// Its volumes of several files, which one folder may hold several of (DICOM's series):
    /// `None` for a reader whose volume is one file or one whole folder.
    fn groups(&self) -> Option<&'static dyn Groups> {
        None
    }

    /// Whether one file of it can hold several volumes (`--volume N` picks one).
    fn volumes(&self) -> bool {
        false
    }

    /// Whether one file of it can hold several arrays (`--array NAME` picks one).
    fn arrays(&self) -> bool {
        false
    }

    /// Whether one file of it can hold several channels (`--channel N` picks one).
    fn channels(&self) -> bool {
        false
    }

    /// The key `info --json` gives this reader's [`Details`](super::Details) under, null for a
    /// volume of another format; `None` for a reader that tells nothing besides the volume.
    fn details_key(&self) -> Option<&'static str> {
        None
    }

    /// Whether `triage` rows carry the details too, under the same key
    /// ([`Details::row_json`](super::Details::row_json)).
    fn in_rows(&self) -> bool {
        false
    }

    /// Reads the volume `opts` picks of `source`.
    fn read(&self, source: &Source, opts: &LoadOptions) -> Result<Read0>;

    /// A coarse pyramid level of that volume, of at most `max_voxels` voxels, read without
    /// reading the volume (an OME-Zarr store's coarser dataset); `None` when `source` is not this
    /// reader's or holds no such level, as every format but OME-Zarr and Imaris's HDF5.
    fn preview(
        &self,
        _source: &Source,
        _opts: &LoadOptions,
        _max_voxels: usize,
    ) -> Result<Option<Read0>> {
        Ok(None)
    }
}

/// One volume of a listing, as a list shows it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Member {
    /// The key that picks it among the folder's volumes (a DICOM series' `SeriesInstanceUID`,
    /// with `#2`, ... on the parts of a split series).
    pub key: String,
    /// The key of the whole it is a part of (the UID without its `#N`): the parts of one whole
    /// found in several folders are listed again together.
    pub whole: String,
    /// How a list names it: `series 3 "Abdomen"`.
    pub label: String,
    /// The files it is read from, sorted.
    pub files: Vec<PathBuf>,
}

/// What a scan of files found: their volumes (in the order a position counts them, from 1),
/// the files that could not be read (each with its error) and what the scan left out, said once
/// for all the files.
#[derive(Debug, Default)]
pub struct Listing {
    /// The volumes.
    pub volumes: Vec<Member>,
    /// The files that could not be read.
    pub failed: Vec<(PathBuf, Error)>,
    /// What was left out.
    pub notes: Vec<String>,
}

/// A reader's volumes of several files.
pub(crate) trait Groups: Sync {
    /// What one such volume is called in messages (`DICOM series`).
    fn noun(&self) -> &'static str;

    /// Whether the file at `path` is one of the files that make such volumes (by content).
    fn member(&self, path: &Path) -> bool;

    /// Those files directly in folder `dir`, sorted.
    fn files_in(&self, dir: &Path) -> Result<Vec<PathBuf>>;

    /// Those files in folder `dir` and below it, sorted.
    fn files_under(&self, dir: &Path) -> Result<Vec<PathBuf>>;

    /// The volumes the files `files` make, each file's header read once.
    fn list(&self, files: &[PathBuf], opts: &LoadOptions) -> Result<Listing>;

    /// The volumes the files directly in folder `dir` make: an error naming the folder when it
    /// holds none of those files.
    fn list_in(&self, dir: &Path, opts: &LoadOptions) -> Result<Listing>;

    /// The volume `key` read from `files` alone (as a listing gave them), named `folder` in
    /// messages, its notes saying nothing of the other files a listing left out (the listing
    /// says that, once).
    fn read(
        &self,
        folder: &Path,
        files: &[PathBuf],
        key: &str,
        opts: &LoadOptions,
    ) -> Result<Loaded>;

    /// The key of the whole the volume `key` is a part of (a split DICOM series' UID, the key
    /// without its `#N`): `key` itself when it is a whole.
    fn whole<'a>(&self, key: &'a str) -> &'a str;

    /// Whether `text` is spelt as one of its keys (a UID, digits and dots, maybe with `#N`).
    fn is_key(&self, text: &str) -> bool;

    /// The options that read the volume `key` of a folder: `opts` with it picked.
    fn pick(&self, opts: &mut LoadOptions, key: &str);

    /// The volume the options pick among a folder's (`--series`), as given: a key, or a
    /// position in the folder's list from 1.
    fn picked<'a>(&self, opts: &'a LoadOptions) -> Option<&'a str>;
}
