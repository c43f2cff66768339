//! Cutting a volume into a slice stack: the voxel planes along a coordinate axis, the grid
//! resampled on the ray lattice along an oblique one, each sample quantized (or left out as
//! background) and each slice's sum and count of values kept for slab means.

use std::borrow::Cow;
use std::ops::Range;

use rayon::prelude::*;

use super::{BackgroundSummary, Column, Lattice, MISSING, SliceStack, StackParams};
use crate::error::{Error, Result};
use crate::geometry::{WorldAxis, canonical, coordinate_axis, normalize};
use crate::progress::Monitor;
use crate::volume::background::Background;
use crate::volume::interpolate::Interpolator;
use crate::volume::{Quantizer, Volume, Voxel};

mod sparse;

pub use self::sparse::{InPlane, sampled_gain};

/// Pixels a task of a cut along a coordinate axis fills.
const CUT_BLOCK: usize = 4096;

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
        let cutter = Cutter::new(volume, axis, params, monitor)?;
        let rows = 0..cutter.rows();
        monitor.start("slicing", cutter.work(&rows));
        let Self {
            columns,
            symbols,
            positions,
            ..
        } = cutter.cut(rows, monitor)?;
        Ok(Self {
            columns,
            symbols,
            ..cutter.summary(positions, monitor)?
        })
    }
}

/// What cutting a volume into slices along one axis needs, found once: the canonical axis, the
/// quantizer, the background, and for an oblique axis the lattice. It cuts the stack a strip of
/// rows at a time (rows of pixels: voxel rows along the slower of the two other axes for a
/// coordinate axis, lattice rows for an oblique one), so that a stack too large to hold can be
/// read strip by strip; the strips' histograms and joint histograms add up to the whole's.
pub(crate) struct Cutter<'a> {
    volume: &'a Volume,
    axis: [f64; 3],
    bins: usize,
    quantizer: Quantizer,
    background: Cow<'a, Background>,
    /// The lattice of an oblique axis; `None` along a coordinate axis.
    lattice: Option<Lattice>,
}

impl<'a> Cutter<'a> {
    /// The cutter of `volume` along `axis` (made canonical): finds the background.
    pub(crate) fn new(
        volume: &'a Volume,
        axis: [f64; 3],
        params: &StackParams,
        monitor: &Monitor,
    ) -> Result<Self> {
        let background = Background::find(volume, params.background, monitor)?;
        Self::with(volume, axis, params, Cow::Owned(background), |d| {
            oblique_lattice(volume, d, params)
        })
    }

    /// The cutter of `volume` along `axis` (made canonical) with `background`, and `lattice`
    /// of the canonical direction for an oblique axis.
    fn with(
        volume: &'a Volume,
        axis: [f64; 3],
        params: &StackParams,
        background: Cow<'a, Background>,
        lattice: impl FnOnce([f64; 3]) -> Result<Lattice>,
    ) -> Result<Self> {
        let d = canonical(normalize(axis).ok_or_else(|| {
            Error::invalid("axis", format!("{axis:?}"), "a direction with a length")
        })?);
        let quantizer = volume.quantizer(params.sampling.bins)?;
        let lattice = match coordinate_axis(d) {
            Some(_) => None,
            None => Some(lattice(d)?),
        };
        let axis = coordinate_axis(d).map_or(d, |m| std::array::from_fn(|i| f64::from(i == m)));
        Ok(Self {
            volume,
            axis,
            bins: params.sampling.bins,
            quantizer,
            background,
            lattice,
        })
    }

    /// The number of slices.
    pub(crate) fn slices(&self) -> usize {
        match (&self.lattice, coordinate_axis(self.axis)) {
            (Some(l), _) => {
                let (k_first, k_last) = l.sample_range();
                (k_last - k_first + 1).max(0) as usize
            }
            (None, Some(m)) => self.volume.dims()[m],
            (None, None) => unreachable!("a coordinate axis has no lattice"),
        }
    }

    /// The number of rows.
    pub(crate) fn rows(&self) -> usize {
        match (&self.lattice, coordinate_axis(self.axis)) {
            (Some(l), _) => {
                let (_, (j0, j1)) = l.ray_ranges();
                (j1 - j0 + 1).max(0) as usize
            }
            (None, Some(m)) => self.volume.dims()[other_axes(m).1],
            (None, None) => unreachable!("a coordinate axis has no lattice"),
        }
    }

    /// The most pixels a row has.
    pub(crate) fn row_pixels(&self) -> usize {
        match (&self.lattice, coordinate_axis(self.axis)) {
            (Some(l), _) => {
                let ((i0, i1), _) = l.ray_ranges();
                (i1 - i0 + 1).max(0) as usize
            }
            (None, Some(m)) => self.volume.dims()[other_axes(m).0],
            (None, None) => unreachable!("a coordinate axis has no lattice"),
        }
    }

    /// The number of bins.
    pub(crate) fn bins(&self) -> usize {
        self.bins
    }

    /// The bytes the background takes (its mask, for a found one).
    pub(crate) fn background_bytes(&self) -> u64 {
        self.background.memory_bytes()
    }

    /// The units of work [`cut`](Self::cut) of `rows` advances its monitor by (the caller starts
    /// the phase, so that strips cut one after another advance one phase).
    pub(crate) fn work(&self, rows: &Range<usize>) -> u64 {
        match coordinate_axis(self.axis) {
            Some(m) if self.lattice.is_none() => {
                (rows.len() * self.volume.dims()[other_axes(m).0]).div_ceil(CUT_BLOCK) as u64
            }
            _ => rows.len() as u64,
        }
    }

    /// The symbol of a sample of value `v` whose voxel (the nearest, for an interpolated one)
    /// is at linear `index`: its bin, or [`MISSING`] for background and values that do not count.
    #[inline]
    fn symbol(&self, index: usize, v: f32) -> u8 {
        if self.background.contains(index, v) {
            MISSING
        } else {
            self.quantizer.bin(v).unwrap_or(MISSING)
        }
    }

    /// The stack of the pixels of `rows`, without the per-slice sums (a strip's positions are
    /// its own).
    pub(crate) fn cut(&self, rows: Range<usize>, monitor: &Monitor) -> Result<SliceStack> {
        let keep = |index: usize, v: f32| self.symbol(index, v);
        match (&self.lattice, coordinate_axis(self.axis)) {
            (Some(lattice), _) => self.along_lattice(lattice, rows, &keep, monitor),
            (None, Some(m)) => self.along_coordinate(m, rows, &keep, monitor),
            (None, None) => unreachable!("a coordinate axis has no lattice"),
        }
    }

    /// The stack's per-slice geometry, background and sums without its columns: what a
    /// partition reports of the stack once its histograms are counted. `positions` are the
    /// strips' positions summed.
    pub(crate) fn summary(&self, positions: Vec<u64>, monitor: &Monitor) -> Result<SliceStack> {
        monitor.check()?;
        let (volume, d) = (self.volume, self.axis);
        let counted = |index: usize, v: f32| v.is_finite() && !self.background.contains(index, v);
        let slices = self.slices();
        let (sums, counts) = match (&self.lattice, coordinate_axis(d)) {
            (Some(lattice), _) => lattice_sums(volume, lattice, slices, &counted),
            (None, Some(m)) => plane_sums(volume, m, &counted),
            (None, None) => unreachable!("a coordinate axis has no lattice"),
        };
        let (thickness, offset) = match (&self.lattice, coordinate_axis(d)) {
            (Some(l), _) => (
                l.sample_spacing,
                l.sample_range().0 as f64 * l.sample_spacing,
            ),
            (None, Some(m)) => (volume.spacing()[m], 0.0),
            (None, None) => unreachable!("a coordinate axis has no lattice"),
        };
        Ok(SliceStack {
            axis: d,
            bins: self.bins,
            slices,
            thickness,
            offset,
            columns: Vec::new(),
            symbols: Vec::new(),
            sums,
            counts,
            positions,
            background: BackgroundSummary::of(&self.background),
            world: volume.transform().describe(d, volume.spacing()),
            world_line: volume.transform().world_line(d, volume.spacing()),
        })
    }

    /// A stack of columns and positions only, the rest filled by [`summary`](Self::summary).
    fn bare(&self, columns: Vec<Column>, symbols: Vec<u8>, positions: Vec<u64>) -> SliceStack {
        SliceStack {
            axis: self.axis,
            bins: self.bins,
            slices: positions.len(),
            thickness: 1.0,
            offset: 0.0,
            columns,
            symbols,
            sums: Vec::new(),
            counts: Vec::new(),
            positions,
            background: BackgroundSummary::default(),
            world: WorldAxis::default(),
            world_line: (1.0, 0.0),
        }
    }

    fn along_coordinate(
        &self,
        m: usize,
        rows: Range<usize>,
        keep: &(dyn Fn(usize, f32) -> u8 + Sync),
        monitor: &Monitor,
    ) -> Result<SliceStack> {
        let volume = self.volume;
        let dims = volume.dims();
        let stride = [1, dims[0], dims[0] * dims[1]];
        let n = dims[m];
        let (a, b) = other_axes(m);
        let first = rows.start * dims[a];
        let pixels = rows.len() * dims[a];
        let mut symbols = vec![MISSING; pixels * n];
        crate::volume::with_voxels!(volume.data(), |voxels| {
            symbols
                .par_chunks_mut(CUT_BLOCK * n)
                .enumerate()
                .try_for_each(|(c, out)| {
                    for (k, col) in out.chunks_mut(n).enumerate() {
                        let p = first + c * CUT_BLOCK + k;
                        let base = (p % dims[a]) * stride[a] + (p / dims[a]) * stride[b];
                        for (s, o) in col.iter_mut().enumerate() {
                            let i = base + s * stride[m];
                            *o = keep(i, voxels[i].to_f32());
                        }
                    }
                    monitor.advance(1)
                })
        })?;
        let columns = (0..pixels)
            .map(|p| Column {
                offset: p * n,
                first: 0,
                len: n as u32,
            })
            .collect();
        Ok(self.bare(columns, symbols, vec![pixels as u64; n]))
    }

    fn along_lattice(
        &self,
        lattice: &Lattice,
        rows: Range<usize>,
        keep: &(dyn Fn(usize, f32) -> u8 + Sync),
        monitor: &Monitor,
    ) -> Result<SliceStack> {
        let volume = self.volume;
        let (_, (j0, _)) = lattice.ray_ranges();
        let (k_first, _) = lattice.sample_range();
        let slices = self.slices();
        let rows: Vec<i64> = rows.map(|r| j0 + r as i64).collect();
        let per_row = crate::volume::with_voxels!(volume.data(), |data| {
            let it = Interpolator::over(data, volume.dims());
            rows.par_iter()
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
                .collect::<Result<Vec<_>>>()
        })?;
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
        Ok(self.bare(columns, symbols, positions))
    }
}

impl SliceStack {
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
}

/// Per voxel plane along coordinate axis `m`: the sum and count of the counted values.
fn plane_sums(
    volume: &Volume,
    m: usize,
    counted: &(dyn Fn(usize, f32) -> bool + Sync),
) -> (Vec<f64>, Vec<u64>) {
    let dims = volume.dims();
    let stride = [1, dims[0], dims[0] * dims[1]];
    let (a, b) = other_axes(m);
    crate::volume::with_voxels!(volume.data(), |voxels| {
        (0..dims[m])
            .into_par_iter()
            .map(|s| {
                let (mut sum, mut count) = (0.0, 0u64);
                for j in 0..dims[b] {
                    let row = s * stride[m] + j * stride[b];
                    for i in 0..dims[a] {
                        let index = row + i * stride[a];
                        let v = voxels[index].to_f32();
                        if counted(index, v) {
                            sum += f64::from(v);
                            count += 1;
                        }
                    }
                }
                (sum, count)
            })
            .unzip()
    })
}

/// Per lattice slice: the sum and count of the counted interpolated values.
fn lattice_sums(
    volume: &Volume,
    lattice: &Lattice,
    slices: usize,
    counted: &(dyn Fn(usize, f32) -> bool + Sync),
) -> (Vec<f64>, Vec<u64>) {
    let (_, (j0, j1)) = lattice.ray_ranges();
    let (k_first, _) = lattice.sample_range();
    let zero = || (vec![0.0f64; slices], vec![0u64; slices]);
    crate::volume::with_voxels!(volume.data(), |data| {
        let it = Interpolator::over(data, volume.dims());
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
