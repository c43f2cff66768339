//! Top-down partitioning (paper §5.1, eq. 5 and 6): greedy information-bottleneck splits. Each
//! step takes, over all current slabs and all cuts strictly inside them, the cut with the largest
//! gain `ΔI = (v1 + v2)/v_T · JS(v1/(v1+v2), v2/(v1+v2); p1, p2)`; ties go to the lowest slice.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use serde::Serialize;

use super::{Slab, prefix_histograms};
use crate::measure::scaled_entropy;

/// One split of the top-down history.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Split {
    /// The slab that was split.
    pub split: Slab,
    /// The first slice of the second part.
    pub at: usize,
    /// `ΔI` of this cut, bits.
    pub gain: f64,
    /// `I(slab; intensity)` after this split, bits.
    pub information: f64,
}

/// The top-down history: splits until every slab is one slice (or a limit). Its memory is linear
/// in the slices: each step keeps its gain, and a curve is computed when asked for.
#[derive(Clone, Debug, PartialEq)]
pub struct SplitHistory {
    /// Number of slices.
    pub slices: usize,
    /// The splits in the order they were taken.
    pub steps: Vec<Split>,
    /// `H(intensity)` of the whole stack, the most information any partition can keep, bits.
    pub entropy: f64,
    /// `ΔI` of cutting the whole stack at each slice 1 .. slices.
    gain_curve: Vec<f64>,
}

/// Gains of splitting slabs, from per-slice histograms.
pub(crate) struct Gains {
    prefix: Vec<u64>,
    bins: usize,
    total: f64,
}

impl Gains {
    /// From `slices × bins` histograms.
    pub(crate) fn new(histograms: &[u64], bins: usize) -> Self {
        let prefix = prefix_histograms(histograms, bins);
        let slices = histograms.len() / bins;
        let total = prefix[slices * bins..].iter().sum::<u64>() as f64;
        Self {
            prefix,
            bins,
            total,
        }
    }

    /// `N·H` of slab `[a, b)`.
    pub(crate) fn scaled(&self, a: usize, b: usize) -> f64 {
        let (lo, hi) = (
            &self.prefix[a * self.bins..(a + 1) * self.bins],
            &self.prefix[b * self.bins..(b + 1) * self.bins],
        );
        scaled_entropy(hi.iter().zip(lo).map(|(h, l)| h - l))
    }

    /// `F / v_T`: a difference of scaled entropies as bits of the whole stack (0 when the stack
    /// counts no sample; never negative, which only rounding could make it).
    pub(crate) fn bits(&self, f: f64) -> f64 {
        if self.total > 0.0 {
            (f / self.total).max(0.0)
        } else {
            0.0
        }
    }

    /// `ΔI` of the cut at `c` of slab `[a, b)` (eq. 6), which is also the information lost by
    /// merging `[a, c)` and `[c, b)`: `(F(a,b) - F(a,c) - F(c,b)) / v_T`.
    pub(crate) fn merge_loss(&self, a: usize, c: usize, b: usize) -> f64 {
        self.bits(self.scaled(a, b) - self.scaled(a, c) - self.scaled(c, b))
    }

    /// `I(slab; intensity)` of a partition of the whole stack: `(F(all) - Σ F(slab)) / v_T`.
    pub(crate) fn information(&self, slabs: &[Slab]) -> f64 {
        let slices = self.prefix.len() / self.bins - 1;
        let parts: f64 = slabs.iter().map(|&(a, b)| self.scaled(a, b)).sum();
        self.bits(self.scaled(0, slices) - parts)
    }

    /// `ΔI` of every cut strictly inside `[a, b)`.
    pub(crate) fn curve(&self, a: usize, b: usize) -> Vec<f64> {
        if self.total == 0.0 {
            return vec![0.0; b.saturating_sub(a + 1)];
        }
        let whole = self.scaled(a, b);
        (a + 1..b)
            .map(|c| self.bits(whole - self.scaled(a, c) - self.scaled(c, b)))
            .collect()
    }
}

/// A slab waiting to be split, with its best cut: ordered by gain, then (for ties) by the lowest
/// cut, so that a max-heap pops the split docs/design.md §2 takes next.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Candidate {
    gain: f64,
    at: usize,
    slab: Slab,
}

impl Eq for Candidate {}

impl Ord for Candidate {
    fn cmp(&self, other: &Self) -> Ordering {
        self.gain
            .total_cmp(&other.gain)
            .then_with(|| other.at.cmp(&self.at))
    }
}

impl PartialOrd for Candidate {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Gains {
    /// The best cut of `[a, b)`: the largest `ΔI`, the lowest slice on ties; `None` for one slice.
    fn best_cut(&self, (a, b): Slab) -> Option<Candidate> {
        let whole = self.scaled(a, b);
        let mut best: Option<Candidate> = None;
        for c in a + 1..b {
            let gain = self.bits(whole - self.scaled(a, c) - self.scaled(c, b));
            if best.is_none_or(|x| gain > x.gain) {
                best = Some(Candidate {
                    gain,
                    at: c,
                    slab: (a, b),
                });
            }
        }
        best
    }
}

impl SplitHistory {
    /// Splits the stack with per-slice `histograms` (`slices × bins`) until every slab is one slice.
    pub fn new(histograms: &[u64], bins: usize) -> Self {
        Self::with_limit(histograms, bins, usize::MAX)
    }

    /// Like [`new`](Self::new), but stops after `limit` splits.
    ///
    /// Each slab's best cut is found once, when the slab is made, and the slabs wait in a heap:
    /// a step costs the length of the slab it splits.
    pub fn with_limit(histograms: &[u64], bins: usize, limit: usize) -> Self {
        let slices = histograms.len() / bins;
        let gains = Gains::new(histograms, bins);
        let entropy = gains.bits(gains.scaled(0, slices));
        let gain_curve = gains.curve(0, slices);
        let mut heap: BinaryHeap<Candidate> = gains.best_cut((0, slices)).into_iter().collect();
        let mut steps = Vec::with_capacity(slices.saturating_sub(1).min(limit));
        let mut information = 0.0;
        while steps.len() < limit
            && let Some(c) = heap.pop()
        {
            let (a, b) = c.slab;
            information += c.gain;
            heap.extend(gains.best_cut((a, c.at)));
            heap.extend(gains.best_cut((c.at, b)));
            steps.push(Split {
                split: c.slab,
                at: c.at,
                gain: c.gain,
                information,
            });
        }
        Self {
            slices,
            steps,
            entropy,
            gain_curve,
        }
    }

    /// The slabs after the first `steps` splits, in slice order.
    pub fn slabs_after(&self, steps: usize) -> Vec<Slab> {
        let mut cuts: Vec<usize> = self.steps.iter().take(steps).map(|s| s.at).collect();
        cuts.sort_unstable();
        let mut bounds = vec![0];
        bounds.extend(cuts);
        bounds.push(self.slices);
        bounds.windows(2).map(|w| (w[0], w[1])).collect()
    }

    /// The slabs of a `k`-slab partition (clamped to 1 ..= slices).
    pub fn slabs(&self, k: usize) -> Vec<Slab> {
        self.slabs_after(k.clamp(1, self.slices) - 1)
    }

    /// How many splits are taken before the best gain falls below `threshold`.
    pub fn steps_above(&self, threshold: f64) -> usize {
        self.steps
            .iter()
            .take_while(|s| s.gain >= threshold)
            .count()
    }

    /// `I(slab; intensity)` of the `k`-slab partition, bits (of the last one the history has,
    /// when it stopped short of `k`).
    pub fn information(&self, k: usize) -> f64 {
        match (k.clamp(1, self.slices) - 1).min(self.steps.len()) {
            0 => 0.0,
            n => self.steps[n - 1].information,
        }
    }

    /// The gain of every cut of the whole stack: the first split's curve.
    pub fn gain_curve(&self) -> &[f64] {
        &self.gain_curve
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Histograms of slices that each hold `n` voxels of one material.
    fn materials(of_slice: &[usize], bins: usize, n: u64) -> Vec<u64> {
        of_slice
            .iter()
            .flat_map(|&m| (0..bins).map(move |b| if b == m { n } else { 0 }))
            .collect()
    }

    #[test]
    fn a_sharp_boundary_is_the_first_cut_worth_one_bit() {
        let h = materials(&[0, 0, 0, 0, 1, 1, 1, 1], 4, 10);
        let t = SplitHistory::new(&h, 4);
        assert_eq!(t.steps[0].split, (0, 8));
        assert_eq!(t.steps[0].at, 4);
        assert!((t.steps[0].gain - 1.0).abs() < 1e-12);
        assert_eq!(t.slabs(2), vec![(0, 4), (4, 8)]);
        assert!((t.entropy - 1.0).abs() < 1e-12);
        // Every later split gains nothing.
        assert!(t.steps[1..].iter().all(|s| s.gain.abs() < 1e-12));
        assert_eq!(t.steps.len(), 7);
    }

    #[test]
    fn ties_go_to_the_lowest_slice() {
        // Three equal thirds of three materials: cuts at 2 and 4 gain the same.
        let h = materials(&[0, 0, 1, 1, 2, 2], 3, 5);
        let t = SplitHistory::new(&h, 3);
        assert_eq!(t.steps[0].at, 2);
        assert_eq!(t.steps[1].at, 4);
        assert!((t.information(3) - 3f64.log2()).abs() < 1e-12);
    }

    #[test]
    fn curves_cover_every_cut_and_information_adds_up() {
        let h = materials(&[0, 1, 1, 2, 0, 3, 3], 4, 3);
        let t = SplitHistory::new(&h, 4);
        assert_eq!(t.gain_curve().len(), 6);
        let mut sum = 0.0;
        for s in &t.steps {
            sum += s.gain;
            assert!((s.information - sum).abs() < 1e-12);
        }
        // Splitting into single slices keeps everything: I = H(X) when slices are pure.
        assert!((t.information(7) - t.entropy).abs() < 1e-12);
        assert_eq!(
            t.steps_above(0.5),
            t.steps.iter().take_while(|s| s.gain >= 0.5).count()
        );
    }
}
