//! One partition as a front end shows it: a position in a method's history, with the slabs, the
//! steps taken, what each slab holds, its boundaries and the curves.

use serde::Serialize;

use super::histories::{Histories, Scope};
use super::{
    BackgroundSummary, COMPARE_MAX_SLICES, MAX_SLICES, Method, Slab, SlabInfo, SliceStack,
    StackParams,
};
use crate::error::Result;
use crate::geometry::WorldAxis;
use crate::progress::Monitor;
use crate::volume::Volume;
use crate::volume::background::BackgroundRule;

/// When to stop splitting or merging.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Stop {
    /// At this many slabs.
    Slabs(usize),
    /// Top-down: when the best ΔI falls below it; bottom-up: when the largest NMI does;
    /// optimal: when one more slab would add less than it to I(slab; intensity).
    Threshold(f64),
}

/// How to partition.
#[derive(Clone, Debug, PartialEq)]
pub struct PartitionParams {
    /// The method.
    pub method: Method,
    /// The stopping rule.
    pub stop: Stop,
    /// How to slice.
    pub stack: StackParams,
}

impl Default for PartitionParams {
    fn default() -> Self {
        Self {
            method: Method::TopDown,
            stop: Stop::Slabs(4),
            stack: StackParams::default(),
        }
    }
}

/// One step taken, as docs/design.md §3 writes it.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Step {
    /// A top-down split of `split` at slice `at` gaining `gain` bits.
    Split {
        /// The slab split.
        split: Slab,
        /// First slice of the second part.
        at: usize,
        /// ΔI, bits.
        gain: f64,
    },
    /// A bottom-up merge of two adjacent slabs with NMI `nmi`.
    Merge {
        /// The two slabs.
        merge: (Slab, Slab),
        /// Their NMI.
        nmi: f64,
    },
}

/// The optimum beside the greedy top-down at one slab count.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Comparison {
    /// Slab count.
    pub slabs: usize,
    /// I(slab; intensity) of the optimal partition, bits.
    pub optimal: f64,
    /// I(slab; intensity) of the greedy top-down partition, bits.
    pub greedy: f64,
}

/// A partition along an axis, with everything a front end shows about it.
#[derive(Clone, Debug, Serialize)]
pub struct Partition {
    /// The canonical axis.
    pub axis: [f64; 3],
    /// The axis in world coordinates: `world_axis` and `anatomy`.
    #[serde(flatten)]
    pub world: WorldAxis,
    /// Position `s` mm along the axis lies at `a·s + b` mm along `world_axis`: `(a, b)`.
    #[serde(skip)]
    pub world_line: (f64, f64),
    /// The method.
    pub method: Method,
    /// Number of slices.
    pub slices: usize,
    /// Distance between slices, mm.
    pub thickness: f64,
    /// Position of slice 0's centre along the axis, mm.
    pub offset: f64,
    /// The slabs, in slice order.
    pub slabs: Vec<Slab>,
    /// The steps taken to reach them, in order (none for the optimal method).
    pub steps: Vec<Step>,
    /// What each slab holds.
    pub info: Vec<SlabInfo>,
    /// NMI of the two slabs at each boundary.
    pub boundary_nmi: Vec<f64>,
    /// ΔI of each boundary: the information lost by merging the two slabs there, bits.
    pub boundary_gain: Vec<f64>,
    /// I(slab; intensity) of the partition, bits.
    pub information: f64,
    /// H(intensity) of the stack: the most any partition can keep, bits.
    pub entropy: f64,
    /// NMI between each slice and the next.
    pub nmi_curve: Vec<f64>,
    /// ΔI of cutting the whole stack at each slice 1 .. slices.
    pub gain_curve: Vec<f64>,
    /// The optimum beside the greedy top-down for 1 ..= max(8, K) slabs.
    pub comparison: Vec<Comparison>,
    /// What was left out as background (reported at the top of the analysis).
    #[serde(skip)]
    pub background: BackgroundSummary,
    /// What was left out of the analysis, and why.
    pub notes: Vec<String>,
}

/// The optimum is compared with greedy up to at least this many slabs.
const COMPARE_SLABS: usize = 8;

impl PartitionParams {
    /// The paper's partition: top-down to 4 slabs, every voxel counted.
    pub fn paper() -> Self {
        Self {
            stack: StackParams {
                background: BackgroundRule::None,
                ..StackParams::default()
            },
            ..Self::default()
        }
    }

    /// The histories a partition by these parameters reads: bottom-up only for its own method,
    /// the optimum as far as the method and the comparison with greedy need.
    pub fn scope(&self, slices_hint: Option<usize>) -> Scope {
        let wanted = match (self.method, self.stop) {
            (_, Stop::Slabs(k)) => k,
            // The threshold rule of the optimal method may ask for any count.
            (Method::Optimal, Stop::Threshold(_)) => slices_hint.unwrap_or(MAX_SLICES),
            (_, Stop::Threshold(_)) => 1,
        };
        Scope {
            bottom_up: self.method == Method::BottomUp,
            optimal_slabs: wanted.max(COMPARE_SLABS),
            optimal_max_slices: if self.method == Method::Optimal {
                MAX_SLICES
            } else {
                COMPARE_MAX_SLICES
            },
            // The greedy side of the comparison, and the method's own steps.
            top_steps: match (self.method, self.stop) {
                (Method::TopDown, Stop::Threshold(_)) => usize::MAX,
                _ => wanted.max(COMPARE_SLABS) - 1,
            },
        }
    }
}

impl Partition {
    /// The world position (mm along `world_axis`) of position `s` mm along the axis.
    pub fn world_mm(&self, s: f64) -> f64 {
        self.world_line.0 * s + self.world_line.1
    }

    /// The partition at `position` of `method`'s history, with everything a front end shows
    /// about it (one pass over the stack for the NMI at its boundaries).
    pub fn new(
        histories: &Histories,
        method: Method,
        position: usize,
        monitor: &Monitor,
    ) -> Result<Self> {
        let slabs = histories.slabs(method, position);
        let boundary_nmi = histories.boundary_nmi(&slabs, monitor)?;
        Ok(Self::with_boundary_nmi(
            histories,
            method,
            position,
            boundary_nmi,
        ))
    }

    /// The partition at `position` of `method`'s history, the NMI at its boundaries counted by
    /// the caller.
    pub(crate) fn with_boundary_nmi(
        histories: &Histories,
        method: Method,
        position: usize,
        boundary_nmi: Vec<f64>,
    ) -> Self {
        let stack = histories.stack();
        let slabs = histories.slabs(method, position);
        let k = slabs.len();
        let top = histories.top();
        let comparison = histories
            .optimal()
            .map(|o| {
                o.by_count
                    .iter()
                    .take(k.max(COMPARE_SLABS))
                    .enumerate()
                    .map(|(i, o)| Comparison {
                        slabs: i + 1,
                        optimal: o.information,
                        greedy: top.information(i + 1),
                    })
                    .collect()
            })
            .unwrap_or_default();
        Self {
            axis: stack.axis(),
            world: stack.world().clone(),
            world_line: stack.world_line(),
            method,
            slices: stack.slices(),
            thickness: stack.thickness(),
            offset: stack.offset(),
            info: histories.describe(&slabs),
            steps: histories.steps(method, position),
            boundary_gain: histories.boundary_gains(&slabs),
            information: histories.information(&slabs),
            entropy: histories.entropy(),
            nmi_curve: histories.nmi_curve().to_vec(),
            gain_curve: histories.gain_curve().to_vec(),
            boundary_nmi,
            slabs,
            comparison,
            background: stack.background(),
            notes: histories.notes(),
        }
    }
}

/// Partitions `volume` along `axis`.
pub fn partition(
    volume: &Volume,
    axis: [f64; 3],
    params: &PartitionParams,
    monitor: &Monitor,
) -> Result<Partition> {
    partition_kept(volume, axis, params, monitor).map(|(p, _)| p)
}

/// [`partition`], with the histories it was taken from (for the numbers behind its steps).
pub fn partition_kept(
    volume: &Volume,
    axis: [f64; 3],
    params: &PartitionParams,
    monitor: &Monitor,
) -> Result<(Partition, Histories)> {
    Histories::check_not_constant(volume)?;
    let stack = SliceStack::new(volume, axis, &params.stack, monitor)?;
    let scope = params.scope(Some(stack.slices()));
    let histories = Histories::of_stack(stack, scope, monitor)?;
    let position = histories.position(params.method, params.stop)?;
    let partition = Partition::new(&histories, params.method, position, monitor)?;
    Ok((partition, histories))
}
