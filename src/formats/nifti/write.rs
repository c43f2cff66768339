//! Writing NIfTI: version 1 (348 bytes, what every reader takes) unless an axis has more voxels
//! than its 16-bit dimensions hold, then version 2 (540 bytes, 64-bit dimensions, f64 fields).

use std::io::{BufWriter, Write};
use std::path::Path;

use flate2::Compression;
use flate2::write::GzEncoder;

use super::DATATYPES;
use crate::error::Result;
use crate::formats::Staged;
use crate::formats::write::{Body, VolumeHeader, check_disk_room, write_whole};
use crate::geometry::world::Quaternion;
use crate::volume::Volume;

/// Writes `volume` as a single-file NIfTI (`.nii`, or gzip-compressed when `gzip`) in its voxel
/// type (integer types rounded and clamped), with its voxel-to-world transform as both the sform
/// and the qform (code 1, scanner), so that every reader places it alike; a sheared transform has
/// no quaternion and is written as the sform alone. A volume of unknown orientation gets both
/// codes 0 and its spacing in `pixdim`. NIfTI-1, or NIfTI-2 when an axis has more than 32767
/// voxels.
///
/// The file is written to a temporary file beside `path` and renamed into place; an existing
/// `path` is replaced only when `force` is set.
pub fn write_nifti(path: &Path, volume: &Volume, gzip: bool, force: bool) -> Result<()> {
    write_whole(path, volume, force, |path, header, body| {
        stage(path, header, gzip, body)
    })
}

/// A volume of `header` whose voxels `body` writes, as NIfTI in a temporary file beside `path`,
/// to be put in place.
pub(crate) fn stage(
    path: &Path,
    header: &VolumeHeader,
    gzip: bool,
    body: Body<'_>,
) -> Result<Staged> {
    let bytes = header_bytes(header);
    super::super::stage(path, |file| {
        check_disk_room(file, header, gzip)?;
        let mut out = BufWriter::new(file);
        if gzip {
            let mut gz = GzEncoder::new(&mut out, Compression::fast());
            gz.write_all(&bytes)?;
            body(&mut gz)?;
            gz.finish()?;
        } else {
            out.write_all(&bytes)?;
            body(&mut out)?;
        }
        out.flush()
    })
}

/// Where each written field lies in a version's header, and how wide its numbers are.
struct Layout {
    /// The header's size, and its magic's place and bytes.
    size: usize,
    magic: (usize, &'static [u8]),
    datatype: usize,
    bitpix: usize,
    /// `dim`, `pixdim`, `vox_offset`, `scl_slope`, `descrip`, `qform_code`, `sform_code`,
    /// `quatern_b`, `qoffset_x`, `srow_x`, `xyzt_units`.
    dim: usize,
    pixdim: usize,
    vox_offset: usize,
    scl_slope: usize,
    descrip: usize,
    qform_code: usize,
    sform_code: usize,
    quatern: usize,
    qoffset: usize,
    srow: usize,
    xyzt_units: usize,
    /// Whether integers are 64-bit (codes 32-bit) and reals f64, rather than 16-bit and f32.
    wide: bool,
}

const NIFTI_1: Layout = Layout {
    size: 348,
    magic: (344, b"n+1\0"),
    datatype: 70,
    bitpix: 72,
    dim: 40,
    pixdim: 76,
    vox_offset: 108,
    scl_slope: 112,
    descrip: 148,
    qform_code: 252,
    sform_code: 254,
    quatern: 256,
    qoffset: 268,
    srow: 280,
    xyzt_units: 123,
    wide: false,
};

const NIFTI_2: Layout = Layout {
    size: 540,
    magic: (4, b"n+2\0\r\n\x1a\n"),
    datatype: 12,
    bitpix: 14,
    dim: 16,
    pixdim: 104,
    vox_offset: 168,
    scl_slope: 176,
    descrip: 240,
    qform_code: 344,
    sform_code: 348,
    quatern: 352,
    qoffset: 376,
    srow: 400,
    xyzt_units: 500,
    wide: true,
};

/// A header being written in `layout`.
struct Fields<'a> {
    bytes: Vec<u8>,
    layout: &'a Layout,
}

impl Fields<'_> {
    fn put(&mut self, at: usize, bytes: &[u8]) {
        self.bytes[at..at + bytes.len()].copy_from_slice(bytes);
    }

    /// An integer field: 16-bit in NIfTI-1, 64-bit in NIfTI-2.
    fn int(&mut self, at: usize, k: usize, v: i64) {
        if self.layout.wide {
            self.put(at + 8 * k, &v.to_le_bytes());
        } else {
            self.put(at + 2 * k, &(v as i16).to_le_bytes());
        }
    }

    /// A code field: 16-bit in NIfTI-1, 32-bit in NIfTI-2.
    fn code(&mut self, at: usize, v: i16) {
        if self.layout.wide {
            self.put(at, &i32::from(v).to_le_bytes());
        } else {
            self.put(at, &v.to_le_bytes());
        }
    }

    /// A real field: f32 in NIfTI-1, f64 in NIfTI-2.
    fn real(&mut self, at: usize, k: usize, v: f64) {
        if self.layout.wide {
            self.put(at + 8 * k, &v.to_le_bytes());
        } else {
            self.put(at + 4 * k, &(v as f32).to_le_bytes());
        }
    }
}

/// The little-endian NIfTI header of a volume of `header` and the 4 zero bytes that say no
/// extension follows: NIfTI-1 when every axis fits its 16-bit dimensions, else NIfTI-2.
fn header_bytes(header: &VolumeHeader) -> Vec<u8> {
    let dims = header.dims;
    let layout = if dims.iter().all(|&n| i16::try_from(n).is_ok()) {
        &NIFTI_1
    } else {
        &NIFTI_2
    };
    let l = layout;
    let mut h = Fields {
        bytes: vec![0u8; l.size + 4],
        layout,
    };
    let ty = header.voxel_type;
    let code = DATATYPES.iter().find(|d| d.1 == ty).map_or(16, |d| d.0);
    let t = &header.transform;
    let known = t.known;
    let zooms = if known { t.zooms() } else { header.spacing };
    let quaternion = if known { t.quaternion() } else { None };
    h.put(0, &(l.size as i32).to_le_bytes());
    if !l.wide {
        h.put(38, b"r"); // regular: NIfTI-1 keeps this ANALYZE field
    }
    let [nx, ny, nz] = dims.map(|n| n as i64);
    for (k, d) in [3, nx, ny, nz, 1, 1, 1, 1].into_iter().enumerate() {
        h.int(l.dim, k, d);
    }
    h.put(l.datatype, &code.to_le_bytes());
    h.put(l.bitpix, &(8 * ty.size() as i16).to_le_bytes());
    let qfac = quaternion.map_or(1.0, |q| q.qfac);
    let pixdim = [qfac, zooms[0], zooms[1], zooms[2], 1.0, 1.0, 1.0, 1.0];
    for (k, p) in pixdim.into_iter().enumerate() {
        h.real(l.pixdim, k, p);
    }
    let offset = (l.size + 4) as i64;
    if l.wide {
        h.put(l.vox_offset, &offset.to_le_bytes());
    } else {
        h.real(l.vox_offset, 0, offset as f64);
    }
    h.real(l.scl_slope, 0, 1.0);
    h.put(l.xyzt_units, &[2]); // mm
    let description = format!("slabscope {}", env!("CARGO_PKG_VERSION"));
    h.put(
        l.descrip,
        &description.as_bytes()[..description.len().min(79)],
    );
    if known {
        h.code(l.qform_code, i16::from(quaternion.is_some()));
        h.code(l.sform_code, 1); // scanner
        if let Some(q) = quaternion {
            let stored = if l.wide {
                [q.b, q.c, q.d]
            } else {
                stored_quaternion(q).map(f64::from)
            };
            for (k, v) in stored.into_iter().enumerate() {
                h.real(l.quatern, k, v);
            }
        }
        for r in 0..3 {
            h.real(l.qoffset, r, t.matrix[r][3]);
            for c in 0..4 {
                h.real(l.srow, 4 * r + c, t.matrix[r][c]);
            }
        }
    }
    h.put(l.magic.0, l.magic.1);
    h.bytes
}
/// The quaternion's `(b, c, d)` as f32. Near a rotation of 180° (`a` close to 0, as for LPS or
/// LSA axes) they are rounded so that `b² + c² + d²` is not below 1, so that readers (`nifti1_io`,
/// nibabel, ITK) take `a` as 0 rather than the square root of a rounding error, which would
/// turn the axes by up to a milliradian.
fn stored_quaternion(q: Quaternion) -> [f32; 3] {
    let sum = |v: &[f32; 3]| v.iter().map(|&x| f64::from(x) * f64::from(x)).sum::<f64>();
    let mut v = [q.b, q.c, q.d].map(|x| x as f32);
    if 1.0 - (q.b * q.b + q.c * q.c + q.d * q.d) >= 1e-6 {
        return v;
    }
    let largest = (0..3)
        .max_by(|&i, &j| v[i].abs().total_cmp(&v[j].abs()))
        .unwrap_or(0);
    for _ in 0..8 {
        if sum(&v) >= 1.0 {
            break;
        }
        // One unit in the last place away from zero.
        let x = v[largest];
        v[largest] = f32::from_bits(x.to_bits() + 1);
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formats::{LoadOptions, load};
    use crate::geometry::WorldTransform;
    use crate::volume::{VoxelType, Voxels};

    /// A volume `nx`×3×2 of u16 ramp values with a rotated, shifted transform.
    fn volume(nx: usize) -> Volume {
        let data: Vec<u16> = (0..nx * 6).map(|i| (i % 60_000) as u16).collect();
        let (c, s) = (0.6f64, 0.8f64);
        let linear = [
            [0.5 * c, -0.75 * s, 0.0],
            [0.5 * s, 0.75 * c, 0.0],
            [0.0, 0.0, 2.0],
        ];
        Volume::from_voxels(
            [nx, 3, 2],
            [0.5, 0.75, 2.0],
            VoxelType::U16,
            Voxels::owned(data),
        )
        .unwrap()
        .with_transform(WorldTransform::ras(linear, [-10.125, 3.5, 7.0]))
    }

    fn round_trip(nx: usize, version: &[u8]) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("v.nii");
        let v = volume(nx);
        write_nifti(&path, &v, false, false).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert!(
            bytes.windows(version.len()).take(600).any(|w| w == version),
            "{nx}"
        );
        let back = load(&path, &LoadOptions::default()).unwrap().volume;
        assert_eq!(back.dims(), v.dims());
        assert_eq!(back.voxel_type(), VoxelType::U16);
        for (i, x) in [0, 1, nx - 1, nx * 6 - 1].into_iter().enumerate() {
            let at = [x % nx, (x / nx) % 3, x / (3 * nx)];
            assert_eq!(back.value(at), v.value(at), "voxel {i}");
        }
        for r in 0..3 {
            for c in 0..4 {
                let (got, want) = (back.transform().matrix[r][c], v.transform().matrix[r][c]);
                assert!(
                    (got - want).abs() < 1e-6,
                    "affine[{r}][{c}]: {got} != {want}"
                );
            }
        }
    }

    #[test]
    fn nifti_1_unless_an_axis_is_longer_than_16_bits_hold() {
        round_trip(32_767, b"n+1\0");
        round_trip(32_768, b"n+2\0\r\n\x1a\n");
    }
}
