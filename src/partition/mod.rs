//! Slab partitioning along an axis (paper §5): slice stacks, top-down splits, bottom-up merges,
//! the optimal partition, and summaries of the slabs they give.

mod bottom_up;
mod histories;
mod labels;
mod optimal;
mod parts;
#[cfg(test)]
pub(crate) use parts::testing as parts_testing;
mod result;
mod stack;
mod streamed;
mod top_down;

use serde::Serialize;

pub use crate::geometry::coordinate_axis;
pub use bottom_up::{Merge, MergeHistory, PAIRS_KEPT, slice_nmi};
pub use histories::{Histories, Scope};
pub use labels::{
    LABEL_CHUNK_BYTES, LabelRoom, Labeller, MaskHome, StreamMemory, label_bytes, label_memory,
    label_stream_memory, label_volume,
};
pub use optimal::{COMPARE_MAX_SLICES, MAX_SLICES, OptimalPartitions, Optimum};
pub use parts::{SlabJoints, SlabsFound, SliceCounts, StackSplit, StripRuns};
pub use result::{Comparison, Partition, PartitionParams, Step, Stop, partition, partition_kept};
pub use stack::{
    BackgroundSummary, InPlane, MISSING, SliceStack, StackParams, sampled_gain, slice_geometry,
};
pub use streamed::{
    most_slices, partition_streamed, partition_streamed_kept, slice_bytes, streamed_memory_floor,
};
pub use top_down::{Split, SplitHistory};

use crate::measure::entropy;

/// A slab: the half-open range of slices `[start, end)` along the axis.
pub type Slab = (usize, usize);

/// Slices `[a, b)` for people, inclusive as a reader counts them: `12` for one slice, `12–40`
/// for several.
pub fn slab_text((a, b): Slab) -> String {
    if b <= a + 1 {
        a.to_string()
    } else {
        format!("{a}–{}", b - 1)
    }
}

/// How slabs are found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Greedy splits by information gain (paper §5.1).
    TopDown,
    /// Greedy merges by normalized mutual information (paper §5.2).
    BottomUp,
    /// The partition keeping the most information, by dynamic programming.
    Optimal,
}

impl Method {
    /// The name used on the command line and in JSON.
    pub fn name(self) -> &'static str {
        match self {
            Self::TopDown => "topdown",
            Self::BottomUp => "bottomup",
            Self::Optimal => "optimal",
        }
    }
}

/// Cumulative histograms: `prefix[s * bins + b]` counts bin `b` in slices `0..s`.
pub(crate) fn prefix_histograms(histograms: &[u64], bins: usize) -> Vec<u64> {
    let slices = histograms.len() / bins;
    let mut prefix = vec![0u64; (slices + 1) * bins];
    for s in 0..slices {
        for b in 0..bins {
            prefix[(s + 1) * bins + b] = prefix[s * bins + b] + histograms[s * bins + b];
        }
    }
    prefix
}

/// What a user wants to know about one slab.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SlabInfo {
    /// Slices `[start, end)`.
    pub slices: Slab,
    /// Where it starts and ends along the axis, mm (voxel (0,0,0) at 0; boundaries lie halfway
    /// between slice centres).
    pub mm: (f64, f64),
    /// Where it starts and ends in world coordinates: the signed positions of its boundary
    /// planes along the partition's `world_axis`, mm (equal to `mm` when the file states no
    /// orientation).
    pub world_mm: (f64, f64),
    /// Counted samples.
    pub samples: u64,
    /// Entropy of its intensity histogram, bits.
    pub entropy: f64,
    /// Mean intensity of its counted samples.
    pub mean: Option<f64>,
    /// The share of its positions inside the volume that are background or missing.
    pub background_fraction: f64,
    /// It holds next to nothing: per slice, fewer counted samples (neither background nor
    /// missing) than [`EMPTY_SHARE`] of the stack's average.
    pub empty: bool,
}

/// A slab counting less than this share of the stack's average samples per slice is empty.
pub const EMPTY_SHARE: f64 = 0.05;

/// Summaries of `slabs` of `stack`, whose per-slice histograms are `histograms`.
pub fn describe(stack: &SliceStack, histograms: &[u64], slabs: &[Slab]) -> Vec<SlabInfo> {
    let bins = stack.bins();
    let per_slice = histograms.iter().sum::<u64>() as f64 / stack.slices().max(1) as f64;
    slabs
        .iter()
        .map(|&(a, b)| {
            // The slab's own slices summed, not prefix sums of every slice: those would hold
            // `slices × bins` counts more for a few slabs (51 MB for 200,000 slices).
            let mut h = vec![0u64; bins];
            for slice in histograms[a * bins..b * bins].chunks_exact(bins) {
                h.iter_mut().zip(slice).for_each(|(t, c)| *t += c);
            }
            let (t, o) = (stack.thickness(), stack.offset());
            let samples = h.iter().sum::<u64>();
            let mm = (o + (a as f64 - 0.5) * t, o + (b as f64 - 0.5) * t);
            SlabInfo {
                slices: (a, b),
                mm,
                world_mm: (stack.world_mm(mm.0), stack.world_mm(mm.1)),
                samples,
                entropy: entropy(h.iter().copied()),
                mean: stack.mean(a, b),
                background_fraction: stack.left_out(a, b),
                empty: (samples as f64) < EMPTY_SHARE * per_slice * (b - a) as f64,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slab_ranges_read_inclusively() {
        assert_eq!(slab_text((12, 13)), "12");
        assert_eq!(slab_text((0, 45)), "0–44");
    }

    #[test]
    fn prefix_sums_accumulate_per_bin() {
        let h = [1, 2, 3, 4, 5, 6];
        assert_eq!(prefix_histograms(&h, 2), vec![0, 0, 1, 2, 4, 6, 9, 12]);
    }
}
