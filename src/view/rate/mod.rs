//! The entropy rate of one axis (paper §4): parallel rays on the lattice, trilinear samples,
//! quantized, with L-block and (L-1)-block counts pooled over all rays.

mod bricks;
mod columns;
mod grid;
#[cfg(target_arch = "x86_64")]
mod lanes;
mod sampler;
mod slab;
mod tiles;

use rayon::prelude::*;
use serde::Serialize;

pub use bricks::counts_of_bricks;
pub use grid::{BRICK_CELLS, Bricks};
pub use sampler::{BinSampler, InnerSpans, VoxelBins, window_bytes};
pub(crate) use slab::SLAB_ROWS;
pub use slab::{OpenRays, count_slab_into, count_slabs_into};

use crate::error::Result;
use crate::geometry::WorldAxis;
use crate::geometry::lattice::Lattice;
use crate::measure::{BlockCounts, DenseCounts};
use crate::progress::Monitor;
use crate::volume::Voxel;
use columns::column_counts;
#[cfg(target_arch = "x86_64")]
use tiles::mixed_bin;
pub use tiles::ray_bins;
use tiles::{Walker, fixed_step, scalar_walk, tile_rows, walk_rows};

/// An axis's entropy rate over lattice phases: the paper's lattice and shifted ones.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PhaseStats {
    /// Mean over the phases: the score axes are ranked by.
    pub mean: f64,
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
    /// Sample standard deviation (0 for one phase).
    pub std: f64,
    /// Number of phases.
    pub n: usize,
}

impl PhaseStats {
    /// The statistics of `values` (not empty).
    pub fn of(values: &[f64]) -> Self {
        let n = values.len();
        let mean = values.iter().sum::<f64>() / n as f64;
        let squares = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>();
        Self {
            mean,
            min: values.iter().copied().fold(f64::INFINITY, f64::min),
            max: values.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            std: if n > 1 {
                (squares / (n - 1) as f64).sqrt()
            } else {
                0.0
            },
            n,
        }
    }

    /// The standard error of the mean, `std / √n`.
    pub fn se(&self) -> f64 {
        self.std / (self.n as f64).sqrt()
    }
}

/// Which rays of a lattice are walked: one block of 8×8 neighbouring rays in `every`, in a
/// pattern spread evenly over the plane of rays (ray `(i, j)` when
/// `⌊i / 8⌋ + 5·⌊j / 8⌋ ≡ offset` modulo `every`). `every = 1` walks them all. Neighbours
/// share the cache lines they read, which single rays spread apart would not (measured: single
/// rays cost half as much again per sample); small blocks spread over the volume sample it
/// evenly, which whole tiles would not (their means strayed by 0.02 bit on the body phantom).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RaySubset {
    /// Keep one ray in this many.
    pub every: u64,
    /// Which one.
    pub offset: u64,
}

impl RaySubset {
    /// Every ray.
    pub const ALL: Self = Self {
        every: 1,
        offset: 0,
    };

    /// Whether ray `(i, j)` is kept.
    #[cfg(test)]
    fn keeps(self, i: i64, j: i64) -> bool {
        let every = self.every.max(1) as i64;
        every == 1
            || (i.div_euclid(RUN) + 5 * j.div_euclid(RUN)).rem_euclid(every)
                == self.offset as i64 % every
    }

    /// The rays `i` of row `j` within `a..=b` the subset keeps, in order: its blocks found by
    /// arithmetic, a division a row, not tested a ray at a time (a shifted lattice keeps a
    /// block in 12, and the test, two divisions, cost as much as setting a kept ray up).
    #[inline]
    fn row(self, j: i64, (a, b): (i64, i64)) -> KeptRays {
        let every = self.every.max(1) as i64;
        let wanted = (self.offset as i64 % every - 5 * j.div_euclid(RUN)).rem_euclid(every);
        let first = a.div_euclid(RUN);
        let block = first + (wanted - first).rem_euclid(every);
        KeptRays {
            i: a.max(block * RUN),
            last: b,
            block_last: block * RUN + RUN - 1,
            gap: RUN * (every - 1),
        }
    }
}

/// The rays of a row a [`RaySubset`] keeps ([`RaySubset::row`]).
struct KeptRays {
    /// The next ray, the last one of the row, the last of the block the next is in, and the
    /// rays between a kept block's end and the next kept block.
    i: i64,
    last: i64,
    block_last: i64,
    gap: i64,
}

impl Iterator for KeptRays {
    type Item = i64;

    #[inline]
    fn next(&mut self) -> Option<i64> {
        if self.i > self.block_last {
            self.i += self.gap;
            self.block_last += self.gap + RUN;
        }
        let i = self.i;
        (i <= self.last).then(|| {
            self.i += 1;
            i
        })
    }
}

/// The entropy rate of one axis, with the block entropies behind it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AxisEntropy {
    /// Canonical unit direction in physical space.
    pub axis: [f64; 3],
    /// The axis in world coordinates: `world_axis` and `anatomy`.
    #[serde(flatten)]
    pub world: WorldAxis,
    /// Angle of the axis's projection on the x-y plane from +x, degrees.
    pub azimuth: f64,
    /// Angle of the axis above the x-y plane, degrees.
    pub elevation: f64,
    /// `h = H(X^L) - H(X^(L-1))`, bits per sample (paper eq. 4): lower is more structured.
    pub entropy_rate: f64,
    /// `H(X^1)`, bits.
    pub h1: f64,
    /// `H(X^(L-1))`, bits.
    pub h_short: f64,
    /// `H(X^L)`, bits.
    pub h_long: f64,
    /// The paper's other estimate, `H(X^L) / L` (eq. 3).
    pub per_symbol: f64,
    /// Rays that met the volume.
    pub rays: u64,
    /// Samples counted (missing ones left out).
    pub samples: u64,
    /// L-blocks counted.
    pub blocks: u64,
    /// The entropy rate over lattice phases, when asked for.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub phases: Option<PhaseStats>,
    /// With the gain ranking: `I(slab; value)`, bits, kept by the top-down partition into K
    /// slabs along this axis, on the ranking's unshifted pixels (for the axis partitioned, on
    /// every voxel: the partition's `information`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub partition_gain: Option<f64>,
    /// With the gain ranking: the gain over its phases, whose mean ranks the axes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gain_phases: Option<PhaseStats>,
}

impl AxisEntropy {
    pub(crate) fn new(axis: [f64; 3], counts: &BlockCounts, rays: u64) -> Self {
        let (h1, h_short, h_long) = counts.entropies();
        let (azimuth, elevation) = crate::geometry::azimuth_elevation(axis);
        Self {
            axis,
            world: WorldAxis {
                world_axis: axis,
                anatomy: None,
                oriented: false,
            },
            azimuth,
            elevation,
            entropy_rate: (h_long - h_short).max(0.0),
            h1,
            h_short,
            h_long,
            per_symbol: h_long / counts.block() as f64,
            rays,
            samples: counts.symbols(),
            blocks: counts.blocks(),
            phases: None,
            partition_gain: None,
            gain_phases: None,
        }
    }

    /// Whether any ray held a block of L samples: without one, the rate says nothing (the
    /// volume is too thin along this axis) and the axis is ranked last.
    pub fn measured(&self) -> bool {
        self.blocks > 0
    }
}

/// Rays a subset keeps side by side in each direction (see [`RaySubset`]).
const RUN: i64 = 8;

/// Number of progress units [`entropy_rate`] reports for `lattice`: its rows of tiles.
pub fn work_units(lattice: &Lattice) -> u64 {
    work_units_of(lattice, RaySubset::ALL)
}

/// Number of progress units [`entropy_rate_of`] reports for `lattice` and `subset`.
pub fn work_units_of(lattice: &Lattice, subset: RaySubset) -> u64 {
    tile_rows(&[(lattice, subset)]).count() as u64
}

/// The entropy rate along `lattice`'s axis with blocks of length `block`, reporting one unit per
/// row of tiles to `monitor` (so it can be cancelled within a row's time).
pub fn entropy_rate<T: Voxel>(
    sampler: &BinSampler<T>,
    lattice: &Lattice,
    block: usize,
    monitor: &Monitor,
) -> Result<AxisEntropy> {
    entropy_rate_of(sampler, lattice, block, RaySubset::ALL, (monitor, 1))
}

/// [`entropy_rate`] over the tiles of rays `subset` keeps, reporting `per_row` units for each
/// row of tiles it walks (so that a search can make a unit of every lattice about as long).
pub fn entropy_rate_of<T: Voxel>(
    sampler: &BinSampler<T>,
    lattice: &Lattice,
    block: usize,
    subset: RaySubset,
    (monitor, per_row): (&Monitor, u64),
) -> Result<AxisEntropy> {
    let walk = (Walk::Fastest, subset);
    let (counts, rays) = counts_with(sampler, lattice, block, (monitor, per_row), walk)?;
    Ok(AxisEntropy::new(lattice.d, &counts, rays))
}

/// How the rays of a lattice are walked; every way counts the same (see [`block_counts_by`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Walk {
    /// Voxel columns where the rays are columns, else the tile walk (vector where the processor
    /// has it). The bricked walk is not chosen: on the machines measured it is slower (see
    /// docs/performance.md).
    Fastest,
    /// The tile walk.
    Tiles {
        /// Eight rays at a time where the processor has AVX2 (by the compilation asked for),
        /// else one by one.
        vector: Vector,
    },
    /// The bricked walk.
    Bricks {
        /// Cells along each side of a brick, or the cube root of its cells when `shaped`.
        size: usize,
        /// Whether the bricks are shaped for the lattice's axis (see [`Bricks::along`]).
        shaped: bool,
    },
}

/// Which compilation of the tile walk's eight-lane walk walks: every one counts the same.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Vector {
    /// None: one ray at a time.
    Off,
    /// The AVX2 one, on a processor with AVX-512 too (for tests and benchmarks).
    Avx2,
    /// The widest this processor runs: AVX-512's where it has it, else AVX2's.
    Widest,
}

/// The counts behind [`entropy_rate`], kept: the L-blocks, (L-1)-blocks and symbols of every
/// ray of the lattice, by the same walk, and the number of rays that met the volume. The
/// entropies of its tables give the rate exactly (the lesson's numbers are these).
pub fn block_counts<T: Voxel>(
    sampler: &BinSampler<T>,
    lattice: &Lattice,
    block: usize,
    monitor: &Monitor,
) -> Result<(BlockCounts, u64)> {
    let walk = (Walk::Fastest, RaySubset::ALL);
    counts_with(sampler, lattice, block, (monitor, 1), walk)
}

/// [`block_counts`] by the walk `walk`: for comparing the walks (every one counts the same).
pub fn block_counts_by<T: Voxel>(
    sampler: &BinSampler<T>,
    lattice: &Lattice,
    block: usize,
    walk: Walk,
    monitor: &Monitor,
) -> Result<(BlockCounts, u64)> {
    counts_with(
        sampler,
        lattice,
        block,
        (monitor, 1),
        (walk, RaySubset::ALL),
    )
}

/// The block counts, and the rays that met the volume, of the lattice's rays `subset` keeps,
/// walked as `walk` says, reporting `per_row` units to `monitor` for each row of tiles (the
/// bricked walk: one for each tile).
fn counts_with<T: Voxel>(
    sampler: &BinSampler<T>,
    lattice: &Lattice,
    block: usize,
    (monitor, per_row): (&Monitor, u64),
    (walk, subset): (Walk, RaySubset),
) -> Result<(BlockCounts, u64)> {
    if walk == Walk::Fastest
        && subset == RaySubset::ALL
        && let Some(axis) = lattice.columns()
    {
        return column_counts(sampler, lattice, axis, block, (monitor, per_row));
    }
    if let Walk::Bricks { size, shaped } = walk {
        return bricks::bricked_counts(sampler, lattice, block, (size, shaped), monitor);
    }
    let vector = match walk {
        Walk::Tiles { vector } => vector,
        _ => Vector::Widest,
    };
    let mut out = tile_counts(
        sampler,
        &[(lattice, subset)],
        block,
        (monitor, per_row),
        vector,
    )?;
    Ok(out.pop().expect("one lattice's counts"))
}

/// The entropy rates of `lattices` over the rays each one's subset keeps, reporting `units` in
/// all: each [`entropy_rate_of`]'s, but lattices of one step of which some walk a subset of
/// their rays (an axis's shifted phases, each walking one block of rays in 12, with or without
/// its paper lattice) walked together, tile by tile (`tiles::walk_rows`): counts are sums, so
/// the same counts.
pub fn entropy_rates_of<T: Voxel>(
    sampler: &BinSampler<T>,
    lattices: &[(&Lattice, RaySubset)],
    block: usize,
    (monitor, units): (&Monitor, u64),
) -> Result<Vec<AxisEntropy>> {
    let Some(&(first, _)) = lattices.first() else {
        monitor.advance(units)?;
        return Ok(Vec::new());
    };
    let step = fixed_step(first);
    let together = lattices.len() > 1
        && lattices.iter().any(|(_, s)| s.every > 1)
        && lattices.iter().all(|(l, _)| fixed_step(l) == step);
    if !together {
        let each = units / lattices.len() as u64;
        let rates = lattices
            .iter()
            .map(|&(l, s)| {
                let rows = work_units_of(l, s);
                let per_row = each / rows.max(1);
                let rate = entropy_rate_of(sampler, l, block, s, (monitor, per_row))?;
                monitor.advance(each - per_row * rows)?;
                Ok(rate)
            })
            .collect::<Result<Vec<_>>>()?;
        monitor.advance(units - each * lattices.len() as u64)?;
        return Ok(rates);
    }
    let rows = tile_rows(lattices).count() as u64;
    let per_row = units / rows.max(1);
    let counts = tile_counts(sampler, lattices, block, (monitor, per_row), Vector::Widest)?;
    monitor.advance(units.saturating_sub(per_row * rows))?;
    Ok(lattices
        .iter()
        .zip(counts)
        .map(|((l, _), (counts, rays))| AxisEntropy::new(l.d, &counts, rays))
        .collect())
}

/// The tile walk of `lattices` (one step; see [`tiles::walk_rows`]): vector where the processor
/// has it and `vector` allows, else one by one.
fn tile_counts<T: Voxel>(
    sampler: &BinSampler<T>,
    lattices: &[(&Lattice, RaySubset)],
    block: usize,
    (monitor, per_row): (&Monitor, u64),
    vector: Vector,
) -> Result<Vec<(BlockCounts, u64)>> {
    let rows: Vec<(i64, i64)> = tile_rows(lattices).collect();
    let step = fixed_step(lattices[0].0);
    let table = (sampler.bins(), block, lattices.len());
    let along = (step, sampler);
    counts_in_parallel(
        rows,
        table,
        sampler.voxels().len(),
        (monitor, per_row),
        |js, counts, rays| {
            let dense: Option<Vec<DenseCounts>> =
                counts.iter_mut().map(BlockCounts::dense).collect();
            match dense {
                #[cfg(target_arch = "x86_64")]
                Some(mut dense) if vector != Vector::Off && lanes::available(sampler) => {
                    let width = match vector {
                        Vector::Avx2 => lanes::Width::Avx2,
                        _ => lanes::Width::detected(),
                    };
                    let mut chunks = lanes::Chunks::new();
                    let mut common = |w: &mut [Walker], c: &mut DenseCounts| {
                        #[allow(unsafe_code)]
                        // SAFETY: `lanes::available` found AVX2 on this processor, and
                        // `detected` AVX-512 where it chose it.
                        unsafe {
                            lanes::walk(width, w, along, c, &mut chunks);
                        }
                    };
                    walk_rows(lattices, js, along, &mut dense, rays, &mut common);
                }
                Some(mut dense) => {
                    let _ = vector;
                    let mut common = |w: &mut [Walker], c: &mut DenseCounts| {
                        scalar_walk(w, step, sampler, c);
                    };
                    walk_rows(lattices, js, along, &mut dense, rays, &mut common);
                }
                None => {
                    let mut common = |w: &mut [Walker], c: &mut BlockCounts| {
                        scalar_walk(w, step, sampler, c);
                    };
                    walk_rows(lattices, js, along, counts, rays, &mut common);
                }
            }
        },
    )
}

/// Volumes of fewer voxels than this are counted on one thread, into one table: each parallel
/// split zeroes and merges a table of its own (256 KiB at the default bins and block), which
/// costs more than counting a small volume (a single DICOM image took 20 ms so, mostly zeroing
/// tables). Counts are integer sums, the same in any order, so every result is unchanged.
const SERIAL_VOXELS: usize = 1 << 16;

/// The least number of a parallel walk's `items` a thread takes when they cover `voxels`: all
/// of them below [`SERIAL_VOXELS`] (a slab of a few planes of a small volume, as the streamed
/// search with a small budget sweeps, is walked sooner than its parts are handed to other
/// threads and each given a zeroed table to add), else one.
fn serial_len(voxels: usize, items: usize) -> usize {
    if voxels < SERIAL_VOXELS {
        items.max(1)
    } else {
        1
    }
}

/// Block counts of `parts` of the work over `voxels` voxels, counted by `count` (which returns
/// its rays), `per_part` progress units a part: in parallel, unless [`serial_len`] says one
/// thread.
fn count_in_parallel<P: Send>(
    parts: Vec<P>,
    (bins, block): (usize, usize),
    voxels: usize,
    (monitor, per_part): (&Monitor, u64),
    count: impl Fn(P, &mut BlockCounts) -> u64 + Sync,
) -> Result<(BlockCounts, u64)> {
    let one = |part, counts: &mut [BlockCounts], rays: &mut [u64]| {
        rays[0] += count(part, &mut counts[0]);
    };
    let mut out = counts_in_parallel(parts, (bins, block, 1), voxels, (monitor, per_part), one)?;
    Ok(out.pop().expect("one table"))
}

/// [`count_in_parallel`] into `tables` tables at once, `count` adding each one's rays to its
/// entry of the rays it is given.
fn counts_in_parallel<P: Send>(
    parts: Vec<P>,
    (bins, block, tables): (usize, usize, usize),
    voxels: usize,
    (monitor, per_part): (&Monitor, u64),
    count: impl Fn(P, &mut [BlockCounts], &mut [u64]) + Sync,
) -> Result<Vec<(BlockCounts, u64)>> {
    // Each table made apart (not cloned): its pages are zeroed lazily, and only those its codes
    // touch are ever resident.
    let empty = || {
        let counts: Vec<BlockCounts> = (0..tables).map(|_| BlockCounts::new(bins, block)).collect();
        (counts, vec![0; tables])
    };
    let min_len = serial_len(voxels, parts.len());
    let (counts, rays) = parts
        .into_par_iter()
        .with_min_len(min_len)
        .try_fold(empty, |(mut counts, mut rays), part| {
            count(part, &mut counts, &mut rays);
            monitor.advance(per_part)?;
            Ok::<_, crate::error::Error>((counts, rays))
        })
        .try_reduce_with(|(mut a, mut ra), (b, rb)| {
            for (a, b) in a.iter_mut().zip(&b) {
                a.merge(b);
            }
            for (a, b) in ra.iter_mut().zip(rb) {
                *a += b;
            }
            Ok((a, ra))
        })
        .unwrap_or_else(|| Ok(empty()))?;
    Ok(counts.into_iter().zip(rays).collect())
}

#[cfg(test)]
pub(super) mod tests;
