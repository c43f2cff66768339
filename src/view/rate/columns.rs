//! The walk of a lattice whose rays are voxel columns: samples are voxels, read in memory order a
//! row of columns at a time.

use rayon::prelude::*;

use super::{BinSampler, VoxelBins, count_in_parallel, serial_len, work_units};
use crate::error::Result;
use crate::geometry::lattice::Lattice;
use crate::measure::{BlockCounts, Counter, PartialCounts, Run};
use crate::progress::Monitor;
use crate::volume::Voxel;
use crate::volume::cells::MIXED;

/// Voxel columns along one axis, walked a few side by side (so that their work overlaps) in
/// memory order: item `i` holds the columns starting at voxels `offset + base·i + gap·c` for `c`
/// in `0..width` (fewer in the last item), and a column's sample `k` lies `stride·k` further.
struct Columns {
    offset: usize,
    count: usize,
    width: usize,
    gap: usize,
    base: usize,
    stride: usize,
    length: usize,
}

impl Columns {
    /// Rows along x are walked eight at a time; columns along y or z a row of them at a time.
    fn new([nx, ny, nz]: [usize; 3], axis: usize) -> Self {
        let (count, width, gap, base, stride, length) = match axis {
            0 => (ny * nz, 8, nx, 8 * nx, 1, nx),
            1 => (nx * nz, nx, 1, nx * ny, nx, ny),
            _ => (nx * ny, nx, 1, nx, nx * ny, nz),
        };
        Self {
            offset: 0,
            count,
            width,
            gap,
            base,
            stride,
            length,
        }
    }

    fn items(&self) -> usize {
        self.count.div_ceil(self.width)
    }

    /// Feeds the items `range` into `counts`; returns the number of columns.
    fn walk<T: Voxel>(
        &self,
        range: std::ops::Range<usize>,
        sampler: &BinSampler<T>,
        counts: &mut impl Counter,
    ) -> u64 {
        match sampler.voxel_bins() {
            VoxelBins::Map(map) => self.walk_with(range, counts, |at| match map[at] {
                MIXED => sampler.voxel_bin_at(at),
                b => Some(b),
            }),
            VoxelBins::Table(table) => {
                let voxels = sampler.voxels();
                self.walk_with(range, counts, |at| Some(table.bin(voxels[at])))
            }
        }
    }

    /// [`walk`](Self::walk) with the bin of voxel `at` from `bin`.
    fn walk_with(
        &self,
        range: std::ops::Range<usize>,
        counts: &mut impl Counter,
        bin: impl Fn(usize) -> Option<u8>,
    ) -> u64 {
        let mut runs = vec![Run::default(); self.width];
        let mut total = 0;
        for item in range {
            let width = self.width.min(self.count - item * self.width);
            total += width;
            for k in 0..self.length {
                let start = self.offset + item * self.base + k * self.stride;
                for (c, run) in runs[..width].iter_mut().enumerate() {
                    match bin(start + c * self.gap) {
                        Some(b) => counts.push_to(run, b),
                        None => counts.end_run(run),
                    }
                }
            }
            for run in &mut runs[..width] {
                counts.end_run(run);
            }
        }
        total as u64
    }
}

/// The block counts of [`entropy_rate`] (and the rays) of a lattice whose rays are the voxel
/// columns along `axis` (see [`Lattice::columns`]): samples are voxels, read in memory order a
/// row of columns at a time.
///
/// [`entropy_rate`]: super::entropy_rate
pub(super) fn column_counts<T: Voxel>(
    sampler: &BinSampler<T>,
    lattice: &Lattice,
    axis: usize,
    block: usize,
    monitor: (&Monitor, u64),
) -> Result<(BlockCounts, u64)> {
    let columns = Columns::new(sampler.dims(), axis);
    // As many parts as the general walk reports progress units.
    let parts = work_units(lattice).max(1) as usize;
    let items = columns.items();
    let ranges = (0..parts)
        .map(|part| part * items / parts..(part + 1) * items / parts)
        .collect();
    count_in_parallel(
        ranges,
        (sampler.bins(), block),
        sampler.voxels().len(),
        monitor,
        |range, counts| match counts.dense() {
            Some(mut dense) => columns.walk(range, sampler, &mut dense),
            None => columns.walk(range, sampler, counts),
        },
    )
}

/// The counts of a lattice whose rays are the voxel rows along x or y (`axis` 0 or 1, see
/// [`Lattice::columns`]) in a slab of cell planes `planes` along z walked whole: the rows of the
/// voxel planes `planes` (and of the last voxel plane, on the far face, in the last slab), each
/// a whole ray, none left open; every voxel read through `sampler` (which may hold a window of
/// the map). What the slab walk counts there, by the columns' walk, as the search counts them.
pub(super) fn slab_rows<T: Voxel>(
    sampler: &BinSampler<T>,
    axis: usize,
    planes: std::ops::Range<usize>,
    block: usize,
) -> PartialCounts {
    let [nx, ny, nz] = sampler.dims();
    let cells = nz.saturating_sub(1).max(1);
    let end = if planes.end >= cells { nz } else { planes.end };
    let depth = end.saturating_sub(planes.start);
    let columns = Columns {
        offset: planes.start * nx * ny,
        ..Columns::new([nx, ny, depth], axis)
    };
    let items = columns.items();
    let parts = items.clamp(1, 64);
    let empty = || PartialCounts::new(sampler.bins(), block);
    let bin = |at: usize| sampler.voxel_bin_at(at);
    (0..parts)
        .into_par_iter()
        .with_min_len(serial_len(nx * ny * depth, parts))
        .fold(empty, |mut out, part| {
            let range = part * items / parts..(part + 1) * items / parts;
            out.rays += match out.counts.dense() {
                Some(mut dense) => columns.walk_with(range, &mut dense, bin),
                None => columns.walk_with(range, &mut out.counts, bin),
            };
            out
        })
        .reduce_with(|mut a, b| {
            a.add(b);
            a
        })
        .unwrap_or_else(empty)
}
