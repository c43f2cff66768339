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
use crate::volume::background::{Background, BackgroundTest};
use crate::volume::{Quantizer, Volume, Voxel};

mod oblique;
mod sparse;

pub use self::sparse::{InPlane, sampled_gain};

/// Pixels a task of a cut along a coordinate axis fills.
const CUT_BLOCK: usize = 4096;

/// Neighbouring pixels a cut along a coordinate axis takes together, plane after plane.
const RUN: usize = 64;

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
        let mut sums = cutter.sums();
        let Self {
            columns,
            symbols,
            positions,
            ..
        } = cutter.cut(rows, sums.as_mut(), monitor)?;
        // The slices' sums along a coordinate axis take a pass over the voxels of their own: a
        // phase, so that a progress bar does not stand full meanwhile.
        monitor.start("summing slices", 1);
        let stack = Self {
            columns,
            symbols,
            ..cutter.summary(positions, sums, monitor)?
        };
        monitor.advance(1)?;
        Ok(stack)
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
    pub(super) background: Cow<'a, Background>,
    /// The lattice of an oblique axis; `None` along a coordinate axis.
    pub(super) lattice: Option<Lattice>,
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
    /// is at linear `index`: its bin, or [`MISSING`] for `background` (the cutter's, its test
    /// found once for a loop) and values that do not count.
    #[inline]
    pub(super) fn symbol_in(&self, background: BackgroundTest, index: usize, v: f32) -> u8 {
        if background.contains(index, v) {
            MISSING
        } else {
            self.quantizer.bin(v).unwrap_or(MISSING)
        }
    }

    /// The sums to give [`cut`](Self::cut): an oblique cut counts them as it cuts; along a
    /// coordinate axis [`summary`](Self::summary) counts them plane by plane.
    pub(crate) fn sums(&self) -> Option<SliceSums> {
        self.lattice.as_ref().map(|_| SliceSums::new(self.slices()))
    }

    /// The stack of the pixels of `rows` (a strip's positions are its own). Along an oblique
    /// axis, its slices' sums and counts of counted values are added onto `sums` when given.
    pub(crate) fn cut(
        &self,
        rows: Range<usize>,
        sums: Option<&mut SliceSums>,
        monitor: &Monitor,
    ) -> Result<SliceStack> {
        match (&self.lattice, coordinate_axis(self.axis)) {
            (Some(lattice), _) => self.along_lattice(lattice, rows, sums, monitor),
            (None, Some(m)) => self.along_coordinate(m, rows, monitor),
            (None, None) => unreachable!("a coordinate axis has no lattice"),
        }
    }

    /// The stack's per-slice geometry, background and sums without its columns: what a
    /// partition reports of the stack once its histograms are counted. `positions` are the
    /// strips' positions summed, `sums` the sums the cuts counted ([`sums`](Self::sums)),
    /// `None` along a coordinate axis, whose sums are counted here.
    pub(crate) fn summary(
        &self,
        positions: Vec<u64>,
        sums: Option<SliceSums>,
        monitor: &Monitor,
    ) -> Result<SliceStack> {
        monitor.check()?;
        let (volume, d) = (self.volume, self.axis);
        let background = self.background.test();
        let counted = |index: usize, v: f32| v.is_finite() && !background.contains(index, v);
        let SliceSums { sums, counts } = match (sums, coordinate_axis(d)) {
            (Some(sums), _) => sums,
            (None, Some(m)) => plane_sums(volume, m, &counted),
            (None, None) => unreachable!("an oblique cut counts its sums"),
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
            slices: self.slices(),
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

    /// The stack along coordinate axis `m`: per pixel its column of voxels. A task's pixels
    /// are taken [`RUN`] neighbours along the row at a time, plane after plane, so that the
    /// voxels are read along the rows they lie in: a column read alone steps a whole plane a
    /// voxel, and on planes of a power of two (256 × 256, 512 × 512) those steps all fall in a
    /// few sets of the caches, which then hold almost none of them.
    fn along_coordinate(
        &self,
        m: usize,
        rows: Range<usize>,
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
        let background = self.background.test();
        crate::volume::with_voxels!(volume.data(), |voxels| {
            symbols
                .par_chunks_mut(CUT_BLOCK * n)
                .enumerate()
                .try_for_each(|(c, out)| {
                    let (start, count) = (first + c * CUT_BLOCK, out.len() / n);
                    let mut k0 = 0;
                    while k0 < count {
                        let p = start + k0;
                        let run = (dims[a] - p % dims[a]).min(RUN).min(count - k0);
                        let base = (p % dims[a]) * stride[a] + (p / dims[a]) * stride[b];
                        let out = &mut out[k0 * n..(k0 + run) * n];
                        for s in 0..n {
                            let row = base + s * stride[m];
                            for k in 0..run {
                                let i = row + k * stride[a];
                                out[k * n + s] = self.symbol_in(background, i, voxels[i].to_f32());
                            }
                        }
                        k0 += run;
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

/// Per slice: the sum and count of the values that count (for slab means).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct SliceSums {
    pub(crate) sums: Vec<f64>,
    pub(crate) counts: Vec<u64>,
}

impl SliceSums {
    /// None yet, for `slices` slices.
    pub(crate) fn new(slices: usize) -> Self {
        Self {
            sums: vec![0.0; slices],
            counts: vec![0; slices],
        }
    }

    /// Adds `other`'s, slice by slice.
    pub(crate) fn add_onto(&mut self, other: &Self) {
        self.sums
            .iter_mut()
            .zip(&other.sums)
            .for_each(|(a, b)| *a += b);
        self.counts
            .iter_mut()
            .zip(&other.counts)
            .for_each(|(a, b)| *a += b);
    }
}

/// Per voxel plane along coordinate axis `m`: the sum and count of the counted values.
fn plane_sums(
    volume: &Volume,
    m: usize,
    counted: &(impl Fn(usize, f32) -> bool + Sync),
) -> SliceSums {
    let dims = volume.dims();
    let stride = [1, dims[0], dims[0] * dims[1]];
    let (a, b) = other_axes(m);
    let (sums, counts) = crate::volume::with_voxels!(volume.data(), |voxels| {
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
    });
    SliceSums { sums, counts }
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
