//! Block entropies of symbol sequences (paper eq. 2): counts of L-blocks, (L-1)-blocks and single
//! symbols pooled over many sequences, as the entropy rate `h = H(X^L) - H(X^(L-1))` needs.

use std::collections::HashMap;

use super::{entropy, sum_c_log_c};

/// Codes up to this many bits are counted in a dense array; longer ones in a hash map.
const DENSE_BITS: u32 = 18;

/// A histogram over block codes, dense for small alphabets.
#[derive(Clone, Debug)]
enum Table {
    Dense(Vec<u64>),
    Sparse(HashMap<u64, u64>),
}

impl Table {
    fn new(bits: u32) -> Self {
        if bits <= DENSE_BITS {
            Self::Dense(vec![0; 1 << bits])
        } else {
            Self::Sparse(HashMap::new())
        }
    }

    #[inline]
    fn add(&mut self, code: u64) {
        match self {
            Self::Dense(v) => v[code as usize] += 1,
            Self::Sparse(m) => *m.entry(code).or_insert(0) += 1,
        }
    }

    fn merge(&mut self, other: &Self) {
        match (self, other) {
            (Self::Dense(a), Self::Dense(b)) => a.iter_mut().zip(b).for_each(|(x, y)| *x += y),
            (Self::Sparse(a), Self::Sparse(b)) => {
                for (k, c) in b {
                    *a.entry(*k).or_insert(0) += c;
                }
            }
            _ => unreachable!("tables of one BlockCounts share a layout"),
        }
    }

    fn total(&self) -> u64 {
        match self {
            Self::Dense(v) => v.iter().sum(),
            Self::Sparse(m) => m.values().sum(),
        }
    }

    fn entropy(&self) -> f64 {
        let n = self.total();
        if n == 0 {
            return 0.0;
        }
        let s = match self {
            Self::Dense(v) => sum_c_log_c(v.iter().copied()),
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

/// Where one sequence stands: its last L symbols as a packed code, and how many symbols it has.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Run {
    code: u64,
    len: usize,
}

/// Counts of the L-blocks, (L-1)-blocks and single symbols of sequences over `bins` symbols.
///
/// Feed one sequence at a time with [`push`](Self::push) and end it with
/// [`end_sequence`](Self::end_sequence), or interleave many with [`push_to`](Self::push_to), each
/// with its own [`Run`]: blocks never span two sequences. Merge counts from several threads with
/// [`merge`](Self::merge); counts are integers, so the result does not depend on the order.
#[derive(Clone, Debug)]
pub struct BlockCounts {
    block: usize,
    bits: u32,
    run: Run,
    long_mask: u64,
    short_mask: u64,
    long: Table,
    short: Table,
    /// Counts per symbol, indexed by the byte itself so that no bounds check is needed.
    single: Box<[u64; 256]>,
    bins: usize,
}

impl BlockCounts {
    /// Empty counts for blocks of length `block` (2 to 4) over `bins` symbols (2 to 256).
    pub fn new(bins: usize, block: usize) -> Self {
        assert!((2..=4).contains(&block), "block length {block}");
        assert!((2..=256).contains(&bins), "bins {bins}");
        let bits = usize::BITS - (bins - 1).leading_zeros();
        Self {
            block,
            bits,
            run: Run::default(),
            long_mask: (1u64 << (bits * block as u32)) - 1,
            short_mask: (1u64 << (bits * (block as u32 - 1))) - 1,
            long: Table::new(bits * block as u32),
            short: Table::new(bits * (block as u32 - 1)),
            single: Box::new([0; 256]),
            bins,
        }
    }

    /// Appends a symbol to the sequence whose state is `run`.
    #[inline]
    pub fn push_to(&mut self, run: &mut Run, symbol: u8) {
        run.code = ((run.code << self.bits) | u64::from(symbol)) & self.long_mask;
        run.len += 1;
        self.single[symbol as usize] += 1;
        if run.len + 1 >= self.block {
            self.short.add(run.code & self.short_mask);
            if run.len >= self.block {
                self.long.add(run.code);
            }
        }
    }

    /// Appends a symbol to the current sequence.
    #[inline]
    pub fn push(&mut self, symbol: u8) {
        let mut run = self.run;
        self.push_to(&mut run, symbol);
        self.run = run;
    }

    /// Ends the current sequence (also used where a missing sample breaks a ray).
    #[inline]
    pub fn end_sequence(&mut self) {
        self.run = Run::default();
    }

    /// Adds `other`'s counts to these.
    pub fn merge(&mut self, other: &Self) {
        self.long.merge(&other.long);
        self.short.merge(&other.short);
        self.single
            .iter_mut()
            .zip(other.single.iter())
            .for_each(|(a, b)| *a += b);
    }

    /// Number of symbols counted.
    pub fn symbols(&self) -> u64 {
        self.single.iter().sum()
    }

    /// The block length L.
    pub fn block(&self) -> usize {
        self.block
    }

    /// `(H(X^1), H(X^(L-1)), H(X^L))` in bits.
    pub fn entropies(&self) -> (f64, f64, f64) {
        (
            entropy(self.single[..self.bins].iter().copied()),
            self.short.entropy(),
            self.long.entropy(),
        )
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
        x.merge(&y);
        let both = block_entropies([a[0], b[0]], 4, 3);
        assert_eq!(x.entropies(), both);
        assert_eq!(x.symbols(), 7);
    }
}
