//! Writing NRRD: an attached header (with the voxel-to-world transform when it is known) and the
//! voxels, raw or gzip, through a temporary file put in place only when asked.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use flate2::Compression;
use flate2::write::GzEncoder;

use super::super::Staged;
use super::super::write::{Body, VolumeHeader, check_disk_room, write_whole};
use super::type_name;
use crate::error::Result;
use crate::volume::Volume;

/// How [`write_nrrd`] stores the voxels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum NrrdEncoding {
    /// Plain little-endian bytes.
    Raw,
    /// gzip-compressed (smaller, slower).
    #[default]
    Gzip,
}

/// Writes `volume` as an attached NRRD in its voxel type (integer types are rounded and clamped),
/// with its voxel-to-world transform as `space: left-posterior-superior`, `space directions` and
/// `space origin` when it is known, and as `spacings` when it is not.
///
/// The file is written to a temporary file beside `path` and renamed into place; an existing
/// `path` is replaced only when `force` is set.
pub fn write_nrrd(path: &Path, volume: &Volume, encoding: NrrdEncoding, force: bool) -> Result<()> {
    write_whole(path, volume, force, |path, header, body| {
        stage(path, header, encoding, body)
    })
}

/// A volume of `header` whose voxels `body` writes, as NRRD in a temporary file beside `path`,
/// to be put in place.
pub(crate) fn stage(
    path: &Path,
    header: &VolumeHeader,
    encoding: NrrdEncoding,
    body: Body<'_>,
) -> Result<Staged> {
    super::super::stage(path, |file| {
        check_disk_room(file, header, encoding == NrrdEncoding::Gzip)?;
        write_to(file, header, encoding, body)
    })
}

/// Writes `header` and the voxels `body` writes into `file`.
fn write_to(
    file: &File,
    header: &VolumeHeader,
    encoding: NrrdEncoding,
    body: Body<'_>,
) -> std::io::Result<()> {
    let mut out = BufWriter::new(file);
    let [nx, ny, nz] = header.dims;
    let [sx, sy, sz] = header.spacing;
    let ty = header.voxel_type;
    write!(
        out,
        "NRRD0004\n# written by slabscope {}\ntype: {}\ndimension: 3\nsizes: {nx} {ny} {nz}\n",
        env!("CARGO_PKG_VERSION"),
        type_name(ty)
    )?;
    let t = &header.transform;
    if t.known {
        // LPS, as Slicer and ITK write it: x and y negated from RAS.
        let lps = |r: usize, v: f64| if r < 2 { -v } else { v };
        let vector = |v: [f64; 3]| format!("({},{},{})", v[0], v[1], v[2]);
        let column = |c: usize| vector(std::array::from_fn(|r| lps(r, t.matrix[r][c]) + 0.0));
        writeln!(
            out,
            "space: left-posterior-superior\nspace directions: {} {} {}\nspace origin: {}",
            column(0),
            column(1),
            column(2),
            vector(std::array::from_fn(|r| lps(r, t.matrix[r][3]) + 0.0))
        )?;
    } else {
        writeln!(out, "spacings: {sx} {sy} {sz}")?;
    }
    writeln!(out, "kinds: domain domain domain")?;
    if ty.size() > 1 {
        writeln!(out, "endian: little")?;
    }
    let gz = encoding == NrrdEncoding::Gzip;
    writeln!(out, "encoding: {}\n", if gz { "gzip" } else { "raw" })?;
    let mut sink: Box<dyn Write + '_> = if gz {
        Box::new(GzEncoder::new(&mut out, Compression::fast()))
    } else {
        Box::new(&mut out)
    };
    body(&mut sink)?;
    drop(sink);
    out.flush()
}
