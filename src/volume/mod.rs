//! The volume: voxels in their own type (see [`voxels`]) with x fastest, spacing in millimetres,
//! statistics and quantization.

pub mod background;
pub mod cells;
pub mod interpolate;
pub mod labels;
pub mod mapped;
pub mod phantom;
pub mod pyramid;
mod quantize;
pub(crate) mod scratch;
mod slab;
mod voxel;
pub mod voxels;
mod wide;

use std::sync::{Arc, OnceLock};

use ndarray::{ArrayView3, ShapeBuilder};
use rayon::prelude::*;

pub use background::parts::{
    BackgroundJoin, Chunk, ChunkAnswer, ChunkLabels, ChunkMask, ChunkSummary,
};
pub use pyramid::Resolution;
pub use quantize::Quantizer;
pub use slab::{SlabGrid, VoxelBox};
pub use voxel::{Endian, VoxelType};
pub(crate) use voxel::{decode_to, write_le};
pub(crate) use voxels::with_voxels;
pub use voxels::{LentBytes, Voxel, VoxelQuantizer, Voxels};

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

/// A scalar volume: voxels in the type they are held in ([`Voxels`]: integers of at most 16 bits
/// as stored, everything else as f32), x fastest in memory, with physical spacing.
///
/// Voxels that were NaN or infinite in the file are held as NaN and count as missing: they are
/// left out of statistics, histograms and every measure.
#[derive(Clone, Debug)]
pub struct Volume {
    data: Voxels,
    dims: [usize; 3],
    spacing: [f64; 3],
    voxel_type: VoxelType,
    stats: Stats,
    transform: WorldTransform,
    /// Where this volume sits in its pyramid (level 0 for a volume read from a file).
    level: Level,
    /// The distinct values with their counts when this is a label volume, found once.
    labels: Arc<OnceLock<Option<LabelCounts>>>,
    /// The coarser levels of this volume's pyramid, shared by all its levels: slot `i` holds
    /// pyramid level `i + 1`, built once when first asked for.
    pyramid: Arc<pyramid::Pyramid>,
    /// Whether its voxels were fetched from a store at a URL ([`Volume::is_remote`]).
    remote: bool,
}

/// The distinct values of a label volume with their voxel counts.
pub type LabelCounts = Vec<(f32, u64)>;

/// A volume's place in its multiresolution pyramid (docs/design.md §5).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Level {
    /// The pyramid level: 0 is the volume as read.
    pub index: usize,
    /// Per axis, how many voxels of level 0 one voxel of this level spans.
    pub factor: [usize; 3],
    /// Level 0's `[min, max]`, which every level is quantized with.
    pub range: [f32; 2],
    /// Whether level 0 is a label volume (coarser levels then take the most frequent label).
    pub labels: bool,
}

impl Volume {
    /// Builds a volume from f32 voxels in x-fastest order (held as f32, whatever `voxel_type`
    /// the file stored).
    ///
    /// Fails when a dimension is zero, the voxel count does not match, a spacing is not a positive
    /// finite number or lies more than [`MAX_SPACING_RATIO`] from another. A volume with no
    /// finite voxel is made (it can be described) but cannot be analysed.
    pub fn new(
        dims: [usize; 3],
        spacing: [f64; 3],
        voxel_type: VoxelType,
        voxels: Vec<f32>,
    ) -> Result<Self> {
        check_shape(dims, spacing, voxels.len())?;
        Self::from_voxels(dims, spacing, voxel_type, Voxels::from_f32(voxels))
    }

    /// Builds a volume from voxels held in their own type (f32 ones with no infinity: a reader
    /// stores those as NaN), under the same checks as [`Volume::new`].
    pub fn from_voxels(
        dims: [usize; 3],
        spacing: [f64; 3],
        voxel_type: VoxelType,
        data: Voxels,
    ) -> Result<Self> {
        check_shape(dims, spacing, data.len())?;
        let stats = crate::volume::with_voxels!(&data, |v| compute_stats(v));
        Ok(Self {
            data,
            dims,
            spacing,
            voxel_type,
            stats,
            transform: WorldTransform::unknown(spacing),
            level: Level {
                index: 0,
                factor: [1; 3],
                range: [stats.min, stats.max],
                labels: false,
            },
            labels: Arc::default(),
            pyramid: pyramid::empty(dims),
            remote: false,
        })
    }

    /// Whether this volume's voxels were fetched from a store at a URL (every level of it,
    /// computed or read): the process then keeps the answers to the store's chunk requests in
    /// memory, a share of the memory budget that the planner leaves them
    /// ([`Budget`](crate::budget::Budget)).
    #[must_use]
    pub fn is_remote(&self) -> bool {
        self.remote
    }

    /// This volume, its voxels fetched from a store at a URL ([`Volume::is_remote`]).
    #[must_use]
    pub(crate) fn fetched_remotely(mut self) -> Self {
        self.remote = true;
        self
    }

    /// The distinct values with their voxel counts when this looks like a label volume (see
    /// [`labels::label_values`]), worked out once; for a coarser pyramid level, level 0's.
    #[must_use]
    pub fn labels(&self) -> Option<&[(f32, u64)]> {
        self.labels
            .get_or_init(|| labels::label_values(self))
            .as_deref()
    }

    /// Dimensions `[nx, ny, nz]`.
    #[must_use]
    pub fn dims(&self) -> [usize; 3] {
        self.dims
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
            self.pyramid = pyramid::empty(self.dims);
        }
        self
    }

    /// This volume, its voxels said to be of type `ty` (a reader that learns the type from the
    /// values, after they are read, and has checked that they all are values of `ty`): f32
    /// voxels in memory are then held as `ty` where it is held as stored.
    #[must_use]
    pub(crate) fn with_voxel_type(mut self, ty: VoxelType) -> Self {
        self.voxel_type = ty;
        // Missing voxels (a resampled series' outside) have no integer to be: such a volume
        // stays f32.
        if self.stats.missing == 0
            && let Voxels::F32(voxels::Store::Owned(values)) = self.data
        {
            self.data = Voxels::narrowed(Arc::unwrap_or_clone(values), ty);
        }
        self.labels = Arc::default();
        self.pyramid = pyramid::empty(self.dims);
        self
    }

    /// This volume, declared a label volume by its file (an OME-Zarr label image): its distinct
    /// values are its labels however they lie, when it has integer voxels of at most
    /// [`labels::MAX_LABELS`] values.
    #[must_use]
    pub(crate) fn declared_labels(mut self) -> Self {
        self.labels = Arc::new(OnceLock::from(labels::declared_label_values(&self)));
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

    /// The voxels, in the type they are held in, in memory order: index `x + nx * (y + ny * z)`.
    #[must_use]
    pub fn data(&self) -> &Voxels {
        &self.data
    }

    /// The voxels of a volume held as f32, in memory order.
    ///
    /// # Panics
    /// When the voxels are held in another type (see [`Volume::data`]).
    #[must_use]
    pub fn voxels(&self) -> &[f32] {
        match &self.data {
            Voxels::F32(s) => s.as_slice(),
            other => panic!("voxels held as {}, not f32", other.held()),
        }
    }

    /// The voxels of a volume held as f32, as an array indexed `[x, y, z]`.
    ///
    /// # Panics
    /// When the voxels are held in another type (see [`Volume::data`]).
    #[must_use]
    pub fn array(&self) -> ArrayView3<'_, f32> {
        ArrayView3::from_shape(self.dims.f(), self.voxels()).expect("dims match the voxels")
    }

    /// The voxel at index `[x, y, z]`, as f32.
    #[must_use]
    pub fn value(&self, [x, y, z]: [usize; 3]) -> f32 {
        let [nx, ny, _] = self.dims;
        self.data.get(x + nx * (y + ny * z))
    }

    /// Bytes the voxels take in memory as held: none when they are read in place from a
    /// mapped file.
    #[must_use]
    pub fn memory_bytes(&self) -> u64 {
        if self.data.is_mapped() {
            0
        } else {
            self.data.bytes()
        }
    }

    /// Bytes of the file read in place for the voxels (mapped, not copied): 0 when they are in
    /// memory.
    #[must_use]
    pub fn mapped_bytes(&self) -> u64 {
        if self.data.is_mapped() {
            self.data.bytes()
        } else {
            0
        }
    }

    /// Bytes of a scratch file on disk the voxels were decoded into, as they did not fit in the
    /// memory budget (docs/design.md §5): 0 when they are in memory or read in place.
    #[must_use]
    pub fn scratch_bytes(&self) -> u64 {
        if self.data.is_scratch() {
            self.data.bytes()
        } else {
            0
        }
    }

    /// Bytes the voxels take as the file stores them (in the file's voxel type).
    #[must_use]
    pub fn stored_bytes(&self) -> u64 {
        (self.len() * self.voxel_type.size()) as u64
    }

    /// The quantizer of docs/design.md §2 for `bins` bins over this volume's finite range.
    pub fn quantizer(&self, bins: usize) -> Result<Quantizer> {
        self.require_data()?;
        let [min, max] = self.level.range;
        Quantizer::new(min, max, bins)
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
        Ok(crate::volume::with_voxels!(&self.data, |voxels| {
            histogram_of(voxels, q)
        }))
    }
}

/// Counts of `voxels` per bin of `q`.
fn histogram_of<T: Voxel>(voxels: &[T], q: Quantizer) -> Vec<u64> {
    let bins = q.bins();
    let q = VoxelQuantizer::new::<T>(q);
    voxels
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
        )
}

/// Fails unless `dims` has a voxel on every axis, `count` is their product and the spacing is
/// usable (see [`Volume::new`]).
fn check_shape(dims: [usize; 3], spacing: [f64; 3], count: usize) -> Result<()> {
    if dims.contains(&0) {
        return Err(Error::invalid(
            "dims",
            dims_string(dims),
            "at least one voxel along each axis",
        ));
    }
    let expected = dims.iter().try_fold(1usize, |a, &d| a.checked_mul(d));
    if expected != Some(count) {
        return Err(Error::invalid(
            "voxels",
            count,
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
    Ok(())
}

/// `"NXxNYxNZ"`.
#[must_use]
pub fn dims_string(dims: [usize; 3]) -> String {
    format!("{}x{}x{}", dims[0], dims[1], dims[2])
}

fn compute_stats<T: Voxel>(voxels: &[T]) -> Stats {
    if T::TYPE != VoxelType::F32 {
        return integer_stats(voxels);
    }
    let (min, max, sum, finite) = voxels
        .par_chunks(1 << 16)
        .map(|chunk| {
            let (mut lo, mut hi, mut sum, mut n) = (f32::INFINITY, f32::NEG_INFINITY, 0.0f64, 0);
            for &v in chunk {
                let v = v.to_f32();
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

/// [`compute_stats`] of integer voxels, in integers: every voxel is finite, and the sum (below
/// 2⁵³) is the one the f64 sum of the f32 path gives, exactly.
fn integer_stats<T: Voxel>(voxels: &[T]) -> Stats {
    let (min, max, sum) = voxels
        .par_chunks(1 << 16)
        .map(|chunk| {
            // Vectorized with AVX2's minimum and maximum of 32-bit integers (docs/performance.md).
            wide::wide(|| {
                let (mut lo, mut hi, mut sum) = (i32::MAX, i32::MIN, 0i64);
                for &v in chunk {
                    let x = v.integer().unwrap_or(0);
                    lo = lo.min(x);
                    hi = hi.max(x);
                    sum += i64::from(x);
                }
                (lo, hi, sum)
            })
        })
        .reduce(
            || (i32::MAX, i32::MIN, 0),
            |a, b| (a.0.min(b.0), a.1.max(b.1), a.2 + b.2),
        );
    let n = voxels.len();
    let (min, max) = if n == 0 {
        (f32::INFINITY, f32::NEG_INFINITY)
    } else {
        (min as f32, max as f32)
    };
    Stats {
        min,
        max,
        mean: if n > 0 { sum as f64 / n as f64 } else { 0.0 },
        finite: n,
        missing: 0,
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
    fn integer_stats_are_the_float_stats() {
        let ints: Vec<u16> = (0..1000u32).map(|i| (i * 7919 % 65536) as u16).collect();
        let floats: Vec<f32> = ints.iter().map(|&v| f32::from(v)).collect();
        let (a, b) = (compute_stats(&ints), compute_stats(&floats));
        assert_eq!(
            (a.min, a.max, a.mean, a.finite, a.missing),
            (b.min, b.max, b.mean, b.finite, b.missing)
        );
        assert_eq!((a.min, a.max), (0.0, 65317.0));
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
