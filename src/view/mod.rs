//! The most structured view (paper §3.1 and §4): the entropy rate of every axis of the viewpoint
//! sphere, lowest first, optionally checked on shifted lattices and refined around the best.

pub mod icosphere;
pub mod lattice;
mod rate;

use rayon::prelude::*;
use serde::Serialize;

pub use rate::{AxisEntropy, BinSampler, InnerSpans, PhaseSpread, entropy_rate, work_units};

use crate::error::{Error, Result};
use crate::geometry::{canonical, dot, frame, normalize};
use crate::progress::Monitor;
use crate::view::lattice::{Lattice, SamplingParams};
use crate::volume::Volume;

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
    /// Shifted lattices per axis for the spread of h (0: the paper's single lattice).
    pub phases: usize,
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
            phases: 0,
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
}

/// The most shifted lattices `--phases` allows.
pub const MAX_PHASES: usize = 64;

/// The result of the view search.
#[derive(Clone, Debug, Serialize)]
pub struct ViewSearch {
    /// One entry per axis, lowest entropy rate first.
    pub views: Vec<AxisEntropy>,
    /// The parameters, with the spacings resolved to millimetres.
    pub params: ViewParams,
    /// With phases: whether the best axis's spread exceeds its margin over the runner-up.
    pub uncertain: bool,
    /// With refine: the best axis found near the best sphere axes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refined: Option<AxisEntropy>,
}

impl ViewSearch {
    /// The most structured axis: the refined one when there is one, else the lowest on the sphere.
    pub fn best(&self) -> &AxisEntropy {
        self.refined.as_ref().unwrap_or(&self.views[0])
    }
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
    if volume.is_constant() {
        return Err(Error::Degenerate(format!(
            "the volume is constant (every voxel is {}): every axis has entropy rate 0",
            volume.stats().min
        )));
    }
    Ok(ViewParams {
        sampling: params.sampling.resolved(volume.spacing())?,
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

/// Everything one search needs to evaluate an axis.
struct Evaluator<'a> {
    volume: &'a Volume,
    sampler: BinSampler<'a>,
    params: ViewParams,
}

impl Evaluator<'_> {
    fn lattice(&self, axis: [f64; 3], n: usize) -> Result<Lattice> {
        Lattice::new(
            self.volume.dims(),
            self.volume.spacing(),
            axis,
            self.params.sampling.ray_spacing.unwrap_or(1.0),
            self.params.sampling.sample_spacing.unwrap_or(1.0),
            phase(self.params.phase_seed, n),
        )
    }

    fn units(&self, axis: [f64; 3]) -> Result<u64> {
        Ok(work_units(&self.lattice(axis, 0)?) * (1 + self.params.phases as u64))
    }

    /// The entropy rate of `axis` on the paper's lattice, with the phase spread when asked for.
    fn evaluate(&self, axis: [f64; 3], monitor: &Monitor) -> Result<AxisEntropy> {
        let axis = canonical(
            normalize(axis)
                .ok_or_else(|| Error::invalid("axis", "[0, 0, 0]", "a direction with a length"))?,
        );
        let mut result = entropy_rate(
            &self.sampler,
            &self.lattice(axis, 0)?,
            self.params.block,
            monitor,
        )?;
        result.axis = axis;
        if self.params.phases > 0 {
            let mut values = vec![result.entropy_rate];
            for n in 1..=self.params.phases {
                let lattice = self.lattice(axis, n)?;
                values.push(
                    entropy_rate(&self.sampler, &lattice, self.params.block, monitor)?.entropy_rate,
                );
            }
            result.phases = Some(PhaseSpread::of(&values));
        }
        Ok(result)
    }
}

/// Evaluates every axis of the viewpoint sphere and returns them sorted by entropy rate (ties keep
/// the sphere's order). Fails with [`Error::Cancelled`] when the monitor's flag is raised.
pub fn search(volume: &Volume, params: &ViewParams, monitor: &Monitor) -> Result<ViewSearch> {
    let params = resolve(volume, params)?;
    let sampler = BinSampler::new(volume, volume.quantizer(params.sampling.bins)?);
    let eval = Evaluator {
        volume,
        sampler,
        params,
    };
    let axes = icosphere::axes(eval.params.level);
    let total = axes.iter().map(|&a| eval.units(a)).sum::<Result<u64>>()?;
    monitor.start("view search", total);
    let mut views = axes
        .par_iter()
        .map(|&axis| eval.evaluate(axis, monitor))
        .collect::<Result<Vec<_>>>()?;
    views.sort_by(|a, b| a.entropy_rate.total_cmp(&b.entropy_rate));
    let uncertain = match (&views[0].phases, views.get(1)) {
        (Some(spread), Some(next)) => spread.range() > next.entropy_rate - views[0].entropy_rate,
        _ => false,
    };
    let refined = if eval.params.refine {
        Some(refine(&eval, &views, monitor)?)
    } else {
        None
    };
    Ok(ViewSearch {
        views,
        params: eval.params,
        uncertain,
        refined,
    })
}

/// How many of the best sphere axes [`refine`] starts from.
const REFINE_SEEDS: usize = 3;
/// The pattern search stops when its step falls below this angle, degrees.
const REFINE_STOP_DEGREES: f64 = 1.0;

/// A pattern search on the sphere from each of the best few axes: try the eight neighbours at
/// the current angular step, move to a better one or halve the step, until the step is below 1°.
fn refine(eval: &Evaluator, views: &[AxisEntropy], monitor: &Monitor) -> Result<AxisEntropy> {
    let start = icosphere::spacing_degrees(eval.params.level) / 2.0;
    let seeds = &views[..views.len().min(REFINE_SEEDS)];
    let per_step = eval.units(seeds[0].axis)? * 8;
    let steps = (start / REFINE_STOP_DEGREES).log2().ceil() as u64 + 4;
    monitor.start("refining", per_step * steps * seeds.len() as u64);
    let quiet = Monitor::new(None, None);
    let mut best: Option<AxisEntropy> = None;
    for seed in seeds {
        let mut here = seed.clone();
        let mut step = start;
        while step >= REFINE_STOP_DEGREES {
            let (_, u, v) = frame(here.axis)?;
            let t = step.to_radians().tan();
            let around: Vec<[f64; 3]> = [
                (-1.0, -1.0),
                (-1.0, 0.0),
                (-1.0, 1.0),
                (0.0, -1.0),
                (0.0, 1.0),
                (1.0, -1.0),
                (1.0, 0.0),
                (1.0, 1.0),
            ]
            .iter()
            .map(|&(a, b)| std::array::from_fn(|m| here.axis[m] + t * (a * u[m] + b * v[m])))
            .collect();
            let tried = around
                .par_iter()
                .map(|&axis| eval.evaluate(axis, &quiet))
                .collect::<Result<Vec<_>>>()?;
            monitor.advance(per_step)?;
            match tried
                .into_iter()
                .min_by(|a, b| a.entropy_rate.total_cmp(&b.entropy_rate))
            {
                Some(c) if c.entropy_rate < here.entropy_rate => here = c,
                _ => step /= 2.0,
            }
        }
        if best
            .as_ref()
            .is_none_or(|b| here.entropy_rate < b.entropy_rate)
        {
            best = Some(here);
        }
    }
    Ok(best.expect("at least one seed"))
}

/// The angle between two axes in degrees, ignoring their sign.
pub fn axis_angle(a: [f64; 3], b: [f64; 3]) -> f64 {
    let (a, b) = (normalize(a).unwrap_or(a), normalize(b).unwrap_or(b));
    dot(a, b).abs().clamp(0.0, 1.0).acos().to_degrees()
}
