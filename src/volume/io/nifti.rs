//! NIfTI-1 (`.nii`, `.nii.gz`, `.hdr`/`.img`): the `nifti` crate parses the header (it detects the
//! byte order); the voxels go through the shared checked reader, so gzip is recognised by its magic
//! and multi-member gzip streams are accepted.

use std::fs::File;
use std::io::{BufReader, Read};
use std::path::{Path, PathBuf};

use flate2::bufread::MultiGzDecoder;
use nifti::{Endianness, NiftiHeader};

use super::data::{DataSpec, Encoding, Skip, read_voxels};
use super::{LoadOptions, Read0, data_file};
use crate::error::{Error, Result};
use crate::volume::{Endian, VoxelType, dims_string};

const GZIP_MAGIC: [u8; 2] = [0x1f, 0x8b];

/// Whether gzip-compressed bytes start with a NIfTI-1 header.
pub(crate) fn is_gzipped_nifti(head: &[u8]) -> bool {
    let mut buf = [0u8; 348];
    let mut dec = MultiGzDecoder::new(head);
    dec.read_exact(&mut buf).is_ok() && (&buf[344..] == b"n+1\0" || &buf[344..] == b"ni1\0")
}

fn open(path: &Path) -> Result<(Box<dyn Read>, bool)> {
    let mut file = BufReader::new(File::open(path).map_err(|e| Error::io(path, e))?);
    let mut magic = [0u8; 2];
    let n = file.read(&mut magic).map_err(|e| Error::io(path, e))?;
    let file = std::io::Cursor::new(magic[..n].to_vec()).chain(file);
    let gz = n == 2 && magic == GZIP_MAGIC;
    Ok(if gz {
        (Box::new(MultiGzDecoder::new(BufReader::new(file))), true)
    } else {
        (Box::new(file), false)
    })
}

/// Reads and checks the header of a NIfTI-1 file.
pub(crate) fn read_header(path: &Path) -> Result<(NiftiHeader, bool)> {
    let (reader, gz) = open(path)?;
    let header = NiftiHeader::from_reader(reader)
        .map_err(|e| Error::format(path, format!("not a valid NIfTI-1 header: {e}")))?;
    if header.sizeof_hdr != 348 {
        return Err(Error::format(
            path,
            format!("NIfTI-1 header size is {}, not 348", header.sizeof_hdr),
        ));
    }
    if &header.magic != b"n+1\0" && &header.magic != b"ni1\0" {
        return Err(Error::format(
            path,
            format!("NIfTI magic is {:?}, not \"n+1\" or \"ni1\"", header.magic),
        ));
    }
    Ok((header, gz))
}

fn voxel_type(path: &Path, code: i16) -> Result<VoxelType> {
    Ok(match code {
        2 => VoxelType::U8,
        4 => VoxelType::I16,
        8 => VoxelType::I32,
        16 => VoxelType::F32,
        64 => VoxelType::F64,
        256 => VoxelType::I8,
        512 => VoxelType::U16,
        768 => VoxelType::U32,
        other => {
            let name = match other {
                32 => "complex64",
                128 => "rgb24",
                1024 => "int64",
                1280 => "uint64",
                1536 => "float128",
                1792 => "complex128",
                2048 => "complex256",
                2304 => "rgba32",
                _ => "unknown",
            };
            return Err(Error::unsupported(
                path,
                format!(
                    "NIfTI datatype {other} ({name}); slabscope reads u8, i8, u16, i16, u32, i32, f32 and f64"
                ),
            ));
        }
    })
}

/// Millimetres per spatial unit of `xyzt_units` (metres, mm, microns; unknown counts as mm).
fn unit_to_mm(xyzt_units: u8) -> f64 {
    match xyzt_units & 0x07 {
        1 => 1000.0,
        3 => 0.001,
        _ => 1.0,
    }
}

pub(crate) fn load(path: &Path, opts: &LoadOptions) -> Result<Read0> {
    let (h, gz) = read_header(path)?;
    let mut notes = Vec::new();
    let ndim = usize::from(h.dim[0]);
    if !(1..=7).contains(&ndim) {
        return Err(Error::format(
            path,
            format!("dim[0] is {ndim}, not between 1 and 7"),
        ));
    }
    let dim = |i: usize| if i <= ndim { usize::from(h.dim[i]) } else { 1 };
    let dims = [dim(1), dim(2), dim(3)];
    let extra: usize = (4..=ndim).map(dim).product();
    if extra == 0 {
        return Err(Error::format(path, "a dimension beyond the third is zero"));
    }
    if extra > 1 {
        notes.push(format!(
            "{ndim}D file with {extra} volumes of {}: loaded the first",
            dims_string(dims)
        ));
    }
    let ty = voxel_type(path, h.datatype)?;
    let unit = unit_to_mm(h.xyzt_units);
    let mut spacing = [1.0; 3];
    for (i, s) in spacing.iter_mut().enumerate() {
        let p = f64::from(h.pixdim[i + 1]).abs() * unit;
        if p.is_finite() && p > 0.0 {
            *s = p;
        } else if i < ndim {
            notes.push(format!(
                "pixdim[{}] is {}: using 1 mm",
                i + 1,
                h.pixdim[i + 1]
            ));
        }
    }
    let (slope, inter) = (f64::from(h.scl_slope), f64::from(h.scl_inter));
    let scale =
        (slope != 0.0 && slope.is_finite() && inter.is_finite() && (slope, inter) != (1.0, 0.0))
            .then_some((slope, inter));
    let offset = f64::from(h.vox_offset);
    if !(0.0..1e15).contains(&offset) {
        return Err(Error::format(
            path,
            format!("vox_offset {offset} is not a byte offset"),
        ));
    }
    let single = &h.magic == b"n+1\0";
    if single && offset < 348.0 {
        return Err(Error::format(
            path,
            format!("vox_offset {offset} lies inside the 348-byte header"),
        ));
    }
    let (file, gz) = if single {
        (path.to_path_buf(), gz)
    } else {
        let img = image_file(path, gz)?;
        let gz = open(&img)?.1;
        (img, gz)
    };
    let spec = DataSpec {
        file,
        start: 0,
        skip_lines: 0,
        skip: Skip::Bytes(offset as u64),
        encoding: if gz { Encoding::Gzip } else { Encoding::Raw },
        dims,
        voxel_type: ty,
        endian: match h.endianness {
            Endianness::Little => Endian::Little,
            Endianness::Big => Endian::Big,
        },
        scale,
        allow_trailing: extra > 1,
    };
    let voxels = read_voxels(&spec, opts.max_memory)?;
    Read0::new(path, dims, spacing, ty, voxels, notes)
}

/// The `.img` (or `.img.gz`) beside a `.hdr` header.
fn image_file(path: &Path, gz: bool) -> Result<PathBuf> {
    let name = path.to_string_lossy();
    let stem = name
        .strip_suffix(".hdr.gz")
        .or_else(|| name.strip_suffix(".hdr"))
        .ok_or_else(|| Error::format(path, "a two-file NIfTI header (ni1) should be named .hdr"))?;
    data_file(
        path,
        &format!("{stem}{}", if gz { ".img.gz" } else { ".img" }),
    )
}
