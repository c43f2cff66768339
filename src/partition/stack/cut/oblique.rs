//! The cut along an oblique axis: the volume resampled on the axis's ray lattice, each sample
//! quantized into its ray's column, and each slice's sum and count of counted values, in one
//! pass.
//!
//! The rays are walked as the view search walks them, in tiles of neighbouring rays advancing
//! together a sample at a time, so that the voxels a tile reads stay in the caches from one
//! sample to the next, and the symbols are written in place (docs/performance.md, "The
//! partition's oblique cut").

use std::ops::Range;

use rayon::prelude::*;

use super::super::{Column, Lattice, MISSING, SliceStack};
use super::{Cutter, RowSink, SliceSums};
use crate::error::Result;
use crate::geometry::lattice::Ray;
use crate::progress::Monitor;
use crate::volume::interpolate::Interpolator;
use crate::volume::{Voxel, VoxelBox};

/// Lattice rows a parallel task cuts.
const BAND_ROWS: usize = 16;

/// Rays along a row a tile takes: a tile is a band's rays of this many neighbouring columns.
const TILE_COLUMNS: i64 = 16;

/// Where the rays of a strip of lattice rows lie: each ray's column (in row order, then `i`),
/// its `i`, and where each row's rays begin among them.
struct Rays {
    columns: Vec<Column>,
    is: Vec<i64>,
    /// Per row of the strip, and one past the last: the index of its first ray.
    row_starts: Vec<usize>,
}

impl Rays {
    /// The rays of lattice rows `rows` that meet the volume, their symbols laid out one after
    /// another from 0.
    fn of(lattice: &Lattice, rows: &[i64], k_first: i64) -> Self {
        // Per row, each ray's `i`, first slice and length (not the rays: they are made again
        // as they are walked).
        let per_row: Vec<Vec<(i64, u32, u32)>> = rows
            .par_iter()
            .map(|&j| {
                let ((i0, i1), _) = lattice.ray_ranges();
                let Some((a, b)) = lattice.row_span(j) else {
                    return Vec::new();
                };
                (a.max(i0)..=b.min(i1))
                    .filter_map(|i| {
                        let ray = lattice.ray(i, j)?;
                        Some((i, (ray.k0 - k_first) as u32, ray.len() as u32))
                    })
                    .collect()
            })
            .collect();
        let n = per_row.iter().map(Vec::len).sum();
        let mut rays = Self {
            columns: Vec::with_capacity(n),
            is: Vec::with_capacity(n),
            row_starts: Vec::with_capacity(rows.len() + 1),
        };
        let mut offset = 0;
        for row in per_row {
            rays.row_starts.push(rays.columns.len());
            for (i, first, len) in row {
                rays.columns.push(Column { offset, first, len });
                rays.is.push(i);
                offset += len as usize;
            }
        }
        rays.row_starts.push(rays.columns.len());
        rays
    }

    /// The number of symbols of all the rays.
    fn symbols(&self) -> usize {
        self.columns.last().map_or(0, |c| c.offset + c.len as usize)
    }

    /// Per slice, the rays crossing it: one position a ray.
    fn positions(&self, slices: usize) -> Vec<u64> {
        let mut change = vec![0i64; slices + 1];
        for c in &self.columns {
            change[c.first as usize] += 1;
            change[(c.first + c.len) as usize] -= 1;
        }
        let mut open = 0;
        change[..slices]
            .iter()
            .map(|&d| {
                open += d;
                open as u64
            })
            .collect()
    }
}

/// One band's part of the cut: its rows (indices into the strip's), its rays' symbols, and the
/// index of its first symbol in the strip.
struct Band<'s> {
    rows: Range<usize>,
    out: &'s mut [u8],
    base: usize,
}

/// Where a tile's ray writes its symbols, and which of its band's rows it is on.
struct TileRay {
    ray: Ray,
    at: usize,
    row: usize,
}

impl Cutter<'_> {
    /// The stack of lattice rows `rows` (counted from the lattice's first). With `sums`, each
    /// row's sums and counts of counted values per slice are handed to it, in row order.
    pub(super) fn along_lattice(
        &self,
        lattice: &Lattice,
        rows: Range<usize>,
        mut sums: Option<RowSink>,
        monitor: &Monitor,
    ) -> Result<SliceStack> {
        let (_, (j0, _)) = lattice.ray_ranges();
        let (k_first, _) = lattice.sample_range();
        let rows: Vec<i64> = rows.map(|r| j0 + r as i64).collect();
        let rays = Rays::of(lattice, &rows, k_first);
        // Every symbol is written by the walk below.
        let mut symbols = vec![0u8; rays.symbols()];
        let mut bands = Vec::with_capacity(rows.len().div_ceil(BAND_ROWS));
        let mut rest = symbols.as_mut_slice();
        for start in (0..rows.len()).step_by(BAND_ROWS) {
            let end = (start + BAND_ROWS).min(rows.len());
            let (first, last) = (rays.row_starts[start], rays.row_starts[end]);
            let base = rays.columns.get(first).map_or(0, |c| c.offset);
            let len = rays.columns[first..last]
                .iter()
                .map(|c| c.len as usize)
                .sum();
            let (out, after) = rest.split_at_mut(len);
            rest = after;
            bands.push(Band {
                rows: start..end,
                out,
                base,
            });
        }
        let counting = sums.is_some();
        crate::volume::with_voxels!(self.volume.data(), |data| {
            let it = Interpolator::over(data, self.volume.dims());
            // A few bands per thread at a time, so that their rows' sums are held only until
            // they are added.
            let group = 4 * rayon::current_num_threads();
            while !bands.is_empty() {
                let taken: Vec<Band> = bands.drain(..group.min(bands.len())).collect();
                let parts = taken
                    .into_par_iter()
                    .map(|band| {
                        let n = band.rows.len() as u64;
                        let tiles = (&rows[..], &rays);
                        let sums = self.cut_band(&it, lattice, tiles, band, (k_first, counting));
                        monitor.advance(n)?;
                        Ok(sums)
                    })
                    .collect::<Result<Vec<Vec<SliceSums>>>>()?;
                if let Some(sink) = sums.as_deref_mut() {
                    parts.iter().flatten().for_each(&mut *sink);
                }
            }
            Ok::<(), crate::error::Error>(())
        })?;
        let positions = rays.positions(self.slices());
        Ok(self.bare(rays.columns, symbols, positions))
    }

    /// Cuts one band's rays, a tile of neighbouring columns at a time (tiles aligned to
    /// multiples of [`TILE_COLUMNS`] along the rows, whatever the band), every ray of the tile a
    /// sample at a time in turn; returns each row's sums when `counting`.
    fn cut_band<T: Voxel>(
        &self,
        it: &Interpolator<T>,
        lattice: &Lattice,
        (rows, rays): (&[i64], &Rays),
        band: Band,
        (k_first, counting): (i64, bool),
    ) -> Vec<SliceSums> {
        let Band {
            rows: range,
            out,
            base,
        } = band;
        let slices = if counting { self.slices() } else { 0 };
        let mut sums: Vec<SliceSums> = range.clone().map(|_| SliceSums::new(slices)).collect();
        // Per row of the band: its next ray not yet walked, and one past its last.
        let mut next: Vec<usize> = range.clone().map(|r| rays.row_starts[r]).collect();
        let ends = &rays.row_starts[range.start + 1..=range.end];
        let mut tile: Vec<TileRay> = Vec::with_capacity(BAND_ROWS * TILE_COLUMNS as usize);
        // The tile of the lowest column not yet walked, while one is left.
        while let Some(lowest) = (0..range.len())
            .filter(|&r| next[r] < ends[r])
            .map(|r| rays.is[next[r]])
            .min()
        {
            let to = (lowest.div_euclid(TILE_COLUMNS) + 1) * TILE_COLUMNS;
            tile.clear();
            for r in 0..range.len() {
                while next[r] < ends[r] && rays.is[next[r]] < to {
                    let c = next[r];
                    let ray = lattice
                        .ray(rays.is[c], rows[range.start + r])
                        .expect("a ray met the volume when its column was laid out");
                    let at = rays.columns[c].offset - base;
                    tile.push(TileRay { ray, at, row: r });
                    next[r] += 1;
                }
            }
            self.cut_tile(it, &tile, out, (&mut sums, k_first));
        }
        sums
    }

    /// The symbols of a tile's rays into `out` (each from its offset there), their counted
    /// values into their rows' `sums` (when those have slices): a sample of every ray at a
    /// time.
    fn cut_tile<T: Voxel>(
        &self,
        it: &Interpolator<T>,
        tile: &[TileRay],
        out: &mut [u8],
        (sums, k_first): (&mut [SliceSums], i64),
    ) {
        let Some(k0) = tile.iter().map(|t| t.ray.k0).min() else {
            return;
        };
        let k1 = tile.iter().map(|t| t.ray.k1).max().unwrap_or(k0);
        let counting = sums.first().is_some_and(|s| !s.sums.is_empty());
        for k in k0..=k1 {
            let s = (k - k_first) as usize;
            for &TileRay { ref ray, at, row } in tile {
                if k < ray.k0 || k > ray.k1 {
                    continue;
                }
                let p = ray.at(k);
                let v = it.sample(p);
                let background = self.background.contains(it.nearest(p), v);
                out[at + (k - ray.k0) as usize] = if background {
                    MISSING
                } else {
                    self.quantizer.bin(v).unwrap_or(MISSING)
                };
                if counting && !background && v.is_finite() {
                    let sums = &mut sums[row];
                    sums.sums[s] += f64::from(v);
                    sums.counts[s] += 1;
                }
            }
        }
    }
}

/// The box of voxels the samples of lattice rows `rows` read: the box around each ray's two
/// ends (its samples lie between them), widened by a voxel for the trilinear corners; with
/// `planes`, of the voxels in those planes along z alone, each ray's segment clipped to where
/// its samples read a voxel of them (z from a plane before the first to the last: a sample at
/// z reads planes ⌊z⌋ and ⌊z⌋ + 1), so that a slanted slab of rays holds in a box a layer of
/// planes far less than in one box.
pub(super) fn lattice_box(
    lattice: &Lattice,
    rows: &Range<usize>,
    dims: [usize; 3],
    planes: Option<&Range<usize>>,
) -> Option<VoxelBox> {
    let ((i0, i1), (j0, _)) = lattice.ray_ranges();
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    let clip = planes.map(|p| (p.start as f64 - 1.0, p.end as f64));
    for r in rows.clone() {
        for i in i0..=i1 {
            let Some(ray) = lattice.ray(i, j0 + r as i64) else {
                continue;
            };
            let (a, b) = (ray.at(ray.k0), ray.at(ray.k1));
            let Some((s0, s1)) = clip.map_or(Some((0.0, 1.0)), |z| clipped(a[2], b[2], z)) else {
                continue;
            };
            for s in [s0, s1] {
                for m in 0..3 {
                    let p = a[m] + s * (b[m] - a[m]);
                    (lo[m], hi[m]) = (lo[m].min(p), hi[m].max(p));
                }
            }
        }
    }
    if lo[0] > hi[0] {
        return None;
    }
    let first: [usize; 3] =
        std::array::from_fn(|m| (lo[m].max(0.0).floor() as usize).min(dims[m] - 1));
    let last: [usize; 3] =
        std::array::from_fn(|m| (hi[m].max(0.0).floor() as usize + 1).min(dims[m] - 1));
    Some(VoxelBox {
        origin: first,
        size: std::array::from_fn(|m| last[m] + 1 - first[m]),
    })
}

/// The part `(s0, s1)` of the segment from z = `a` to z = `b` (s from 0 to 1) within
/// `[lo, hi]`, or `None` when it never is.
fn clipped(a: f64, b: f64, (lo, hi): (f64, f64)) -> Option<(f64, f64)> {
    if a == b {
        return (lo <= a && a <= hi).then_some((0.0, 1.0));
    }
    let (t0, t1) = ((lo - a) / (b - a), (hi - a) / (b - a));
    let (s0, s1) = (t0.min(t1).max(0.0), t0.max(t1).min(1.0));
    (s0 <= s1).then_some((s0, s1))
}
