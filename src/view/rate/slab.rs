//! The walk of one slab of planes: the stretches of a lattice's rays between two planes of
//! constant z, counted with the bricked walk from a window of the cell map
//! ([`BinSampler::window`]), bands of rows of rays in parallel, and stitched at once, band by
//! band, to the pieces of rays that the slabs walked before it left open ([`OpenRays`]). A slab
//! walked with nothing open is counted apart: its part and its open pieces
//! ([`OpenRays::into_fragments`]) add to its neighbours' in any order ([`PartialCounts::of`]).

use rayon::prelude::*;

use super::bricks::BrickWalk;
use super::grid::Bricks;
use super::{BinSampler, RaySubset};
use crate::geometry::lattice::Lattice;
use crate::measure::{Fragment, PartialCounts};
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
    let walk = BrickWalk::of_slab(sampler, lattice, block, bricks, (planes, subset));
    let order = walk.order();
    let empty = || PartialCounts::new(sampler.bins(), block);
    open.bands
        .par_iter()
        .zip(open.open.par_iter_mut())
        .fold(empty, |mut out, (&js, held)| {
            let mut band = walk.band(js, &mut out);
            walk.walk(&mut band, &order, &mut out);
            out.stitch_into(held);
            out
        })
        .reduce(empty, |mut a, b| {
            a.add(b);
            a
        })
}
