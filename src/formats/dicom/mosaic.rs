//! Siemens mosaics, as dcm2niix reads them: an image whose `ImageType` says `MOSAIC` holds
//! `NumberOfImagesInMosaic` slices (from the CSA image header, else from (0019,xx0A)) as tiles
//! of a square grid, `ceil(sqrt(N))` a row, filled row by row. Each tile becomes an image of its
//! own, placed where dcm2niix places it: the mosaic's `ImagePositionPatient` is the corner of
//! the whole mosaic, so the first tile is half the difference in size further along the rows
//! and the columns; tile `k` is `k` slice spacings along the normal, pointing as the CSA
//! `SliceNormalVector` does; the slice spacing is `SpacingBetweenSlices`, else `SliceThickness`.

use dicom_core::{Tag, VR};
use dicom_object::InMemDicomObject;
use dicom_object::mem::InMemElement;

use super::csa;
use super::elements::{float, floats, text};
use super::format::PixelFormat;
use super::protocol::{self, Numbering};
use crate::geometry::{cross, dot, normalize};

/// The most slices a mosaic may hold (dcm2niix's limit for slices of one volume).
pub(super) const MAX_TILES: u32 = 1024;

/// How one mosaic frame is cut into slices.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Mosaic {
    /// Slices (tiles holding one).
    pub tiles: u32,
    /// Tiles in a row (and rows of tiles).
    pub per_row: u32,
    /// Columns and rows of a tile.
    pub plane: [u16; 2],
    /// `SliceNormalVector` along the cross product of the orientation (+1) or against it (-1).
    pub sign: f64,
    /// Millimetres between slices.
    pub step: f64,
    /// Where the step comes from, for a note.
    pub step_from: &'static str,
    /// What the CSA series header says of the slices' numbering.
    pub numbering: Numbering,
}

/// One tile of a mosaic frame: which, and its size.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Tile {
    /// Its index in tile order (row by row).
    pub index: u32,
    /// Tiles in a row.
    pub per_row: u32,
    /// Columns and rows of a tile.
    pub plane: [u16; 2],
    /// Slices in the mosaic.
    pub of: u32,
    /// Where the slice spacing comes from.
    pub step_from: &'static str,
    /// What the CSA series header says of the slices' numbering.
    pub numbering: Numbering,
}

impl Tile {
    /// Whether pixel (`x`, `y`) of the mosaic frame lies in one of its slices' tiles (not in a
    /// trailing empty one).
    pub fn holds(&self, x: usize, y: usize) -> bool {
        let [tc, tr] = self.plane.map(usize::from);
        let (col, row) = (x / tc.max(1), y / tr.max(1));
        col < self.per_row as usize && row * self.per_row as usize + col < self.of as usize
    }

    /// Copies this tile of the mosaic frame `values` (`mosaic_cols` wide) into `plane`.
    pub fn cut(&self, values: &[f32], mosaic_cols: usize, plane: &mut [f32]) {
        let [tc, tr] = self.plane.map(usize::from);
        let x0 = (self.index % self.per_row) as usize * tc;
        let y0 = (self.index / self.per_row) as usize * tr;
        for (y, out) in plane.chunks_exact_mut(tc).take(tr).enumerate() {
            let start = (y0 + y) * mosaic_cols + x0;
            out.copy_from_slice(&values[start..start + tc]);
        }
    }
}

/// The element `element` of the private block of `group` that `creator` reserves (its
/// (gggg,00xx) names it); the block at 10 when no block is reserved at all (as dcm2niix reads
/// files whose creators were stripped).
fn private<'o>(
    obj: &'o InMemDicomObject,
    group: u16,
    creator: &str,
    element: u16,
) -> Option<&'o InMemElement> {
    let named = |block: u16| {
        text(obj, Tag(group, block)).is_some_and(|t| t.to_ascii_uppercase().contains(creator))
    };
    match (0x10..=0xFF).find(|&b| named(b)) {
        Some(block) => obj.get(Tag(group, (block << 8) | element)),
        None if obj.get(Tag(group, 0x10)).is_none() => obj.get(Tag(group, 0x1000 | element)),
        None => None,
    }
}

/// `NumberOfImagesInMosaic` of the `SIEMENS MR HEADER` block (0019,xx0A), an US (or its two
/// bytes, stored as UN).
fn mr_header_count(obj: &InMemDicomObject) -> Option<f64> {
    let e = private(obj, 0x0019, "SIEMENS MR HEADER", 0x0A)?;
    if e.vr() == VR::UN {
        let b = e.to_bytes().ok()?;
        return (b.len() == 2).then(|| f64::from(u16::from_le_bytes([b[0], b[1]])));
    }
    e.to_int::<u32>().ok().map(f64::from)
}

/// Whether `ImageType` says `MOSAIC`.
fn says_mosaic(obj: &InMemDicomObject) -> bool {
    text(obj, dicom_dictionary_std::tags::IMAGE_TYPE)
        .is_some_and(|t| t.to_ascii_uppercase().contains("MOSAIC"))
}

/// How the frames of `obj` (of `format`) are cut into slices when it is a mosaic; fails on a
/// mosaic whose slices cannot be known: a CSA header that cannot be read, no slice count, or one
/// the matrix cannot hold.
pub(super) fn of(obj: &InMemDicomObject, format: &PixelFormat) -> Result<Option<Mosaic>, String> {
    if !says_mosaic(obj) {
        return Ok(None);
    }
    let header = private(obj, 0x0029, "SIEMENS CSA HEADER", 0x10);
    let csa = match header {
        Some(e) => {
            let bytes = e
                .to_bytes()
                .map_err(|_| "Siemens mosaic: the CSA image header is not bytes".to_string())?;
            Some(csa::parse(&bytes).map_err(|m| format!("Siemens mosaic: CSA image header: {m}"))?)
        }
        None => None,
    };
    let count = csa
        .as_ref()
        .and_then(|c| c.number("NumberOfImagesInMosaic"))
        .or_else(|| mr_header_count(obj))
        .ok_or_else(|| {
            "ImageType says MOSAIC, but neither a CSA image header nor (0019,100A) gives \
             NumberOfImagesInMosaic"
                .to_string()
        })?;
    let tiles = Some(count.round())
        .filter(|n| (1.0..=f64::from(MAX_TILES)).contains(n))
        .ok_or_else(|| {
            format!("Siemens mosaic: NumberOfImagesInMosaic {count} (1 to {MAX_TILES} are read)")
        })? as u32;
    let per_row = (1..=tiles).find(|p| p * p >= tiles).unwrap_or(1);
    let [cols, rows] = [format.cols, format.rows].map(u32::from);
    if cols % per_row != 0 || rows % per_row != 0 {
        return Err(format!(
            "Siemens mosaic: {tiles} slices take {per_row}x{per_row} tiles, which do not \
             divide its {cols}x{rows} pixels"
        ));
    }
    let normal = csa.and_then(|c| c.numbers::<3>("SliceNormalVector"));
    let thickness = float(obj, dicom_dictionary_std::tags::SLICE_THICKNESS);
    let between = float(obj, dicom_dictionary_std::tags::SPACING_BETWEEN_SLICES);
    let (step, step_from) = match (between, thickness) {
        (Some(s), _) if s > 0.0 => (s, "SpacingBetweenSlices"),
        (_, Some(t)) if t > 0.0 => (t, "SliceThickness"),
        _ => (
            1.0,
            "no SpacingBetweenSlices or SliceThickness, 1 mm assumed",
        ),
    };
    let numbering = match private(obj, 0x0029, "SIEMENS CSA HEADER", 0x20) {
        Some(e) if tiles > 1 => e
            .to_bytes()
            .map_or(Numbering::Plain, |b| protocol::numbering(&b)),
        _ => Numbering::Plain,
    };
    let sign = match (normal, orientation_normal(obj)) {
        (Some(v), Some(n)) if dot(v, n) < 0.0 => -1.0,
        _ => 1.0,
    };
    Ok(Some(Mosaic {
        tiles,
        per_row,
        plane: [(cols / per_row) as u16, (rows / per_row) as u16],
        sign,
        step,
        step_from,
        numbering,
    }))
}

/// The cross product of `ImageOrientationPatient`'s directions, normalised.
fn orientation_normal(obj: &InMemDicomObject) -> Option<[f64; 3]> {
    let o = floats(obj, dicom_dictionary_std::tags::IMAGE_ORIENTATION_PATIENT)?;
    let (r, c) = (o.get(..3)?, o.get(3..6)?);
    normalize(cross([r[0], r[1], r[2]], [c[0], c[1], c[2]]))
}

impl Mosaic {
    /// Tile `index`.
    pub fn tile(&self, index: u32) -> Tile {
        Tile {
            index,
            per_row: self.per_row,
            plane: self.plane,
            of: self.tiles,
            step_from: self.step_from,
            numbering: self.numbering,
        }
    }

    /// Where tile `index` of a mosaic of `mosaic` columns and rows lies: its first pixel's
    /// centre (LPS mm), from the mosaic's `position`, `orientation` and pixel `spacing` (rows,
    /// columns).
    pub fn position(
        &self,
        index: u32,
        mosaic: [u16; 2],
        position: [f64; 3],
        orientation: [f64; 6],
        spacing: [f64; 2],
    ) -> Option<[f64; 3]> {
        let o = orientation;
        let r = normalize([o[0], o[1], o[2]])?;
        let c = normalize([o[3], o[4], o[5]])?;
        let n = normalize(cross(r, c))?;
        let valid = spacing.iter().all(|s| s.is_finite() && *s > 0.0);
        let [dy, dx] = if valid { spacing } else { [1.0, 1.0] };
        let half = |m: u16, t: u16| (f64::from(m) - f64::from(t)) / 2.0;
        let (sx, sy) = (
            half(mosaic[0], self.plane[0]),
            half(mosaic[1], self.plane[1]),
        );
        let along = f64::from(index) * self.step * self.sign;
        Some(std::array::from_fn(|k| {
            position[k] + r[k] * dx * sx + c[k] * dy * sy + n[k] * along
        }))
    }
}
