//! Reading volumes from files, above the [`Volume`] they produce: one entry point, [`load`],
//! that asks the readers of one registry (`registry.rs`; each format's module holds its reader,
//! `reader.rs` the trait they share) by content first and by name second, each reading a
//! [`Source`]; and writers for exporting ([`write_volume`]).

mod data;
mod details;
pub mod dicom;
pub mod group;
mod hdf5;
mod limits;
mod metaimage;
mod mrc;
mod nifti;
mod nrrd;
mod ome;
mod output;
mod placement;
mod raw;
mod reader;
mod registry;
pub mod remote;
mod scratch;
mod source;
mod tiff;
mod tiff_ifd;
mod volumeshop;
mod vti;
mod vtk;
mod write;
pub mod zarr;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use serde::Serialize;

pub use details::{Details, RowDetails};
pub use dicom::DicomOptions;
pub use limits::{default_max_memory, parse_bytes, physical_memory};
pub use nifti::write_nifti;
pub use nrrd::{NrrdEncoding, write_nrrd};
pub use output::{Staged, check_output, remove_staged, same_file, stage, write_atomic};
pub use raw::{RawOptions, parse_dims, parse_raw_name};
pub use registry::{folder_kind, picks_in_folder, volume_name};
pub use source::{Source, check_input, open_regular, regular};
pub use write::{
    Body, VolumeHeader, VolumeOutput, stage_streamed, stage_volume, write_phantom, write_volume,
};
pub use zarr::ZarrOptions;

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
    /// An MRC/CCP4 map or tomogram (electron microscopy).
    Mrc,
    /// Legacy VTK image data (`STRUCTURED_POINTS`).
    Vtk,
    /// VTK XML image data (`.vti`).
    Vti,
    /// An HDF5 file's dataset (`.h5`, `.hdf5`, `.nxs`, `.ims`).
    Hdf5,
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
            Self::Mrc => "mrc",
            Self::Vtk => "vtk",
            Self::Vti => "vti",
            Self::Hdf5 => "hdf5",
            Self::Synthetic => "synthetic",
        }
    }
}

/// What a folder is, as the readers say ([`folder_kind`]): one volume (a reader's store, or a
/// stack of two or more slices and no other volume file or folder), files that make volumes
/// together (one series or several), a collection of volumes, or nothing slabscope reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Folder {
    /// A stack of slices (TIFF): one volume.
    Slices,
    /// Files that make volumes together (DICOM) and no other volume file or folder: one series
    /// is a volume, several a collection of series.
    Series,
    /// Volume files or folders (or a single TIFF file): looked at one by one.
    Collection,
    /// Neither a volume file nor a folder in it.
    Empty,
    /// A reader's store (a Zarr store: an OME-Zarr image or a plain array): one volume, never
    /// walked into.
    Store,
}

/// Options for [`load`]: those every reader takes, which part of a file holding several to
/// read, and each format's own.
#[derive(Clone, Debug)]
pub struct LoadOptions {
    /// The most bytes the loaded f32 volume may occupy; checked before anything is allocated.
    pub max_memory: u64,
    /// Which volume, channel or array of a file holding several to read.
    pub part: PartOptions,
    /// Description of a headerless raw file; when `dims` is set the file is read as raw.
    pub raw: RawOptions,
    /// Which DICOM series to read, and how.
    pub dicom: DicomOptions,
    /// What of an OME-Zarr store to read.
    pub zarr: ZarrOptions,
    /// A folder on disk to decode voxels into when they do not fit in `max_memory` (compressed
    /// or converted voxels; those stored as held are read in place anyway): they are then read
    /// from there as a mapped file. `None`: such voxels beyond the budget are refused.
    pub scratch: Option<PathBuf>,
    /// Raised, the load stops between chunks, files or pages with [`Error::Cancelled`] (a
    /// timeout, Ctrl-C, the user moving on).
    pub cancel: crate::progress::Cancel,
}

/// Which part of a file holding several to read (`--volume`, `--channel`, `--array`): a reader
/// whose files hold one refuses a part past the first, with the error naming the parameter.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PartOptions {
    /// Which volume of a 4D file (NIfTI, NRRD, MetaImage, a DICOM series, an OME-Zarr store's
    /// or an Imaris file's time points) to read, from 0.
    pub volume: usize,
    /// Which channel of a multichannel file (an OME-TIFF's or an OME-Zarr store's `C`, an
    /// Imaris file's channels), from 0.
    pub channel: usize,
    /// Which array of a file holding several to read: a `.vti` file's array by its name, an
    /// HDF5 file's dataset by its path (`None`: the active scalars, the only 3-D dataset, or
    /// `DXchange`'s `/exchange/data`).
    pub array: Option<String>,
}

impl LoadOptions {
    /// Where decoded voxels may go.
    pub(crate) fn room(&self) -> scratch::Room<'_> {
        scratch::Room {
            max_memory: self.max_memory,
            scratch: self.scratch.as_deref(),
        }
    }
}

impl Default for LoadOptions {
    fn default() -> Self {
        Self {
            max_memory: default_max_memory(),
            part: PartOptions::default(),
            raw: RawOptions::default(),
            dicom: DicomOptions::default(),
            zarr: ZarrOptions::default(),
            scratch: None,
            cancel: crate::progress::Cancel::never(),
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
    /// What the reader tells besides the volume (a DICOM series, an OME-Zarr store's levels,
    /// an MRC map's mode), for `info` and lists to show without knowing the format.
    pub details: Option<Arc<dyn Details>>,
    /// The version of the format the file is written in, where the format has versions that
    /// readers tell apart (NIfTI `1` or `2`, OME-Zarr `0.4` or `0.5`).
    pub format_version: Option<String>,
}

impl Loaded {
    /// The reader's details as the type it wrote them in, for code that knows the format
    /// (`loaded.details_as::<DicomSeries>()`); `None` when they are another's or there are none.
    #[must_use]
    pub fn details_as<T: Details>(&self) -> Option<&T> {
        let details: &dyn std::any::Any = self.details.as_deref()?;
        details.downcast_ref()
    }

    /// What `info --json` gives of the details: every reader's key, null but for the reader
    /// that read the volume (a format added adds its key).
    #[must_use]
    pub fn details_json(&self) -> BTreeMap<&'static str, serde_json::Value> {
        details::info_json(self.format, self.details.as_deref())
    }

    /// What a `triage` row gives of the details: the keys of the readers whose rows carry
    /// them, null but for the reader that read the volume.
    #[must_use]
    pub fn row_details(&self) -> RowDetails {
        RowDetails::of(Some(self.format), self.details.as_deref())
    }
}

/// Loads the volume at `path`: a file, or a folder (a stack of TIFF slices, a DICOM series or a
/// Zarr store).
pub fn load(path: &Path, opts: &LoadOptions) -> Result<Loaded> {
    opts.cancel.check()?;
    check_input(path)?;
    registry::read(path, opts)
        .and_then(|(format, read)| {
            check_array(path, format, opts)?;
            finish(path, format, read)
        })
        .map_err(|e| e.reached_from(&named(path)))
}

/// `--array` names an array of a file holding several (VTK XML image data, HDF5: the readers
/// say which): of a file of another format it is an error saying so, as `--channel` of a file
/// of one channel is.
fn check_array(path: &Path, format: Format, opts: &LoadOptions) -> Result<()> {
    match &opts.part.array {
        Some(name) if !registry::arrays(format) => Err(Error::unsupported(
            path,
            format!(
                "--array {:?} names an array of a {} file; this {} file holds one volume",
                crate::error::names::text(name),
                registry::array_formats(),
                format.name()
            ),
        )),
        _ => Ok(()),
    }
}

/// `path` as errors name it: a URL without what it must not show ([`remote::shown_text`]).
fn named(path: &Path) -> std::borrow::Cow<'_, Path> {
    if remote::is_url(path) {
        std::borrow::Cow::Owned(remote::shown_text(&path.to_string_lossy()))
    } else {
        std::borrow::Cow::Borrowed(path)
    }
}

/// A coarse pyramid level of the volume at `path`, read without reading level 0, where the file
/// holds one on the pyramid's grid of at most `max_voxels` voxels (an OME-Zarr store's coarser
/// dataset): the finest such, its [`Volume::level`](crate::Volume::level) saying which,
/// quantized with its own range (level 0's is not known until level 0 is read). `None` for every
/// other file, and when level 0 itself has at most `max_voxels` voxels. A first picture while
/// [`load`] reads level 0. With `max_voxels` 0, the coarsest level the file holds (for `info`'s
/// statistics of a remote store); its [`Volume::unread_finest`](crate::Volume::unread_finest)
/// gives level 0's grid.
pub fn load_preview(path: &Path, opts: &LoadOptions, max_voxels: usize) -> Result<Option<Loaded>> {
    check_input(path)?;
    let read =
        registry::preview(path, opts, max_voxels).map_err(|e| e.reached_from(&named(path)))?;
    read.map(|(format, read)| finish(path, format, read))
        .transpose()
}

/// For a Zarr store, local or at a URL, the coarsest of its datasets on the pyramid's grid that
/// serves the pyramid level `resolution` picks (that level, or the finest above it, from which
/// it is computed), read without reading level 0, whose grid its
/// [`Volume::unread_finest`](crate::Volume::unread_finest) gives; quantized with its own range,
/// a note says so. `None` for any other file (whose level 0 is read, as [`load`] does), when
/// `resolution` picks level 0, and when the store holds no such dataset: then [`load`] reads
/// level 0. What `analyze --resolution auto` reads of a store.
pub fn load_serving(
    path: &Path,
    opts: &LoadOptions,
    resolution: crate::volume::Resolution,
) -> Result<Option<Loaded>> {
    let url = remote::is_url(path);
    let store = url || (path.is_dir() && zarr::is_store(path));
    if !store || resolution == crate::volume::Resolution::Full {
        return Ok(None);
    }
    opts.cancel.check()?;
    check_input(path)?;
    let read = registry::check_store(path, url, opts)
        .and_then(|()| zarr::read_serving(path, opts, resolution))
        .map_err(|e| e.reached_from(&named(path)))?;
    read.map(|read| finish(path, Format::OmeZarr, read))
        .transpose()
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
    let scratch = loaded.volume.scratch_bytes();
    if scratch > 0 {
        loaded.notes.push(format!(
            "decoded beyond the memory limit into an unnamed scratch file of {} on disk, read \
             from there as a mapped file",
            crate::error::human_bytes(scratch),
        ));
    }
    let mut sources = vec![path.to_path_buf()];
    sources.extend(loaded.sources.into_iter().filter(|s| s != path));
    Ok(Loaded {
        volume: loaded.volume,
        format,
        notes: loaded.notes,
        sources,
        details: loaded.details,
        format_version: loaded.format_version,
    })
}

/// What a format reader returns before `load` adds its general notes.
pub(crate) struct Read0 {
    pub volume: Volume,
    pub notes: Vec<String>,
    /// Files read besides the one named (a detached header's data file).
    pub sources: Vec<PathBuf>,
    /// What the reader tells besides the volume (see [`Loaded::details`]).
    pub details: Option<Arc<dyn Details>>,
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
            details: None,
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
