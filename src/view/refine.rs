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

/// The state of a pattern search on the sphere: where it stands and its angular step. Each
/// step tries the eight neighbours at the current step ([`Pattern::around`]), then moves to the
/// one better than the others and than here, or halves the step ([`Pattern::take`]), until
/// the step is below [`REFINE_STOP_DEGREES`]. Several searches can take their steps in
/// lockstep, their neighbours evaluated together (as the view search counted slab by slab
/// does: a sweep over the volume a step), and end where each would alone.
#[derive(Clone, Debug)]
pub struct Pattern<T> {
    here: T,
    step: f64,
}

impl<T> Pattern<T> {
    /// A search from `seed`, with a step of `start` degrees.
    pub fn new(seed: T, start: f64) -> Self {
        Self {
            here: seed,
            step: start,
        }
    }

    /// Whether the search has ended.
    pub fn done(&self) -> bool {
        self.step < REFINE_STOP_DEGREES
    }

    /// Where the search stands.
    pub fn here(&self) -> &T {
        &self.here
    }

    /// Where the search ended (or stands).
    pub fn into_here(self) -> T {
        self.here
    }

    /// The eight neighbours of `centre` (the axis of [`Pattern::here`]) at the current step.
    pub fn around(&self, centre: [f64; 3]) -> Result<Vec<[f64; 3]>> {
        let (_, u, v) = frame(centre)?;
        let t = self.step.to_radians().tan();
        Ok([
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
        .collect())
    }

    /// Ends the step whose neighbours scored `tried` (in [`Pattern::around`]'s order): moves
    /// to the one `better` than the others and than here, or halves the step.
    pub fn take(&mut self, tried: Vec<T>, better: impl Fn(&T, &T) -> bool) {
        let best = tried
            .into_iter()
            .reduce(|a, b| if better(&b, &a) { b } else { a });
        match best {
            Some(c) if better(&c, &self.here) => self.here = c,
            _ => self.step /= 2.0,
        }
    }
}

/// A pattern search (`refine::Pattern`) from `seed`, whose axis `axis_of` gives, from a step of
/// `start` degrees: `evaluate` scores an axis (the neighbours of a step in parallel); `stepped`
/// runs after each step, for progress and cancellation.
pub fn pattern_search<T: Clone + Send>(
    seed: &T,
    start: f64,
    axis_of: impl Fn(&T) -> [f64; 3],
    evaluate: impl Fn([f64; 3]) -> Result<T> + Sync,
    better: impl Fn(&T, &T) -> bool,
    stepped: impl Fn() -> Result<()>,
) -> Result<T> {
    let mut search = Pattern::new(seed.clone(), start);
    while !search.done() {
        let around = search.around(axis_of(search.here()))?;
        let tried = around
            .par_iter()
            .map(|&axis| evaluate(axis))
            .collect::<Result<Vec<_>>>()?;
        stepped()?;
        search.take(tried, &better);
    }
    Ok(search.into_here())
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
    let ends = seeds
        .iter()
        .map(|seed| {
            pattern_search(
                seed,
                start,
                |a| a.axis,
                |axis| eval.evaluate(axis, &quiet),
                better,
                || monitor.advance(per_step),
            )
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(best_end(ends))
}

/// [`refine`]'s answer with its seeds' pattern searches taken in lockstep: at each step the
/// neighbours of every search still going are scored together by `evaluate_all` (which gives
/// one result an axis, in order), so that a search counted slab by slab sweeps the volume once
/// a step for all of them. Each search ends where it would alone.
pub(super) fn refine_in_lockstep(
    level: usize,
    views: &[AxisEntropy],
    mut evaluate_all: impl FnMut(&[[f64; 3]]) -> Result<Vec<AxisEntropy>>,
) -> Result<AxisEntropy> {
    let start = icosphere::spacing_degrees(level) / 2.0;
    let seeds = &views[..views.len().min(REFINE_SEEDS)];
    let mut searches: Vec<_> = seeds
        .iter()
        .map(|seed| Pattern::new(seed.clone(), start))
        .collect();
    loop {
        let (mut asked, mut going) = (Vec::new(), Vec::new());
        for (k, search) in searches.iter().enumerate().filter(|(_, s)| !s.done()) {
            asked.extend(search.around(search.here().axis)?);
            going.push(k);
        }
        if going.is_empty() {
            break;
        }
        let mut tried = evaluate_all(&asked)?.into_iter();
        for k in going {
            searches[k].take(tried.by_ref().take(8).collect(), better);
        }
    }
    Ok(best_end(searches.into_iter().map(Pattern::into_here)))
}

/// The refinement's order: the ranking's score, lowest best.
fn better(a: &AxisEntropy, b: &AxisEntropy) -> bool {
    score(a) < score(b)
}

/// The best of the seeds' searches' ends, the first of equals.
fn best_end(ends: impl IntoIterator<Item = AxisEntropy>) -> AxisEntropy {
    ends.into_iter()
        .reduce(|best, here| if better(&here, &best) { here } else { best })
        .expect("at least one seed")
}
