//! The cell map behind quantized trilinear sampling: per cell of the voxel grid (indexed by its
//! lower corner voxel), the bin that all eight corners safely share, or [`MIXED`]. A trilinear
//! sample is a convex combination of its cell's corners, so it lies in their common bin: where
//! the map knows the bin, no interpolation is needed.

use std::ops::Range;

use rayon::prelude::*;

use super::wide::wide;
use super::{Quantizer, Volume, Voxel};

/// Voxels per parallel task.
const CHUNK: usize = 1 << 16;

/// Marks a cell whose corners do not all lie safely inside one bin.
pub const MIXED: u8 = u8::MAX;

/// Per cell: the bin its corners share, or [`MIXED`], at the linear index of its lower corner
/// voxel (one byte per voxel). Entries of voxels on the last plane of an axis with more than one
/// voxel are no cell's and must not be read.
///
/// A corner counts as in a bin only with a margin for the rounding of f32 interpolation.
///
/// Returns the map and, per voxel, the bin it safely lies in or [`MIXED`] (near a bin edge, or
/// missing): samples on the voxel grid read that, and compute only the [`MIXED`] ones.
pub fn cell_map(volume: &Volume, q: &Quantizer) -> (Vec<u8>, Vec<u8>) {
    crate::volume::with_voxels!(volume.data(), |voxels| cell_map_of(voxels, volume, q))
}

/// The cell map of [`cell_map`] alone, made a band of planes at a time so that only the map
/// (one byte a voxel) is held whole: for voxels whose bins a table gives exactly, which need no
/// per-voxel map.
pub fn cells_only(volume: &Volume, q: &Quantizer) -> Vec<u8> {
    cells_window(volume, q, 0..volume.len())
}

/// [`cell_map`] over `voxels`, the voxels of `volume` in their own type.
fn cell_map_of<T: Voxel>(voxels: &[T], volume: &Volume, q: &Quantizer) -> (Vec<u8>, Vec<u8>) {
    let safe_bin = safe_bin_of::<T>(volume, q);
    let mut bins: Vec<u8> = vec![0; voxels.len()];
    bins.par_chunks_mut(CHUNK)
        .zip(voxels.par_chunks(CHUNK))
        .for_each(|(b, v)| wide(|| b.iter_mut().zip(v).for_each(|(b, &v)| *b = safe_bin(v))));
    let corners = Corners::of(volume.dims());
    let mut cells = vec![0; bins.len()];
    let with_corners = corners.cells(bins.len());
    cells[with_corners..].fill(MIXED);
    cells[..with_corners]
        .par_chunks_mut(CHUNK)
        .enumerate()
        .for_each(|(c, out)| corners.label(out, &bins[c * CHUNK..]));
    (cells, bins)
}

/// The entries `range` (linear voxel indices) of [`cells_only`]'s map, made alone: the map of a
/// window of planes, for a walk that holds no more (entries of the last plane are [`MIXED`], as
/// there).
pub fn cells_window(volume: &Volume, q: &Quantizer, range: Range<usize>) -> Vec<u8> {
    crate::volume::with_voxels!(volume.data(), |voxels| {
        banded_cells(voxels, volume, q, range)
    })
}

/// The entries `range` of [`cell_map`]'s per-voxel map: the bin each voxel safely lies in, or
/// [`MIXED`].
pub fn voxel_map_window(volume: &Volume, q: &Quantizer, range: Range<usize>) -> Vec<u8> {
    crate::volume::with_voxels!(volume.data(), |voxels| {
        let safe_bin = safe_bin_of(volume, q);
        let mut bins = vec![0u8; range.len()];
        bins.par_chunks_mut(CHUNK)
            .zip(voxels[range].par_chunks(CHUNK))
            .for_each(|(b, v)| wide(|| b.iter_mut().zip(v).for_each(|(b, &v)| *b = safe_bin(v))));
        bins
    })
}

/// The entries `range` of [`cells_only`]'s map over `voxels`: each task makes the safe bins of
/// its band of cells and of the corners beyond it (one plane more) in a buffer of its own.
fn banded_cells<T: Voxel>(
    voxels: &[T],
    volume: &Volume,
    q: &Quantizer,
    range: Range<usize>,
) -> Vec<u8> {
    let safe_bin = safe_bin_of::<T>(volume, q);
    let corners = Corners::of(volume.dims());
    let [nx, ny, _] = volume.dims();
    // Eight planes a band: the plane of corners beyond a band is made twice, an eighth more.
    let band = CHUNK.max(8 * nx * ny);
    let with_corners = corners.cells(voxels.len()).clamp(range.start, range.end) - range.start;
    let mut cells = vec![0; range.len()];
    cells[with_corners..].fill(MIXED);
    cells[..with_corners]
        .par_chunks_mut(band)
        .enumerate()
        .for_each(|(c, out)| {
            let start = range.start + c * band;
            let end = (start + out.len() + corners.reach).min(voxels.len());
            let mut bins = vec![0u8; end - start];
            wide(|| {
                bins.iter_mut()
                    .zip(&voxels[start..end])
                    .for_each(|(b, &v)| *b = safe_bin(v));
            });
            for (k, out) in out.chunks_mut(CHUNK).enumerate() {
                corners.label(out, &bins[k * CHUNK..]);
            }
        });
    cells
}

/// The offsets from a cell's lower corner voxel to its seven other corners.
struct Corners {
    offsets: [usize; 7],
    /// The farthest of them.
    reach: usize,
}

impl Corners {
    fn of([nx, ny, nz]: [usize; 3]) -> Self {
        let next = |n: usize, stride: usize| if n > 1 { stride } else { 0 };
        let (x, y, z) = (next(nx, 1), next(ny, nx), next(nz, nx * ny));
        Self {
            offsets: [x, y, y + x, z, z + x, z + y, z + y + x],
            reach: z + y + x,
        }
    }

    /// How many of `voxels` entries have a whole cell: those before the last plane's.
    fn cells(&self, voxels: usize) -> usize {
        voxels - self.reach
    }

    /// Labels the cells `out` whose lower corners' safe bins start `bins` (which reaches the
    /// farthest corner of the last): a cell is uniform when its eight corners share a bin.
    fn label(&self, out: &mut [u8], bins: &[u8]) {
        let here = &bins[..out.len()];
        let others = self.offsets.map(|o| &bins[o..o + out.len()]);
        // Corner by corner, each loop simple enough to be vectorized: first the bits in which
        // any corner differs from the lower one, then the label.
        wide(|| {
            out.fill(0);
            for other in others {
                for ((o, &b), &c) in out.iter_mut().zip(here).zip(other) {
                    *o |= b ^ c;
                }
            }
            for (o, &b) in out.iter_mut().zip(here) {
                *o = if *o == 0 { b } else { MIXED };
            }
        });
    }
}

/// The bin a voxel of `volume` safely lies in under `q`, or [`MIXED`] (near a bin edge, or
/// missing).
fn safe_bin_of<T: Voxel>(volume: &Volume, q: &Quantizer) -> impl Fn(T) -> u8 + Sync {
    let (scale, margin) = scale_and_margin(volume, q);
    let last = (q.bins() - 1) as f64;
    // The quantizer's range: the volume's own, or for a pyramid level that of level 0.
    let (min, _, _) = q.formula();
    // 2^52: adding it to a number in 0..2^51 leaves that number rounded to a whole one in the
    // low bits of the sum.
    let whole = 2f64.powi(52);
    // Without branches (`&` and `|`, not `&&` and `||`), so that the compiler can work on
    // several voxels at once.
    #[allow(clippy::needless_bitwise_bool)]
    move |v: T| -> u8 {
        let t = (f64::from(v.to_f32()) - min) * scale;
        // The bin is ⌊t⌋ clamped to 0..B - 1: c rounded down. A NaN voxel gives 0 here, and is
        // marked below.
        let c = if t > 0.0 { t } else { 0.0 };
        let c = if c < last { c } else { last };
        let sum = c + whole;
        let rounded_up = sum - whole > c;
        let b = (sum.to_bits() as u8).wrapping_sub(u8::from(rounded_up));
        let bf = f64::from(b);
        let low_ok = (b == 0) | (t - bf >= margin);
        let high_ok = (bf == last) | (bf + 1.0 - t >= margin);
        if low_ok & high_ok & !t.is_nan() {
            b
        } else {
            MIXED
        }
    }
}

/// Bins per unit of intensity, and how far (in bins) a corner must lie from a bin edge to count
/// as safely inside its bin: trilinear interpolation in f32 is within a few ulps of the largest
/// corner magnitude, so 16 ulps in bin units.
fn scale_and_margin(volume: &Volume, q: &Quantizer) -> (f64, f64) {
    let s = volume.stats();
    let (_, span, _) = q.formula();
    let scale = if span > 0.0 {
        q.bins() as f64 / span
    } else {
        0.0
    };
    let magnitude = f64::from(s.min.abs().max(s.max.abs()));
    (
        scale,
        16.0 * f64::from(f32::EPSILON) * magnitude * scale + 1e-9,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::Lcg;
    use crate::volume::{VoxelType, Voxels};

    /// The cell map written plainly: what the branch-free passes must reproduce.
    fn plain_cell_map(volume: &Volume, q: &Quantizer) -> (Vec<u8>, Vec<u8>) {
        let s = volume.stats();
        let (scale, margin) = scale_and_margin(volume, q);
        let last = q.bins() - 1;
        let bins: Vec<u8> = volume
            .voxels()
            .iter()
            .map(|&v| {
                if v.is_nan() {
                    return MIXED;
                }
                let t = (f64::from(v) - f64::from(s.min)) * scale;
                let b = (t.max(0.0) as usize).min(last);
                let low_ok = b == 0 || t - b as f64 >= margin;
                let high_ok = b == last || (b + 1) as f64 - t >= margin;
                if low_ok && high_ok { b as u8 } else { MIXED }
            })
            .collect();
        let [nx, ny, nz] = volume.dims();
        let mut cells = vec![MIXED; bins.len()];
        for z in 0..nz.saturating_sub(1).max(usize::from(nz == 1)) {
            for y in 0..ny.saturating_sub(1).max(usize::from(ny == 1)) {
                for x in 0..nx.saturating_sub(1).max(usize::from(nx == 1)) {
                    let at = |dx: usize, dy: usize, dz: usize| {
                        let (x, y, z) = (
                            (x + dx).min(nx - 1),
                            (y + dy).min(ny - 1),
                            (z + dz).min(nz - 1),
                        );
                        bins[x + nx * (y + ny * z)]
                    };
                    let b = at(0, 0, 0);
                    let same = (0..8).all(|k| at(k & 1, k >> 1 & 1, k >> 2) == b);
                    cells[x + nx * (y + ny * z)] = if same { b } else { MIXED };
                }
            }
        }
        (cells, bins)
    }

    /// Voxels on, near and between bin edges of `bins` bins over 0..=100, with missing ones.
    fn awkward(dims: [usize; 3], bins: usize) -> Volume {
        let width = 100.0 / bins as f64;
        let mut lcg = Lcg::new(5);
        let data = (0..dims.iter().product::<usize>())
            .map(|i| {
                let r = lcg.next_u64() >> 33;
                let edge = (r % (bins as u64 + 1)) as f64 * width;
                match r % 7 {
                    0 => f32::NAN,
                    1 => edge as f32,
                    2 => (edge + 1e-6) as f32,
                    3 => (edge - 1e-6).max(0.0) as f32,
                    // Runs of one value, so that some cells are uniform.
                    _ => ((i / 5) % bins) as f32 * width as f32 + 0.5 * width as f32,
                }
            })
            .collect();
        let mut v = Volume::new(dims, [1.0; 3], VoxelType::F32, data).unwrap();
        // Pin the range to 0..=100 whatever the draws.
        v = Volume::new(dims, [1.0; 3], VoxelType::F32, {
            let mut d = v.voxels().to_vec();
            d[0] = 0.0;
            d[1] = 100.0;
            d
        })
        .unwrap();
        v
    }

    #[test]
    fn cells_made_in_bands_are_the_whole_map() {
        // Bands of 65536 cells: several, ending inside a plane and on one.
        for dims in [[70, 50, 60], [64, 64, 40], [9, 7, 5], [300, 1, 400]] {
            let n = dims.iter().product::<usize>();
            let mut lcg = Lcg::new(3);
            let data: Vec<i16> = (0..n)
                .map(|i| {
                    let r = (lcg.next_u64() >> 40) as i32;
                    // Layers three planes thick, noise of a unit: uniform cells inside a
                    // layer, mixed ones between.
                    let z = (i / (dims[0] * dims[1])) as i32;
                    (z / 3 % 9 * 400 + r % 3 - 950) as i16
                })
                .collect();
            let v =
                Volume::from_voxels(dims, [1.0; 3], VoxelType::I16, Voxels::owned(data)).unwrap();
            let q = v.quantizer(32).unwrap();
            let (cells, _) = cell_map(&v, &q);
            assert!(cells.contains(&MIXED) && cells.iter().any(|&c| c != MIXED));
            assert_eq!(cells_only(&v, &q), cells, "{dims:?}");
        }
    }

    #[test]
    fn the_cell_map_is_the_plain_one() {
        for dims in [[9, 7, 5], [1, 6, 4], [5, 1, 1], [70, 3, 2]] {
            for bins in [2, 7, 32, 255] {
                let v = awkward(dims, bins);
                let q = v.quantizer(bins).unwrap();
                let (cells, voxel_bins) = cell_map(&v, &q);
                let (plain_cells, plain_bins) = plain_cell_map(&v, &q);
                assert_eq!(voxel_bins, plain_bins, "{dims:?} {bins} bins");
                assert!(voxel_bins.contains(&MIXED) && voxel_bins.iter().any(|&b| b != MIXED));
                // Entries without a whole cell are never read: compare the others.
                let [nx, ny, nz] = dims;
                for (i, (&c, &p)) in cells.iter().zip(&plain_cells).enumerate() {
                    let (x, y, z) = (i % nx, i / nx % ny, i / (nx * ny));
                    let whole = (nx == 1 || x + 1 < nx)
                        && (ny == 1 || y + 1 < ny)
                        && (nz == 1 || z + 1 < nz);
                    if whole {
                        assert_eq!(c, p, "{dims:?} {bins} bins, cell {i}");
                    }
                }
            }
        }
    }

    #[test]
    fn a_safe_bin_is_the_quantizers_bin() {
        let v = awkward([40, 30, 20], 32);
        let q = v.quantizer(32).unwrap();
        let (_, voxel_bins) = cell_map(&v, &q);
        for (&b, &x) in voxel_bins.iter().zip(v.voxels()) {
            if b != MIXED {
                assert_eq!(q.bin(x), Some(b), "{x}");
            } else if x.is_nan() {
                assert_eq!(q.bin(x), None);
            }
        }
    }

    #[test]
    fn a_cell_is_mixed_whenever_one_corner_differs() {
        // 255 bins over 0..=255: bin b holds b + 0.5. Labels that differ in one bit only, and
        // a missing corner (MIXED is all ones) beside bin 127.
        let value = |b: u8| f32::from(b) + 0.5;
        for (a, b) in [
            (127, None),
            (3, Some(131)),
            (0, Some(128)),
            (254, Some(126)),
            (9, Some(9)),
        ] {
            for corner in 0..8 {
                let mut data = vec![value(a); 8];
                data[corner] = b.map_or(f32::NAN, value);
                // Fix the range to 0..=255 in a second cell.
                data.extend([0.0, 255.0, 0.0, 255.0, 0.0, 255.0, 0.0, 255.0]);
                let v = Volume::new([2, 2, 4], [1.0; 3], VoxelType::F32, data).unwrap();
                let (cells, _) = cell_map(&v, &v.quantizer(255).unwrap());
                let expected = if b == Some(a) { a } else { MIXED };
                assert_eq!(cells[0], expected, "{a} beside {b:?} at corner {corner}");
            }
        }
    }
}
