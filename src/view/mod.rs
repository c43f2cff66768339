//! The most structured view (paper §3.1 and §4): the entropy rate of every axis of the viewpoint
//! sphere, ranked by its mean over lattice phases (docs/design.md §2: the paper's lattice favours the
//! coordinate axes), with the axes that cannot be told from the best named as contenders, and
//! optionally refined around the best.

mod evaluator;
pub mod icosphere;
mod parts;
mod rate;
mod refine;
mod streamed;

use rayon::prelude::*;
use serde::Serialize;

use evaluator::Evaluator;
pub use evaluator::evaluate;
pub use parts::{ViewRound, ViewRounds};
pub use rate::{
    AxisEntropy, BRICK_CELLS, BinSampler, Bricks, InnerSpans, OpenRays, PhaseStats, RaySubset,
    Vector, Walk, block_counts, block_counts_by, count_slab_into, counts_of_bricks, entropy_rate,
    entropy_rate_of, entropy_rates_of, ray_bins, work_units, work_units_of,
};
pub use refine::{REFINE_STOP_DEGREES, pattern_search, refine_evaluations, refine_steps};
pub use streamed::{block_counts_streamed, search_streamed, streamed_memory_floor, streamed_slabs};

use crate::error::{Error, Result};
use crate::geometry::lattice::{Lattice, SamplingParams};
use crate::geometry::{canonical, dot, normalize};
use crate::progress::Monitor;
use crate::volume::{Volume, Voxel};

/// The lattice phases averaged by default, the paper's among them.
pub const DEFAULT_PHASES: usize = 8;

/// Each shifted lattice walks one block of rays in this many by default, so that the seven
/// shifted lattices together cost about 0.6 of a full lattice (when the volume affords it).
pub const DEFAULT_PHASE_SUBSET: u64 = 12;

/// Parameters of the view search.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ViewParams {
    /// Bins and spacings, shared with the slicing.
    #[serde(flatten)]
    pub sampling: SamplingParams,
    /// Block length L (2 to 4).
    pub block: usize,
    /// Icosphere subdivision level (0 to 4).
    pub level: usize,
    /// Lattice phases averaged per axis, the paper's lattice among them; 0 ranks by the paper's
    /// single lattice.
    pub phases: usize,
    /// Each shifted lattice walks one block of rays in this many (1: every ray).
    pub phase_subset: u64,
    /// Seed of the lattice shifts.
    pub phase_seed: u64,
    /// Whether to refine the best axes on a finer local grid.
    pub refine: bool,
}

impl Default for ViewParams {
    fn default() -> Self {
        Self {
            sampling: SamplingParams::default(),
            block: 3,
            level: 1,
            phases: DEFAULT_PHASES,
            phase_subset: DEFAULT_PHASE_SUBSET,
            phase_seed: 1,
            refine: false,
        }
    }
}

impl ViewParams {
    /// The defaults with `bins` quantization bins.
    pub fn with_bins(bins: usize) -> Self {
        Self {
            sampling: SamplingParams {
                bins,
                ..SamplingParams::default()
            },
            ..Self::default()
        }
    }

    /// The paper's method: one lattice per axis, ranked by its entropy rate.
    pub fn paper() -> Self {
        Self {
            phases: 0,
            ..Self::default()
        }
    }
}

/// A shifted lattice walking a subset of its rays keeps at least this many samples per cell
/// of the L-block table (the view search's sampled passes choose their subset by it).
pub const SAMPLES_PER_CELL: u64 = 32;

/// The most lattice phases `--phases` allows.
pub const MAX_PHASES: usize = 64;

/// What the views are sorted by.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RankedBy {
    /// The mean entropy rate over lattice phases.
    PhaseMean,
    /// The entropy rate on the paper's lattice.
    PaperLattice,
}

/// An axis that cannot be told from the best: its mean lies within two standard errors of the
/// difference (docs/design.md §2).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Contender {
    /// The canonical axis.
    pub axis: [f64; 3],
    /// Its mean entropy rate over the phases.
    pub mean: f64,
    /// The standard error of that mean.
    pub se: f64,
}

/// The result of the view search.
#[derive(Clone, Debug, Serialize)]
pub struct ViewSearch {
    /// One entry per axis, by the score the ranking used (lowest first).
    pub views: Vec<AxisEntropy>,
    /// The parameters, with the spacings resolved to millimetres.
    pub params: ViewParams,
    /// What the views are sorted by.
    pub ranked_by: RankedBy,
    /// With phases: whether another axis is a contender (`None` on the paper's single lattice).
    pub uncertain: Option<bool>,
    /// With phases: the best axis and every contender, best first.
    pub contenders: Option<Vec<Contender>>,
    /// With refine: the best axis found near the best sphere axes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refined: Option<AxisEntropy>,
}

impl ViewSearch {
    /// The most structured axis: the refined one when there is one, else the first on the sphere.
    pub fn best(&self) -> &AxisEntropy {
        self.refined.as_ref().unwrap_or(&self.views[0])
    }
}

/// The score an axis is ranked by: its phase mean when there is one, else the paper's rate.
pub fn score(a: &AxisEntropy) -> f64 {
    a.phases.map_or(a.entropy_rate, |p| p.mean)
}

/// The order of the ranking: measured axes by score (lowest first), then the axes too thin to
/// measure.
fn rank(a: &AxisEntropy, b: &AxisEntropy) -> std::cmp::Ordering {
    (!a.measured(), score(a))
        .partial_cmp(&(!b.measured(), score(b)))
        .unwrap_or(std::cmp::Ordering::Equal)
}

/// The contenders of `best` among `views`: `best` itself first, then every axis whose mean is
/// within two standard errors of the difference, `mean_b - mean_best < 2·√(se_b² + se_best²)`.
pub fn contenders(best: &AxisEntropy, views: &[AxisEntropy]) -> Option<Vec<Contender>> {
    let of = |a: &AxisEntropy| {
        a.phases.map(|p| Contender {
            axis: a.axis,
            mean: p.mean,
            se: p.se(),
        })
    };
    let b = of(best)?;
    let mut out = vec![b];
    for a in views {
        if a.axis == best.axis || !a.measured() {
            continue;
        }
        let c = of(a)?;
        if c.mean - b.mean < 2.0 * c.se.hypot(b.se) {
            out.push(c);
        }
    }
    Some(out)
}

/// The validated parameters with spacings resolved.
fn resolve(volume: &Volume, params: &ViewParams) -> Result<ViewParams> {
    if !(2..=4).contains(&params.block) {
        return Err(Error::invalid("block", params.block, "2, 3 or 4"));
    }
    if params.level > icosphere::MAX_LEVEL {
        return Err(Error::invalid(
            "level",
            params.level,
            format!("0 to {}", icosphere::MAX_LEVEL),
        ));
    }
    if params.phases > MAX_PHASES {
        return Err(Error::invalid(
            "phases",
            params.phases,
            format!("at most {MAX_PHASES}"),
        ));
    }
    if params.phase_subset == 0 {
        return Err(Error::invalid("phase_subset", 0, "at least 1"));
    }
    if volume.is_constant() {
        return Err(Error::Degenerate(format!(
            "the volume is constant (every voxel is {}): every axis has entropy rate 0",
            volume.stats().min
        )));
    }
    Ok(ViewParams {
        sampling: params.sampling.resolved(volume.dims(), volume.spacing())?,
        ..params.clone()
    })
}

/// The lattice shift of phase `n` (0 is the paper's lattice): deterministic in `seed`.
fn phase(seed: u64, n: usize) -> [f64; 3] {
    if n == 0 {
        return [0.0; 3];
    }
    std::array::from_fn(|m| {
        let mut z = seed ^ ((n as u64) << 8 | m as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    })
}

/// Lattice `n` of `axis` (0 is the paper's) for `volume` under `params`.
fn lattice_of(volume: &Volume, params: &ViewParams, axis: [f64; 3], n: usize) -> Result<Lattice> {
    Ok(Lattice::new(
        volume.dims(),
        volume.spacing(),
        axis,
        params.sampling.ray_spacing.unwrap_or(1.0),
        params.sampling.sample_spacing.unwrap_or(1.0),
        phase(params.phase_seed, n),
    )?)
}

/// The candidate axes of icosphere `level` as canonical unit directions, the order every
/// search counts them in.
fn candidate_axes(level: usize) -> Result<Vec<[f64; 3]>> {
    icosphere::axes(level)
        .into_iter()
        .map(canonical_axis)
        .collect()
}

/// `axis` made a canonical unit direction.
fn canonical_axis(axis: [f64; 3]) -> Result<[f64; 3]> {
    Ok(canonical(normalize(axis).ok_or_else(|| {
        Error::invalid("axis", "[0, 0, 0]", "a direction with a length")
    })?))
}

/// The shifted lattices of `axis` (phases 1 on), each with the rays it walks, for an axis
/// whose paper lattice counted `samples`; `None` for each when the axis is too thin for a block
/// in any phase (those phases would say nothing, and are not walked).
fn shifted_lattices(
    volume: &Volume,
    params: &ViewParams,
    axis: [f64; 3],
    samples: u64,
) -> Result<Vec<(Lattice, Option<RaySubset>)>> {
    let thin = !lattice_of(volume, params, axis, 0)?.could_hold(params.block);
    (1..params.phases)
        .map(|n| {
            let lattice = lattice_of(volume, params, axis, n)?;
            Ok((lattice, (!thin).then(|| subset(params, samples, n))))
        })
        .collect()
}

/// About how many samples a lattice of `paper`'s spacings holds in `volume`'s box (the same
/// for every axis).
fn box_samples(volume: &Volume, paper: &Lattice) -> u64 {
    let extent: f64 = (0..3)
        .map(|m| (volume.dims()[m] - 1) as f64 * volume.spacing()[m])
        .product();
    (extent / (paper.ray_spacing.powi(2) * paper.sample_spacing)) as u64
}

/// The shifted lattices of `axis` and the rays each walks, guessed before its paper lattice
/// `paper` is walked, so that they can be walked with it: their subset hangs on the paper's
/// samples, guessed as those its lattice holds in the volume's box. `None` where the guess
/// gives any of them less than the largest subset (or none: too thin), or phases are not asked
/// for; else the guess is right unless missing samples bring the paper's count under it,
/// which [`guess_holds`] tells once it is counted.
fn guessed_shifted(
    volume: &Volume,
    params: &ViewParams,
    axis: [f64; 3],
    paper: &Lattice,
) -> Result<Option<Vec<(Lattice, RaySubset)>>> {
    if params.phases < 2 {
        return Ok(None);
    }
    let guess = shifted_lattices(volume, params, axis, box_samples(volume, paper))?;
    Ok(guess
        .into_iter()
        .map(|(l, s)| s.filter(|s| s.every == params.phase_subset).map(|s| (l, s)))
        .collect())
}

/// The paper lattice of each of `axes`, each followed by its [`guessed_shifted`] lattices (none
/// where they cannot be guessed), each with the index of its axis: what a search counting the
/// phases with the paper's lattices walks first ([`by_axis`] splits what it counts).
fn paper_and_guessed(
    volume: &Volume,
    params: &ViewParams,
    axes: &[[f64; 3]],
) -> Result<Vec<(usize, Lattice, RaySubset)>> {
    let mut out = Vec::new();
    for (a, &axis) in axes.iter().enumerate() {
        let paper = lattice_of(volume, params, axis, 0)?;
        let guess = guessed_shifted(volume, params, axis, &paper)?;
        out.push((a, paper, RaySubset::ALL));
        out.extend(guess.into_iter().flatten().map(|(l, s)| (a, l, s)));
    }
    Ok(out)
}

/// What was counted of [`paper_and_guessed`]'s lattices, in their order with their axes' indices,
/// split into each axis's paper lattice's and its guessed lattices' (empty where none were).
fn by_axis<R>(counted: impl IntoIterator<Item = (usize, R)>) -> (Vec<R>, Vec<Vec<R>>) {
    let (mut paper, mut guessed) = (Vec::new(), Vec::new());
    for (a, r) in counted {
        // An axis's first lattice is its paper lattice, the rest its guessed ones.
        if a == paper.len() {
            paper.push(r);
            guessed.push(Vec::new());
        } else {
            guessed[a].push(r);
        }
    }
    (paper, guessed)
}

/// Whether [`guessed_shifted`]'s lattices walk the rays [`shifted_lattices`] gives them for a
/// paper lattice that counted `samples`: the largest subset (thinness does not hang on the
/// samples, and every phase's subset is the same).
fn guess_holds(params: &ViewParams, samples: u64) -> bool {
    subset(params, samples, 1).every == params.phase_subset
}

/// The rays a shifted lattice walks, for an axis whose paper lattice counted `samples`:
/// one block in `phase_subset`, spread over the volume, as long as each shifted lattice keeps
/// [`SAMPLES_PER_CELL`] samples per cell of the L-block table; else all of them.
///
/// The plug-in entropy of L-blocks is biased low by about `cells / (2·N·ln 2)` bits for N
/// samples, so a lattice with fewer samples scores lower; with this many samples a cell the
/// bias stays below 0.023 bit and varies between axes by a tenth of that. Small volumes, where
/// it would not, are cheap to walk whole.
fn subset(params: &ViewParams, samples: u64, n: usize) -> RaySubset {
    let cells = (params.sampling.bins as u64).saturating_pow(params.block as u32);
    let affordable = samples / cells.saturating_mul(SAMPLES_PER_CELL).max(1);
    RaySubset {
        every: params.phase_subset.min(affordable).max(1),
        offset: n as u64,
    }
}

/// The paper lattice's result `paper` for `axis`, described in world terms, with the phase
/// statistics of it and the `shifted` lattices' results when phases are asked for (lattices
/// whose rays hold no block say nothing, and are left out of the mean).
fn finish(
    volume: &Volume,
    params: &ViewParams,
    axis: [f64; 3],
    mut paper: AxisEntropy,
    shifted: &[AxisEntropy],
) -> AxisEntropy {
    paper.axis = axis;
    paper.world = volume.transform().describe(axis, volume.spacing());
    if params.phases > 0 {
        let values: Vec<f64> = std::iter::once(&paper)
            .chain(shifted)
            .filter(|r| r.measured())
            .map(|r| r.entropy_rate)
            .collect();
        paper.phases = (!values.is_empty()).then(|| PhaseStats::of(&values));
    }
    paper
}

/// Evaluates every axis of the viewpoint sphere and sorts them by their score (ties keep the
/// sphere's order). Fails with [`Error::Cancelled`] when the monitor's flag is raised.
pub fn search(volume: &Volume, params: &ViewParams, monitor: &Monitor) -> Result<ViewSearch> {
    let params = resolve(volume, params)?;
    let q = volume.quantizer(params.sampling.bins)?;
    crate::volume::with_voxels!(volume.data(), |data| {
        search_in(BinSampler::over(data, volume, q), volume, params, monitor)
    })
}

/// [`search`] with the sampler of `volume`'s voxels, in their own type.
fn search_in<T: Voxel>(
    sampler: BinSampler<'_, T>,
    volume: &Volume,
    params: ViewParams,
    monitor: &Monitor,
) -> Result<ViewSearch> {
    let eval = Evaluator {
        volume,
        sampler,
        params,
    };
    let axes = icosphere::axes(eval.params.level);
    let total = axes.iter().map(|&a| eval.units(a)).sum::<Result<u64>>()?;
    monitor.start("view search", total);
    let views = axes
        .par_iter()
        .map(|&axis| eval.evaluate(axis, monitor))
        .collect::<Result<Vec<_>>>()?;
    let views = ranked(views, eval.params.block)?;
    let refined = if eval.params.refine {
        Some(refine::refine(&eval, &views, monitor)?)
    } else {
        None
    };
    Ok(concluded(views, eval.params, refined))
}

/// `views` in the ranking's order, refused when no axis could be measured.
fn ranked(mut views: Vec<AxisEntropy>, block: usize) -> Result<Vec<AxisEntropy>> {
    views.sort_by(rank);
    if !views[0].measured() {
        return Err(Error::Degenerate(format!(
            "no ray holds {block} samples in a row along any axis: the volume is too thin to measure"
        )));
    }
    Ok(views)
}

/// The search's result from its ranked views, with the contenders of the best.
fn concluded(
    views: Vec<AxisEntropy>,
    params: ViewParams,
    refined: Option<AxisEntropy>,
) -> ViewSearch {
    let contenders = contenders(refined.as_ref().unwrap_or(&views[0]), &views);
    ViewSearch {
        ranked_by: if params.phases > 0 {
            RankedBy::PhaseMean
        } else {
            RankedBy::PaperLattice
        },
        uncertain: contenders.as_ref().map(|c| c.len() > 1),
        contenders,
        views,
        params,
        refined,
    }
}

/// The angle between two axes in degrees, ignoring their sign.
pub fn axis_angle(a: [f64; 3], b: [f64; 3]) -> f64 {
    let (a, b) = (normalize(a).unwrap_or(a), normalize(b).unwrap_or(b));
    dot(a, b).abs().clamp(0.0, 1.0).acos().to_degrees()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::view::rate::tests::awkward_volume_of as awkward_volume;
    use crate::volume::VoxelType;

    /// A search reports exactly the units it announced: the paper lattices' rows, the shifted
    /// lattices' shares whether they walk a subset of their rays (few bins: a subset of one in
    /// twelve), all of them (32 bins on a small volume) or none (a volume too thin for a block).
    #[test]
    fn a_search_reports_the_units_it_announced() {
        let few_bins = |bins| {
            let mut params = ViewParams::default();
            params.sampling.bins = bins;
            params
        };
        for (dims, params, every) in [
            ([30, 26, 41], few_bins(4), 12),
            ([30, 26, 41], few_bins(32), 1),
            ([30, 26, 41], ViewParams::paper(), 1),
            ([23, 19, 2], few_bins(4), 1),
        ] {
            let v = awkward_volume(dims, [1.0, 0.9, 1.3], VoxelType::U8, 7);
            // The case is the one named: the rays a shifted lattice walks, about.
            let resolved = resolve(&v, &params).unwrap();
            assert_eq!(subset(&resolved, v.len() as u64, 1).every, every);
            let monitor = Monitor::new(None, None);
            search(&v, &params, &monitor).unwrap();
            let (done, total) = monitor.counted();
            assert_eq!(done, total, "{dims:?} {params:?}");
        }
    }
}
