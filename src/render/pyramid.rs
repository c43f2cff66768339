//! Which pyramid level a picture reads (docs/design.md §5): pyramid level k only where level
//! k − 1 gives at least 2 voxels per pixel along both screen axes, so that a small picture of a
//! large volume reads few voxels and today's pictures stay as they are; and the grid of a
//! pyramid level in level 0's millimetres, where cameras, boxes and overlays stay.

use crate::geometry::dot;
use crate::volume::Volume;
use crate::volume::pyramid::{chain_dims, steps_after};

/// A pyramid level's dimensions and spacing (mm).
pub type LevelGrid = ([usize; 3], [f64; 3]);

/// Voxels per pixel, along both screen axes, that a pyramid level must give for the next one to
/// be read instead.
pub const VOXELS_PER_PIXEL: f64 = 2.0;

/// The pyramid level a picture reads from a volume of `dims` voxels `spacing` mm apart whose
/// pyramid halves every axis, when its pixels are `pixel` mm across and its screen axes are the
/// unit physical directions `right` and `up`: [`pyramid_level_in`] of that pyramid's levels.
#[must_use]
pub fn pyramid_level(
    pixel: f64,
    axes: ([f64; 3], [f64; 3]),
    dims: [usize; 3],
    spacing: [f64; 3],
) -> usize {
    pyramid_level_in(pixel, axes, &halving_grids(dims, spacing))
}

/// The dimensions and spacing of every level of the pyramid that halves every axis of a level 0
/// of `dims` voxels `spacing` mm apart (as [`Volume::level_grids`] gives a volume's own).
#[must_use]
pub fn halving_grids(dims: [usize; 3], spacing: [f64; 3]) -> Vec<([usize; 3], [f64; 3])> {
    let steps = steps_after(dims, &[]);
    let mut factor = [1usize; 3];
    let mut grids = vec![(dims, spacing)];
    for (s, d) in steps
        .iter()
        .zip(chain_dims(dims, &steps).into_iter().skip(1))
    {
        factor = std::array::from_fn(|m| factor[m] * s[m]);
        grids.push((d, std::array::from_fn(|m| spacing[m] * factor[m] as f64)));
    }
    grids
}

/// The pyramid level a picture reads from a pyramid whose levels have the dimensions and
/// spacing `grids` (level 0's first), when its pixels are `pixel` mm across and its screen axes
/// are the unit physical directions `right` and `up`: the coarsest level k such that level k − 1
/// gives at least [`VOXELS_PER_PIXEL`] along both, 0 when level 0 gives fewer.
///
/// A level with spacing `s` gives `pixel · ‖(r_x/s_x, r_y/s_y, r_z/s_z)‖` voxels per pixel along
/// a screen axis `r`; an axis of one voxel holds no voxels to count and is left out (it is never
/// halved).
#[must_use]
pub fn pyramid_level_in(
    pixel: f64,
    (right, up): ([f64; 3], [f64; 3]),
    grids: &[([usize; 3], [f64; 3])],
) -> usize {
    if !(pixel.is_finite() && pixel > 0.0) {
        return 0;
    }
    let per_pixel = |r: [f64; 3], dims: [usize; 3], spacing: [f64; 3]| {
        let across: [f64; 3] =
            std::array::from_fn(|m| if dims[m] > 1 { r[m] / spacing[m] } else { 0.0 });
        pixel * dot(across, across).sqrt()
    };
    grids
        .iter()
        .take(grids.len().saturating_sub(1))
        .take_while(|&&(dims, spacing)| {
            dims.iter().any(|&n| n > 1)
                && per_pixel(right, dims, spacing) >= VOXELS_PER_PIXEL
                && per_pixel(up, dims, spacing) >= VOXELS_PER_PIXEL
        })
        .count()
}

/// A pyramid level's voxel grid seen from level 0's millimetres (voxel indices times level 0's
/// spacing, where cameras and boxes are): index coordinates `q = (p − shift) / spacing`, clamped
/// to the level's grid, which level 0's box overhangs by up to half a coarse voxel (level 0 is
/// not clamped, so its samples are exactly as before).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Grid {
    /// The level's voxel spacing, mm.
    pub(crate) spacing: [f64; 3],
    /// Where the level's voxel (0, 0, 0) lies, mm from level 0's: `(f − 1) / 2` level-0 voxels
    /// per axis for a level whose voxels span `f` of level 0's.
    pub(crate) shift: [f64; 3],
    lo: [f64; 3],
    hi: [f64; 3],
}

impl Grid {
    /// The grid of `level`, a pyramid level of `fine` (or `fine` itself), in `fine`'s mm.
    pub(crate) fn of(fine: &Volume, level: &Volume) -> Self {
        let (f0, f) = (fine.level().factor, level.level().factor);
        let spacing0 = fine.spacing();
        let same = f == f0;
        let dims = level.dims();
        Self {
            spacing: level.spacing(),
            shift: std::array::from_fn(|m| (f[m] / f0[m] - 1) as f64 / 2.0 * spacing0[m]),
            lo: [if same { f64::NEG_INFINITY } else { 0.0 }; 3],
            hi: std::array::from_fn(|m| {
                if same {
                    f64::INFINITY
                } else {
                    (dims[m] - 1) as f64
                }
            }),
        }
    }

    /// The level's index coordinates of point `p` (mm).
    #[inline]
    pub(crate) fn index(&self, p: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|m| {
            ((p[m] - self.shift[m]) / self.spacing[m]).clamp(self.lo[m], self.hi[m])
        })
    }

    /// The mm position (level 0's) of the level's index coordinate `i` along axis `m`.
    #[inline]
    pub(crate) fn position(&self, m: usize, i: f64) -> f64 {
        i * self.spacing[m] + self.shift[m]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::VoxelType;

    const X: [f64; 3] = [1.0, 0.0, 0.0];
    const Y: [f64; 3] = [0.0, 1.0, 0.0];
    const Z: [f64; 3] = [0.0, 0.0, 1.0];

    #[test]
    fn the_rule_counts_voxels_per_pixel_of_the_level_before() {
        // 1 mm voxels: pixels of 1.99 mm stay at level 0, 2 mm read level 1 (level 0 gives 2),
        // 4 mm level 2, 7.99 mm still level 2 (level 2 gives 1.99), 8 mm level 3.
        let level = |pixel| pyramid_level(pixel, (X, Y), [512; 3], [1.0; 3]);
        assert_eq!(level(1.99), 0);
        assert_eq!(level(2.0), 1);
        assert_eq!(level(4.0), 2);
        assert_eq!(level(7.99), 2);
        assert_eq!(level(8.0), 3);
        assert_eq!(level(0.0), 0);
        assert_eq!(level(f64::NAN), 0);
        // It stops at the last level, one voxel every way.
        assert_eq!(level(1e9), 9);
        assert_eq!(pyramid_level(1e9, (X, Y), [1; 3], [1.0; 3]), 0);
    }

    #[test]
    fn both_screen_axes_must_be_oversampled_and_spacings_count_per_axis() {
        // x and z 0.5 mm, y 2 mm: a pixel of 2 mm is 4 voxels along x but 1 along y.
        let s = [0.5, 2.0, 0.5];
        assert_eq!(pyramid_level(2.0, (X, Y), [256; 3], s), 0);
        assert_eq!(
            pyramid_level(2.0, (X, Z), [256; 3], s),
            2,
            "4 at level 0, 2 at level 1"
        );
        // A diagonal axis: ‖(0.6 / 0.5, 0.8 / 2)‖ = ‖(1.2, 0.4)‖ = √1.6 voxels a mm.
        let r = [0.6, 0.8, 0.0];
        let per_mm = 1.6f64.sqrt();
        assert_eq!(pyramid_level(2.0 / per_mm - 1e-9, (r, Z), [256; 3], s), 0);
        assert_eq!(pyramid_level(2.0 / per_mm + 1e-9, (r, Z), [256; 3], s), 1);
    }

    #[test]
    fn an_axis_of_one_voxel_is_left_out_and_never_halved() {
        // A 2D image seen face on: z does not count, and x and y keep halving.
        assert_eq!(pyramid_level(4.0, (X, Y), [1024, 1024, 1], [1.0; 3]), 2);
        // Seen obliquely, z adds nothing: a pixel along (0, 0.6, 0.8) spans 0.6 voxels a mm.
        let up = [0.0, 0.6, 0.8];
        assert_eq!(
            pyramid_level(2.0 / 0.6, (X, up), [1024, 1024, 1], [1.0; 3]),
            1
        );
        assert_eq!(
            pyramid_level(2.0 / 0.6 - 1e-9, (X, up), [1024, 1024, 1], [1.0; 3]),
            0
        );
        // Seen edge on, the picture is a line: nothing is oversampled along up.
        assert_eq!(pyramid_level(100.0, (X, Z), [1024, 1024, 1], [1.0; 3]), 0);
        // Two voxels along z: level 1 makes it one, and z stops counting from there.
        assert_eq!(pyramid_level(3.0, (X, Z), [1024, 1024, 2], [1.0; 3]), 1);
    }

    #[test]
    fn grids_put_coarse_voxels_at_the_centre_of_their_blocks() {
        let data: Vec<f32> = (0..9 * 6).map(|i| i as f32).collect();
        let v = Volume::new([9, 6, 1], [0.5, 2.0, 3.0], VoxelType::F32, data).unwrap();
        let g0 = Grid::of(&v, &v);
        assert_eq!(g0.index([1.0, 4.0, 0.0]), [2.0, 2.0, 0.0]);
        assert_eq!(
            g0.index([-1.0, 0.0, 0.0]),
            [-2.0, 0.0, 0.0],
            "level 0 is not clamped"
        );
        let c = v.coarser(2);
        assert_eq!(c.dims(), [3, 2, 1]);
        let g = Grid::of(&v, &c);
        // Factors 4, 4 and 1 (z is one voxel): shifts of 1.5 voxels of level 0 in x and y.
        assert_eq!(g.spacing, [2.0, 8.0, 3.0]);
        assert_eq!(g.shift, [0.75, 3.0, 0.0]);
        assert_eq!(g.index([0.75, 3.0, 0.0]), [0.0, 0.0, 0.0]);
        assert_eq!(g.index([2.75, 5.0, 0.0]), [1.0, 0.25, 0.0]);
        // Level 0's box reaches past the outer grid points: clamped onto them.
        assert_eq!(g.index([0.0, 6.0, 0.0]), [0.0, 0.375, 0.0]);
        assert_eq!(g.index([4.0, 10.0, 0.0]), [1.625, 0.875, 0.0]);
        assert_eq!(g.index([100.0, 100.0, 1.0]), [2.0, 1.0, 0.0]);
        assert_eq!(g.position(0, 1.0), 2.75);
        // Relative to a level already coarse: the shift of the ratio of the factors.
        let g12 = Grid::of(&v.coarser(1), &c);
        assert_eq!(g12.shift, [0.5, 2.0, 0.0]);
    }
}
