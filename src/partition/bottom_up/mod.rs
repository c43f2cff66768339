//! Bottom-up partitioning (paper §5.2, eq. 7 and 8): agglomerative merging of adjacent slabs by
//! normalized mutual information. The joint histogram of two slabs sums the joint histograms of
//! every pair of their slices over corresponding pixels; per pixel it factorizes as the outer
//! product of the two slabs' histograms there, `h(x, y) = Σ_p cA(p, x)·cB(p, y)`.
//! Those histograms and their NMI are `joints`; this is the merging.

mod checkpoints;
mod encoded;
mod joints;

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use serde::Serialize;

pub use self::joints::slice_nmi;
pub(crate) use self::joints::{
    Columns, PASS_BYTES, add_consecutive_joints, consecutive_nmi, nmi_of_joints,
};
use super::Slab;
use super::stack::SliceStack;
use crate::error::Result;
use crate::progress::Monitor;

/// One merge of the bottom-up history.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Merge {
    /// The two adjacent slabs merged.
    pub merge: (Slab, Slab),
    /// Their NMI, the largest of all adjacent pairs at that moment.
    pub nmi: f64,
    /// The NMI of every adjacent pair just before this merge, in slice order; kept only while
    /// at most [`PAIRS_KEPT`] slabs are left (empty before).
    #[serde(skip)]
    pub pairs: Vec<f64>,
}

/// The whole bottom-up history: merges until one slab is left.
#[derive(Clone, Debug, PartialEq)]
pub struct MergeHistory {
    /// Number of slices.
    pub slices: usize,
    /// The merges in the order they were taken.
    pub steps: Vec<Merge>,
    /// The NMI between each slice and the next.
    slice_nmi: Vec<f64>,
}

/// Steps keep the NMI of every adjacent pair only while there are at most this many slabs, so
/// that the history's memory stays linear in the slices (the pairs are what a viewer shows at
/// the end of the history, where few slabs are left).
pub const PAIRS_KEPT: usize = 1024;

/// A pair of adjacent slabs waiting to be merged, by its NMI and then (for ties) the lowest
/// left slab, so that a max-heap pops the merge docs/design.md §2 takes next. `stamp` tells a current
/// entry from a stale one left behind when a neighbour merged.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Pair {
    nmi: f64,
    left: usize,
    stamp: u64,
}

impl Eq for Pair {}

impl Ord for Pair {
    fn cmp(&self, other: &Self) -> Ordering {
        self.nmi
            .total_cmp(&other.nmi)
            .then_with(|| other.left.cmp(&self.left))
    }
}

impl PartialOrd for Pair {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

/// The slabs while merging: slab `i` (indexed by its first slice) ends at `end[i]` and
/// follows `prev[i]`; `nmi[i]` and `stamp[i]` are those of the pair it starts.
struct Chain {
    end: Vec<usize>,
    prev: Vec<usize>,
    nmi: Vec<f64>,
    stamp: Vec<u64>,
}

impl Chain {
    fn slab(&self, start: usize) -> Slab {
        (start, self.end[start])
    }

    /// The NMI of every adjacent pair, in slice order.
    fn pairs(&self, slices: usize) -> Vec<f64> {
        let mut out = Vec::new();
        let mut s = 0;
        while self.end[s] < slices {
            out.push(self.nmi[s]);
            s = self.end[s];
        }
        out
    }
}

impl MergeHistory {
    /// Merges the slices of `stack` until one slab is left, reporting one unit per merge.
    pub fn new(stack: &SliceStack, monitor: &Monitor) -> Result<Self> {
        Self::with_limit(stack, monitor, usize::MAX)
    }

    /// Like [`new`](Self::new), but stops after `limit` merges. The pairs wait in a heap: a merge
    /// costs two NMIs and a logarithm, whatever the number of slices.
    pub fn with_limit(stack: &SliceStack, monitor: &Monitor, limit: usize) -> Result<Self> {
        let n = stack.slices();
        monitor.start("bottom-up", n as u64);
        let columns = Columns::new(stack);
        let singles: Vec<Slab> = (0..n).map(|s| (s, s + 1)).collect();
        let slice_nmi = consecutive_nmi(stack, &columns, &singles, monitor)?;
        let mut chain = Chain {
            end: (1..=n).collect(),
            prev: (0..n).map(|s| s.saturating_sub(1)).collect(),
            nmi: slice_nmi.clone(),
            stamp: vec![0; n],
        };
        chain.nmi.resize(n, f64::NAN);
        let mut heap: BinaryHeap<Pair> = (0..n.saturating_sub(1))
            .map(|left| Pair {
                nmi: slice_nmi[left],
                left,
                stamp: 0,
            })
            .collect();
        let (mut steps, mut slabs) = (Vec::with_capacity(n.saturating_sub(1)), n);
        while steps.len() < limit
            && let Some(p) = heap.pop()
        {
            if p.stamp != chain.stamp[p.left] || chain.end[p.left] >= n {
                continue;
            }
            let (left, right) = (p.left, chain.end[p.left]);
            steps.push(Merge {
                merge: (chain.slab(left), chain.slab(right)),
                nmi: p.nmi,
                pairs: if slabs <= PAIRS_KEPT {
                    chain.pairs(n)
                } else {
                    Vec::new()
                },
            });
            let end = chain.end[right];
            chain.end[left] = end;
            if end < n {
                chain.prev[end] = left;
            }
            slabs -= 1;
            // The pairs the merged slab is in are new; the ones its parts were in are stale.
            let before = (left > 0).then(|| chain.prev[left]);
            for start in [Some(left), Some(right), before].into_iter().flatten() {
                chain.stamp[start] += 1;
            }
            // The slab before (if any), the merged one and the one after (if any), as one batch.
            let mut around: Vec<Slab> = before.into_iter().map(|b| chain.slab(b)).collect();
            around.push(chain.slab(left));
            if end < n {
                around.push(chain.slab(end));
            }
            let fresh = consecutive_nmi(stack, &columns, &around, &Monitor::none())?;
            for (w, nmi) in around.windows(2).zip(fresh) {
                let start = w[0].0;
                chain.nmi[start] = nmi;
                heap.push(Pair {
                    nmi,
                    left: start,
                    stamp: chain.stamp[start],
                });
            }
            monitor.advance(1)?;
        }
        Ok(Self {
            slices: n,
            steps,
            slice_nmi,
        })
    }

    /// The slabs after the first `steps` merges, in slice order: each merge removes the boundary
    /// at the start of its right slab.
    pub fn slabs_after(&self, steps: usize) -> Vec<Slab> {
        let mut boundary = vec![true; self.slices + 1];
        for m in self.steps.iter().take(steps) {
            boundary[m.merge.1.0] = false;
        }
        let starts: Vec<usize> = (0..=self.slices).filter(|&b| boundary[b]).collect();
        starts.windows(2).map(|w| (w[0], w[1])).collect()
    }

    /// The slabs of a `k`-slab partition (clamped to 1 ..= slices).
    pub fn slabs(&self, k: usize) -> Vec<Slab> {
        self.slabs_after(self.slices - k.clamp(1, self.slices))
    }

    /// How many merges are taken before the largest NMI falls below `threshold`.
    pub fn steps_above(&self, threshold: f64) -> usize {
        self.steps.iter().take_while(|s| s.nmi >= threshold).count()
    }

    /// The NMI between each slice and the next.
    pub fn slice_nmi(&self) -> &[f64] {
        &self.slice_nmi
    }

    /// A history of `slices` slices that took `steps`, for tests of what reads histories.
    #[cfg(test)]
    pub(crate) fn of_steps(slices: usize, steps: Vec<Merge>) -> Self {
        Self {
            slices,
            steps,
            slice_nmi: Vec::new(),
        }
    }
}

#[cfg(test)]
mod tests;
