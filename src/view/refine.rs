//! Refinement beyond the sphere's directions: a pattern search around the best few axes, by the
//! same score the ranking uses.

use rayon::prelude::*;

use super::{AxisEntropy, Evaluator, icosphere, score};
use crate::error::Result;
use crate::geometry::frame;
use crate::progress::Monitor;
use crate::volume::Voxel;

/// How many of the best sphere axes [`refine`] starts from.
const REFINE_SEEDS: usize = 3;
/// The pattern search stops when its step falls below this angle, degrees.
const REFINE_STOP_DEGREES: f64 = 1.0;

/// A pattern search on the sphere from each of the best few axes: try the eight neighbours at
/// the current angular step, move to a better one or halve the step, until the step is below 1°.
pub(super) fn refine<T: Voxel>(
    eval: &Evaluator<T>,
    views: &[AxisEntropy],
    monitor: &Monitor,
) -> Result<AxisEntropy> {
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
                .min_by(|a, b| score(a).total_cmp(&score(b)))
            {
                Some(c) if score(&c) < score(&here) => here = c,
                _ => step /= 2.0,
            }
        }
        if best.as_ref().is_none_or(|b| score(&here) < score(b)) {
            best = Some(here);
        }
    }
    Ok(best.expect("at least one seed"))
}
