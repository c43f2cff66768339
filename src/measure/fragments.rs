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

/// The longest head a fragment keeps: L - 1 for the longest block, 4.
const MAX_HEAD: usize = 3;

/// One sample: a symbol, or a missing sample (`None`) that breaks its sequence.
pub type Sample = Option<u8>;

/// A piece of one sequence counted apart: samples `start..end` of sequence `key`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Fragment {
    /// Which sequence (for a ray of a lattice, its `(i, j)` packed by [`ray_key`]).
    pub key: u64,
    /// Its first sample's index in the sequence.
    pub start: u64,
    /// One past its last sample's index.
    pub end: u64,
    /// Whether it starts the sequence (`start` is 0): then nothing is left open at its start.
    pub first: bool,
    /// Whether it ends the sequence.
    pub last: bool,
    /// Whether one of its samples is missing.
    broken: bool,
    /// Its first L-1 samples (fewer when it is shorter), kept raw and not counted; empty when
    /// it starts the sequence.
    head: [Sample; MAX_HEAD],
    head_len: u8,
    /// The run at its end.
    run: Run,
}

/// The key of ray `(i, j)` of a lattice: the two indices side by side, row `j` first, each as
/// 32 bits offset so that keys are in the order of `(j, i)` (rays of a volume's lattice have
/// indices far within 32 bits). The walks set rays up by bands of rows, so the open pieces of
/// the bands taken in order are in key order already, and are never sorted again (issue #44).
pub fn ray_key(i: i64, j: i64) -> u64 {
    let ordered = |x: i64| u64::from(x as i32 as u32 ^ 0x8000_0000);
    (ordered(j) << 32) | ordered(i)
}

impl Fragment {
    /// An empty fragment of sequence `key` starting at sample `start` (the sequence's first when
    /// `start` is 0).
    pub fn new(key: u64, start: u64) -> Self {
        Self {
            key,
            start,
            end: start,
            first: start == 0,
            last: false,
            broken: false,
            head: [None; MAX_HEAD],
            head_len: 0,
            run: Run::default(),
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

    /// Whether its next sample is still part of its head: kept raw, not counted (then it must
    /// go through [`push`](Self::push), one at a time).
    #[inline]
    pub fn in_head(&self, block: usize) -> bool {
        !self.first && self.len() < block as u64 - 1
    }

    /// The run at its end, for a walk that takes over after the head (see
    /// [`walked`](Self::walked)).
    pub fn run(&self) -> Run {
        self.run
    }

    /// Its run after a walk of `samples` more samples past its head, which left the run `run`
    /// and counted them (a missing sample there matters no more: the head is known).
    pub fn walked(&mut self, samples: u64, run: Run) {
        self.end += samples;
        self.run = run;
    }

    /// Appends one sample, counting into `counts` what it completes (nothing in the head).
    pub fn push(&mut self, counts: &mut BlockCounts, sample: Sample) {
        let block = counts.block();
        if self.in_head(block) {
            self.head[self.head_len as usize] = sample;
            self.head_len += 1;
            counts.prime(&mut self.run, sample);
        } else {
            match sample {
                Some(s) => counts.push_to(&mut self.run, s),
                None => counts.end_run(&mut self.run),
            }
        }
        self.broken |= sample.is_none();
        self.end += 1;
    }

    /// Whether everything before its end is known: it starts the sequence, has a missing
    /// sample, or holds L-1 samples (as many as a run end looks back).
    fn determined(&self, block: usize) -> bool {
        self.first || self.broken || self.len() >= block as u64 - 1
    }

    /// Ends it where the sequence ends (when `last`) or where the next piece takes over:
    /// counts the sequence's end if it can be known here; `None` when it is the whole
    /// sequence (complete: only its counts remain).
    pub fn close(mut self, counts: &mut BlockCounts, last: bool) -> Option<Self> {
        self.last = last;
        if last && self.determined(counts.block()) {
            let mut run = self.run;
            counts.end_run(&mut run);
        }
        (!(self.first && self.last)).then_some(self)
    }

    /// The fragment `self` followed by `next`, the piece of the same sequence that starts where
    /// `self` ends, counting into `counts` what crosses the seam; `None` when together they are
    /// the whole sequence.
    pub fn stitch(self, next: &Self, counts: &mut BlockCounts) -> Option<Self> {
        debug_assert!(self.key == next.key && self.end == next.start && !next.first);
        let block = counts.block();
        let mut run = self.run;
        let mut out = Self {
            end: next.end,
            last: next.last,
            broken: self.broken || next.broken,
            ..self
        };
        // The seam's samples: `next`'s head, counted from where the whole is known, kept in
        // the whole's head before that.
        for (k, &sample) in next.head[..next.head_len as usize].iter().enumerate() {
            if !out.first && self.len() + (k as u64) < block as u64 - 1 {
                out.head[out.head_len as usize] = sample;
                out.head_len += 1;
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
        out.run = if next.determined(block) {
            next.run
        } else {
            run
        };
        if next.last && !next.determined(block) && out.determined(block) {
            counts.end_run(&mut run);
        }
        (!(out.first && out.last)).then_some(out)
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
    /// Fragments not yet joined to their neighbours, by key and start.
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
        out.join(fragments);
        out
    }

    /// Adds `other`'s counts: what both determine, and their fragments stitched where they meet.
    pub fn add(&mut self, other: Self) {
        self.counts.merge(&other.counts);
        self.rays += other.rays;
        self.join(other.fragments);
    }

    /// Keeps `fragment` (if any) open, to be stitched by the next [`add`](Self::add): a walk's
    /// own fragments never meet (a ray's stretch goes on while the walk holds it).
    pub fn push_fragment(&mut self, fragment: Option<Fragment>) {
        self.fragments.extend(fragment);
    }

    /// The fragments still open.
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
        *open = stitched(std::mem::take(open), more, &mut self.counts);
        // Held until the next slab: no room kept for the merge it came from.
        open.shrink_to_fit();
    }

    /// Takes `more` fragments in, stitching every pair that meets.
    fn join(&mut self, more: Vec<Fragment>) {
        let held = std::mem::take(&mut self.fragments);
        self.fragments = stitched(held, more, &mut self.counts);
    }
}

/// The first words of [`PartialCounts::to_bytes`]: `SLABPC` and a version (2 since ray keys
/// are in the order of row then ray: a part of version 1 would not stitch to these).
const MAGIC: u64 = u64::from_le_bytes(*b"SLABPC\x00\x02");

impl Fragment {
    /// The fragment as six words.
    fn write(&self, out: &mut Vec<u64>) {
        let flags = u64::from(self.first)
            | u64::from(self.last) << 1
            | u64::from(self.broken) << 2
            | u64::from(self.head_len) << 8;
        let head = self
            .head
            .iter()
            .enumerate()
            .map(|(k, s)| s.map_or(0, |v| u64::from(v) + 1) << (16 * k))
            .fold(0, |a, b| a | b);
        let (code, len) = self.run.parts();
        out.extend([
            self.key,
            self.start,
            self.end,
            flags | head << 16,
            code,
            len,
        ]);
    }

    /// A fragment [`write`](Self::write) wrote.
    fn read(words: &mut super::blocks::Words) -> super::blocks::ReadResult<Self> {
        let [key, start, end, flags, code, len] = [(); 6].map(|()| words.next());
        let (key, start, end, flags) = (key?, start?, end?, flags?);
        let head_len = (flags >> 8 & 0xff) as u8;
        if end < start || usize::from(head_len) > MAX_HEAD {
            return Err(super::blocks::corrupt("a piece of a ray"));
        }
        let head = std::array::from_fn(|k| match flags >> (16 + 16 * k) & 0xffff {
            0 => None,
            v => Some((v - 1) as u8),
        });
        Ok(Self {
            key,
            start,
            end,
            first: flags & 1 != 0,
            last: flags & 2 != 0,
            broken: flags & 4 != 0,
            head,
            head_len,
            run: Run::from_parts(code?, len?),
        })
    }
}

impl PartialCounts {
    /// The counts, rays and open pieces as bytes (little-endian words), to send to another
    /// process: [`from_bytes`](Self::from_bytes) reads them back to the same counts.
    #[must_use]
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut words = vec![MAGIC];
        self.counts.write(&mut words);
        words.extend([self.rays, self.fragments.len() as u64]);
        for f in &self.fragments {
            f.write(&mut words);
        }
        words.iter().flat_map(|w| w.to_le_bytes()).collect()
    }

    /// Counts [`to_bytes`](Self::to_bytes) wrote; an error for any other bytes.
    pub fn from_bytes(bytes: &[u8]) -> super::blocks::ReadResult<Self> {
        let corrupt = super::blocks::corrupt;
        if !bytes.len().is_multiple_of(8) {
            return Err(corrupt("not a whole number of words"));
        }
        let words: Vec<u64> = bytes
            .chunks_exact(8)
            .map(|c| u64::from_le_bytes(c.try_into().unwrap_or_default()))
            .collect();
        let mut words = super::blocks::Words::new(&words);
        if words.next()? != MAGIC {
            return Err(corrupt("not slabscope's partial counts"));
        }
        let counts = BlockCounts::read(&mut words)?;
        let (rays, n) = (words.next()?, words.next()?);
        if n > words.left() as u64 / 6 {
            return Err(corrupt("more pieces of rays than words"));
        }
        let fragments = (0..n)
            .map(|_| Fragment::read(&mut words))
            .collect::<super::blocks::ReadResult<Vec<_>>>()?;
        if words.left() > 0 {
            return Err(corrupt("words after the last piece"));
        }
        Ok(Self::of(counts, rays, fragments))
    }
}

/// The fragments `held` (in order of key and start) and `more` (in any order) in order, every
/// pair that meets stitched, counting into `counts` what crosses the seams.
fn stitched(
    held: Vec<Fragment>,
    mut more: Vec<Fragment>,
    counts: &mut BlockCounts,
) -> Vec<Fragment> {
    if more.is_empty() {
        return held;
    }
    // Only the new ones are sorted (unless they come in order, as a part's own do: a slab's
    // bands taken in order, or a part read back), and the two runs merged.
    let order = |f: &Fragment| (f.key, f.start);
    if !more.is_sorted_by_key(order) {
        more.sort_unstable_by_key(order);
    }
    let mut out: Vec<Fragment> = Vec::with_capacity(held.len() + more.len());
    let (mut a, mut b) = (held.into_iter().peekable(), more.into_iter().peekable());
    let merged = std::iter::from_fn(|| match (a.peek(), b.peek()) {
        (Some(x), Some(y)) if order(y) < order(x) => b.next(),
        (Some(_), _) => a.next(),
        (None, _) => b.next(),
    });
    for f in merged {
        match out.last_mut() {
            Some(prev) if prev.key == f.key && prev.end == f.start => {
                match prev.stitch(&f, counts) {
                    Some(joined) => *prev = joined,
                    None => {
                        out.pop();
                    }
                }
            }
            _ => out.push(f),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::Lcg;

    /// Sequences of symbols below `bins` with missing samples, of lengths 0 to `max`.
    fn sequences(lcg: &mut Lcg, n: usize, max: u64, bins: u64) -> Vec<Vec<Sample>> {
        let mut next = |k: u64| (lcg.next_u64() >> 33) % k;
        (0..n)
            .map(|_| {
                let len = next(max + 1);
                (0..len)
                    .map(|_| (next(9) != 0).then(|| next(bins) as u8))
                    .collect()
            })
            .collect()
    }

    fn whole(seqs: &[Vec<Sample>], bins: usize, block: usize) -> BlockCounts {
        let mut c = BlockCounts::new(bins, block);
        for seq in seqs.iter().filter(|s| !s.is_empty()) {
            for s in seq {
                match s {
                    Some(s) => c.push(*s),
                    None => c.end_sequence(),
                }
            }
            c.end_sequence();
        }
        c
    }

    fn same(a: &BlockCounts, b: &BlockCounts, at: &str) {
        for k in [1, a.block() - 1, a.block()] {
            assert_eq!(a.table(k), b.table(k), "{k}-blocks, {at}");
        }
        assert_eq!(a.entropies(), b.entropies(), "{at}");
    }

    #[test]
    fn pieces_counted_apart_and_added_in_any_order_count_the_whole() {
        let mut lcg = Lcg::new(42);
        for trial in 0..300 {
            let block = 2 + trial % 3;
            let bins = [2, 3, 5, 32][trial % 4];
            let seqs = sequences(&mut lcg, 12, 14, bins as u64);
            let mut next = |k: u64| (lcg.next_u64() >> 33) % k;
            // Each sequence cut at random places, each piece counted apart.
            let mut pieces = Vec::new();
            for (key, seq) in seqs.iter().enumerate().filter(|(_, s)| !s.is_empty()) {
                let n = seq.len() as u64;
                let mut cuts: Vec<u64> = (1..n).filter(|_| next(3) == 0).collect();
                cuts.insert(0, 0);
                cuts.push(n);
                for w in cuts.windows(2) {
                    let mut c = BlockCounts::new(bins, block);
                    let mut f = Fragment::new(key as u64, w[0]);
                    for &s in &seq[w[0] as usize..w[1] as usize] {
                        f.push(&mut c, s);
                    }
                    let rays = u64::from(f.first);
                    let open = f.close(&mut c, w[1] == n).into_iter().collect();
                    pieces.push(PartialCounts::of(c, rays, open));
                }
            }
            // Shuffled, added in random groups, the groups added.
            for i in (1..pieces.len()).rev() {
                pieces.swap(i, next(i as u64 + 1) as usize);
            }
            let mut groups: Vec<PartialCounts> = Vec::new();
            for p in pieces {
                let g = next(groups.len() as u64 + 1) as usize;
                match groups.get_mut(g) {
                    Some(group) => group.add(p),
                    None => groups.push(p),
                }
            }
            let mut total = PartialCounts::new(bins, block);
            while let Some(g) = groups.pop() {
                total.add(g);
            }
            let at = format!("trial {trial}, L {block}, {bins} bins");
            assert!(total.is_complete(), "{at}: {:?}", total.fragments());
            let met = seqs.iter().filter(|s| !s.is_empty()).count() as u64;
            assert_eq!(total.rays, met, "{at}");
            same(&total.counts, &whole(&seqs, bins, block), &at);
        }
    }

    #[test]
    fn ray_keys_are_in_the_order_of_row_then_ray() {
        let rays = [
            (-3, -2),
            (5, -2),
            (-7, -1),
            (-1, 0),
            (0, 0),
            (2, 0),
            (-9, 4),
            (1, 4),
        ];
        let keys: Vec<u64> = rays.iter().map(|&(i, j)| ray_key(i, j)).collect();
        assert!(keys.windows(2).all(|w| w[0] < w[1]), "{keys:x?}");
        assert_eq!(ray_key(0, 0), 0x8000_0000_8000_0000);
        assert_eq!(ray_key(-1, 1), 0x8000_0001_7fff_ffff);
    }

    #[test]
    fn a_piece_alone_counts_only_what_it_holds() {
        // a b a b c as a b | a b c: the first piece holds no 3-block, the second only abc;
        // aba and bab cross the seam and are counted when the pieces meet.
        let seq = [0u8, 1, 0, 1, 2];
        let mut parts = Vec::new();
        for (start, end) in [(0, 2), (2, 5)] {
            let mut c = BlockCounts::new(4, 3);
            let mut f = Fragment::new(7, start);
            for &s in &seq[start as usize..end as usize] {
                f.push(&mut c, Some(s));
            }
            let f = f.close(&mut c, end == 5).unwrap();
            parts.push((c, f));
        }
        assert_eq!(parts[0].0.blocks(), 0);
        assert_eq!(parts[1].0.table(3).unwrap(), vec![(vec![0, 1, 2], 1)]);
        let (c0, f0) = parts.remove(0);
        let (c1, f1) = parts.remove(0);
        let mut total = PartialCounts::of(c0, 1, vec![f0]);
        total.add(PartialCounts::of(c1, 0, vec![f1]));
        assert!(total.is_complete());
        let mut expect = BlockCounts::new(4, 3);
        for s in seq {
            expect.push(s);
        }
        expect.end_sequence();
        same(&total.counts, &expect, "a b | a b c");
    }
}
