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
use crate::volume::{Quantizer, Volume, Voxel, VoxelBox};

mod oblique;
mod sparse;
mod sums;

use self::oblique::lattice_box;
pub(crate) use self::sums::{RowSink, SliceSums};

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
        monitor.start("slicing", cutter.work(&rows, true));
        let mut sums = SliceSums::new(cutter.slices());
        let Self {
            columns,
            symbols,
            positions,
            ..
        } = cutter.cut(rows, Some(&mut |row| sums.add_onto(row)), monitor)?;
        Ok(Self {
            columns,
            symbols,
            ..cutter.summary(positions, sums, monitor)?
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

    /// The cutter of `volume` along `axis` (made canonical) with `background` found beforehand
    /// (of the whole volume, when `volume` holds a part of it): what a task of a partition in
    /// parts cuts with.
    pub(crate) fn given(
        volume: &'a Volume,
        axis: [f64; 3],
        params: &StackParams,
        background: &'a Background,
    ) -> Result<Self> {
        Self::with(volume, axis, params, Cow::Borrowed(background), |d| {
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

    /// The box of voxels the samples of `rows` read (their cells' corners and nearest
    /// voxels), `None` when they hold no sample.
    pub(crate) fn voxel_box(&self, rows: &Range<usize>) -> Option<VoxelBox> {
        self.voxel_box_within(rows, None)
    }

    /// [`voxel_box`](Self::voxel_box) of the voxels in the planes `planes` along z alone (all
    /// of them with `None`): a box holding every voxel of those planes the samples of `rows`
    /// read, `None` when they read none there.
    pub(crate) fn voxel_box_within(
        &self,
        rows: &Range<usize>,
        planes: Option<&Range<usize>>,
    ) -> Option<VoxelBox> {
        let whole = match (&self.lattice, coordinate_axis(self.axis)) {
            (Some(lattice), _) => lattice_box(lattice, rows, self.volume.dims(), planes),
            (None, Some(m)) => {
                let (dims, (_, b)) = (self.volume.dims(), other_axes(m));
                if rows.is_empty() || rows.end > dims[b] || dims.contains(&0) {
                    return None;
                }
                let (mut origin, mut size) = ([0; 3], dims);
                (origin[b], size[b]) = (rows.start, rows.len());
                Some(VoxelBox { origin, size })
            }
            (None, None) => unreachable!("a coordinate axis has no lattice"),
        }?;
        let Some(planes) = planes else {
            return Some(whole);
        };
        let start = whole.origin[2].max(planes.start);
        let end = (whole.origin[2] + whole.size[2]).min(planes.end);
        (start < end).then(|| VoxelBox {
            origin: [whole.origin[0], whole.origin[1], start],
            size: [whole.size[0], whole.size[1], end - start],
        })
    }

    /// The number of bins.
    pub(crate) fn bins(&self) -> usize {
        self.bins
    }

    /// The bytes the background takes (its mask, for a found one).
    pub(crate) fn background_bytes(&self) -> u64 {
        self.background.memory_bytes()
    }

    /// The units of work [`cut`](Self::cut) of `rows` advances its monitor by, `counting` the
    /// rows' sums or not (the caller starts the phase, so that strips cut one after another
    /// advance one phase).
    pub(crate) fn work(&self, rows: &Range<usize>, counting: bool) -> u64 {
        match coordinate_axis(self.axis) {
            Some(m) if self.lattice.is_none() => {
                let cut = (rows.len() * self.volume.dims()[other_axes(m).0]).div_ceil(CUT_BLOCK);
                (cut + if counting { rows.len() } else { 0 }) as u64
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

    /// The stack of the pixels of `rows` (a strip's positions are its own). With `sums`, each
    /// row's sums and counts of counted values per slice are handed to it, in row order: the
    /// slices' sums are those rows' sums added in row order, whether the rows are cut at once,
    /// in strips one after another, or in parts apart ([`SliceSums`]).
    pub(crate) fn cut(
        &self,
        rows: Range<usize>,
        sums: Option<RowSink>,
        monitor: &Monitor,
    ) -> Result<SliceStack> {
        match (&self.lattice, coordinate_axis(self.axis)) {
            (Some(lattice), _) => self.along_lattice(lattice, rows, sums, monitor),
            (None, Some(m)) => {
                let stack = self.along_coordinate(m, rows.clone(), monitor)?;
                if let Some(sink) = sums {
                    self.coordinate_row_sums(m, rows, sink, monitor)?;
                }
                Ok(stack)
            }
            (None, None) => unreachable!("a coordinate axis has no lattice"),
        }
    }

    /// The stack's per-slice geometry, background and sums without its columns: what a
    /// partition reports of the stack once its histograms are counted. `positions` are the
    /// strips' positions summed, `sums` every row's sums added in row order.
    pub(crate) fn summary(
        &self,
        positions: Vec<u64>,
        sums: SliceSums,
        monitor: &Monitor,
    ) -> Result<SliceStack> {
        monitor.check()?;
        let (volume, d) = (self.volume, self.axis);
        let SliceSums { sums, counts } = sums;
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
