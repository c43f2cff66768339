//! The evaluation of one axis: its paper lattice and, when asked for, its shifted phases, walked
//! and scored as the search ranks them.

use super::rate::{AxisEntropy, BinSampler, RaySubset, entropy_rates_of, work_units};
use super::{ViewParams, box_samples, canonical_axis, finish, guess_holds, guessed_shifted};
use super::{lattice_of, resolve, shifted_lattices, subset};
use crate::error::Result;
use crate::geometry::lattice::Lattice;
use crate::progress::Monitor;
use crate::volume::{Volume, Voxel};

/// The lattices of `lattices` that walk rays, with the rays they walk.
fn walked(lattices: &[(Lattice, Option<RaySubset>)]) -> Vec<(&Lattice, RaySubset)> {
    lattices
        .iter()
        .filter_map(|(l, subset)| subset.map(|s| (l, s)))
        .collect()
}

/// Everything one search needs to evaluate an axis.
pub(super) struct Evaluator<'a, T> {
    pub(super) volume: &'a Volume,
    pub(super) sampler: BinSampler<'a, T>,
    pub(super) params: ViewParams,
}

impl<T: Voxel> Evaluator<'_, T> {
    /// The progress units of an axis whose paper lattice is `paper`: its own, the samples a
    /// lattice of its spacings holds in the volume's box (the same for every axis), and each
    /// shifted lattice's, in proportion to the rays it walks (one in its subset's `every`), so
    /// that a unit takes about as long in every lattice. (Counted in rows of tiles, a unit of a
    /// lattice walking one ray in twelve, or of an axis whose tiles lie along its rows, took a
    /// fraction of another's: the bar ran ahead through some lattices and stood through others.)
    fn shares(&self, paper: &Lattice) -> (u64, u64) {
        let samples = box_samples(self.volume, paper);
        let own = samples.max(work_units(paper));
        (own, own / subset(&self.params, samples, 1).every)
    }

    /// The entropy rate of the rays of `lattice` that `subset` keeps, reporting `units` in all:
    /// a share of them for each row of tiles walked, what does not divide at the end.
    fn walk(
        &self,
        lattice: &Lattice,
        subset: RaySubset,
        (monitor, units): (&Monitor, u64),
    ) -> Result<AxisEntropy> {
        let block = self.params.block;
        let mut rate =
            entropy_rates_of(&self.sampler, &[(lattice, subset)], block, (monitor, units))?;
        Ok(rate.pop().expect("one lattice's rate"))
    }

    pub(super) fn units(&self, axis: [f64; 3]) -> Result<u64> {
        let lattice = lattice_of(self.volume, &self.params, axis, 0)?;
        let (own, shifted) = self.shares(&lattice);
        Ok(own + shifted * self.params.phases.saturating_sub(1) as u64)
    }

    /// [`Self::evaluate`] with the paper's lattice and its shifted phases walked together, tile
    /// by tile (the phases' rays read the lines the paper's rays beside them read), or `None`
    /// where they are not: along a coordinate axis (the paper's lattice is walked as voxel
    /// columns) and where the phases' subset cannot be guessed ([`guessed_shifted`]). Where
    /// the paper's count proves the guess wrong, the shifted lattices are walked again as they
    /// should be. Counts are sums: the same counts as walking the lattices one after another.
    fn evaluate_together(
        &self,
        axis: [f64; 3],
        paper: &Lattice,
        (own, share): (u64, u64),
        monitor: &Monitor,
    ) -> Result<Option<AxisEntropy>> {
        let (volume, params) = (self.volume, &self.params);
        if paper.columns().is_some() {
            return Ok(None);
        }
        let Some(guess) = guessed_shifted(volume, params, axis, paper)? else {
            return Ok(None);
        };
        let mut all = vec![(paper, RaySubset::ALL)];
        all.extend(guess.iter().map(|(l, s)| (l, *s)));
        let units = own + share * guess.len() as u64;
        let mut rates = entropy_rates_of(&self.sampler, &all, params.block, (monitor, units))?;
        let mut shifted = rates.split_off(1);
        let paper = rates.pop().expect("the paper lattice's rate");
        if !guess_holds(params, paper.samples) {
            // Too many samples were missing for the guess: the shifted lattices walked again.
            let wanted = shifted_lattices(volume, params, axis, paper.samples)?;
            shifted =
                entropy_rates_of(&self.sampler, &walked(&wanted), params.block, (monitor, 0))?;
        }
        Ok(Some(finish(volume, params, axis, paper, &shifted)))
    }

    /// The entropy rate of `axis` on the paper's lattice, with the phase statistics when asked
    /// for.
    pub(super) fn evaluate(&self, axis: [f64; 3], monitor: &Monitor) -> Result<AxisEntropy> {
        let axis = canonical_axis(axis)?;
        let (volume, params) = (self.volume, &self.params);
        let lattice = lattice_of(volume, params, axis, 0)?;
        let (own, share) = self.shares(&lattice);
        if let Some(done) = self.evaluate_together(axis, &lattice, (own, share), monitor)? {
            return Ok(done);
        }
        let paper = self.walk(&lattice, RaySubset::ALL, (monitor, own))?;
        let lattices = shifted_lattices(volume, params, axis, paper.samples)?;
        let kept = walked(&lattices);
        monitor.advance(share * (lattices.len() - kept.len()) as u64)?;
        let units = share * kept.len() as u64;
        let shifted = entropy_rates_of(&self.sampler, &kept, params.block, (monitor, units))?;
        Ok(finish(volume, params, axis, paper, &shifted))
    }
}

/// The entropy rate of one `axis` as [`search`](super::search) measures it under `params`
/// (with its phase statistics when `params` asks for phases).
pub fn evaluate(
    volume: &Volume,
    params: &ViewParams,
    axis: [f64; 3],
    monitor: &Monitor,
) -> Result<AxisEntropy> {
    let params = resolve(volume, params)?;
    let q = volume.quantizer(params.sampling.bins)?;
    crate::volume::with_voxels!(volume.data(), |data| {
        let eval = Evaluator {
            volume,
            sampler: BinSampler::over(data, volume, q),
            params,
        };
        monitor.start("one axis", eval.units(axis)?);
        eval.evaluate(axis, monitor)
    })
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::view::rate::tests::{awkward_volume_of as awkward_volume, holed_below};
    use crate::volume::VoxelType;

    /// [`evaluate`]'s result as the search computed it before the paper's lattice was walked
    /// with its phases: each lattice alone, the shifted ones' subset from the paper's samples.
    pub(in crate::view) fn evaluated_apart(
        volume: &Volume,
        params: &ViewParams,
        axis: [f64; 3],
    ) -> AxisEntropy {
        let params = resolve(volume, params).unwrap();
        let q = volume.quantizer(params.sampling.bins).unwrap();
        let none = Monitor::none();
        let axis = canonical_axis(axis).unwrap();
        crate::volume::with_voxels!(volume.data(), |data| {
            let sampler = BinSampler::over(data, volume, q);
            let rate = |l: &Lattice, s| {
                crate::view::rate::entropy_rate_of(&sampler, l, params.block, s, (&none, 0))
                    .unwrap()
            };
            let lattice = lattice_of(volume, &params, axis, 0).unwrap();
            let paper = rate(&lattice, RaySubset::ALL);
            let shifted: Vec<AxisEntropy> =
                walked(&shifted_lattices(volume, &params, axis, paper.samples).unwrap())
                    .into_iter()
                    .map(|(l, s)| rate(l, s))
                    .collect();
            finish(volume, &params, axis, paper, &shifted)
        })
    }

    /// The paper's lattice walked together with its shifted phases gives what each walks
    /// alone: where the subset guessed from the volume's box holds (few bins, so that a small
    /// volume keeps one block in twelve), and where missing samples prove it wrong (a slab of
    /// NaN: the subset is one in fewer, and the phases are walked again).
    #[test]
    fn the_paper_lattice_walked_with_its_phases_gives_what_each_walks_alone() {
        let mut params = ViewParams::default();
        params.sampling.bins = 4;
        let v = awkward_volume([32, 32, 32], [1.0, 0.9, 1.3], VoxelType::I16, 5);
        let holed = holed_below(&v, 20);
        let oblique = [0.526, 0.0, 0.851];
        for (volume, holes) in [(&v, false), (&holed, true)] {
            let resolved = resolve(volume, &params).unwrap();
            let lattice = lattice_of(volume, &resolved, oblique, 0).unwrap();
            assert_eq!(
                subset(&resolved, box_samples(volume, &lattice), 1).every,
                12
            );
            let apart = evaluated_apart(volume, &params, oblique);
            // The case named: the guess right, or proved wrong by the missing samples.
            assert_eq!(subset(&resolved, apart.samples, 1).every < 12, holes);
            assert!(lattice.columns().is_none());
            let together = evaluate(volume, &params, oblique, &Monitor::none()).unwrap();
            assert_eq!(together, apart);
            // The shifted phases were measured (a phase whose rays hold no block is left out).
            assert!(
                together.phases.as_ref().is_some_and(|p| p.n >= 7),
                "{together:?}"
            );
        }
    }
}
