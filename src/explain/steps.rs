//! The numbers behind each step of a partition: a top-down split's two parts and their
//! Jensen-Shannon divergence (paper eq. 5, 6), a bottom-up merge's joint histogram and NMI
//! (eq. 7, 8), and the optimum against greedy splitting.

use serde::Serialize;

use crate::error::{Error, Result};
use crate::measure::{entropy, mutual_information};
use crate::partition::{Histories, Slab};
use crate::progress::Monitor;

/// Why top-down took one split: the histograms it compared and the gain they give.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SplitLesson {
    /// The step's number, from 1.
    pub step: usize,
    /// The slab split, `[first, end)` slices.
    pub split: Slab,
    /// The first slice of the second part.
    pub at: usize,
    /// The histogram of the first part's samples (background left out), one count a bin.
    pub first: Vec<u64>,
    /// The second part's.
    pub second: Vec<u64>,
    /// Their union: the slab's.
    pub union: Vec<u64>,
    /// The parts' samples, `v1` and `v2`.
    pub samples: [u64; 2],
    /// The whole stack's samples, `v_T`.
    pub total: u64,
    /// `π_i = v_i / (v1 + v2)`.
    pub weights: [f64; 2],
    /// `H(p1)`, `H(p2)` and `H(union)`, bits.
    pub entropies: [f64; 3],
    /// `JS = H(union) - π1·H(p1) - π2·H(p2)`, bits.
    pub js: f64,
    /// `ΔI = (v1 + v2) / v_T · JS`, bits: the step's gain.
    pub gain: f64,
    /// `ΔI` of every cut inside the slab: entry `i` cuts at slice `split.0 + 1 + i`.
    pub gains: Vec<f64>,
    /// `I(slab; value)` after the step, bits.
    pub information: f64,
}

/// Why bottom-up took one merge: the two slabs' joint histogram and its NMI.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MergeLesson {
    /// The step's number, from 1.
    pub step: usize,
    /// The two adjacent slabs merged.
    pub merge: (Slab, Slab),
    /// Quantization bins: the joint histogram is `bins × bins`.
    pub bins: usize,
    /// The non-zero cells of their joint histogram: `[x, y, count]`, x the first slab's bin
    /// and y the second's at corresponding pixels, in order of x then y.
    pub joint: Vec<[u64; 3]>,
    /// `H(X)`, `H(Y)` (of the joint histogram's margins) and `H(X,Y)`, bits.
    pub h_x: f64,
    /// `H(Y)`, bits.
    pub h_y: f64,
    /// `H(X,Y)`, bits.
    pub h_xy: f64,
    /// `MI = H(X) + H(Y) - H(X,Y)`, bits.
    pub mi: f64,
    /// `NMI = MI / H(X,Y)`: the step's score, the largest of all adjacent pairs.
    pub nmi: f64,
    /// The pair with the next largest NMI at that step, when the history kept the pairs.
    pub runner_up: Option<RunnerUp>,
}

/// The pair of slabs bottom-up would have merged next.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RunnerUp {
    /// The two slabs.
    pub merge: (Slab, Slab),
    /// Their NMI.
    pub nmi: f64,
}

/// What the optimal partition maximises, beside greedy top-down's at the same slab count.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct OptimalLesson {
    /// The slab count.
    pub slabs: usize,
    /// `I(slab; value)` of the optimum, bits: the most any partition into this many slabs keeps.
    pub optimal: f64,
    /// `I(slab; value)` of top-down's partition into as many slabs, bits.
    pub greedy: f64,
    /// The optimum's inner boundaries (the first slice of every slab but the first).
    pub optimal_boundaries: Vec<usize>,
    /// Top-down's inner boundaries.
    pub greedy_boundaries: Vec<usize>,
}

/// The lesson of top-down's split number `step` (from 1).
pub fn split_lesson(histories: &Histories, step: usize) -> Result<SplitLesson> {
    let taken = histories.top().steps.len();
    let split = step
        .checked_sub(1)
        .and_then(|i| histories.top().steps.get(i))
        .ok_or_else(|| Error::invalid("step", step, format!("1 to {taken} (the splits taken)")))?;
    let ((a, b), c) = (split.split, split.at);
    let first = histories.slab_histogram((a, c));
    let second = histories.slab_histogram((c, b));
    let union: Vec<u64> = first.iter().zip(&second).map(|(x, y)| x + y).collect();
    let total = histories
        .slab_histogram((0, histories.slices()))
        .iter()
        .sum();
    let (v1, v2) = (first.iter().sum::<u64>(), second.iter().sum::<u64>());
    let v = (v1 + v2).max(1) as f64;
    let weights = [v1 as f64 / v, v2 as f64 / v];
    let h = |c: &[u64]| entropy(c.iter().copied());
    let entropies = [h(&first), h(&second), h(&union)];
    let js = (entropies[2] - weights[0] * entropies[0] - weights[1] * entropies[1]).max(0.0);
    Ok(SplitLesson {
        step,
        split: (a, b),
        at: c,
        samples: [v1, v2],
        total,
        weights,
        entropies,
        js,
        gain: if total > 0 {
            (v1 + v2) as f64 / total as f64 * js
        } else {
            0.0
        },
        gains: histories.cut_gains((a, b)),
        information: split.information,
        first,
        second,
        union,
    })
}

/// The lessons of bottom-up's merges number `steps` (from 1): the stack's columns sorted once,
/// then one pass over them a merge for its joint histogram.
pub fn merge_lessons(
    histories: &Histories,
    steps: std::ops::RangeInclusive<usize>,
    monitor: &Monitor,
) -> Result<Vec<MergeLesson>> {
    let bottom = histories
        .bottom()
        .ok_or_else(|| Error::invalid("method", "bottom-up", "a history that was computed"))?;
    let taken = bottom.steps.len();
    let merges = steps
        .clone()
        .map(|step| {
            step.checked_sub(1)
                .and_then(|i| bottom.steps.get(i))
                .ok_or_else(|| {
                    Error::invalid("step", step, format!("1 to {taken} (the merges taken)"))
                })
        })
        .collect::<Result<Vec<_>>>()?;
    monitor.start("joint histograms", merges.len() as u64);
    let pairs: Vec<(Slab, Slab)> = merges.iter().map(|m| m.merge).collect();
    let joints = histories.joint_histograms(&pairs, monitor)?;
    let bins = histories.stack().bins();
    Ok(steps
        .zip(merges)
        .zip(joints)
        .map(|((step, merge), joint)| {
            let (mi, h_xy) = mutual_information(&joint, bins, bins);
            let rows: Vec<u64> = joint.chunks_exact(bins).map(|r| r.iter().sum()).collect();
            let columns: Vec<u64> = (0..bins)
                .map(|c| joint.iter().skip(c).step_by(bins).sum())
                .collect();
            let cells = joint
                .iter()
                .enumerate()
                .filter(|(_, n)| **n > 0)
                .map(|(k, &n)| [(k / bins) as u64, (k % bins) as u64, n])
                .collect();
            MergeLesson {
                step,
                merge: merge.merge,
                bins,
                joint: cells,
                h_x: entropy(rows),
                h_y: entropy(columns),
                h_xy,
                mi,
                nmi: merge.nmi,
                runner_up: runner_up(histories, step - 1),
            }
        })
        .collect())
}

/// The step (numbered from 1) of the merge of the highest NMI among `steps` in order, each a
/// merge's NMI or `None` for a step that is no merge; the first on ties: the example the lesson
/// and the tour's export show, two slabs nearly alike, where the last merge may join slabs
/// barely alike. `None` when no step is a merge.
pub fn highest_nmi_merge(steps: impl IntoIterator<Item = Option<f64>>) -> Option<usize> {
    steps
        .into_iter()
        .enumerate()
        .filter_map(|(i, nmi)| Some((i + 1, nmi?)))
        .fold(None, |best: Option<(usize, f64)>, (step, nmi)| match best {
            Some((_, top)) if top >= nmi => best,
            _ => Some((step, nmi)),
        })
        .map(|(step, _)| step)
}

/// The merge the lesson and the tour's export show as the example of slabs alike, among `steps`
/// in order (each a merge's NMI, or `None` for a step that is no merge): the first of the
/// highest NMI below 1 ([`highest_nmi_merge`]). Two constant slabs, or slabs whose paired
/// samples are each of one bin, have a joint histogram of one cell, `H(X,Y) = 0`, and NMI 1 by
/// convention (0/0): nothing to show, and a perfect copy's diagonal is shown as well by the
/// nearly perfect pair below it. The first of the highest NMI of all when every merge's is 1;
/// `None` when no step is a merge.
pub fn example_merge(steps: &[Option<f64>]) -> Option<usize> {
    let below_one = steps.iter().map(|nmi| nmi.filter(|&v| v < 1.0));
    highest_nmi_merge(below_one).or_else(|| highest_nmi_merge(steps.iter().copied()))
}

/// The lesson of bottom-up's merge number `step` (from 1): one pass over the stack for the
/// joint histogram.
pub fn merge_lesson(histories: &Histories, step: usize, monitor: &Monitor) -> Result<MergeLesson> {
    Ok(merge_lessons(histories, step..=step, monitor)?.remove(0))
}

/// The pair with the second largest NMI just before merge `index` (from 0), from the pairs the
/// history kept (the first largest on ties, as merging takes the lowest).
fn runner_up(histories: &Histories, index: usize) -> Option<RunnerUp> {
    let bottom = histories.bottom()?;
    let pairs = &bottom.steps[index].pairs;
    let slabs = bottom.slabs_after(index);
    let taken = slabs
        .iter()
        .position(|s| *s == bottom.steps[index].merge.0)?;
    let (i, nmi) = pairs.iter().enumerate().filter(|(i, _)| *i != taken).fold(
        None,
        |best: Option<(usize, f64)>, (i, &n)| match best {
            Some((_, b)) if b >= n => best,
            _ => Some((i, n)),
        },
    )?;
    Some(RunnerUp {
        merge: (slabs[i], slabs[i + 1]),
        nmi,
    })
}

/// The optimum into `slabs` slabs beside top-down's, when the optimum was computed for it.
pub fn optimal_lesson(histories: &Histories, slabs: usize) -> Option<OptimalLesson> {
    let optimum = histories.optimal()?.by_count.get(slabs.checked_sub(1)?)?;
    let greedy = histories.top().slabs(slabs);
    let inner = |s: &[Slab]| s.iter().skip(1).map(|s| s.0).collect::<Vec<_>>();
    Some(OptimalLesson {
        slabs,
        optimal: optimum.information,
        greedy: histories.information(&greedy),
        optimal_boundaries: inner(&optimum.slabs),
        greedy_boundaries: inner(&greedy),
    })
}

#[cfg(test)]
mod tests {
    use super::{example_merge, highest_nmi_merge};
    use crate::partition::{Histories, Scope, SliceStack};
    use crate::progress::Monitor;

    #[test]
    fn the_highest_nmi_merge_is_the_first_of_equals_among_merges() {
        assert_eq!(
            highest_nmi_merge([Some(0.2), Some(0.7), Some(0.7), Some(0.1)]),
            Some(2)
        );
        // Steps that are no merge count in the numbering, never as the example.
        assert_eq!(
            highest_nmi_merge([None, Some(0.3), None, Some(0.5)]),
            Some(4)
        );
        assert_eq!(highest_nmi_merge([None, None]), None);
        assert_eq!(highest_nmi_merge(std::iter::empty()), None);
    }

    #[test]
    fn the_example_merge_passes_over_an_nmi_of_one() {
        // A merge of two constant slabs (NMI 1 by convention, H(X,Y) = 0) before the highest
        // below 1; steps that are no merge count in the numbering.
        assert_eq!(
            example_merge(&[Some(0.4), Some(1.0), None, Some(0.9), Some(0.9), Some(1.0)]),
            Some(4)
        );
        // Only merges of NMI 1 yet: the first of them; no merge: none.
        assert_eq!(example_merge(&[None, Some(1.0), Some(1.0)]), Some(2));
        assert_eq!(example_merge(&[None]), None);
        assert_eq!(example_merge(&[]), None);
    }

    #[test]
    fn constant_slabs_merge_at_an_nmi_of_one() {
        // Two constant slices of two bins, two slices of two bins partly alike: bottom-up first joins
        // the constant ones, NMI 1 by convention, and the example is the other two's.
        let slices = [
            vec![0, 0, 0, 0],
            vec![3, 3, 3, 3],
            vec![1, 2, 1, 2],
            vec![1, 2, 1, 1],
        ];
        let stack = SliceStack::from_slices(&slices, 4).unwrap();
        let h = Histories::of_stack(stack, Scope::ALL, &Monitor::none()).unwrap();
        let steps = &h.bottom().unwrap().steps;
        assert_eq!((steps[0].merge, steps[0].nmi), (((0, 1), (1, 2)), 1.0));
        assert_eq!(steps[1].merge, ((2, 3), (3, 4)));
        assert!(steps[1].nmi > 0.0 && steps[1].nmi < 1.0, "{}", steps[1].nmi);
        let nmis: Vec<_> = steps.iter().map(|s| Some(s.nmi)).collect();
        assert_eq!(highest_nmi_merge(nmis.iter().copied()), Some(1));
        assert_eq!(example_merge(&nmis), Some(2));
    }
}
