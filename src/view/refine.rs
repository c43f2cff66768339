//! Refinement beyond the sphere's directions: a pattern search around the best few axes, by the
//! same score the ranking uses.

use rayon::prelude::*;

use super::{AxisEntropy, Evaluator, icosphere, score};
use crate::error::Result;
use crate::geometry::frame;
use crate::progress::Monitor;
use crate::volume::Voxel;

/// How many of the best sphere axes the refinement starts from.
const REFINE_SEEDS: usize = 3;
/// The pattern search stops when its step falls below this angle, degrees.
pub const REFINE_STOP_DEGREES: f64 = 1.0;

/// The pattern search's steps from a start of `start` degrees until it stops: the halvings, and
/// as many moves again as a bound for the progress bar.
pub fn refine_steps(start: f64) -> u64 {
    (start / REFINE_STOP_DEGREES).log2().ceil() as u64 + 4
}

/// The axes the refinement evaluates at most on icosphere level `level`: eight a step of the pattern
/// search from each seed, for a progress bar and a work estimate.
pub fn refine_evaluations(level: usize) -> u64 {
    let start = icosphere::spacing_degrees(level) / 2.0;
    REFINE_SEEDS as u64 * 8 * refine_steps(start)
}

/// A pattern search on the sphere from `seed`, whose axis `axis_of` gives: try the eight
/// neighbours at the current angular step (from `start` degrees), move to the one `better` than
/// the others and than here, or halve the step, until the step is below
/// [`REFINE_STOP_DEGREES`]. `evaluate` scores an axis (the neighbours of a step in parallel);
/// `stepped` runs after each step, for progress and cancellation.
pub fn pattern_search<T: Clone + Send>(
    seed: &T,
    start: f64,
    axis_of: impl Fn(&T) -> [f64; 3],
    evaluate: impl Fn([f64; 3]) -> Result<T> + Sync,
    better: impl Fn(&T, &T) -> bool,
    stepped: impl Fn() -> Result<()>,
) -> Result<T> {
    let mut here = seed.clone();
    let mut step = start;
    while step >= REFINE_STOP_DEGREES {
        let (_, u, v) = frame(axis_of(&here))?;
        let t = step.to_radians().tan();
        let centre = axis_of(&here);
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
        .map(|&(a, b)| std::array::from_fn(|m| centre[m] + t * (a * u[m] + b * v[m])))
        .collect();
        let tried = around
            .par_iter()
            .map(|&axis| evaluate(axis))
            .collect::<Result<Vec<_>>>()?;
        stepped()?;
        let best = tried
            .into_iter()
            .reduce(|a, b| if better(&b, &a) { b } else { a });
        match best {
            Some(c) if better(&c, &here) => here = c,
            _ => step /= 2.0,
        }
    }
    Ok(here)
}

/// The pattern search from each of the best few sphere axes, by the ranking's score; the best
/// axis any of them ends at.
pub(super) fn refine<T: Voxel>(
    eval: &Evaluator<T>,
    views: &[AxisEntropy],
    monitor: &Monitor,
) -> Result<AxisEntropy> {
    let start = icosphere::spacing_degrees(eval.params.level) / 2.0;
    let seeds = &views[..views.len().min(REFINE_SEEDS)];
    let per_step = eval.units(seeds[0].axis)? * 8;
    monitor.start(
        "refining",
        per_step * refine_steps(start) * seeds.len() as u64,
    );
    let quiet = Monitor::new(None, None);
    let better = |a: &AxisEntropy, b: &AxisEntropy| score(a) < score(b);
    let mut best: Option<AxisEntropy> = None;
    for seed in seeds {
        let here = pattern_search(
            seed,
            start,
            |a| a.axis,
            |axis| eval.evaluate(axis, &quiet),
            better,
            || monitor.advance(per_step),
        )?;
        if best.as_ref().is_none_or(|b| better(&here, b)) {
            best = Some(here);
        }
    }
    Ok(best.expect("at least one seed"))
}
