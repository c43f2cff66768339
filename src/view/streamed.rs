//! The view search of a volume whose cell map does not fit in memory, at full resolution: the
//! volume is counted a slab of planes at a time, each slab's cell map made, walked along every
//! lattice and dropped, and each lattice's counts added slab after slab ([`PartialCounts`]), so
//! that the result is [`search`](super::search)'s, bit for bit, in a fraction of its memory.
//!
//! The voxels are read where they are (a mapped file, or held); what is held is one slab's cell
//! map (a byte a voxel of the slab, two for f32), per lattice counted in the same sweep its
//! tables and the pieces of its rays open at the slab's face ([`OpenRays`], stitched band by
//! band as each slab is walked), and per thread the band of rays it is walking. The lattices
//! are counted in as few sweeps as that memory allows: the paper's lattices of every axis first,
//! with the shifted ones whose rays can be guessed before the paper's samples are counted, then
//! the other shifted ones, whose rays depend on what the paper's counted (see `subset`).

use std::ops::Range;

use rayon::prelude::*;

use super::rate::{
    AxisEntropy, BinSampler, Bricks, OpenRays, RaySubset, count_slabs_into, window_bytes,
};
use super::refine::refine_in_lockstep;
use super::resolve;
use super::shifted_lattices;
use super::{ViewParams, ViewSearch, candidate_axes, canonical_axis, concluded, finish};
use super::{by_axis, guess_holds, paper_and_guessed, ranked, refine_evaluations};
use crate::error::{Error, Result};
use crate::geometry::lattice::Lattice;
use crate::measure::{BlockCounts, Fragment, PartialCounts};
use crate::progress::Monitor;
use crate::view::rate::SLAB_ROWS;
use crate::volume::{Quantizer, Volume, Voxel, VoxelType};

/// About what a ray being set up for a slab's walk holds, bytes.
const SLOT_BYTES: u64 = 160;

/// The least memory [`search_streamed`] works in for `volume` (bytes): the cell map of a slab
/// one plane thick, and the counts of one lattice.
#[must_use]
pub fn streamed_memory_floor(volume: &Volume, params: &ViewParams) -> u64 {
    let dims = volume.dims();
    // Two planes of two bytes a voxel, and a lattice along z (the most rays crossing a plane).
    let s = crate::geometry::min_spacing(volume.spacing());
    let ray = params.sampling.ray_spacing.unwrap_or(s);
    let z = Lattice::new(dims, volume.spacing(), [0.0, 0.0, 1.0], ray, s, [0.0; 3]);
    let threads = rayon::current_num_threads() as u64;
    let job = z.map_or(u64::MAX, |l| {
        job_bytes(dims, &l, params, 1).saturating_add(threads * band_bytes(&l, params))
    });
    (4 * (dims[0] * dims[1]) as u64).saturating_add(job)
}

/// [`search`](super::search)'s result, counted a slab of planes at a time within about `room`
/// bytes (at least [`streamed_memory_floor`]): the same numbers, bit for bit, the axis
/// refinement's among them (its seeds' pattern searches in lockstep, a round of sweeps a step).
pub fn search_streamed(
    volume: &Volume,
    params: &ViewParams,
    room: u64,
    monitor: &Monitor,
) -> Result<ViewSearch> {
    let params = resolve(volume, params)?;
    let q = volume.quantizer(params.sampling.bins)?;
    let axes = candidate_axes(params.level)?;
    crate::volume::with_voxels!(volume.data(), |data| {
        let sweeps = Sweeps {
            data,
            volume,
            q,
            params: &params,
            room,
        };
        sweeps.search(&axes, monitor)
    })
}

/// The block counts of every ray of `lattice` in blocks of `block` by `params`' bins, and the
/// rays that met the volume: [`block_counts`](super::block_counts)'s, bit for bit, counted a
/// slab of planes at a time within about `room` bytes (at least [`streamed_memory_floor`]);
/// one progress unit a slab.
pub fn block_counts_streamed(
    volume: &Volume,
    lattice: &Lattice,
    params: &ViewParams,
    block: usize,
    room: u64,
    monitor: &Monitor,
) -> Result<(BlockCounts, u64)> {
    let params = ViewParams {
        block,
        ..resolve(volume, params)?
    };
    let q = volume.quantizer(params.sampling.bins)?;
    crate::volume::with_voxels!(volume.data(), |data| {
        let sweeps = Sweeps {
            data,
            volume,
            q,
            params: &params,
            room,
        };
        let slabs = sweeps.slabs();
        let lattices = vec![(lattice.clone(), RaySubset::ALL)];
        let mut counts = sweeps.counts(lattices, slabs, monitor)?;
        let counts = counts.pop().expect("one lattice counted");
        Ok((counts.counts, counts.rays))
    })
}

/// The slabs a sweep of [`block_counts_streamed`] reads `volume` in, within `room` bytes: one
/// progress unit each.
#[must_use]
pub fn streamed_slabs(volume: &Volume, room: u64) -> u64 {
    crate::volume::with_voxels!(volume.data(), |data| slab_count(data, volume.dims(), room))
}

/// One lattice counted slab by slab.
struct Job {
    lattice: Lattice,
    subset: RaySubset,
    counts: PartialCounts,
    open: OpenRays,
}

/// What every sweep over the volume shares.
struct Sweeps<'a, T> {
    data: &'a [T],
    volume: &'a Volume,
    q: Quantizer,
    params: &'a ViewParams,
    room: u64,
}

impl<T: Voxel> Sweeps<'_, T> {
    fn search(&self, axes: &[[f64; 3]], monitor: &Monitor) -> Result<ViewSearch> {
        let (volume, params) = (self.volume, self.params);
        let slabs = self.slabs();
        let sweep = planes(volume.dims(), slabs.1).count() as u64;
        let phases = params.phases.max(1) as u64;
        monitor.start("view search", axes.len() as u64 * phases * sweep);
        let views = ranked(self.evaluate(axes, slabs, monitor)?, params.block)?;
        let refined = if params.refine {
            let evaluations = refine_evaluations(params.level);
            monitor.start("refining", evaluations * phases * sweep);
            Some(refine_in_lockstep(params.level, &views, |axes| {
                let axes = axes
                    .iter()
                    .map(|&a| canonical_axis(a))
                    .collect::<Result<Vec<_>>>()?;
                self.evaluate(&axes, slabs, monitor)
            })?)
        } else {
            None
        };
        Ok(concluded(views, params.clone(), refined))
    }

    /// The entropy rates of `axes` (canonical), as `Evaluator::evaluate` gives each: its
    /// paper's lattice counted in one round of sweeps, with its shifted lattices where their
    /// rays can be guessed before the paper's samples are counted ([`guessed_shifted`](super::guessed_shifted)), the
    /// others (and those the count proves guessed wrong) in a second round.
    fn evaluate(
        &self,
        axes: &[[f64; 3]],
        slabs: (Bricks, usize),
        monitor: &Monitor,
    ) -> Result<Vec<AxisEntropy>> {
        let (volume, params) = (self.volume, self.params);
        let sweep = planes(volume.dims(), slabs.1).count() as u64;
        let (owners, first): (Vec<usize>, Vec<_>) = paper_and_guessed(volume, params, axes)?
            .into_iter()
            .map(|(a, l, s)| (a, (l, s)))
            .unzip();
        let counted = self.count(first, slabs, monitor)?;
        let (paper, mut of_axis) = by_axis(owners.into_iter().zip(counted));
        let (mut owners, mut shifted) = (Vec::new(), Vec::new());
        for (a, (&axis, paper)) in axes.iter().zip(&paper).enumerate() {
            if !of_axis[a].is_empty() && guess_holds(params, paper.samples) {
                continue;
            }
            of_axis[a].clear();
            for (lattice, subset) in shifted_lattices(volume, params, axis, paper.samples)? {
                match subset {
                    Some(subset) => {
                        owners.push(a);
                        shifted.push((lattice, subset));
                    }
                    None => monitor.advance(sweep)?,
                }
            }
        }
        for (a, r) in owners.into_iter().zip(self.count(shifted, slabs, monitor)?) {
            of_axis[a].push(r);
        }
        Ok(axes
            .iter()
            .zip(paper)
            .zip(&of_axis)
            .map(|((&axis, paper), shifted)| finish(volume, params, axis, paper, shifted))
            .collect())
    }

    /// The entropy rates of `lattices` (each with the rays it walks), as [`Self::counts`]
    /// counts them.
    fn count(
        &self,
        lattices: Vec<(Lattice, RaySubset)>,
        slabs: (Bricks, usize),
        monitor: &Monitor,
    ) -> Result<Vec<AxisEntropy>> {
        let axes: Vec<[f64; 3]> = lattices.iter().map(|(l, _)| l.d).collect();
        let counts = self.counts(lattices, slabs, monitor)?;
        Ok(axes
            .iter()
            .zip(counts)
            .map(|(&d, c)| AxisEntropy::new(d, &c.counts, c.rays))
            .collect())
    }

    /// The block counts of `lattices` (each with the rays it walks), in as few sweeps over the
    /// volume's slabs as the room allows; one progress unit a lattice and slab.
    fn counts(
        &self,
        lattices: Vec<(Lattice, RaySubset)>,
        (bricks, slab): (Bricks, usize),
        monitor: &Monitor,
    ) -> Result<Vec<PartialCounts>> {
        let dims = self.volume.dims();
        let window = window_bytes(T::TYPE, dims, slab + 1);
        // Each thread walks one band of one lattice's rays at a time.
        let widest = lattices
            .iter()
            .map(|(l, _)| band_bytes(l, self.params))
            .max()
            .unwrap_or(0)
            + together_bytes(lattices.iter().map(|(l, _)| l.d), self.params);
        let threads = rayon::current_num_threads() as u64;
        let room = self
            .room
            .saturating_sub(window)
            .saturating_sub(threads * widest);
        let (bins, block) = (self.params.sampling.bins, self.params.block);
        let mut out = Vec::with_capacity(lattices.len());
        let mut jobs: Vec<Job> = Vec::new();
        let mut held = 0;
        let mut lattices = lattices.into_iter().peekable();
        while let Some((lattice, subset)) = lattices.next() {
            let bytes = job_bytes(dims, &lattice, self.params, subset.every);
            held += bytes;
            jobs.push(Job {
                open: OpenRays::new(&lattice),
                lattice,
                subset,
                counts: PartialCounts::new(bins, block),
            });
            let next = lattices
                .peek()
                .map_or(u64::MAX, |(l, s)| job_bytes(dims, l, self.params, s.every));
            if held.saturating_add(next) > room {
                out.extend(self.sweep(std::mem::take(&mut jobs), (bricks, slab), monitor)?);
                held = 0;
            }
        }
        Ok(out)
    }

    /// One sweep over the slabs counting `jobs`, and their counts, every ray joined whole.
    fn sweep(
        &self,
        mut jobs: Vec<Job>,
        (bricks, slab): (Bricks, usize),
        monitor: &Monitor,
    ) -> Result<Vec<PartialCounts>> {
        let block = self.params.block;
        for planes in planes(self.volume.dims(), slab) {
            let sampler = BinSampler::window(self.data, self.volume, self.q, planes.clone());
            let z = planes.start as i64..planes.end as i64;
            // An axis's lattices (its shifted phases) walked together.
            let axes: Vec<&mut [Job]> = jobs
                .chunk_by_mut(|a, b| a.lattice.d == b.lattice.d)
                .collect();
            axes.into_par_iter().try_for_each(|axis| {
                let (mut kept, mut opens, mut counts) = (Vec::new(), Vec::new(), Vec::new());
                for job in axis.iter_mut() {
                    kept.push((&job.lattice, job.subset));
                    opens.push(&mut job.open);
                    counts.push(&mut job.counts);
                }
                let parts =
                    count_slabs_into(&sampler, &kept, block, (bricks, z.clone()), &mut opens);
                for (counts, part) in counts.into_iter().zip(parts) {
                    counts.add(part);
                }
                monitor.advance(kept.len() as u64)
            })?;
        }
        jobs.into_iter()
            .map(|job| {
                if !job.open.is_empty() {
                    return Err(Error::Degenerate(format!(
                        "the slab walk left {} pieces of rays unjoined",
                        job.open.len()
                    )));
                }
                Ok(job.counts)
            })
            .collect()
    }

    /// The bricks of the sweeps, and the planes of cells a slab holds (a whole number of
    /// bricks but the last), as many as a quarter of the room allows.
    fn slabs(&self) -> (Bricks, usize) {
        let dims = self.volume.dims();
        let planes = slab_planes::<T>(dims, self.room);
        // A slab is one brick: its rays' stretches run from face to face of the slab, long
        // enough that the walk's cost per stretch fades (bricks of 64³ cells cost twice the tile
        // walk for it), and its map stays in the last-level cache.
        (Bricks::shaped(dims, [dims[0], dims[1], planes]), planes)
    }
}

/// About the bytes counting `lattices` in a slab of `planes` planes of cells of a volume of
/// `dims` voxels held as `voxel_type` holds beyond its voxels, as
/// [`ViewRounds::count_slab`](super::ViewRounds::count_slab) counts them with `threads`
/// threads: the window of the cell map over the slab; each lattice's tables and the pieces of
/// its rays open at the slab's two faces, all held until the part is whole; and each thread's
/// band of rays being walked.
pub(super) fn slab_part_bytes(
    (dims, voxel_type): ([usize; 3], VoxelType),
    params: &ViewParams,
    lattices: &[(usize, Lattice, RaySubset)],
    (planes, threads): (usize, usize),
) -> u64 {
    let window = window_bytes(voxel_type, dims, planes);
    let tables = table_bytes(params);
    let held = lattices.iter().fold(0u64, |sum, (_, lattice, subset)| {
        let open = 2 * crossing(dims, lattice, subset.every) * FRAGMENT;
        sum.saturating_add(tables + open)
    });
    let band = (lattices.iter())
        .map(|(_, lattice, _)| band_bytes(lattice, params))
        .max()
        .unwrap_or(0)
        + together_bytes(lattices.iter().map(|(_, l, _)| l.d), params);
    window
        .saturating_add(held)
        .saturating_add((threads as u64).saturating_mul(band))
}

/// The planes of cells a slab of a sweep within `room` bytes holds: as many as a quarter of the
/// room allows.
fn slab_planes<T: Voxel>(dims: [usize; 3], room: u64) -> usize {
    let cells = dims[2].saturating_sub(1).max(1);
    let per_plane = window_bytes(T::TYPE, dims, 1).max(1);
    let affordable = ((room / 4) / per_plane).saturating_sub(1).max(1) as usize;
    affordable.min(cells)
}

/// The slabs of a sweep over `data`'s volume of `dims` within `room` bytes.
fn slab_count<T: Voxel>(_data: &[T], dims: [usize; 3], room: u64) -> u64 {
    planes(dims, slab_planes::<T>(dims, room)).count() as u64
}

/// The planes of cells of each slab of `slab` planes, in order along z.
fn planes(dims: [usize; 3], slab: usize) -> impl Iterator<Item = Range<usize>> {
    let cells = dims[2].saturating_sub(1).max(1);
    (0..cells)
        .step_by(slab.max(1))
        .map(move |z| z..(z + slab).min(cells))
}

/// The bytes of one lattice's block tables (266 KiB at 32 bins and blocks of 3; the estimate
/// here before, 32 bytes a possible code, was four times that).
fn table_bytes(params: &ViewParams) -> u64 {
    BlockCounts::held_bytes(params.sampling.bins, params.block)
}

/// The bytes one lattice counted in a sweep over a volume of `dims` holds between slabs: its
/// tables, and an open piece for each ray crossing a plane of constant z.
fn job_bytes(dims: [usize; 3], lattice: &Lattice, params: &ViewParams, every: u64) -> u64 {
    table_bytes(params) + crossing(dims, lattice, every) * FRAGMENT
}

/// The bytes a thread holds while it walks one band of `lattice`'s rays through a slab: the
/// rays being set up, the pieces they leave and their stitching to the band's open ones (at
/// most three pieces a ray while both lists and the stitched one are held), and the tables it
/// counts into.
fn band_bytes(lattice: &Lattice, params: &ViewParams) -> u64 {
    let ((i0, i1), _) = lattice.ray_ranges();
    let rays = SLAB_ROWS * (i1 - i0 + 1).max(1) as u64;
    rays * (SLOT_BYTES + 3 * FRAGMENT) + 2 * table_bytes(params)
}

/// What a thread walking an axis's lattices together ([`count_slabs_into`]) holds beyond one
/// lattice's band ([`band_bytes`]): the tables of the others, for the longest run of lattices
/// along one axis among those of `directions`.
fn together_bytes(directions: impl Iterator<Item = [f64; 3]>, params: &ViewParams) -> u64 {
    let (mut longest, mut run, mut last) = (0u64, 0u64, None);
    for d in directions {
        run = if last == Some(d) { run + 1 } else { 1 };
        (longest, last) = (longest.max(run), Some(d));
    }
    longest.saturating_sub(1) * 2 * table_bytes(params)
}

const FRAGMENT: u64 = std::mem::size_of::<Fragment>() as u64;

/// An upper bound on the rays of `lattice` (one in `every`, as a subset keeps them) that cross
/// a plane of constant z of a volume of `dims`: the plane's rectangle seen along the axis, and
/// the rays on its outline.
fn crossing(dims: [usize; 3], lattice: &Lattice, every: u64) -> u64 {
    let spacing = lattice.spacing();
    let [ex, ey] = [0, 1].map(|m| dims[m].saturating_sub(1) as f64 * spacing[m]);
    let rs = lattice.ray_spacing;
    let crossing = ex * ey * lattice.d[2].abs() / (rs * rs) + 2.0 * (ex + ey) / rs + 4.0;
    (crossing / every.max(1) as f64 + 16.0 * (ex + ey) / rs) as u64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::view::evaluator::tests::evaluated_apart;
    use crate::view::rate::tests::{awkward_volume_of as awkward_volume, holed_below};
    use crate::volume::VoxelType;

    #[test]
    fn the_streamed_search_is_the_search_bit_for_bit() {
        let none = Monitor::none();
        let mut sweeps = 0;
        for (dims, spacing, voxel_type) in [
            ([30, 26, 41], [1.0, 1.0, 1.0], VoxelType::U8),
            ([28, 20, 33], [0.8, 0.8, 1.7], VoxelType::F32),
            ([24, 31, 19], [1.0, 1.2, 1.0], VoxelType::I16),
        ] {
            let v = awkward_volume(dims, spacing, voxel_type, 4);
            for params in [ViewParams::paper(), ViewParams::default()] {
                let expect =
                    serde_json::to_string(&super::super::search(&v, &params, &none).unwrap())
                        .unwrap();
                // From one slab and one sweep to slabs of a plane, a lattice a sweep.
                for room in [u64::MAX, 400_000, 1] {
                    let got = search_streamed(&v, &params, room, &none).unwrap();
                    assert_eq!(
                        serde_json::to_string(&got).unwrap(),
                        expect,
                        "{dims:?} {room}"
                    );
                    sweeps += 1;
                }
            }
        }
        assert_eq!(sweeps, 18);
    }

    /// With few bins a small volume's shifted lattices walk one block of rays in 12, guessed
    /// before the paper's samples are counted and swept with the paper's lattices; a slab of
    /// NaN proves the guess wrong and they are swept again: the search's result either way.
    #[test]
    fn the_phases_swept_with_the_paper_lattices_are_the_search() {
        let none = Monitor::none();
        let mut params = ViewParams::default();
        params.sampling.bins = 4;
        let v = awkward_volume([32, 32, 32], [1.0, 0.9, 1.3], VoxelType::I16, 5);
        for volume in [&v, &holed_below(&v, 20)] {
            let expect = super::super::search(volume, &params, &none).unwrap();
            for view in &expect.views {
                assert_eq!(view, &evaluated_apart(volume, &params, view.axis));
            }
            let expect = serde_json::to_string(&expect).unwrap();
            for room in [u64::MAX, 1] {
                let got = search_streamed(volume, &params, room, &none).unwrap();
                assert_eq!(serde_json::to_string(&got).unwrap(), expect, "{room}");
            }
        }
    }

    #[test]
    fn the_refinement_counted_slab_by_slab_is_the_refinement_in_memory() {
        let none = Monitor::none();
        let mut moved = 0;
        for (dims, spacing, voxel_type) in [
            ([22, 19, 27], [1.0, 1.0, 1.0], VoxelType::U8),
            ([18, 21, 16], [0.9, 0.9, 1.6], VoxelType::F32),
        ] {
            let v = awkward_volume(dims, spacing, voxel_type, 4);
            for phases in [0, 2] {
                let params = ViewParams {
                    refine: true,
                    phases,
                    ..ViewParams::default()
                };
                let expect = super::super::search(&v, &params, &none).unwrap();
                moved += usize::from(expect.refined.as_ref().unwrap().axis != expect.views[0].axis);
                let expect = serde_json::to_string(&expect).unwrap();
                for room in [u64::MAX, 1] {
                    let got = search_streamed(&v, &params, room, &none).unwrap();
                    assert_eq!(serde_json::to_string(&got).unwrap(), expect, "{dims:?}");
                }
            }
        }
        // The refinement went somewhere off the sphere's vertices, so its steps were compared.
        assert!(moved > 0);
    }

    #[test]
    fn a_cancel_stops_the_sweeps() {
        let v = awkward_volume([20, 20, 20], [1.0; 3], VoxelType::U8, 4);
        let cancel = std::sync::atomic::AtomicBool::new(true);
        let monitor = Monitor::new(Some(&cancel), None);
        let e = search_streamed(&v, &ViewParams::default(), 1, &monitor).unwrap_err();
        assert!(matches!(e, Error::Cancelled), "{e}");
    }

    #[test]
    fn a_slabs_part_holds_no_more_than_its_task_weighs() {
        use crate::view::{ViewRound, ViewRounds};
        for (dims, voxel_type) in [
            ([30, 26, 41], VoxelType::U8),
            ([28, 20, 33], VoxelType::F32),
        ] {
            let v = awkward_volume(dims, [1.0, 1.0, 1.3], voxel_type, 4);
            let params = ViewParams::default();
            let rounds = ViewRounds::new(&v, &params).unwrap();
            let paper = rounds
                .count_slab(&v, &ViewRound::Paper, 0..dims[2] - 1)
                .unwrap();
            let shifted = ViewRound::Shifted(rounds.paper_samples(&v, &paper).unwrap());
            let params = rounds.params().clone();
            for round in [ViewRound::Paper, shifted] {
                for planes in [0..1, 3..12, 0..dims[2] - 1] {
                    let parts = rounds.count_slab(&v, &round, planes.clone()).unwrap();
                    let window = match voxel_type {
                        VoxelType::F32 => 2,
                        _ => 1,
                    } * (dims[0] * dims[1] * planes.len()) as u64;
                    let held = parts.iter().fold(window, |sum, p| {
                        sum + BlockCounts::held_bytes(params.sampling.bins, params.block)
                            + p.fragments().len() as u64 * FRAGMENT
                    });
                    let weighed = rounds
                        .slab_bytes(&v, &round, (&planes, 1), voxel_type)
                        .unwrap();
                    assert!(
                        held <= weighed,
                        "{planes:?}: {held} held, {weighed} weighed"
                    );
                    // A second thread weighs one more band of rays, less than the rest.
                    let two = rounds
                        .slab_bytes(&v, &round, (&planes, 2), voxel_type)
                        .unwrap();
                    assert!(weighed < two && two - weighed < weighed);
                }
            }
        }
    }
}
