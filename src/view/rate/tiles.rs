//! The tile walk: the lattice's rays in tiles of neighbouring rays, each ray's samples before and
//! after its inner span one by one, and the inner spans walked together, by the scalar walk here
//! or eight at a time by `lanes`.

use super::{BinSampler, InnerSpans, RaySubset};
use crate::geometry::cross;
use crate::geometry::lattice::{Lattice, Ray, round_half_away, to_fixed};
use crate::measure::{Counter, Run};
use crate::volume::Voxel;
use crate::volume::cells::MIXED;

/// Rays are walked in tiles of neighbouring rays, so that the memory they read stays a small
/// neighbourhood: the scalar walk advances all rays of a tile together, one sample each in
/// turn; the vector walk takes them eight at a time. A tile spans this many of a lattice's
/// rays, whether each is walked or not, where a core's second-level cache holds 1 MiB or
/// more...
const TILE_SPAN: f64 = 512.0;

/// ...and this many where it holds less. A group of eight rays walks its whole span before the
/// next group starts, so the group beside it in the tile's next row of rays finds the lines it
/// shares with it only if a row of the tile's groups, each over a ray's length, fit in that
/// cache. Measured on a processor with 512 KiB a core (AMD EPYC, Zen 3): the paper's lattices
/// of a 512³ body 7.6 s against 8.9 s with tiles of 512 (1024³: 66 and 71 ns a voxel), the
/// same at 256×256×415, where rays are shorter; with 1 or 2 MiB (Zen 4, Xeon) 512 was best.
const SMALL_TILE_SPAN: f64 = 128.0;

/// Whichever the span, a tile walks at least this share of it: a tile of a lattice walking one
/// ray in 12 spans six times as many of its rays.
const TILE_RAYS_OF_SPAN: f64 = 0.5;

/// The rays a tile spans on this processor ([`TILE_SPAN`], [`SMALL_TILE_SPAN`]), found once.
/// Where its cache is not known, [`TILE_SPAN`]. Only the order of the rays depends on it, so
/// the counts are the same on every processor.
fn tile_span() -> f64 {
    static SPAN: std::sync::OnceLock<f64> = std::sync::OnceLock::new();
    *SPAN.get_or_init(|| match second_level_cache() {
        Some(bytes) if bytes < 1 << 20 => SMALL_TILE_SPAN,
        _ => TILE_SPAN,
    })
}

/// A core's second-level cache in bytes, as the processor reports it (the extended leaf
/// `0x8000_0006` of `cpuid`, which AMD's and Intel's processors fill); `None` where it does not.
fn second_level_cache() -> Option<u64> {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::__cpuid;
        if __cpuid(0x8000_0000).eax >= 0x8000_0006 {
            let kib = u64::from(__cpuid(0x8000_0006).ecx >> 16);
            return (kib > 0).then_some(kib << 10);
        }
    }
    None
}

/// Cells per cache line in the cell map (one byte per cell).
const CELLS_PER_LINE: f64 = 64.0;

/// The shape of the tiles of `lattice` walking `density` rays a lattice ray (the sum of one in
/// `every` over the lattices walked together): how many rays along `i` and along `j`.
///
/// Reading memory dominates the walk, so the shape is the one whose walk crosses the fewest
/// cache lines. A tile sweeps a prism along the axis; its cross-section's area is the same for
/// every shape, so the lines it crosses differ by its side faces: a face spanned by a tile edge
/// `e` and the step `s` crosses about `|(e × s)_x| + (|(e × s)_y| + |(e × s)_z|) / 64` lines per
/// unit area (cache lines run 64 cells along x). Minimizing `ti·c_i + tj·c_j` with `ti·tj` the
/// tile's span gives `ti = sqrt(span·c_j / c_i)`, rounded to a power of two.
fn tile_shape(lattice: &Lattice, density: f64) -> (i64, i64) {
    let span = tile_span();
    let rays = span.max(span * TILE_RAYS_OF_SPAN / density).round() as i64;
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

/// The shape of the tiles of `lattices` walked together (one step): the first one's, for the
/// rays they walk together (a lattice walking one ray in `every` adds `1 / every` to the
/// density). Measured on the default search of a 512³ body (an axis's paper lattice and its 7
/// shifted phases, each walking one block of rays in 12, walked together): tiles spanning 512
/// lattice rays took 5% less time than tiles holding 256 of the rays walked, and as long as
/// tiles spanning 1,024; the paper's lattice alone took the same time with tiles of 256 and
/// 512 rays.
fn shape_of(lattices: &[(&Lattice, RaySubset)]) -> (i64, i64) {
    let Some(&(l, _)) = lattices.first() else {
        return (1, 1);
    };
    let density: f64 = lattices
        .iter()
        .map(|(_, s)| 1.0 / s.every.max(1) as f64)
        .sum();
    tile_shape(l, density)
}

/// The tile walk's order of a lattice's rays, as the number of each ray's tile: rows of tiles
/// in turn, each column by column. Rays set up in key order (row by row) and sorted stably by
/// it are walked as the tile walk takes them, neighbours together, so that a ray meets the
/// cache lines its neighbours in the rows beside it have just read.
#[derive(Clone, Copy, Debug)]
pub(super) struct TileOrder {
    first: (i64, i64),
    shape: (i64, i64),
    columns: i64,
}

impl TileOrder {
    pub(super) fn new(lattice: &Lattice, every: u64) -> Self {
        let ((i0, i1), (j0, _)) = lattice.ray_ranges();
        let shape = tile_shape(lattice, 1.0 / every.max(1) as f64);
        Self {
            first: (i0, j0),
            shape,
            columns: (i1 - i0).div_euclid(shape.0) + 1,
        }
    }

    /// The tile of ray `(i, j)` (of the lattice's ranges).
    pub(super) fn tile_of(&self, (i, j): (i64, i64)) -> usize {
        let column = (i - self.first.0).div_euclid(self.shape.0);
        let row = (j - self.first.1).div_euclid(self.shape.1);
        (row * self.columns + column).max(0) as usize
    }
}

/// `walkers` into `sorted` by the bucket `of` gives each, smallest first, in their order within
/// a bucket: a counting sort (no walker compared, each moved once), with `tally` its counts.
pub(super) fn by_bucket(
    walkers: &mut Vec<Walker>,
    sorted: &mut Vec<Walker>,
    tally: &mut Vec<usize>,
    of: impl Fn(&Walker) -> usize,
) {
    let (lo, hi) = walkers
        .iter()
        .map(&of)
        .fold((usize::MAX, 0), |(lo, hi), b| (lo.min(b), hi.max(b)));
    tally.clear();
    tally.resize(hi.saturating_sub(lo) + 2, 0);
    for w in walkers.iter() {
        tally[of(w) - lo + 1] += 1;
    }
    for k in 1..tally.len() {
        tally[k] += tally[k - 1];
    }
    sorted.clear();
    sorted.resize_with(walkers.len(), Walker::idle);
    for w in walkers.drain(..) {
        let slot = &mut tally[of(&w) - lo];
        sorted[*slot] = w;
        *slot += 1;
    }
}

/// A ray of a tile being walked: where it is, its block state, and how many samples it has in
/// the tile's common walk (all inside cells, see [`BinSampler::inner_span`]) and after it.
pub(super) struct Walker {
    pub(super) p: [i64; 3],
    /// During the common walk: the bin or `MIXED` of the cell of `p`, and the cell of the next
    /// sample.
    pub(super) bin: u8,
    pub(super) next: usize,
    pub(super) run: Run,
    pub(super) inner: i64,
    pub(super) tail: i64,
    pub(super) grid: bool,
    /// Which ray it is, for a walk that keeps rays between common walks.
    pub(super) id: usize,
}

impl Walker {
    /// A walker with nothing to walk, to be filled in.
    pub(super) fn idle() -> Self {
        Self {
            p: [0; 3],
            bin: MIXED,
            next: 0,
            run: Run::default(),
            inner: 0,
            tail: 0,
            grid: false,
            id: 0,
        }
    }
}

/// Whether `x` is a whole number up to rounding.
fn is_whole(x: f64) -> bool {
    (x - round_half_away(x) as f64).abs() < 1e-9
}

/// The bin of the sample at `p` (anywhere in the volume up to rounding), the voxel itself when
/// the ray lies on the `grid`: what every walk counts there.
#[inline]
pub(super) fn sample_bin<T: Voxel>(sampler: &BinSampler<T>, p: [i64; 3], grid: bool) -> Option<u8> {
    if grid {
        sampler.voxel_bin(p)
    } else {
        sampler.bin_fixed(p)
    }
}

/// One sample at `w`'s position (anywhere in the volume up to rounding) into its run.
fn edge_sample<T: Voxel>(sampler: &BinSampler<T>, counts: &mut impl Counter, w: &mut Walker) {
    match sample_bin(sampler, w.p, w.grid) {
        Some(b) => counts.push_to(&mut w.run, b),
        None => counts.end_run(&mut w.run),
    }
}

/// The bin of a sample in a mixed cell: interpolated, or the voxel itself on the grid. Out of
/// line, to keep the common path of [`walk_tile`] small.
#[inline(never)]
pub(super) fn mixed_bin<T: Voxel>(
    sampler: &BinSampler<T>,
    p: [i64; 3],
    cell: usize,
    grid: bool,
) -> Option<u8> {
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
pub(super) fn advance(p: &mut [i64; 3], step: [i64; 3]) {
    for m in 0..3 {
        p[m] += step[m];
    }
}

/// Where a ray's walk starts, in fixed point, and whether its samples lie on the voxel grid
/// (`whole_step`: the lattice's step is whole): then they are the voxels themselves.
fn ray_start(ray: &Ray, whole_step: bool) -> ([i64; 3], bool) {
    let start = ray.at(ray.k0);
    let grid = whole_step && start.iter().all(|&c| is_whole(c));
    let p = to_fixed(if grid {
        start.map(|c| round_half_away(c) as f64)
    } else {
        start
    });
    (p, grid)
}

/// A ray set up for a walk: its first sample's position (fixed point), whether its samples are
/// voxels, how many it has, and its inner span `t0..t1` (the samples inside cells).
pub(super) struct RayStart {
    pub(super) p: [i64; 3],
    pub(super) grid: bool,
    pub(super) n: i64,
    pub(super) t0: i64,
    pub(super) t1: i64,
}

/// What setting up the rays of one lattice for a walk needs, worked out once.
pub(super) struct RayStarts<'a> {
    lattice: &'a Lattice,
    spans: InnerSpans,
    whole_step: bool,
}

impl<'a> RayStarts<'a> {
    /// For the rays of `lattice` walked with `sampler`, `step` (fixed point) apart.
    pub(super) fn new<T: Voxel>(
        lattice: &'a Lattice,
        sampler: &BinSampler<T>,
        step: [i64; 3],
    ) -> Self {
        Self {
            lattice,
            spans: sampler.inner_spans(step),
            whole_step: lattice.step().iter().all(|&c| is_whole(c)),
        }
    }

    /// Ray `(i, j)` set up, or `None` when it misses the box.
    #[inline]
    pub(super) fn of(&self, i: i64, j: i64) -> Option<RayStart> {
        let ray = self.lattice.ray(i, j)?;
        let (p, grid) = ray_start(&ray, self.whole_step);
        let n = ray.k1 - ray.k0 + 1;
        let (t0, t1) = self.spans.of(p, n);
        Some(RayStart { p, grid, n, t0, t1 })
    }
}

/// The quantized samples of ray `(i, j)` of `lattice`, in order (`None` for a missing one), as
/// every walk of the entropy rate counts them; `None` when the ray misses the volume. One ray
/// at a time, for showing: the walks count whole tiles.
pub fn ray_bins<T: Voxel>(
    sampler: &BinSampler<T>,
    lattice: &Lattice,
    i: i64,
    j: i64,
) -> Option<Vec<Option<u8>>> {
    let ray = lattice.ray(i, j)?;
    let (mut p, grid) = ray_start(&ray, lattice.step().iter().all(|&c| is_whole(c)));
    let step = fixed_step(lattice);
    let bins = (ray.k0..=ray.k1)
        .map(|_| {
            let bin = sample_bin(sampler, p, grid);
            advance(&mut p, step);
            bin
        })
        .collect();
    Some(bins)
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
fn walk_tile<C: Counter, T: Voxel>(
    starts: &RayStarts,
    tile: &TileRays,
    step: [i64; 3],
    sampler: &BinSampler<T>,
    counts: &mut C,
    walkers: &mut Vec<Walker>,
    common: &mut impl FnMut(&mut [Walker], &mut C),
) -> u64 {
    walkers.clear();
    for (j, row) in (tile.js.0..=tile.js.1).zip(tile.rows) {
        let Some((a, b)) = *row else { continue };
        for i in tile.subset.row(j, (a.max(tile.is.0), b.min(tile.is.1))) {
            let Some(RayStart { p, grid, n, t0, t1 }) = starts.of(i, j) else {
                continue;
            };
            let mut w = Walker {
                p,
                bin: MIXED,
                next: 0,
                run: Run::default(),
                inner: t1 - t0,
                tail: n - t1,
                grid,
                id: 0,
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
pub(super) fn scalar_walk<T: Voxel>(
    walkers: &mut [Walker],
    step: [i64; 3],
    sampler: &BinSampler<T>,
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

/// One lattice's part of a row of tiles: its rows of rays there (clipped to its own), each
/// row's rays that can meet the box, and the columns any of them can meet.
struct RowOf {
    js: (i64, i64),
    rows: Vec<Option<(i64, i64)>>,
    is: (i64, i64),
}

impl RowOf {
    fn new(lattice: &Lattice, js: (i64, i64)) -> Option<Self> {
        let ((i0, i1), (j0, j1)) = lattice.ray_ranges();
        let js = (js.0.max(j0), js.1.min(j1));
        if js.0 > js.1 {
            return None;
        }
        let rows: Vec<Option<(i64, i64)>> = (js.0..=js.1).map(|j| lattice.row_span(j)).collect();
        let (lo, hi) = rows
            .iter()
            .flatten()
            .fold((i1, i0), |(lo, hi), &(a, b)| (lo.min(a), hi.max(b)));
        let is = (lo.max(i0), hi.min(i1));
        (is.0 <= is.1).then_some(Self { js, rows, is })
    }
}

/// Feeds the rays of the tile row `js` of each of `lattices` that its subset keeps into its
/// counter in `counts`, walking their inner spans with `common`, and adds each lattice's rays
/// to `rays`. The lattices share one step (an axis's shifted phases, each walking one block of
/// rays in `every`, the blocks of one phase beside those of the next, and perhaps its paper
/// lattice, every ray) and the tiles of the first: each tile's rays of every lattice are walked in turn, so that the cache lines one
/// lattice's block of rays reads are still near for its neighbours' blocks. (Walked one
/// lattice after another, each block met lines whose other rays' blocks were walked a whole
/// sweep of the volume earlier or later.)
pub(super) fn walk_rows<C: Counter, T: Voxel>(
    lattices: &[(&Lattice, RaySubset)],
    js: (i64, i64),
    (step, sampler): ([i64; 3], &BinSampler<T>),
    counts: &mut [C],
    rays: &mut [u64],
    common: &mut impl FnMut(&mut [Walker], &mut C),
) {
    let own: Vec<Option<RowOf>> = lattices.iter().map(|(l, _)| RowOf::new(l, js)).collect();
    let Some((lo, hi)) = own
        .iter()
        .flatten()
        .map(|o| o.is)
        .reduce(|a, b| (a.0.min(b.0), a.1.max(b.1)))
    else {
        return;
    };
    let starts: Vec<RayStarts> = lattices
        .iter()
        .map(|(l, _)| RayStarts::new(l, sampler, step))
        .collect();
    let (ti, tj) = shape_of(lattices);
    let mut walkers = Vec::with_capacity((ti * tj) as usize);
    for i in (lo..=hi).step_by(ti as usize) {
        for (k, o) in own.iter().enumerate() {
            let Some(o) = o else { continue };
            let is = (i.max(o.is.0), (i + ti - 1).min(o.is.1));
            if is.0 > is.1 {
                continue;
            }
            let tile = TileRays {
                is,
                js: o.js,
                rows: &o.rows,
                subset: lattices[k].1,
            };
            rays[k] += walk_tile(
                &starts[k],
                &tile,
                step,
                sampler,
                &mut counts[k],
                &mut walkers,
                common,
            );
        }
    }
}

/// The step between samples of `lattice` in fixed point; a whole step is snapped, so that rays
/// on the grid stay exactly on it.
pub(super) fn fixed_step(lattice: &Lattice) -> [i64; 3] {
    let step = lattice.step();
    if step.iter().all(|&c| is_whole(c)) {
        to_fixed(step.map(|c| round_half_away(c) as f64))
    } else {
        to_fixed(step)
    }
}

/// The inclusive ranges of the tile rows of `lattices`' rays together (see [`walk_rows`]): the
/// tiles of the first, over the rows of all.
pub(super) fn tile_rows(lattices: &[(&Lattice, RaySubset)]) -> impl Iterator<Item = (i64, i64)> {
    let (j0, j1) = lattices
        .iter()
        .map(|(l, _)| l.ray_ranges().1)
        .reduce(|a, b| (a.0.min(b.0), a.1.max(b.1)))
        .unwrap_or((0, -1));
    let (_, tj) = shape_of(lattices);
    (j0..=j1)
        .step_by(tj as usize)
        .map(move |j| (j, (j + tj - 1).min(j1)))
}
