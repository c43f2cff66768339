//! Bottom-up partitioning (paper §5.2, eq. 7 and 8): agglomerative merging of adjacent slabs by
//! normalized mutual information. The joint histogram of two slabs sums the joint histograms of
//! every pair of their slices over corresponding pixels; per pixel it factorizes as the outer
//! product of the two slabs' histograms there, `h(x, y) = Σ_p cA(p, x)·cB(p, y)`.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use rayon::prelude::*;
use serde::Serialize;

use super::Slab;
use super::stack::{MISSING, SliceStack};
use crate::error::Result;
use crate::measure::normalized_mutual_information;
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

/// A slab's histogram at one pixel: counts per bin and the bins in use.
struct PixelHistogram {
    counts: Vec<u32>,
    used: Vec<u8>,
}

impl PixelHistogram {
    fn new(bins: usize) -> Self {
        Self {
            counts: vec![0; bins],
            used: Vec::with_capacity(bins),
        }
    }

    fn clear(&mut self) {
        for &u in &self.used {
            self.counts[usize::from(u)] = 0;
        }
        self.used.clear();
    }

    #[inline]
    fn add(&mut self, symbol: u8, n: u32) {
        let c = &mut self.counts[usize::from(symbol)];
        if *c == 0 {
            self.used.push(symbol);
        }
        *c += n;
    }

    fn fill(&mut self, symbols: &[u8]) {
        self.clear();
        for &s in symbols {
            if s != MISSING {
                self.add(s, 1);
            }
        }
    }

    /// Adds `other ⊗ self` into the `bins × bins` joint histogram `h` (rows are `other`'s bins).
    fn cross_into(&self, other: &Self, h: &mut [u64], bins: usize) {
        for &x in &other.used {
            let cx = u64::from(other.counts[usize::from(x)]);
            let row = &mut h[usize::from(x) * bins..(usize::from(x) + 1) * bins];
            for &y in &self.used {
                row[usize::from(y)] += cx * u64::from(self.counts[usize::from(y)]);
            }
        }
    }
}

/// Columns a task of [`Columns::new`] fills.
const COLUMN_BLOCK: usize = 1024;

/// Bytes of joint histograms one pass may hold per thread.
const PASS_BYTES: usize = 32 << 20;

/// The stack's columns sorted for joint histograms: columns of one symbol throughout (air, empty
/// background) are grouped by symbol and valid range, since each contributes to one cell without
/// being read; the others are read.
pub(crate) struct Columns {
    /// Pixels whose column holds more than one symbol, or missing samples.
    active: Vec<u32>,
    /// Constant columns: (symbol, first slice, slices, how many pixels).
    constant: Vec<(u8, usize, usize, u64)>,
    /// The active columns as runs of one symbol: active column `i` has the runs
    /// `run_start[i] .. run_start[i + 1]`, each from slice `run_first[r]` to the next run's first
    /// (or `run_end[i]`), of symbol `run_symbol[r]`.
    run_start: Vec<usize>,
    run_first: Vec<u32>,
    run_symbol: Vec<u8>,
    run_end: Vec<u32>,
}

impl Columns {
    pub(crate) fn new(stack: &SliceStack) -> Self {
        let n = stack.slices();
        let (active, constant): (Vec<u32>, Vec<(u8, usize, usize)>) = (0..stack.pixels())
            .into_par_iter()
            .fold(
                || (Vec::new(), Vec::new()),
                |(mut active, mut constant), p| {
                    let (first, column) = stack.column(p, 0, n);
                    match column.first() {
                        Some(&s) if s != MISSING && column.iter().all(|&c| c == s) => {
                            constant.push((s, first, column.len()));
                        }
                        Some(_) => active.push(p as u32),
                        None => {}
                    }
                    (active, constant)
                },
            )
            .reduce(
                || (Vec::new(), Vec::new()),
                |(mut a, mut c), (b, d)| {
                    a.extend(b);
                    c.extend(d);
                    (a, c)
                },
            );
        let mut groups: std::collections::HashMap<(u8, usize, usize), u64> =
            std::collections::HashMap::new();
        for key in constant {
            *groups.entry(key).or_insert(0) += 1;
        }
        let mut constant: Vec<_> = groups
            .into_iter()
            .map(|((s, f, l), c)| (s, f, l, c))
            .collect();
        constant.sort_unstable();
        let mut active = active;
        active.sort_unstable();
        // Two passes, so that the runs are written once, in place: count each column's runs,
        // then fill the arrays, a block of columns a task.
        let runs = |p: u32| {
            let (_, column) = stack.column(p as usize, 0, n);
            1 + column.windows(2).filter(|w| w[0] != w[1]).count()
        };
        let counts: Vec<usize> = active.par_iter().map(|&p| runs(p)).collect();
        let mut run_start = Vec::with_capacity(active.len() + 1);
        run_start.push(0);
        for c in &counts {
            run_start.push(run_start.last().copied().unwrap_or(0) + c);
        }
        drop(counts);
        let total = run_start.last().copied().unwrap_or(0);
        let (mut run_first, mut run_symbol) = (vec![0u32; total], vec![0u8; total]);
        let mut run_end = vec![0u32; active.len()];
        let mut tasks = Vec::with_capacity(active.len().div_ceil(COLUMN_BLOCK));
        let (mut firsts, mut symbols) = (&mut run_first[..], &mut run_symbol[..]);
        for (b, (columns, ends)) in active
            .chunks(COLUMN_BLOCK)
            .zip(run_end.chunks_mut(COLUMN_BLOCK))
            .enumerate()
        {
            let len = run_start[b * COLUMN_BLOCK + columns.len()] - run_start[b * COLUMN_BLOCK];
            let (f, rest_f) = std::mem::take(&mut firsts).split_at_mut(len);
            let (s, rest_s) = std::mem::take(&mut symbols).split_at_mut(len);
            (firsts, symbols) = (rest_f, rest_s);
            tasks.push((columns, ends, f, s));
        }
        tasks.into_par_iter().for_each(|(columns, ends, f, s)| {
            let mut at = 0;
            for (&p, end) in columns.iter().zip(ends) {
                let (first, column) = stack.column(p as usize, 0, n);
                for (k, &c) in column.iter().enumerate() {
                    if k == 0 || column[k - 1] != c {
                        f[at] = (first + k) as u32;
                        s[at] = c;
                        at += 1;
                    }
                }
                *end = (first + column.len()) as u32;
            }
        });
        Self {
            active,
            constant,
            run_start,
            run_first,
            run_symbol,
            run_end,
        }
    }

    /// The symbol of active column `i` when one run covers all of slices `lo..hi`.
    #[inline]
    fn single_run(&self, i: usize, lo: usize, hi: usize) -> Option<u8> {
        let runs = self.run_start[i]..self.run_start[i + 1];
        let firsts = &self.run_first[runs.clone()];
        let r = firsts
            .partition_point(|&f| f as usize <= lo)
            .checked_sub(1)?;
        let end = firsts.get(r + 1).copied().unwrap_or(self.run_end[i]) as usize;
        (end >= hi).then(|| self.run_symbol[runs][r])
    }

    /// Fills `hists[j]` with active column `i`'s histogram over `slabs[j]` (contiguous slabs),
    /// from its runs: the work is the number of runs, not of slices.
    fn fill_from_runs(&self, i: usize, slabs: &[Slab], hists: &mut [PixelHistogram]) {
        for h in hists.iter_mut() {
            h.clear();
        }
        let (lo, hi) = (slabs[0].0 as u32, slabs[slabs.len() - 1].1 as u32);
        let runs = self.run_start[i]..self.run_start[i + 1];
        let firsts = &self.run_first[runs.clone()];
        let symbols = &self.run_symbol[runs];
        let end = self.run_end[i];
        let mut r = firsts.partition_point(|&f| f <= lo).saturating_sub(1);
        let mut j = 0;
        while r < firsts.len() && firsts[r] < hi {
            let run_end = firsts.get(r + 1).copied().unwrap_or(end).min(hi);
            let mut from = firsts[r].max(lo);
            if symbols[r] != MISSING {
                while from < run_end {
                    while slabs[j].1 as u32 <= from {
                        j += 1;
                    }
                    let to = run_end.min(slabs[j].1 as u32);
                    hists[j].add(symbols[r], to - from);
                    from = to;
                }
            }
            r += 1;
        }
    }
}

/// The joint histograms `h(S_i, S_i+1)` of consecutive slabs of `slabs` (contiguous, in order),
/// each `bins × bins`. Many pairs are split among the threads, each pair's histogram made once;
/// a few pairs (a merge step) split the pixels instead.
fn consecutive_joints(stack: &SliceStack, columns: &Columns, slabs: &[Slab]) -> Vec<Vec<u64>> {
    let pairs = slabs.len().saturating_sub(1);
    let threads = rayon::current_num_threads();
    if pairs >= 4 * threads {
        let per = pairs.div_ceil(2 * threads);
        let blocks: Vec<Vec<Vec<u64>>> = (0..pairs)
            .step_by(per)
            .collect::<Vec<_>>()
            .into_par_iter()
            .map(|first| {
                joints_over_pixels(
                    stack,
                    columns,
                    &slabs[first..=(first + per).min(pairs)],
                    false,
                )
            })
            .collect();
        return blocks.into_iter().flatten().collect();
    }
    joints_over_pixels(stack, columns, slabs, true)
}

/// The joint histograms of consecutive `slabs` by one pass over the active pixels (in parallel
/// when `parallel`) and the constant groups.
fn joints_over_pixels(
    stack: &SliceStack,
    columns: &Columns,
    slabs: &[Slab],
    parallel: bool,
) -> Vec<Vec<u64>> {
    let b = stack.bins();
    let pairs = slabs.len().saturating_sub(1);
    if pairs == 0 {
        return Vec::new();
    }
    let (start, end) = (slabs[0].0, slabs[slabs.len() - 1].1);
    let zero = || vec![0u64; pairs * b * b];
    // A few tasks per thread: each task sums into its own histograms, which are then added up.
    let tasks = if parallel {
        rayon::current_num_threads() * 4
    } else {
        1
    };
    let chunk = columns.active.len().div_ceil(tasks).max(1024);
    let singles = slabs.iter().all(|s| s.1 - s.0 == 1);
    let mut flat = (0..columns.active.len())
        .into_par_iter()
        .with_min_len(chunk)
        .fold(
            || (zero(), vec![]),
            |(mut joint, mut hists): (Vec<u64>, Vec<PixelHistogram>), i| {
                if hists.is_empty() {
                    hists = (0..slabs.len()).map(|_| PixelHistogram::new(b)).collect();
                }
                if !singles && let Some(symbol) = columns.single_run(i, start, end) {
                    // One symbol throughout the slabs: each pair adds |S_j|·|S_j+1| to (s, s).
                    if symbol != MISSING {
                        let cell = usize::from(symbol) * (b + 1);
                        for (j, pair) in slabs.windows(2).enumerate() {
                            joint[j * b * b + cell] +=
                                ((pair[0].1 - pair[0].0) * (pair[1].1 - pair[1].0)) as u64;
                        }
                    }
                    return (joint, hists);
                }
                if singles {
                    let (first, column) = stack.column(columns.active[i] as usize, start, end);
                    for (j, h) in hists.iter_mut().enumerate() {
                        let k = (start + j).wrapping_sub(first);
                        h.fill(column.get(k..=k).unwrap_or(&[]));
                    }
                } else {
                    columns.fill_from_runs(i, slabs, &mut hists);
                }
                for (j, pair) in hists.windows(2).enumerate() {
                    pair[1].cross_into(&pair[0], &mut joint[j * b * b..(j + 1) * b * b], b);
                }
                (joint, hists)
            },
        )
        .map(|(joint, _)| joint)
        .reduce(zero, |mut a, c| {
            a.iter_mut().zip(&c).for_each(|(x, y)| *x += y);
            a
        });
    // A constant column adds |S ∩ column| · |T ∩ column| to the cell (s, s) of each pair.
    let overlap = |s: Slab, first: usize, len: usize| {
        s.1.min(first + len).saturating_sub(s.0.max(first)) as u64
    };
    for &(symbol, first, len, count) in &columns.constant {
        let cell = usize::from(symbol) * (b + 1);
        for (i, pair) in slabs.windows(2).enumerate() {
            let n = overlap(pair[0], first, len) * overlap(pair[1], first, len);
            flat[i * b * b + cell] += n * count;
        }
    }
    flat.chunks(b * b).map(<[u64]>::to_vec).collect()
}

/// NMI of every consecutive pair of `slabs`, batched so that a pass's histograms fit in memory.
pub(crate) fn consecutive_nmi(
    stack: &SliceStack,
    columns: &Columns,
    slabs: &[Slab],
    monitor: &Monitor,
) -> Result<Vec<f64>> {
    let b = stack.bins();
    let batch = (PASS_BYTES / (b * b * 8)).max(1);
    let mut out = Vec::with_capacity(slabs.len().saturating_sub(1));
    let mut i = 0;
    while i + 1 < slabs.len() {
        let j = (i + batch + 1).min(slabs.len());
        for joint in consecutive_joints(stack, columns, &slabs[i..j]) {
            out.push(normalized_mutual_information(&joint, b, b));
        }
        monitor.check()?;
        i = j - 1;
    }
    Ok(out)
}

/// The NMI between each slice and the next, along the stack.
pub fn slice_nmi(stack: &SliceStack, monitor: &Monitor) -> Result<Vec<f64>> {
    let slabs: Vec<Slab> = (0..stack.slices()).map(|s| (s, s + 1)).collect();
    consecutive_nmi(stack, &Columns::new(stack), &slabs, monitor)
}

/// Steps keep the NMI of every adjacent pair only while there are at most this many slabs, so
/// that the history's memory stays linear in the slices (the pairs are what a viewer shows at
/// the end of the history, where few slabs are left).
pub const PAIRS_KEPT: usize = 1024;

/// A pair of adjacent slabs waiting to be merged, by its NMI and then (for ties) the lowest
/// left slab, so that a max-heap pops the merge DESIGN §2 takes next. `stamp` tells a current
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measure::mutual_information;

    fn stack_of(slices: &[Vec<u8>], bins: usize) -> SliceStack {
        SliceStack::from_slices(slices, bins).unwrap()
    }

    /// The literal definition: sum the joint histograms of every pair of slices.
    fn literal_joint(slices: &[Vec<u8>], a: Slab, c: Slab, bins: usize) -> Vec<u64> {
        let mut h = vec![0u64; bins * bins];
        for s in a.0..a.1 {
            for t in c.0..c.1 {
                for (&x, &y) in slices[s].iter().zip(&slices[t]) {
                    if x != MISSING && y != MISSING {
                        h[usize::from(x) * bins + usize::from(y)] += 1;
                    }
                }
            }
        }
        h
    }

    #[test]
    fn slab_joint_histograms_equal_the_pairwise_definition() {
        let mut state = 7u32;
        let mut next = || {
            state = state.wrapping_mul(1_103_515_245).wrapping_add(12345);
            (state >> 16) as u8
        };
        let slices: Vec<Vec<u8>> = (0..9)
            .map(|_| {
                (0..50)
                    .map(|_| if next() % 9 == 0 { MISSING } else { next() % 5 })
                    .collect()
            })
            .collect();
        let stack = stack_of(&slices, 5);
        let slabs = [(0, 2), (2, 3), (3, 7), (7, 9)];
        let joints = consecutive_joints(&stack, &Columns::new(&stack), &slabs);
        for (i, joint) in joints.iter().enumerate() {
            assert_eq!(
                joint,
                &literal_joint(&slices, slabs[i], slabs[i + 1], 5),
                "pair {i}"
            );
        }
    }

    #[test]
    fn oblique_columns_follow_the_pairwise_definition() {
        use crate::volume::{Volume, VoxelType};
        // Blocky values with noise, so columns have both long runs and short ones, and start and
        // end at different slices.
        let mut state = 11u32;
        let data = (0..14 * 11 * 9)
            .map(|i| {
                state = state.wrapping_mul(1_103_515_245).wrapping_add(12345);
                ((i % 14) / 5 * 20 + (i / 154) / 3 * 30) as f32
                    + if state >> 29 == 0 { 15.0 } else { 0.0 }
            })
            .collect();
        let v = Volume::new([14, 11, 9], [1.0; 3], VoxelType::F32, data).unwrap();
        let params = super::super::StackParams {
            sampling: crate::geometry::lattice::SamplingParams {
                bins: 8,
                ..Default::default()
            },
            ..Default::default()
        };
        let stack = SliceStack::new(&v, [1.0, 2.0, 3.0], &params, &Monitor::none()).unwrap();
        let n = stack.slices();
        let slabs = [(0, 3), (3, 4), (4, n / 2), (n / 2, n)];
        let joints = consecutive_joints(&stack, &Columns::new(&stack), &slabs);
        let symbol = |p: usize, k: usize| stack.column(p, k, k + 1).1.first().copied();
        for (i, joint) in joints.iter().enumerate() {
            let mut literal = vec![0u64; 64];
            for p in 0..stack.pixels() {
                for s in slabs[i].0..slabs[i].1 {
                    for t in slabs[i + 1].0..slabs[i + 1].1 {
                        if let (Some(x), Some(y)) = (symbol(p, s), symbol(p, t))
                            && x != MISSING
                            && y != MISSING
                        {
                            literal[usize::from(x) * 8 + usize::from(y)] += 1;
                        }
                    }
                }
            }
            assert_eq!(joint, &literal, "pair {i}");
        }
    }

    #[test]
    fn two_materials_merge_into_their_halves() {
        let slices: Vec<Vec<u8>> = (0..10)
            .map(|s| {
                (0..40)
                    .map(|p| {
                        if s < 6 {
                            (p % 3) as u8
                        } else {
                            3 + (p % 2) as u8
                        }
                    })
                    .collect()
            })
            .collect();
        let h = MergeHistory::new(&stack_of(&slices, 5), &Monitor::none()).unwrap();
        assert_eq!(h.slabs(2), vec![(0, 6), (6, 10)]);
        assert_eq!(h.steps.len(), 9);
        // Identical slices have NMI 1; the last merge joins unrelated halves.
        assert!((h.steps[0].nmi - 1.0).abs() < 1e-12);
        assert!(h.steps.last().unwrap().nmi < 0.5);
        for s in &h.steps {
            assert!((0.0..=1.0).contains(&s.nmi));
        }
    }

    #[test]
    fn nmi_matches_the_measure_on_single_slices() {
        let slices = vec![vec![0u8, 1, 2, 3, 0, 1], vec![0u8, 1, 1, 3, 0, 2]];
        let nmi = slice_nmi(&stack_of(&slices, 4), &Monitor::none()).unwrap();
        let joint = literal_joint(&slices, (0, 1), (1, 2), 4);
        let (mi, h) = mutual_information(&joint, 4, 4);
        assert!((nmi[0] - mi / h).abs() < 1e-12);
    }
}
