//! A volume of which one slab of planes along z is held: what a task of a split analysis
//! (issue #44) works on. Its voxels sit at their own linear indices of the whole grid, in an
//! anonymous map of the whole grid's size whose other pages are never written (the kernel gives
//! them no memory: only the slab's planes are resident), so that every walk reads them at the
//! indices it reads the whole volume's, and the statistics are the whole volume's, given up
//! front: the quantizer, the cell map and every count are the whole volume's wherever the slab
//! is read.

use std::sync::Arc;

use super::voxels::{LentBytes, Store};
use super::{Level, Stats, Volume, Voxel, VoxelType, Voxels, check_shape, pyramid};
use crate::error::{Error, Result};
use crate::geometry::WorldTransform;

/// The whole grid a slab belongs to: what every task is told up front.
#[derive(Clone, Debug, PartialEq)]
pub struct SlabGrid {
    /// The whole volume's dimensions.
    pub dims: [usize; 3],
    /// Its spacing, mm.
    pub spacing: [f64; 3],
    /// Its voxel-to-world transform.
    pub transform: WorldTransform,
    /// The voxel type of the file.
    pub voxel_type: VoxelType,
    /// The whole volume's statistics (the range a first round finds).
    pub stats: Stats,
}

impl SlabGrid {
    /// The grid of `volume`.
    #[must_use]
    pub fn of(volume: &Volume) -> Self {
        Self {
            dims: volume.dims(),
            spacing: volume.spacing(),
            transform: *volume.transform(),
            voxel_type: volume.voxel_type(),
            stats: volume.stats(),
        }
    }
}

/// A box of voxels of a grid: its first voxel and its size, per axis (x, y, z).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VoxelBox {
    /// The first voxel.
    pub origin: [usize; 3],
    /// The voxels along each axis.
    pub size: [usize; 3],
}

impl VoxelBox {
    /// Its voxels.
    #[must_use]
    pub fn len(&self) -> usize {
        self.size.iter().product()
    }

    /// Whether it holds none.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Whether it lies within a grid of `dims` voxels.
    fn within(&self, dims: [usize; 3]) -> bool {
        (0..3).all(|m| {
            self.origin[m]
                .checked_add(self.size[m])
                .is_some_and(|end| end <= dims[m])
        })
    }
}

/// An anonymous map of a whole grid's bytes, written only where a slab is.
#[derive(Debug)]
struct SparseBytes(memmap2::Mmap);

impl LentBytes for SparseBytes {
    fn bytes(&self) -> &[u8] {
        &self.0
    }
}

impl Volume {
    /// The volume of `grid` whose voxel planes `first..first + n` along z are `voxels` (x
    /// fastest, `n` whole planes), every other voxel unread: the whole volume to every walk
    /// that reads those planes alone. f32 infinities are made missing, as every reader makes
    /// them.
    pub fn of_slab<T: Voxel>(grid: &SlabGrid, first: usize, voxels: &[T]) -> Result<Self> {
        let [nx, ny, nz] = grid.dims;
        let plane = nx.saturating_mul(ny);
        if plane == 0
            || !voxels.len().is_multiple_of(plane)
            || first > nz
            || voxels.len() / plane > nz - first
        {
            return Err(Error::invalid(
                "slab",
                format!("{} voxels from plane {first}", voxels.len()),
                format!("whole planes of {nx}×{ny} voxels within the {nz} planes"),
            ));
        }
        let held = VoxelBox {
            origin: [0, 0, first],
            size: [nx, ny, voxels.len() / plane],
        };
        Self::of_box(grid, held, voxels)
    }

    /// The volume of `grid` whose box `held` is `voxels` (x fastest), every other voxel
    /// unread: the whole volume to every walk and cut that reads that box alone. f32
    /// infinities are made missing, as every reader makes them.
    pub fn of_box<T: Voxel>(grid: &SlabGrid, held: VoxelBox, voxels: &[T]) -> Result<Self> {
        Self::of_boxes(grid, &[(held, voxels)])
    }

    /// [`of_box`](Self::of_box) of several boxes, each with its voxels (x fastest): a voxel in
    /// two takes the later one's value.
    pub fn of_boxes<T: Voxel>(grid: &SlabGrid, boxes: &[(VoxelBox, &[T])]) -> Result<Self> {
        let too_many = || Error::invalid("slab", "a grid", "one of a size this machine can map");
        let count = grid.dims.iter().try_fold(1usize, |n, &d| n.checked_mul(d));
        let count = count.ok_or_else(too_many)?;
        let size = std::mem::size_of::<T>();
        count.checked_mul(size).ok_or_else(too_many)?;
        check_shape(grid.dims, grid.spacing, count)?;
        for &(held, voxels) in boxes {
            if !held.within(grid.dims) || voxels.len() != held.len() {
                return Err(Error::invalid(
                    "slab",
                    format!(
                        "{} voxels in a box of {:?} from {:?}",
                        voxels.len(),
                        held.size,
                        held.origin
                    ),
                    format!("a box's voxels within the grid of {:?}", grid.dims),
                ));
            }
        }
        let mut map = memmap2::MmapOptions::new()
            .len((count * size).max(1))
            .no_reserve_swap()
            .map_anon()
            .map_err(|e| Error::invalid("slab", "a map of the whole grid", e.to_string()))?;
        let [nx, ny, _] = grid.dims;
        for &(held, voxels) in boxes {
            let [sx, sy, sz] = held.size;
            let [x0, y0, z0] = held.origin;
            let rows = voxels.chunks_exact(sx.max(1)).take(sy * sz);
            for (r, row) in rows.enumerate() {
                let (y, z) = (y0 + r % sy, z0 + r / sy);
                let start = ((z * ny + y) * nx + x0) * size;
                let end = start + std::mem::size_of_val(row);
                map[start..end].copy_from_slice(bytemuck::cast_slice(row));
                if T::TYPE == VoxelType::F32 {
                    let row = bytemuck::cast_slice_mut(&mut map[start..end]);
                    super::voxels::infinities_missing(row);
                }
            }
        }
        let map = map
            .make_read_only()
            .map_err(|e| Error::invalid("slab", "a map of the whole grid", e.to_string()))?;
        let data: Voxels = T::wrap(Store::Lent(Arc::new(SparseBytes(map))));
        Ok(Self {
            data,
            dims: grid.dims,
            spacing: grid.spacing,
            voxel_type: grid.voxel_type,
            stats: grid.stats,
            transform: grid.transform,
            level: Level {
                index: 0,
                factor: [1; 3],
                range: [grid.stats.min, grid.stats.max],
                labels: false,
            },
            labels: Arc::default(),
            pyramid: pyramid::empty(grid.dims),
            remote: false,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_slab_sits_at_its_own_indices_with_the_whole_grids_statistics() {
        let data: Vec<f32> = (0..4 * 3 * 5).map(|i| i as f32).collect();
        let whole = Volume::new([4, 3, 5], [1.0, 1.5, 2.0], VoxelType::F32, data).unwrap();
        let grid = SlabGrid::of(&whole);
        let slab = Volume::of_slab(&grid, 2, &whole.voxels()[24..48]).unwrap();
        assert_eq!(slab.dims(), [4, 3, 5]);
        assert_eq!(slab.stats(), whole.stats());
        assert_eq!(slab.value([1, 2, 2]), whole.value([1, 2, 2]));
        assert_eq!(slab.value([3, 0, 3]), 39.0);
        // Outside the planes held nothing was written.
        assert_eq!(slab.value([3, 2, 4]), 0.0);
        assert_eq!(slab.quantizer(32).unwrap(), whole.quantizer(32).unwrap());
        // An infinity is made missing, as a reader makes it.
        let inf = [f32::INFINITY; 12];
        assert!(
            Volume::of_slab(&grid, 0, &inf)
                .unwrap()
                .value([0, 0, 0])
                .is_nan()
        );
        // Part of a plane, or planes past the grid, are refused.
        for (first, len) in [(0, 13), (4, 24), (6, 0), (usize::MAX, 12)] {
            let e = Volume::of_slab(&grid, first, &whole.voxels()[..len]).unwrap_err();
            assert!(e.to_string().contains("whole planes of 4×3"), "{e}");
        }
    }
}
