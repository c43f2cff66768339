//! The view search counted in parts that add (issue #44): each part the counts of one slab of
//! planes of cells along z, walked from the voxels of that slab and the plane above it alone,
//! as a cluster's tasks count them. The parts of one round, added in any grouping and order
//! ([`PartialCounts::add`]), are the whole volume's counts, and [`ViewRounds::finish`] makes of
//! them [`search`](super::search)'s result, bit for bit: the same walk as the slab-by-slab
//! search ([`search_streamed`](super::search_streamed)), with nothing open when a slab starts.
//!
//! Two rounds, as in the slab-by-slab search: the paper's lattice of every axis, then (with
//! phases) the shifted lattices, whose rays depend on the samples the paper's counted. Each
//! task is told the round (and, for the second, those sample counts), so the lattices are made
//! again where the task runs and nothing but numbers travels.

use std::ops::Range;

use rayon::prelude::*;

use super::rate::{AxisEntropy, BinSampler, Bricks, OpenRays, RaySubset, count_slab_into};
use super::{ViewParams, ViewSearch, candidate_axes, concluded, finish};
use super::{lattice_of, ranked, resolve, shifted_lattices};
use crate::error::{Error, Result};
use crate::geometry::lattice::Lattice;
use crate::measure::{BlockCounts, PartialCounts};
use crate::volume::Volume;

/// A round of a view search counted in parts.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ViewRound {
    /// The paper's lattice of every axis.
    Paper,
    /// The shifted lattices of every axis (phases 1 on), given the samples each axis's paper
    /// lattice counted (the first round's [`ViewRounds::paper_samples`]).
    Shifted(Vec<u64>),
}

/// The view search of one volume counted in parts: its parameters resolved and its axes, the
/// same wherever they are made from the same grid.
#[derive(Clone, Debug)]
pub struct ViewRounds {
    params: ViewParams,
    axes: Vec<[f64; 3]>,
    spacing_z: f64,
}

impl ViewRounds {
    /// The rounds of `params`' search of `volume` (the whole volume, or a slab of it made by
    /// [`Volume::of_slab`]: only its grid and statistics are read). The refinement is refused:
    /// it evaluates axes one after another, each from the last, and is not split yet.
    pub fn new(volume: &Volume, params: &ViewParams) -> Result<Self> {
        if params.refine {
            return Err(Error::invalid(
                "refine",
                true,
                "off for a view search counted in parts (the refinement is not split yet)",
            ));
        }
        let params = resolve(volume, params)?;
        let axes = candidate_axes(params.level)?;
        Ok(Self {
            params,
            axes,
            spacing_z: volume.spacing()[2],
        })
    }

    /// The parameters, resolved for the volume.
    #[must_use]
    pub fn params(&self) -> &ViewParams {
        &self.params
    }

    /// Whether a second round (the shifted lattices) follows the paper's.
    #[must_use]
    pub fn has_shifted(&self) -> bool {
        self.params.phases > 1
    }

    /// The voxel planes along z a task counting the cell planes `planes` of a volume `depth`
    /// voxels deep must hold: those planes and the one above, and as many more on each side as
    /// one sample step spans along z (a ray's first and last samples on the volume's far faces
    /// lie up to a step outside the slab whose cells it starts or ends in): one plane each side
    /// at the default sample spacing.
    #[must_use]
    pub fn voxel_planes(&self, planes: &Range<usize>, depth: usize) -> Range<usize> {
        let spacing = self.params.sampling.sample_spacing.unwrap_or(1.0);
        let margin = (spacing / self.spacing_z).ceil().max(1.0) as usize;
        planes.start.saturating_sub(margin)..(planes.end + 1 + margin).min(depth)
    }

    /// The lattices `round` counts, each with the index of its axis and the rays it walks.
    fn lattices(
        &self,
        volume: &Volume,
        round: &ViewRound,
    ) -> Result<Vec<(usize, Lattice, RaySubset)>> {
        let mut out = Vec::new();
        match round {
            ViewRound::Paper => {
                for (a, &axis) in self.axes.iter().enumerate() {
                    out.push((
                        a,
                        lattice_of(volume, &self.params, axis, 0)?,
                        RaySubset::ALL,
                    ));
                }
            }
            ViewRound::Shifted(samples) => {
                if samples.len() != self.axes.len() {
                    return Err(Error::invalid(
                        "paper samples",
                        samples.len(),
                        format!("one count for each of the {} axes", self.axes.len()),
                    ));
                }
                for (a, (&axis, &n)) in self.axes.iter().zip(samples).enumerate() {
                    for (lattice, subset) in shifted_lattices(volume, &self.params, axis, n)? {
                        if let Some(subset) = subset {
                            out.push((a, lattice, subset));
                        }
                    }
                }
            }
        }
        Ok(out)
    }

    /// The counts of `round`'s lattices in the slab of planes of cells `planes` along z (cell
    /// plane z lies between voxel planes z and z + 1), one [`PartialCounts`] a lattice, with
    /// the pieces of rays open at the slab's faces. `volume` need hold the voxel planes
    /// [`voxel_planes`](Self::voxel_planes) alone ([`Volume::of_slab`]). The slabs of a round must
    /// cover the cell planes `0..cells` (`cells` = depth − 1, 1 for a single plane) once.
    pub fn count_slab(
        &self,
        volume: &Volume,
        round: &ViewRound,
        planes: Range<usize>,
    ) -> Result<Vec<PartialCounts>> {
        let dims = volume.dims();
        let cells = dims[2].saturating_sub(1).max(1);
        if planes.is_empty() || planes.end > cells {
            return Err(Error::invalid(
                "slab",
                format!("cell planes {}..{}", planes.start, planes.end),
                format!("a non-empty range within 0..{cells}"),
            ));
        }
        // The slab one layer of bricks of whole planes, its boundaries on the slab's faces
        // wherever they fall (chunks of 37 and 38 planes give a brick each, not one a plane).
        let bricks = Bricks::shaped_from(dims, [dims[0], dims[1], planes.len()], planes.start);
        let (bins, block) = (self.params.sampling.bins, self.params.block);
        let lattices = self.lattices(volume, round)?;
        let q = volume.quantizer(bins)?;
        crate::volume::with_voxels!(volume.data(), |data| {
            let sampler = BinSampler::window(data, volume, q, planes.clone());
            let z = planes.start as i64..planes.end as i64;
            Ok(lattices
                .par_iter()
                .map(|(_, lattice, subset)| {
                    let mut open = OpenRays::new(lattice);
                    let part = count_slab_into(
                        &sampler,
                        lattice,
                        block,
                        bricks,
                        (z.clone(), *subset),
                        &mut open,
                    );
                    let mut out = PartialCounts::new(bins, block);
                    out.add(part);
                    out.add(PartialCounts::of(
                        crate::measure::BlockCounts::new(bins, block),
                        0,
                        open.into_fragments(),
                    ));
                    out
                })
                .collect())
        })
    }

    /// The empty counts of `round` (what parts are added to).
    pub fn zero(&self, volume: &Volume, round: &ViewRound) -> Result<Vec<PartialCounts>> {
        let (bins, block) = (self.params.sampling.bins, self.params.block);
        Ok(self
            .lattices(volume, round)?
            .iter()
            .map(|_| PartialCounts::new(bins, block))
            .collect())
    }

    /// The samples each axis's paper lattice counted, from the first round's counts added up:
    /// what [`ViewRound::Shifted`] needs.
    pub fn paper_samples(&self, volume: &Volume, paper: &[PartialCounts]) -> Result<Vec<u64>> {
        Ok(self
            .entropies(&self.paper_directions(volume, paper.len())?, paper)?
            .iter()
            .map(|r| r.samples)
            .collect())
    }

    /// The directions of the paper lattices, for a paper round of `n` counts.
    fn paper_directions(&self, volume: &Volume, n: usize) -> Result<Vec<[f64; 3]>> {
        if n != self.axes.len() {
            return Err(Error::invalid(
                "paper counts",
                n,
                format!("one for each of the {} axes", self.axes.len()),
            ));
        }
        Ok(self
            .lattices(volume, &ViewRound::Paper)?
            .into_iter()
            .map(|(_, l, _)| l.d)
            .collect())
    }

    /// The entropy rates of complete counts, one a lattice of direction `axes`.
    fn entropies(&self, axes: &[[f64; 3]], counts: &[PartialCounts]) -> Result<Vec<AxisEntropy>> {
        let expected = BlockCounts::new(self.params.sampling.bins, self.params.block);
        axes.iter()
            .zip(counts)
            .map(|(&d, c)| {
                if !c.counts.agrees(&expected) {
                    return Err(Error::Degenerate(
                        "parts counted with other bins or another block length than the search's"
                            .into(),
                    ));
                }
                if !c.is_complete() {
                    return Err(Error::Degenerate(format!(
                        "the parts left {} pieces of rays unjoined: a slab is missing",
                        c.fragments().len()
                    )));
                }
                Ok(AxisEntropy::new(d, &c.counts, c.rays))
            })
            .collect()
    }

    /// The view search of the whole volume from the rounds' counts added up: `paper` of the
    /// first round, `shifted` of the second (empty without phases), `search`'s result bit for
    /// bit. `volume` gives the grid (a slab of it will do).
    pub fn finish(
        &self,
        volume: &Volume,
        paper: &[PartialCounts],
        shifted: &[PartialCounts],
    ) -> Result<ViewSearch> {
        let paper = self.entropies(&self.paper_directions(volume, paper.len())?, paper)?;
        let axes = &self.axes;
        let mut of_axis = vec![Vec::new(); axes.len()];
        if self.has_shifted() {
            let round = ViewRound::Shifted(paper.iter().map(|r| r.samples).collect());
            let lattices = self.lattices(volume, &round)?;
            if lattices.len() != shifted.len() {
                return Err(Error::invalid(
                    "shifted counts",
                    shifted.len(),
                    format!("one for each of the {} shifted lattices", lattices.len()),
                ));
            }
            let directions: Vec<[f64; 3]> = lattices.iter().map(|(_, l, _)| l.d).collect();
            for ((a, _, _), r) in lattices.iter().zip(self.entropies(&directions, shifted)?) {
                of_axis[*a].push(r);
            }
        }
        let views = axes
            .iter()
            .zip(paper)
            .zip(&of_axis)
            .map(|((&axis, paper), shifted)| finish(volume, &self.params, axis, paper, shifted))
            .collect();
        Ok(concluded(
            ranked(views, self.params.block)?,
            self.params.clone(),
            None,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::Monitor;
    use crate::testing::Lcg;
    use crate::view::rate::tests::awkward_volume_of as awkward_volume;
    use crate::volume::{SlabGrid, VoxelType};

    /// Cell planes `0..cells` cut at random into slabs.
    pub(crate) fn random_slabs(cells: usize, lcg: &mut Lcg) -> Vec<Range<usize>> {
        let mut cuts = vec![0];
        while *cuts.last().unwrap() < cells {
            let last = *cuts.last().unwrap();
            let len = 1 + (lcg.next_u64() >> 33) as usize % 9;
            cuts.push((last + len).min(cells));
        }
        cuts.windows(2).map(|w| w[0]..w[1]).collect()
    }

    /// The volume holding only the voxel planes a slab of cell planes `planes` reads.
    pub(crate) fn slab_of(v: &Volume, rounds: &ViewRounds, planes: &Range<usize>) -> Volume {
        let [nx, ny, nz] = v.dims();
        let held = rounds.voxel_planes(planes, nz);
        crate::volume::with_voxels!(v.data(), |d| {
            Volume::of_slab(
                &SlabGrid::of(v),
                held.start,
                &d[held.start * nx * ny..held.end * nx * ny],
            )
        })
        .unwrap()
    }

    /// The parts of `round` over `slabs`, counted apart and added in a shuffled order.
    fn added(
        rounds: &ViewRounds,
        v: &Volume,
        round: &ViewRound,
        slabs: &[Range<usize>],
        lcg: &mut Lcg,
    ) -> Vec<PartialCounts> {
        let mut parts: Vec<_> = slabs
            .iter()
            .map(|p| {
                rounds
                    .count_slab(&slab_of(v, rounds, p), round, p.clone())
                    .unwrap()
            })
            .collect();
        for i in (1..parts.len()).rev() {
            parts.swap(i, (lcg.next_u64() >> 33) as usize % (i + 1));
        }
        let mut sum = rounds.zero(v, round).unwrap();
        for part in parts {
            // Each part travels as bytes, as between a cluster's processes.
            for (s, p) in sum.iter_mut().zip(part) {
                let bytes = p.to_bytes();
                let back = PartialCounts::from_bytes(&bytes).unwrap();
                assert_eq!(back.to_bytes(), bytes);
                for cut in [0, 7, 8, bytes.len() - 8] {
                    assert!(PartialCounts::from_bytes(&bytes[..cut]).is_err());
                }
                s.add(back);
            }
        }
        sum
    }

    #[test]
    fn parts_of_slabs_added_in_any_order_are_the_search_bit_for_bit() {
        let mut lcg = Lcg::new(44);
        for (dims, spacing, voxel_type) in [
            ([30, 26, 41], [1.0, 1.0, 1.0], VoxelType::U8),
            ([28, 20, 33], [0.8, 0.8, 1.7], VoxelType::F32),
            ([24, 31, 19], [1.0, 1.2, 1.0], VoxelType::I16),
        ] {
            let v = awkward_volume(dims, spacing, voxel_type, 4);
            for params in [ViewParams::paper(), ViewParams::default()] {
                let expect = super::super::search(&v, &params, &Monitor::none()).unwrap();
                let expect = serde_json::to_string(&expect).unwrap();
                let slabs = random_slabs(dims[2] - 1, &mut lcg);
                assert!(slabs.len() > 2);
                // Each slab's rounds made from its own volume, as a task makes them.
                let whole = ViewRounds::new(&v, &params).unwrap();
                let rounds = ViewRounds::new(&slab_of(&v, &whole, &slabs[1]), &params).unwrap();
                let paper = added(&rounds, &v, &ViewRound::Paper, &slabs, &mut lcg);
                let shifted = if rounds.has_shifted() {
                    let samples = rounds.paper_samples(&v, &paper).unwrap();
                    added(&rounds, &v, &ViewRound::Shifted(samples), &slabs, &mut lcg)
                } else {
                    Vec::new()
                };
                let got = rounds.finish(&v, &paper, &shifted).unwrap();
                assert_eq!(serde_json::to_string(&got).unwrap(), expect, "{dims:?}");
                // A slab left out is an error, not another answer.
                let short = added(&rounds, &v, &ViewRound::Paper, &slabs[1..], &mut lcg);
                let e = rounds.finish(&v, &short, &shifted).unwrap_err();
                assert!(e.to_string().contains("unjoined"), "{e}");
            }
        }
    }

    #[test]
    fn the_refinement_and_slabs_off_the_grid_are_refused() {
        let v = awkward_volume([20, 20, 20], [1.0; 3], VoxelType::U8, 4);
        let refine = ViewParams {
            refine: true,
            ..ViewParams::default()
        };
        let e = ViewRounds::new(&v, &refine).unwrap_err();
        assert!(e.to_string().contains("refine"), "{e}");
        let rounds = ViewRounds::new(&v, &ViewParams::paper()).unwrap();
        for planes in [5..5, 10..20] {
            let e = rounds
                .count_slab(&v, &ViewRound::Paper, planes)
                .unwrap_err();
            assert!(e.to_string().contains("0..19"), "{e}");
        }
    }

    /// Bytes that no writer made are refused, never read into counts that would overflow or
    /// tables whose codes repeat; parts of another binning are refused when they are added up.
    #[test]
    fn hostile_or_foreign_parts_are_refused() {
        let mut counts = BlockCounts::new(4, 3);
        let mut run = crate::measure::Run::default();
        for s in [0, 1, 2, 3, 0, 1] {
            crate::measure::Counter::push_to(&mut counts, &mut run, s);
        }
        let bytes = PartialCounts::of(counts, 1, Vec::new()).to_bytes();
        let words: Vec<u64> = bytes
            .chunks_exact(8)
            .map(|c| u64::from_le_bytes(c.try_into().unwrap()))
            .collect();
        // MAGIC, bins, block, then the long table: its length and (code, count) pairs.
        assert!(words[3] >= 2, "{words:?}");
        let with = |edit: &dyn Fn(&mut Vec<u64>)| {
            let mut w = words.clone();
            edit(&mut w);
            let b: Vec<u8> = w.iter().flat_map(|x| x.to_le_bytes()).collect();
            PartialCounts::from_bytes(&b).err().unwrap_or_default()
        };
        assert!(with(&|w| w[6] = w[4]).contains("out of order or repeated"));
        assert!(with(&|w| w[5] = u64::MAX).contains("more blocks than any volume holds"));
        let v = awkward_volume([12, 10, 9], [1.0; 3], VoxelType::U8, 4);
        let params = ViewParams {
            phases: 0,
            ..ViewParams::default()
        };
        let rounds = ViewRounds::new(&v, &params).unwrap();
        let paper = rounds.zero(&v, &ViewRound::Paper).unwrap();
        let foreign = vec![PartialCounts::new(8, 3); paper.len()];
        let e = rounds.finish(&v, &foreign, &[]);
        assert!(e.is_err_and(|e| e.to_string().contains("other bins")));
    }
}
