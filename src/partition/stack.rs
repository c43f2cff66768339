//! Slice stacks along an axis (DESIGN.md §2): the voxel planes for a coordinate axis, planes of the
//! grid resampled on the ray lattice for an oblique one. Stored pixel-major: each pixel's column
//! of quantized symbols across the slices is contiguous, over the slices where it is valid.

use rayon::prelude::*;
use serde::Serialize;

use crate::error::{Error, Result};
use crate::geometry::lattice::{Lattice, SamplingParams};
use crate::geometry::{WorldAxis, canonical, coordinate_axis, normalize};
use crate::progress::Monitor;
use crate::volume::Volume;
use crate::volume::background::{Background, BackgroundRule};
use crate::volume::interpolate::Interpolator;

/// The symbol of a sample that does not count: outside the volume, missing, or background.
pub const MISSING: u8 = u8::MAX;

/// How to cut a volume into slices.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StackParams {
    /// Bins, and for an oblique axis the lattice's spacings (the ray spacing between a slice's
    /// pixels, the sample spacing between slices): the view search's.
    pub sampling: SamplingParams,
    /// The background, left out of every histogram.
    pub background: BackgroundRule,
}

/// One pixel's column: symbols for slices `first .. first + len`, stored from `offset`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Column {
    offset: usize,
    first: u32,
    len: u32,
}

/// The slices of a volume along an axis, quantized.
#[derive(Clone, Debug)]
pub struct SliceStack {
    axis: [f64; 3],
    bins: usize,
    slices: usize,
    /// Millimetres between consecutive slices.
    thickness: f64,
    /// Position along the axis of slice 0's centre, mm (voxel (0,0,0) at 0).
    offset: f64,
    columns: Vec<Column>,
    symbols: Vec<u8>,
    /// Per slice: the sum and count of the values that count, for slab means.
    sums: Vec<f64>,
    counts: Vec<u64>,
    /// Per slice: the samples inside the volume's box, background and missing ones included.
    positions: Vec<u64>,
    /// The background left out.
    background: BackgroundSummary,
    /// The axis in world coordinates.
    world: WorldAxis,
    /// A position `s` along the axis is at `a·s + b` along the world axis: `(a, b)`.
    world_line: (f64, f64),
}

/// What was left out as background, for reports: `{"mode": "auto", "value": 12.0,
/// "fraction": 0.38}`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct BackgroundSummary {
    /// How it was chosen: `none`, `auto` or `value`.
    pub mode: &'static str,
    /// The threshold: background voxels are at or below it (`None` when there is none).
    pub value: Option<f32>,
    /// The share of the volume's voxels that are background.
    pub fraction: f64,
}

impl BackgroundSummary {
    /// The summary of `b`.
    pub fn of(b: &Background) -> Self {
        Self {
            mode: match b.rule {
                BackgroundRule::None => "none",
                BackgroundRule::Auto => "auto",
                BackgroundRule::Below(_) => "value",
            },
            value: b.value,
            fraction: b.fraction,
        }
    }

    /// Whether any voxel was left out.
    pub fn any(&self) -> bool {
        self.fraction > 0.0
    }
}

/// The two axes other than `m`, in order.
fn other_axes(m: usize) -> (usize, usize) {
    match m {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    }
}

/// Where the slices perpendicular to `axis` lie, without cutting them: the canonical axis,
/// the number of slices, the distance between them and the position of slice 0 along the axis,
/// mm (what [`SliceStack::new`] makes, for a slice view that needs no histograms).
pub fn slice_geometry(
    volume: &Volume,
    axis: [f64; 3],
    params: &StackParams,
) -> Result<([f64; 3], usize, f64, f64)> {
    let d =
        canonical(normalize(axis).ok_or_else(|| {
            Error::invalid("axis", format!("{axis:?}"), "a direction with a length")
        })?);
    if let Some(m) = coordinate_axis(d) {
        let mut axis = [0.0; 3];
        axis[m] = 1.0;
        return Ok((axis, volume.dims()[m], volume.spacing()[m], 0.0));
    }
    let lattice = oblique_lattice(volume, d, params)?;
    let (k_first, k_last) = lattice.sample_range();
    let slices = (k_last - k_first + 1).max(0) as usize;
    let step = lattice.sample_spacing;
    Ok((d, slices, step, k_first as f64 * step))
}

impl SliceStack {
    /// Cuts `volume` into slices perpendicular to `axis` (made canonical).
    pub fn new(
        volume: &Volume,
        axis: [f64; 3],
        params: &StackParams,
        monitor: &Monitor,
    ) -> Result<Self> {
        let d = canonical(normalize(axis).ok_or_else(|| {
            Error::invalid("axis", format!("{axis:?}"), "a direction with a length")
        })?);
        let q = volume.quantizer(params.sampling.bins)?;
        let background = Background::find(volume, params.background);
        // A sample's voxel (the nearest, for an interpolated one) and value.
        let keep = |index: usize, v: f32| -> u8 {
            if background.contains(index, v) {
                MISSING
            } else {
                q.bin(v).unwrap_or(MISSING)
            }
        };
        let mut stack = match coordinate_axis(d) {
            Some(m) => Self::along_coordinate(volume, m, params.sampling.bins, &keep, monitor)?,
            None => Self::along_lattice(volume, d, params, &keep, monitor)?,
        };
        stack.background = BackgroundSummary::of(&background);
        stack.world = volume.transform().describe(d, volume.spacing());
        stack.world_line = volume.transform().world_line(d, volume.spacing());
        stack.with_sums(volume, d, params, &background, monitor)
    }

    fn along_coordinate(
        volume: &Volume,
        m: usize,
        bins: usize,
        keep: &(dyn Fn(usize, f32) -> u8 + Sync),
        monitor: &Monitor,
    ) -> Result<Self> {
        let dims = volume.dims();
        let stride = [1, dims[0], dims[0] * dims[1]];
        let n = dims[m];
        let (a, b) = other_axes(m);
        let pixels = dims[a] * dims[b];
        let voxels = volume.voxels();
        let mut symbols = vec![MISSING; pixels * n];
        monitor.start("slicing", pixels.div_ceil(4096) as u64);
        symbols
            .par_chunks_mut(4096 * n)
            .enumerate()
            .try_for_each(|(c, out)| {
                for (k, col) in out.chunks_mut(n).enumerate() {
                    let p = c * 4096 + k;
                    let base = (p % dims[a]) * stride[a] + (p / dims[a]) * stride[b];
                    for (s, o) in col.iter_mut().enumerate() {
                        let i = base + s * stride[m];
                        *o = keep(i, voxels[i]);
                    }
                }
                monitor.advance(1)
            })?;
        let columns = (0..pixels)
            .map(|p| Column {
                offset: p * n,
                first: 0,
                len: n as u32,
            })
            .collect();
        let mut axis = [0.0; 3];
        axis[m] = 1.0;
        Ok(Self {
            axis,
            bins,
            slices: n,
            thickness: volume.spacing()[m],
            offset: 0.0,
            columns,
            symbols,
            sums: Vec::new(),
            counts: Vec::new(),
            positions: vec![pixels as u64; n],
            background: BackgroundSummary::default(),
            world: WorldAxis::default(),
            world_line: (1.0, 0.0),
        })
    }

    fn along_lattice(
        volume: &Volume,
        d: [f64; 3],
        params: &StackParams,
        keep: &(dyn Fn(usize, f32) -> u8 + Sync),
        monitor: &Monitor,
    ) -> Result<Self> {
        let lattice = oblique_lattice(volume, d, params)?;
        let (_, (j0, j1)) = lattice.ray_ranges();
        let (k_first, k_last) = lattice.sample_range();
        let slices = (k_last - k_first + 1).max(0) as usize;
        let it = Interpolator::new(volume);
        let rows: Vec<i64> = (j0..=j1).collect();
        monitor.start("slicing", rows.len() as u64);
        let per_row = rows
            .par_iter()
            .map(|&j| {
                let mut columns = Vec::new();
                let mut symbols = Vec::new();
                for ray in lattice.row(j) {
                    columns.push(Column {
                        offset: symbols.len(),
                        first: (ray.k0 - k_first) as u32,
                        len: ray.len() as u32,
                    });
                    symbols.extend((ray.k0..=ray.k1).map(|k| {
                        let p = ray.at(k);
                        keep(it.nearest(p), it.sample(p))
                    }));
                }
                monitor.advance(1)?;
                Ok((columns, symbols))
            })
            .collect::<Result<Vec<_>>>()?;
        let total = per_row.iter().map(|(_, s)| s.len()).sum();
        let mut columns = Vec::with_capacity(per_row.iter().map(|(c, _)| c.len()).sum());
        let mut symbols = Vec::with_capacity(total);
        let mut positions = vec![0u64; slices];
        for (cols, syms) in per_row {
            for c in &cols {
                let first = c.first as usize;
                for p in &mut positions[first..first + c.len as usize] {
                    *p += 1;
                }
            }
            let base = symbols.len();
            columns.extend(cols.into_iter().map(|c| Column {
                offset: c.offset + base,
                ..c
            }));
            symbols.extend(syms);
        }
        Ok(Self {
            axis: d,
            bins: params.sampling.bins,
            slices,
            thickness: lattice.sample_spacing,
            offset: k_first as f64 * lattice.sample_spacing,
            columns,
            symbols,
            sums: Vec::new(),
            counts: Vec::new(),
            positions,
            background: BackgroundSummary::default(),
            world: WorldAxis::default(),
            world_line: (1.0, 0.0),
        })
    }

    /// Adds the per-slice sums of the counted values (for slab means).
    fn with_sums(
        mut self,
        volume: &Volume,
        d: [f64; 3],
        params: &StackParams,
        background: &Background,
        monitor: &Monitor,
    ) -> Result<Self> {
        monitor.check()?;
        let counted = |index: usize, v: f32| v.is_finite() && !background.contains(index, v);
        let (sums, counts) = if let Some(m) = coordinate_axis(d) {
            plane_sums(volume, m, &counted)
        } else {
            lattice_sums(
                volume,
                &oblique_lattice(volume, d, params)?,
                self.slices,
                &counted,
            )
        };
        self.sums = sums;
        self.counts = counts;
        Ok(self)
    }

    /// Builds a stack directly from slices of symbols (each a `pixels`-long row, `MISSING` for
    /// samples that do not count), for tests and synthetic data.
    pub fn from_slices(slices: &[Vec<u8>], bins: usize) -> Result<Self> {
        let n = slices.len();
        let pixels = slices.first().map_or(0, Vec::len);
        if n == 0 || pixels == 0 || slices.iter().any(|s| s.len() != pixels) {
            return Err(Error::invalid(
                "slices",
                format!("{n} of {pixels} pixels"),
                "at least one, all of one size",
            ));
        }
        if slices
            .iter()
            .flatten()
            .any(|&s| s != MISSING && usize::from(s) >= bins)
        {
            return Err(Error::invalid(
                "symbols",
                "out of range",
                format!("below {bins} bins"),
            ));
        }
        let symbols = (0..pixels)
            .flat_map(|p| slices.iter().map(move |s| s[p]))
            .collect();
        let counts = slices
            .iter()
            .map(|s| s.iter().filter(|&&v| v != MISSING).count() as u64)
            .collect();
        let sums = slices
            .iter()
            .map(|s| {
                s.iter()
                    .filter(|&&v| v != MISSING)
                    .map(|&v| f64::from(v))
                    .sum()
            })
            .collect();
        Ok(Self {
            axis: [0.0, 0.0, 1.0],
            bins,
            slices: n,
            thickness: 1.0,
            offset: 0.0,
            columns: (0..pixels)
                .map(|p| Column {
                    offset: p * n,
                    first: 0,
                    len: n as u32,
                })
                .collect(),
            symbols,
            sums,
            counts,
            positions: vec![pixels as u64; n],
            background: BackgroundSummary::default(),
            world: WorldAxis {
                world_axis: [0.0, 0.0, 1.0],
                anatomy: None,
                oriented: false,
            },
            world_line: (1.0, 0.0),
        })
    }

    /// The canonical axis the slices are perpendicular to.
    pub fn axis(&self) -> [f64; 3] {
        self.axis
    }

    /// Number of slices.
    pub fn slices(&self) -> usize {
        self.slices
    }

    /// Number of bins of the symbols.
    pub fn bins(&self) -> usize {
        self.bins
    }

    /// Millimetres between consecutive slices.
    pub fn thickness(&self) -> f64 {
        self.thickness
    }

    /// Position along the axis of slice 0's centre, mm, with voxel (0,0,0) at 0.
    pub fn offset(&self) -> f64 {
        self.offset
    }

    /// The axis in world coordinates: the slab planes' world normal and anatomical name.
    pub fn world(&self) -> &WorldAxis {
        &self.world
    }

    /// The world position (along [`world`](Self::world)'s axis, mm) of position `s` mm along the
    /// axis.
    pub fn world_mm(&self, s: f64) -> f64 {
        let (a, b) = self.world_line;
        a * s + b
    }

    /// `(a, b)` of [`world_mm`](Self::world_mm)`(s) = a·s + b`.
    pub fn world_line(&self) -> (f64, f64) {
        self.world_line
    }

    /// Number of pixel columns.
    pub fn pixels(&self) -> usize {
        self.columns.len()
    }

    /// The share of the positions of slices `start..end` inside the volume that do not count:
    /// background or missing voxels.
    pub fn left_out(&self, start: usize, end: usize) -> f64 {
        let positions: u64 = self.positions[start..end].iter().sum();
        let counted: u64 = self.counts[start..end].iter().sum();
        if positions == 0 {
            1.0
        } else {
            1.0 - counted as f64 / positions as f64
        }
    }

    /// What was left out as background.
    pub fn background(&self) -> BackgroundSummary {
        self.background
    }

    /// Mean of the counted values of slices `start..end`, or `None` when none counts.
    pub fn mean(&self, start: usize, end: usize) -> Option<f64> {
        let n: u64 = self.counts[start..end].iter().sum();
        (n > 0).then(|| self.sums[start..end].iter().sum::<f64>() / n as f64)
    }

    /// The symbols of pixel `p` in slices `start..end`, clipped to where the column is valid,
    /// with the slice index of the first one.
    #[inline]
    pub fn column(&self, p: usize, start: usize, end: usize) -> (usize, &[u8]) {
        let c = self.columns[p];
        let (first, last) = (c.first as usize, (c.first + c.len) as usize);
        let (a, b) = (start.max(first), end.min(last));
        if a >= b {
            return (a, &[]);
        }
        (a, &self.symbols[c.offset + a - first..c.offset + b - first])
    }

    /// The slices where pixel `p`'s column is valid: `(first, len)`.
    #[inline]
    pub fn column_range(&self, p: usize) -> (usize, usize) {
        let c = self.columns[p];
        (c.first as usize, c.len as usize)
    }

    /// Per slice, the histogram of its symbols (counted samples only): `slices × bins` counts.
    pub fn slice_histograms(&self) -> Vec<u64> {
        let (n, bins) = (self.slices, self.bins);
        let zero = || vec![0u64; n * bins];
        self.columns
            .par_chunks(4096)
            .fold(zero, |mut h, cols| {
                for c in cols {
                    let syms = &self.symbols[c.offset..c.offset + c.len as usize];
                    for (k, &s) in syms.iter().enumerate() {
                        if s != MISSING {
                            h[(c.first as usize + k) * bins + usize::from(s)] += 1;
                        }
                    }
                }
                h
            })
            .reduce(zero, |mut a, b| {
                a.iter_mut().zip(&b).for_each(|(x, y)| *x += y);
                a
            })
    }
}

/// Per voxel plane along coordinate axis `m`: the sum and count of the counted values.
fn plane_sums(
    volume: &Volume,
    m: usize,
    counted: &(dyn Fn(usize, f32) -> bool + Sync),
) -> (Vec<f64>, Vec<u64>) {
    let dims = volume.dims();
    let stride = [1, dims[0], dims[0] * dims[1]];
    let voxels = volume.voxels();
    let (a, b) = other_axes(m);
    (0..dims[m])
        .into_par_iter()
        .map(|s| {
            let (mut sum, mut count) = (0.0, 0u64);
            for j in 0..dims[b] {
                let row = s * stride[m] + j * stride[b];
                for i in 0..dims[a] {
                    let index = row + i * stride[a];
                    let v = voxels[index];
                    if counted(index, v) {
                        sum += f64::from(v);
                        count += 1;
                    }
                }
            }
            (sum, count)
        })
        .unzip()
}

/// Per lattice slice: the sum and count of the counted interpolated values.
fn lattice_sums(
    volume: &Volume,
    lattice: &Lattice,
    slices: usize,
    counted: &(dyn Fn(usize, f32) -> bool + Sync),
) -> (Vec<f64>, Vec<u64>) {
    let it = Interpolator::new(volume);
    let (_, (j0, j1)) = lattice.ray_ranges();
    let (k_first, _) = lattice.sample_range();
    let zero = || (vec![0.0f64; slices], vec![0u64; slices]);
    (j0..=j1)
        .into_par_iter()
        .fold(zero, |(mut sums, mut counts), j| {
            for ray in lattice.row(j) {
                for k in ray.k0..=ray.k1 {
                    let p = ray.at(k);
                    let v = it.sample(p);
                    if counted(it.nearest(p), v) {
                        let s = (k - k_first) as usize;
                        sums[s] += f64::from(v);
                        counts[s] += 1;
                    }
                }
            }
            (sums, counts)
        })
        .reduce(zero, |(mut a, mut b), (c, e)| {
            a.iter_mut().zip(c).for_each(|(x, y)| *x += y);
            b.iter_mut().zip(e).for_each(|(x, y)| *x += y);
            (a, b)
        })
}

/// The lattice of an oblique stack.
fn oblique_lattice(volume: &Volume, d: [f64; 3], params: &StackParams) -> Result<Lattice> {
    let (x, y, _) = params.sampling.spacings(volume.dims(), volume.spacing())?;
    Ok(Lattice::new(
        volume.dims(),
        volume.spacing(),
        d,
        x,
        y,
        [0.0; 3],
    )?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::VoxelType;

    fn ramp() -> Volume {
        let data = (0..4 * 3 * 5).map(|i| i as f32).collect();
        Volume::new([4, 3, 5], [1.0, 1.0, 2.5], VoxelType::F32, data).unwrap()
    }

    #[test]
    fn coordinate_slices_are_voxel_planes() {
        let v = ramp();
        let q = v.quantizer(60).unwrap();
        for (m, n) in [(0, 4), (1, 3), (2, 5)] {
            let mut axis = [0.0; 3];
            axis[m] = -1.0;
            let s = SliceStack::new(
                &v,
                axis,
                &StackParams {
                    sampling: SamplingParams {
                        bins: 60,
                        ..SamplingParams::default()
                    },
                    ..StackParams::default()
                },
                &Monitor::none(),
            )
            .unwrap();
            assert_eq!(s.axis()[m], 1.0, "canonical");
            assert_eq!(s.slices(), n);
            assert_eq!(s.pixels(), 60 / n);
            let h = s.slice_histograms();
            // Every slice holds exactly the voxels of its plane.
            for slice in 0..n {
                let mut expect = vec![0u64; 60];
                for (i, &x) in v.voxels().iter().enumerate() {
                    let coord = [i % 4, (i / 4) % 3, i / 12][m];
                    if coord == slice {
                        expect[usize::from(q.bin(x).unwrap())] += 1;
                    }
                }
                assert_eq!(
                    &h[slice * 60..(slice + 1) * 60],
                    &expect[..],
                    "axis {m} slice {slice}"
                );
            }
        }
        let s = SliceStack::new(
            &v,
            [0.0, 0.0, 1.0],
            &StackParams::default(),
            &Monitor::none(),
        )
        .unwrap();
        assert_eq!(s.thickness(), 2.5);
        assert_eq!(s.mean(0, 1), Some((0..12).sum::<i32>() as f64 / 12.0));
    }

    #[test]
    fn background_is_left_out() {
        let v = ramp();
        let params = StackParams {
            background: BackgroundRule::Below(29.0),
            ..StackParams::default()
        };
        let s = SliceStack::new(&v, [0.0, 0.0, 1.0], &params, &Monitor::none()).unwrap();
        let h = s.slice_histograms();
        let per_slice: Vec<u64> = h.chunks(32).map(|c| c.iter().sum()).collect();
        assert_eq!(per_slice, vec![0, 0, 6, 12, 12]);
        assert_eq!(s.mean(0, 2), None);
    }

    #[test]
    fn oblique_stacks_count_only_samples_inside() {
        let v = ramp();
        let s = SliceStack::new(
            &v,
            [1.0, 1.0, 1.0],
            &StackParams::default(),
            &Monitor::none(),
        )
        .unwrap();
        let total: u64 = s.slice_histograms().iter().sum();
        // The box is 3 x 2 x 10 mm: about 60 samples at 1 mm.
        assert!((40..=90).contains(&total), "{total} samples");
        for p in 0..s.pixels() {
            assert!(s.column(p, 0, s.slices()).1.iter().all(|&c| c != MISSING));
        }
    }

    #[test]
    fn the_geometry_alone_matches_the_stack() {
        let v = ramp();
        let params = StackParams::default();
        for axis in [
            [0.0, 0.0, 1.0],
            [0.0, -1.0, 0.0],
            [1.0, 2.0, 3.0],
            [-0.3, 0.1, 0.9],
        ] {
            let stack = SliceStack::new(&v, axis, &params, &Monitor::none()).unwrap();
            let (d, slices, thickness, offset) = slice_geometry(&v, axis, &params).unwrap();
            assert_eq!(d, stack.axis(), "{axis:?}");
            assert_eq!(slices, stack.slices(), "{axis:?}");
            assert_eq!(thickness.to_bits(), stack.thickness().to_bits(), "{axis:?}");
            assert_eq!(offset.to_bits(), stack.offset().to_bits(), "{axis:?}");
        }
    }
}
