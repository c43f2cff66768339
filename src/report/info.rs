//! The reports of `info`: one volume, with what its reader tells of it, and the volumes of a
//! folder.

use std::collections::BTreeMap;
use std::path::Path;

use serde::Serialize;

use super::{GeometryReport, ResolutionReport, SCHEMA_VERSION};
use crate::error::Result;
use crate::formats::Loaded;
use crate::volume::VoxelType;

/// The object `info --json` prints for one volume: what it is, where it lies, how its values
/// spread, and what its reader tells besides (which DICOM series it is, ...).
#[derive(Clone, Debug, Serialize)]
pub struct InfoReport {
    /// [`SCHEMA_VERSION`].
    pub schema_version: u32,
    /// The file as the user named it.
    pub file: String,
    /// The format it was read as (`nifti`, `nrrd`, `dicom`, ...).
    pub format: &'static str,
    /// The format's version where readers tell versions apart (NIfTI `1` or `2`, OME-Zarr
    /// `0.4` or `0.5`), null otherwise.
    pub format_version: Option<String>,
    /// `[nx, ny, nz]`.
    pub dims: [usize; 3],
    /// `[sx, sy, sz]`, mm.
    pub spacing: [f64; 3],
    /// The voxel type of the file (`u8`, `i16`, `f32`, ...).
    #[serde(rename = "type")]
    pub voxel_type: VoxelType,
    /// Smallest and largest finite voxel, null when no voxel is finite.
    pub range: Option<[f32; 2]>,
    /// Mean of the finite voxels, null when no voxel is finite.
    pub mean: Option<f64>,
    /// Number of voxels.
    pub voxels: usize,
    /// Voxels that are NaN or infinite.
    pub missing: usize,
    /// The type the voxels are held in: the file's for integers of at most 16 bits that it
    /// does not scale, else `f32`.
    pub held_type: VoxelType,
    /// Bytes the voxels take in memory as held (0 when they are read in place from the file).
    pub memory_bytes: u64,
    /// Bytes of the file read in place for the voxels, mapped, not copied (0 when in memory).
    pub mapped_bytes: u64,
    /// Of those, bytes of a scratch file the voxels were decoded into beyond the memory budget
    /// (`--scratch`), not of the file itself (0 otherwise).
    pub scratch_bytes: u64,
    /// Bytes the voxels take as the file stores them.
    pub stored_bytes: u64,
    /// The voxel-to-world transform: `affine`, `orientation`, `orthogonal`, `world_bounds`.
    #[serde(flatten)]
    pub geometry: GeometryReport,
    /// Voxel counts over equal bins between the smallest and largest finite voxel.
    pub histogram: Vec<u64>,
    /// The pyramid level `range`, `mean`, `missing` and `histogram` were taken from when not
    /// from every voxel (a remote store's coarsest dataset, unless `--exact`); null when from
    /// every voxel.
    pub statistics_from: Option<ResolutionReport>,
    /// What the loader noticed (a 4D file, a volume picked, ...).
    pub notes: Vec<String>,
    /// What the reader tells besides the volume, under each reader's key (`dicom`, `ome_zarr`,
    /// `mrc`, `vtk`, `vti`): null but for the reader that read it.
    #[serde(flatten)]
    pub details: BTreeMap<&'static str, serde_json::Value>,
}

impl InfoReport {
    /// The report of `loaded`, read from the file `file`, with a histogram of `bins` bins.
    pub fn new(file: &str, loaded: &Loaded, bins: usize) -> Result<Self> {
        let report = Self::of_volume(file, loaded, bins)?;
        let v = &loaded.volume;
        // A level read without level 0: the statistics are its, the grid level 0's.
        let Some(finest) = v.unread_finest() else {
            return Ok(report);
        };
        let voxels = finest.dims.iter().product::<usize>();
        Ok(Self {
            dims: finest.dims,
            spacing: finest.spacing,
            voxels,
            stored_bytes: (voxels * v.voxel_type().size()) as u64,
            geometry: GeometryReport::of_grid(&finest.transform, finest.dims),
            statistics_from: Some(ResolutionReport::of(v)),
            ..report
        })
    }

    /// The report of `loaded`'s volume as it is.
    fn of_volume(file: &str, loaded: &Loaded, bins: usize) -> Result<Self> {
        let v = &loaded.volume;
        let s = v.stats();
        let finite = s.finite > 0;
        Ok(Self {
            schema_version: SCHEMA_VERSION,
            file: file.to_string(),
            format: loaded.format.name(),
            format_version: loaded.format_version.clone(),
            dims: v.dims(),
            spacing: v.spacing(),
            voxel_type: v.voxel_type(),
            range: finite.then_some([s.min, s.max]),
            mean: finite.then_some(s.mean),
            voxels: v.len(),
            missing: s.missing,
            held_type: v.data().held(),
            memory_bytes: v.memory_bytes(),
            mapped_bytes: v.mapped_bytes(),
            scratch_bytes: v.scratch_bytes(),
            stored_bytes: v.stored_bytes(),
            geometry: GeometryReport::of(v),
            histogram: v.histogram(bins)?,
            statistics_from: None,
            notes: loaded.notes.clone(),
            details: loaded.details_json(),
        })
    }
}

/// The object `info --json` prints for a folder of several volumes: each one a line of the
/// list, as `triage` would look at them.
#[derive(Clone, Debug, Serialize)]
pub struct FolderReport {
    /// [`SCHEMA_VERSION`].
    pub schema_version: u32,
    /// The folder as the user named it.
    pub folder: String,
    /// The volumes in it.
    pub volumes: Vec<ListedVolume>,
}

/// One volume of a [`FolderReport`].
#[derive(Clone, Debug, Serialize)]
pub struct ListedVolume {
    /// The file, or the folder of slices or of DICOM files.
    pub path: String,
    /// The DICOM series' key in a folder of DICOM files, else null.
    pub series: Option<String>,
    /// How a list names the series (number and description), else null.
    pub label: Option<String>,
}

impl FolderReport {
    /// The report of `folder`, holding `volumes`.
    pub fn new(folder: &Path, volumes: Vec<ListedVolume>) -> Self {
        Self {
            schema_version: SCHEMA_VERSION,
            folder: crate::error::shown(folder),
            volumes,
        }
    }
}
