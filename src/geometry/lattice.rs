//! The ray lattice of docs/design.md §2 (paper §4): parallel rays a ray spacing apart along an axis,
//! samples a sample spacing apart along them, counted inside the box of the voxel centres. The
//! view search walks it ray by ray; oblique slice stacks resample the volume on it. Positions are
//! also kept in 32.32 fixed point, so that a walk advances by exact integer additions.

use serde::Serialize;

use super::{
    InvalidParameter, MAX_SPACING_RATIO, Result, coordinate_axis, dot, frame, min_spacing,
};

/// How a volume is sampled and its samples quantized: the same for the view search and for the
/// slices it partitions, so that both see one signal. `None` spacings mean the smallest voxel
/// spacing.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SamplingParams {
    /// Quantization bins B (2 to 255).
    pub bins: usize,
    /// Distance between rays (and between oblique slices' pixels), mm.
    pub ray_spacing: Option<f64>,
    /// Distance between samples along a ray (and between oblique slices), mm.
    pub sample_spacing: Option<f64>,
}

impl Default for SamplingParams {
    fn default() -> Self {
        Self {
            bins: 32,
            ray_spacing: None,
            sample_spacing: None,
        }
    }
}

/// A lattice takes at most this many samples per voxel of the volume (and at least
/// [`MIN_SAMPLE_BUDGET`] in all): finer spacings are coarsened to fit, and said so.
pub const SAMPLES_PER_VOXEL: f64 = 16.0;

/// The sample budget of a lattice is never below this.
pub const MIN_SAMPLE_BUDGET: f64 = 4_194_304.0;

impl SamplingParams {
    /// The spacings in mm for a volume of `dims` and `spacing`: the given ones, else the
    /// smallest voxel spacing, coarsened when a lattice would take more samples than the budget
    /// ([`SAMPLES_PER_VOXEL`] a voxel): the finer of the two first, up to the other, then both
    /// alike. Returns the spacings and how much coarser the cell became (1 when nothing changed);
    /// an error for a spacing that is not a positive finite number.
    pub fn spacings(&self, dims: [usize; 3], spacing: [f64; 3]) -> Result<(f64, f64, f64)> {
        let s = min_spacing(spacing);
        let x = self.ray_spacing.unwrap_or(s);
        let y = self.sample_spacing.unwrap_or(s);
        for (name, v) in [("ray_spacing", x), ("sample_spacing", y)] {
            if !(v.is_finite()
                && v > 0.0
                && v <= MAX_SPACING_RATIO * s
                && s <= MAX_SPACING_RATIO * v)
            {
                return Err(InvalidParameter::new(
                    name,
                    v,
                    format!(
                        "a positive number of mm within a factor of {MAX_SPACING_RATIO} of the \
                         smallest voxel spacing, {s} mm"
                    ),
                ));
            }
        }
        // A lattice's samples fill the box of the voxels: its volume over a cell's, x²·y.
        let voxels: f64 = dims.iter().map(|&n| n as f64).product();
        let box_volume: f64 = (0..3).map(|k| dims[k] as f64 * spacing[k]).product();
        let budget = (SAMPLES_PER_VOXEL * voxels).max(MIN_SAMPLE_BUDGET);
        let over = box_volume / (x * x * y) / budget;
        if over <= 1.0 {
            return Ok((x, y, 1.0));
        }
        let (x1, y1) = if x < y && x * over.sqrt() <= y {
            (x * over.sqrt(), y)
        } else if y < x && y * over <= x {
            (x, y * over)
        } else {
            let b = x.max(y);
            let rest = (box_volume / (b * b * b) / budget).max(1.0).cbrt();
            (b * rest, b * rest)
        };
        Ok((x1, y1, (x1 * x1 * y1 / (x * x * y)).cbrt()))
    }

    /// These parameters with the spacings resolved for a volume of `dims` and `spacing`.
    pub fn resolved(&self, dims: [usize; 3], spacing: [f64; 3]) -> Result<Self> {
        let (x, y, _) = self.spacings(dims, spacing)?;
        Ok(Self {
            ray_spacing: Some(x),
            sample_spacing: Some(y),
            ..*self
        })
    }

    /// What the budget changed, in words, when it changed anything.
    pub fn budget_note(&self, dims: [usize; 3], spacing: [f64; 3]) -> Option<String> {
        let (x, y, factor) = self.spacings(dims, spacing).ok()?;
        (factor > 1.0).then(|| {
            format!(
                "rays every {x:.4} mm and samples every {y:.4} mm, coarser than asked: a finer \
                 lattice would take more than {SAMPLES_PER_VOXEL} samples a voxel"
            )
        })
    }
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
        for (name, s) in [("ray_spacing", x), ("sample_spacing", y)] {
            if !(s.is_finite() && s > 0.0) {
                return Err(InvalidParameter::new(name, s, "a positive number of mm"));
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

    /// The lattice along `axis` for a volume of `dims` and `spacing` with the default spacings
    /// (the smallest voxel spacing) and no phase.
    pub fn at_voxel_spacing(dims: [usize; 3], spacing: [f64; 3], axis: [f64; 3]) -> Result<Self> {
        let s = min_spacing(spacing);
        Self::new(dims, spacing, axis, s, s, [0.0; 3])
    }

    fn corners(&self) -> impl Iterator<Item = [f64; 3]> + '_ {
        corners_of([0.0; 3], self.extent)
    }

    /// The voxel spacing, mm.
    pub fn spacing(&self) -> [f64; 3] {
        self.spacing
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

    /// The ray `(i, j)` passing nearest the volume's centre: the one a lesson shows.
    pub fn central_ray(&self) -> (i64, i64) {
        let centre = self.extent.map(|e| e / 2.0);
        let index = |w: [f64; 3], phase: f64| {
            round_half_away(crate::geometry::dot(centre, w) / self.ray_spacing - phase)
        };
        (index(self.u, self.phase[0]), index(self.v, self.phase[1]))
    }

    /// Inclusive ranges of the ray indices `i` and `j` that can meet the box.
    pub fn ray_ranges(&self) -> ((i64, i64), (i64, i64)) {
        (
            self.index_range(self.u, self.ray_spacing, self.phase[0]),
            self.index_range(self.v, self.ray_spacing, self.phase[1]),
        )
    }

    /// The rays of row `j` that can meet the box: an inclusive range of `i` holding every `i`
    /// for which [`ray`](Self::ray) is `Some` (and a few around it), or `None` when the row
    /// misses the box. The box seen along the axis is a convex polygon, the hull of its eight
    /// corners; a row is a line across it, which it meets in an interval whose ends lie on
    /// segments between two corners. Rows of a flat box (one voxel thick) meet it in a point or
    /// not at all, so walking only these spans keeps a lattice's cost to the rays that count.
    pub fn row_span(&self, j: i64) -> Option<(i64, i64)> {
        self.span_in_box(j, [0.0; 3], self.extent)
    }

    /// [`row_span`](Self::row_span) for the part of the box whose coordinate `m` lies in
    /// `lo..=hi` (mm): the rays of row `j` that can meet that slab of the box (and a few more).
    pub fn row_span_within(&self, j: i64, (m, lo, hi): (usize, f64, f64)) -> Option<(i64, i64)> {
        let (mut a, mut b) = ([0.0; 3], self.extent);
        (a[m], b[m]) = (lo.max(0.0), hi.min(self.extent[m]));
        self.span_in_box(j, a, b)
    }

    fn span_in_box(&self, j: i64, lo: [f64; 3], hi: [f64; 3]) -> Option<(i64, i64)> {
        let y = (j as f64 + self.phase[1]) * self.ray_spacing;
        let points: Vec<(f64, f64)> = corners_of(lo, hi)
            .map(|c| (dot(c, self.u), dot(c, self.v)))
            .collect();
        let size: f64 = self.extent.iter().sum();
        let margin = 1e-6 * (1.0 + size) + 1e-9 * self.ray_spacing;
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for (a, p) in points.iter().enumerate() {
            if (p.1 - y).abs() <= margin {
                (lo, hi) = (lo.min(p.0), hi.max(p.0));
            }
            for q in &points[a + 1..] {
                if (p.1 - y) * (q.1 - y) < 0.0 {
                    let x = p.0 + (y - p.1) * (q.0 - p.0) / (q.1 - p.1);
                    (lo, hi) = (lo.min(x), hi.max(x));
                }
            }
        }
        if lo > hi {
            return None;
        }
        let to_i = |x: f64| x / self.ray_spacing - self.phase[0];
        Some((
            floor_i64(to_i(lo - margin)) - 1,
            ceil_i64(to_i(hi + margin)) + 1,
        ))
    }

    /// The rays of row `j` that meet the box, in order of `i`.
    pub fn row(&self, j: i64) -> impl Iterator<Item = Ray> + '_ {
        let ((i0, i1), _) = self.ray_ranges();
        let (a, b) = self
            .row_span(j)
            .map_or((1, 0), |(a, b)| (a.max(i0), b.min(i1)));
        (a..=b).filter_map(move |i| self.ray(i, j))
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

    /// Whether some ray of a lattice along `d` with this sample spacing, in any phase, could
    /// hold `block` samples in the box: the longest chord of the box along `d` (the box's
    /// tolerance included) is at least `block - 1` sample spacings. Never false where one could
    /// (a volume one voxel thick is too thin along every axis that crosses it).
    pub fn could_hold(&self, block: usize) -> bool {
        let chord = (0..3)
            .filter(|&m| self.d[m].abs() > 1e-12)
            .map(|m| (self.extent[m] + 4e-9 * (1.0 + self.extent[m])) / self.d[m].abs())
            .fold(f64::INFINITY, f64::min);
        let need = block.saturating_sub(1) as f64 * self.sample_spacing;
        chord >= need * (1.0 - 1e-9)
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

/// The corners of the box `lo..hi` (mm).
fn corners_of(lo: [f64; 3], hi: [f64; 3]) -> impl Iterator<Item = [f64; 3]> {
    (0..8).map(move |c| std::array::from_fn(|k| if c >> k & 1 == 1 { hi[k] } else { lo[k] }))
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

/// Fraction bits of fixed-point positions.
pub const FIXED_BITS: u32 = 32;
pub(crate) const FIXED_STEP: f64 = 1.0 / (1u64 << FIXED_BITS) as f64;

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

#[cfg(test)]
mod tests;
