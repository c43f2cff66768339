//! Cutting a volume into a slice stack: the voxel planes along a coordinate axis, the grid
//! resampled on the ray lattice along an oblique one, each sample quantized (or left out as
//! background) and each slice's sum and count of values kept for slab means.

use rayon::prelude::*;

use super::{BackgroundSummary, Column, Lattice, MISSING, SliceStack, StackParams};
use crate::error::{Error, Result};
use crate::geometry::{WorldAxis, canonical, coordinate_axis, normalize};
use crate::progress::Monitor;
use crate::volume::background::Background;
use crate::volume::interpolate::Interpolator;
use crate::volume::{Volume, Voxel};

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
        let background = Background::find(volume, params.background, monitor)?;
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
        let mut symbols = vec![MISSING; pixels * n];
        monitor.start("slicing", pixels.div_ceil(4096) as u64);
        crate::volume::with_voxels!(volume.data(), |voxels| {
            symbols
                .par_chunks_mut(4096 * n)
                .enumerate()
                .try_for_each(|(c, out)| {
                    for (k, col) in out.chunks_mut(n).enumerate() {
                        let p = c * 4096 + k;
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
        let rows: Vec<i64> = (j0..=j1).collect();
        monitor.start("slicing", rows.len() as u64);
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
