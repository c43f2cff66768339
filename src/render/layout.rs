//! The exploded layout: the slabs of a partition translated apart along the axis, with gaps that
//! are uniform or grow with how dissimilar the two slabs at a boundary are.

use serde::Serialize;

use crate::partition::{Partition, SliceStack};

/// With similarity gaps, this share of the total gap is spread evenly (the rest by
/// dissimilarity), so that no gap is narrower than this fraction of the mean and every cut shows.
pub const MIN_GAP: f64 = 0.5;

/// The total gap, as a fraction of the stack's length, that renders use unless told: wide
/// enough that the cut faces show from the default camera.
pub const DEFAULT_SPREAD: f64 = 0.5;

/// How the gaps between slabs are sized.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Gap {
    /// Every gap the same.
    Uniform,
    /// Proportional to `1 - NMI` of the two slabs: the strongest boundaries open widest (none
    /// narrower than [`MIN_GAP`] of the mean).
    Similarity,
}

/// The geometry of a slice stack that a layout needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stack {
    /// Unit axis.
    pub axis: [f64; 3],
    /// Number of slices.
    pub slices: usize,
    /// Distance between slices, mm.
    pub thickness: f64,
    /// Position of slice 0's centre along the axis, mm.
    pub offset: f64,
}

impl Stack {
    /// The position of the centre of `slice` along the axis, mm.
    pub fn position(&self, slice: usize) -> f64 {
        self.offset + slice as f64 * self.thickness
    }

    /// The stack of a partition.
    pub fn of(p: &Partition) -> Self {
        Self {
            axis: p.axis,
            slices: p.slices,
            thickness: p.thickness,
            offset: p.offset,
        }
    }

    /// The geometry of a slice stack (a history's, whose slabs an interactive front end steps
    /// through).
    pub fn of_slices(s: &SliceStack) -> Self {
        Self {
            axis: s.axis(),
            slices: s.slices(),
            thickness: s.thickness(),
            offset: s.offset(),
        }
    }
}

/// One slab of the scene: the part of the volume whose position along the axis lies in
/// `[lo, hi)` (mm, voxel (0,0,0) at 0), drawn translated by `offset` mm along the axis.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Placement {
    /// Index of the slab in the partition.
    pub index: usize,
    /// Start along the axis, mm (−∞ for the first slab).
    pub lo: f64,
    /// End along the axis, mm (+∞ for the last slab).
    pub hi: f64,
    /// Translation along the axis, mm.
    pub offset: f64,
}

/// The slabs of a scene along an axis.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Layout {
    /// Unit axis.
    pub axis: [f64; 3],
    /// The slabs, in order along the axis.
    pub slabs: Vec<Placement>,
}

impl Layout {
    /// The whole volume as one slab, seen around `axis`.
    pub fn whole(axis: [f64; 3]) -> Self {
        Self {
            axis,
            slabs: vec![Placement {
                index: 0,
                lo: f64::NEG_INFINITY,
                hi: f64::INFINITY,
                offset: 0.0,
            }],
        }
    }

    /// The slabs of `p` pulled apart: the gaps add up to `spread` times the stack's length.
    pub fn exploded(p: &Partition, gap: Gap, spread: f64) -> Self {
        Self::from_slabs(&Stack::of(p), &p.slabs, Some(&p.boundary_nmi), gap, spread)
    }

    /// `slabs` of a stack pulled apart; `nmi` (one per boundary) sizes similarity gaps, which
    /// are uniform without it.
    pub fn from_slabs(
        stack: &Stack,
        slabs: &[(usize, usize)],
        nmi: Option<&[f64]>,
        gap: Gap,
        spread: f64,
    ) -> Self {
        let k = slabs.len();
        let total = spread.max(0.0) * stack.slices as f64 * stack.thickness;
        let mut weights: Vec<f64> = match (gap, nmi) {
            (Gap::Similarity, Some(nmi)) if nmi.len() + 1 == k => {
                nmi.iter().map(|n| (1.0 - n).max(0.0)).collect()
            }
            _ => vec![1.0; k.saturating_sub(1)],
        };
        // Every gap shows: a share of the total spread evenly, the rest by the weights, so
        // that none is narrower than that share of the mean.
        let mean = weights.iter().sum::<f64>() / weights.len().max(1) as f64;
        for w in &mut weights {
            *w = MIN_GAP * mean + (1.0 - MIN_GAP) * *w;
        }
        let sum: f64 = weights.iter().sum();
        let gaps: Vec<f64> = if sum > 1e-12 {
            weights.iter().map(|w| total * w / sum).collect()
        } else {
            vec![total / k.saturating_sub(1).max(1) as f64; k.saturating_sub(1)]
        };
        let mut offset = -total / 2.0;
        let edge = |c: usize| stack.offset + (c as f64 - 0.5) * stack.thickness;
        let placed = slabs
            .iter()
            .enumerate()
            .map(|(i, &(a, b))| {
                if i > 0 {
                    offset += gaps[i - 1];
                }
                Placement {
                    index: i,
                    lo: if i == 0 { f64::NEG_INFINITY } else { edge(a) },
                    hi: if i + 1 == k { f64::INFINITY } else { edge(b) },
                    offset,
                }
            })
            .collect();
        Self {
            axis: stack.axis,
            slabs: placed,
        }
    }

    /// How far the slabs reach beyond the volume along the axis, each way, mm.
    pub fn reach(&self) -> f64 {
        self.slabs
            .iter()
            .map(|s| s.offset.abs())
            .fold(0.0, f64::max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn similarity_gaps_follow_dissimilarity_but_none_closes() {
        let stack = Stack {
            axis: [0.0, 0.0, 1.0],
            slices: 100,
            thickness: 1.0,
            offset: 0.0,
        };
        let slabs = [(0, 25), (25, 50), (50, 75), (75, 100)];
        let nmi = [0.99, 0.5, 0.2];
        let l = Layout::from_slabs(&stack, &slabs, Some(&nmi), Gap::Similarity, 0.6);
        let gaps: Vec<f64> = l
            .slabs
            .windows(2)
            .map(|w| w[1].offset - w[0].offset)
            .collect();
        let total: f64 = gaps.iter().sum();
        assert!(
            (total - 60.0).abs() < 1e-9,
            "the gaps add up to the spread: {total}"
        );
        let mean = total / 3.0;
        assert!(gaps[0] >= MIN_GAP * mean - 1e-9, "{gaps:?}");
        assert!(gaps[0] < gaps[1] && gaps[1] < gaps[2], "{gaps:?}");
        let uniform = Layout::from_slabs(&stack, &slabs, Some(&nmi), Gap::Uniform, 0.6);
        for w in uniform.slabs.windows(2) {
            assert!((w[1].offset - w[0].offset - 20.0).abs() < 1e-9);
        }
    }
}
