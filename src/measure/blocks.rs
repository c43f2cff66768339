//! Block entropies of symbol sequences (paper eq. 2): counts of L-blocks, (L-1)-blocks and single
//! symbols pooled over many sequences, as the entropy rate `h = H(X^L) - H(X^(L-1))` needs.
//!
//! Only the L-blocks are counted per symbol. Every (L-1)-block of a sequence but its last is the
//! first L-1 symbols of an L-block, and every symbol but the last L-1 is the first symbol of one;
//! so the (L-1)-block and symbol counts are the L-block counts summed over their trailing symbols,
//! plus what each sequence leaves at its end. That makes a symbol one table update instead of
//! three.

use std::collections::HashMap;

mod codec;
pub use codec::ReadResult;
pub(crate) use codec::{Bytes, Words, corrupt, put_varint};

use super::{entropy, sum_c_log_c};

/// Codes up to this many bits are counted in a dense array; longer ones in a hash map.
const DENSE_BITS: u32 = 18;

/// A histogram over block codes, dense for small alphabets.
#[derive(Clone, Debug)]
enum Table {
    /// One count per code, and one more that counts nothing: a slot that branch-free code can
    /// add to when it has nothing to count (see [`DenseCounts::split`]).
    Dense(Vec<u64>),
    Sparse(HashMap<u64, u64>),
}

/// The counts of a dense table, without its spare slot.
fn counted(v: &[u64]) -> &[u64] {
    &v[..v.len() - 1]
}

impl Table {
    fn new(bits: u32) -> Self {
        if bits <= DENSE_BITS {
            Self::Dense(vec![0; (1 << bits) + 1])
        } else {
            Self::Sparse(HashMap::new())
        }
    }

    /// About the bytes [`new`](Self::new)'s table for codes of `bits` bits holds: exactly where
    /// it is dense (a word a code), and 32 bytes a possible code where it is a map (an entry a
    /// code counted, every code at worst).
    fn held_bytes(bits: u32) -> u64 {
        let codes = 1u64 << bits.min(40);
        if bits <= DENSE_BITS {
            8 * (codes + 1)
        } else {
            32 * codes
        }
    }

    #[inline]
    fn add(&mut self, code: u64, n: u64) {
        match self {
            Self::Dense(v) => v[code as usize] += n,
            Self::Sparse(m) => add_sparse(m, code, n),
        }
    }

    /// Calls `f(code, count)` for every code counted.
    fn for_each(&self, mut f: impl FnMut(u64, u64)) {
        match self {
            Self::Dense(v) => counted(v)
                .iter()
                .enumerate()
                .filter(|(_, c)| **c > 0)
                .for_each(|(k, &c)| f(k as u64, c)),
            Self::Sparse(m) => m.iter().for_each(|(&k, &c)| f(k, c)),
        }
    }

    fn merge(&mut self, other: &Self) {
        match (self, other) {
            (Self::Dense(a), Self::Dense(b)) => a.iter_mut().zip(b).for_each(|(x, y)| *x += y),
            (a, b) => b.for_each(|k, c| a.add(k, c)),
        }
    }

    fn total(&self) -> u64 {
        match self {
            Self::Dense(v) => counted(v).iter().sum(),
            Self::Sparse(m) => m.values().sum(),
        }
    }

    fn entropy(&self) -> f64 {
        let n = self.total();
        if n == 0 {
            return 0.0;
        }
        let s = match self {
            Self::Dense(v) => sum_c_log_c(counted(v).iter().copied()),
            Self::Sparse(m) => {
                // In a fixed order: a hash map's order changes from run to run, and with it the
                // last bits of a floating-point sum.
                let mut counts: Vec<u64> = m.values().copied().collect();
                counts.sort_unstable();
                sum_c_log_c(counts)
            }
        };
        ((n as f64).log2() - s / n as f64).max(0.0)
    }
}

/// Kept out of line so that the dense path of [`Table::add`] stays small enough to inline.
#[inline(never)]
fn add_sparse(m: &mut HashMap<u64, u64>, code: u64, n: u64) {
    *m.entry(code).or_insert(0) += n;
}

/// Where one sequence stands: its last L symbols as a packed code, and how many symbols it has.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Run {
    code: u64,
    len: u64,
}

impl Run {
    /// A run with the packed code of its last symbols and its length (which may be capped at
    /// L: only whether it reaches L - 1 and L matters).
    pub fn from_parts(code: u64, len: u64) -> Self {
        Self { code, len }
    }

    /// `(code, length)`.
    pub fn parts(&self) -> (u64, u64) {
        (self.code, self.len)
    }
}

/// How symbols pack into block codes: `bits` per symbol, the latest in the lowest bits.
#[derive(Clone, Copy, Debug)]
struct Packing {
    bits: u32,
    block: u64,
    long_mask: u64,
    short_mask: u64,
}

impl Packing {
    /// `run` with `symbol` appended; whether it now ends an L-block.
    #[inline]
    fn push(&self, run: &mut Run, symbol: u8) -> bool {
        run.code = ((run.code << self.bits) | u64::from(symbol)) & self.long_mask;
        run.len += 1;
        run.len >= self.block
    }
}

/// What ended sequences leave beyond their L-blocks: the last (L-1)-block of each (the one that
/// starts no L-block) and its last L-1 symbols (indexed by the byte itself: no bounds check).
#[derive(Clone, Debug)]
struct Ends {
    short: Table,
    single: Box<[u64; 256]>,
}

impl Ends {
    fn end_run(&mut self, packing: &Packing, run: &mut Run) {
        let tail = run.len.min(packing.block - 1);
        if tail == packing.block - 1 {
            self.short.add(run.code & packing.short_mask, 1);
        }
        let symbol_mask = (1u64 << packing.bits) - 1;
        for i in 0..tail {
            self.single[((run.code >> (u64::from(packing.bits) * i)) & symbol_mask) as usize] += 1;
        }
        *run = Run::default();
    }
}

/// Something that counts the blocks of interleaved sequences: [`BlockCounts`], or its
/// [`DenseCounts`] view for hot loops.
pub trait Counter {
    /// Appends a symbol to the sequence whose state is `run`.
    fn push_to(&mut self, run: &mut Run, symbol: u8);

    /// Ends the sequence whose state is `run` (at its end or where a missing sample breaks it),
    /// counting what it leaves, and resets `run` for a new one.
    fn end_run(&mut self, run: &mut Run);
}

/// Counts of the L-blocks, (L-1)-blocks and single symbols of sequences over `bins` symbols.
///
/// Feed one sequence at a time with [`push`](Self::push) and end it with
/// [`end_sequence`](Self::end_sequence), or interleave many through [`Counter`], each with its
/// own [`Run`]: blocks never span two sequences. Merge counts from several threads with
/// [`merge`](Self::merge); counts are integers, so the result does not depend on the order.
#[derive(Clone, Debug)]
pub struct BlockCounts {
    packing: Packing,
    run: Run,
    long: Table,
    ends: Ends,
    bins: usize,
}

impl Counter for BlockCounts {
    #[inline]
    fn push_to(&mut self, run: &mut Run, symbol: u8) {
        if self.packing.push(run, symbol) {
            self.long.add(run.code, 1);
        }
    }

    fn end_run(&mut self, run: &mut Run) {
        self.ends.end_run(&self.packing, run);
    }
}

/// A view of [`BlockCounts`] whose L-block table is a dense array, so that counting a symbol
/// needs no dispatch: see [`BlockCounts::dense`].
pub struct DenseCounts<'a> {
    packing: Packing,
    long: &'a mut [u64],
    ends: &'a mut Ends,
}

impl DenseCounts<'_> {
    /// `(bits per symbol, mask of an L-block code, L)`.
    pub fn packing(&self) -> (u32, u64, u64) {
        (
            self.packing.bits,
            self.packing.long_mask,
            self.packing.block,
        )
    }

    /// The L-block counts, indexed by code (`mask + 1` of them) and followed by a spare slot
    /// that counts nothing, and what ends runs.
    pub fn split(&mut self) -> (&mut [u64], RunEnds<'_>) {
        (
            &mut *self.long,
            RunEnds {
                packing: self.packing,
                ends: &mut *self.ends,
            },
        )
    }
}

/// Ends runs of a [`DenseCounts`] while its L-block counts are borrowed: see
/// [`DenseCounts::split`].
pub struct RunEnds<'a> {
    packing: Packing,
    ends: &'a mut Ends,
}

impl RunEnds<'_> {
    /// As [`Counter::end_run`].
    pub fn end_run(&mut self, run: &mut Run) {
        self.ends.end_run(&self.packing, run);
    }
}

impl Counter for DenseCounts<'_> {
    #[inline]
    fn push_to(&mut self, run: &mut Run, symbol: u8) {
        if self.packing.push(run, symbol) {
            self.long[run.code as usize] += 1;
        }
    }

    fn end_run(&mut self, run: &mut Run) {
        self.ends.end_run(&self.packing, run);
    }
}

impl BlockCounts {
    /// About the bytes [`new`](Self::new)'s tables for `bins` and `block` hold (each table's as
    /// `Table::held_bytes` says).
    #[must_use]
    pub fn held_bytes(bins: usize, block: usize) -> u64 {
        let bits = usize::BITS - (bins.max(2) - 1).leading_zeros();
        let long = bits * block as u32;
        Table::held_bytes(long) + Table::held_bytes(long.saturating_sub(bits)) + 8 * 256
    }

    /// Empty counts for blocks of length `block` (2 to 4) over `bins` symbols (2 to 256).
    pub fn new(bins: usize, block: usize) -> Self {
        assert!((2..=4).contains(&block), "block length {block}");
        assert!((2..=256).contains(&bins), "bins {bins}");
        let bits = usize::BITS - (bins - 1).leading_zeros();
        let block_bits = bits * block as u32;
        Self {
            packing: Packing {
                bits,
                block: block as u64,
                long_mask: (1u64 << block_bits) - 1,
                short_mask: (1u64 << (block_bits - bits)) - 1,
            },
            run: Run::default(),
            long: Table::new(block_bits),
            ends: Ends {
                short: Table::new(block_bits - bits),
                single: Box::new([0; 256]),
            },
            bins,
        }
    }

    /// The fast view, when the L-block table is dense (`bits × L` at most 18: 32 bins with
    /// L = 3, or 8 bins with L = 4, for example).
    pub fn dense(&mut self) -> Option<DenseCounts<'_>> {
        match &mut self.long {
            Table::Dense(long) => Some(DenseCounts {
                packing: self.packing,
                long,
                ends: &mut self.ends,
            }),
            Table::Sparse(_) => None,
        }
    }

    /// Appends a symbol to the current sequence.
    #[inline]
    pub fn push(&mut self, symbol: u8) {
        let mut run = self.run;
        self.push_to(&mut run, symbol);
        self.run = run;
    }

    /// Ends the current sequence (also used where a missing sample breaks a sequence).
    #[inline]
    pub fn end_sequence(&mut self) {
        let mut run = self.run;
        self.end_run(&mut run);
        self.run = run;
    }

    /// Appends `sample` to the run `run` without counting anything (a missing sample starts it
    /// afresh): the state a run would have, for counting what follows.
    pub fn prime(&self, run: &mut Run, sample: Option<u8>) {
        match sample {
            Some(s) => {
                self.packing.push(run, s);
            }
            None => *run = Run::default(),
        }
    }

    /// Whether `other` counts blocks of the same length over the same symbols, so that the two
    /// can be [merged](Self::merge).
    #[must_use]
    pub fn agrees(&self, other: &Self) -> bool {
        self.bins == other.bins && self.packing.block == other.packing.block
    }

    /// Adds `other`'s counts to these (both with no sequence under way, and [agreeing](Self::agrees)).
    pub fn merge(&mut self, other: &Self) {
        self.long.merge(&other.long);
        self.ends.short.merge(&other.ends.short);
        self.ends
            .single
            .iter_mut()
            .zip(other.ends.single.iter())
            .for_each(|(a, b)| *a += b);
    }

    /// Number of symbols counted in ended sequences.
    pub fn symbols(&self) -> u64 {
        self.long.total() + self.ends.single.iter().sum::<u64>()
    }

    /// Number of L-blocks counted.
    pub fn blocks(&self) -> u64 {
        self.long.total()
    }

    /// The number of symbols counted over.
    pub fn bins(&self) -> usize {
        self.bins
    }

    /// The bits an L-block's code may have set.
    pub(crate) fn code_mask(&self) -> u64 {
        self.packing.long_mask
    }

    /// The block length L.
    pub fn block(&self) -> usize {
        self.packing.block as usize
    }

    /// `(H(X^1), H(X^(L-1)), H(X^L))` in bits, over the ended sequences.
    pub fn entropies(&self) -> (f64, f64, f64) {
        let bits = self.packing.bits;
        let short_bits = bits * (self.packing.block as u32 - 1);
        let mut short = self.ends.short.clone();
        let mut single = *self.ends.single;
        self.long.for_each(|code, n| {
            short.add(code >> bits, n);
            single[(code >> short_bits) as usize] += n;
        });
        (
            entropy(single[..self.bins].iter().copied()),
            short.entropy(),
            self.long.entropy(),
        )
    }
}

impl BlockCounts {
    /// The non-zero counts of the blocks of length `k` (1, L-1 or L), each block's symbols in
    /// sequence order, most frequent first (ties by the symbols): the tables the entropies of
    /// [`entropies`](Self::entropies) are taken over. `None` for another length.
    pub fn table(&self, k: usize) -> Option<Vec<(Vec<u8>, u64)>> {
        let block = self.block();
        if k != 1 && k + 1 != block && k != block {
            return None;
        }
        let bits = self.packing.bits;
        let mask = (1u64 << bits) - 1;
        let mut codes: HashMap<u64, u64> = HashMap::new();
        let mut add = |code: u64, n: u64| *codes.entry(code).or_insert(0) += n;
        let short_bits = bits * (block as u32 - 1);
        if k == block {
            self.long.for_each(&mut add);
        } else if k == 1 {
            let mut single = *self.ends.single;
            self.long
                .for_each(|code, n| single[(code >> short_bits) as usize] += n);
            for (s, &n) in single.iter().enumerate().filter(|(_, n)| **n > 0) {
                add(s as u64, n);
            }
        } else {
            self.ends.short.for_each(&mut add);
            self.long.for_each(|code, n| add(code >> bits, n));
        }
        let symbols = |code: u64| -> Vec<u8> {
            (0..k)
                .rev()
                .map(|i| ((code >> (bits * i as u32)) & mask) as u8)
                .collect()
        };
        let mut out: Vec<(Vec<u8>, u64)> =
            codes.into_iter().map(|(c, n)| (symbols(c), n)).collect();
        out.sort_unstable_by(|a, b| b.1.cmp(&a.1).then_with(|| a.0.cmp(&b.0)));
        Some(out)
    }
}

/// `(H(X^1), H(X^(L-1)), H(X^L))` of the given sequences, each a slice of symbols below `bins`.
pub fn block_entropies<'a>(
    sequences: impl IntoIterator<Item = &'a [u8]>,
    bins: usize,
    block: usize,
) -> (f64, f64, f64) {
    let mut counts = BlockCounts::new(bins, block);
    for seq in sequences {
        for &s in seq {
            counts.push(s);
        }
        counts.end_sequence();
    }
    counts.entropies()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::Lcg;

    const EPS: f64 = 1e-12;

    #[test]
    fn the_papers_five_sample_example() {
        // x0..x4 = a b a b c: 3-blocks aba, bab, abc; 2-blocks ab, ba, ab, bc.
        let (h1, h2, h3) = block_entropies([&[0u8, 1, 0, 1, 2][..]], 4, 3);
        let h = |p: &[f64]| -p.iter().map(|p| p * p.log2()).sum::<f64>();
        assert!((h1 - h(&[0.4, 0.4, 0.2])).abs() < EPS);
        assert!((h2 - h(&[0.5, 0.25, 0.25])).abs() < EPS);
        assert!((h3 - 3f64.log2()).abs() < EPS);
    }

    #[test]
    fn blocks_do_not_span_sequences() {
        // Two sequences "01" and "01": 2-blocks are only (0,1) twice, never (1,0).
        let (_, h1, h2) = block_entropies([&[0u8, 1][..], &[0, 1][..]], 2, 2);
        assert!((h1 - 1.0).abs() < EPS, "H(X^1) = {h1}");
        assert!(h2.abs() < EPS, "H(X^2) = {h2}");
    }

    #[test]
    fn a_periodic_sequence_has_zero_entropy_rate() {
        let seq: Vec<u8> = (0..300).map(|i| (i % 3) as u8).collect();
        for block in 2..=4 {
            let (_, hs, hl) = block_entropies([&seq[..]], 3, block);
            assert!((hl - hs).abs() < 1e-3, "L = {block}: {hl} - {hs}");
        }
    }

    #[test]
    fn wide_alphabets_match_a_brute_force_count() {
        // 256 bins with L = 3 needs 24-bit codes: the hash-map table.
        let seq: Vec<u8> = (0..500u32).map(|i| (i * i * 37 % 253) as u8).collect();
        let brute = |len: usize| {
            let mut m: HashMap<&[u8], u64> = HashMap::new();
            for w in seq.windows(len) {
                *m.entry(w).or_insert(0) += 1;
            }
            entropy(m.into_values().collect::<Vec<_>>())
        };
        let (h1, h2, h3) = block_entropies([&seq[..]], 256, 3);
        assert!((h1 - brute(1)).abs() < EPS);
        assert!((h2 - brute(2)).abs() < EPS);
        assert!((h3 - brute(3)).abs() < EPS);
    }

    #[test]
    fn many_short_sequences_match_a_brute_force_count() {
        let mut lcg = Lcg::new(7);
        let mut next = |n: u64| (lcg.next_u64() >> 33) % n;
        for block in 2..=4 {
            let seqs: Vec<Vec<u8>> = (0..60)
                .map(|_| {
                    let len = next(9);
                    (0..len).map(|_| next(3) as u8).collect()
                })
                .collect();
            let brute = |len: usize| {
                let mut m: HashMap<&[u8], u64> = HashMap::new();
                for w in seqs.iter().flat_map(|s| s.windows(len)) {
                    *m.entry(w).or_insert(0) += 1;
                }
                entropy(m.into_values().collect::<Vec<_>>())
            };
            let got = block_entropies(seqs.iter().map(Vec::as_slice), 3, block);
            let expect = (brute(1), brute(block - 1), brute(block));
            assert!((got.0 - expect.0).abs() < EPS, "L = {block}");
            assert!((got.1 - expect.1).abs() < EPS, "L = {block}");
            assert!((got.2 - expect.2).abs() < EPS, "L = {block}");
        }
    }

    #[test]
    fn tables_list_every_block_with_its_count() {
        // a b a b c and a b: 3-blocks aba, bab, abc; 2-blocks ab ×3, ba, bc; symbols a ×3, b ×3, c.
        let mut x = BlockCounts::new(4, 3);
        for seq in [&[0u8, 1, 0, 1, 2][..], &[0, 1][..]] {
            for &s in seq {
                x.push(s);
            }
            x.end_sequence();
        }
        let three = vec![(vec![0, 1, 0], 1), (vec![0, 1, 2], 1), (vec![1, 0, 1], 1)];
        assert_eq!(x.table(3).unwrap(), three);
        let two = vec![(vec![0, 1], 3), (vec![1, 0], 1), (vec![1, 2], 1)];
        assert_eq!(x.table(2).unwrap(), two);
        assert_eq!(
            x.table(1).unwrap(),
            vec![(vec![0], 3), (vec![1], 3), (vec![2], 1)]
        );
        assert_eq!(x.table(4), None);
        let (h1, h2, h3) = x.entropies();
        let h = |t: Vec<(Vec<u8>, u64)>| entropy(t.into_iter().map(|(_, n)| n).collect::<Vec<_>>());
        assert!((h(x.table(1).unwrap()) - h1).abs() < EPS);
        assert!((h(x.table(2).unwrap()) - h2).abs() < EPS);
        assert!((h(x.table(3).unwrap()) - h3).abs() < EPS);
    }

    #[test]
    fn merging_is_counting_together() {
        let a = [&[0u8, 1, 2, 3][..]];
        let b = [&[3u8, 3, 1][..]];
        let mut x = BlockCounts::new(4, 3);
        let mut y = BlockCounts::new(4, 3);
        for s in a[0] {
            x.push(*s);
        }
        for s in b[0] {
            y.push(*s);
        }
        x.end_sequence();
        y.end_sequence();
        x.merge(&y);
        let both = block_entropies([a[0], b[0]], 4, 3);
        assert_eq!(x.entropies(), both);
        assert_eq!(x.symbols(), 7);
    }
}
