//! Trilinear interpolation of a volume at voxel index coordinates: the value between voxel
//! centres that the view search's rays, oblique slices and the renderer sample.

use crate::volume::{Volume, Voxel};

/// Trilinear interpolation of a volume at voxel index coordinates, reading voxels of type `T`
/// and widening each corner to f32 (exactly), so every type gives the f32 path's values.
#[derive(Clone, Copy)]
pub struct Interpolator<'a, T = f32> {
    pub(crate) data: &'a [T],
    pub(crate) stride: [usize; 3],
    /// Per axis: the stride to the next voxel (0 for a single-voxel axis).
    pub(crate) next: [usize; 3],
    /// Per axis: the largest lower corner index (n - 2, or 0 for a single-voxel axis).
    pub(crate) last: [usize; 3],
}

impl<'a> Interpolator<'a, f32> {
    /// An interpolator over a volume held as f32.
    ///
    /// # Panics
    /// When the volume's voxels are held in another type: use [`Interpolator::over`].
    pub fn new(volume: &'a Volume) -> Self {
        Self::over(volume.voxels(), volume.dims())
    }
}

impl<'a, T: Voxel> Interpolator<'a, T> {
    /// An interpolator over `data`, voxels of dimensions `dims` in x-fastest order.
    pub fn over(data: &'a [T], dims: [usize; 3]) -> Self {
        debug_assert_eq!(data.len(), dims.iter().product::<usize>());
        let stride = [1, dims[0], dims[0] * dims[1]];
        Self {
            data,
            stride,
            next: std::array::from_fn(|m| if dims[m] > 1 { stride[m] } else { 0 }),
            last: dims.map(|n| n.saturating_sub(2)),
        }
    }

    /// The corner at offset `at` from the lower one of the cell at `base`, as f32.
    #[inline]
    fn corner(c: &[T], at: usize) -> f32 {
        c[at].to_f32()
    }

    /// The value at `p`, which must lie inside the volume up to rounding (lattice samples do);
    /// NaN when a voxel it mixes is missing.
    #[inline]
    pub fn sample(&self, p: [f64; 3]) -> f32 {
        let (base, f) = self.cell(p);
        self.interpolate(base, f)
    }

    /// The linear offset of the lower corner of the cell around `p`, and the fractions in it.
    #[inline]
    fn cell(&self, p: [f64; 3]) -> (usize, [f32; 3]) {
        let mut base = 0;
        let mut f = [0.0f32; 3];
        for m in 0..3 {
            // Truncation is floor here, since q >= 0.
            let q = p[m].max(0.0);
            let i = (q as usize).min(self.last[m]);
            f[m] = (q - i as f64) as f32;
            base += i * self.stride[m];
        }
        (base, f)
    }

    /// Trilinear interpolation in the cell whose lower corner is at linear offset `base`, with
    /// fractions `f` along x, y and z.
    #[inline]
    pub(crate) fn interpolate(&self, base: usize, f: [f32; 3]) -> f32 {
        let [x1, y1, z1] = self.next;
        let c = &self.data[base..=base + x1 + y1 + z1];
        let k = |at: usize| Self::corner(c, at);
        let lerp = |a: f32, b: f32, t: f32| a + t * (b - a);
        let c00 = lerp(k(0), k(x1), f[0]);
        let c10 = lerp(k(y1), k(y1 + x1), f[0]);
        let c01 = lerp(k(z1), k(z1 + x1), f[0]);
        let c11 = lerp(k(z1 + y1), k(z1 + y1 + x1), f[0]);
        lerp(lerp(c00, c10, f[1]), lerp(c01, c11, f[1]), f[2])
    }

    /// The value at `p` and its gradient (per voxel index unit), both from the trilinear
    /// interpolant of the cell around `p`, so shading costs no extra voxel reads.
    #[inline]
    pub fn sample_gradient(&self, p: [f64; 3]) -> (f32, [f32; 3]) {
        let (base, f) = self.cell(p);
        let [x1, y1, z1] = self.next;
        let c = &self.data[base..=base + x1 + y1 + z1];
        let k = |at: usize| Self::corner(c, at);
        let lerp = |a: f32, b: f32, t: f32| a + t * (b - a);
        let (c000, c100, c010, c110) = (k(0), k(x1), k(y1), k(y1 + x1));
        let (c001, c101, c011, c111) = (k(z1), k(z1 + x1), k(z1 + y1), k(z1 + y1 + x1));
        let c00 = lerp(c000, c100, f[0]);
        let c10 = lerp(c010, c110, f[0]);
        let c01 = lerp(c001, c101, f[0]);
        let c11 = lerp(c011, c111, f[0]);
        let (lo, hi) = (lerp(c00, c10, f[1]), lerp(c01, c11, f[1]));
        let value = lerp(lo, hi, f[2]);
        let dz = hi - lo;
        let dy = lerp(c10 - c00, c11 - c01, f[2]);
        let dx = lerp(
            lerp(c100 - c000, c110 - c010, f[1]),
            lerp(c101 - c001, c111 - c011, f[1]),
            f[2],
        );
        (value, [dx, dy, dz])
    }

    /// The linear index of the voxel nearest to `p` (index coordinates inside the volume up to
    /// rounding).
    #[inline]
    pub fn nearest(&self, p: [f64; 3]) -> usize {
        (0..3)
            .map(|m| {
                let i = (p[m].max(0.0) + 0.5) as usize;
                i.min(self.last[m] + usize::from(self.next[m] > 0)) * self.stride[m]
            })
            .sum()
    }

    /// The voxel at integer index coordinates.
    #[inline]
    pub fn voxel(&self, x: usize, y: usize, z: usize) -> f32 {
        self.data[x * self.stride[0] + y * self.stride[1] + z * self.stride[2]].to_f32()
    }

    /// The voxel at linear index `i`, as f32.
    #[inline]
    pub fn at(&self, i: usize) -> f32 {
        self.data[i].to_f32()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::VoxelType;

    #[test]
    fn trilinear_is_exact_on_linear_fields() {
        let dims = [4, 5, 6];
        let data: Vec<f32> = (0..120)
            .map(|i| {
                let (x, y, z) = (i % 4, (i / 4) % 5, i / 20);
                (2 * x + 3 * y + 5 * z) as f32
            })
            .collect();
        let vol = Volume::new(dims, [1.0; 3], VoxelType::F32, data).unwrap();
        let it = Interpolator::new(&vol);
        for p in [
            [0.5, 0.25, 1.75],
            [3.0, 4.0, 5.0],
            [0.0, 0.0, 0.0],
            [2.2, 3.9, 4.1],
        ] {
            let expect = 2.0 * p[0] + 3.0 * p[1] + 5.0 * p[2];
            assert!((f64::from(it.sample(p)) - expect).abs() < 1e-4, "{p:?}");
        }
        assert_eq!(it.voxel(3, 4, 5), 2.0 * 3.0 + 3.0 * 4.0 + 5.0 * 5.0);
        let (v, g) = it.sample_gradient([1.5, 2.25, 3.5]);
        assert!((f64::from(v) - (3.0 + 6.75 + 17.5)).abs() < 1e-4);
        assert_eq!(g, [2.0, 3.0, 5.0]);
    }
}
