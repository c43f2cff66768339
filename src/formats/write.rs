//! Writing a volume in the format its output's extension names, staged beside it and put in
//! place whole ([`super::output`]).

use std::path::Path;

use super::output::{Staged, check_output};
use super::{nifti, nrrd};
use crate::error::{Error, Result};
use crate::volume::Volume;
use nrrd::NrrdEncoding;

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
