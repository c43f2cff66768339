//! Bottom-up partitioning (paper §5.2, eq. 7 and 8): agglomerative merging of adjacent slabs by
//! normalized mutual information. The joint histogram of two slabs sums the joint histograms of
//! every pair of their slices over corresponding pixels; per pixel it factorizes as the outer
//! product of the two slabs' histograms there, `h(x, y) = Σ_p cA(p, x)·cB(p, y)`.

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
    /// The NMI of every adjacent pair just before this merge, in slice order.
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

    fn fill(&mut self, symbols: &[u8]) {
        for &u in &self.used {
            self.counts[usize::from(u)] = 0;
        }
        self.used.clear();
        for &s in symbols {
            if s != MISSING {
                let c = &mut self.counts[usize::from(s)];
                if *c == 0 {
                    self.used.push(s);
                }
                *c += 1;
            }
        }
    }
}

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
        Self { active, constant }
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
    let mut flat = columns
        .active
        .par_iter()
        .with_min_len(chunk)
        .fold(
            || (zero(), PixelHistogram::new(b), PixelHistogram::new(b)),
            |(mut joint, mut prev, mut cur), &p| {
                let (first, column) = stack.column(p as usize, start, end);
                if column.is_empty() {
                    return (joint, prev, cur);
                }
                // The part of the column inside slab `s`.
                let take = |s: Slab| {
                    let clip = |i: usize| i.saturating_sub(first).min(column.len());
                    &column[clip(s.0)..clip(s.1)]
                };
                prev.fill(take(slabs[0]));
                for (i, &slab) in slabs.iter().enumerate().skip(1) {
                    cur.fill(take(slab));
                    let h = &mut joint[(i - 1) * b * b..i * b * b];
                    for &x in &prev.used {
                        let cx = u64::from(prev.counts[usize::from(x)]);
                        let row = &mut h[usize::from(x) * b..(usize::from(x) + 1) * b];
                        for &y in &cur.used {
                            row[usize::from(y)] += cx * u64::from(cur.counts[usize::from(y)]);
                        }
                    }
                    std::mem::swap(&mut prev, &mut cur);
                }
                (joint, prev, cur)
            },
        )
        .map(|(joint, _, _)| joint)
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

/// The index of the largest value, the first on ties.
fn argmax(values: &[f64]) -> Option<usize> {
    let mut best: Option<usize> = None;
    for (i, &v) in values.iter().enumerate() {
        if best.is_none_or(|b| v > values[b]) {
            best = Some(i);
        }
    }
    best
}

impl MergeHistory {
    /// Merges the slices of `stack` until one slab is left, reporting one unit per merge.
    pub fn new(stack: &SliceStack, monitor: &Monitor) -> Result<Self> {
        Self::with_limit(stack, monitor, usize::MAX)
    }

    /// Like [`new`](Self::new), but stops after `limit` merges.
    pub fn with_limit(stack: &SliceStack, monitor: &Monitor, limit: usize) -> Result<Self> {
        let n = stack.slices();
        monitor.start(n as u64);
        let columns = Columns::new(stack);
        let mut slabs: Vec<Slab> = (0..n).map(|s| (s, s + 1)).collect();
        let mut nmi = consecutive_nmi(stack, &columns, &slabs, monitor)?;
        let mut steps = Vec::with_capacity(n.saturating_sub(1));
        while steps.len() < limit
            && let Some(i) = argmax(&nmi)
        {
            steps.push(Merge {
                merge: (slabs[i], slabs[i + 1]),
                nmi: nmi[i],
                pairs: nmi.clone(),
            });
            let merged = (slabs[i].0, slabs[i + 1].1);
            slabs.splice(i..=i + 1, [merged]);
            nmi.remove(i);
            // Recompute the pairs the merged slab is in: with its left and right neighbours.
            let lo = i.saturating_sub(1);
            let hi = (i + 2).min(slabs.len());
            let fresh = consecutive_nmi(stack, &columns, &slabs[lo..hi], &Monitor::none())?;
            nmi[lo..hi - 1].copy_from_slice(&fresh);
            monitor.advance(1)?;
        }
        Ok(Self { slices: n, steps })
    }

    /// The slabs after the first `steps` merges, in slice order.
    pub fn slabs_after(&self, steps: usize) -> Vec<Slab> {
        let mut slabs: Vec<Slab> = (0..self.slices).map(|s| (s, s + 1)).collect();
        for m in self.steps.iter().take(steps) {
            let i = slabs
                .iter()
                .position(|s| *s == m.merge.0)
                .expect("history merges existing slabs");
            slabs.splice(i..=i + 1, [(m.merge.0.0, m.merge.1.1)]);
        }
        slabs
    }

    /// The slabs of a `k`-slab partition (clamped to 1 ..= slices).
    pub fn slabs(&self, k: usize) -> Vec<Slab> {
        self.slabs_after(self.slices - k.clamp(1, self.slices))
    }

    /// How many merges are taken before the largest NMI falls below `threshold`.
    pub fn steps_above(&self, threshold: f64) -> usize {
        self.steps.iter().take_while(|s| s.nmi >= threshold).count()
    }

    /// The NMI between each slice and the next: the pairs before the first merge.
    pub fn slice_nmi(&self) -> &[f64] {
        self.steps.first().map_or(&[], |s| &s.pairs)
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
