//! The partition's parts as bytes, to send to another process (issue #44: a cluster's tasks):
//! little-endian words. A magic word (`SLABSC` for [`SliceCounts`], `SLABSJ` for
//! [`SlabJoints`], a zero and the version), the stack's shape, the rows counted as ranges, the
//! histograms and joint histograms as their entries that are not zero (index and count, in
//! index order: most of a joint histogram is zeros), then for slice counts the counted values'
//! counts, the folded rows' sums and each kept row's sums (f64 bits).

use std::collections::BTreeMap;
use std::ops::Range;

use super::{RowSet, SlabJoints, SliceCounts};
use crate::measure::ReadResult;
use crate::measure::{Words, corrupt};
use crate::partition::{MAX_SLICES, Slab};

/// The first word of [`SliceCounts::to_bytes`].
const COUNTS_MAGIC: [u8; 8] = *b"SLABSC\x00\x01";

/// The first word of [`SlabJoints::to_bytes`].
const JOINTS_MAGIC: [u8; 8] = *b"SLABSJ\x00\x01";

/// The most bins a stack has (symbols are bytes, one of them the missing sample's).
const MAX_BINS: u64 = 255;

/// Writes words as bytes.
pub(super) fn bytes_of(words: &[u64]) -> Vec<u8> {
    words.iter().flat_map(|w| w.to_le_bytes()).collect()
}

/// The most bytes the tables of a part read back may take: a stack's joint histograms of
/// consecutive slices, dense, take this much for about 4,000 slices of 255 bins.
const MOST_TABLE_BYTES: u64 = 1 << 31;

/// The stack's shape: slices, bins and rows, each within what a stack can have, and its
/// tables within [`MOST_TABLE_BYTES`] (checked before they are made).
pub(super) fn read_shape(words: &mut Words) -> ReadResult<(usize, usize, usize)> {
    let (slices, bins, rows) = (words.next()?, words.next()?, words.next()?);
    if !(2..=MAX_SLICES as u64 * 64).contains(&slices)
        || !(2..=MAX_BINS).contains(&bins)
        || slices * bins * bins * 8 > MOST_TABLE_BYTES
    {
        return Err(corrupt("a stack of a shape no partition has"));
    }
    let rows = usize::try_from(rows).map_err(|_| corrupt("more rows than this machine holds"))?;
    Ok((slices as usize, bins as usize, rows))
}

fn put_rows(words: &mut Vec<u64>, rows: &RowSet) {
    words.push(rows.0.len() as u64);
    words.extend(rows.0.iter().flat_map(|r| [r.start as u64, r.end as u64]));
}

/// Ranges of rows in order, none empty, touching or overlapping another, all below `rows`.
fn read_rows(words: &mut Words, rows: usize) -> ReadResult<RowSet> {
    let n = words.next()?;
    if n > words.rest().len() as u64 / 16 {
        return Err(corrupt("more ranges of rows than bytes"));
    }
    let mut set: Vec<Range<usize>> = Vec::with_capacity(n as usize);
    for _ in 0..n {
        let (a, b) = (words.next()?, words.next()?);
        let after = set.last().map_or(0, |r| r.end as u64 + 1);
        if a < after || b <= a || b > rows as u64 {
            return Err(corrupt("rows out of order or beyond the stack"));
        }
        set.push(a as usize..b as usize);
    }
    Ok(RowSet(set))
}

/// The entries of `v` that are not zero: their number, then each one's index and value.
fn put_sparse(words: &mut Vec<u64>, v: &[u64]) {
    let at = words.len();
    words.push(0);
    for (i, &x) in v.iter().enumerate().filter(|(_, x)| **x != 0) {
        words.extend([i as u64, x]);
    }
    words[at] = ((words.len() - at - 1) / 2) as u64;
}

/// What [`put_sparse`] wrote of a vector of `len` entries.
fn read_sparse(words: &mut Words, len: usize) -> ReadResult<Vec<u64>> {
    let n = words.next()?;
    if n > words.rest().len() as u64 / 16 || n > len as u64 {
        return Err(corrupt("more entries than bytes or than the table holds"));
    }
    let mut v = vec![0; len];
    let mut next = 0;
    for _ in 0..n {
        let (i, x) = (words.next()?, words.next()?);
        if i < next || i >= len as u64 || x == 0 {
            return Err(corrupt("a table's entries out of order, beyond it or zero"));
        }
        v[i as usize] = x;
        next = i + 1;
    }
    Ok(v)
}

fn read_floats(words: &mut Words, n: usize) -> ReadResult<Vec<f64>> {
    (0..n).map(|_| Ok(f64::from_bits(words.next()?))).collect()
}

/// The words left must be none.
fn check_end(words: &Words) -> ReadResult<()> {
    if words.rest().is_empty() {
        Ok(())
    } else {
        Err(corrupt("bytes after the end"))
    }
}

impl SliceCounts {
    /// The counts as bytes (little-endian words) to send to another process:
    /// [`from_bytes`](Self::from_bytes) reads them back to the same counts.
    #[must_use]
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut w = vec![u64::from_le_bytes(COUNTS_MAGIC)];
        w.extend([self.slices as u64, self.bins as u64, self.rows as u64]);
        put_rows(&mut w, &self.counted);
        for v in [
            &self.histograms,
            &self.positions,
            &self.joints,
            &self.counts,
        ] {
            put_sparse(&mut w, v);
        }
        w.push(self.folded as u64);
        if self.folded > 0 {
            w.extend(self.sums.iter().map(|x| x.to_bits()));
        }
        w.push(self.pending.len() as u64);
        for (&row, sums) in &self.pending {
            w.push(row as u64);
            w.extend(sums.iter().map(|x| x.to_bits()));
        }
        bytes_of(&w)
    }

    /// Counts [`to_bytes`](Self::to_bytes) wrote; an error for any other bytes, those of
    /// another version of slabscope among them.
    pub fn from_bytes(bytes: &[u8]) -> ReadResult<Self> {
        let mut words = Words::new(bytes);
        words.magic(COUNTS_MAGIC, "slice counts")?;
        let (n, bins, rows) = read_shape(&mut words)?;
        let counted = read_rows(&mut words, rows)?;
        let histograms = read_sparse(&mut words, n * bins)?;
        let positions = read_sparse(&mut words, n)?;
        let joints = read_sparse(&mut words, (n - 1) * bins * bins)?;
        let counts = read_sparse(&mut words, n)?;
        let folded = words.next()?;
        let sums = if folded > 0 {
            read_floats(&mut words, n)?
        } else {
            vec![0.0; n]
        };
        let kept = words.next()?;
        if kept > words.rest().len() as u64 / (8 * (n as u64 + 1)) {
            return Err(corrupt("more rows' sums than bytes"));
        }
        let mut pending = BTreeMap::new();
        for _ in 0..kept {
            let row = words.next()?;
            let counted_row = counted.0.iter().any(|r| r.contains(&(row as usize)));
            if row <= folded || !counted_row || pending.contains_key(&(row as usize)) {
                return Err(corrupt(
                    "a row's sums kept that are folded or beyond the stack",
                ));
            }
            pending.insert(row as usize, read_floats(&mut words, n)?);
        }
        check_end(&words)?;
        let have: usize = counted.0.iter().map(ExactSizeIterator::len).sum();
        let folded_counted = folded == 0 || counted.0.first() == Some(&(0..folded as usize));
        if have as u64 != folded + kept || !folded_counted {
            return Err(corrupt("rows' sums that are not the rows counted"));
        }
        Ok(Self {
            slices: n,
            bins,
            rows,
            counted,
            histograms,
            positions,
            joints,
            counts,
            sums,
            folded: folded as usize,
            pending,
        })
    }
}

impl SlabJoints {
    /// The joint histograms as bytes (little-endian words) to send to another process:
    /// [`from_bytes`](Self::from_bytes) reads them back to the same counts.
    #[must_use]
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut w = vec![u64::from_le_bytes(JOINTS_MAGIC)];
        let slices = self.slabs.last().map_or(0, |s| s.1);
        w.extend([slices as u64, self.bins as u64, self.rows as u64]);
        w.push(self.slabs.len() as u64);
        w.extend(self.slabs.iter().map(|s| s.1 as u64));
        put_rows(&mut w, &self.counted);
        put_sparse(&mut w, &self.joints);
        bytes_of(&w)
    }

    /// Joint histograms [`to_bytes`](Self::to_bytes) wrote; an error for any other bytes.
    pub fn from_bytes(bytes: &[u8]) -> ReadResult<Self> {
        let mut words = Words::new(bytes);
        words.magic(JOINTS_MAGIC, "slab joints")?;
        let (slices, bins, rows) = read_shape(&mut words)?;
        let count = words.next()?;
        if count == 0 || count > slices as u64 {
            return Err(corrupt("more slabs than slices, or none"));
        }
        let mut slabs: Vec<Slab> = Vec::with_capacity(count as usize);
        for _ in 0..count {
            let (start, end) = (slabs.last().map_or(0, |s| s.1), words.next()?);
            if end <= start as u64 || end > slices as u64 {
                return Err(corrupt("slabs out of order or beyond the slices"));
            }
            slabs.push((start, end as usize));
        }
        if slabs.last().map(|s| s.1) != Some(slices) {
            return Err(corrupt("slabs that do not end at the last slice"));
        }
        let counted = read_rows(&mut words, rows)?;
        let joints = read_sparse(&mut words, (slabs.len() - 1) * bins * bins)?;
        check_end(&words)?;
        Ok(Self {
            slabs,
            bins,
            rows,
            counted,
            joints,
        })
    }
}
