//! A stack's columns as bytes, to keep a strip's cut stack between the partition's passes in
//! another process (issue #44: a cluster's tasks): every number a LEB128 varint. The shape
//! (bins, slices, pixels), the constant groups (symbol, first slice, slices, pixels), then the
//! active columns, each as the step from the last one's pixel, its first slice and its runs
//! (each a symbol and a length): a run in two or three bytes, where the columns hold nine.
//! Read back, they are the same columns, their checkpoints made again; anything else is
//! refused before it is used (a symbol beyond the bins, runs beyond the slices, more of
//! anything than the bytes can hold).

use super::joints::{Columns, ConstantGroup};
use crate::measure::{Bytes, ReadResult, corrupt, put_varint};
use crate::partition::stack::MISSING;

/// What reading columns past their end says.
const CUT: &str = "columns cut short: the strip's runs end early";

impl Columns {
    /// Appends the columns' bytes to `out`.
    pub(crate) fn put_bytes(&self, out: &mut Vec<u8>) {
        for x in [self.bins, self.slices, self.pixels, self.constant.len()] {
            put_varint(out, x as u64);
        }
        for &(symbol, first, len, count) in &self.constant {
            out.push(symbol);
            for x in [first as u64, len as u64, count] {
                put_varint(out, x);
            }
        }
        put_varint(out, self.active.len() as u64);
        put_varint(out, self.run_first.len() as u64);
        let mut next = 0;
        for (i, &p) in self.active.iter().enumerate() {
            put_varint(out, u64::from(p - next));
            next = p + 1;
            let runs = self.run_start[i]..self.run_start[i + 1];
            let firsts = &self.run_first[runs.clone()];
            put_varint(out, runs.len() as u64);
            put_varint(out, u64::from(firsts[0]));
            let ends = firsts[1..].iter().chain(std::iter::once(&self.run_end[i]));
            for ((&symbol, &first), &end) in self.run_symbol[runs].iter().zip(firsts).zip(ends) {
                out.push(symbol);
                put_varint(out, u64::from(end - first));
            }
        }
    }

    /// The columns [`put_bytes`](Self::put_bytes) wrote, all of `bytes`.
    pub(crate) fn read_bytes(bytes: &[u8]) -> ReadResult<Self> {
        let mut b = Bytes::new(bytes, CUT);
        let (bins, slices, pixels) = (b.varint()?, b.varint()?, b.varint()?);
        if !(2..=u64::from(MISSING)).contains(&bins) || slices > u64::from(u32::MAX) {
            return Err(corrupt("columns of a stack no partition has"));
        }
        let pixels = u32::try_from(pixels).map_err(|_| corrupt("more pixels than a strip has"))?;
        let (bins, slices) = (bins as u8, slices as u32);
        let constant = read_constant(&mut b, bins, slices, pixels)?;
        let (active, total) = (b.varint()?, b.varint()?);
        // A column takes three bytes at least, a run two.
        if active > b.left() as u64 / 3 || total > b.left() as u64 / 2 || active > total {
            return Err(corrupt("more columns or runs than bytes"));
        }
        let mut columns = Vec::with_capacity(active as usize);
        let mut run_start = Vec::with_capacity(active as usize + 1);
        let (mut run_first, mut run_symbol) = (
            Vec::with_capacity(total as usize),
            Vec::with_capacity(total as usize),
        );
        let mut run_end = Vec::with_capacity(active as usize);
        run_start.push(0);
        let mut next = 0u64;
        for _ in 0..active {
            let p = next.saturating_add(b.varint()?);
            let (runs, mut at) = (b.varint()?, b.varint()?);
            if p >= u64::from(pixels) || runs == 0 || at >= u64::from(slices) {
                return Err(corrupt("columns beyond the strip or empty"));
            }
            if run_first.len() as u64 + runs > total {
                return Err(corrupt("more runs than written"));
            }
            for _ in 0..runs {
                let (symbol, len) = (b.byte()?, b.varint()?);
                if (symbol >= bins && symbol != MISSING) || len == 0 || len > u64::from(slices) - at
                {
                    return Err(corrupt("a run beyond the bins or the slices"));
                }
                run_first.push(at as u32);
                run_symbol.push(symbol);
                at += len;
            }
            columns.push(p as u32);
            run_start.push(run_first.len());
            run_end.push(at as u32);
            next = p + 1;
        }
        if run_first.len() as u64 != total || !b.is_done() {
            return Err(corrupt("runs or bytes beyond those written"));
        }
        let shape = [bins.into(), slices as usize, pixels as usize];
        let runs = (run_first, run_symbol, run_end);
        Ok(Self::of_runs(shape, columns, constant, run_start, runs))
    }
}

/// The constant groups: a symbol within the bins, slices within the stack, some of its
/// `pixels` (all the groups' together within them).
fn read_constant(
    b: &mut Bytes,
    bins: u8,
    slices: u32,
    pixels: u32,
) -> ReadResult<Vec<ConstantGroup>> {
    let n = b.varint()?;
    if n > b.left() as u64 / 4 {
        return Err(corrupt("more constant columns than bytes"));
    }
    let mut left = u64::from(pixels);
    (0..n)
        .map(|_| {
            let (symbol, first, len, count) = (b.byte()?, b.varint()?, b.varint()?, b.varint()?);
            let within = first < u64::from(slices) && len <= u64::from(slices) - first;
            if symbol >= bins || len == 0 || !within || count == 0 || count > left {
                return Err(corrupt(
                    "constant columns beyond the bins, slices or pixels",
                ));
            }
            left -= count;
            Ok((symbol, first as usize, len as usize, count))
        })
        .collect()
}
