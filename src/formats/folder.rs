//! What a folder is (one volume, or a collection of them) and which file names say volume.

use std::path::Path;

use super::{Folder, parse_raw_name};
use crate::error::{Error, Result};

/// Whether the file name says a volume slabscope reads (content decides when it is loaded; a
/// raw file counts only when its name carries its dimensions).
pub fn volume_name(path: &Path) -> bool {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    [
        ".nii", ".nii.gz", ".hdr", ".nrrd", ".nhdr", ".mha", ".mhd", ".tif", ".tiff", ".dat",
    ]
    .iter()
    .any(|e| name.ends_with(e))
        || ([".raw", ".bin", ".vol"].iter().any(|e| name.ends_with(e))
            && parse_raw_name(&name).is_some())
}

pub(crate) fn is_tiff(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("tif") || e.eq_ignore_ascii_case("tiff"))
}

/// Says what the folder `dir` is.
pub fn folder_kind(dir: &Path) -> Result<Folder> {
    if super::zarr::is_store(dir) {
        return Ok(Folder::Zarr);
    }
    let (mut tiffs, mut others, mut dicoms) = (0usize, 0usize, 0usize);
    for entry in std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))? {
        let entry = entry.map_err(|e| Error::io(dir, e))?;
        let path = entry.path();
        let is_dir = entry.file_type().is_ok_and(|t| t.is_dir());
        // Anything named like a slice counts as one (a folder or a FIFO so named is then an
        // error of the stack that names it).
        if is_tiff(&path) {
            tiffs += 1;
        } else if is_dir || volume_name(&path) {
            others += 1;
        } else if entry.file_type().is_ok_and(|t| t.is_file()) && super::dicom::is_dicom(&path) {
            dicoms += 1;
        }
    }
    Ok(if tiffs >= 2 && others + dicoms == 0 {
        Folder::Slices
    } else if dicoms > 0 && tiffs + others == 0 {
        Folder::Dicom
    } else if tiffs + others + dicoms == 0 {
        Folder::Empty
    } else {
        Folder::Collection
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_that_say_volume() {
        for name in [
            "a.nii", "B.NII.GZ", "c.nrrd", "d.nhdr", "e.mha", "f.mhd", "g.tif", "h.dat",
        ] {
            assert!(volume_name(Path::new(name)), "{name}");
        }
        for name in ["notes.txt", "a.img", "scan.raw", "x.data", "y.zraw"] {
            assert!(!volume_name(Path::new(name)), "{name}");
        }
        assert!(volume_name(Path::new("bonsai_256x256x256_uint8.raw")));
    }
}
