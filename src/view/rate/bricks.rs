//! The bricked walk: the cell map visited brick by brick, and while a brick is in cache, every
//! stretch of every ray of the lattice that crosses it walked. A ray carries its run (its last
//! L-1 symbols) from brick to brick, so the counts are those of the tile walk, bit for bit.
//!
//! The tile walk takes a few hundred neighbouring rays through the whole volume together: along
//! an oblique axis each step reads new cache lines, a few cells of each used, and once the cell
//! map outgrows the cache every axis reads it from memory several times over. Here each brick
//! of the map (a cube of [`BRICK_CELLS`] cells a side: 256 KiB, within a core's L2 cache) is
//! read once per axis and pass over the rays, and all its cells are used while it is there.
//!
//! Bricks are visited in an order every ray meets them in (coordinates rising or falling with
//! the ray's step, z slowest), so a ray's stretches come in order. Counted apart, any set of
//! bricks gives [`PartialCounts`]: what its stretches determine, and the fragments of rays that
//! enter or leave it, which [`PartialCounts::add`] stitches with the neighbours' — so bricks can
//! be counted on any thread, in any order, in any process.
//!
//! Not the default walk: its stretches are short (a brick's mean chord), and the eight-lane
//! walk's fixed cost per stretch makes it slower than the tile walk on the machines measured
//! (docs/performance.md, "The bricked walk").

use rayon::prelude::*;

use super::grid::Bricks;
use super::tiles::{
    RayStart, RayStarts, TileOrder, Walker, advance, by_bucket, sample_bin, scalar_walk, tile_rows,
};
use super::{BinSampler, RaySubset};
use crate::error::{Error, Result};
use crate::geometry::lattice::{FIXED_BITS, Lattice};
use crate::measure::{BlockCounts, Fragment, PartialCounts, ray_key};
use crate::progress::Monitor;
use crate::volume::Voxel;

/// Where one ray of a band stands.
struct Slot {
    /// Sample 0's position, fixed point, and whether the samples are voxels.
    p0: [i64; 3],
    grid: bool,
    /// Samples in all, and the inner span `t0..t1` (samples inside cells).
    n: i64,
    t0: i64,
    t1: i64,
    /// The next sample, and its position.
    t: i64,
    p: [i64; 3],
    key: u64,
    /// The fragment being counted.
    open: Option<Fragment>,
}

/// The rays of a band of rows walked together, and per brick the rays whose next sample lies in
/// it (by index in `slots`), in the order they were set up.
pub(super) struct Band {
    slots: Vec<Slot>,
    waiting: Vec<Vec<u32>>,
}

/// Exact `⌊a / b⌋` for `b > 0`.
fn floor_div(a: i64, b: i64) -> i64 {
    a.div_euclid(b)
}

/// How many samples from `p` on, `step` apart, stay in the box `lo..hi` (fixed point), where
/// `p` lies in it.
#[inline]
fn steps_in(p: [i64; 3], step: [i64; 3], lo: [i64; 3], hi: [i64; 3]) -> i64 {
    let mut n = i64::MAX;
    for m in 0..3 {
        let s = step[m];
        let k = match s.signum() {
            1 => floor_div(hi[m] - p[m] - 1, s) + 1,
            -1 => floor_div(p[m] - lo[m], -s) + 1,
            _ => continue,
        };
        n = n.min(k);
    }
    n
}

#[inline]
pub(super) fn at(p0: [i64; 3], step: [i64; 3], t: i64) -> [i64; 3] {
    std::array::from_fn(|m| p0[m] + t * step[m])
}

/// The walk of one lattice brick by brick: what every band shares.
pub(super) struct BrickWalk<'a, T: Voxel> {
    pub(super) sampler: &'a BinSampler<'a, T>,
    lattice: &'a Lattice,
    bricks: Bricks,
    pub(super) block: usize,
    pub(super) step: [i64; 3],
    /// Which bricks are walked (all when `None`).
    member: Option<Vec<bool>>,
    /// Which rays are walked.
    subset: RaySubset,
    /// When the bricks walked are a slab of the grid: its cells along z, `lo..hi` in fixed
    /// point. Rays are then set up only where they can meet it, and taken up where they enter it.
    slab: Option<(i64, i64)>,
    /// Whether the bricks walked are one brick, the slab's planes whole: a ray's samples inside
    /// cells there are then one stretch, found by arithmetic ([`slab_stretch`](Self::slab_stretch)).
    whole: bool,
}

impl<'a, T: Voxel> BrickWalk<'a, T> {
    fn new(
        sampler: &'a BinSampler<'a, T>,
        lattice: &'a Lattice,
        block: usize,
        bricks: Bricks,
        member: Option<Vec<bool>>,
    ) -> Self {
        Self {
            sampler,
            lattice,
            bricks,
            block,
            step: super::fixed_step(lattice),
            member,
            subset: RaySubset::ALL,
            slab: None,
            whole: false,
        }
    }

    /// The walk of the bricks of `bricks` whose cells along z are `planes`, along the rays
    /// `subset` keeps.
    pub(super) fn of_slab(
        sampler: &'a BinSampler<'a, T>,
        lattice: &'a Lattice,
        block: usize,
        bricks: Bricks,
        (planes, subset): (std::ops::Range<i64>, RaySubset),
    ) -> Self {
        let member: Vec<bool> = (0..bricks.len())
            .map(|b| {
                let (lo, hi) = bricks.cells_of(b);
                lo[2] >= planes.start && hi[2] <= planes.end
            })
            .collect();
        let (_, all) = bricks.cells_of(bricks.len() - 1);
        let whole = member.iter().filter(|&&m| m).count() == 1
            && member.iter().enumerate().any(|(b, &m)| {
                m && bricks.cells_of(b) == ([0, 0, planes.start], [all[0], all[1], planes.end])
            });
        Self {
            subset,
            slab: Some((planes.start << FIXED_BITS, planes.end << FIXED_BITS)),
            whole,
            ..Self::new(sampler, lattice, block, bricks, Some(member))
        }
    }

    /// The tile walk's order of the rays walked.
    pub(super) fn tile_order(&self) -> TileOrder {
        TileOrder::new(self.lattice, self.subset.every)
    }

    /// Whether the bricks walked are the slab's planes whole, one brick.
    pub(super) fn whole_slab(&self) -> bool {
        self.whole
    }

    /// The samples `ta..tb` of the inner span `t0..t1` of the ray from `p0` (fixed point) whose
    /// cells lie in the slab's planes (empty when none do), for a walk of the slab's planes
    /// whole ([`whole_slab`](Self::whole_slab)): as the ray's cells along z rise or fall
    /// steadily, they are one stretch, from where it enters the slab to where it leaves it.
    pub(super) fn slab_stretch(&self, p0: [i64; 3], (t0, t1): (i64, i64)) -> (i64, i64) {
        let Some((lo, hi)) = self.slab else {
            return (t0, t1);
        };
        let (s, ta) = (self.step[2], self.slab_entry(p0, t0));
        let z = p0[2] + ta * s;
        if ta >= t1 || z < lo || z >= hi {
            // It misses the slab, or steps over it.
            return (t1, t1);
        }
        let exit = match s.signum() {
            // The first sample at or past `hi`, or below `lo` going down.
            1 => floor_div(hi - 1 - p0[2], s) + 1,
            -1 => floor_div(p0[2] - lo, -s) + 1,
            _ => t1,
        };
        (ta, exit.min(t1))
    }

    /// The range of `i` of row `j` whose rays can meet the bricks walked.
    fn row_span(&self, j: i64) -> Option<(i64, i64)> {
        match self.slab {
            None => self.lattice.row_span(j),
            Some((lo, hi)) => {
                let s = self.lattice.spacing()[2];
                let z = |c: i64| (c >> FIXED_BITS) as f64 * s;
                self.lattice.row_span_within(j, (2, z(lo), z(hi)))
            }
        }
    }

    /// The first sample of a ray from `p0` (fixed point) at or after `t` that can lie in the
    /// slab walked (`t` when there is none): samples before it lie in bricks not walked.
    fn slab_entry(&self, p0: [i64; 3], t: i64) -> i64 {
        let (Some((lo, hi)), s) = (self.slab, self.step[2]) else {
            return t;
        };
        let first = match s.signum() {
            // The first with p + t·s >= lo, or below hi going down.
            1 => floor_div(lo - p0[2] + s - 1, s),
            -1 => floor_div(p0[2] - hi, -s) + 1,
            _ => return t,
        };
        first.max(t)
    }

    /// Whether a ray at `p` has left the slab walked for good.
    fn past_slab(&self, p: [i64; 3]) -> bool {
        self.slab.is_some_and(|(lo, hi)| {
            let s = self.step[2];
            (s > 0 && p[2] >= hi) || (s < 0 && p[2] < lo)
        })
    }

    fn walked(&self, b: usize) -> bool {
        self.member.as_ref().is_none_or(|m| m[b])
    }

    /// The bricks walked, in sweep order.
    pub(super) fn order(&self) -> Vec<usize> {
        self.bricks
            .sweep(self.step)
            .into_iter()
            .filter(|&b| self.walked(b))
            .collect()
    }

    /// Each ray of rows `j0..=j1` that can meet the bricks walked and has samples inside cells,
    /// set up, in order of key, to `each`. A ray with no sample inside a cell is counted into
    /// `out` here: whole if the brick of its first sample is walked, or, in a slab, as the
    /// pieces of its samples in the slab's bricks ([`outer_pieces`](Self::outer_pieces)).
    pub(super) fn rays(
        &self,
        (j0, j1): (i64, i64),
        out: &mut PartialCounts,
        mut each: impl FnMut(u64, RayStart, &mut PartialCounts),
    ) {
        let ((i0, i1), _) = self.lattice.ray_ranges();
        let starts = RayStarts::new(self.lattice, self.sampler, self.step);
        for j in j0..=j1 {
            let Some((a, b)) = self.row_span(j) else {
                continue;
            };
            for i in self.subset.row(j, (a.max(i0), b.min(i1))) {
                let Some(start) = starts.of(i, j) else {
                    continue;
                };
                let key = ray_key(i, j);
                if start.t0 < start.t1 {
                    each(key, start, out);
                } else if self.slab.is_some() {
                    // No sample inside a cell (the ray lies on the volume's far faces). In a
                    // slab: its samples in the slab's bricks, as pieces.
                    self.outer_pieces(key, (start.p, start.grid, start.n), out);
                } else if self.walked(self.bricks.holding(start.p)) {
                    // Else the whole ray, with the brick of its first sample.
                    let mut f = Fragment::new(key, 0);
                    self.feed(&mut f, &mut out.counts, start.p, start.grid, start.n);
                    out.rays += 1;
                    let _ = f.close(&mut out.counts, true);
                }
            }
        }
    }

    /// The rays of rows `j0..=j1`, each waiting in the brick of its first sample inside a cell
    /// that is walked (in a slab, the first from where the ray can enter it); those with no
    /// sample inside a cell counted into `out` at once ([`rays`](Self::rays)).
    pub(super) fn band(&self, js: (i64, i64), out: &mut PartialCounts) -> Band {
        let mut band = Band {
            slots: Vec::new(),
            waiting: vec![Vec::new(); self.bricks.len()],
        };
        self.rays(js, out, |key, start, out| {
            let RayStart {
                p: p0,
                grid,
                n,
                t0,
                t1,
            } = start;
            let t = self.slab_entry(p0, t0);
            if t >= t1 {
                return;
            }
            let mut slot = Slot {
                p0,
                grid,
                n,
                t0,
                t1,
                t,
                p: at(p0, self.step, t),
                key,
                open: None,
            };
            if let Some(b) = self.locate(&mut slot, out) {
                band.waiting[b].push(band.slots.len() as u32);
            }
            band.slots.push(slot);
        });
        band
    }

    /// The pieces of a ray of `n` samples from `p` with no sample inside a cell (it lies on
    /// the volume's far faces) whose samples lie in bricks walked, each a fragment, so that a
    /// slab reads the planes of its own samples alone.
    fn outer_pieces(
        &self,
        key: u64,
        (mut p, grid, n): ([i64; 3], bool, i64),
        out: &mut PartialCounts,
    ) {
        let mut piece: Option<Fragment> = None;
        for t in 0..n {
            if self.walked(self.bricks.holding(p)) {
                if piece.is_none() {
                    out.rays += u64::from(t == 0);
                    piece = Some(Fragment::new(key, t as u64));
                }
                if let Some(f) = piece.as_mut() {
                    f.push(&mut out.counts, sample_bin(self.sampler, p, grid));
                }
            } else if let Some(f) = piece.take() {
                let left = f.close(&mut out.counts, false);
                out.push_fragment(left);
            }
            advance(&mut p, self.step);
        }
        if let Some(f) = piece {
            let left = f.close(&mut out.counts, true);
            out.push_fragment(left);
        }
    }

    /// Appends the `count` samples of a ray from `p` on to `f`, one by one.
    pub(super) fn feed(
        &self,
        f: &mut Fragment,
        counts: &mut BlockCounts,
        mut p: [i64; 3],
        grid: bool,
        count: i64,
    ) {
        for _ in 0..count {
            f.push(counts, sample_bin(self.sampler, p, grid));
            advance(&mut p, self.step);
        }
    }

    /// The brick walked that holds `slot`'s next sample, moving the ray on past bricks not
    /// walked (closing its fragment as it leaves them); `None` when its inner span has ended.
    fn locate(&self, slot: &mut Slot, out: &mut PartialCounts) -> Option<usize> {
        while slot.t < slot.t1 {
            let b = self.bricks.holding(slot.p);
            if self.walked(b) {
                return Some(b);
            }
            if let Some(f) = slot.open.take() {
                let left = f.close(&mut out.counts, false);
                out.push_fragment(left);
            }
            if self.past_slab(slot.p) {
                return None;
            }
            let (lo, hi) = self.bricks.bounds(b);
            slot.t += steps_in(slot.p, self.step, lo, hi);
            slot.p = at(slot.p0, self.step, slot.t);
        }
        None
    }

    /// Walks `band`'s rays through the bricks `order` (the walked ones, in sweep order),
    /// counting into `out`, and ends them.
    pub(super) fn walk(&self, band: &mut Band, order: &[usize], out: &mut PartialCounts) {
        let (mut walkers, mut sorted, mut tally) = (Vec::new(), Vec::new(), Vec::new());
        let mut state = CommonState::default();
        for &b in order {
            let ids = std::mem::take(&mut band.waiting[b]);
            if ids.is_empty() {
                continue;
            }
            walkers.clear();
            for &id in &ids {
                if let Some(w) = self.enter(&mut band.slots[id as usize], b, out) {
                    walkers.push(Walker {
                        id: id as usize,
                        ..w
                    });
                }
            }
            // Stretches of like lengths side by side: the walk eight at a time takes each group
            // as many steps as its longest (stretches in a brick run from one sample to its
            // diameter; every cell they read is in cache).
            by_length(&mut walkers, &mut sorted, &mut tally);
            let along = (self.step, self.sampler);
            common_walk(&mut sorted, along, &mut out.counts, &mut state);
            for w in &sorted {
                let slot = &mut band.slots[w.id];
                slot.p = w.p;
                slot.t += w.inner;
                if let Some(f) = slot.open.as_mut() {
                    f.walked(w.inner as u64, w.run);
                }
            }
            for &id in &ids {
                if let Some(next) = self.locate(&mut band.slots[id as usize], out) {
                    band.waiting[next].push(id);
                }
            }
        }
        // Rays end: the samples after the inner span where the ray reached its end here.
        for slot in &mut band.slots {
            let Some(mut f) = slot.open.take() else {
                continue;
            };
            let last = slot.t == slot.t1;
            if last {
                self.feed(&mut f, &mut out.counts, slot.p, slot.grid, slot.n - slot.t1);
            }
            let left = f.close(&mut out.counts, last);
            out.push_fragment(left);
        }
    }

    /// The stretch of `slot`'s ray in brick `b`, where its next sample lies, to walk with the
    /// others, after its fragment's head (taken one sample at a time); `None` when the stretch
    /// was all head.
    fn enter(&self, slot: &mut Slot, b: usize, out: &mut PartialCounts) -> Option<Walker> {
        let f = slot.open.get_or_insert_with(|| {
            let mut f = Fragment::new(slot.key, if slot.t == slot.t0 { 0 } else { slot.t as u64 });
            if f.first() {
                out.rays += 1;
                // The samples before the inner span.
                self.feed(&mut f, &mut out.counts, slot.p0, slot.grid, slot.t0);
            }
            f
        });
        let (lo, hi) = self.bricks.bounds(b);
        let mut m = steps_in(slot.p, self.step, lo, hi).min(slot.t1 - slot.t);
        // The head of a fragment that does not start its ray, one sample at a time.
        while m > 0 && f.in_head(self.block) {
            f.push(&mut out.counts, sample_bin(self.sampler, slot.p, slot.grid));
            advance(&mut slot.p, self.step);
            slot.t += 1;
            m -= 1;
        }
        (m > 0).then(|| Walker {
            p: slot.p,
            run: f.run(),
            inner: m,
            grid: slot.grid,
            ..Walker::idle()
        })
    }
}

/// `walkers` moved into `sorted`, longest stretch first (a counting sort: the lengths are
/// small numbers, bounded by a brick's diameter).
pub(super) fn by_length(
    walkers: &mut Vec<Walker>,
    sorted: &mut Vec<Walker>,
    tally: &mut Vec<usize>,
) {
    let longest = walkers.iter().map(|w| w.inner).max().unwrap_or(0) as usize;
    by_bucket(walkers, sorted, tally, |w| longest - w.inner as usize);
}

/// What [`common_walk`] keeps from one call to the next of a thread's walk: the eight-lane
/// walk's chunks, made at the first call that walks eight at a time (a brick's stretches are
/// walked by a call each, and making the chunks for each would allocate and zero 6.8 KiB).
#[derive(Default)]
pub(super) struct CommonState {
    #[cfg(target_arch = "x86_64")]
    chunks: Option<super::lanes::Chunks>,
}

/// The inner spans of `walkers` walked together, into `counts`: eight at a time with AVX2 on a
/// dense table, else one by one.
pub(super) fn common_walk<T: Voxel>(
    walkers: &mut [Walker],
    (step, sampler): ([i64; 3], &BinSampler<T>),
    counts: &mut BlockCounts,
    state: &mut CommonState,
) {
    if walkers.is_empty() {
        return;
    }
    match counts.dense() {
        #[cfg(target_arch = "x86_64")]
        Some(mut dense) if super::lanes::available(sampler) => {
            let chunks = state.chunks.get_or_insert_with(super::lanes::Chunks::new);
            #[allow(unsafe_code)]
            // SAFETY: `lanes::available` found AVX2 on this processor, and `detected` AVX-512
            // where it chose it.
            unsafe {
                let width = super::lanes::Width::detected();
                super::lanes::walk(width, walkers, (step, sampler), &mut dense, chunks);
            }
        }
        Some(mut dense) => scalar_walk(walkers, step, sampler, &mut dense),
        None => scalar_walk(walkers, step, sampler, counts),
    }
}

/// Rows of tiles per band: about four bricks thick, so that few bricks are read by two bands.
fn band_rows(lattice: &Lattice, size: usize) -> usize {
    let rays = 4.0 * size as f64 * lattice.sample_spacing / lattice.ray_spacing;
    let tile = tile_rows(&[(lattice, RaySubset::ALL)])
        .next()
        .map_or(1, |(a, b)| (b - a + 1).max(1));
    ((rays / tile as f64).ceil() as usize).max(1)
}

/// The block counts of every ray of `lattice`, and the rays that met the volume, by the bricked
/// walk with bricks of `size` cells a side (or as many cells, shaped for the axis, when
/// `shaped`): bands of rows of rays in parallel, each band's
/// bricks in sweep order. One progress unit per row of tiles, as the tile walk reports.
pub(super) fn bricked_counts<T: Voxel>(
    sampler: &BinSampler<T>,
    lattice: &Lattice,
    block: usize,
    (size, shaped): (usize, bool),
    monitor: &Monitor,
) -> Result<(BlockCounts, u64)> {
    let bricks = if shaped {
        Bricks::along(sampler.dims(), size, super::fixed_step(lattice))
    } else {
        Bricks::new(sampler.dims(), size)
    };
    let walk = BrickWalk::new(sampler, lattice, block, bricks, None);
    let order = walk.order();
    let rows: Vec<(i64, i64)> = tile_rows(&[(lattice, RaySubset::ALL)]).collect();
    let bands: Vec<&[(i64, i64)]> = rows.chunks(band_rows(lattice, size)).collect();
    let empty = || PartialCounts::new(sampler.bins(), block);
    let total = bands
        .into_par_iter()
        .try_fold(empty, |mut out, tiles| {
            let js = (tiles[0].0, tiles[tiles.len() - 1].1);
            let mut band = walk.band(js, &mut out);
            walk.walk(&mut band, &order, &mut out);
            monitor.advance(tiles.len() as u64)?;
            Ok::<_, Error>(out)
        })
        .try_reduce_with(|mut a, b| {
            a.add(b);
            Ok(a)
        })
        .unwrap_or_else(|| Ok(empty()))?;
    if !total.is_complete() {
        return Err(Error::Degenerate(format!(
            "the bricked walk left {} pieces of rays unjoined",
            total.fragments().len()
        )));
    }
    Ok((total.counts, total.rays))
}

/// The block counts of the bricks `set` of `bricks` (a grid over `sampler`'s volume) along
/// `lattice`: what their stretches of rays determine, and the fragments of the rays that enter
/// or leave them. The counts of all the bricks, added in any grouping and order, are those of
/// [`block_counts`](super::block_counts), bit for bit.
pub fn counts_of_bricks<T: Voxel>(
    sampler: &BinSampler<T>,
    lattice: &Lattice,
    block: usize,
    bricks: Bricks,
    set: &[usize],
) -> PartialCounts {
    let mut member = vec![false; bricks.len()];
    for &b in set {
        if let Some(m) = member.get_mut(b) {
            *m = true;
        }
    }
    let walk = BrickWalk::new(sampler, lattice, block, bricks, Some(member));
    let order = walk.order();
    let mut out = PartialCounts::new(sampler.bins(), block);
    let (_, js) = lattice.ray_ranges();
    let mut band = walk.band(js, &mut out);
    walk.walk(&mut band, &order, &mut out);
    out
}
