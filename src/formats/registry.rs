//! The registry: every reader, once, in the order they are asked. A file's format is found by
//! content first (each reader's sniff in this order, then each reader's deeper probe), by name
//! second; a folder's by what it holds ([`folder_kind`]); which names say volume to a folder's
//! walk, by the readers too ([`volume_name`]). What a format can hold (volumes, channels) is its
//! reader's to say.

use std::path::Path;

use super::reader::{Reader, Sniff};
use super::{Folder, Format, LoadOptions, Read0, Source, data};
use super::{dicom, hdf5, metaimage, mrc, nifti, nrrd, raw, tiff, volumeshop, vti, vtk, zarr};
use crate::error::{Error, Result};

/// Every reader, in the order they are asked: the order of the content sniff (DICOM's preamble
/// first, as some DICOM files carry a TIFF header in theirs), of the deeper probes and of the
/// name rules.
static READERS: &[&dyn Reader] = &[
    &dicom::Dicom,
    &nifti::Nifti,
    &nrrd::Nrrd,
    &tiff::TiffStack,
    &metaimage::MetaImage,
    &mrc::Mrc,
    &vtk::Vtk,
    &vti::Vti,
    &hdf5::Hdf5,
    &volumeshop::VolumeShop,
    &raw::Raw,
    &tiff::TiffSlices,
    &zarr::Zarr,
];

/// What every message refusing a file says slabscope reads: the readers' names for their formats
/// ([`Reader::reads`]) in the order of [`Format`]'s variants (the order the formats came in),
/// the one that reads what no other format does ([`Reader::fallback`]: raw data) last.
pub(crate) fn reads() -> String {
    let mut named: Vec<((bool, u8), &str)> = READERS
        .iter()
        .filter_map(|r| Some(((r.fallback(), r.format() as u8), r.reads()?)))
        .collect();
    named.sort_unstable_by_key(|&(order, _)| order);
    let names: Vec<&str> = named.into_iter().map(|(_, name)| name).collect();
    match names.split_last() {
        Some((last, rest)) if !rest.is_empty() => {
            format!("slabscope reads {}, and {last}", rest.join(", "))
        }
        _ => format!("slabscope reads {}", names.concat()),
    }
}

/// Reads the file or folder at `path` (checked to be one), with the format it was read as.
pub(super) fn read(path: &Path, opts: &LoadOptions) -> Result<(Format, Read0)> {
    if super::remote::is_url(path) {
        return read_url(path, opts);
    }
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    for reader in READERS {
        reader.check_options(path, meta.is_dir(), opts)?;
    }
    let source = Source::new(path);
    if meta.is_dir() {
        return read_folder(&source, opts);
    }
    let reader = detect(&source, opts)?;
    if opts.part.volume > 0 && !reader.volumes() {
        return Err(data::one_volume(path, 1, opts.part.volume));
    }
    if opts.part.channel > 0 && !reader.channels() {
        return Err(data::one_channel(path, 1, opts.part.channel));
    }
    Ok((reader.format(), reader.read(&source, opts)?))
}

/// Reads the URL `path`: a Zarr store, read in place (files of every other format are refused
/// by name, unread: they are read from a file).
fn read_url(path: &Path, opts: &LoadOptions) -> Result<(Format, Read0)> {
    check_url(path, opts)?;
    Ok((Format::OmeZarr, zarr::Zarr.read(&Source::new(path), opts)?))
}

/// Fails for the URL `path` when its name says a file of another format than Zarr's (read from
/// disk), or when `opts` do not fit a store.
pub(super) fn check_url(path: &Path, opts: &LoadOptions) -> Result<()> {
    let shown = super::remote::shown_text(&path.to_string_lossy());
    let lower = shown.to_string_lossy().to_ascii_lowercase();
    let lower = lower.trim_end_matches('/');
    let store = Path::new(lower)
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("zarr"));
    if !store && volume_name(Path::new(lower)) {
        return Err(Error::unsupported(
            &shown,
            "slabscope reads Zarr and OME-Zarr stores at URLs, in place; files of other formats \
             are read from disk: download it and name the file",
        ));
    }
    for reader in READERS {
        reader.check_options(path, true, opts)?;
    }
    Ok(())
}

/// The options checked of the store at `path` (a URL when `url`, else a folder) as a load checks
/// them ([`check_url`], or every reader's [`Reader::check_options`] of a folder).
pub(super) fn check_store(path: &Path, url: bool, opts: &LoadOptions) -> Result<()> {
    if url {
        return check_url(path, opts);
    }
    for reader in READERS {
        reader.check_options(path, true, opts)?;
    }
    Ok(())
}

/// Whether the file name says a volume slabscope reads (content decides when it is loaded; a
/// raw file counts only when its name carries its dimensions).
pub fn volume_name(path: &Path) -> bool {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    READERS.iter().any(|r| r.volume_name(&name))
}

/// Every reader's key for its details in `info --json` (see [`Reader::details_key`]), with its
/// format and whether `triage` rows carry them too, in the registry's order.
pub(super) fn details_keys() -> impl Iterator<Item = (Format, &'static str, bool)> {
    READERS
        .iter()
        .filter_map(|r| r.details_key().map(|key| (r.format(), key, r.in_rows())))
}

/// Whether the options pick one volume among a folder's files (a DICOM series by `--series`),
/// so that a front end reads the folder named rather than list it.
pub fn picks_in_folder(opts: &LoadOptions) -> bool {
    READERS.iter().any(|r| r.picks_in_folder(opts))
}

/// Whether the reader of `format` reads files that hold several arrays (`--array` picks one).
pub(super) fn arrays(format: Format) -> bool {
    READERS.iter().any(|r| r.format() == format && r.arrays())
}

/// The formats whose files hold several arrays, as the refusal of `--array` names them (`VTK
/// XML image data or HDF5`), in the registry's order.
pub(super) fn array_formats() -> String {
    let titles: Vec<&str> = READERS
        .iter()
        .filter(|r| r.arrays())
        .map(|r| r.title())
        .collect();
    titles.join(" or ")
}

/// The volumes of several files of the reader that makes them (at most one does: a test holds
/// that), for `formats::group`.
pub(super) fn groups() -> Option<&'static dyn super::reader::Groups> {
    READERS.iter().find_map(|r| r.groups())
}

/// Says what the folder `dir` is, asking the readers: whether it is one's store, which of its
/// entries are slices by name and which files make volumes together by content.
pub fn folder_kind(dir: &Path) -> Result<Folder> {
    if READERS.iter().any(|r| r.store(dir)) {
        return Ok(Folder::Store);
    }
    let (mut slices, mut others, mut series) = (0usize, 0usize, 0usize);
    for entry in std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))? {
        let entry = entry.map_err(|e| Error::io(dir, e))?;
        let path = entry.path();
        let is_dir = entry.file_type().is_ok_and(|t| t.is_dir());
        // Anything named like a slice counts as one (a folder or a FIFO so named is then an
        // error of the stack that names it).
        if READERS.iter().any(|r| r.slice_name(&path)) {
            slices += 1;
        } else if is_dir || volume_name(&path) {
            others += 1;
        } else if entry.file_type().is_ok_and(|t| t.is_file())
            && READERS.iter().any(|r| r.series_file(&path))
        {
            series += 1;
        }
    }
    Ok(if slices >= 2 && others + series == 0 {
        Folder::Slices
    } else if series > 0 && slices + others == 0 {
        Folder::Series
    } else if slices + others + series == 0 {
        Folder::Empty
    } else {
        Folder::Collection
    })
}

/// A coarse pyramid level of the volume at `path` that a reader reads without reading the
/// volume (see [`Reader::preview`]), with the format it was read as; `None` when none does.
pub(super) fn preview(
    path: &Path,
    opts: &LoadOptions,
    max_voxels: usize,
) -> Result<Option<(Format, Read0)>> {
    if super::remote::is_url(path) {
        check_url(path, opts)?;
    }
    let source = Source::new(path);
    for reader in READERS {
        if let Some(read) = reader.preview(&source, opts, max_voxels)? {
            return Ok(Some((reader.format(), read)));
        }
    }
    Ok(None)
}

/// Reads the folder `source`: a Zarr store, a DICOM series, or a stack of TIFF slices.
fn read_folder(source: &Source, opts: &LoadOptions) -> Result<(Format, Read0)> {
    let path = source.path();
    let kind = folder_kind(path)?;
    let reader = READERS.iter().find(|r| r.reads_folder(kind, opts));
    if opts.part.channel > 0 && !reader.is_some_and(|r| r.channels()) {
        return Err(data::one_channel(path, 1, opts.part.channel));
    }
    let Some(reader) = reader else {
        return Err(Error::format(
            path,
            match kind {
                Folder::Collection => {
                    "a folder of volumes, not one stack of TIFF slices: name a volume in it, or \
                     triage the folder"
                }
                _ => "folder holds no .tif or .tiff slices, no DICOM files and no volume files",
            },
        ));
    };
    if opts.part.volume > 0 && !reader.volumes() {
        return Err(data::one_volume(path, 1, opts.part.volume));
    }
    Ok((reader.format(), reader.read(source, opts)?))
}

/// The reader of the file `source`: the one the options name, else by content, else by name.
fn detect(source: &Source, opts: &LoadOptions) -> Result<&'static dyn Reader> {
    if let Some(reader) = READERS.iter().find(|r| r.forced(opts)) {
        return Ok(*reader);
    }
    let head = source.head(4096)?;
    if let Some(reader) = sniff(&head) {
        return Ok(reader);
    }
    if let Some(reader) = READERS.iter().find(|r| r.probe(source)) {
        return Ok(*reader);
    }
    let name = source.name().to_ascii_lowercase();
    if let Some(reader) = READERS.iter().find(|r| r.claims_name(&name)) {
        return Ok(*reader);
    }
    let claimed = READERS
        .iter()
        .find(|r| r.extensions().iter().any(|e| name.ends_with(e)));
    let what = match claimed {
        _ if head.is_empty() => "the file is empty".to_string(),
        Some(r) => format!(
            "the name says {0} but the content does not start like a {0} file",
            r.title()
        ),
        None => "not a volume file".to_string(),
    };
    Err(Error::format(
        source.path(),
        format!("{what} ({})", reads()),
    ))
}

/// The reader whose format the first bytes `head` are, asking each in the registry's order.
fn sniff(head: &[u8]) -> Option<&'static dyn Reader> {
    for reader in READERS {
        match reader.sniff(head) {
            Sniff::Mine => return Some(*reader),
            Sniff::Nobody => return None,
            Sniff::No => {}
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sniffed(head: &[u8]) -> Option<Format> {
        sniff(head).map(Reader::format)
    }

    #[test]
    fn sniffs_magic_bytes() {
        assert_eq!(sniffed(b"NRRD0004\ntype: uchar\n"), Some(Format::Nrrd));
        assert_eq!(sniffed(b"II*\0\x08\0\0\0"), Some(Format::Tiff));
        assert_eq!(
            sniffed(b"ObjectType = Image\nNDims = 3\n"),
            Some(Format::MetaImage)
        );
        assert_eq!(sniffed(b"hello world"), None);
        let mut nii = vec![0u8; 352];
        nii[344..348].copy_from_slice(b"n+1\0");
        assert_eq!(sniffed(&nii), Some(Format::Nifti));
        // A TIFF header in a DICOM preamble is DICOM's.
        let mut dcm = b"II*\0".to_vec();
        dcm.resize(128, 0);
        dcm.extend_from_slice(b"DICM");
        assert_eq!(sniffed(&dcm), Some(Format::Dicom));
        // VTK XML image data, after its declaration and a comment.
        assert_eq!(
            sniffed(b"<?xml version=\"1.0\"?>\n<!-- a -->\n<VTKFile type=\"ImageData\">"),
            Some(Format::Vti)
        );
        assert_eq!(sniffed(b"<?xml version=\"1.0\"?>\n<svg>"), None);
        // A gzip stream is NIfTI's or no reader's.
        assert_eq!(sniffed(&[0x1f, 0x8b, 8, 0]), None);
    }

    #[test]
    fn names_that_say_volume() {
        for name in [
            "a.nii", "B.NII.GZ", "c.nrrd", "d.nhdr", "e.mha", "f.mhd", "g.tif", "h.dat", "i.vti",
        ] {
            assert!(volume_name(Path::new(name)), "{name}");
        }
        for name in ["notes.txt", "a.img", "scan.raw", "x.data", "y.zraw"] {
            assert!(!volume_name(Path::new(name)), "{name}");
        }
        assert!(volume_name(Path::new("bonsai_256x256x256_uint8.raw")));
    }

    /// The sentence of every refusal, made from the readers, is the one that was kept by hand
    /// before byte for byte (HDF5's since added), and names every reader (its title's first word): a format added
    /// is added to it.
    #[test]
    fn the_sentence_names_every_reader() {
        let reads = reads();
        assert_eq!(
            reads,
            "slabscope reads NIfTI, NRRD, MetaImage, VolumeShop .dat, TIFF stacks, DICOM, \
             OME-Zarr stores, MRC, legacy VTK image data, VTK XML image data (.vti), HDF5 \
             datasets, and headerless raw data given its dimensions and voxel type"
        );
        for reader in READERS {
            let word = reader.title().split(' ').next().unwrap_or_default();
            assert!(reads.contains(word), "{word} is not in {reads:?}");
        }
    }

    /// A load whose cancellation is raised stops in the reader's loop (past [`crate::load`]'s
    /// own look at it): between a Zarr store's chunks, a DICOM series' files, a TIFF stack's
    /// pages and a folder's TIFF slices, with [`Error::Cancelled`], not an error of a file.
    #[test]
    fn a_cancelled_load_stops_in_every_readers_loop() {
        let flag = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(true));
        let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
        for (name, format, series) in [
            ("zarr/v05_tczyx.ome.zarr", Format::OmeZarr, None),
            ("dicom/ct", Format::Dicom, Some("1")),
            ("ramp_u16_stack.tif", Format::Tiff, None),
            ("ramp_slices", Format::TiffFolder, None),
        ] {
            let mut uncancelled = LoadOptions::default();
            uncancelled.dicom.series = series.map(String::from);
            let opts = LoadOptions {
                cancel: crate::progress::Cancel::new(std::sync::Arc::clone(&flag)),
                ..uncancelled.clone()
            };
            let path = data.join(name);
            let read_whole = read(&path, &uncancelled).map(|r| r.0);
            assert_eq!(read_whole.ok(), Some(format), "{name}");
            assert!(
                matches!(read(&path, &opts), Err(Error::Cancelled)),
                "{name}"
            );
        }
    }

    /// At most one reader makes volumes of several files (the entries of a walk carry no
    /// reader), and it is DICOM, whose files a folder's kind calls a series.
    #[test]
    fn one_reader_makes_volumes_of_several_files() {
        let grouping: Vec<Format> = READERS
            .iter()
            .filter(|r| r.groups().is_some())
            .map(|r| r.format())
            .collect();
        assert_eq!(grouping, [Format::Dicom]);
        assert_eq!(
            groups().map(super::super::reader::Groups::noun),
            Some("DICOM series")
        );
    }

    /// The refusal of `--array` names the readers whose files hold arrays, as it did by hand.
    #[test]
    fn the_formats_of_arrays() {
        assert_eq!(array_formats(), "VTK XML image data or HDF5");
        assert!(arrays(Format::Vti) && arrays(Format::Hdf5) && !arrays(Format::Vtk));
        let mut opts = LoadOptions::default();
        opts.part.array = Some("density".into());
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/ramp_i16.nii");
        let e = crate::formats::load(&path, &opts).unwrap_err().to_string();
        assert!(
            e.ends_with(
                "ramp_i16.nii: unsupported: --array \"density\" names an array of a VTK XML \
                 image data or HDF5 file; this nifti file holds one volume"
            ),
            "{e}"
        );
    }

    /// Each format is read by one reader, and each reader reads its own format.
    #[test]
    fn one_reader_a_format() {
        let mut formats: Vec<&str> = READERS.iter().map(|r| r.format().name()).collect();
        formats.sort_unstable();
        let count = formats.len();
        formats.dedup();
        assert_eq!(formats.len(), count, "{formats:?}");
    }
}
