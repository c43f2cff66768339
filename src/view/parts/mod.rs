//! The view search counted in parts that add (issue #44): each part the counts of one slab of
//! planes of cells along z, walked from the voxels of that slab and the plane above it alone,
//! as a cluster's tasks count them. The parts of one round, added in any grouping and order
//! ([`PartialCounts::add`]), are the whole volume's counts, and [`ViewRounds::finish`] makes of
//! them [`search`](super::search)'s result, bit for bit: the same walk as the slab-by-slab
//! search ([`search_streamed`](super::search_streamed)), with nothing open when a slab starts.
//!
//! Two rounds, as in the slab-by-slab search: the paper's lattice of every axis, then (with
//! phases) the shifted lattices, whose rays depend on the samples the paper's counted. Where
//! they can be guessed from the volume's box ([`guessed_shifted`]), an axis's shifted lattices
//! are counted in the first round beside its paper lattice (walked together, reading the same
//! cells), and the second round counts only those of the axes whose guess could not be made or
//! the count proved wrong: on a large volume there is no second round
//! ([`ViewRounds::shifted_after`] says). Each task is told the round (and, for the second, the
//! paper lattices' sample counts), so the lattices are made again where the task runs and
//! nothing but numbers travels. The refinement ([`ViewRounds::refine`]) is more rounds of the
//! same two kinds, two a step of its pattern searches in lockstep (as the slab-by-slab search
//! takes them), of the axes each step asks for.

use std::ops::Range;

use rayon::prelude::*;

use super::rate::{AxisEntropy, BinSampler, Bricks, OpenRays, RaySubset, count_slabs_into};
use super::refine::refine_in_lockstep;
use super::streamed::slab_part_bytes;
use super::{ViewParams, ViewSearch, candidate_axes, canonical_axis, concluded, finish};
use super::{by_axis, guess_holds, guessed_shifted, lattice_of, paper_and_guessed};
use super::{ranked, resolve, shifted_lattices};
use crate::error::{Error, Result};
use crate::geometry::lattice::Lattice;
use crate::measure::{BlockCounts, PartialCounts};
use crate::volume::{Volume, VoxelType};

/// A round of a view search counted in parts.
#[derive(Clone, Debug, PartialEq)]
pub enum ViewRound {
    /// The paper's lattice of every axis, each followed by its shifted lattices where they can
    /// be guessed (`view::guessed_shifted`).
    Paper,
    /// The shifted lattices (phases 1 on) of every axis the paper round did not count right,
    /// given the samples each axis's paper lattice counted (the first round's
    /// [`ViewRounds::paper_samples`]).
    Shifted(Vec<u64>),
    /// A step of the refinement: the paper's lattices of these (canonical) axes, with their
    /// guessed shifted lattices.
    RefinePaper(Vec<[f64; 3]>),
    /// A step of the refinement: the shifted lattices of these axes its paper round did not
    /// count right, given the samples each one's paper lattice counted.
    RefineShifted(Vec<[f64; 3]>, Vec<u64>),
}

impl ViewRound {
    /// The round's kind: 0 the paper's lattices, 1 the shifted ones, 2 and 3 the same of a
    /// refinement step (what a part carries, so that parts of two kinds never add).
    #[must_use]
    pub fn kind(&self) -> u8 {
        match self {
            Self::Paper => 0,
            Self::Shifted(_) => 1,
            Self::RefinePaper(_) => 2,
            Self::RefineShifted(..) => 3,
        }
    }
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
    /// [`Volume::of_slab`]: only its grid and statistics are read). With `refine`, the
    /// sphere's search ([`finish`](Self::finish)) is followed by [`refine`](Self::refine).
    pub fn new(volume: &Volume, params: &ViewParams) -> Result<Self> {
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

    /// Whether the search walks shifted lattices (phases), in the paper round where they are
    /// guessed, else in a second round ([`shifted_after`](Self::shifted_after)).
    #[must_use]
    pub fn has_shifted(&self) -> bool {
        self.params.phases > 1
    }

    /// Whether a second round is foreseen before the first is counted: phases, and an axis
    /// whose shifted lattices cannot be guessed (one the count proves guessed wrong makes a
    /// second round no one foresaw).
    pub fn foresees_shifted(&self, volume: &Volume) -> Result<bool> {
        if !self.has_shifted() {
            return Ok(false);
        }
        for &axis in &self.axes {
            let paper = lattice_of(volume, &self.params, axis, 0)?;
            if guessed_shifted(volume, &self.params, axis, &paper)?.is_none() {
                return Ok(true);
            }
        }
        Ok(false)
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
        match round {
            ViewRound::Paper => paper_and_guessed(volume, &self.params, &self.axes),
            ViewRound::Shifted(samples) => self.shifted_lattices(volume, &self.axes, samples),
            ViewRound::RefinePaper(axes) => paper_and_guessed(volume, &self.params, axes),
            ViewRound::RefineShifted(axes, samples) => self.shifted_lattices(volume, axes, samples),
        }
    }

    /// The shifted lattices of each of `axes` whose paper lattice counted `samples`, the
    /// lattices whose rays hold no subset left out, and those of the axes whose guess the paper
    /// round counted right ([`counted_with_paper`](Self::counted_with_paper)) too.
    fn shifted_lattices(
        &self,
        volume: &Volume,
        axes: &[[f64; 3]],
        samples: &[u64],
    ) -> Result<Vec<(usize, Lattice, RaySubset)>> {
        if samples.len() != axes.len() {
            return Err(Error::invalid(
                "paper samples",
                samples.len(),
                format!("one count for each of the {} axes", axes.len()),
            ));
        }
        let mut out = Vec::new();
        for (a, (&axis, &n)) in axes.iter().zip(samples).enumerate() {
            if self.counted_with_paper(volume, axis, n)? {
                continue;
            }
            for (lattice, subset) in shifted_lattices(volume, &self.params, axis, n)? {
                if let Some(subset) = subset {
                    out.push((a, lattice, subset));
                }
            }
        }
        Ok(out)
    }

    /// Whether the paper round counted `axis`'s shifted lattices as they are walked for a paper
    /// lattice of `samples`: guessed, and guessed right.
    fn counted_with_paper(&self, volume: &Volume, axis: [f64; 3], samples: u64) -> Result<bool> {
        if !guess_holds(&self.params, samples) {
            return Ok(false);
        }
        let paper = lattice_of(volume, &self.params, axis, 0)?;
        Ok(guessed_shifted(volume, &self.params, axis, &paper)?.is_some())
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
            // An axis's lattices (its shifted phases) walked together.
            let axes: Vec<&[(usize, Lattice, RaySubset)]> =
                lattices.chunk_by(|a, b| a.0 == b.0).collect();
            let parts: Vec<Vec<PartialCounts>> = axes
                .par_iter()
                .map(|axis| {
                    let kept: Vec<(&Lattice, RaySubset)> =
                        axis.iter().map(|(_, l, s)| (l, *s)).collect();
                    let mut opens: Vec<OpenRays> =
                        axis.iter().map(|(_, l, _)| OpenRays::new(l)).collect();
                    let mut each: Vec<&mut OpenRays> = opens.iter_mut().collect();
                    let parts =
                        count_slabs_into(&sampler, &kept, block, (bricks, z.clone()), &mut each);
                    // The bands' pieces, taken in order, are in key order: never sorted.
                    (parts.into_iter().zip(opens))
                        .map(|(part, open)| {
                            PartialCounts::of(part.counts, part.rays, open.into_fragments())
                        })
                        .collect()
                })
                .collect();
            Ok(parts.into_iter().flatten().collect())
        })
    }

    /// About the bytes [`count_slab`](Self::count_slab) of `round` in the cell planes `planes`
    /// of `volume` (its grid alone is read), its voxels held as `held`, holds beyond the voxels
    /// it is given, with `threads` threads: what a task weighs against its budget before it
    /// copies its voxels.
    pub fn slab_bytes(
        &self,
        volume: &Volume,
        round: &ViewRound,
        (planes, threads): (&Range<usize>, usize),
        held: VoxelType,
    ) -> Result<u64> {
        let lattices = self.lattices(volume, round)?;
        let slab = (planes.len(), threads.max(1));
        Ok(slab_part_bytes(
            (volume.dims(), held),
            &self.params,
            &lattices,
            slab,
        ))
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
        let (paper, _) = self.paper_rates(volume, &ViewRound::Paper, paper)?;
        Ok(paper.iter().map(|r| r.samples).collect())
    }

    /// The round that follows the paper round `round` (the sphere's or a refinement step's),
    /// given its counts added up: the shifted lattices it did not count right. `None` where
    /// there are none: without phases, or where every axis's were guessed right (on any volume
    /// whose box holds enough samples for the shifted lattices' largest subset and no missing
    /// voxel brings a paper lattice's count under it).
    pub fn shifted_after(
        &self,
        volume: &Volume,
        round: &ViewRound,
        counts: &[PartialCounts],
    ) -> Result<Option<ViewRound>> {
        if !self.has_shifted() {
            return Ok(None);
        }
        let (paper, _) = self.paper_rates(volume, round, counts)?;
        let next = shifted_round(round, paper.iter().map(|r| r.samples).collect());
        Ok((!self.lattices(volume, &next)?.is_empty()).then_some(next))
    }

    /// The entropy rates of `round`'s lattices from its counts added up, one a lattice, each
    /// with the index of its axis.
    fn rates(
        &self,
        volume: &Volume,
        round: &ViewRound,
        counts: &[PartialCounts],
    ) -> Result<Vec<(usize, AxisEntropy)>> {
        let lattices = self.lattices(volume, round)?;
        if lattices.len() != counts.len() {
            let (name, what) = match round {
                ViewRound::Paper | ViewRound::RefinePaper(_) => ("paper counts", "lattices"),
                _ => ("shifted counts", "shifted lattices"),
            };
            return Err(Error::invalid(
                name,
                counts.len(),
                format!("one for each of the round's {} {what}", lattices.len()),
            ));
        }
        let directions: Vec<[f64; 3]> = lattices.iter().map(|(_, l, _)| l.d).collect();
        let rates = self.entropies(&directions, counts)?;
        Ok(lattices.iter().map(|(a, _, _)| *a).zip(rates).collect())
    }

    /// The entropy rates of the paper round `round`'s lattices from its counts added up: each
    /// axis's paper lattice's, and its guessed shifted lattices' (empty where none were).
    fn paper_rates(
        &self,
        volume: &Volume,
        round: &ViewRound,
        counts: &[PartialCounts],
    ) -> Result<(Vec<AxisEntropy>, Vec<Vec<AxisEntropy>>)> {
        Ok(by_axis(self.rates(volume, round, counts)?))
    }

    /// The entropy rates of the axes of the paper round `round` (the sphere's or a refinement
    /// step's), as the search evaluates each: from its paper lattice's counts `paper` and (with
    /// phases) its shifted lattices', guessed in `paper` or counted in `shifted`.
    fn evaluated(
        &self,
        volume: &Volume,
        round: &ViewRound,
        paper: &[PartialCounts],
        shifted: &[PartialCounts],
    ) -> Result<Vec<AxisEntropy>> {
        let axes = match round {
            ViewRound::Paper => &self.axes,
            ViewRound::RefinePaper(axes) => axes,
            _ => return Err(Error::invalid("round", "shifted", "a paper round")),
        };
        let (paper, mut of_axis) = self.paper_rates(volume, round, paper)?;
        if self.has_shifted() {
            for (of_axis, p) in of_axis.iter_mut().zip(&paper) {
                if !guess_holds(&self.params, p.samples) {
                    of_axis.clear();
                }
            }
            let samples = paper.iter().map(|r| r.samples).collect();
            for (a, r) in self.rates(volume, &shifted_round(round, samples), shifted)? {
                of_axis[a].push(r);
            }
        }
        Ok(axes
            .iter()
            .zip(paper)
            .zip(&of_axis)
            .map(|((&axis, paper), shifted)| finish(volume, &self.params, axis, paper, shifted))
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
    /// first round, `shifted` of the second (empty where [`shifted_after`](Self::shifted_after) gave none), `search`'s result bit for
    /// bit, but for the refinement, which [`refine`](Self::refine) adds. `volume` gives the
    /// grid (a slab of it will do).
    pub fn finish(
        &self,
        volume: &Volume,
        paper: &[PartialCounts],
        shifted: &[PartialCounts],
    ) -> Result<ViewSearch> {
        let views = self.evaluated(volume, &ViewRound::Paper, paper, shifted)?;
        Ok(concluded(
            ranked(views, self.params.block)?,
            self.params.clone(),
            None,
        ))
    }

    /// The sphere's search `search` ([`finish`](Self::finish)'s) refined when the parameters
    /// ask for it (else as it is): the pattern searches from its best axes taken in lockstep,
    /// the axes of each step evaluated from the sums `count` gives of a round's parts (a
    /// [`ViewRound::RefinePaper`], then with phases a [`ViewRound::RefineShifted`] of the samples
    /// it counted): [`search`](super::search)'s result with `refine`, bit for bit.
    pub fn refine(
        &self,
        volume: &Volume,
        search: ViewSearch,
        mut count: impl FnMut(&ViewRound) -> Result<Vec<PartialCounts>>,
    ) -> Result<ViewSearch> {
        if !self.params.refine {
            return Ok(search);
        }
        let refined = refine_in_lockstep(self.params.level, &search.views, |axes| {
            let axes = axes
                .iter()
                .map(|&a| canonical_axis(a))
                .collect::<Result<Vec<_>>>()?;
            let round = ViewRound::RefinePaper(axes);
            let paper = count(&round)?;
            let shifted = match self.shifted_after(volume, &round, &paper)? {
                Some(next) => count(&next)?,
                None => Vec::new(),
            };
            self.evaluated(volume, &round, &paper, &shifted)
        })?;
        Ok(concluded(search.views, search.params, Some(refined)))
    }
}

/// The shifted round following the paper round `round`, its lattices having counted `samples`.
fn shifted_round(round: &ViewRound, samples: Vec<u64>) -> ViewRound {
    match round {
        ViewRound::RefinePaper(axes) => ViewRound::RefineShifted(axes.clone(), samples),
        _ => ViewRound::Shifted(samples),
    }
}

#[cfg(test)]
mod tests;
