//! The joint histograms bottom-up merging measures (paper eq. 7): those of consecutive slabs,
//! summed per pixel as the outer product of the two slabs' histograms there, from the stack's
//! columns sorted into constant ones (added without being read) and run-length encoded active
//! ones; and the NMI of each consecutive pair.

use rayon::prelude::*;

use super::super::Slab;
use super::super::stack::{MISSING, SliceStack};
use super::checkpoints::{Checkpoints, Runs};
use crate::error::Result;
use crate::measure::normalized_mutual_information;
use crate::progress::Monitor;

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
pub(crate) const PASS_BYTES: usize = 32 << 20;

/// Bytes of joint histograms one pass holds for `stack`: at most [`PASS_BYTES`], and at most a
/// mebibyte or the stack's own samples, so that a stack of many small slices (a long thin
/// volume: 200,000 slices of one pixel) holds histograms in proportion to its samples.
fn pass_bytes(columns: &Columns) -> usize {
    (columns.pixels.saturating_mul(columns.slices)).clamp(1 << 20, PASS_BYTES)
}

/// A group of constant columns: their symbol, first slice, slices, and how many pixels.
pub(super) type ConstantGroup = (u8, usize, usize, u64);

/// The stack's columns sorted for joint histograms: columns of one symbol throughout (air, empty
/// background) are grouped by symbol and valid range, since each contributes to one cell without
/// being read; the others are read.
pub(crate) struct Columns {
    /// The stack's bins, slices and pixels.
    pub(super) bins: usize,
    pub(super) slices: usize,
    pub(super) pixels: usize,
    /// Pixels whose column holds more than one symbol, or missing samples.
    pub(super) active: Vec<u32>,
    /// Constant columns, grouped.
    pub(super) constant: Vec<ConstantGroup>,
    /// The active columns as runs of one symbol: active column `i` has the runs
    /// `run_start[i] .. run_start[i + 1]`, each from slice `run_first[r]` to the next run's first
    /// (or `run_end[i]`), of symbol `run_symbol[r]`.
    pub(super) run_start: Vec<usize>,
    pub(super) run_first: Vec<u32>,
    pub(super) run_symbol: Vec<u8>,
    pub(super) run_end: Vec<u32>,
    /// The cumulative histograms of the columns of many runs, at every so many runs.
    pub(super) checkpoints: Checkpoints,
}

impl Columns {
    /// The columns of `stack`, sorted into constant and active ones, the active ones run-length
    /// encoded.
    pub(crate) fn new(stack: &SliceStack) -> Self {
        let (active, constant) = sorted_columns(stack);
        // Two passes, so that the runs are written once, in place: count each column's runs,
        // then fill the arrays, a block of columns a task.
        let run_start = run_starts(stack, &active);
        let (run_first, run_symbol, run_end) = runs_of(stack, &active, &run_start);
        let shape = [stack.bins(), stack.slices(), stack.pixels()];
        Self::of_runs(
            shape,
            active,
            constant,
            run_start,
            (run_first, run_symbol, run_end),
        )
    }

    /// The columns of a stack of `[bins, slices, pixels]`, from the constant groups and the
    /// active columns' runs as laid out in the fields (checked by the caller), their checkpoints
    /// made.
    pub(super) fn of_runs(
        [bins, slices, pixels]: [usize; 3],
        active: Vec<u32>,
        constant: Vec<ConstantGroup>,
        run_start: Vec<usize>,
        (run_first, run_symbol, run_end): (Vec<u32>, Vec<u8>, Vec<u32>),
    ) -> Self {
        let runs = |i: usize| {
            let r = run_start[i]..run_start[i + 1];
            Runs {
                firsts: &run_first[r.clone()],
                symbols: &run_symbol[r],
                end: run_end[i],
            }
        };
        let checkpoints = Checkpoints::new(active.len(), runs, bins);
        Self {
            bins,
            slices,
            pixels,
            active,
            constant,
            run_start,
            run_first,
            run_symbol,
            run_end,
            checkpoints,
        }
    }

    /// The stack's bins.
    pub(crate) fn bins(&self) -> usize {
        self.bins
    }

    /// The stack's slices.
    pub(crate) fn slices(&self) -> usize {
        self.slices
    }

    /// The bytes the columns hold.
    pub(crate) fn held_bytes(&self) -> usize {
        use std::mem::size_of_val;
        size_of_val(&self.active[..])
            + size_of_val(&self.constant[..])
            + size_of_val(&self.run_start[..])
            + size_of_val(&self.run_first[..])
            + size_of_val(&self.run_symbol[..])
            + size_of_val(&self.run_end[..])
            + self.checkpoints.held_bytes()
    }

    /// Active column `i`'s runs.
    #[inline]
    fn runs(&self, i: usize) -> Runs<'_> {
        let runs = self.run_start[i]..self.run_start[i + 1];
        Runs {
            firsts: &self.run_first[runs.clone()],
            symbols: &self.run_symbol[runs],
            end: self.run_end[i],
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
    /// from its runs: the work is the number of runs, not of slices, and for a slab of many
    /// runs, the runs between two checkpoints.
    fn fill_from_runs(&self, i: usize, slabs: &[Slab], hists: &mut [PixelHistogram]) {
        for h in hists.iter_mut() {
            h.clear();
        }
        let runs = self.runs(i);
        let span = |s: &Slab| (s.0 as u32, s.1 as u32);
        let whole = (span(&slabs[0]).0, span(&slabs[slabs.len() - 1]).1);
        if !self.checkpoints.serve(i, &runs, whole) {
            return Self::walk_runs(&runs, slabs, hists);
        }
        let mut scratch = [0u32; 512];
        for (j, slab) in slabs.iter().enumerate() {
            if self.checkpoints.serve(i, &runs, span(slab)) {
                let h = &mut hists[j];
                self.checkpoints
                    .histogram(i, &runs, span(slab), &mut scratch, |s, n| h.add(s, n));
            } else {
                Self::walk_runs(&runs, std::slice::from_ref(slab), &mut hists[j..=j]);
            }
        }
    }

    /// Adds into `hists[j]` the histogram over `slabs[j]` (contiguous slabs) of a column's
    /// `runs`, run by run.
    fn walk_runs(runs: &Runs, slabs: &[Slab], hists: &mut [PixelHistogram]) {
        let (lo, hi) = (slabs[0].0 as u32, slabs[slabs.len() - 1].1 as u32);
        let Runs {
            firsts,
            symbols,
            end,
        } = *runs;
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

/// The pixels of `stack` whose column is active (holds more than one symbol, or missing
/// samples), in order, and the constant columns grouped by symbol and valid range, with how
/// many pixels each group has.
fn sorted_columns(stack: &SliceStack) -> (Vec<u32>, Vec<ConstantGroup>) {
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
    (active, constant)
}

/// Where the runs of each of the `active` columns start among all runs (one more entry than
/// columns: the last is the total).
fn run_starts(stack: &SliceStack, active: &[u32]) -> Vec<usize> {
    let n = stack.slices();
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
    run_start
}

/// The runs of the `active` columns, laid out as `run_start` says: each run's first slice and
/// symbol, and the slice each column ends at.
fn runs_of(
    stack: &SliceStack,
    active: &[u32],
    run_start: &[usize],
) -> (Vec<u32>, Vec<u8>, Vec<u32>) {
    let n = stack.slices();
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
    (run_first, run_symbol, run_end)
}

/// The joint histograms `h(S_i, S_i+1)` of consecutive slabs of `slabs` (contiguous, in order),
/// each `bins × bins`, from `columns` (and `stack`, the stack they were made from, if it is
/// still held: slabs of a slice each are read from it, else from the runs). Many pairs are split
/// among the threads, each pair's histogram made once; a few pairs (a merge step) split the
/// pixels instead.
pub(super) fn consecutive_joints(
    stack: Option<&SliceStack>,
    columns: &Columns,
    slabs: &[Slab],
) -> Vec<Vec<u64>> {
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
    stack: Option<&SliceStack>,
    columns: &Columns,
    slabs: &[Slab],
    parallel: bool,
) -> Vec<Vec<u64>> {
    let b = columns.bins;
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
    let singles = stack.filter(|_| slabs.iter().all(|s| s.1 - s.0 == 1));
    let mut flat = (0..columns.active.len())
        .into_par_iter()
        .with_min_len(chunk)
        .fold(
            || (zero(), vec![]),
            |(mut joint, mut hists): (Vec<u64>, Vec<PixelHistogram>), i| {
                if let Some(stack) = singles {
                    let (first, column) = stack.column(columns.active[i] as usize, start, end);
                    add_neighbours(column, first - start, &mut joint, b);
                    return (joint, hists);
                }
                if hists.is_empty() {
                    hists = (0..slabs.len()).map(|_| PixelHistogram::new(b)).collect();
                }
                if let Some(symbol) = columns.single_run(i, start, end) {
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
                columns.fill_from_runs(i, slabs, &mut hists);
                for (j, pair) in hists.windows(2).enumerate() {
                    pair[1].cross_into(&pair[0], &mut joint[j * b * b..(j + 1) * b * b], b);
                }
                (joint, hists)
            },
        )
        .map(|(joint, _)| joint)
        .reduce_with(|mut a, c| {
            a.iter_mut().zip(&c).for_each(|(x, y)| *x += y);
            a
        })
        .unwrap_or_else(zero);
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

/// Adds one pixel's pairs of neighbouring slices to their joint histograms: `column` holds its
/// symbols from the slice `first` pairs past the first pair's (`joints` holds a `bins × bins`
/// histogram a pair, rows the first slice's bins), missing samples left out. A slab of one slice
/// holds one sample a pixel, so its pair's histogram gains one count, where the slabs' general
/// path builds a histogram of each slab at the pixel and crosses them.
#[inline]
fn add_neighbours(column: &[u8], first: usize, joints: &mut [u64], bins: usize) {
    if column.len() < 2 {
        return;
    }
    let joints = &mut joints[first * bins * bins..];
    for (pair, joint) in column.windows(2).zip(joints.chunks_exact_mut(bins * bins)) {
        let (x, y) = (pair[0], pair[1]);
        if x != MISSING && y != MISSING {
            joint[usize::from(x) * bins + usize::from(y)] += 1;
        }
    }
}

/// Adds the joint histograms of every consecutive pair of `slabs` into `joints` (`pairs × bins²`
/// counts, pair by pair), batched so that a pass's histograms fit in memory, from `columns` and
/// the `stack` they were made from if it is held ([`consecutive_joints`]). Joint histograms are
/// sums over pixels, so those of a stack cut in strips of pixels add up to the whole stack's.
pub(crate) fn add_consecutive_joints(
    stack: Option<&SliceStack>,
    columns: &Columns,
    slabs: &[Slab],
    joints: &mut [u64],
    monitor: &Monitor,
) -> Result<()> {
    let b2 = columns.bins * columns.bins;
    debug_assert_eq!(joints.len(), slabs.len().saturating_sub(1) * b2);
    let batch = (pass_bytes(columns) / (b2 * 8)).max(1);
    let mut i = 0;
    while i + 1 < slabs.len() {
        let j = (i + batch + 1).min(slabs.len());
        for (k, joint) in consecutive_joints(stack, columns, &slabs[i..j])
            .into_iter()
            .enumerate()
        {
            let into = &mut joints[(i + k) * b2..(i + k + 1) * b2];
            into.iter_mut().zip(&joint).for_each(|(x, y)| *x += y);
        }
        monitor.check()?;
        i = j - 1;
    }
    Ok(())
}

/// The NMI of each consecutive pair of `joints` (`bins × bins` each).
pub(crate) fn nmi_of_joints(joints: &[u64], bins: usize) -> Vec<f64> {
    joints
        .chunks(bins * bins)
        .map(|joint| normalized_mutual_information(joint, bins, bins))
        .collect()
}

/// NMI of every consecutive pair of `slabs`, a batch of pairs at a time (as
/// [`add_consecutive_joints`] batches them), each batch's joint histograms reduced to their NMI
/// before the next: the memory is a pass's, however many pairs there are (a stack of 200,000
/// slices would otherwise hold 200,000 joint histograms of `bins²` counts at once, 1.6 GB at 32
/// bins).
pub(crate) fn consecutive_nmi(
    stack: &SliceStack,
    columns: &Columns,
    slabs: &[Slab],
    monitor: &Monitor,
) -> Result<Vec<f64>> {
    let b = stack.bins();
    let batch = (pass_bytes(columns) / (b * b * 8)).max(1);
    let mut nmi = Vec::with_capacity(slabs.len().saturating_sub(1));
    let mut i = 0;
    while i + 1 < slabs.len() {
        let j = (i + batch + 1).min(slabs.len());
        let mut joints = vec![0u64; (j - i - 1) * b * b];
        add_consecutive_joints(Some(stack), columns, &slabs[i..j], &mut joints, monitor)?;
        nmi.extend(nmi_of_joints(&joints, b));
        i = j - 1;
    }
    Ok(nmi)
}

/// The NMI between each slice and the next, along the stack.
pub fn slice_nmi(stack: &SliceStack, monitor: &Monitor) -> Result<Vec<f64>> {
    let slabs: Vec<Slab> = (0..stack.slices()).map(|s| (s, s + 1)).collect();
    consecutive_nmi(stack, &Columns::new(stack), &slabs, monitor)
}
