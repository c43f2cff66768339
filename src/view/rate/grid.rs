//! The grid of bricks the bricked walk visits: cubes (or boxes shaped for an axis) of cells,
//! and the order in which every ray along a step meets them.

use crate::geometry::lattice::FIXED_BITS;

/// Cells along each side of a brick: 64³ one-byte cells, 256 KiB.
pub const BRICK_CELLS: usize = 64;

/// A grid of bricks over a volume's cells (the cell between voxels `x` and `x + 1` along each
/// axis, one cell along an axis of one voxel), `size` cells along each axis, the last ones cut
/// short; along z the boundaries may be shifted to fall on a chosen plane, the first bricks
/// then cut short too.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Bricks {
    cells: [i64; 3],
    size: [i64; 3],
    count: [i64; 3],
    /// Cells a brick boundary lies before cell 0 along each axis (`0..size`): brick `c` holds
    /// cells `c·size − shift .. (c + 1)·size − shift`, clipped to the volume's.
    shift: [i64; 3],
}

impl Bricks {
    /// The bricks of `size` cells a side over a volume of `dims` voxels.
    pub fn new(dims: [usize; 3], size: usize) -> Self {
        Self::shaped(dims, [size; 3])
    }

    /// The bricks of `size[m]` cells along axis `m` over a volume of `dims` voxels.
    pub fn shaped(dims: [usize; 3], size: [usize; 3]) -> Self {
        Self::shaped_from(dims, size, 0)
    }

    /// The bricks of `size[m]` cells along axis `m` over a volume of `dims` voxels whose
    /// boundaries along z fall on cell plane `origin` (and every `size[2]` planes before and
    /// after it): a slab of cell planes `origin..origin + size[2]` is one layer of bricks,
    /// wherever it starts.
    pub fn shaped_from(dims: [usize; 3], size: [usize; 3], origin: usize) -> Self {
        let cells = dims.map(|n| n.saturating_sub(1).max(1) as i64);
        let size = size.map(|s| s.max(1) as i64);
        let shift = [0, 0, (size[2] - origin as i64 % size[2]) % size[2]];
        Self {
            cells,
            size,
            count: std::array::from_fn(|m| (cells[m] + shift[m] + size[m] - 1) / size[m]),
            shift,
        }
    }

    /// Bricks of about `cells³` cells for rays along `step`: longest along the axes the rays
    /// run most along, so that a ray's stretch in a brick is long (its mean is the brick's
    /// volume over its area seen along the ray, which this shape makes least), each side at
    /// least a quarter of `cells`.
    pub fn along(dims: [usize; 3], cells: usize, step: [i64; 3]) -> Self {
        let norm = step
            .iter()
            .map(|&s| (s as f64).powi(2))
            .sum::<f64>()
            .sqrt()
            .max(1.0);
        let w = step.map(|s| (s.unsigned_abs() as f64 / norm).max(0.25));
        let k = (cells as f64).powi(3) / w.iter().product::<f64>();
        let k = k.cbrt();
        Self::shaped(dims, w.map(|w| ((k * w / 8.0).round() as usize).max(1) * 8))
    }

    /// Number of bricks.
    pub fn len(&self) -> usize {
        self.count.iter().product::<i64>() as usize
    }

    /// Always false: a volume has a cell.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn coords(&self, b: usize) -> [i64; 3] {
        let b = b as i64;
        let [nx, ny, _] = self.count;
        [b % nx, (b / nx) % ny, b / (nx * ny)]
    }

    /// The cells of brick `b`: `lo..hi` along each axis.
    pub fn cells_of(&self, b: usize) -> ([i64; 3], [i64; 3]) {
        let c = self.coords(b);
        let lo = std::array::from_fn(|m| (c[m] * self.size[m] - self.shift[m]).max(0));
        let hi =
            std::array::from_fn(|m| ((c[m] + 1) * self.size[m] - self.shift[m]).min(self.cells[m]));
        (lo, hi)
    }

    /// The box of brick `b` in fixed-point index coordinates: `lo..hi` along each axis.
    pub(super) fn bounds(&self, b: usize) -> ([i64; 3], [i64; 3]) {
        let (lo, hi) = self.cells_of(b);
        (lo.map(|x| x << FIXED_BITS), hi.map(|x| x << FIXED_BITS))
    }

    /// The brick holding the sample at `p` (fixed point), clamped into the grid.
    pub(super) fn holding(&self, p: [i64; 3]) -> usize {
        let c: [i64; 3] = std::array::from_fn(|m| {
            ((p[m].max(0) >> FIXED_BITS).min(self.cells[m] - 1) + self.shift[m]) / self.size[m]
        });
        let [nx, ny, _] = self.count;
        (c[0] + nx * (c[1] + ny * c[2])) as usize
    }

    /// Every brick, in an order in which each ray along `step` meets the bricks it crosses:
    /// coordinates rising where the step rises and falling where it falls, z slowest.
    pub fn sweep(&self, step: [i64; 3]) -> Vec<usize> {
        let along = |m: usize| -> Vec<i64> {
            let n = self.count[m];
            if step[m] < 0 {
                (0..n).rev().collect()
            } else {
                (0..n).collect()
            }
        };
        let [nx, ny, _] = self.count;
        let mut out = Vec::with_capacity(self.len());
        for z in along(2) {
            for y in along(1) {
                for x in along(0) {
                    out.push((x + nx * (y + ny * z)) as usize);
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bricks shifted to start on any plane tile the cells once, the plane a boundary.
    #[test]
    fn bricks_from_a_plane_tile_the_cells_with_a_boundary_there() {
        let dims = [5, 4, 101];
        for (size, origin) in [(38, 37), (7, 0), (7, 3), (100, 99), (1, 50), (150, 37)] {
            let bricks = Bricks::shaped_from(dims, [5, 4, size], origin);
            let mut held = vec![0; 100];
            for b in 0..bricks.len() {
                let (lo, hi) = bricks.cells_of(b);
                assert!(lo[2] < hi[2], "{size} {origin}: brick {b} is empty");
                assert!(origin as i64 <= lo[2] || hi[2] <= origin as i64);
                for z in lo[2]..hi[2] {
                    held[z as usize] += 1;
                    let p = [0, 0, z << FIXED_BITS];
                    assert_eq!(bricks.holding(p), b, "{size} {origin}: cell {z}");
                }
            }
            assert_eq!(held, vec![1; 100], "{size} {origin}");
        }
        // Cuts at 37 and 75 of 100 cell planes: the middle slab is one brick, not 37 of one.
        let bricks = Bricks::shaped_from(dims, [5, 4, 38], 37);
        assert_eq!(bricks.len(), 3);
        assert_eq!(bricks.cells_of(1), ([0, 0, 37], [4, 3, 75]));
        assert_eq!(
            Bricks::shaped(dims, [5, 4, 7]),
            Bricks::shaped_from(dims, [5, 4, 7], 14)
        );
    }
}
