//! A strip kept between the partition's passes (issue #44): the first pass cuts the strip's
//! stack from the voxels and sorts its columns into runs; the second needs those runs alone
//! (the joint histograms of consecutive slabs are read from them), so a task that keeps them
//! gives the second pass's counts without the voxels and without cutting the strip again.

use std::ops::Range;

use super::super::bottom_up::Columns;
use super::SlabJoints;
use super::bytes::{bytes_of, read_shape};
use crate::error::{Error, Result};
use crate::measure::{ReadResult, Words, corrupt};
use crate::partition::Slab;
use crate::progress::Monitor;

/// The first word of [`StripRuns::to_bytes`]: `SLABSR`, a zero and the version.
const RUNS_MAGIC: [u8; 8] = *b"SLABSR\x00\x01";

/// A strip of a stack's rows as its columns' runs: what
/// [`StackSplit::count_keeping`](super::StackSplit::count_keeping) keeps of the strip it cut.
pub struct StripRuns {
    /// The whole stack's rows, and the strip's.
    pub(super) stack_rows: usize,
    pub(super) rows: Range<usize>,
    pub(super) columns: Columns,
}

impl std::fmt::Debug for StripRuns {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StripRuns")
            .field("rows", &self.rows)
            .field("of", &self.stack_rows)
            .field("held_bytes", &self.held_bytes())
            .finish_non_exhaustive()
    }
}

impl StripRuns {
    /// The strip's rows.
    pub fn rows(&self) -> Range<usize> {
        self.rows.clone()
    }

    /// The bytes the runs hold in memory.
    pub fn held_bytes(&self) -> usize {
        self.columns.held_bytes()
    }

    /// The second pass's counts of the strip: the joint histograms of consecutive `slabs` (the
    /// slabs the first pass found: contiguous, in order, covering every slice), bit for bit
    /// those [`StackSplit::count_boundaries`](super::StackSplit::count_boundaries) gives.
    pub fn joints(&self, slabs: &[Slab], monitor: &Monitor) -> Result<SlabJoints> {
        let slices = self.columns.slices();
        let tiled = slabs.first().is_some_and(|s| s.0 == 0)
            && slabs.last().is_some_and(|s| s.1 == slices)
            && slabs.iter().all(|s| s.0 < s.1)
            && slabs.windows(2).all(|w| w[0].1 == w[1].0);
        if !tiled {
            return Err(Error::invalid(
                "slabs",
                format!("{slabs:?}"),
                format!("slabs that tile the stack's {slices} slices in order"),
            ));
        }
        let mut joints = SlabJoints::new(slabs, self.columns.bins(), self.stack_rows);
        joints.add_runs(&self.rows, &self.columns, monitor)?;
        Ok(joints)
    }

    /// The runs as bytes to send to another process: [`from_bytes`](Self::from_bytes) reads
    /// them back to the same runs.
    #[must_use]
    pub fn to_bytes(&self) -> Vec<u8> {
        let words = [
            u64::from_le_bytes(RUNS_MAGIC),
            self.columns.slices() as u64,
            self.columns.bins() as u64,
            self.stack_rows as u64,
            self.rows.start as u64,
            self.rows.end as u64,
        ];
        let mut out = bytes_of(&words);
        self.columns.put_bytes(&mut out);
        out
    }

    /// Runs [`to_bytes`](Self::to_bytes) wrote; an error for any other bytes, those of another
    /// version of slabscope among them.
    pub fn from_bytes(bytes: &[u8]) -> ReadResult<Self> {
        let mut words = Words::new(bytes);
        words.magic(RUNS_MAGIC, "strip's runs")?;
        let (slices, bins, stack_rows) = read_shape(&mut words)?;
        let (start, end) = (words.next()?, words.next()?);
        if start >= end || end > stack_rows as u64 {
            return Err(corrupt("a strip's rows beyond its stack"));
        }
        let columns = Columns::read_bytes(words.rest())?;
        if (columns.slices(), columns.bins()) != (slices, bins) {
            return Err(corrupt("columns of another stack than the strip's"));
        }
        Ok(Self {
            stack_rows,
            rows: start as usize..end as usize,
            columns,
        })
    }
}
