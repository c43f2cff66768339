//! Block counts as words, to send between processes (issue #44: a cluster's parts): the bins
//! and block length, each table's counted codes with their counts (in code order), the single
//! symbols' ends. Read back, they are the same counts; anything else is refused.

use super::{BlockCounts, Table};

/// What reading counts back gives: the counts, or what is wrong with the words.
pub type ReadResult<T> = std::result::Result<T, String>;

/// Appends `x` as a LEB128 varint (seven bits a byte, the lowest first): the numbers of the
/// parts' open pieces and of the background's runs.
pub(crate) fn put_varint(out: &mut Vec<u8>, mut x: u64) {
    while x >= 0x80 {
        out.push(x as u8 | 0x80);
        x >>= 7;
    }
    out.push(x as u8);
}

/// Why a LEB128 varint did not read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum BadVarint {
    /// The bytes end before its last byte.
    Short,
    /// It is longer than 64 bits.
    Long,
}

/// The LEB128 varint [`put_varint`] wrote at the start of `bytes`, and how many bytes it took.
#[inline]
fn varint(bytes: &[u8]) -> Result<(u64, usize), BadVarint> {
    let mut x = 0u64;
    for (k, &b) in bytes.iter().enumerate().take(10) {
        let bits = u64::from(b & 0x7f);
        if k == 9 && bits > 1 {
            return Err(BadVarint::Long);
        }
        x |= bits << (7 * k);
        if b & 0x80 == 0 {
            return Ok((x, k + 1));
        }
    }
    Err(if bytes.len() >= 10 {
        BadVarint::Long
    } else {
        BadVarint::Short
    })
}

/// Reads bytes and LEB128 varints one at a time, refusing to read past the end.
pub(crate) struct Bytes<'a> {
    data: &'a [u8],
    at: usize,
    /// What reading past the end says.
    cut: &'static str,
}

impl<'a> Bytes<'a> {
    /// The bytes of `bytes`; reading past their end is the error `cut`.
    pub(crate) fn new(bytes: &'a [u8], cut: &'static str) -> Self {
        Self {
            data: bytes,
            at: 0,
            cut,
        }
    }

    pub(crate) fn byte(&mut self) -> ReadResult<u8> {
        let b = self.data.get(self.at).copied().ok_or(self.cut)?;
        self.at += 1;
        Ok(b)
    }

    /// A LEB128 varint of at most 64 bits.
    pub(crate) fn varint(&mut self) -> ReadResult<u64> {
        match varint(&self.data[self.at..]) {
            Ok((x, n)) => {
                self.at += n;
                Ok(x)
            }
            Err(BadVarint::Short) => Err(self.cut.into()),
            Err(BadVarint::Long) => Err(corrupt("a number longer than 64 bits")),
        }
    }

    /// The bytes left.
    pub(crate) fn left(&self) -> usize {
        self.data.len() - self.at
    }

    /// Whether every byte was read.
    pub(crate) fn is_done(&self) -> bool {
        self.at == self.data.len()
    }
}

/// Reads little-endian words one at a time from bytes, refusing to read past the end.
pub(crate) struct Words<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Words<'a> {
    /// The words of `bytes` (a whole number of them).
    pub(crate) fn new(bytes: &'a [u8]) -> Self {
        Self { bytes, at: 0 }
    }

    pub(crate) fn next(&mut self) -> ReadResult<u64> {
        let word = self.bytes.get(self.at..self.at + 8).ok_or_else(short)?;
        self.at += 8;
        Ok(u64::from_le_bytes(word.try_into().unwrap_or_default()))
    }

    /// Reads the magic word `magic` (seven bytes of name, then a version) of a `what`: bytes that
    /// begin otherwise, however few, are not slabscope's; those of another version of slabscope
    /// are refused by their version.
    pub(crate) fn magic(&mut self, magic: [u8; 8], what: &str) -> ReadResult<()> {
        let rest = self.rest();
        let name = &rest[..rest.len().min(7)];
        if name != &magic[..name.len()] {
            return Err(corrupt(&format!("not slabscope's {what}")));
        }
        let version = self.next()?.to_le_bytes()[7];
        if version != magic[7] {
            return Err(format!(
                "{what} of version {version} where this slabscope reads version {}: count the \
                 parts again with one version of slabscope",
                magic[7]
            ));
        }
        Ok(())
    }

    /// The number of words left.
    pub(crate) fn left(&self) -> usize {
        (self.bytes.len() - self.at) / 8
    }

    /// The bytes left.
    pub(crate) fn rest(&self) -> &'a [u8] {
        &self.bytes[self.at..]
    }
}

fn short() -> String {
    "counts cut short: the part was not written whole".into()
}

/// An error for counts that no writer made.
pub(crate) fn corrupt(what: &str) -> String {
    format!("counts that do not read back: {what}")
}

fn put_table(table: &Table, out: &mut Vec<u64>) {
    let mut pairs = Vec::new();
    table.for_each(|code, count| pairs.push((code, count)));
    pairs.sort_unstable();
    out.push(pairs.len() as u64);
    for (code, count) in pairs {
        out.extend([code, count]);
    }
}

/// The most a table or a symbol may count in a part read back: far beyond any volume's samples
/// (2^56), so that adding parts cannot overflow.
const MOST: u64 = 1 << 56;

fn get_table(table: &mut Table, mask: u64, words: &mut Words) -> ReadResult<()> {
    let n = words.next()?;
    if n > words.left() as u64 / 2 {
        return Err(short());
    }
    let (mut last, mut total) = (None, 0u64);
    for _ in 0..n {
        let (code, count) = (words.next()?, words.next()?);
        if code & !mask != 0 {
            return Err(corrupt("a block code beyond its table"));
        }
        if last.is_some_and(|l| code <= l) {
            return Err(corrupt("block codes out of order or repeated"));
        }
        total = total.saturating_add(count);
        if total > MOST {
            return Err(corrupt("more blocks than any volume holds"));
        }
        last = Some(code);
        table.add(code, count);
    }
    Ok(())
}

impl BlockCounts {
    /// The counts as words, appended to `out` (`PartialCounts::from_bytes` reads them back).
    pub fn write(&self, out: &mut Vec<u64>) {
        out.extend([self.bins as u64, self.packing.block]);
        put_table(&self.long, out);
        put_table(&self.ends.short, out);
        out.extend(self.ends.single.iter());
    }

    /// Counts [`write`](Self::write) wrote, from `words`.
    pub(crate) fn read(words: &mut Words) -> ReadResult<Self> {
        let (bins, block) = (words.next()?, words.next()?);
        if !(2..=256).contains(&bins) || !(2..=4).contains(&block) {
            return Err(corrupt("bins or block length out of range"));
        }
        let mut counts = Self::new(bins as usize, block as usize);
        let (long, short) = (counts.packing.long_mask, counts.packing.short_mask);
        get_table(&mut counts.long, long, words)?;
        get_table(&mut counts.ends.short, short, words)?;
        for s in counts.ends.single.iter_mut() {
            *s = words.next()?;
            if *s > MOST {
                return Err(corrupt("more symbols than any volume holds"));
            }
        }
        Ok(counts)
    }
}

#[cfg(test)]
mod tests {
    use super::{BadVarint, put_varint, varint};

    #[test]
    fn varints_read_back_and_refuse_what_is_cut_or_too_long() {
        for x in [0, 1, 127, 128, 300, 1 << 35, u64::MAX - 1, u64::MAX] {
            let mut out = vec![];
            put_varint(&mut out, x);
            assert_eq!(
                out.len(),
                (64 - x.leading_zeros() as usize).div_ceil(7).max(1)
            );
            out.push(0xff);
            assert_eq!(varint(&out), Ok((x, out.len() - 1)), "{x}");
            assert_eq!(varint(&out[..out.len() - 2]), Err(BadVarint::Short), "{x}");
        }
        assert_eq!(varint(&[]), Err(BadVarint::Short));
        // A tenth byte holds the 64th bit alone; an eleventh is never reached.
        let mut ten = vec![0xff; 9];
        ten.push(0x02);
        assert_eq!(varint(&ten), Err(BadVarint::Long));
        assert_eq!(varint(&[0x80; 12]), Err(BadVarint::Long));
    }
}
