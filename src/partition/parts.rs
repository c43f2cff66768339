//! The partition in parts (issue #44): the slice stack counted a strip of its rows at a time,
//! each strip by a task that may hold only the voxels its rows' samples read
//! ([`StackSplit::voxel_box`]), the counts added in any grouping and order into the whole
//! stack's, bit for bit: the histograms and joint histograms are sums over the pixels, and
//! the slices' float sums are kept a row apart until every row before is in
//! ([`SliceSums`]).
//!
//! Two passes, as [`partition_streamed`](super::partition_streamed) (built on them) makes:
//! [`SliceCounts`] (the slices' histograms and positions, the joint histograms of consecutive
//! slices, the slices' sums), from which the histories and the slabs follow; then
//! [`SlabJoints`] (the joint histograms of consecutive slabs), for the NMI at their boundaries.

use std::collections::BTreeMap;
use std::ops::Range;

use super::bottom_up::{Columns, add_consecutive_joints, nmi_of_joints};
use super::histories::Histories;
use super::stack::{Cutter, SliceSums};
use super::{Method, Partition, PartitionParams, Slab};
use crate::error::{Error, Result};
use crate::progress::Monitor;
use crate::volume::background::Background;
use crate::volume::{Volume, VoxelBox};

/// What the tasks of a partition in parts and the client that adds their counts agree on: the
/// axis, the partition's parameters, and the stack's shape.
#[derive(Clone, Debug)]
pub struct StackSplit {
    axis: [f64; 3],
    params: PartitionParams,
    slices: usize,
    rows: usize,
    bins: usize,
}

/// The slabs the first pass's counts give, with the histories they were taken from.
pub struct SlabsFound {
    /// The histories of the splits (and the optimum).
    pub histories: Histories,
    /// Their position chosen by the stop rule.
    pub position: usize,
    /// The slabs at that position.
    pub slabs: Vec<Slab>,
}

impl StackSplit {
    /// The split of `volume`'s stack along `axis` by `params`: only its grid is read (a volume
    /// holding a part of the voxels, with the whole one's statistics, will do). Bottom-up
    /// merging reads the whole stack once per merge and is refused, as is a constant volume.
    pub fn new(volume: &Volume, axis: [f64; 3], params: &PartitionParams) -> Result<Self> {
        if params.method == Method::BottomUp {
            return Err(Error::invalid(
                "method",
                params.method.name(),
                "top-down or optimal for a stack counted strip by strip (bottom-up merging reads \
                 the whole stack once per merge)",
            ));
        }
        Histories::check_not_constant(volume)?;
        let none = Background::none();
        let cutter = Cutter::given(volume, axis, &params.stack, &none)?;
        let slices = cutter.slices();
        Histories::check_slices(slices)?;
        Ok(Self {
            axis,
            params: params.clone(),
            slices,
            rows: cutter.rows(),
            bins: cutter.bins(),
        })
    }

    /// The stack's slices.
    pub fn slices(&self) -> usize {
        self.slices
    }

    /// The stack's rows of pixels, which strips divide.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// The rows cut in `count` strips as even as can be (fewer when there are fewer rows).
    pub fn strips(&self, count: usize) -> Vec<Range<usize>> {
        let count = count.clamp(1, self.rows.max(1));
        (0..count)
            .map(|k| k * self.rows / count..(k + 1) * self.rows / count)
            .filter(|r| !r.is_empty())
            .collect()
    }

    /// The box of `volume`'s voxels the samples of `rows` read (their cells' corners, and the
    /// voxels nearest them that the background is tested at): all a task counting those rows
    /// needs to hold. Along a coordinate axis a slab of whole voxel rows; along an oblique one
    /// the box around a slanted slab of rays. `None` when the rows hold no sample.
    pub fn voxel_box(&self, volume: &Volume, rows: &Range<usize>) -> Result<Option<VoxelBox>> {
        let none = Background::none();
        let cutter = Cutter::given(volume, self.axis, &self.params.stack, &none)?;
        Ok(cutter.voxel_box(rows))
    }

    /// [`voxel_box`](Self::voxel_box) cut by layers of planes along z: for each of `planes`,
    /// a box holding every voxel of those planes the samples of `rows` read (`None` where
    /// they read none). Along an oblique axis a strip's rows are a slanted slab of rays, whose
    /// one box may hold most of the volume while its boxes a layer each hold little more than
    /// the slab: a task gathering its voxels from an array's layers of chunks takes these.
    pub fn voxel_boxes(
        &self,
        volume: &Volume,
        rows: &Range<usize>,
        planes: &[Range<usize>],
    ) -> Result<Vec<Option<VoxelBox>>> {
        let none = Background::none();
        let cutter = Cutter::given(volume, self.axis, &self.params.stack, &none)?;
        Ok(planes
            .iter()
            .map(|p| cutter.voxel_box_within(rows, Some(p)))
            .collect())
    }

    /// The first pass's counts of `rows`, from `volume` (holding at least their
    /// [`voxel_box`](Self::voxel_box)) and the whole volume's `background`.
    pub fn count(
        &self,
        volume: &Volume,
        background: &Background,
        rows: Range<usize>,
        monitor: &Monitor,
    ) -> Result<SliceCounts> {
        let (counts, _) = self.count_keeping(volume, background, rows, monitor)?;
        Ok(counts)
    }

    /// [`count`](Self::count), keeping the strip's columns as runs: what the second pass reads
    /// of the strip, so that [`StripRuns::joints`] gives its second-pass counts without cutting
    /// the strip from the voxels again.
    pub fn count_keeping(
        &self,
        volume: &Volume,
        background: &Background,
        rows: Range<usize>,
        monitor: &Monitor,
    ) -> Result<(SliceCounts, StripRuns)> {
        let cutter = Cutter::given(volume, self.axis, &self.params.stack, background)?;
        monitor.start("slicing in strips (pass 1 of 2)", cutter.work(&rows, true));
        let mut counts = SliceCounts::new(&cutter);
        let columns = counts.add_rows(&cutter, rows.clone(), monitor)?;
        let runs = StripRuns {
            stack_rows: self.rows,
            rows,
            columns,
        };
        Ok((counts, runs))
    }

    /// The slabs of every row's first-pass counts added up.
    pub fn slabs(
        &self,
        volume: &Volume,
        background: &Background,
        counts: SliceCounts,
        monitor: &Monitor,
    ) -> Result<SlabsFound> {
        let cutter = Cutter::given(volume, self.axis, &self.params.stack, background)?;
        SlabsFound::of(
            counts.into_histories(&cutter, &self.params, monitor)?,
            &self.params,
        )
    }

    /// The second pass's counts of `rows`: the joint histograms of consecutive `slabs`.
    pub fn count_boundaries(
        &self,
        volume: &Volume,
        background: &Background,
        rows: Range<usize>,
        slabs: &[Slab],
        monitor: &Monitor,
    ) -> Result<SlabJoints> {
        let cutter = Cutter::given(volume, self.axis, &self.params.stack, background)?;
        monitor.start("slicing in strips (pass 2 of 2)", cutter.work(&rows, false));
        let mut joints = SlabJoints::new(slabs, self.bins, self.rows);
        joints.add_rows(&cutter, rows, monitor)?;
        Ok(joints)
    }

    /// The partition of `found` with the NMI at its boundaries from every row's second-pass
    /// `joints` added up (none needed for a single slab).
    pub fn finish(&self, found: &SlabsFound, joints: Option<SlabJoints>) -> Result<Partition> {
        let boundary_nmi = match joints {
            _ if found.slabs.len() < 2 => Vec::new(),
            Some(joints) if joints.slabs == found.slabs => joints.boundary_nmi()?,
            _ => {
                return Err(Error::invalid(
                    "part",
                    "joint histograms of other slabs, or none",
                    "the joint histograms of the slabs found",
                ));
            }
        };
        Ok(Partition::with_boundary_nmi(
            &found.histories,
            self.params.method,
            found.position,
            boundary_nmi,
        ))
    }
}

impl SlabsFound {
    /// The slabs `params`' stop rule finds in `histories`.
    pub(super) fn of(histories: Histories, params: &PartitionParams) -> Result<Self> {
        let position = histories.position(params.method, params.stop)?;
        let slabs = histories.slabs(params.method, position);
        Ok(Self {
            histories,
            position,
            slabs,
        })
    }
}

/// The rows a part has counted: sorted ranges, none overlapping another.
#[derive(Clone, Debug, Default, PartialEq)]
struct RowSet(Vec<Range<usize>>);

impl RowSet {
    /// Adds `rows`, refusing rows counted already.
    fn insert(&mut self, rows: &Range<usize>) -> Result<()> {
        if rows.is_empty() {
            return Ok(());
        }
        let at = self.0.partition_point(|r| r.end <= rows.start);
        if self.0.get(at).is_some_and(|r| r.start < rows.end) {
            return Err(Error::invalid(
                "part",
                format!("rows {}–{}", rows.start, rows.end - 1),
                "rows no other part counted",
            ));
        }
        self.0.insert(at, rows.clone());
        // Join the neighbours that touch.
        let mut joined: Vec<Range<usize>> = Vec::with_capacity(self.0.len());
        for r in self.0.drain(..) {
            match joined.last_mut() {
                Some(last) if last.end == r.start => last.end = r.end,
                _ => joined.push(r),
            }
        }
        self.0 = joined;
        Ok(())
    }

    /// Whether they are every row of `rows`.
    fn is_all(&self, rows: usize) -> bool {
        rows == 0 || (self.0.len() == 1 && self.0[0] == (0..rows))
    }

    fn check_all(&self, rows: usize) -> Result<()> {
        if self.is_all(rows) {
            Ok(())
        } else {
            let have: usize = self.0.iter().map(ExactSizeIterator::len).sum();
            Err(Error::invalid(
                "part",
                format!("{have} of {rows} rows counted"),
                "every row of the stack counted once",
            ))
        }
    }
}

/// The first pass's counts of some rows of a stack: the slices' histograms and positions, the
/// joint histograms of consecutive slices, the slices' counts of counted values, and their
/// sums, folded in row order as far as every row before is in and kept a row apart beyond.
#[derive(Clone, Debug, PartialEq)]
pub struct SliceCounts {
    slices: usize,
    bins: usize,
    rows: usize,
    counted: RowSet,
    histograms: Vec<u64>,
    positions: Vec<u64>,
    joints: Vec<u64>,
    counts: Vec<u64>,
    /// Rows `0..folded`' sums, added in row order.
    sums: Vec<f64>,
    folded: usize,
    /// The sums of rows past a row not yet in, by row.
    pending: BTreeMap<usize, Vec<f64>>,
}

impl SliceCounts {
    /// No rows yet, of `cutter`'s stack.
    pub(super) fn new(cutter: &Cutter) -> Self {
        let (n, bins) = (cutter.slices(), cutter.bins());
        Self {
            slices: n,
            bins,
            rows: cutter.rows(),
            counted: RowSet::default(),
            histograms: vec![0; n * bins],
            positions: vec![0; n],
            joints: vec![0; n.saturating_sub(1) * bins * bins],
            counts: vec![0; n],
            sums: vec![0.0; n],
            folded: 0,
            pending: BTreeMap::new(),
        }
    }

    /// Cuts `rows` of `cutter`'s stack and adds their counts, giving back the strip's columns
    /// as runs (what the second pass reads of it).
    pub(super) fn add_rows(
        &mut self,
        cutter: &Cutter,
        rows: Range<usize>,
        monitor: &Monitor,
    ) -> Result<Columns> {
        self.counted.insert(&rows)?;
        let mut row = rows.start;
        let strip = cutter.cut(
            rows,
            Some(&mut |sums: &SliceSums| {
                self.take_row(row, sums);
                row += 1;
            }),
            monitor,
        )?;
        add(&mut self.histograms, &strip.slice_histograms());
        add(&mut self.positions, strip.positions());
        let singles: Vec<Slab> = (0..self.slices).map(|s| (s, s + 1)).collect();
        let columns = Columns::new(&strip);
        add_consecutive_joints(Some(&strip), &columns, &singles, &mut self.joints, monitor)?;
        Ok(columns)
    }

    /// Takes row `row`'s sums: folded when every row before it is, else kept.
    fn take_row(&mut self, row: usize, sums: &SliceSums) {
        add(&mut self.counts, &sums.counts);
        if row == self.folded {
            self.fold_row(&sums.sums);
            self.fold();
        } else {
            self.pending.insert(row, sums.sums.clone());
        }
    }

    /// Adds the next row's sums onto the folded ones.
    fn fold_row(&mut self, sums: &[f64]) {
        self.sums.iter_mut().zip(sums).for_each(|(a, b)| *a += b);
        self.folded += 1;
    }

    /// Folds the kept rows that follow the folded ones.
    fn fold(&mut self) {
        while let Some(sums) = self.pending.remove(&self.folded) {
            self.fold_row(&sums);
        }
    }

    /// Adds `other`'s counts (of other rows of the same stack).
    pub fn add(&mut self, mut other: Self) -> Result<()> {
        if (other.slices, other.bins, other.rows) != (self.slices, self.bins, self.rows) {
            return Err(Error::invalid(
                "part",
                format!(
                    "counts of {} slices, {} bins and {} rows",
                    other.slices, other.bins, other.rows
                ),
                format!(
                    "counts of the same stack ({} slices, {} bins, {} rows)",
                    self.slices, self.bins, self.rows
                ),
            ));
        }
        for r in &other.counted.0 {
            self.counted.insert(r)?;
        }
        if other.folded > 0 {
            // Only one of the two can hold row 0 (the rows were checked apart above).
            std::mem::swap(&mut self.sums, &mut other.sums);
            self.folded = other.folded;
        }
        add(&mut self.histograms, &other.histograms);
        add(&mut self.positions, &other.positions);
        add(&mut self.joints, &other.joints);
        add(&mut self.counts, &other.counts);
        self.pending.append(&mut other.pending);
        self.fold();
        Ok(())
    }

    /// The histories of the whole stack's counts (every row in).
    pub(super) fn into_histories(
        self,
        cutter: &Cutter,
        params: &PartitionParams,
        monitor: &Monitor,
    ) -> Result<Histories> {
        self.counted.check_all(self.rows)?;
        let nmi_curve = nmi_of_joints(&self.joints, self.bins);
        let sums = SliceSums {
            sums: self.sums,
            counts: self.counts,
        };
        let summary = cutter.summary(self.positions, sums, monitor)?;
        Histories::of_summary(
            summary,
            self.histograms,
            nmi_curve,
            params.scope(Some(self.slices)),
        )
    }
}

/// The second pass's counts of some rows of a stack: the joint histograms of each pair of
/// consecutive slabs.
#[derive(Clone, Debug, PartialEq)]
pub struct SlabJoints {
    slabs: Vec<Slab>,
    bins: usize,
    rows: usize,
    counted: RowSet,
    joints: Vec<u64>,
}

impl SlabJoints {
    /// No rows yet, of a stack of `rows` rows and `bins` bins cut into `slabs`.
    pub(super) fn new(slabs: &[Slab], bins: usize, rows: usize) -> Self {
        Self {
            slabs: slabs.to_vec(),
            bins,
            rows,
            counted: RowSet::default(),
            joints: vec![0; slabs.len().saturating_sub(1) * bins * bins],
        }
    }

    /// Cuts `rows` of `cutter`'s stack and adds their joint histograms.
    pub(super) fn add_rows(
        &mut self,
        cutter: &Cutter,
        rows: Range<usize>,
        monitor: &Monitor,
    ) -> Result<()> {
        self.counted.insert(&rows)?;
        let strip = cutter.cut(rows, None, monitor)?;
        add_consecutive_joints(
            Some(&strip),
            &Columns::new(&strip),
            &self.slabs,
            &mut self.joints,
            monitor,
        )
    }

    /// Adds the joint histograms of the strip of `rows` whose columns' runs are `columns` (kept
    /// by its first pass): [`add_rows`](Self::add_rows)' counts without cutting it again.
    pub(super) fn add_runs(
        &mut self,
        rows: &Range<usize>,
        columns: &Columns,
        monitor: &Monitor,
    ) -> Result<()> {
        self.counted.insert(rows)?;
        add_consecutive_joints(None, columns, &self.slabs, &mut self.joints, monitor)
    }

    /// Adds `other`'s joint histograms (of other rows of the same stack and slabs).
    pub fn add(&mut self, other: &Self) -> Result<()> {
        if (&other.slabs, other.bins, other.rows) != (&self.slabs, self.bins, self.rows) {
            return Err(Error::invalid(
                "part",
                "joint histograms of other slabs or another stack",
                "the same stack's and slabs'",
            ));
        }
        for r in &other.counted.0 {
            self.counted.insert(r)?;
        }
        add(&mut self.joints, &other.joints);
        Ok(())
    }

    /// The NMI at each boundary between consecutive slabs (every row in).
    pub(super) fn boundary_nmi(&self) -> Result<Vec<f64>> {
        self.counted.check_all(self.rows)?;
        Ok(nmi_of_joints(&self.joints, self.bins))
    }
}

/// Adds `b` into `a`, element by element.
fn add(a: &mut [u64], b: &[u64]) {
    a.iter_mut().zip(b).for_each(|(x, y)| *x += y);
}

mod bytes;
mod runs;

pub use runs::StripRuns;
#[cfg(test)]
pub(crate) mod testing;
#[cfg(test)]
mod tests;
