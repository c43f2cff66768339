//! Slice stacks along an axis (docs/design.md §2): the voxel planes for a coordinate axis, planes of the
//! grid resampled on the ray lattice for an oblique one. Stored pixel-major: each pixel's column
//! of quantized symbols across the slices is contiguous, over the slices where it is valid.
//! How a volume is cut into a stack is `cut`; this is the stack and what it is asked.

mod cut;

use rayon::prelude::*;
use serde::Serialize;

use crate::geometry::WorldAxis;
use crate::geometry::lattice::{Lattice, SamplingParams};
use crate::volume::background::{Background, BackgroundRule};

pub(crate) use self::cut::{Cutter, SliceSums};
pub use self::cut::{InPlane, sampled_gain, slice_geometry};

/// The symbol of a sample that does not count: outside the volume, missing, or background.
pub const MISSING: u8 = u8::MAX;

/// How to cut a volume into slices.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StackParams {
    /// Bins, and for an oblique axis the lattice's spacings (the ray spacing between a slice's
    /// pixels, the sample spacing between slices): the view search's.
    pub sampling: SamplingParams,
    /// The background, left out of every histogram.
    pub background: BackgroundRule,
}

/// One pixel's column: symbols for slices `first .. first + len`, stored from `offset`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Column {
    offset: usize,
    first: u32,
    len: u32,
}

/// The slices of a volume along an axis, quantized.
#[derive(Clone, Debug)]
pub struct SliceStack {
    axis: [f64; 3],
    bins: usize,
    slices: usize,
    /// Millimetres between consecutive slices.
    thickness: f64,
    /// Position along the axis of slice 0's centre, mm (voxel (0,0,0) at 0).
    offset: f64,
    columns: Vec<Column>,
    symbols: Vec<u8>,
    /// Per slice: the sum and count of the values that count, for slab means.
    sums: Vec<f64>,
    counts: Vec<u64>,
    /// Per slice: the samples inside the volume's box, background and missing ones included.
    positions: Vec<u64>,
    /// The background left out.
    background: BackgroundSummary,
    /// The axis in world coordinates.
    world: WorldAxis,
    /// A position `s` along the axis is at `a·s + b` along the world axis: `(a, b)`.
    world_line: (f64, f64),
}

/// What was left out as background, for reports: `{"mode": "auto", "value": 12.0,
/// "fraction": 0.38}`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct BackgroundSummary {
    /// How it was chosen: `none`, `auto` or `value`.
    pub mode: &'static str,
    /// The threshold: background voxels are at or below it (`None` when there is none).
    pub value: Option<f32>,
    /// The share of the volume's voxels that are background.
    pub fraction: f64,
    /// The rule (its threshold is `value`).
    #[serde(skip)]
    pub rule: BackgroundRule,
}

impl BackgroundSummary {
    /// The summary of `b`.
    pub fn of(b: &Background) -> Self {
        Self {
            mode: match b.rule {
                BackgroundRule::None => "none",
                BackgroundRule::Auto => "auto",
                BackgroundRule::Below(_) => "value",
            },
            value: b.value,
            fraction: b.fraction,
            rule: b.rule,
        }
    }

    /// Whether any voxel was left out.
    pub fn any(&self) -> bool {
        self.fraction > 0.0
    }
}

impl SliceStack {
    /// The canonical axis the slices are perpendicular to.
    pub fn axis(&self) -> [f64; 3] {
        self.axis
    }

    /// Number of slices.
    pub fn slices(&self) -> usize {
        self.slices
    }

    /// Number of bins of the symbols.
    pub fn bins(&self) -> usize {
        self.bins
    }

    /// Millimetres between consecutive slices.
    pub fn thickness(&self) -> f64 {
        self.thickness
    }

    /// Position along the axis of slice 0's centre, mm, with voxel (0,0,0) at 0.
    pub fn offset(&self) -> f64 {
        self.offset
    }

    /// The axis in world coordinates: the slab planes' world normal and anatomical name.
    pub fn world(&self) -> &WorldAxis {
        &self.world
    }

    /// The world position (along [`world`](Self::world)'s axis, mm) of position `s` mm along the
    /// axis.
    pub fn world_mm(&self, s: f64) -> f64 {
        let (a, b) = self.world_line;
        a * s + b
    }

    /// `(a, b)` of [`world_mm`](Self::world_mm)`(s) = a·s + b`.
    pub fn world_line(&self) -> (f64, f64) {
        self.world_line
    }

    /// Number of pixel columns.
    pub fn pixels(&self) -> usize {
        self.columns.len()
    }

    /// The share of the positions of slices `start..end` inside the volume that do not count:
    /// background or missing voxels.
    pub fn left_out(&self, start: usize, end: usize) -> f64 {
        let positions: u64 = self.positions[start..end].iter().sum();
        let counted: u64 = self.counts[start..end].iter().sum();
        if positions == 0 {
            1.0
        } else {
            1.0 - counted as f64 / positions as f64
        }
    }

    /// Per slice: the samples inside the volume's box, background and missing ones included.
    pub(crate) fn positions(&self) -> &[u64] {
        &self.positions
    }

    /// What was left out as background.
    pub fn background(&self) -> BackgroundSummary {
        self.background
    }

    /// Mean of the counted values of slices `start..end`, or `None` when none counts.
    pub fn mean(&self, start: usize, end: usize) -> Option<f64> {
        let n: u64 = self.counts[start..end].iter().sum();
        (n > 0).then(|| self.sums[start..end].iter().sum::<f64>() / n as f64)
    }

    /// The symbols of pixel `p` in slices `start..end`, clipped to where the column is valid,
    /// with the slice index of the first one.
    #[inline]
    pub fn column(&self, p: usize, start: usize, end: usize) -> (usize, &[u8]) {
        let c = self.columns[p];
        let (first, last) = (c.first as usize, (c.first + c.len) as usize);
        let (a, b) = (start.max(first), end.min(last));
        if a >= b {
            return (a, &[]);
        }
        (a, &self.symbols[c.offset + a - first..c.offset + b - first])
    }

    /// The slices where pixel `p`'s column is valid: `(first, len)`.
    #[inline]
    pub fn column_range(&self, p: usize) -> (usize, usize) {
        let c = self.columns[p];
        (c.first as usize, c.len as usize)
    }

    /// Per slice, the histogram of its symbols (counted samples only): `slices × bins` counts.
    pub fn slice_histograms(&self) -> Vec<u64> {
        let (n, bins) = (self.slices, self.bins);
        let zero = || vec![0u64; n * bins];
        self.columns
            .par_chunks(4096)
            .fold(zero, |mut h, cols| {
                for c in cols {
                    let syms = &self.symbols[c.offset..c.offset + c.len as usize];
                    for (k, &s) in syms.iter().enumerate() {
                        if s != MISSING {
                            h[(c.first as usize + k) * bins + usize::from(s)] += 1;
                        }
                    }
                }
                h
            })
            .reduce_with(|mut a, b| {
                a.iter_mut().zip(&b).for_each(|(x, y)| *x += y);
                a
            })
            .unwrap_or_else(zero)
    }
}

#[cfg(test)]
mod tests;
