//! Writing a volume in the format its output's extension names, staged beside it and put in
//! place whole ([`super::output`]).

use std::io::Write;
use std::path::Path;

use super::output::{Staged, check_output};
use super::{nifti, nrrd};
use crate::error::{Error, Result};
use crate::geometry::WorldTransform;
use crate::volume::{Volume, VoxelType};
use nrrd::NrrdEncoding;

/// What a volume file's header says: the shape, spacing, voxel type and voxel-to-world
/// transform of the voxels that follow it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumeHeader {
    /// `[nx, ny, nz]`.
    pub dims: [usize; 3],
    /// `[sx, sy, sz]`, millimetres.
    pub spacing: [f64; 3],
    /// The voxels' type.
    pub voxel_type: VoxelType,
    /// The voxel-to-world transform.
    pub transform: WorldTransform,
}

impl VolumeHeader {
    /// The header of `volume`.
    #[must_use]
    pub fn of(volume: &Volume) -> Self {
        Self {
            dims: volume.dims(),
            spacing: volume.spacing(),
            voxel_type: volume.voxel_type(),
            transform: *volume.transform(),
        }
    }
}

/// Whether the file system of `file` has room for the voxels of `header` (as they are, or
/// compressed: then at least what deflate could pack them to, 1032 bytes a byte), an error
/// saying how much it needs and has when not: checked before a volume file is written, so that
/// a volume too large for the disk is refused at once, not when the disk is full.
pub(crate) fn check_disk_room(
    file: &std::fs::File,
    header: &VolumeHeader,
    compressed: bool,
) -> std::io::Result<()> {
    let voxels = header.dims.iter().map(|&d| d as u64).product::<u64>();
    let bytes = voxels.saturating_mul(header.voxel_type.size() as u64);
    let needed = if compressed { bytes / 1032 } else { bytes };
    let free = crate::volume::scratch::room_of(file)?.free;
    if needed > free {
        return Err(std::io::Error::other(disk_short(needed, free, compressed)));
    }
    Ok(())
}

/// The words of [`check_disk_room`]'s refusal.
fn disk_short(needed: u64, free: u64, compressed: bool) -> String {
    use crate::error::human_bytes;
    format!(
        "its voxels need {}{} of disk and the disk holds {} free",
        if compressed { "at least " } else { "" },
        human_bytes(needed),
        human_bytes(free)
    )
}

/// The voxels of a file being written, handed to their writer piece by piece: `body` writes
/// every voxel of the header's shape, x fastest, little-endian, in the header's type.
pub type Body<'a> = &'a mut dyn FnMut(&mut dyn Write) -> std::io::Result<()>;

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
    write_whole(path, volume, force, stage_streamed)
}

/// `volume` written in the format the extension of `path` names, to a temporary file beside it
/// that [`Staged::persist`] puts in place.
pub fn stage_volume(path: &Path, volume: &Volume) -> Result<Staged> {
    stage_whole(path, volume, stage_streamed)
}

/// Writes `volume` whole through a format's `stage`, atomically; an existing `path` is replaced
/// only when `force` is set, and only when it is a regular file.
pub(crate) fn write_whole(
    path: &Path,
    volume: &Volume,
    force: bool,
    stage: impl Fn(&Path, &VolumeHeader, Body<'_>) -> Result<Staged>,
) -> Result<()> {
    check_output(path, force)?;
    stage_whole(path, volume, stage)?.persist(force)
}

/// `volume`'s header and voxels, little-endian in their own type, through a format's `stage`.
fn stage_whole(
    path: &Path,
    volume: &Volume,
    stage: impl Fn(&Path, &VolumeHeader, Body<'_>) -> Result<Staged>,
) -> Result<Staged> {
    let ty = volume.voxel_type();
    stage(path, &VolumeHeader::of(volume), &mut |mut out| {
        crate::volume::write_le(volume.data(), ty, &mut out)
    })
}

/// A volume of `header`'s shape whose voxels `body` writes as it makes them (a volume never
/// held whole), in the format the extension of `path` names, to a temporary file beside it
/// that [`Staged::persist`] puts in place: the same bytes [`stage_volume`] writes for a volume
/// of those voxels.
pub fn stage_streamed(path: &Path, header: &VolumeHeader, body: Body<'_>) -> Result<Staged> {
    stage_encoded(path, header, NrrdEncoding::Gzip, body)
}

/// [`stage_streamed`] with `.nrrd` written in `encoding`.
fn stage_encoded(
    path: &Path,
    header: &VolumeHeader,
    encoding: NrrdEncoding,
    body: Body<'_>,
) -> Result<Staged> {
    match VolumeOutput::for_path(path)? {
        VolumeOutput::Nrrd => nrrd::stage(path, header, encoding, body),
        VolumeOutput::Nifti => nifti::stage(path, header, false, body),
        VolumeOutput::NiftiGz => nifti::stage(path, header, true, body),
    }
}

/// Writes a volume of `header`'s shape whose voxels `body` writes as it makes them (never held
/// whole) to `path`, in the format its extension names (`.nrrd` in `encoding`), atomically; an
/// existing `path` is replaced only when `force` is set, and only when it is a regular file.
fn write_streamed(
    path: &Path,
    header: &VolumeHeader,
    encoding: NrrdEncoding,
    force: bool,
    body: Body<'_>,
) -> Result<()> {
    check_output(path, force)?;
    stage_encoded(path, header, encoding, body)?.persist(force)
}

/// Writes the phantom `recipe` makes to `path` in the format its extension names (`.nrrd` in
/// `encoding`), made and written a chunk of voxels at a time, never held whole, atomically; an
/// existing `path` is replaced only when `force` is set, and only when it is a regular file.
pub fn write_phantom(
    path: &Path,
    recipe: &crate::volume::phantom::Recipe,
    encoding: NrrdEncoding,
    force: bool,
) -> Result<()> {
    let header = VolumeHeader {
        dims: recipe.dims(),
        spacing: [1.0; 3],
        voxel_type: recipe.voxel_type(),
        transform: recipe.transform(),
    };
    write_streamed(path, &header, encoding, force, &mut |out| {
        recipe.write_le(out)
    })
}
