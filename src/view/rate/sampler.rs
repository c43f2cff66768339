//! Quantized trilinear sampling for the view search: the bin of a sample, answered from the cell
//! map where a cell's eight corners share a bin, and the exact span of a ray that lies inside
//! cells, where the walks need no clamping.

use crate::geometry::lattice::{FIXED_BITS, FIXED_STEP, ceil_i64, to_fixed};
use crate::volume::cells::{MIXED, cell_map, cells_only, cells_window, voxel_map_window};
use crate::volume::interpolate::Interpolator;
use crate::volume::voxels::BinTable;
use crate::volume::{Quantizer, Volume, Voxel, VoxelType};

/// Quantized trilinear sampling: the bin of the interpolated value, as
/// [`Quantizer::bin`]`(`[`Interpolator::sample`]`)` gives it, but answered from a cell map (see
/// [`cell_map`]) where all eight corners of a cell lie in one bin with a margin for rounding:
/// the map only saves work, it never changes a result.
pub struct BinSampler<'a, T = f32> {
    it: Interpolator<'a, T>,
    q: Quantizer,
    /// The cell map of the cells from linear index `base` on: the whole map, or a window of it
    /// (see [`BinSampler::window`]); a cell outside is answered by interpolation.
    cells: Vec<u8>,
    base: usize,
    voxel_bins: VoxelBins,
    dims: [usize; 3],
}

/// How a sampler knows the bin of a voxel.
pub enum VoxelBins {
    /// Per voxel from the sampler's `base` on: the bin it safely lies in, or [`MIXED`] (see
    /// [`cell_map`]), for f32; a voxel outside is answered from its value.
    Map(Vec<u8>),
    /// The bins of every value of an integer type of at most 16 bits, exactly.
    Table(BinTable),
}

impl<'a> BinSampler<'a, f32> {
    /// Builds the cell map of `volume`, held as f32, for quantizer `q` (one byte per voxel).
    ///
    /// # Panics
    /// When the voxels are held in another type: use [`BinSampler::over`].
    pub fn new(volume: &'a Volume, q: Quantizer) -> Self {
        Self::over(volume.voxels(), volume, q)
    }
}

impl<'a, T: Voxel> BinSampler<'a, T> {
    /// Builds the cell map of `volume`, whose voxels `data` are, for quantizer `q` (one byte per
    /// voxel).
    pub fn over(data: &'a [T], volume: &Volume, q: Quantizer) -> Self {
        // Integers are binned by table, exactly: no per-voxel map, so a byte a voxel in all.
        let (cells, voxel_bins) = if let Some(table) = BinTable::new::<T>(&q) {
            (cells_only(volume, &q), VoxelBins::Table(table))
        } else {
            let (cells, map) = cell_map(volume, &q);
            (cells, VoxelBins::Map(map))
        };
        Self {
            it: Interpolator::over(data, volume.dims()),
            cells,
            base: 0,
            voxel_bins,
            dims: volume.dims(),
            q,
        }
    }

    /// A sampler of all of `volume` (whose voxels `data` are) that holds the cell map of the
    /// planes of cells `planes` alone (and the per-voxel map of their voxels, for f32): a byte a
    /// voxel of those planes instead of the whole volume's. It answers every sample as
    /// [`over`](Self::over)'s does; outside the planes, by interpolating the voxels (the map
    /// only saves work).
    pub fn window(
        data: &'a [T],
        volume: &Volume,
        q: Quantizer,
        planes: std::ops::Range<usize>,
    ) -> Self {
        let [nx, ny, _] = volume.dims();
        let range = planes.start * nx * ny..(planes.end * nx * ny).min(data.len());
        let voxel_bins = match BinTable::new::<T>(&q) {
            Some(table) => VoxelBins::Table(table),
            None => VoxelBins::Map(voxel_map_window(volume, &q, range.clone())),
        };
        Self {
            it: Interpolator::over(data, volume.dims()),
            cells: cells_window(volume, &q, range.clone()),
            base: range.start,
            voxel_bins,
            dims: volume.dims(),
            q,
        }
    }

    /// The cell map's entry for cell `index`: [`MIXED`] outside the planes held.
    #[inline]
    fn cell_entry(&self, index: usize) -> u8 {
        self.cells
            .get(index.wrapping_sub(self.base))
            .copied()
            .unwrap_or(MIXED)
    }

    /// Number of bins.
    pub fn bins(&self) -> usize {
        self.q.bins()
    }

    /// The bin of the value at `p` (inside the volume up to rounding), `None` when missing.
    #[inline]
    pub fn bin(&self, p: [f64; 3]) -> Option<u8> {
        self.bin_fixed(to_fixed(p))
    }

    /// The bin of the value at `p` in 32.32 fixed-point index coordinates (see [`to_fixed`]),
    /// inside the volume up to rounding: positions just outside are clamped into it.
    pub fn bin_fixed(&self, p: [i64; 3]) -> Option<u8> {
        let mut index = 0;
        let mut corner = [0i64; 3];
        for m in 0..3 {
            let i = (p[m].max(0) >> FIXED_BITS).min(self.it.last[m] as i64);
            corner[m] = i;
            index += i as usize * self.it.stride[m];
        }
        match self.cell_entry(index) {
            MIXED => {
                let f = std::array::from_fn(|m| {
                    ((p[m].max(0) - (corner[m] << FIXED_BITS)) as f64 * FIXED_STEP) as f32
                });
                self.q.bin(self.it.interpolate(index, f))
            }
            bin => Some(bin),
        }
    }

    /// The samples `t` in `0..n` of the ray `p + t·step` (fixed point) that lie inside a cell
    /// without clamping (each coordinate in `[0, last + 1)`), as a range `t0..t1`: there
    /// [`inner_bin`](Self::inner_bin) applies. Empty ranges are `n..n`.
    pub fn inner_span(&self, p: [i64; 3], step: [i64; 3], n: i64) -> (i64, i64) {
        self.inner_spans(step).of(p, n)
    }

    /// [`inner_span`](Self::inner_span) for many rays of one `step`.
    pub fn inner_spans(&self, step: [i64; 3]) -> InnerSpans {
        InnerSpans {
            step,
            inverse: step.map(|s| 1.0 / s as f64),
            end: std::array::from_fn(|m| ((self.it.last[m] + 1) as i128) << FIXED_BITS),
        }
    }

    /// The linear index of the cell around `p` (fixed point), which must lie in
    /// [`inner_span`](Self::inner_span)'s range for the index to be meaningful (anywhere else
    /// it is some number, fit only for [`prefetch_cell`](Self::prefetch_cell)).
    #[inline]
    pub fn inner_cell(&self, p: [i64; 3]) -> usize {
        let [sx, sy, sz] = self.it.stride;
        ((p[0] >> FIXED_BITS) as usize)
            .wrapping_mul(sx)
            .wrapping_add(((p[1] >> FIXED_BITS) as usize).wrapping_mul(sy))
            .wrapping_add(((p[2] >> FIXED_BITS) as usize).wrapping_mul(sz))
    }

    /// Asks the processor to bring cell `index` of the map into cache, for a read soon after.
    /// Any index may be given: a prefetch never faults.
    #[inline]
    pub fn prefetch_cell(&self, index: usize) {
        prefetch(
            self.cells
                .as_ptr()
                .wrapping_add(index.wrapping_sub(self.base)),
        );
    }

    /// Asks the processor to bring the corner voxels of cell `index` into cache.
    #[inline]
    pub fn prefetch_corners(&self, index: usize) {
        let [_, y, z] = self.it.next;
        let base = self.it.data.as_ptr().wrapping_add(index);
        for offset in [0, y, z, y + z] {
            prefetch(base.wrapping_add(offset));
        }
    }

    /// The cell map held: per cell (at the linear index of its lower corner voxel less
    /// [`cells_base`](Self::cells_base)) its bin or [`MIXED`].
    pub fn cells(&self) -> &[u8] {
        &self.cells
    }

    /// The linear index of the first cell [`cells`](Self::cells) holds: 0 unless a
    /// [`window`](Self::window).
    pub fn cells_base(&self) -> usize {
        self.base
    }

    /// How the bin of a voxel is known: a per-voxel map whose [`MIXED`] entries
    /// [`voxel_bin_at`] resolves, or a table.
    ///
    /// [`voxel_bin_at`]: Self::voxel_bin_at
    pub fn voxel_bins(&self) -> &VoxelBins {
        &self.voxel_bins
    }

    /// The bin of the voxel at linear index `index`, `None` when it is missing.
    #[inline]
    pub fn voxel_bin_at(&self, index: usize) -> Option<u8> {
        match &self.voxel_bins {
            VoxelBins::Table(table) => Some(table.bin(self.it.data[index])),
            VoxelBins::Map(map) => match map.get(index.wrapping_sub(self.base)) {
                Some(&b) if b != MIXED => Some(b),
                _ => self.q.bin(self.it.at(index)),
            },
        }
    }

    /// The quantizer.
    pub fn quantizer(&self) -> &Quantizer {
        &self.q
    }

    /// The voxels, x fastest.
    pub fn voxels(&self) -> &'a [T] {
        self.it.data
    }

    /// Offsets from a cell's lower corner voxel to its neighbours along x, y and z (0 along an
    /// axis of one voxel, whose cells are flat).
    pub fn corner_steps(&self) -> [usize; 3] {
        self.it.next
    }

    /// Dimensions of the voxel grid.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Linear memory strides of the voxel grid along x, y and z.
    pub fn strides(&self) -> [usize; 3] {
        self.it.stride
    }

    /// The bin of cell `index` when all its samples share one, else [`MIXED`].
    #[inline]
    pub fn cell_bin(&self, index: usize) -> u8 {
        self.cell_entry(index)
    }

    /// The bin of the trilinear sample at `p` in cell `index`, where `p` lies in
    /// [`inner_span`](Self::inner_span)'s range and `index` is its
    /// [`inner_cell`](Self::inner_cell); `None` when a voxel it mixes is missing.
    #[inline]
    pub fn inner_bin(&self, p: [i64; 3], index: usize) -> Option<u8> {
        let mask = (1i64 << FIXED_BITS) - 1;
        let f = p.map(|c| ((c & mask) as f64 * FIXED_STEP) as f32);
        self.q.bin(self.it.interpolate(index, f))
    }

    /// The bin of the voxel at `p`, which must be a voxel centre (whole index coordinates in
    /// fixed point) inside the volume; `None` when it is missing.
    #[inline]
    pub fn voxel_bin(&self, p: [i64; 3]) -> Option<u8> {
        self.voxel_bin_at(self.inner_cell(p))
    }
}

/// Asks the processor to bring the cache line at `address` into cache. Any address may be
/// given: a prefetch never faults.
#[inline]
#[allow(unsafe_code)]
fn prefetch<T>(address: *const T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch is a hint: it reads nothing into the program and does not fault on any
    // address, so the pointer needs no validity.
    unsafe {
        std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(address.cast());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = address;
}

/// The inner spans of rays that share a step (see [`BinSampler::inner_span`]), with the step's
/// reciprocals worked out once.
pub struct InnerSpans {
    step: [i64; 3],
    inverse: [f64; 3],
    end: [i128; 3],
}

impl InnerSpans {
    /// The inner span of the ray from `p` with `n` samples.
    pub fn of(&self, p: [i64; 3], n: i64) -> (i64, i64) {
        // The samples inside cells are where a line meets a box: one run. Most rays start and
        // end inside, and then that is all of them.
        let inside = |t: i64| {
            (0..3).all(|m| {
                self.step[m]
                    .checked_mul(t)
                    .and_then(|d| d.checked_add(p[m]))
                    .is_some_and(|c| c >= 0 && i128::from(c) < self.end[m])
            })
        };
        if n > 0 && inside(0) && inside(n - 1) {
            return (0, n);
        }
        let (mut t0, mut t1) = (0i64, n);
        for m in 0..3 {
            // 0 <= p + t·s < end, in exact integer arithmetic (i128 only where i64 might not
            // hold it: no ordinary volume).
            let (end, s) = (self.end[m], self.step[m]);
            if end < 1 << 60 && p[m].unsigned_abs() < 1 << 60 && s.unsigned_abs() < 1 << 60 {
                let (lo, hi) = span_along(p[m], s, self.inverse[m], end as i64);
                t0 = t0.max(lo.clamp(0, n));
                t1 = t1.min(hi.clamp(0, n));
                continue;
            }
            let (p, s) = (i128::from(p[m]), i128::from(s));
            let (lo, hi) = match s.cmp(&0) {
                std::cmp::Ordering::Equal if (0..end).contains(&p) => continue,
                std::cmp::Ordering::Equal => (0, 0),
                std::cmp::Ordering::Greater => (div_ceil(-p, s), div_floor(end - 1 - p, s) + 1),
                std::cmp::Ordering::Less => (div_ceil(end - 1 - p, s), div_floor(-p, s) + 1),
            };
            t0 = t0.max(lo.clamp(0, n as i128) as i64);
            t1 = t1.min(hi.clamp(0, n as i128) as i64);
        }
        if t0 < t1 { (t0, t1) } else { (n, n) }
    }
}

/// The range `lo..hi` of `t` with `0 <= p + t·s < end`, all below 2^60 in magnitude, given
/// `inverse = 1 / s`; an empty range when there is none, and `i64::MIN..i64::MAX` for every
/// `t`. Exact, without integer division (rays need it once each, and a division costs tens of
/// cycles).
fn span_along(p: i64, s: i64, inverse: f64, end: i64) -> (i64, i64) {
    // The smallest t with p + t·s >= bound, for s > 0: a floating-point guess, made exact.
    let first = |s: i64, inverse: f64, bound: i64| {
        let reaches = |t: i64| i128::from(p) + i128::from(t) * i128::from(s) >= i128::from(bound);
        let mut t = ceil_i64((bound - p) as f64 * inverse);
        while !reaches(t) {
            t += 1;
        }
        while reaches(t - 1) {
            t -= 1;
        }
        t
    };
    match s.cmp(&0) {
        std::cmp::Ordering::Equal if (0..end).contains(&p) => (i64::MIN, i64::MAX),
        std::cmp::Ordering::Equal => (0, 0),
        std::cmp::Ordering::Greater => (first(s, inverse, 0), first(s, inverse, end)),
        // p + t·s = p + (-t)·(-s): mirror the range.
        std::cmp::Ordering::Less => (1 - first(-s, -inverse, end), 1 - first(-s, -inverse, 0)),
    }
}

fn div_floor(a: i128, b: i128) -> i128 {
    let q = a / b;
    if (a % b != 0) && ((a < 0) != (b < 0)) {
        q - 1
    } else {
        q
    }
}

fn div_ceil(a: i128, b: i128) -> i128 {
    -div_floor(-a, b)
}

/// The bytes [`BinSampler::window`] holds for `planes` planes of cells of a volume of `dims`
/// voxels of `voxel_type` (one a voxel, two for f32 with its per-voxel map).
#[must_use]
pub fn window_bytes(voxel_type: VoxelType, dims: [usize; 3], planes: usize) -> u64 {
    let per_voxel = if BinTable::exists(voxel_type) { 1 } else { 2 };
    (dims[0] * dims[1] * planes * per_voxel) as u64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::Lcg;
    use crate::volume::VoxelType;

    #[test]
    fn the_cell_map_never_changes_a_bin() {
        // Blocky data with noise: many uniform cells, many mixed ones, values at bin edges.
        let dims = [20, 17, 13];
        let mut lcg = Lcg::with_increment(9, 1);
        let data: Vec<f32> = (0..dims.iter().product::<usize>())
            .map(|i| {
                let state = lcg.next_u64();
                let block = ((i % 20) / 5 + (i / 340) / 4) as f32 * 25.0;
                block + ((state >> 40) % 4) as f32 * if i % 7 == 0 { 3.0 } else { 0.0 }
            })
            .collect();
        let vol = Volume::new(dims, [1.0; 3], VoxelType::F32, data).unwrap();
        for bins in [2, 7, 32] {
            let q = vol.quantizer(bins).unwrap();
            let fast = BinSampler::new(&vol, q);
            let it = Interpolator::new(&vol);
            let mut uniform = 0;
            for n in 0..20_000u32 {
                let h = |k: u32| f64::from((n.wrapping_mul(2_654_435_761) >> k) % 1000) / 999.0;
                let p = [h(0) * 19.0, h(7) * 16.0, h(13) * 12.0];
                assert_eq!(fast.bin(p), q.bin(it.sample(p)), "{p:?} with {bins} bins");
                let base = (p[0] as usize).min(18)
                    + 20 * ((p[1] as usize).min(15) + 17 * (p[2] as usize).min(11));
                uniform += usize::from(fast.cells[base] != MIXED);
            }
            assert!(uniform > 1000, "the map is used ({uniform} uniform hits)");
        }
    }

    #[test]
    fn spans_along_one_coordinate_match_a_brute_force_search() {
        let mut lcg = Lcg::with_increment(5, 1);
        let mut next = |n: i64| (lcg.next_u64() >> 33) as i64 % n;
        for _ in 0..5000 {
            let (p, s, end) = (next(201) - 100, next(41) - 20, next(60) + 1);
            let (lo, hi) = span_along(p, s, 1.0 / s as f64, end);
            for t in -300..300 {
                let inside = (0..end).contains(&(p + t * s));
                assert_eq!(inside, (lo..hi).contains(&t), "p {p} s {s} end {end} t {t}");
            }
        }
    }

    #[test]
    fn inner_spans_are_exactly_the_samples_inside_cells() {
        let dims = [6, 5, 7];
        let v = Volume::new(dims, [1.0; 3], VoxelType::F32, vec![1.0; 210]).unwrap();
        let sampler = BinSampler::new(&v, v.quantizer(4).unwrap());
        let one = 1i64 << FIXED_BITS;
        let inside = |p: [i64; 3]| (0..3).all(|m| p[m] >= 0 && p[m] < (dims[m] as i64 - 1) * one);
        for (p, step) in [
            ([0, 0, 0], [one, 0, 0]),
            ([0, 0, 0], [one / 5, one / 6, one / 7]),
            ([-3, one / 2, one], [one / 3, one / 7, -one / 5]),
            ([5 * one, 4 * one, 6 * one], [-one, -one, -one]),
            ([one, 4 * one, one], [one / 2, 0, one / 4]),
            ([2 * one + 1, one, one], [0, 0, 0]),
        ] {
            let n = 40;
            let (t0, t1) = sampler.inner_span(p, step, n);
            let expect: Vec<i64> = (0..n)
                .filter(|&t| inside(std::array::from_fn(|m| p[m] + t * step[m])))
                .collect();
            let got: Vec<i64> = (t0..t1).collect();
            // The samples inside cells form one run along a straight line.
            assert_eq!(got, expect, "{p:?} + t·{step:?}");
        }
        // Random rays of one step, as a lattice has them: starting inside, on a face, or
        // outside, and ending inside or out.
        let mut lcg = Lcg::new(3);
        let mut next = move |n: i64| (lcg.next_u64() >> 33) as i64 % n;
        for _ in 0..200 {
            let step: [i64; 3] = std::array::from_fn(|_| next(2 * one) - one);
            let spans = sampler.inner_spans(step);
            for _ in 0..50 {
                let p = std::array::from_fn(|m| next((dims[m] as i64 + 2) * one) - one);
                let n = next(12);
                let (t0, t1) = spans.of(p, n);
                let expect: Vec<i64> = (0..n)
                    .filter(|&t| inside(std::array::from_fn(|m| p[m] + t * step[m])))
                    .collect();
                let got: Vec<i64> = (t0..t1).collect();
                assert_eq!(got, expect, "{p:?} + t·{step:?}, {n} samples");
                assert!(t0 < t1 || t0 == n, "empty spans are n..n");
            }
        }
    }
}
