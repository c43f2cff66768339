//! The walk of one slab of planes: the stretches of a lattice's rays between two planes of
//! constant z, counted with the bricked walk from a window of the cell map
//! ([`BinSampler::window`]), bands of rows of rays in parallel (a slab that is one brick of whole
//! planes, as the sweeps and the parts make it, walked as one stretch a ray found by arithmetic,
//! and a lattice of voxel rows along x or y by the columns' walk), and stitched at once, band by
//! band, to the pieces of rays that the slabs walked before it left open ([`OpenRays`]). A slab
//! walked with nothing open is counted apart: its part and its open pieces
//! ([`OpenRays::into_fragments`]) add to its neighbours' in any order ([`PartialCounts::of`]).

use rayon::prelude::*;

use super::bricks::{BrickWalk, at, common_walk};
use super::columns::slab_rows;
use super::grid::Bricks;
use super::tiles::{RayStart, Walker, advance, by_bucket, sample_bin};
use super::{BinSampler, RaySubset};
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
    let walk = BrickWalk::of_slab(sampler, lattice, block, bricks, (planes.clone(), subset));
    if walk.whole_slab()
        && subset == RaySubset::ALL
        && let Some(axis @ (0 | 1)) = lattice.columns()
    {
        // Rays along x or y lie in voxel planes, each whole in one slab: voxel rows.
        let z = planes.start.max(0) as usize..planes.end.max(0) as usize;
        return slab_rows(sampler, axis, z, block);
    }
    let order = walk.order();
    let empty = || PartialCounts::new(sampler.bins(), block);
    open.bands
        .par_iter()
        .zip(open.open.par_iter_mut())
        .fold(
            || (empty(), Scratch::default()),
            |(mut out, mut scratch), (&js, held)| {
                if walk.whole_slab() {
                    whole_band(&walk, js, &mut out, &mut scratch);
                } else {
                    let mut band = walk.band(js, &mut out);
                    walk.walk(&mut band, &order, &mut out);
                }
                out.stitch_into(held);
                (out, scratch)
            },
        )
        .map(|(out, _)| out)
        .reduce_with(|mut a, b| {
            a.add(b);
            a
        })
        .unwrap_or_else(empty)
}

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
/// walkers, allocated once (fresh vectors of a band's size took page faults and copies).
#[derive(Default)]
struct Scratch {
    stretches: Vec<Stretch>,
    walkers: Vec<Walker>,
    sorted: Vec<Walker>,
    tally: Vec<usize>,
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
    common_walk(sorted, step, sampler, &mut out.counts);
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
