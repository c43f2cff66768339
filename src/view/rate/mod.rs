//! The entropy rate of one axis (paper §4): parallel rays on the lattice, trilinear samples,
//! quantized, with L-block and (L-1)-block counts pooled over all rays.

#[cfg(target_arch = "x86_64")]
mod lanes;

use rayon::prelude::*;
use serde::Serialize;

use crate::error::Result;
use crate::measure::{BlockCounts, Counter, DenseCounts, Run};
use crate::progress::Monitor;
use crate::volume::cells::MIXED;
mod sampler;

pub use sampler::{BinSampler, InnerSpans};

use crate::geometry::lattice::{Lattice, round_half_away, to_fixed};
use crate::geometry::{WorldAxis, cross};

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

    #[inline]
    fn keeps(self, i: i64, j: i64) -> bool {
        let every = self.every.max(1) as i64;
        every == 1
            || (i.div_euclid(RUN) + 5 * j.div_euclid(RUN)).rem_euclid(every)
                == self.offset as i64 % every
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
}

impl AxisEntropy {
    fn new(axis: [f64; 3], counts: &BlockCounts, rays: u64) -> Self {
        let (h1, h_short, h_long) = counts.entropies();
        Self {
            axis,
            world: WorldAxis {
                world_axis: axis,
                anatomy: None,
                oriented: false,
            },
            // `+ 0.0` turns -0 into 0 for display.
            azimuth: axis[1].atan2(axis[0]).to_degrees() + 0.0,
            elevation: axis[2].clamp(-1.0, 1.0).asin().to_degrees() + 0.0,
            entropy_rate: (h_long - h_short).max(0.0),
            h1,
            h_short,
            h_long,
            per_symbol: h_long / counts.block() as f64,
            rays,
            samples: counts.symbols(),
            blocks: counts.blocks(),
            phases: None,
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

/// Rays are walked in tiles of this many neighbouring rays, so that the memory they read stays a
/// small neighbourhood: the scalar walk advances all rays of a tile together, one sample each in
/// turn; the vector walk takes them eight at a time.
const TILE_RAYS: i64 = 256;

/// Cells per cache line in the cell map (one byte per cell).
const CELLS_PER_LINE: f64 = 64.0;

/// The shape of the tiles of `lattice`: how many rays along `i` and along `j`.
///
/// Reading memory dominates the walk, so the shape is the one whose walk crosses the fewest
/// cache lines. A tile sweeps a prism along the axis; its cross-section's area is the same for
/// every shape, so the lines it crosses differ by its side faces: a face spanned by a tile edge
/// `e` and the step `s` crosses about `|(e × s)_x| + (|(e × s)_y| + |(e × s)_z|) / 64` lines per
/// unit area (cache lines run 64 cells along x). Minimizing `ti·c_i + tj·c_j` with
/// `ti·tj = TILE_RAYS` gives `ti = sqrt(TILE_RAYS·c_j / c_i)`, rounded to a power of two.
/// A walk of one ray in `every` spans `every` times the rays, so that a tile still walks about
/// `TILE_RAYS` of them.
fn tile_shape(lattice: &Lattice, every: u64) -> (i64, i64) {
    let rays = TILE_RAYS * every.max(1) as i64;
    let to_index = |w: [f64; 3], length: f64| lattice.to_index(w.map(|c| c * length));
    let step = to_index(lattice.d, lattice.sample_spacing);
    let cost = |w: [f64; 3]| {
        let n = cross(to_index(w, lattice.ray_spacing), step);
        n[0].abs() + (n[1].abs() + n[2].abs()) / CELLS_PER_LINE
    };
    let (ci, cj) = (cost(lattice.u), cost(lattice.v));
    let ratio = (rays as f64 * cj / ci.max(1e-12)).sqrt();
    let max_log = rays.ilog2() as f64;
    let ti = 1i64 << ratio.log2().round().clamp(0.0, max_log) as u32;
    (ti, rays / ti)
}

/// A ray of a tile being walked: where it is, its block state, and how many samples it has in
/// the tile's common walk (all inside cells, see [`BinSampler::inner_span`]) and after it.
struct Walker {
    p: [i64; 3],
    /// During the common walk: the bin or `MIXED` of the cell of `p`, and the cell of the next
    /// sample.
    bin: u8,
    next: usize,
    run: Run,
    inner: i64,
    tail: i64,
    grid: bool,
}

/// Whether `x` is a whole number up to rounding.
fn is_whole(x: f64) -> bool {
    (x - round_half_away(x) as f64).abs() < 1e-9
}

/// One sample at `w`'s position (anywhere in the volume up to rounding) into its run.
fn edge_sample(sampler: &BinSampler, counts: &mut impl Counter, w: &mut Walker) {
    let bin = if w.grid {
        sampler.voxel_bin(w.p)
    } else {
        sampler.bin_fixed(w.p)
    };
    match bin {
        Some(b) => counts.push_to(&mut w.run, b),
        None => counts.end_run(&mut w.run),
    }
}

/// The bin of a sample in a mixed cell: interpolated, or the voxel itself on the grid. Out of
/// line, to keep the common path of [`walk_tile`] small.
#[inline(never)]
fn mixed_bin(sampler: &BinSampler, p: [i64; 3], cell: usize, grid: bool) -> Option<u8> {
    if grid {
        sampler.voxel_bin(p)
    } else {
        sampler.inner_bin(p, cell)
    }
}

#[inline]
fn add(p: [i64; 3], step: [i64; 3]) -> [i64; 3] {
    std::array::from_fn(|m| p[m] + step[m])
}

#[inline]
fn advance(p: &mut [i64; 3], step: [i64; 3]) {
    for m in 0..3 {
        p[m] += step[m];
    }
}

/// The rays of one tile: columns `is` of the rows `js.0 ..`, each row's rays that can meet the
/// box in `rows` (see [`Lattice::row_span`]), and the subset walked.
struct TileRays<'a> {
    is: (i64, i64),
    js: (i64, i64),
    rows: &'a [Option<(i64, i64)>],
    subset: RaySubset,
}

/// Feeds the quantized samples of the rays `(i, j)` of one tile into `counts`: each ray's
/// samples in order, a missing sample breaking its sequence. `step` is the lattice's step in
/// fixed point; `common` walks the rays' inner spans together. Returns the number of rays.
fn walk_tile<C: Counter>(
    lattice: &Lattice,
    tile: &TileRays,
    step: [i64; 3],
    sampler: &BinSampler,
    counts: &mut C,
    walkers: &mut Vec<Walker>,
    common: &mut impl FnMut(&mut [Walker], &mut C),
) -> u64 {
    let whole_step = lattice.step().iter().all(|&c| is_whole(c));
    let spans = sampler.inner_spans(step);
    walkers.clear();
    for (j, row) in (tile.js.0..=tile.js.1).zip(tile.rows) {
        let Some((a, b)) = *row else { continue };
        for i in a.max(tile.is.0)..=b.min(tile.is.1) {
            if !tile.subset.keeps(i, j) {
                continue;
            }
            let Some(ray) = lattice.ray(i, j) else {
                continue;
            };
            let start = ray.at(ray.k0);
            let grid = whole_step && start.iter().all(|&c| is_whole(c));
            let p = to_fixed(if grid {
                start.map(|c| round_half_away(c) as f64)
            } else {
                start
            });
            let n = ray.k1 - ray.k0 + 1;
            let (t0, t1) = spans.of(p, n);
            let mut w = Walker {
                p,
                bin: MIXED,
                next: 0,
                run: Run::default(),
                inner: t1 - t0,
                tail: n - t1,
                grid,
            };
            // The samples before the inner span, one by one.
            for _ in 0..t0 {
                edge_sample(sampler, counts, &mut w);
                advance(&mut w.p, step);
            }
            walkers.push(w);
        }
    }
    let rays = walkers.len() as u64;
    common(walkers, counts);
    // The samples after the inner span.
    for w in walkers.iter_mut() {
        for _ in 0..w.tail {
            edge_sample(sampler, counts, w);
            advance(&mut w.p, step);
        }
        counts.end_run(&mut w.run);
    }
    rays
}

/// The common walk of a tile's rays through their inner spans, one sample per ray in turn,
/// leaving each at the end of its span.
fn scalar_walk(
    walkers: &mut [Walker],
    step: [i64; 3],
    sampler: &BinSampler,
    counts: &mut impl Counter,
) {
    // Longest span first, so that the rays still walking are always a prefix.
    walkers.sort_unstable_by_key(|w| std::cmp::Reverse(w.inner));
    for w in walkers.iter_mut().filter(|w| w.inner > 0) {
        w.bin = sampler.cell_bin(sampler.inner_cell(w.p));
        w.next = sampler.inner_cell(add(w.p, step));
    }
    let mut active = walkers.len();
    let mut t = 0;
    loop {
        while active > 0 && walkers[active - 1].inner <= t {
            active -= 1;
        }
        if active == 0 {
            break;
        }
        for w in &mut walkers[..active] {
            match w.bin {
                MIXED => match mixed_bin(sampler, w.p, sampler.inner_cell(w.p), w.grid) {
                    Some(b) => counts.push_to(&mut w.run, b),
                    None => counts.end_run(&mut w.run),
                },
                b => counts.push_to(&mut w.run, b),
            }
            advance(&mut w.p, step);
            // A walker comes back a whole round of the tile later, time enough for memory: ask
            // now for the cell after next, and for the corners of the next if it is mixed.
            if w.inner > t + 1 {
                w.bin = sampler.cell_bin(w.next);
                if w.bin == MIXED {
                    sampler.prefetch_corners(w.next);
                }
            }
            w.next = sampler.inner_cell(add(w.p, step));
            sampler.prefetch_cell(w.next);
        }
        t += 1;
    }
}

/// Feeds the rays of the tile row `js` that `subset` keeps into `counts`, walking their inner
/// spans with `common`. Returns the number of rays.
fn walk_row<C: Counter>(
    lattice: &Lattice,
    js: (i64, i64),
    subset: RaySubset,
    step: [i64; 3],
    sampler: &BinSampler,
    counts: &mut C,
    common: &mut impl FnMut(&mut [Walker], &mut C),
) -> u64 {
    let ((i0, i1), _) = lattice.ray_ranges();
    let rows: Vec<Option<(i64, i64)>> = (js.0..=js.1).map(|j| lattice.row_span(j)).collect();
    // The columns any row of the tile row can meet.
    let (lo, hi) = rows
        .iter()
        .flatten()
        .fold((i1, i0), |(lo, hi), &(a, b)| (lo.min(a), hi.max(b)));
    let (lo, hi) = (lo.max(i0), hi.min(i1));
    if lo > hi {
        return 0;
    }
    let (ti, _) = tile_shape(lattice, subset.every);
    let mut walkers = Vec::with_capacity(TILE_RAYS as usize);
    (lo..=hi)
        .step_by(ti as usize)
        .map(|i| {
            let tile = TileRays {
                is: (i, (i + ti - 1).min(hi)),
                js,
                rows: &rows,
                subset,
            };
            walk_tile(lattice, &tile, step, sampler, counts, &mut walkers, common)
        })
        .sum()
}

/// The step between samples of `lattice` in fixed point; a whole step is snapped, so that rays
/// on the grid stay exactly on it.
fn fixed_step(lattice: &Lattice) -> [i64; 3] {
    let step = lattice.step();
    if step.iter().all(|&c| is_whole(c)) {
        to_fixed(step.map(|c| round_half_away(c) as f64))
    } else {
        to_fixed(step)
    }
}

/// The inclusive ranges of the tile rows of `lattice`'s rays, for a walk of one ray in `every`.
fn tile_rows(lattice: &Lattice, every: u64) -> impl Iterator<Item = (i64, i64)> {
    let (_, (j0, j1)) = lattice.ray_ranges();
    let (_, tj) = tile_shape(lattice, every);
    (j0..=j1)
        .step_by(tj as usize)
        .map(move |j| (j, (j + tj - 1).min(j1)))
}

/// Number of progress units [`entropy_rate`] reports for `lattice`: its rows of tiles.
pub fn work_units(lattice: &Lattice) -> u64 {
    work_units_of(lattice, RaySubset::ALL)
}

/// Number of progress units [`entropy_rate_of`] reports for `lattice` and `subset`.
pub fn work_units_of(lattice: &Lattice, subset: RaySubset) -> u64 {
    tile_rows(lattice, subset.every).count() as u64
}

/// The entropy rate along `lattice`'s axis with blocks of length `block`, reporting one unit per
/// row of tiles to `monitor` (so it can be cancelled within a row's time).
pub fn entropy_rate(
    sampler: &BinSampler,
    lattice: &Lattice,
    block: usize,
    monitor: &Monitor,
) -> Result<AxisEntropy> {
    rate_with(
        sampler,
        lattice,
        block,
        monitor,
        Walk::Fastest,
        RaySubset::ALL,
    )
}

/// [`entropy_rate`] over the tiles of rays `subset` keeps.
pub fn entropy_rate_of(
    sampler: &BinSampler,
    lattice: &Lattice,
    block: usize,
    subset: RaySubset,
    monitor: &Monitor,
) -> Result<AxisEntropy> {
    rate_with(sampler, lattice, block, monitor, Walk::Fastest, subset)
}

/// How [`rate_with`] walks the rays; every way counts the same.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Walk {
    /// Voxel columns where the rays are columns, else the vector walk where the processor has
    /// it, else the scalar walk.
    Fastest,
    /// The tile walk, vector or scalar.
    Tiles { vector: bool },
}

/// [`entropy_rate`], walking the rays as `walk` says.
fn rate_with(
    sampler: &BinSampler,
    lattice: &Lattice,
    block: usize,
    monitor: &Monitor,
    walk: Walk,
    subset: RaySubset,
) -> Result<AxisEntropy> {
    if walk == Walk::Fastest
        && subset == RaySubset::ALL
        && let Some(axis) = lattice.columns()
    {
        return column_rate(sampler, lattice, axis, block, monitor);
    }
    let vector = walk != (Walk::Tiles { vector: false });
    let rows: Vec<(i64, i64)> = tile_rows(lattice, subset.every).collect();
    let step = fixed_step(lattice);
    let (counts, rays) = count_in_parallel(rows, sampler.bins(), block, monitor, |js, counts| {
        match counts.dense() {
            #[cfg(target_arch = "x86_64")]
            Some(mut dense) if vector && lanes::available(sampler) => {
                let mut common = |w: &mut [Walker], c: &mut DenseCounts| {
                    #[allow(unsafe_code)]
                    // SAFETY: `lanes::available` found AVX2 on this processor.
                    unsafe {
                        lanes::walk(w, step, sampler, c);
                    }
                };
                walk_row(lattice, js, subset, step, sampler, &mut dense, &mut common)
            }
            Some(mut dense) => {
                let _ = vector;
                let mut common = |w: &mut [Walker], c: &mut DenseCounts| {
                    scalar_walk(w, step, sampler, c);
                };
                walk_row(lattice, js, subset, step, sampler, &mut dense, &mut common)
            }
            None => {
                let mut common = |w: &mut [Walker], c: &mut BlockCounts| {
                    scalar_walk(w, step, sampler, c);
                };
                walk_row(lattice, js, subset, step, sampler, counts, &mut common)
            }
        }
    })?;
    Ok(AxisEntropy::new(lattice.d, &counts, rays))
}

/// Block counts of `parts` of the work, counted in parallel by `count` (which returns its
/// rays), one progress unit per part.
fn count_in_parallel<P: Send>(
    parts: Vec<P>,
    bins: usize,
    block: usize,
    monitor: &Monitor,
    count: impl Fn(P, &mut BlockCounts) -> u64 + Sync,
) -> Result<(BlockCounts, u64)> {
    let empty = || (BlockCounts::new(bins, block), 0);
    parts
        .into_par_iter()
        .try_fold(empty, |(mut counts, rays), part| {
            let n = count(part, &mut counts);
            monitor.advance(1)?;
            Ok((counts, rays + n))
        })
        .try_reduce(empty, |(mut a, ra), (b, rb)| {
            a.merge(&b);
            Ok((a, ra + rb))
        })
}

/// Voxel columns along one axis, walked a few side by side (so that their work overlaps) in
/// memory order: item `i` holds the columns starting at voxels `base·i + gap·c` for `c` in
/// `0..width` (fewer in the last item), and a column's sample `k` lies `stride·k` further.
struct Columns {
    count: usize,
    width: usize,
    gap: usize,
    base: usize,
    stride: usize,
    length: usize,
}

impl Columns {
    /// Rows along x are walked eight at a time; columns along y or z a row of them at a time.
    fn new([nx, ny, nz]: [usize; 3], axis: usize) -> Self {
        let (count, width, gap, base, stride, length) = match axis {
            0 => (ny * nz, 8, nx, 8 * nx, 1, nx),
            1 => (nx * nz, nx, 1, nx * ny, nx, ny),
            _ => (nx * ny, nx, 1, nx, nx * ny, nz),
        };
        Self {
            count,
            width,
            gap,
            base,
            stride,
            length,
        }
    }

    fn items(&self) -> usize {
        self.count.div_ceil(self.width)
    }

    /// Feeds the items `range` into `counts`; returns the number of columns.
    fn walk(
        &self,
        range: std::ops::Range<usize>,
        sampler: &BinSampler,
        counts: &mut impl Counter,
    ) -> u64 {
        let bins = sampler.voxel_bins();
        let mut runs = vec![Run::default(); self.width];
        let mut total = 0;
        for item in range {
            let width = self.width.min(self.count - item * self.width);
            total += width;
            for k in 0..self.length {
                let start = item * self.base + k * self.stride;
                for (c, run) in runs[..width].iter_mut().enumerate() {
                    let at = start + c * self.gap;
                    let bin = match bins[at] {
                        MIXED => sampler.voxel_bin_at(at),
                        b => Some(b),
                    };
                    match bin {
                        Some(b) => counts.push_to(run, b),
                        None => counts.end_run(run),
                    }
                }
            }
            for run in &mut runs[..width] {
                counts.end_run(run);
            }
        }
        total as u64
    }
}

/// [`entropy_rate`] of a lattice whose rays are the voxel columns along `axis` (see
/// [`Lattice::columns`]): samples are voxels, read in memory order a row of columns at a time.
fn column_rate(
    sampler: &BinSampler,
    lattice: &Lattice,
    axis: usize,
    block: usize,
    monitor: &Monitor,
) -> Result<AxisEntropy> {
    let columns = Columns::new(sampler.dims(), axis);
    // As many parts as the general walk reports progress units.
    let parts = work_units(lattice).max(1) as usize;
    let items = columns.items();
    let ranges = (0..parts)
        .map(|part| part * items / parts..(part + 1) * items / parts)
        .collect();
    let (counts, rays) = count_in_parallel(
        ranges,
        sampler.bins(),
        block,
        monitor,
        |range, counts| match counts.dense() {
            Some(mut dense) => columns.walk(range, sampler, &mut dense),
            None => columns.walk(range, sampler, counts),
        },
    )?;
    Ok(AxisEntropy::new(lattice.d, &counts, rays))
}

#[cfg(test)]
mod tests;
