//! NIfTI-1 and NIfTI-2 (`.nii`, `.nii.gz`, `.hdr`/`.img`): [`header`] reads either version's
//! header (the `nifti` crate parses version 1 and detects its byte order; version 2 is parsed
//! there); the voxels go through the shared checked reader, so gzip is recognised by its magic
//! and multi-member gzip streams are accepted. Written files are NIfTI-1.

mod header;
mod write;

pub(crate) use write::stage;
pub use write::write_nifti;

use std::io::{BufReader, Read};
use std::path::Path;

use flate2::bufread::MultiGzDecoder;

use header::Header;

use super::data::{DataSpec, Encoding, Skip, pick_volume, read_voxels};
use super::reader::{Reader, Sniff};
use super::{Format, LoadOptions, Read0, Source};
use crate::error::{Error, Result};
use crate::geometry::WorldTransform;
use crate::volume::VoxelType;

const GZIP_MAGIC: [u8; 2] = [0x1f, 0x8b];

/// The NIfTI reader.
pub(crate) struct Nifti;

impl Reader for Nifti {
    fn format(&self) -> Format {
        Format::Nifti
    }

    fn title(&self) -> &'static str {
        "NIfTI"
    }

    /// A NIfTI header, plain or gzipped; a gzip stream of anything else is no reader's.
    fn sniff(&self, head: &[u8]) -> Sniff {
        if head.starts_with(&GZIP_MAGIC) {
            return if is_gzipped_nifti(head) {
                Sniff::Mine
            } else {
                Sniff::Nobody
            };
        }
        if looks_like(head) {
            Sniff::Mine
        } else {
            Sniff::No
        }
    }

    fn extensions(&self) -> &'static [&'static str] {
        &[".nii", ".nii.gz"]
    }

    /// Its extensions, and a two-file header's `.hdr`.
    fn volume_name(&self, name: &str) -> bool {
        [".nii", ".nii.gz", ".hdr"]
            .iter()
            .any(|e| name.ends_with(e))
    }

    fn volumes(&self) -> bool {
        true
    }

    fn read(&self, source: &Source, opts: &LoadOptions) -> Result<Read0> {
        load(source, opts)
    }
}

/// Whether bytes start with a NIfTI-1 or NIfTI-2 header.
fn looks_like(head: &[u8]) -> bool {
    matches!(head.get(344..348), Some(b"n+1\0" | b"ni1\0")) || header::looks_like_2(head)
}

/// Whether gzip-compressed bytes start with a NIfTI-1 or NIfTI-2 header.
fn is_gzipped_nifti(head: &[u8]) -> bool {
    let mut buf = Vec::with_capacity(540);
    // A truncated stream still shows its first bytes.
    let _ = MultiGzDecoder::new(head).take(540).read_to_end(&mut buf);
    looks_like(&buf)
}

/// The file of `source` to read from, gunzipped where it is gzipped, and whether it is.
fn open(source: &Source) -> Result<(Box<dyn Read>, bool)> {
    let path = source.path();
    let mut file = BufReader::new(source.open()?);
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

/// Reads and checks the header of a NIfTI file of either version, and whether it is gzipped.
fn read_header(source: &Source) -> Result<(Header, bool)> {
    let (reader, gz) = open(source)?;
    Ok((Header::read(source.path(), reader)?, gz))
}

/// NIfTI `datatype` codes of the voxel types slabscope reads and writes.
const DATATYPES: [(i16, VoxelType); 8] = [
    (2, VoxelType::U8),
    (4, VoxelType::I16),
    (8, VoxelType::I32),
    (16, VoxelType::F32),
    (64, VoxelType::F64),
    (256, VoxelType::I8),
    (512, VoxelType::U16),
    (768, VoxelType::U32),
];

fn voxel_type(path: &Path, code: i16) -> Result<VoxelType> {
    if let Some(&(_, ty)) = DATATYPES.iter().find(|d| d.0 == code) {
        return Ok(ty);
    }
    let name = match code {
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
    Err(Error::unsupported(
        path,
        format!(
            "NIfTI datatype {code} ({name}); slabscope reads u8, i8, u16, i16, u32, i32, f32 and f64"
        ),
    ))
}

/// Millimetres per spatial unit of `xyzt_units` (metres, mm, microns; unknown counts as mm).
fn unit_to_mm(xyzt_units: u8) -> f64 {
    match xyzt_units & 0x07 {
        1 => 1000.0,
        3 => 0.001,
        _ => 1.0,
    }
}

fn load(source: &Source, opts: &LoadOptions) -> Result<Read0> {
    let path = source.path();
    let (h, gz) = read_header(source)?;
    let mut notes = Vec::new();
    check_intent(path, &h)?;
    let (ndim, dims, extra) = dimensions(path, &h)?;
    let volumes = pick_volume(path, extra, opts.part.volume, &mut notes)?;
    let ty = voxel_type(path, h.datatype)?;
    let unit = unit_to_mm(h.xyzt_units);
    let spacing = spacing(&h, ndim, unit, &mut notes);
    let (slope, inter) = (h.scl_slope, h.scl_inter);
    let scale =
        (slope != 0.0 && slope.is_finite() && inter.is_finite() && (slope, inter) != (1.0, 0.0))
            .then_some((slope, inter));
    let offset = h.vox_offset;
    if !(0.0..1e15).contains(&offset) {
        return Err(Error::format(
            path,
            format!("vox_offset {offset} is not a byte offset"),
        ));
    }
    let single = h.single;
    if single && offset < h.size() as f64 {
        return Err(Error::format(
            path,
            format!(
                "vox_offset {offset} lies inside the {}-byte header",
                h.size()
            ),
        ));
    }
    let (file, gz) = if single {
        (source.clone(), gz)
    } else {
        let img = image_file(source, gz)?;
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
        endian: h.endian,
        scale,
        volumes,
        trailing: false,
    };
    let (voxels, rounded) = read_voxels(&spec, opts.room())?;
    notes.extend(rounded.note(ty.name()));
    let mut read = Read0::new(path, dims, spacing, ty, voxels, notes)?
        .with_transform(transform(&h, unit))
        .with_source(spec.file.path());
    read.format_version = Some(h.version.to_string());
    Ok(read)
}

/// A CIFTI-2 file is a NIfTI-2 file whose intent code is 3000-3099: a matrix over brain
/// ordinates (surface vertices and voxels) and time or parcels, not a volume.
fn check_intent(path: &Path, h: &Header) -> Result<()> {
    if (3000..3100).contains(&h.intent_code) {
        return Err(Error::unsupported(
            path,
            format!(
                "a CIFTI-2 file (NIfTI intent code {}): a matrix over brain ordinates, not a \
                 volume of voxels",
                h.intent_code
            ),
        ));
    }
    Ok(())
}

/// The dimensions the header states: how many are used, the three spatial ones, and the
/// product of the others (the volumes of a 4D or higher image). Fails on a count outside 1 to 7,
/// a used dimension below 1, or dimensions whose product no address can reach.
fn dimensions(path: &Path, h: &Header) -> Result<(usize, [usize; 3], usize)> {
    let ndim = h.dim[0];
    if !(1..=7).contains(&ndim) {
        return Err(Error::format(
            path,
            format!("dim[0] is {ndim}, not between 1 and 7"),
        ));
    }
    let ndim = ndim as usize;
    if let Some(i) = (1..=ndim).find(|&i| h.dim[i] < 1) {
        return Err(Error::format(
            path,
            format!(
                "dim[{i}] is {}: every used dimension must be at least 1",
                h.dim[i]
            ),
        ));
    }
    let used = &h.dim[1..=ndim];
    let count = used.iter().try_fold(1usize, |n, &d| {
        usize::try_from(d).ok().and_then(|d| n.checked_mul(d))
    });
    if count.is_none() {
        return Err(Error::format(
            path,
            format!("dimensions {used:?} hold more voxels than any file can"),
        ));
    }
    let dim = |i: usize| if i <= ndim { h.dim[i] as usize } else { 1 };
    let extra: usize = (4..=ndim).map(dim).product();
    Ok((ndim, [dim(1), dim(2), dim(3)], extra))
}

/// The voxel spacing in mm (`unit` mm a header unit): `pixdim`, with 1 mm (and a note) for a
/// used dimension whose spacing is not a positive number.
fn spacing(h: &Header, ndim: usize, unit: f64, notes: &mut Vec<String>) -> [f64; 3] {
    let mut spacing = [1.0; 3];
    for (i, s) in spacing.iter_mut().enumerate() {
        let p = h.pixdim[i + 1].abs() * unit;
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
    spacing
}

/// The voxel-to-world transform the header states, in mm: the sform when its code is set, else
/// the qform (quaternion, offsets and `pixdim`, with `pixdim[0]` the handedness), else none.
fn transform(h: &Header, unit: f64) -> Option<WorldTransform> {
    if h.sform_code > 0 {
        let linear = h.srow.map(|r| [r[0], r[1], r[2]].map(|v| v * unit));
        let origin = h.srow.map(|r| r[3] * unit);
        return Some(WorldTransform::ras(linear, origin));
    }
    if h.qform_code <= 0 {
        return None;
    }
    let [b, c, d] = h.quatern;
    // As nifti1_io: a rotation of 180° has a = 0, which the rounding of b, c and d to f32 can
    // leave a little above or below.
    let (a, b, c, d) = match 1.0 - (b * b + c * c + d * d) {
        a2 if a2 < 1e-7 => {
            let norm = (b * b + c * c + d * d).sqrt();
            (0.0, b / norm, c / norm, d / norm)
        }
        a2 => (a2.sqrt(), b, c, d),
    };
    let r = [
        [
            a * a + b * b - c * c - d * d,
            2.0 * (b * c - a * d),
            2.0 * (b * d + a * c),
        ],
        [
            2.0 * (b * c + a * d),
            a * a + c * c - b * b - d * d,
            2.0 * (c * d - a * b),
        ],
        [
            2.0 * (b * d - a * c),
            2.0 * (c * d + a * b),
            a * a + d * d - c * c - b * b,
        ],
    ];
    let qfac = if h.pixdim[0] < 0.0 { -1.0 } else { 1.0 };
    let zoom = [h.pixdim[1], h.pixdim[2], qfac * h.pixdim[3]];
    let linear = r.map(|row| std::array::from_fn(|k| row[k] * zoom[k] * unit));
    let origin = h.qoffset.map(|v| v * unit);
    Some(WorldTransform::ras(linear, origin))
}

/// The `.img` (or `.img.gz`) beside a `.hdr` header: named by the header's own name, relative to
/// its folder (the whole path would be taken relative to the folder a second time).
fn image_file(source: &Source, gz: bool) -> Result<Source> {
    let name = source.name();
    let stem = name
        .strip_suffix(".hdr.gz")
        .or_else(|| name.strip_suffix(".hdr"))
        .ok_or_else(|| {
            Error::format(
                source.path(),
                "a two-file NIfTI header (ni1, ni2) should be named .hdr",
            )
        })?;
    source.sibling(&format!("{stem}{}", if gz { ".img.gz" } else { ".img" }))
}
