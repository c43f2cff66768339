//! Partial counts as bytes, to send to another process (issue #44: a cluster's parts): the
//! counts as little-endian words, then the open pieces of rays, each in a few bytes.
//!
//! The pieces are in order of key and start, so each is written as the step from the last
//! one's key, its start and length, its flags and head and its run's code, each number as a
//! LEB128 varint: about 10 bytes a piece of a ray crossing a slab's face, where six words
//! (48 bytes) were written before version 3.

use super::{Fragment, HEAD_MISSING, MAX_HEAD, PartialCounts, RUN_LEN};
use crate::measure::blocks::{BlockCounts, Bytes, ReadResult, Words, corrupt, put_varint};

/// The first word of [`PartialCounts::to_bytes`]: `SLABPC`, a zero and the version. 3 since
/// the pieces are written in a few bytes each (2: six words a piece; 1: ray keys in another
/// order, which would not stitch to these).
const MAGIC: [u8; 8] = *b"SLABPC\x00\x03";

/// The fewest bytes a piece takes: its key's step, start, length, flags and code.
const LEAST_PIECE: usize = 5;

/// What reading pieces past their end says.
const CUT: &str = "counts cut short: the pieces of rays end early";

impl Fragment {
    /// Appends the fragment, `last_key` the key of the one written before it (0 for the first).
    fn write(&self, last_key: u64, block: usize, out: &mut Vec<u8>) {
        // The step from the last key, which is no greater (wrapping, so that any order reads
        // back as it was written).
        put_varint(out, self.key.wrapping_sub(last_key));
        put_varint(out, self.start);
        put_varint(out, self.len());
        out.push(self.bits);
        out.extend_from_slice(&self.head[..self.head_len(block)]);
        put_varint(out, u64::from(self.code));
    }

    /// A fragment [`write`](Self::write) wrote after one of key `last_key`, for `counts`.
    fn read(bytes: &mut Bytes, last_key: u64, counts: &BlockCounts) -> ReadResult<Self> {
        let key = last_key.wrapping_add(bytes.varint()?);
        let start = bytes.varint()?;
        let end = start
            .checked_add(bytes.varint()?)
            .ok_or_else(|| corrupt("a piece of a ray past 2^64 samples"))?;
        let mut f = Self {
            key,
            start,
            end,
            code: 0,
            head: [0; MAX_HEAD],
            bits: bytes.byte()?,
        };
        let head = f.head_len(counts.block());
        let missing = u32::from(f.bits >> HEAD_MISSING) & ((1 << (RUN_LEN - HEAD_MISSING)) - 1);
        if missing >> head != 0 {
            return Err(corrupt("a missing sample past a piece's head"));
        }
        if f.first() && f.last() {
            return Err(corrupt("a whole ray kept as an open piece"));
        }
        for k in 0..head {
            f.head[k] = bytes.byte()?;
            if usize::from(f.head[k]) >= counts.bins() {
                return Err(corrupt("a symbol beyond the bins"));
            }
        }
        let code = bytes.varint()?;
        if code & !counts.code_mask() != 0 {
            return Err(corrupt("a run's code beyond its blocks"));
        }
        f.code = code as u32;
        Ok(f)
    }
}

impl PartialCounts {
    /// The counts, rays and open pieces as bytes (little-endian words, then the pieces in a few
    /// bytes each, padded to a whole word), to send to another process:
    /// [`from_bytes`](Self::from_bytes) reads them back to the same counts.
    #[must_use]
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut words = vec![u64::from_le_bytes(MAGIC)];
        self.counts.write(&mut words);
        // The pieces' length, known once they are written.
        words.extend([self.rays, self.fragments.len() as u64, 0]);
        let mut out = Vec::with_capacity(8 * words.len() + 12 * self.fragments.len() + 8);
        for w in words {
            out.extend_from_slice(&w.to_le_bytes());
        }
        let at = out.len();
        let block = self.counts.block();
        let mut last_key = 0;
        for f in &self.fragments {
            f.write(last_key, block, &mut out);
            last_key = f.key;
        }
        let len = (out.len() - at) as u64;
        out[at - 8..at].copy_from_slice(&len.to_le_bytes());
        out.resize(out.len().next_multiple_of(8), 0);
        out
    }

    /// Counts [`to_bytes`](Self::to_bytes) wrote; an error for any other bytes, those of
    /// another version of slabscope among them.
    pub fn from_bytes(bytes: &[u8]) -> ReadResult<Self> {
        let mut words = Words::new(bytes);
        words.magic(MAGIC, "partial counts")?;
        if !bytes.len().is_multiple_of(8) {
            return Err(corrupt("not a whole number of words"));
        }
        let counts = BlockCounts::read(&mut words)?;
        let (rays, n, len) = (words.next()?, words.next()?, words.next()?);
        let rest = words.rest();
        if len > rest.len() as u64 || rest.len() as u64 - len >= 8 {
            return Err(corrupt("the pieces of rays are not the length written"));
        }
        let (pieces, pad) = rest.split_at(len as usize);
        if n > len / LEAST_PIECE as u64 {
            return Err(corrupt("more pieces of rays than bytes"));
        }
        if pad.iter().any(|&b| b != 0) {
            return Err(corrupt("bytes after the last piece"));
        }
        let mut bytes = Bytes::new(pieces, CUT);
        let mut fragments = Vec::with_capacity(n as usize);
        let mut last_key = 0;
        for _ in 0..n {
            let f = Fragment::read(&mut bytes, last_key, &counts)?;
            last_key = f.key;
            fragments.push(f);
        }
        if !bytes.is_done() {
            return Err(corrupt("bytes after the last piece"));
        }
        Ok(Self::of(counts, rays, fragments))
    }
}

#[cfg(test)]
mod tests {
    use super::super::{BROKEN, LAST};
    use super::*;
    use crate::measure::Counter;

    /// A part of two rays' pieces: a whole one, one open at both ends with a missing sample
    /// in its head, and one starting its ray.
    fn part() -> PartialCounts {
        let mut c = BlockCounts::new(32, 3);
        let mut run = crate::measure::Run::default();
        for s in [3, 1, 4, 1, 5] {
            c.push_to(&mut run, s);
        }
        c.end_run(&mut run);
        let mut open = Vec::new();
        let mut a = Fragment::new(super::super::ray_key(-2, 7), 40);
        for s in [None, Some(9), Some(2), Some(6)] {
            a.push(&mut c, s);
        }
        open.extend(a.close(&mut c, false));
        let mut b = Fragment::new(super::super::ray_key(5, 7), 0);
        for s in [Some(31), Some(0), Some(8)] {
            b.push(&mut c, s);
        }
        open.extend(b.close(&mut c, false));
        PartialCounts::of(c, 2, open)
    }

    #[test]
    fn a_part_reads_back_to_the_same_counts_and_pieces() {
        let p = part();
        let bytes = p.to_bytes();
        assert_eq!(bytes.len() % 8, 0);
        let back = PartialCounts::from_bytes(&bytes).unwrap();
        assert_eq!(back.fragments(), p.fragments());
        assert_eq!(back.rays, 2);
        assert_eq!(back.counts.table(3), p.counts.table(3));
        assert_eq!(back.to_bytes(), bytes);
        // The second piece: its key 5 - (-2) = 7 past the first's, start 0 and 3 samples,
        // flags (a run of 3: 0b011 << 5), no head, the run's code (31, 0, 8 at 5 bits each).
        let mut tail = Vec::new();
        put_varint(&mut tail, 7);
        tail.extend([0, 3, 3 << 5]);
        put_varint(&mut tail, (31 << 10) | 8);
        let end = bytes.iter().rposition(|&b| b != 0).unwrap() + 1;
        assert_eq!(&bytes[end - tail.len()..end], &tail[..]);
        // The pieces in 24 bytes (the first's key takes 10), where version 2 wrote 96.
        let mut pieces = Vec::new();
        p.fragments()[0].write(0, 3, &mut pieces);
        assert_eq!(pieces.len() + tail.len(), 24);
    }

    #[test]
    fn other_versions_and_broken_pieces_are_refused() {
        let p = part();
        let bytes = p.to_bytes();
        let with = |at: usize, b: u8| {
            let mut x = bytes.clone();
            x[at] = b;
            PartialCounts::from_bytes(&x).err().unwrap_or_default()
        };
        let e = with(7, 2);
        assert!(
            e.contains("version 2 where this slabscope reads version 3"),
            "{e}"
        );
        assert!(with(0, b'X').contains("not slabscope's partial counts"));
        // However few the bytes: foreign ones are foreign, the start of a part is cut short.
        let few = |b: &[u8]| PartialCounts::from_bytes(b).err().unwrap_or_default();
        assert!(few(b"junk").contains("not slabscope's partial counts"));
        assert!(
            few(&bytes[..4]).contains("cut short"),
            "{}",
            few(&bytes[..4])
        );
        assert!(few(&bytes[..12]).contains("not a whole number of words"));
        // The first piece: its key's step (10 bytes: the key has its top bit set), start 40,
        // 4 samples, flags, a head of two samples (the first missing: 0), its run's code.
        let mut pieces = Vec::new();
        p.fragments()[0].write(0, 3, &mut pieces);
        p.fragments()[1].write(p.fragments()[0].key, 3, &mut pieces);
        let at = bytes.len() - pieces.len().next_multiple_of(8);
        assert_eq!(&bytes[at..at + pieces.len()], &pieces[..]);
        assert_eq!(&bytes[at + 10..at + 12], &[40, 4]);
        let flags = bytes[at + 12];
        assert_eq!(flags & LAST, 0);
        assert_eq!(flags & BROKEN, BROKEN);
        assert_eq!(flags >> HEAD_MISSING & 0b111, 0b001, "{flags:b}");
        assert_eq!(&bytes[at + 13..at + 15], &[0, 9]);
        let e = with(at + 12, flags | 1 << (HEAD_MISSING + 2));
        assert!(e.contains("a missing sample past a piece's head"), "{e}");
        assert!(with(at + 14, 32).contains("a symbol beyond the bins"));
        assert!(with(at + 12, flags | LAST).is_empty(), "a last piece reads");
        // Cut anywhere, or a word more: refused.
        for cut in (0..bytes.len()).step_by(8) {
            assert!(
                PartialCounts::from_bytes(&bytes[..cut]).is_err(),
                "cut at {cut}"
            );
        }
        let mut long = bytes.clone();
        long.extend([0; 8]);
        assert!(PartialCounts::from_bytes(&long).is_err());
    }
}
