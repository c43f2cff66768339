//! The volume: f32 voxels with x fastest, spacing in millimetres, statistics and quantization.

pub mod background;
pub mod cells;
pub mod interpolate;
pub mod io;
pub mod phantom;
mod quantize;
mod voxel;

use ndarray::{Array3, ArrayView3, ShapeBuilder};
use rayon::prelude::*;

pub use quantize::Quantizer;
pub use voxel::{Endian, VoxelType};

use crate::error::{Error, Result};
pub use crate::geometry::MAX_SPACING_RATIO;
use crate::geometry::WorldTransform;

/// Summary statistics over the finite voxels of a volume.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stats {
    /// Smallest finite voxel value.
    pub min: f32,
    /// Largest finite voxel value.
    pub max: f32,
    /// Mean of the finite voxels.
    pub mean: f64,
    /// Number of finite voxels.
    pub finite: usize,
    /// Number of voxels that were NaN or infinite in the file and are treated as missing.
    pub missing: usize,
}

/// A scalar volume: voxels as f32, x fastest in memory, with physical spacing.
///
/// Voxels that were NaN or infinite in the file are stored as NaN and count as missing: they are
/// left out of statistics, histograms and every measure.
#[derive(Clone, Debug)]
pub struct Volume {
    data: Array3<f32>,
    spacing: [f64; 3],
    voxel_type: VoxelType,
    stats: Stats,
    transform: WorldTransform,
}

impl Volume {
    /// Builds a volume from voxels in x-fastest order.
    ///
    /// Fails when a dimension is zero, the voxel count does not match, a spacing is not a positive
    /// finite number or lies more than [`MAX_SPACING_RATIO`] from another. A volume with no
    /// finite voxel is made (it can be described) but cannot be analysed.
    pub fn new(
        dims: [usize; 3],
        spacing: [f64; 3],
        voxel_type: VoxelType,
        mut voxels: Vec<f32>,
    ) -> Result<Self> {
        if dims.contains(&0) {
            return Err(Error::invalid(
                "dims",
                dims_string(dims),
                "at least one voxel along each axis",
            ));
        }
        let count = dims.iter().try_fold(1usize, |a, &d| a.checked_mul(d));
        if count != Some(voxels.len()) {
            return Err(Error::invalid(
                "voxels",
                voxels.len(),
                format!("one per voxel of {}", dims_string(dims)),
            ));
        }
        let (lo, hi) = spacing
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(lo, hi), &s| {
                (lo.min(s), hi.max(s))
            });
        if spacing.iter().any(|s| !(s.is_finite() && *s > 0.0)) || hi > MAX_SPACING_RATIO * lo {
            return Err(Error::invalid(
                "spacing",
                format!("{spacing:?}"),
                format!(
                    "three positive finite numbers within a factor of {MAX_SPACING_RATIO} of \
                     each other"
                ),
            ));
        }
        voxels.par_iter_mut().for_each(|v| {
            if v.is_infinite() {
                *v = f32::NAN;
            }
        });
        let stats = compute_stats(&voxels);
        let data = Array3::from_shape_vec(dims.f(), voxels)
            .map_err(|e| Error::invalid("dims", dims_string(dims), e.to_string()))?;
        Ok(Self {
            data,
            spacing,
            voxel_type,
            stats,
            transform: WorldTransform::unknown(spacing),
        })
    }

    /// Dimensions `[nx, ny, nz]`.
    #[must_use]
    pub fn dims(&self) -> [usize; 3] {
        let s = self.data.shape();
        [s[0], s[1], s[2]]
    }

    /// Voxel spacing `[sx, sy, sz]` in millimetres.
    #[must_use]
    pub fn spacing(&self) -> [f64; 3] {
        self.spacing
    }

    /// This volume with the voxel-to-world transform its file states (see [`WorldTransform`]);
    /// unchanged when `t` is not finite or not invertible.
    #[must_use]
    pub fn with_transform(mut self, t: WorldTransform) -> Self {
        if t.is_usable() {
            self.transform = t;
        }
        self
    }

    /// This volume, its voxels said to be of type `ty` (a reader that learns the type from the
    /// values, after they are read).
    #[must_use]
    pub(crate) fn with_voxel_type(mut self, ty: VoxelType) -> Self {
        self.voxel_type = ty;
        self
    }

    /// The voxel-to-world transform: to RAS+ mm, or spacing on the diagonal when the file states
    /// no orientation.
    #[must_use]
    pub fn transform(&self) -> &WorldTransform {
        &self.transform
    }

    /// The voxel type of the file the volume came from.
    #[must_use]
    pub fn voxel_type(&self) -> VoxelType {
        self.voxel_type
    }

    /// Statistics over the finite voxels.
    #[must_use]
    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// Number of voxels.
    #[must_use]
    pub fn len(&self) -> usize {
        self.data.len()
    }

    /// Always false: a volume has at least one voxel.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// Whether every finite voxel has the same value.
    #[must_use]
    pub fn is_constant(&self) -> bool {
        self.stats.min == self.stats.max
    }

    /// The voxels in memory order: index `x + nx * (y + ny * z)`.
    #[must_use]
    pub fn voxels(&self) -> &[f32] {
        self.data
            .as_slice_memory_order()
            .expect("volumes are built contiguous")
    }

    /// The voxels as an array indexed `[x, y, z]`.
    #[must_use]
    pub fn array(&self) -> ArrayView3<'_, f32> {
        self.data.view()
    }

    /// Bytes the voxels occupy in memory.
    #[must_use]
    pub fn memory_bytes(&self) -> u64 {
        (self.len() * std::mem::size_of::<f32>()) as u64
    }

    /// The quantizer of DESIGN.md §2 for `bins` bins over this volume's finite range.
    pub fn quantizer(&self, bins: usize) -> Result<Quantizer> {
        self.require_data()?;
        Quantizer::new(self.stats.min, self.stats.max, bins)
    }

    /// Fails when no voxel is finite: such a volume can be described, not analysed or drawn.
    pub fn require_data(&self) -> Result<()> {
        if self.stats.finite == 0 {
            return Err(Error::Degenerate(format!(
                "all {} voxels are NaN or infinite: the volume holds no data",
                self.len()
            )));
        }
        Ok(())
    }

    /// Counts of finite voxels per quantization bin (`bins` equal-width bins over [min, max]).
    pub fn histogram(&self, bins: usize) -> Result<Vec<u64>> {
        if self.stats.finite == 0 {
            return Ok(vec![0; bins]);
        }
        let q = self.quantizer(bins)?;
        Ok(self
            .voxels()
            .par_chunks(1 << 16)
            .map(|chunk| {
                let mut h = vec![0u64; bins];
                for &v in chunk {
                    if let Some(b) = q.bin(v) {
                        h[b as usize] += 1;
                    }
                }
                h
            })
            .reduce(
                || vec![0u64; bins],
                |mut a, b| {
                    a.iter_mut().zip(&b).for_each(|(x, y)| *x += y);
                    a
                },
            ))
    }
}

/// `"NXxNYxNZ"`.
#[must_use]
pub fn dims_string(dims: [usize; 3]) -> String {
    format!("{}x{}x{}", dims[0], dims[1], dims[2])
}

fn compute_stats(voxels: &[f32]) -> Stats {
    let (min, max, sum, finite) = voxels
        .par_chunks(1 << 16)
        .map(|chunk| {
            let (mut lo, mut hi, mut sum, mut n) = (f32::INFINITY, f32::NEG_INFINITY, 0.0f64, 0);
            for &v in chunk {
                if v.is_finite() {
                    lo = lo.min(v);
                    hi = hi.max(v);
                    sum += f64::from(v);
                    n += 1;
                }
            }
            (lo, hi, sum, n)
        })
        .reduce(
            || (f32::INFINITY, f32::NEG_INFINITY, 0.0, 0usize),
            |a, b| (a.0.min(b.0), a.1.max(b.1), a.2 + b.2, a.3 + b.3),
        );
    Stats {
        min,
        max,
        mean: if finite > 0 { sum / finite as f64 } else { 0.0 },
        finite,
        missing: voxels.len() - finite,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp(n: usize) -> Vec<f32> {
        (0..n).map(|i| i as f32).collect()
    }

    #[test]
    fn indexing_is_x_fastest() {
        let v = Volume::new([2, 3, 4], [1.0; 3], VoxelType::F32, ramp(24)).unwrap();
        assert_eq!(v.dims(), [2, 3, 4]);
        assert_eq!(v.array()[[1, 2, 3]], (1 + 2 * (2 + 3 * 3)) as f32);
        assert_eq!(v.voxels()[5], 5.0);
    }

    #[test]
    fn stats_skip_missing_voxels() {
        let mut data = ramp(8);
        data[3] = f32::NAN;
        data[4] = f32::INFINITY;
        let v = Volume::new([2, 2, 2], [1.0; 3], VoxelType::F32, data).unwrap();
        let s = v.stats();
        assert_eq!((s.min, s.max, s.finite, s.missing), (0.0, 7.0, 6, 2));
        assert!((s.mean - (0.0 + 1.0 + 2.0 + 5.0 + 6.0 + 7.0) / 6.0).abs() < 1e-12);
        assert!(v.voxels()[4].is_nan(), "infinities are stored as missing");
    }

    #[test]
    fn rejects_bad_shapes_and_spacings() {
        let bad = |dims, spacing, data| Volume::new(dims, spacing, VoxelType::U8, data).is_err();
        assert!(bad([0, 1, 1], [1.0; 3], vec![]));
        assert!(bad([2, 2, 2], [1.0; 3], ramp(7)));
        assert!(bad([1, 1, 2], [1.0, 0.0, 1.0], ramp(2)));
        assert!(bad([1, 1, 2], [1.0, f64::NAN, 1.0], ramp(2)));
        assert!(
            bad([1, 1, 2], [1.0, 1e-5, 1.0], ramp(2)),
            "a spacing ratio above 1e4"
        );
        assert!(
            !bad([1, 1, 2], [1.0, 1e-4, 1.0], ramp(2)),
            "a ratio of 1e4 is allowed"
        );
        // A volume with no finite voxel is described, not analysed.
        let empty = Volume::new([1, 1, 2], [1.0; 3], VoxelType::U8, vec![f32::NAN; 2]).unwrap();
        assert_eq!(empty.histogram(4).unwrap(), vec![0; 4]);
        assert!(matches!(empty.quantizer(4), Err(Error::Degenerate(_))));
    }

    #[test]
    fn histogram_counts_every_finite_voxel() {
        let mut data = ramp(64);
        data[0] = f32::NAN;
        let v = Volume::new([4, 4, 4], [1.0; 3], VoxelType::F32, data).unwrap();
        let h = v.histogram(4).unwrap();
        // Range [1, 63]: bin = floor((v - 1) * 4 / 62), so 63 lands in the last bin by the clamp.
        assert_eq!(h.iter().sum::<u64>(), 63);
        assert_eq!(h, vec![16, 15, 16, 16]);
    }

    #[test]
    fn constant_volume_is_reported() {
        let v = Volume::new([2, 2, 1], [1.0; 3], VoxelType::U8, vec![3.0; 4]).unwrap();
        assert!(v.is_constant());
        assert_eq!(v.histogram(8).unwrap()[0], 4);
    }
}
