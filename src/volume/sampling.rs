//! Sampling a volume along an arbitrary axis on the ray lattice of DESIGN.md §2, with trilinear
//! interpolation. Used by the view search (rays) and by oblique slice stacks (planes).

use crate::error::{Error, Result};
use crate::volume::cells::{MIXED, cell_map};
use crate::volume::{Quantizer, Volume};

/// Dot product.
#[inline]
pub fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Cross product.
#[inline]
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `a` scaled to unit length, or `None` for a zero or non-finite vector.
pub fn normalize(a: [f64; 3]) -> Option<[f64; 3]> {
    let n = dot(a, a).sqrt();
    (n.is_finite() && n > 1e-12).then(|| a.map(|c| c / n))
}

/// The coordinate axis (0 for x, 1 for y, 2 for z) that the unit vector `d` lies along, if any.
pub fn coordinate_axis(d: [f64; 3]) -> Option<usize> {
    (0..3).find(|&m| d[m].abs() > 1.0 - 1e-12)
}

/// The canonical one of `d` and `-d`: the one whose first non-zero component (|c| > 1e-9, in
/// x, y, z order) is positive.
pub fn canonical(d: [f64; 3]) -> [f64; 3] {
    match d.iter().find(|c| c.abs() > 1e-9) {
        Some(c) if *c < 0.0 => d.map(|c| -c),
        _ => d,
    }
}

/// The orthonormal frame `(d, u, v)` of DESIGN.md §2: `e` is the coordinate axis where `|d|` has
/// its smallest component (the first on ties), `u = normalize(e - (e·d) d)`, `v = d × u`.
pub fn frame(d: [f64; 3]) -> Result<([f64; 3], [f64; 3], [f64; 3])> {
    let d = normalize(d)
        .ok_or_else(|| Error::InvalidParameter(format!("axis {d:?} has no direction")))?;
    let mut smallest = 0;
    for k in 1..3 {
        if d[k].abs() < d[smallest].abs() {
            smallest = k;
        }
    }
    let mut e = [0.0; 3];
    e[smallest] = 1.0;
    let ed = dot(e, d);
    let u = normalize([e[0] - ed * d[0], e[1] - ed * d[1], e[2] - ed * d[2]])
        .expect("e is not parallel to d, since it is d's smallest component");
    Ok((d, u, cross(d, u)))
}

/// One ray of a lattice: sample `k` (for `k` in `k0..=k1`) lies at `origin + k·step` in voxel
/// index coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Position of sample `k = 0`, in voxel index coordinates.
    pub origin: [f64; 3],
    /// Displacement between consecutive samples, in voxel index coordinates.
    pub step: [f64; 3],
    /// First sample inside the box.
    pub k0: i64,
    /// Last sample inside the box.
    pub k1: i64,
}

impl Ray {
    /// Number of samples.
    pub fn len(&self) -> usize {
        (self.k1 - self.k0 + 1) as usize
    }

    /// Always false: rays are only made when they hold samples.
    pub fn is_empty(&self) -> bool {
        self.k1 < self.k0
    }

    /// Position of sample `k` in voxel index coordinates.
    #[inline]
    pub fn at(&self, k: i64) -> [f64; 3] {
        let k = k as f64;
        [
            self.origin[0] + k * self.step[0],
            self.origin[1] + k * self.step[1],
            self.origin[2] + k * self.step[2],
        ]
    }
}

/// The lattice of parallel rays along an axis: rays through `(i + a)·x·u + (j + b)·x·v`, samples
/// `(k + c)·y·d` along them, counted only inside the box spanned by the first and last voxel
/// centres (physical coordinates, voxel (0,0,0) at the origin). `(a, b, c)` is the phase, zero for
/// the paper's lattice.
#[derive(Clone, Debug)]
pub struct Lattice {
    /// Unit axis direction in physical space.
    pub d: [f64; 3],
    /// First in-plane unit vector.
    pub u: [f64; 3],
    /// Second in-plane unit vector.
    pub v: [f64; 3],
    /// Distance between neighbouring rays, mm.
    pub ray_spacing: f64,
    /// Distance between samples along a ray, mm.
    pub sample_spacing: f64,
    phase: [f64; 3],
    extent: [f64; 3],
    spacing: [f64; 3],
    /// Worked out once for [`ray`](Self::ray), which runs for every ray.
    per_ray: PerRay,
}

/// What every ray of a lattice shares, worked out once.
#[derive(Clone, Debug)]
struct PerRay {
    /// The step between samples in voxel index coordinates.
    step: [f64; 3],
    /// `1 / spacing` where dividing by the spacing and multiplying by this agree for every
    /// number (a power of two), else `None`.
    inverse_spacing: [Option<f64>; 3],
    /// Per axis: the step in mm, and its reciprocal.
    dm: [f64; 3],
    inverse_dm: [f64; 3],
}

impl Lattice {
    /// The lattice along `axis` for a volume of `dims` and `spacing`, with ray spacing `x`, sample
    /// spacing `y` (mm) and a phase in units of the spacings.
    pub fn new(
        dims: [usize; 3],
        spacing: [f64; 3],
        axis: [f64; 3],
        x: f64,
        y: f64,
        phase: [f64; 3],
    ) -> Result<Self> {
        for (name, s) in [("ray spacing", x), ("sample spacing", y)] {
            if !(s.is_finite() && s > 0.0) {
                return Err(Error::InvalidParameter(format!(
                    "{name} must be a positive number of mm, not {s}"
                )));
            }
        }
        let (d, u, v) = frame(axis)?;
        let dm = d.map(|c| y * c);
        Ok(Self {
            d,
            u,
            v,
            ray_spacing: x,
            sample_spacing: y,
            phase,
            extent: std::array::from_fn(|k| (dims[k] - 1) as f64 * spacing[k]),
            spacing,
            per_ray: PerRay {
                step: std::array::from_fn(|m| dm[m] / spacing[m]),
                inverse_spacing: spacing.map(|s| {
                    let inverse = 1.0 / s;
                    (power_of_two(s) && power_of_two(inverse)).then_some(inverse)
                }),
                dm,
                inverse_dm: dm.map(|c| 1.0 / c),
            },
        })
    }

    /// The lattice of `volume` with the default spacings (the smallest voxel spacing).
    pub fn for_volume(volume: &Volume, axis: [f64; 3]) -> Result<Self> {
        let s = min_spacing(volume.spacing());
        Self::new(volume.dims(), volume.spacing(), axis, s, s, [0.0; 3])
    }

    fn corners(&self) -> impl Iterator<Item = [f64; 3]> + '_ {
        (0..8).map(|c| std::array::from_fn(|k| if c >> k & 1 == 1 { self.extent[k] } else { 0.0 }))
    }

    /// The integer range of `t` such that `(t + phase)·spacing` covers the projections of the box
    /// on `axis`.
    fn index_range(&self, axis: [f64; 3], spacing: f64, phase: f64) -> (i64, i64) {
        let (lo, hi) = self
            .corners()
            .map(|c| dot(c, axis))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), t| {
                (a.min(t), b.max(t))
            });
        (
            (lo / spacing - phase - 1e-9).ceil() as i64,
            (hi / spacing - phase + 1e-9).floor() as i64,
        )
    }

    /// Inclusive ranges of the ray indices `i` and `j` that can meet the box.
    pub fn ray_ranges(&self) -> ((i64, i64), (i64, i64)) {
        (
            self.index_range(self.u, self.ray_spacing, self.phase[0]),
            self.index_range(self.v, self.ray_spacing, self.phase[1]),
        )
    }

    /// Inclusive range of the sample index `k` along the axis over the whole box.
    pub fn sample_range(&self) -> (i64, i64) {
        self.index_range(self.d, self.sample_spacing, self.phase[2])
    }

    /// Physical position of lattice point `(i, j, k)`.
    pub fn point(&self, i: i64, j: i64, k: i64) -> [f64; 3] {
        let (a, b, c) = (
            (i as f64 + self.phase[0]) * self.ray_spacing,
            (j as f64 + self.phase[1]) * self.ray_spacing,
            (k as f64 + self.phase[2]) * self.sample_spacing,
        );
        std::array::from_fn(|m| a * self.u[m] + b * self.v[m] + c * self.d[m])
    }

    /// Whether a physical point lies inside the box (with a relative tolerance of 1e-9).
    pub fn inside(&self, p: [f64; 3]) -> bool {
        (0..3).all(|m| {
            let eps = 1e-9 * (1.0 + self.extent[m]);
            p[m] >= -eps && p[m] <= self.extent[m] + eps
        })
    }

    /// Voxel index coordinates of a physical point.
    pub fn to_index(&self, p: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|m| match self.per_ray.inverse_spacing[m] {
            // The same number as the division: the reciprocal of a power of two is exact.
            Some(inverse) => p[m] * inverse,
            None => p[m] / self.spacing[m],
        })
    }

    /// The coordinate axis whose voxel columns are exactly this lattice's rays, sample for
    /// sample: the axis is a coordinate axis, the sample spacing is its voxel spacing, the ray
    /// spacing is the other two, and the phase is whole.
    pub fn columns(&self) -> Option<usize> {
        let m = coordinate_axis(self.d)?;
        let same = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b;
        let whole = |x: f64| (x - round_half_away(x) as f64).abs() < 1e-9;
        (same(self.sample_spacing, self.spacing[m])
            && (0..3).all(|a| a == m || same(self.ray_spacing, self.spacing[a]))
            && self.phase.iter().all(|&c| whole(c)))
        .then_some(m)
    }

    /// Displacement between consecutive samples of a ray, in voxel index coordinates.
    pub fn step(&self) -> [f64; 3] {
        self.per_ray.step
    }

    /// Ray `(i, j)`, or `None` when it misses the box.
    pub fn ray(&self, i: i64, j: i64) -> Option<Ray> {
        let base = self.point(i, j, 0);
        // The samples inside: `(bound - base) / dm` for the two bounds per axis, first with the
        // reciprocal (a few units in the last place from the quotient), then, only when that
        // lies so near a whole number that the two might round to different ones, exactly.
        let (lo, hi) = self.sample_bounds(base, |x, m| x * self.per_ray.inverse_dm[m])?;
        let (k0, k1) = (ceil_i64(lo), floor_i64(hi));
        let margin = |x: f64| 1e-12 * (1.0 + x.abs());
        let clear = k0 as f64 - lo > margin(lo)
            && lo - (k0 - 1) as f64 > margin(lo)
            && hi - k1 as f64 > margin(hi)
            && (k1 + 1) as f64 - hi > margin(hi);
        let (k0, k1) = if clear {
            (k0, k1)
        } else {
            let (lo, hi) = self.sample_bounds(base, |x, m| x / self.per_ray.dm[m])?;
            (ceil_i64(lo), floor_i64(hi))
        };
        (k0 <= k1).then(|| Ray {
            origin: self.to_index(base),
            step: self.step(),
            k0,
            k1,
        })
    }

    /// The range of real `k` where `base + k·y·d` lies in the box (with a tolerance), dividing
    /// by the step along axis `m` with `divide`; `None` when the ray misses the box.
    #[inline]
    fn sample_bounds(
        &self,
        base: [f64; 3],
        divide: impl Fn(f64, usize) -> f64,
    ) -> Option<(f64, f64)> {
        let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
        for m in 0..3 {
            let eps = 1e-9 * (1.0 + self.extent[m]);
            let dm = self.per_ray.dm[m];
            if dm.abs() < 1e-12 {
                if base[m] < -eps || base[m] > self.extent[m] + eps {
                    return None;
                }
                continue;
            }
            // The bounds are ordered as the numerators are when `dm > 0` (rounding keeps the
            // order), the other way round otherwise; all finite, so `>` does what `max` does.
            let t1 = divide(-eps - base[m], m);
            let t2 = divide(self.extent[m] + eps - base[m], m);
            let (near, far) = if dm > 0.0 { (t1, t2) } else { (t2, t1) };
            lo = if near > lo { near } else { lo };
            hi = if far < hi { far } else { hi };
        }
        Some((lo, hi))
    }
}

/// Whether `x` is a power of two in the normal range (no mantissa bits set).
fn power_of_two(x: f64) -> bool {
    x.is_normal() && x.to_bits() & ((1 << 52) - 1) == 0
}

/// `x.floor() as i64` for `|x| < 2^52`, without the library call that `floor` is on
/// processors before SSE4.1.
#[inline]
pub fn floor_i64(x: f64) -> i64 {
    let t = x as i64;
    t - i64::from((t as f64) > x)
}

/// `x.ceil() as i64` for `|x| < 2^52` (see [`floor_i64`]).
#[inline]
pub fn ceil_i64(x: f64) -> i64 {
    let t = x as i64;
    t + i64::from((t as f64) < x)
}

/// The smallest of three spacings.
pub fn min_spacing(spacing: [f64; 3]) -> f64 {
    spacing.iter().copied().fold(f64::INFINITY, f64::min)
}

/// Trilinear interpolation of a volume at voxel index coordinates.
#[derive(Clone, Copy)]
pub struct Interpolator<'a> {
    data: &'a [f32],
    stride: [usize; 3],
    /// Per axis: the stride to the next voxel (0 for a single-voxel axis).
    next: [usize; 3],
    /// Per axis: the largest lower corner index (n - 2, or 0 for a single-voxel axis).
    last: [usize; 3],
}

impl<'a> Interpolator<'a> {
    /// An interpolator over `volume`.
    pub fn new(volume: &'a Volume) -> Self {
        let dims = volume.dims();
        let stride = [1, dims[0], dims[0] * dims[1]];
        Self {
            data: volume.voxels(),
            stride,
            next: std::array::from_fn(|m| if dims[m] > 1 { stride[m] } else { 0 }),
            last: dims.map(|n| n.saturating_sub(2)),
        }
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
    fn interpolate(&self, base: usize, f: [f32; 3]) -> f32 {
        let [x1, y1, z1] = self.next;
        let c = &self.data[base..=base + x1 + y1 + z1];
        let lerp = |a: f32, b: f32, t: f32| a + t * (b - a);
        let c00 = lerp(c[0], c[x1], f[0]);
        let c10 = lerp(c[y1], c[y1 + x1], f[0]);
        let c01 = lerp(c[z1], c[z1 + x1], f[0]);
        let c11 = lerp(c[z1 + y1], c[z1 + y1 + x1], f[0]);
        lerp(lerp(c00, c10, f[1]), lerp(c01, c11, f[1]), f[2])
    }

    /// The value at `p` and its gradient (per voxel index unit), both from the trilinear
    /// interpolant of the cell around `p`, so shading costs no extra voxel reads.
    #[inline]
    pub fn sample_gradient(&self, p: [f64; 3]) -> (f32, [f32; 3]) {
        let (base, f) = self.cell(p);
        let [x1, y1, z1] = self.next;
        let c = &self.data[base..=base + x1 + y1 + z1];
        let lerp = |a: f32, b: f32, t: f32| a + t * (b - a);
        let (c000, c100, c010, c110) = (c[0], c[x1], c[y1], c[y1 + x1]);
        let (c001, c101, c011, c111) = (c[z1], c[z1 + x1], c[z1 + y1], c[z1 + y1 + x1]);
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

    /// The voxel at integer index coordinates.
    #[inline]
    pub fn voxel(&self, x: usize, y: usize, z: usize) -> f32 {
        self.data[x * self.stride[0] + y * self.stride[1] + z * self.stride[2]]
    }
}

/// Fraction bits of fixed-point positions.
pub const FIXED_BITS: u32 = 32;
const FIXED_STEP: f64 = 1.0 / (1u64 << FIXED_BITS) as f64;

/// A position in voxel index coordinates as 32.32 fixed point, so that a ray advances by exact
/// integer additions and finding the cell needs no float-to-integer conversion per sample.
#[inline]
pub fn to_fixed(p: [f64; 3]) -> [i64; 3] {
    p.map(|c| round_half_away(c * (1u64 << FIXED_BITS) as f64))
}

/// `x.round() as i64` (halves away from zero) for `|x| < 2^52`, without the library call that
/// `round` is on processors before SSE4.1.
#[inline]
pub fn round_half_away(x: f64) -> i64 {
    let whole = x as i64;
    // Exact: both are below 2^52 in magnitude.
    let rest = x - whole as f64;
    whole + i64::from(rest >= 0.5) - i64::from(rest <= -0.5)
}

/// Quantized trilinear sampling: the bin of the interpolated value, as
/// [`Quantizer::bin`]`(`[`Interpolator::sample`]`)` gives it, but answered from a cell map (see
/// [`cell_map`]) where all eight corners of a cell lie in one bin with a margin for rounding:
/// the map only saves work, it never changes a result.
pub struct BinSampler<'a> {
    it: Interpolator<'a>,
    q: Quantizer,
    cells: Vec<u8>,
    /// Per voxel: the bin it safely lies in, or `MIXED` (see [`cell_map`]).
    voxel_bins: Vec<u8>,
    dims: [usize; 3],
}

impl<'a> BinSampler<'a> {
    /// Builds the cell map of `volume` for quantizer `q` (one byte per voxel).
    pub fn new(volume: &'a Volume, q: Quantizer) -> Self {
        let (cells, voxel_bins) = cell_map(volume, &q);
        Self {
            it: Interpolator::new(volume),
            cells,
            voxel_bins,
            dims: volume.dims(),
            q,
        }
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
        match self.cells[index] {
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
        prefetch(self.cells.as_ptr().wrapping_add(index));
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

    /// The cell map: per cell (at the linear index of its lower corner voxel) its bin or
    /// [`MIXED`].
    pub fn cells(&self) -> &[u8] {
        &self.cells
    }

    /// Per voxel: the bin it safely lies in, or [`MIXED`] (then [`voxel_bin_at`] tells).
    ///
    /// [`voxel_bin_at`]: Self::voxel_bin_at
    pub fn voxel_bins(&self) -> &[u8] {
        &self.voxel_bins
    }

    /// The bin of the voxel at linear index `index`, `None` when it is missing.
    #[inline]
    pub fn voxel_bin_at(&self, index: usize) -> Option<u8> {
        match self.voxel_bins[index] {
            MIXED => self.q.bin(self.it.data[index]),
            b => Some(b),
        }
    }

    /// The quantizer.
    pub fn quantizer(&self) -> &Quantizer {
        &self.q
    }

    /// The voxels, x fastest.
    pub fn voxels(&self) -> &'a [f32] {
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
        self.cells[index]
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::Lcg;
    use crate::volume::VoxelType;

    #[test]
    fn frame_is_orthonormal_and_follows_the_design() {
        let (d, u, v) = frame([0.0, 0.0, 2.0]).unwrap();
        assert_eq!(
            (d, u, v),
            ([0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
        );
        let (_, u, v) = frame([1.0, 0.0, 0.0]).unwrap();
        assert_eq!((u, v), ([0.0, 1.0, 0.0], [0.0, 0.0, 1.0]));
        for axis in [[1.0, 2.0, 3.0], [-0.3, 0.1, 0.9], [1.0, 1.0, 1.0]] {
            let (d, u, v) = frame(axis).unwrap();
            for (a, b) in [(d, u), (d, v), (u, v)] {
                assert!(dot(a, b).abs() < 1e-12);
            }
            for a in [d, u, v] {
                assert!((dot(a, a) - 1.0).abs() < 1e-12);
            }
        }
        assert!(frame([0.0; 3]).is_err());
    }

    #[test]
    fn canonical_picks_the_positive_first_component() {
        assert_eq!(canonical([-1.0, 2.0, 0.0]), [1.0, -2.0, -0.0]);
        assert_eq!(canonical([0.0, -0.5, 1.0]), [-0.0, 0.5, -1.0]);
        assert_eq!(canonical([1e-12, 0.0, -1.0]), [-1e-12, -0.0, 1.0]);
    }

    #[test]
    fn axis_aligned_rays_are_the_voxel_columns() {
        let l = Lattice::new([4, 3, 5], [1.0; 3], [0.0, 0.0, 1.0], 1.0, 1.0, [0.0; 3]).unwrap();
        assert_eq!(l.ray_ranges(), ((0, 3), (0, 2)));
        let r = l.ray(2, 1).unwrap();
        assert_eq!((r.k0, r.k1), (0, 4));
        assert_eq!(r.at(3), [2.0, 1.0, 3.0]);
        assert!(l.ray(4, 0).is_none());
        assert!(l.ray(-1, 0).is_none());
    }

    /// `Lattice::ray`'s sample range as the definition computes it: a division per bound.
    fn rays_by_division(l: &Lattice, i: i64, j: i64) -> Option<(i64, i64)> {
        let base = l.point(i, j, 0);
        let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
        for m in 0..3 {
            let eps = 1e-9 * (1.0 + l.extent[m]);
            let dm = l.sample_spacing * l.d[m];
            if dm.abs() < 1e-12 {
                if base[m] < -eps || base[m] > l.extent[m] + eps {
                    return None;
                }
                continue;
            }
            let t1 = (-eps - base[m]) / dm;
            let t2 = (l.extent[m] + eps - base[m]) / dm;
            lo = lo.max(t1.min(t2));
            hi = hi.min(t1.max(t2));
        }
        let (k0, k1) = (lo.ceil() as i64, hi.floor() as i64);
        (k0 <= k1).then_some((k0, k1))
    }

    #[test]
    fn rays_are_the_ones_division_gives() {
        // Random axes, spacings and phases, and lattices whose samples fall on the box's faces
        // (whole steps from a whole phase), where a bound is a whole number.
        let mut lcg = Lcg::new(11);
        let mut unit = move || (lcg.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
        let mut cases = vec![
            ([7, 5, 9], [1.0; 3], [1.0, 0.0, 0.0], 1.0, 1.0, [0.0; 3]),
            (
                [7, 5, 9],
                [0.5, 1.0, 2.0],
                [1.0, 1.0, 0.0],
                0.5,
                0.5,
                [0.0; 3],
            ),
            ([7, 5, 9], [1.0; 3], [1.0, 2.0, 2.0], 1.0, 1.0, [0.0; 3]),
            (
                [6, 6, 6],
                [1.0; 3],
                [0.0, 3.0, 4.0],
                1.0,
                1.0,
                [1.0, 0.0, 2.0],
            ),
        ];
        for _ in 0..40 {
            let axis = [unit() - 0.5, unit() - 0.5, unit() - 0.5];
            let spacing = [0.3 + unit(), 0.3 + unit(), 0.3 + unit()];
            let phase = [unit(), unit(), unit()];
            cases.push(([9, 8, 11], spacing, axis, 0.2 + unit(), 0.2 + unit(), phase));
        }
        let mut rays = 0;
        for (dims, spacing, axis, x, y, phase) in cases {
            let l = Lattice::new(dims, spacing, axis, x, y, phase).unwrap();
            let ((i0, i1), (j0, j1)) = l.ray_ranges();
            for j in j0 - 1..=j1 + 1 {
                for i in i0 - 1..=i1 + 1 {
                    let got = l.ray(i, j).map(|r| (r.k0, r.k1));
                    assert_eq!(got, rays_by_division(&l, i, j), "{axis:?} ray {i}, {j}");
                    rays += usize::from(got.is_some());
                }
            }
        }
        assert!(rays > 1000, "{rays} rays");
    }

    #[test]
    fn index_coordinates_are_divisions_by_the_spacing() {
        let p = [0.1, -7.3, 1e-310];
        for spacing in [[1.0, 2.0, 0.25], [0.7, 3.0, 1.5], [1.0, 1.0, 0.125]] {
            let l = Lattice::new([4, 4, 4], spacing, [1.0, 2.0, 3.0], 1.0, 1.0, [0.0; 3]).unwrap();
            let exact: [f64; 3] = std::array::from_fn(|m| p[m] / spacing[m]);
            assert_eq!(l.to_index(p).map(f64::to_bits), exact.map(f64::to_bits));
        }
    }

    #[test]
    fn oblique_rays_stay_inside_the_box() {
        let l = Lattice::new(
            [10, 12, 9],
            [1.0, 0.5, 2.0],
            [1.0, 2.0, 3.0],
            0.5,
            0.5,
            [0.3, 0.7, 0.1],
        )
        .unwrap();
        let ((i0, i1), (j0, j1)) = l.ray_ranges();
        let mut samples = 0;
        for i in i0..=i1 {
            for j in j0..=j1 {
                if let Some(r) = l.ray(i, j) {
                    for k in [r.k0, r.k1] {
                        let p = r.at(k);
                        assert!(p[0] > -1e-6 && p[0] < 9.0 + 1e-6, "{p:?}");
                        assert!(p[1] > -1e-6 && p[1] < 11.0 + 1e-6, "{p:?}");
                        assert!(p[2] > -1e-6 && p[2] < 8.0 + 1e-6, "{p:?}");
                    }
                    assert!(
                        !l.inside(l.point(i, j, r.k0 - 1)) && !l.inside(l.point(i, j, r.k1 + 1))
                    );
                    samples += r.len();
                }
            }
        }
        // The box is 9 x 5.5 x 16 mm = 792 mm³; each sample stands for 0.5³ mm³.
        let expected = 792.0 / 0.125;
        assert!(
            (samples as f64 / expected - 1.0).abs() < 0.1,
            "{samples} samples, about {expected} expected"
        );
    }

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
    fn floor_and_ceil_match_the_library() {
        for x in [
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            2.999_999,
            -2.000_001,
            1e15 + 0.5,
            -7.25,
        ] {
            assert_eq!(floor_i64(x), x.floor() as i64, "{x}");
            assert_eq!(ceil_i64(x), x.ceil() as i64, "{x}");
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
    fn rounding_halves_away_from_zero_like_the_library() {
        for x in [
            0.0,
            0.5,
            -0.5,
            1.5,
            -1.5,
            2.5,
            0.499_999_999_999_999_94,
            -2.4,
            7.0,
            1e15 + 0.5,
            -3.75,
            4_294_967_295.5,
        ] {
            assert_eq!(round_half_away(x), x.round() as i64, "{x}");
        }
        let mut lcg = Lcg::with_increment(3, 1);
        for _ in 0..10_000 {
            let state = lcg.next_u64();
            let x = ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 1e12;
            assert_eq!(round_half_away(x), x.round() as i64, "{x}");
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
