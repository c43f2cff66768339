//! Checkpoints of the cumulative histograms of long columns: a column of many runs (a long thin
//! volume's, or noise's) keeps its histogram up to every [`EVERY`]-th run, so that its histogram
//! over a slab costs two lookups and at most [`EVERY`] runs each, not one step per run of the
//! slab. Without them, merging the slices of a 1×1×200,000 volume of noise costs a step per
//! slice of each slab merged, quadratic in the slices.

use super::super::stack::MISSING;

/// Runs between two checkpoints: four times the bins, so that the checkpoints take at most a
/// byte a run (the runs themselves take five).
fn every(bins: usize) -> usize {
    4 * bins.max(1)
}

/// A column's runs, as [`Columns`](super::joints::Columns) lays them out: each run's first slice
/// and symbol, and the slice the column ends at.
#[derive(Clone, Copy)]
pub(super) struct Runs<'a> {
    pub firsts: &'a [u32],
    pub symbols: &'a [u8],
    pub end: u32,
}

impl Runs<'_> {
    /// The slice run `r` ends at.
    #[inline]
    fn end_of(&self, r: usize) -> u32 {
        self.firsts.get(r + 1).copied().unwrap_or(self.end)
    }

    /// The runs with a sample in slices `lo..hi`.
    pub fn within(&self, lo: u32, hi: u32) -> usize {
        let first = self.firsts.partition_point(|&f| f <= lo).saturating_sub(1);
        self.firsts.partition_point(|&f| f < hi) - first
    }
}

/// The checkpoints of the columns with at least `4 ·` [`every`] runs.
pub(super) struct Checkpoints {
    bins: usize,
    /// Per column: where its checkpoints start in `counts`, in histograms (`u32::MAX`: none).
    start: Vec<u32>,
    /// Checkpoint `c` of a column: the histogram of its runs `0 .. c · every`.
    counts: Vec<u32>,
}

impl Checkpoints {
    /// The checkpoints of the columns `runs` gives, of `bins` symbols (a missing sample is not
    /// counted).
    pub fn new<'a>(columns: usize, runs: impl Fn(usize) -> Runs<'a>, bins: usize) -> Self {
        let k = every(bins);
        let mut out = Self {
            bins,
            start: vec![u32::MAX; columns],
            counts: Vec::new(),
        };
        let mut running = vec![0u32; bins];
        for (i, start) in out.start.iter_mut().enumerate() {
            let column = runs(i);
            if column.firsts.len() < 4 * k {
                continue;
            }
            *start = (out.counts.len() / bins) as u32;
            running.fill(0);
            for (r, &s) in column.symbols.iter().enumerate() {
                if r % k == 0 {
                    out.counts.extend_from_slice(&running);
                }
                if s != MISSING {
                    running[usize::from(s)] += column.end_of(r) - column.firsts[r];
                }
            }
        }
        out
    }

    /// The bytes the checkpoints hold.
    pub fn held_bytes(&self) -> usize {
        std::mem::size_of_val(&self.start[..]) + std::mem::size_of_val(&self.counts[..])
    }

    /// Whether column `i`'s histogram over slices `lo..hi` is better taken from its checkpoints
    /// than run by run.
    #[inline]
    pub fn serve(&self, i: usize, runs: &Runs, (lo, hi): (u32, u32)) -> bool {
        self.start[i] != u32::MAX && runs.within(lo, hi) > 2 * every(self.bins) + self.bins
    }

    /// Column `i`'s histogram over slices `lo..hi`, added into `add(symbol, count)` bin by bin
    /// (in the order of the bins); `scratch` holds two histograms.
    pub fn histogram(
        &self,
        i: usize,
        runs: &Runs,
        (lo, hi): (u32, u32),
        scratch: &mut [u32],
        mut add: impl FnMut(u8, u32),
    ) {
        let (below, upto) = scratch.split_at_mut(self.bins);
        self.prefix(i, runs, lo, below);
        self.prefix(i, runs, hi, &mut upto[..self.bins]);
        for (s, (&a, &b)) in below.iter().zip(upto.iter()).enumerate() {
            if b > a {
                add(s as u8, b - a);
            }
        }
    }

    /// Column `i`'s histogram over its slices before `x`, into `out`.
    fn prefix(&self, i: usize, runs: &Runs, x: u32, out: &mut [u32]) {
        out.fill(0);
        // Runs `0..n` start before `x`; all but the last of them end before it.
        let n = runs.firsts.partition_point(|&f| f < x);
        let Some(last) = n.checked_sub(1) else {
            return;
        };
        let k = every(self.bins);
        let c = last / k;
        let at = (self.start[i] as usize + c) * self.bins;
        out.copy_from_slice(&self.counts[at..at + self.bins]);
        for r in c * k..=last {
            let s = runs.symbols[r];
            if s != MISSING {
                let end = if r == last {
                    runs.end_of(r).min(x)
                } else {
                    runs.end_of(r)
                };
                out[usize::from(s)] += end - runs.firsts[r];
            }
        }
    }
}
