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
//! again where the task runs and nothing but numbers travels. The refinement
//! ([`ViewRounds::refine`]) is more rounds of the same two kinds, two a step of its pattern
//! searches in lockstep (as the slab-by-slab search takes them), of the axes each step asks for.

use std::ops::Range;

use rayon::prelude::*;

use super::rate::{AxisEntropy, BinSampler, Bricks, OpenRays, RaySubset, count_slabs_into};
use super::refine::refine_in_lockstep;
use super::streamed::slab_part_bytes;
use super::{ViewParams, ViewSearch, candidate_axes, canonical_axis, concluded, finish};
use super::{lattice_of, ranked, resolve, shifted_lattices};
use crate::error::{Error, Result};
use crate::geometry::lattice::Lattice;
use crate::measure::{BlockCounts, PartialCounts};
use crate::volume::{Volume, VoxelType};

/// A round of a view search counted in parts.
#[derive(Clone, Debug, PartialEq)]
pub enum ViewRound {
    /// The paper's lattice of every axis.
    Paper,
    /// The shifted lattices of every axis (phases 1 on), given the samples each axis's paper
    /// lattice counted (the first round's [`ViewRounds::paper_samples`]).
    Shifted(Vec<u64>),
    /// A step of the refinement: the paper's lattices of these (canonical) axes.
    RefinePaper(Vec<[f64; 3]>),
    /// A step of the refinement: the shifted lattices of these axes, given the samples each
    /// one's paper lattice counted.
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
        match round {
            ViewRound::Paper => self.paper_lattices(volume, &self.axes),
            ViewRound::Shifted(samples) => self.shifted_lattices(volume, &self.axes, samples),
            ViewRound::RefinePaper(axes) => self.paper_lattices(volume, axes),
            ViewRound::RefineShifted(axes, samples) => self.shifted_lattices(volume, axes, samples),
        }
    }

    /// The paper's lattice of each of `axes`.
    fn paper_lattices(
        &self,
        volume: &Volume,
        axes: &[[f64; 3]],
    ) -> Result<Vec<(usize, Lattice, RaySubset)>> {
        axes.iter()
            .enumerate()
            .map(|(a, &axis)| {
                Ok((
                    a,
                    lattice_of(volume, &self.params, axis, 0)?,
                    RaySubset::ALL,
                ))
            })
            .collect()
    }

    /// The shifted lattices of each of `axes` whose paper lattice counted `samples`, the
    /// lattices whose rays hold no subset left out.
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
            for (lattice, subset) in shifted_lattices(volume, &self.params, axis, n)? {
                if let Some(subset) = subset {
                    out.push((a, lattice, subset));
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
        Ok(self
            .rates(volume, &ViewRound::Paper, paper)?
            .iter()
            .map(|(_, r)| r.samples)
            .collect())
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
                ViewRound::Paper | ViewRound::RefinePaper(_) => ("paper counts", "axes"),
                _ => ("shifted counts", "shifted lattices"),
            };
            return Err(Error::invalid(
                name,
                counts.len(),
                format!("one for each of the {} {what}", lattices.len()),
            ));
        }
        let directions: Vec<[f64; 3]> = lattices.iter().map(|(_, l, _)| l.d).collect();
        let rates = self.entropies(&directions, counts)?;
        Ok(lattices.iter().map(|(a, _, _)| *a).zip(rates).collect())
    }

    /// The entropy rates of the axes of the paper round `round` (the sphere's or a refinement
    /// step's), as the search evaluates each: from its paper lattice's counts `paper` and (with
    /// phases) its shifted lattices' `shifted`.
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
        let paper = self.rates(volume, round, paper)?;
        let mut of_axis = vec![Vec::new(); axes.len()];
        if self.has_shifted() {
            let samples = paper.iter().map(|(_, r)| r.samples).collect();
            for (a, r) in self.rates(volume, &shifted_round(round, samples), shifted)? {
                of_axis[a].push(r);
            }
        }
        Ok(axes
            .iter()
            .zip(paper)
            .zip(&of_axis)
            .map(|((&axis, (_, paper)), shifted)| {
                finish(volume, &self.params, axis, paper, shifted)
            })
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
            let shifted = if self.has_shifted() {
                let rates = self.rates(volume, &round, &paper)?;
                count(&shifted_round(
                    &round,
                    rates.iter().map(|(_, r)| r.samples).collect(),
                ))?
            } else {
                Vec::new()
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
                // A slab's pieces come in key order: they are never sorted again.
                assert!(p.fragments().is_sorted_by_key(|f| (f.key, f.start)));
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
    fn the_refinement_in_parts_is_the_search_bit_for_bit() {
        let mut lcg = Lcg::new(4444);
        let v = awkward_volume([26, 22, 29], [1.0, 0.9, 1.2], VoxelType::U8, 4);
        for params in [ViewParams::paper(), ViewParams::default()] {
            let params = ViewParams {
                refine: true,
                ..params
            };
            let expect = super::super::search(&v, &params, &Monitor::none()).unwrap();
            assert!(expect.refined.is_some());
            let slabs = random_slabs(28, &mut lcg);
            let rounds = ViewRounds::new(&v, &params).unwrap();
            let paper = added(&rounds, &v, &ViewRound::Paper, &slabs, &mut lcg);
            let shifted = if rounds.has_shifted() {
                let samples = rounds.paper_samples(&v, &paper).unwrap();
                added(&rounds, &v, &ViewRound::Shifted(samples), &slabs, &mut lcg)
            } else {
                Vec::new()
            };
            let sphere = rounds.finish(&v, &paper, &shifted).unwrap();
            assert!(sphere.refined.is_none());
            let mut kinds = Vec::new();
            let got = rounds
                .refine(&v, sphere, |round| {
                    kinds.push(round.kind());
                    Ok(added(&rounds, &v, round, &slabs, &mut lcg))
                })
                .unwrap();
            let json = |s: &ViewSearch| serde_json::to_string(s).unwrap();
            assert_eq!(json(&got), json(&expect));
            // Rounds of a step: the paper's lattices, then (with phases) the shifted ones.
            let step: &[u8] = if rounds.has_shifted() { &[2, 3] } else { &[2] };
            assert!(kinds.len() >= 2 * step.len(), "{kinds:?}");
            assert!(kinds.chunks(step.len()).all(|c| c == step), "{kinds:?}");
        }
        // Without refine, the search is as it was and nothing more is counted.
        let rounds = ViewRounds::new(&v, &ViewParams::paper()).unwrap();
        let slabs_of_all = random_slabs(28, &mut lcg);
        let paper = added(&rounds, &v, &ViewRound::Paper, &slabs_of_all, &mut lcg);
        let sphere = rounds.finish(&v, &paper, &[]).unwrap();
        let expect = serde_json::to_string(&sphere).unwrap();
        let got = rounds.refine(&v, sphere, |_| unreachable!()).unwrap();
        assert_eq!(serde_json::to_string(&got).unwrap(), expect);
    }

    #[test]
    fn slabs_off_the_grid_are_refused() {
        let v = awkward_volume([20, 20, 20], [1.0; 3], VoxelType::U8, 4);
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
