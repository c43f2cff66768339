//! The exploded layout: the slabs of a partition translated apart along the axis, with gaps that
//! are uniform or grow with how dissimilar the two slabs at a boundary are.

use serde::Serialize;

use crate::partition::Partition;

/// How the gaps between slabs are sized.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Gap {
    /// Every gap the same.
    Uniform,
    /// Proportional to `1 - NMI` of the two slabs: the strongest boundaries open widest.
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
    /// The stack of a partition.
    pub fn of(p: &Partition) -> Self {
        Self {
            axis: p.axis,
            slices: p.slices,
            thickness: p.thickness,
            offset: p.offset,
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
        let weights: Vec<f64> = match (gap, nmi) {
            (Gap::Similarity, Some(nmi)) if nmi.len() + 1 == k => {
                nmi.iter().map(|n| (1.0 - n).max(0.0)).collect()
            }
            _ => vec![1.0; k.saturating_sub(1)],
        };
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
