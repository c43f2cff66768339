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
        let too_many = || Error::invalid("slab", "a grid", "one of a size this machine can map");
        let plane = nx.checked_mul(ny).ok_or_else(too_many)?;
        let count = plane.checked_mul(nz).ok_or_else(too_many)?;
        count
            .checked_mul(std::mem::size_of::<T>())
            .ok_or_else(too_many)?;
        check_shape(grid.dims, grid.spacing, count)?;
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
        let size = std::mem::size_of::<T>();
        let mut map = memmap2::MmapOptions::new()
            .len((plane * nz * size).max(1))
            .no_reserve_swap()
            .map_anon()
            .map_err(|e| Error::invalid("slab", "a map of the whole grid", e.to_string()))?;
        let start = first * plane * size;
        let bytes: &[u8] = bytemuck::cast_slice(voxels);
        map[start..start + bytes.len()].copy_from_slice(bytes);
        if T::TYPE == VoxelType::F32 {
            let written: &mut [f32] =
                bytemuck::cast_slice_mut(&mut map[start..start + bytes.len()]);
            super::voxels::infinities_missing(written);
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
