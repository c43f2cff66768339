//! Loading volumes from files: one entry point, [`load`], that picks the reader by content (magic
//! bytes) first and by extension second, and writers for exporting.

mod data;
pub mod dicom;
mod folder;
mod limits;
mod metaimage;
mod nifti;
mod nrrd;
mod ome;
mod output;
mod placement;
mod raw;
mod tiff;
mod tiff_ifd;
mod volumeshop;
pub mod zarr;

use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};

use serde::Serialize;

pub use folder::{Folder, folder_kind, volume_name};
pub use limits::{default_max_memory, parse_bytes, physical_memory};
pub use nifti::write_nifti;
pub use nrrd::{NrrdEncoding, write_nrrd};
pub use output::{Staged, check_output, remove_staged, same_file, stage, write_atomic};
pub use raw::{RawOptions, parse_dims, parse_raw_name};

use crate::error::{Error, Result};
use crate::geometry::WorldTransform;
use crate::volume::Volume;

/// The file formats slabscope reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Format {
    /// NIfTI-1, `.nii`, `.nii.gz` or a `.hdr`/`.img` pair.
    Nifti,
    /// NRRD, attached (`.nrrd`) or detached (`.nhdr`).
    Nrrd,
    /// MetaImage, `.mha` or `.mhd` with a data file.
    MetaImage,
    /// VolumeShop / TU Wien `.dat`: three u16 dimensions then u16 voxels.
    VolumeShop,
    /// Headerless raw voxels described by options or the file name.
    Raw,
    /// A multi-page TIFF stack.
    Tiff,
    /// A folder of single-page TIFF slices.
    TiffFolder,
    /// A DICOM file or series (a folder of files).
    Dicom,
    /// An OME-Zarr image or a plain Zarr array (a folder).
    OmeZarr,
    /// Made in memory (a phantom or the built-in dataset).
    Synthetic,
}

impl Format {
    /// The name shown to users and in JSON.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Nifti => "nifti",
            Self::Nrrd => "nrrd",
            Self::MetaImage => "metaimage",
            Self::VolumeShop => "volumeshop",
            Self::Raw => "raw",
            Self::Tiff => "tiff",
            Self::TiffFolder => "tiff-folder",
            Self::Dicom => "dicom",
            Self::OmeZarr => "ome-zarr",
            Self::Synthetic => "synthetic",
        }
    }
}

/// Options for [`load`].
#[derive(Clone, Debug)]
pub struct LoadOptions {
    /// The most bytes the loaded f32 volume may occupy; checked before anything is allocated.
    pub max_memory: u64,
    /// Description of a headerless raw file; when `dims` is set the file is read as raw.
    pub raw: RawOptions,
    /// Which volume of a 4D file (NIfTI, NRRD, MetaImage, a DICOM series) to read, from 0.
    pub volume: usize,
    /// Which channel of a multichannel file (an OME-TIFF's `C`), from 0.
    pub channel: usize,
    /// Which series of a DICOM folder: its position in the list (from 1) or its UID.
    pub series: Option<String>,
    /// Keep DICOM localizer and derived images (left out by default).
    pub include_localizers: bool,
    /// Resample a DICOM series with uneven spacing or gantry tilt to an even, orthogonal grid.
    pub resample: bool,
    /// Read the patient-identifying DICOM fields (never read otherwise).
    pub show_phi: bool,
    /// Which label image of an OME-Zarr store to read (`labels/NAME`) instead of its image.
    pub label_image: Option<String>,
}

impl Default for LoadOptions {
    fn default() -> Self {
        Self {
            max_memory: default_max_memory(),
            raw: RawOptions::default(),
            volume: 0,
            channel: 0,
            series: None,
            include_localizers: false,
            resample: false,
            show_phi: false,
            label_image: None,
        }
    }
}

/// A loaded volume with what the loader noticed on the way.
#[derive(Clone, Debug)]
pub struct Loaded {
    /// The volume.
    pub volume: Volume,
    /// The format it was read as.
    pub format: Format,
    /// Things a user should know, e.g. "4D file with 12 volumes: loaded volume 0 (the first)".
    pub notes: Vec<String>,
    /// Every file read: the one named, and a detached header's data file.
    pub sources: Vec<PathBuf>,
    /// The DICOM series read, for a DICOM file or folder.
    pub dicom: Option<DicomSeries>,
    /// The store's image, levels, chunking and codecs, for an OME-Zarr store.
    pub zarr: Option<zarr::ZarrInfo>,
    /// The version of the format the file is written in, where the format has versions that
    /// readers tell apart (NIfTI `1` or `2`, OME-Zarr `0.4` or `0.5`).
    pub format_version: Option<String>,
}

/// What a DICOM volume is, beyond its geometry: never a patient-identifying field unless they
/// were asked for.
#[derive(Clone, Debug, Default, Serialize)]
pub struct DicomSeries {
    /// The series' key: its `SeriesInstanceUID` (with `#2`, ... on the parts of a split series).
    pub key: String,
    /// `SeriesNumber`.
    pub number: Option<i64>,
    /// `SeriesDescription`.
    pub description: String,
    /// Modality.
    pub modality: String,
    /// The transfer syntax, named.
    pub syntax: String,
    /// Patient-identifying fields, read only when asked for (empty otherwise).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub patient: Vec<(String, String)>,
}

/// Loads the volume at `path` (a file, or a folder of TIFF slices).
pub fn load(path: &Path, opts: &LoadOptions) -> Result<Loaded> {
    check_input(path)?;
    load_checked(path, opts).map_err(|e| e.reached_from(path))
}

/// Fails unless `path` is a regular file or a folder: a FIFO would block forever and a device
/// would never end.
pub fn check_input(path: &Path) -> Result<()> {
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    match kind(&meta) {
        None => Ok(()),
        Some(kind) => Err(Error::unsupported(
            path,
            format!("{kind}: slabscope reads regular files and folders"),
        )),
    }
}

/// Opens `path` for reading, only if it is a regular file, without ever blocking: the open does
/// not wait (`O_NONBLOCK`: a FIFO or a device, even one mounted over a file's name, opens at once
/// instead of waiting for a writer) and the opened handle's own type is checked (not the name's,
/// which a directory listing or an earlier `stat` may have seen differently). Every input file
/// is opened through it.
pub fn open_regular(path: &Path) -> std::io::Result<File> {
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NONBLOCK | libc::O_NOCTTY);
    }
    let file = options.open(path)?;
    let meta = file.metadata()?;
    match kind(&meta) {
        None if meta.is_file() => Ok(file),
        None => Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "a folder, where a file was expected",
        )),
        Some(kind) => Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("{kind}: slabscope reads regular files and folders"),
        )),
    }
}

/// What a path that is neither a regular file nor a folder is, in words.
fn kind(meta: &std::fs::Metadata) -> Option<&'static str> {
    if meta.is_file() || meta.is_dir() {
        return None;
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let t = meta.file_type();
        if t.is_fifo() {
            return Some("a FIFO (named pipe)");
        }
        if t.is_char_device() || t.is_block_device() {
            return Some("a device");
        }
        if t.is_socket() {
            return Some("a socket");
        }
    }
    Some("not a regular file")
}

fn load_checked(path: &Path, opts: &LoadOptions) -> Result<Loaded> {
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if opts.label_image.is_some() && !(meta.is_dir() && zarr::is_store(path)) {
        return Err(Error::format(
            path,
            "--label-image names a label image of an OME-Zarr store, and this is none",
        ));
    }
    let (format, loaded) = if meta.is_dir() {
        load_folder(path, opts)?
    } else {
        let format = detect(path, opts)?;
        let four_d = matches!(
            format,
            Format::Nifti | Format::Nrrd | Format::MetaImage | Format::Dicom | Format::Tiff
        );
        if opts.volume > 0 && !four_d {
            return Err(data::one_volume(path, 1, opts.volume));
        }
        if opts.channel > 0 && format != Format::Tiff {
            return Err(data::one_channel(path, 1, opts.channel));
        }
        let loaded = match format {
            Format::Nifti => nifti::load(path, opts)?,
            Format::Nrrd => nrrd::load(path, opts)?,
            Format::MetaImage => metaimage::load(path, opts)?,
            Format::VolumeShop => volumeshop::load(path, opts)?,
            Format::Raw => raw::load(path, opts)?,
            Format::Tiff => tiff::load_stack(path, opts)?,
            Format::Dicom => dicom::load(path, opts)?,
            Format::TiffFolder | Format::OmeZarr | Format::Synthetic => {
                unreachable!("not detected from a file")
            }
        };
        (format, loaded)
    };
    finish(path, format, loaded)
}

/// The volume a reader read from `path`, its spacing checked (for every reader, here once:
/// [`placement`]), with the notes every format shares.
fn finish(path: &Path, format: Format, mut loaded: Read0) -> Result<Loaded> {
    placement::check_spacing(path, &loaded.volume)?;
    let missing = loaded.volume.stats().missing;
    if missing > 0 {
        loaded.notes.push(format!(
            "{missing} NaN or infinite voxels are treated as missing (left out of every measure)"
        ));
    }
    if loaded.volume.is_constant() {
        loaded.notes.push(format!(
            "every voxel is {}: the volume is constant and has no structure to analyse",
            loaded.volume.stats().min
        ));
    }
    let mut sources = vec![path.to_path_buf()];
    sources.extend(loaded.sources.into_iter().filter(|s| s != path));
    Ok(Loaded {
        volume: loaded.volume,
        format,
        notes: loaded.notes,
        sources,
        dicom: loaded.dicom,
        zarr: loaded.zarr,
        format_version: loaded.format_version,
    })
}

/// Reads the folder `path`: a Zarr store, a DICOM series, or a stack of TIFF slices.
fn load_folder(path: &Path, opts: &LoadOptions) -> Result<(Format, Read0)> {
    let kind = folder_kind(path)?;
    // Only an OME-TIFF file or an OME-Zarr store holds channels.
    if opts.channel > 0 && kind != Folder::Zarr {
        return Err(data::one_channel(path, 1, opts.channel));
    }
    Ok(match kind {
        Folder::Zarr => (Format::OmeZarr, zarr::load(path, opts)?),
        // A series may be named in a folder of DICOM files and other volumes.
        Folder::Dicom => (Format::Dicom, dicom::load(path, opts)?),
        Folder::Collection if opts.series.is_some() => (Format::Dicom, dicom::load(path, opts)?),
        Folder::Collection => {
            return Err(Error::format(
                path,
                "a folder of volumes, not one stack of TIFF slices: name a volume in it, or \
                 triage the folder",
            ));
        }
        Folder::Empty => {
            return Err(Error::format(
                path,
                "folder holds no .tif or .tiff slices, no DICOM files and no volume files",
            ));
        }
        Folder::Slices => {
            if opts.volume > 0 {
                return Err(data::one_volume(path, 1, opts.volume));
            }
            (Format::TiffFolder, tiff::load_folder(path, opts)?)
        }
    })
}

/// What a format reader returns before `load` adds its general notes.
pub(crate) struct Read0 {
    pub volume: Volume,
    pub notes: Vec<String>,
    /// Files read besides the one named (a detached header's data file).
    pub sources: Vec<PathBuf>,
    /// The DICOM series read.
    pub dicom: Option<DicomSeries>,
    /// The store read, for an OME-Zarr store.
    pub zarr: Option<zarr::ZarrInfo>,
    /// The format's version (see [`Loaded::format_version`]).
    pub format_version: Option<String>,
}

impl Read0 {
    /// The volume read from `path`, with the reader's notes.
    pub(crate) fn new(
        path: &Path,
        dims: [usize; 3],
        spacing: [f64; 3],
        ty: crate::volume::VoxelType,
        voxels: crate::volume::Voxels,
        notes: Vec<String>,
    ) -> Result<Self> {
        // The file's values, not a parameter the user gave: said as the file's.
        let volume = Volume::from_voxels(dims, spacing, ty, voxels).map_err(|e| match e {
            Error::InvalidParameter {
                parameter,
                value,
                expected,
            } => Error::format(
                path,
                format!("the file's voxel {parameter} {value}: expected {expected}"),
            ),
            other => Error::format(path, other.to_string()),
        })?;
        Ok(Self {
            volume,
            notes,
            sources: Vec::new(),
            dicom: None,
            zarr: None,
            format_version: None,
        })
    }

    /// With `file` among the files read, when it is not the one named.
    pub(crate) fn with_source(mut self, file: &Path) -> Self {
        self.sources.push(file.to_path_buf());
        self
    }

    /// With the voxel-to-world transform the file states, when it states one, held to bounds
    /// ([`placement::place`]: an origin out of them replaced with 0, an unusable orientation
    /// left out, each with a note).
    pub(crate) fn with_transform(mut self, t: Option<WorldTransform>) -> Self {
        self.volume = placement::place(self.volume, t, &mut self.notes);
        self
    }
}

fn detect(path: &Path, opts: &LoadOptions) -> Result<Format> {
    if opts.raw.dims.is_some() {
        return Ok(Format::Raw);
    }
    let mut head = Vec::with_capacity(4096);
    open_regular(path)
        .and_then(|f| f.take(4096).read_to_end(&mut head))
        .map_err(|e| Error::io(path, e))?;
    if let Some(format) = sniff(&head) {
        return Ok(format);
    }
    if dicom::is_dicom(path) {
        return Ok(Format::Dicom);
    }
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let ext = |e: &str| name.ends_with(e);
    if ext(".dat") {
        return Ok(Format::VolumeShop);
    }
    if ext(".raw") || ext(".bin") || ext(".vol") || ext(".img") || parse_raw_name(&name).is_some() {
        return Ok(Format::Raw);
    }
    let claimed = [
        (".nii", "NIfTI"),
        (".nii.gz", "NIfTI"),
        (".nrrd", "NRRD"),
        (".nhdr", "NRRD"),
        (".mha", "MetaImage"),
        (".mhd", "MetaImage"),
    ]
    .into_iter()
    .find(|(e, _)| ext(e));
    let what = match claimed {
        _ if head.is_empty() => "the file is empty".to_string(),
        Some((_, format)) => {
            format!("the name says {format} but the content does not start like a {format} file")
        }
        None => "not a volume file".to_string(),
    };
    Err(Error::format(
        path,
        format!(
            "{what} (slabscope reads NIfTI, NRRD, MetaImage, VolumeShop .dat, TIFF stacks, \
             DICOM, OME-Zarr stores, and headerless raw data given its dimensions and voxel type)"
        ),
    ))
}

/// Recognises a format by its first bytes.
fn sniff(head: &[u8]) -> Option<Format> {
    // First: some DICOM files carry a TIFF header in their preamble.
    if head.get(128..132) == Some(b"DICM") {
        return Some(Format::Dicom);
    }
    if head.starts_with(&[0x1f, 0x8b]) {
        return nifti::is_gzipped_nifti(head).then_some(Format::Nifti);
    }
    if nifti::looks_like(head) {
        return Some(Format::Nifti);
    }
    if head.starts_with(b"NRRD000") {
        return Some(Format::Nrrd);
    }
    if head.starts_with(b"II*\0")
        || head.starts_with(b"MM\0*")
        || head.starts_with(b"II+\0")
        || head.starts_with(b"MM\0+")
    {
        return Some(Format::Tiff);
    }
    metaimage::looks_like(head).then_some(Format::MetaImage)
}

/// The formats slabscope writes volumes in, chosen by the output's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VolumeOutput {
    /// `.nrrd`: attached, gzip-compressed, in LPS `space`.
    Nrrd,
    /// `.nii`.
    Nifti,
    /// `.nii.gz`.
    NiftiGz,
}

impl VolumeOutput {
    /// The format the name of `path` asks for; an unknown extension is an error, so that it is
    /// found before any work is done.
    pub fn for_path(path: &Path) -> Result<Self> {
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        // The name is lowercased: `.NII.GZ` counts.
        let ends = |ext: &str| name.len() > ext.len() && name.ends_with(ext);
        if ends(".nrrd") {
            Ok(Self::Nrrd)
        } else if ends(".nii.gz") {
            Ok(Self::NiftiGz)
        } else if ends(".nii") {
            Ok(Self::Nifti)
        } else {
            Err(Error::unsupported(
                path,
                "volumes are written as .nrrd, .nii or .nii.gz, chosen by the extension",
            ))
        }
    }
}

/// Writes `volume` in the format its extension names ([`VolumeOutput`]), atomically; an existing
/// `path` is replaced only when `force` is set, and only when it is a regular file.
pub fn write_volume(path: &Path, volume: &Volume, force: bool) -> Result<()> {
    check_output(path, force)?;
    stage_volume(path, volume)?.persist(force)
}

/// `volume` written in the format the extension of `path` names, to a temporary file beside it
/// that [`Staged::persist`] puts in place.
pub fn stage_volume(path: &Path, volume: &Volume) -> Result<Staged> {
    match VolumeOutput::for_path(path)? {
        VolumeOutput::Nrrd => nrrd::stage(path, volume, NrrdEncoding::Gzip),
        VolumeOutput::Nifti => nifti::stage(path, volume, false),
        VolumeOutput::NiftiGz => nifti::stage(path, volume, true),
    }
}

/// The data file a header names, relative to the header's folder; it must exist.
pub(crate) fn data_file(header: &Path, name: &str) -> Result<PathBuf> {
    let p = Path::new(name);
    let file = if p.is_absolute() {
        p.to_path_buf()
    } else {
        header.parent().unwrap_or(Path::new(".")).join(p)
    };
    match std::fs::metadata(&file) {
        Ok(meta) if meta.is_file() => Ok(file),
        Ok(meta) => Err(Error::format(
            header,
            format!(
                "its data file {} is {}",
                crate::error::shown(&file),
                kind(&meta).unwrap_or("a folder")
            ),
        )),
        Err(e) => Err(Error::format(
            header,
            format!("its data file {}: {e}", crate::error::shown(&file)),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A FIFO opens at once and is refused by its handle's own type, never waiting for a writer
    /// (a plain `File::open` would wait forever); a folder is refused too.
    #[test]
    #[cfg(unix)]
    fn only_regular_files_open_and_a_fifo_never_blocks() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("scan0001");
        if !std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .is_ok_and(|s| s.success())
        {
            eprintln!("skipped: no mkfifo");
            return;
        }
        let (tx, rx) = std::sync::mpsc::channel();
        let path = fifo.clone();
        std::thread::spawn(move || {
            let _ = tx.send(open_regular(&path).map(drop).map_err(|e| e.to_string()));
        });
        let opened = rx
            .recv_timeout(std::time::Duration::from_secs(10))
            .expect("the open returned at once");
        let e = opened.unwrap_err();
        assert!(e.contains("a FIFO"), "{e}");
        let e = open_regular(dir.path()).unwrap_err().to_string();
        assert!(e.contains("a folder"), "{e}");
        let file = dir.path().join("a.nii");
        std::fs::write(&file, b"x").unwrap();
        assert!(open_regular(&file).is_ok());
    }

    #[test]
    fn sniffs_magic_bytes() {
        assert_eq!(sniff(b"NRRD0004\ntype: uchar\n"), Some(Format::Nrrd));
        assert_eq!(sniff(b"II*\0\x08\0\0\0"), Some(Format::Tiff));
        assert_eq!(
            sniff(b"ObjectType = Image\nNDims = 3\n"),
            Some(Format::MetaImage)
        );
        assert_eq!(sniff(b"hello world"), None);
        let mut nii = vec![0u8; 352];
        nii[344..348].copy_from_slice(b"n+1\0");
        assert_eq!(sniff(&nii), Some(Format::Nifti));
    }
}
