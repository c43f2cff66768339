//! The NIfTI header, version 1 (348 bytes, parsed by the `nifti` crate) or 2 (540 bytes, 64-bit
//! dimensions and offsets and f64 fields, parsed here: the crate reads version 1 only), held in
//! the widths of version 2.

use std::io::Read;
use std::path::Path;

use nifti::{Endianness, NiftiHeader};

use crate::error::{Error, Result};
use crate::volume::Endian;

/// NIfTI-2's header size, the first field.
const SIZE_2: usize = 540;

/// The bytes after NIfTI-2's four-byte magic: a check that the file was not sent as text.
const EOL_CHECK: [u8; 4] = [b'\r', b'\n', 0x1a, b'\n'];

/// What slabscope reads of a NIfTI header of either version.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Header {
    /// 1 or 2.
    pub version: u8,
    /// Whether the voxels follow the header in the same file (`n+1`, `n+2`) rather than in an
    /// `.img` beside it (`ni1`, `ni2`).
    pub single: bool,
    pub endian: Endian,
    pub datatype: i16,
    /// `dim[0]` is the number of dimensions used.
    pub dim: [i64; 8],
    /// `pixdim[0]` is the qform's handedness.
    pub pixdim: [f64; 8],
    pub vox_offset: f64,
    pub scl_slope: f64,
    pub scl_inter: f64,
    pub qform_code: i32,
    pub sform_code: i32,
    /// `quatern_b`, `quatern_c`, `quatern_d`.
    pub quatern: [f64; 3],
    /// `qoffset_x`, `qoffset_y`, `qoffset_z`.
    pub qoffset: [f64; 3],
    /// `srow_x`, `srow_y`, `srow_z`.
    pub srow: [[f64; 4]; 3],
    pub xyzt_units: u8,
    pub intent_code: i32,
}

impl Header {
    /// The header at the start of `bytes`, the first bytes of a NIfTI file (decompressed), of
    /// either version: version 2 when its first field says 540 in either byte order.
    pub fn parse(path: &Path, bytes: &[u8]) -> Result<Self> {
        if let Some(endian) = version_2(bytes) {
            return parse_2(path, bytes, endian);
        }
        let h = NiftiHeader::from_reader(bytes)
            .map_err(|e| Error::format(path, format!("not a valid NIfTI-1 header: {e}")))?;
        Self::of_1(path, &h)
    }

    /// Reads the header from `reader`, the file's (decompressed) bytes from its start.
    pub fn read(path: &Path, reader: impl Read) -> Result<Self> {
        let mut bytes = Vec::with_capacity(SIZE_2);
        reader
            .take(SIZE_2 as u64)
            .read_to_end(&mut bytes)
            .map_err(|e| Error::io(path, e))?;
        Self::parse(path, &bytes)
    }

    /// A NIfTI-1 header the crate parsed.
    fn of_1(path: &Path, h: &NiftiHeader) -> Result<Self> {
        if h.sizeof_hdr != 348 {
            return Err(Error::format(
                path,
                format!("NIfTI-1 header size is {}, not 348", h.sizeof_hdr),
            ));
        }
        let single = match &h.magic {
            b"n+1\0" => true,
            b"ni1\0" => false,
            m => {
                return Err(Error::format(
                    path,
                    format!("NIfTI magic is {m:?}, not \"n+1\" or \"ni1\""),
                ));
            }
        };
        let wide = |v: [f32; 4]| v.map(f64::from);
        Ok(Self {
            version: 1,
            single,
            endian: match h.endianness {
                Endianness::Little => Endian::Little,
                Endianness::Big => Endian::Big,
            },
            datatype: h.datatype,
            // The header's dims are signed 16-bit numbers (the crate reads them unsigned).
            dim: h.dim.map(|d| i64::from(d as i16)),
            pixdim: h.pixdim.map(f64::from),
            vox_offset: f64::from(h.vox_offset),
            scl_slope: f64::from(h.scl_slope),
            scl_inter: f64::from(h.scl_inter),
            qform_code: i32::from(h.qform_code),
            sform_code: i32::from(h.sform_code),
            quatern: [h.quatern_b, h.quatern_c, h.quatern_d].map(f64::from),
            qoffset: [h.quatern_x, h.quatern_y, h.quatern_z].map(f64::from),
            srow: [wide(h.srow_x), wide(h.srow_y), wide(h.srow_z)],
            xyzt_units: h.xyzt_units,
            intent_code: i32::from(h.intent_code),
        })
    }

    /// The header's size in bytes: where the extensions or the voxels of a single file may start.
    pub fn size(&self) -> usize {
        if self.version == 2 { SIZE_2 } else { 348 }
    }
}

/// The byte order of a NIfTI-2 header at the start of `bytes`, when it is one.
fn version_2(bytes: &[u8]) -> Option<Endian> {
    let first: [u8; 4] = bytes.get(..4)?.try_into().ok()?;
    let size = SIZE_2 as i32;
    if i32::from_le_bytes(first) == size {
        Some(Endian::Little)
    } else if i32::from_be_bytes(first) == size {
        Some(Endian::Big)
    } else {
        None
    }
}

/// Whether `bytes` start with a NIfTI-2 header's size and magic (the sniffing test).
pub(super) fn looks_like_2(bytes: &[u8]) -> bool {
    version_2(bytes).is_some() && matches!(bytes.get(4..8), Some(b"n+2\0" | b"ni2\0"))
}

/// Parses a NIfTI-2 header in byte order `endian`.
fn parse_2(path: &Path, bytes: &[u8], endian: Endian) -> Result<Header> {
    if bytes.len() < SIZE_2 {
        return Err(Error::format(
            path,
            format!(
                "the NIfTI-2 header is cut short: {} of its {SIZE_2} bytes",
                bytes.len()
            ),
        ));
    }
    let single = match &bytes[4..8] {
        b"n+2\0" => true,
        b"ni2\0" => false,
        m => {
            return Err(Error::format(
                path,
                format!("NIfTI-2 magic is {m:?}, not \"n+2\" or \"ni2\""),
            ));
        }
    };
    if bytes[8..12] != EOL_CHECK {
        return Err(Error::format(
            path,
            "the NIfTI-2 header's line-ending check bytes are altered (was the file \
             transferred as text?)",
        ));
    }
    let f = Fields { bytes, endian };
    let f64s = |at: usize| -> [f64; 4] { std::array::from_fn(|k| f.f64(at + 8 * k)) };
    Ok(Header {
        version: 2,
        single,
        endian,
        datatype: f.i16(12),
        dim: std::array::from_fn(|k| f.i64(16 + 8 * k)),
        pixdim: std::array::from_fn(|k| f.f64(104 + 8 * k)),
        vox_offset: f.i64(168) as f64,
        scl_slope: f.f64(176),
        scl_inter: f.f64(184),
        qform_code: f.i32(344),
        sform_code: f.i32(348),
        quatern: std::array::from_fn(|k| f.f64(352 + 8 * k)),
        qoffset: std::array::from_fn(|k| f.f64(376 + 8 * k)),
        srow: [f64s(400), f64s(432), f64s(464)],
        // Only the low byte holds units (spatial in bits 0-2, temporal in 3-5).
        xyzt_units: (f.i32(500) & 0xff) as u8,
        intent_code: f.i32(504),
    })
}

/// The fields of a header of at least [`SIZE_2`] bytes, in byte order `endian`.
struct Fields<'a> {
    bytes: &'a [u8],
    endian: Endian,
}

impl Fields<'_> {
    fn array<const N: usize>(&self, at: usize) -> [u8; N] {
        let mut b: [u8; N] = self.bytes[at..at + N]
            .try_into()
            .expect("within the header");
        if self.endian == Endian::Big {
            b.reverse();
        }
        b
    }

    fn i16(&self, at: usize) -> i16 {
        i16::from_le_bytes(self.array(at))
    }

    fn i32(&self, at: usize) -> i32 {
        i32::from_le_bytes(self.array(at))
    }

    fn i64(&self, at: usize) -> i64 {
        i64::from_le_bytes(self.array(at))
    }

    fn f64(&self, at: usize) -> f64 {
        f64::from_le_bytes(self.array(at))
    }
}
