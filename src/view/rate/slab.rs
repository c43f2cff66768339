//! The walk of one slab of planes: the stretches of a lattice's rays between two planes of
//! constant z, counted with the bricked walk from a window of the cell map
//! ([`BinSampler::window`]), bands of rows of rays in parallel (a slab that is one brick of whole
//! planes, as the sweeps and the parts make it, walked as one stretch a ray found by arithmetic,
//! and a lattice of voxel rows along x or y by the columns' walk), and stitched at once, band by
//! band, to the pieces of rays that the slabs walked before it left open ([`OpenRays`]). A slab
//! walked with nothing open is counted apart: its part and its open pieces
//! ([`OpenRays::into_fragments`]) add to its neighbours' in any order ([`PartialCounts::of`]).

use rayon::prelude::*;

use super::bricks::{BrickWalk, CommonState, at, common_walk};
use super::columns::slab_rows;
use super::grid::Bricks;
use super::tiles::{RayStart, Walker, advance, by_bucket, sample_bin};
use super::{BinSampler, RaySubset, serial_len};
use crate::geometry::lattice::Lattice;
use crate::measure::{Fragment, PartialCounts, key_ray};
use crate::volume::Voxel;

/// Rows of rays a slab's walk sets up at a time: what it holds per ray is bounded by a band.
pub(crate) const SLAB_ROWS: u64 = 16;

/// The bands of rows of `lattice`'s rays a slab's walk takes one at a time.
fn bands(lattice: &Lattice) -> Vec<(i64, i64)> {
    let (_, (j0, j1)) = lattice.ray_ranges();
    (j0..=j1)
        .step_by(SLAB_ROWS as usize)
        .map(|j| (j, (j + SLAB_ROWS as i64 - 1).min(j1)))
        .collect()
}

/// The pieces of one lattice's rays a sweep over its slabs holds open between slabs, kept by
/// band of rows: a slab's pieces are stitched to their band's at once, so the sweep never
/// holds more than the open pieces and one band's new ones per thread, and never sorts more
/// than a band's.
#[derive(Debug)]
pub struct OpenRays {
    bands: Vec<(i64, i64)>,
    open: Vec<Vec<Fragment>>,
}

impl OpenRays {
    /// No ray open, for a sweep along `lattice`.
    #[must_use]
    pub fn new(lattice: &Lattice) -> Self {
        let bands = bands(lattice);
        let open = vec![Vec::new(); bands.len()];
        Self { bands, open }
    }

    /// How many pieces of rays are open.
    #[must_use]
    pub fn len(&self) -> usize {
        self.open.iter().map(Vec::len).sum()
    }

    /// Whether every ray met is counted whole.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.open.iter().all(Vec::is_empty)
    }

    /// The open pieces, to add to other parts' ([`PartialCounts::of`]).
    #[must_use]
    pub fn into_fragments(self) -> Vec<Fragment> {
        let mut out = Vec::with_capacity(self.len());
        for band in self.open {
            out.extend(band);
        }
        out
    }
}

/// The block counts of the stretches of `lattice`'s rays (those `subset` keeps) in the slab of
/// `bricks` whose cells along z are `planes` (a whole number of bricks thick), its pieces of rays
/// stitched at once to those `open` holds (the pieces of the slabs walked before it): what the
/// stretches and the stitching determine is counted in the part returned (which holds no
/// fragment), and what stays open is left in `open`. After a sweep of every slab, in any order,
/// the parts added are [`block_counts`](super::block_counts)'s counts bit for bit and `open`
/// is empty. The sampler need hold the cell map of the slab's planes alone
/// ([`BinSampler::window`]); only the rays that can meet the slab are set up.
pub fn count_slab_into<T: Voxel>(
    sampler: &BinSampler<T>,
    lattice: &Lattice,
    block: usize,
    bricks: Bricks,
    (planes, subset): (std::ops::Range<i64>, RaySubset),
    open: &mut OpenRays,
) -> PartialCounts {
    let one = [(lattice, subset)];
    let mut parts = count_slabs_into(sampler, &one, block, (bricks, planes), &mut [open]);
    parts.pop().expect("one lattice's part")
}

/// [`count_slab_into`] of several lattices at once, each with its open pieces in `opens`, a
/// part each: an axis's shifted phases (each walking one block of rays in 12, phase n's blocks
/// beside phase n + 1's, their bands of one index over about the same rows), with or without
/// its paper lattice, walked band by band, each band's rays of every lattice in turn, so that
/// the cache lines one lattice's rays read are still near for its neighbours'. Counts are sums: the parts are each lattice's alone.
pub fn count_slabs_into<T: Voxel>(
    sampler: &BinSampler<T>,
    lattices: &[(&Lattice, RaySubset)],
    block: usize,
    (bricks, planes): (Bricks, std::ops::Range<i64>),
    opens: &mut [&mut OpenRays],
) -> Vec<PartialCounts> {
    assert_eq!(lattices.len(), opens.len(), "open pieces for each lattice");
    let empty = || PartialCounts::new(sampler.bins(), block);
    let walks: Vec<BrickWalk<T>> = (lattices.iter())
        .map(|&(l, s)| BrickWalk::of_slab(sampler, l, block, bricks, (planes.clone(), s)))
        .collect();
    // Rays along x or y lie in voxel planes, each whole in one slab: voxel rows.
    let rows_of = |k: usize| {
        let (lattice, subset) = lattices[k];
        match lattice.columns() {
            Some(axis @ (0 | 1)) if walks[k].whole_slab() && subset == RaySubset::ALL => {
                let z = planes.start.max(0) as usize..planes.end.max(0) as usize;
                Some(slab_rows(sampler, axis, z, block))
            }
            _ => None,
        }
    };
    let mut parts: Vec<Option<PartialCounts>> = (0..lattices.len()).map(rows_of).collect();
    let orders: Vec<Vec<usize>> = walks.iter().map(BrickWalk::order).collect();
    // Each band's open pieces of every lattice walked by the band.
    let mut bands: Vec<Vec<BandOf>> = Vec::new();
    for (k, open) in opens.iter_mut().enumerate() {
        if parts[k].is_some() {
            continue;
        }
        for (b, (&js, held)) in open.bands.iter().zip(&mut open.open).enumerate() {
            if bands.len() <= b {
                bands.push(Vec::with_capacity(lattices.len()));
            }
            bands[b].push((k, js, held));
        }
    }
    let outs = || lattices.iter().map(|_| empty()).collect::<Vec<_>>();
    let [nx, ny, _] = sampler.dims();
    let voxels = (planes.end - planes.start).max(0) as usize * nx * ny;
    let min_len = serial_len(voxels, bands.len());
    let walked = bands
        .into_par_iter()
        .with_min_len(min_len)
        .fold(
            || (outs(), Scratch::default()),
            |(mut outs, mut scratch), band| {
                for (k, js, held) in band {
                    let (walk, out) = (&walks[k], &mut outs[k]);
                    if walk.whole_slab() {
                        whole_band(walk, js, out, &mut scratch);
                    } else {
                        let mut band = walk.band(js, out);
                        walk.walk(&mut band, &orders[k], out);
                    }
                    out.stitch_into(held);
                }
                (outs, scratch)
            },
        )
        .map(|(outs, _)| outs)
        .reduce_with(|mut a, b| {
            for (a, b) in a.iter_mut().zip(b) {
                a.add(b);
            }
            a
        })
        .unwrap_or_else(outs);
    parts
        .iter_mut()
        .zip(walked)
        .map(|(rows, walked)| rows.take().unwrap_or(walked))
        .collect()
}

/// A band of one lattice's rays a slab's walk takes: the lattice's index, the band's rows, and
/// the band's open pieces.
type BandOf<'a> = (usize, (i64, i64), &'a mut Vec<Fragment>);

/// A ray's stretch in a slab walked whole: its open piece, and where its walk stands.
struct Stretch {
    f: Fragment,
    p: [i64; 3],
    t: i64,
    tb: i64,
    t1: i64,
    n: i64,
    grid: bool,
}

/// What a thread's walk of whole slabs keeps from band to band: room for a band's stretches and
/// walkers, and the common walk's chunks, allocated once (fresh vectors of a band's size took
/// page faults and copies).
#[derive(Default)]
struct Scratch {
    stretches: Vec<Stretch>,
    walkers: Vec<Walker>,
    sorted: Vec<Walker>,
    tally: Vec<usize>,
    common: CommonState,
}

/// The rays of rows `js` through a slab whose planes are walked whole (one brick): each ray's
/// samples inside cells there are one stretch, found by arithmetic ([`BrickWalk::slab_stretch`])
/// rather than brick by brick, and the stretches walked together, as the bricked walk walks a
/// brick's. The same pieces, counted and left open alike, as the bricked walk's.
fn whole_band<T: Voxel>(
    walk: &BrickWalk<T>,
    js: (i64, i64),
    out: &mut PartialCounts,
    scratch: &mut Scratch,
) {
    let (sampler, step) = (walk.sampler, walk.step);
    let Scratch {
        stretches,
        walkers,
        sorted,
        tally,
        common,
    } = scratch;
    stretches.clear();
    walkers.clear();
    walk.rays(js, out, |key, start, out| {
        let RayStart { p, grid, n, t0, t1 } = start;
        let (ta, tb) = walk.slab_stretch(p, (t0, t1));
        if ta >= tb {
            return;
        }
        let mut f = Fragment::new(key, if ta == t0 { 0 } else { ta as u64 });
        if f.first() {
            out.rays += 1;
            // The samples before the inner span.
            walk.feed(&mut f, &mut out.counts, p, grid, t0);
        }
        let p = at(p, step, ta);
        // Its head is read once the band is set up: by then its cell has arrived.
        sampler.prefetch_cell(sampler.inner_cell(p));
        stretches.push(Stretch {
            f,
            p,
            t: ta,
            tb,
            t1,
            n,
            grid,
        });
    });
    heads(walk, stretches, walkers, out);
    // In the tile walk's order: a stretch runs from face to face of the slab (or of the volume
    // where it leaves it first), so neighbouring rays' stretches have like lengths, and walked
    // together they share the cache lines they read. (Longest first, as the bricked walk takes
    // a brick's, a group's eight rays came from all over the band: on the 512³ body held as
    // f32, 35% more CPU for a slab of the whole volume and 11% for slabs of 64 planes; as i16,
    // whose map is half the size, the same within the noise.)
    let tiles = walk.tile_order();
    by_bucket(walkers, sorted, tally, |w| {
        tiles.tile_of(key_ray(stretches[w.id].f.key))
    });
    common_walk(sorted, (step, sampler), &mut out.counts, common);
    for w in sorted.iter() {
        let s = &mut stretches[w.id];
        s.p = w.p;
        s.t += w.inner;
        s.f.walked(w.inner as u64, w.run);
    }
    // In order of key, as the rays were set up: never sorted again.
    out.reserve_fragments(stretches.len());
    for s in stretches.drain(..) {
        let (mut f, last) = (s.f, s.t == s.t1);
        if last {
            // The samples after the inner span, where the ray ends in this slab.
            walk.feed(&mut f, &mut out.counts, s.p, s.grid, s.n - s.t1);
        }
        let left = f.close(&mut out.counts, last);
        out.push_fragment(left);
    }
}

/// The heads of `stretches` (the samples of a piece that does not start its ray, up to L − 1,
/// one at a time), and a walker for what each has left, into `walkers`.
fn heads<T: Voxel>(
    walk: &BrickWalk<T>,
    stretches: &mut [Stretch],
    walkers: &mut Vec<Walker>,
    out: &mut PartialCounts,
) {
    let (sampler, step, block) = (walk.sampler, walk.step, walk.block);
    for (id, s) in stretches.iter_mut().enumerate() {
        while s.t < s.tb && s.f.in_head(block) {
            s.f.push(&mut out.counts, sample_bin(sampler, s.p, s.grid));
            advance(&mut s.p, step);
            s.t += 1;
        }
        if s.t < s.tb {
            walkers.push(Walker {
                p: s.p,
                run: s.f.run(),
                inner: s.tb - s.t,
                grid: s.grid,
                id,
                ..Walker::idle()
            });
        }
    }
}
