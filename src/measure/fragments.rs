//! Block counts that add: the counts of pieces of sequences counted apart, in any order, on any
//! thread or machine, stitched exactly where two pieces of one sequence meet.
//!
//! A [`Fragment`] is the samples `start..end` of one sequence (a ray), counted with what can be
//! known inside it: every L-block all of whose symbols it holds, and every run end (a missing
//! sample, or the sequence's end) whose run it holds back to its start or far enough (L-1
//! symbols). What depends on the samples before it is left open: its first L-1 samples are kept
//! raw (its *head*) and not counted; its run at the end (its *tail*, a [`Run`]) is kept. When two
//! fragments of one sequence meet ([`Fragment::stitch`]), the later one's head is replayed onto
//! the earlier one's tail, counting exactly the blocks and ends that cross the seam. A fragment
//! holding a whole sequence is complete and leaves nothing but counts. [`PartialCounts`] holds
//! the counts of any set of fragments and adds to another, so that counting the pieces apart and
//! adding them gives, bit for bit, the counts of the sequences counted whole.

use super::blocks::{BlockCounts, Counter, Run};

mod bytes;

/// The longest head a fragment keeps: L - 1 for the longest block, 4.
const MAX_HEAD: usize = 3;

/// One sample: a symbol, or a missing sample (`None`) that breaks its sequence.
pub type Sample = Option<u8>;

/// [`Fragment::bits`]: it ends its sequence.
const LAST: u8 = 1;
/// [`Fragment::bits`]: one of its samples is missing.
const BROKEN: u8 = 2;
/// [`Fragment::bits`]: the first of three bits saying which of its head's samples are missing.
const HEAD_MISSING: u32 = 2;
/// [`Fragment::bits`]: the first of three bits holding its run's length, capped.
const RUN_LEN: u32 = 5;
/// The longest run length a fragment keeps: more says no more (only whether a run reaches L - 1
/// and L samples counts, and L is at most 4).
const RUN_CAP: u64 = 7;

/// A piece of one sequence counted apart: samples `start..end` of sequence `key`, in 32 bytes
/// (a cluster's parts hold one for each ray crossing a slab's face, issue #44).
///
/// It starts the sequence when `start` is 0 (then nothing is left open at its start). Its head,
/// its first L-1 samples (fewer when it is shorter; none when it starts the sequence), is kept
/// raw and not counted: as many samples as its length and L allow, so its length is not stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Fragment {
    /// Which sequence (for a ray of a lattice, its `(i, j)` packed by [`ray_key`]).
    pub key: u64,
    /// Its first sample's index in the sequence.
    pub start: u64,
    /// One past its last sample's index.
    pub end: u64,
    /// The code of the run at its end (its last L symbols: 32 bits at most, 8 bits a symbol).
    code: u32,
    /// Its head's symbols (0 where one is missing).
    head: [u8; MAX_HEAD],
    /// [`LAST`], [`BROKEN`], which head samples are missing from bit [`HEAD_MISSING`] on, and
    /// the run's length (capped at [`RUN_CAP`]) from bit [`RUN_LEN`] on.
    bits: u8,
}

/// The key of ray `(i, j)` of a lattice: the two indices side by side, row `j` first, each as
/// 32 bits offset so that keys are in the order of `(j, i)` (rays of a volume's lattice have
/// indices far within 32 bits). The walks set rays up by bands of rows, so the open pieces of
/// the bands taken in order are in key order already, and are never sorted again (issue #44).
pub fn ray_key(i: i64, j: i64) -> u64 {
    let ordered = |x: i64| u64::from(x as i32 as u32 ^ 0x8000_0000);
    (ordered(j) << 32) | ordered(i)
}

/// The ray `(i, j)` whose key [`ray_key`] made.
#[must_use]
pub fn key_ray(key: u64) -> (i64, i64) {
    let index = |x: u64| i64::from((x as u32 ^ 0x8000_0000) as i32);
    (index(key), index(key >> 32))
}

impl Fragment {
    /// An empty fragment of sequence `key` starting at sample `start` (the sequence's first when
    /// `start` is 0).
    pub fn new(key: u64, start: u64) -> Self {
        Self {
            key,
            start,
            end: start,
            code: 0,
            head: [0; MAX_HEAD],
            bits: 0,
        }
    }

    /// Number of samples.
    pub fn len(&self) -> u64 {
        self.end - self.start
    }

    /// Whether it holds no sample yet.
    pub fn is_empty(&self) -> bool {
        self.end == self.start
    }

    /// Whether it starts the sequence: then nothing is left open at its start.
    pub fn first(&self) -> bool {
        self.start == 0
    }

    /// Whether it ends the sequence.
    pub fn last(&self) -> bool {
        self.bits & LAST != 0
    }

    /// Whether one of its samples is missing.
    fn broken(&self) -> bool {
        self.bits & BROKEN != 0
    }

    /// How many of its first samples are kept raw for blocks of length `block`.
    fn head_len(&self, block: usize) -> usize {
        if self.first() {
            0
        } else {
            self.len().min(block as u64 - 1) as usize
        }
    }

    /// Its head's sample `k`.
    fn head_sample(&self, k: usize) -> Sample {
        (self.bits & 1 << (HEAD_MISSING as usize + k) == 0).then_some(self.head[k])
    }

    /// Keeps `sample` as its head's sample `k`.
    fn set_head(&mut self, k: usize, sample: Sample) {
        self.head[k] = sample.unwrap_or(0);
        self.bits |= u8::from(sample.is_none()) << (HEAD_MISSING as usize + k);
    }

    /// Whether its next sample is still part of its head: kept raw, not counted (then it must
    /// go through [`push`](Self::push), one at a time).
    #[inline]
    pub fn in_head(&self, block: usize) -> bool {
        !self.first() && self.len() < block as u64 - 1
    }

    /// The run at its end, for a walk that takes over after the head (see
    /// [`walked`](Self::walked)).
    pub fn run(&self) -> Run {
        Run::from_parts(u64::from(self.code), u64::from(self.bits >> RUN_LEN))
    }

    /// Keeps `run` as the run at its end.
    fn set_run(&mut self, run: Run) {
        let (code, len) = run.parts();
        // A block code holds L symbols of at most 8 bits: 32 bits.
        self.code = code as u32;
        self.bits = (self.bits & ((1 << RUN_LEN) - 1)) | (len.min(RUN_CAP) as u8) << RUN_LEN;
    }

    /// Its run after a walk of `samples` more samples past its head, which left the run `run`
    /// and counted them (a missing sample there matters no more: the head is known).
    pub fn walked(&mut self, samples: u64, run: Run) {
        self.end += samples;
        self.set_run(run);
    }

    /// Appends one sample, counting into `counts` what it completes (nothing in the head).
    pub fn push(&mut self, counts: &mut BlockCounts, sample: Sample) {
        let block = counts.block();
        let mut run = self.run();
        if self.in_head(block) {
            // The head holds every sample so far.
            self.set_head(self.len() as usize, sample);
            counts.prime(&mut run, sample);
        } else {
            match sample {
                Some(s) => counts.push_to(&mut run, s),
                None => counts.end_run(&mut run),
            }
        }
        self.set_run(run);
        self.bits |= u8::from(sample.is_none()) * BROKEN;
        self.end += 1;
    }

    /// Whether everything before its end is known: it starts the sequence, has a missing
    /// sample, or holds L-1 samples (as many as a run end looks back).
    fn determined(&self, block: usize) -> bool {
        self.first() || self.broken() || self.len() >= block as u64 - 1
    }

    /// Ends it where the sequence ends (when `last`) or where the next piece takes over:
    /// counts the sequence's end if it can be known here; `None` when it is the whole
    /// sequence (complete: only its counts remain).
    pub fn close(mut self, counts: &mut BlockCounts, last: bool) -> Option<Self> {
        self.bits = (self.bits & !LAST) | (u8::from(last) * LAST);
        if last && self.determined(counts.block()) {
            let mut run = self.run();
            counts.end_run(&mut run);
        }
        (!(self.first() && self.last())).then_some(self)
    }

    /// The fragment `self` followed by `next`, the piece of the same sequence that starts where
    /// `self` ends, counting into `counts` what crosses the seam; `None` when together they are
    /// the whole sequence.
    pub fn stitch(self, next: &Self, counts: &mut BlockCounts) -> Option<Self> {
        debug_assert!(self.key == next.key && self.end == next.start && !next.first());
        let block = counts.block();
        let mut run = self.run();
        let mut out = Self {
            end: next.end,
            bits: (self.bits & !LAST) | (next.bits & LAST) | (next.bits & BROKEN),
            ..self
        };
        // The seam's samples: `next`'s head, counted from where the whole is known, kept in
        // the whole's head before that.
        for k in 0..next.head_len(block) {
            let sample = next.head_sample(k);
            let at = self.len() + k as u64;
            if !out.first() && at < block as u64 - 1 {
                out.set_head(at as usize, sample);
                counts.prime(&mut run, sample);
            } else {
                match sample {
                    Some(s) => counts.push_to(&mut run, s),
                    None => counts.end_run(&mut run),
                }
            }
        }
        // `next` walked on from its head with the run its head left: the same as ours from
        // there on, once it holds L-1 samples or a missing one; else all of it was its head.
        out.set_run(if next.determined(block) {
            next.run()
        } else {
            run
        });
        if next.last() && !next.determined(block) && out.determined(block) {
            counts.end_run(&mut run);
        }
        (!(out.first() && out.last())).then_some(out)
    }
}

/// Block counts of any set of pieces of sequences: the counts they determine, the sequences
/// they start (rays met), and the fragments still open. Adds to another in any order.
#[derive(Clone, Debug)]
pub struct PartialCounts {
    /// What is counted.
    pub counts: BlockCounts,
    /// Sequences started (for a lattice: rays that met the volume).
    pub rays: u64,
    /// Fragments not yet joined to their neighbours, in order of key and start.
    fragments: Vec<Fragment>,
}

impl PartialCounts {
    /// Nothing counted, for blocks of length `block` over `bins` symbols.
    pub fn new(bins: usize, block: usize) -> Self {
        Self::of(BlockCounts::new(bins, block), 0, Vec::new())
    }

    /// Counts with `rays` sequences started and `fragments` still open (in any order; those of
    /// one sequence that meet are stitched).
    pub fn of(counts: BlockCounts, rays: u64, fragments: Vec<Fragment>) -> Self {
        let mut out = Self {
            counts,
            rays,
            fragments: Vec::new(),
        };
        join(&mut out.fragments, fragments, &mut out.counts);
        out
    }

    /// Adds `other`'s counts: what both determine, and their fragments stitched where they meet.
    pub fn add(&mut self, other: Self) {
        self.counts.merge(&other.counts);
        self.rays += other.rays;
        join(&mut self.fragments, other.fragments, &mut self.counts);
    }

    /// Adds `other`'s counts in place, as [`add`](Self::add) does, leaving `other` as it is:
    /// nothing of `self` is copied but where the two lists of open pieces are merged.
    pub fn add_ref(&mut self, other: &Self) {
        self.counts.merge(&other.counts);
        self.rays += other.rays;
        if other.fragments.is_sorted_by_key(order) {
            in_order(&mut self.fragments);
            merge_in(&mut self.fragments, &other.fragments);
            stitch_sorted(&mut self.fragments, &mut self.counts);
        } else {
            join(
                &mut self.fragments,
                other.fragments.clone(),
                &mut self.counts,
            );
        }
    }

    /// Keeps `fragment` (if any) open, to be stitched by the next [`add`](Self::add): a walk's
    /// own fragments never meet (a ray's stretch goes on while the walk holds it).
    pub fn push_fragment(&mut self, fragment: Option<Fragment>) {
        self.fragments.extend(fragment);
    }

    /// Room for `more` fragments to be pushed without moving the others.
    pub fn reserve_fragments(&mut self, more: usize) {
        self.fragments.reserve(more);
    }

    /// The fragments still open, in order of key and start (once added or read: those a walk
    /// pushed, as it pushed them).
    pub fn fragments(&self) -> &[Fragment] {
        &self.fragments
    }

    /// Whether every sequence begun is counted whole.
    pub fn is_complete(&self) -> bool {
        self.fragments.is_empty()
    }

    /// Stitches this part's fragments into `open` (fragments of the same sequences held apart,
    /// in order of key and start, as this leaves them), counting here what crosses each seam:
    /// afterwards `open` holds every fragment still open, and this part none. For a walk that
    /// keeps the open rays of a sweep by bands of its own rather than in one list.
    pub fn stitch_into(&mut self, open: &mut Vec<Fragment>) {
        let more = std::mem::take(&mut self.fragments);
        join(open, more, &mut self.counts);
        // Held until the next slab: no room kept for the merge it came from.
        open.shrink_to_fit();
    }
}

/// The order fragments are kept in.
fn order(f: &Fragment) -> (u64, u64) {
    (f.key, f.start)
}

/// Takes the fragments `more` (in any order) into `held` (in order), every pair that meets
/// stitched, counting into `counts` what crosses the seams.
fn join(held: &mut Vec<Fragment>, mut more: Vec<Fragment>, counts: &mut BlockCounts) {
    if more.is_empty() {
        return;
    }
    in_order(&mut more);
    in_order(held);
    if held.is_empty() {
        *held = more;
    } else {
        merge_in(held, &more);
    }
    stitch_sorted(held, counts);
}

/// Sorts `v` when it is not in order already (a part's own pieces are: a slab's bands taken in
/// order, a part read back or added; a walk's pieces pushed one by one may not be). By the
/// stable sort, which merges runs already in order: a slab's walk pushes a band's pieces as a
/// few such runs (those set up on its faces, those leaving it, those ending in it).
fn in_order(v: &mut [Fragment]) {
    if !v.is_sorted_by_key(order) {
        v.sort_by_key(order);
    }
}

/// `held` and `more` (both in order) merged in place into `held`, in order, `held`'s first
/// where two compare equal: from the back, so that nothing of `held` moves twice.
fn merge_in(held: &mut Vec<Fragment>, more: &[Fragment]) {
    if more.is_empty() {
        return;
    }
    let n = held.len();
    if held.last().is_none_or(|f| order(f) <= order(&more[0])) {
        held.extend_from_slice(more);
        return;
    }
    held.reserve_exact(more.len());
    held.extend_from_slice(more);
    let (mut i, mut j) = (n, more.len());
    let mut k = held.len();
    while j > 0 {
        k -= 1;
        if i > 0 && order(&held[i - 1]) > order(&more[j - 1]) {
            held[k] = held[i - 1];
            i -= 1;
        } else {
            held[k] = more[j - 1];
            j -= 1;
        }
    }
}

/// Stitches in place every pair of consecutive fragments of `v` (in order) that meet,
/// counting into `counts` what crosses the seams.
fn stitch_sorted(v: &mut Vec<Fragment>, counts: &mut BlockCounts) {
    // Nothing moves before the first pair that meets.
    let Some(first) = v
        .windows(2)
        .position(|w| w[0].key == w[1].key && w[0].end == w[1].start)
    else {
        return;
    };
    let mut kept = first + 1;
    for r in first + 1..v.len() {
        let f = v[r];
        if kept > 0 && v[kept - 1].key == f.key && v[kept - 1].end == f.start {
            match v[kept - 1].stitch(&f, counts) {
                Some(joined) => v[kept - 1] = joined,
                None => kept -= 1,
            }
        } else {
            v[kept] = f;
            kept += 1;
        }
    }
    v.truncate(kept);
}

#[cfg(test)]
mod tests;
