//! One partition as a front end shows it: run a method along an axis to a stopping rule, and
//! gather the slabs, the steps taken, what each slab holds, its boundaries and the curves.

use rayon::prelude::*;
use serde::Serialize;

use super::bottom_up::{Columns, consecutive_nmi};
use super::top_down::Gains;
use super::{
    MergeHistory, Method, OptimalPartitions, Slab, SlabInfo, SliceStack, SplitHistory, StackParams,
    describe,
};
use crate::error::{Error, Result};
use crate::progress::Monitor;
use crate::volume::sampling::dot;
use crate::volume::{Volume, VoxelType};

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

/// One step taken, as DESIGN.md §3 writes it.
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
}

/// The optimum is compared with greedy up to at least this many slabs.
const COMPARE_SLABS: usize = 8;

/// The slabs and steps of `params.method` stopped by `params.stop`.
fn choose(
    stack: &SliceStack,
    h: &[u64],
    top: &SplitHistory,
    optimal: &OptimalPartitions,
    params: &PartitionParams,
    monitor: &Monitor,
) -> Result<(Vec<Slab>, Vec<Step>)> {
    let (n, bins) = (stack.slices(), stack.bins());
    Ok(match params.method {
        Method::TopDown => {
            let taken = match params.stop {
                Stop::Slabs(k) => k - 1,
                Stop::Threshold(t) => top.steps_above(t),
            };
            let steps = top.steps[..taken]
                .iter()
                .map(|s| Step::Split {
                    split: s.split,
                    at: s.at,
                    gain: s.gain,
                })
                .collect();
            (top.slabs_after(taken), steps)
        }
        Method::BottomUp => {
            let history = MergeHistory::new(stack, monitor)?;
            let taken = match params.stop {
                Stop::Slabs(k) => n - k,
                Stop::Threshold(t) => history.steps_above(t),
            };
            let steps = history.steps[..taken]
                .iter()
                .map(|m| Step::Merge {
                    merge: m.merge,
                    nmi: m.nmi,
                })
                .collect();
            (history.slabs_after(taken), steps)
        }
        Method::Optimal => {
            let k = match params.stop {
                Stop::Slabs(k) => k,
                Stop::Threshold(t) => {
                    // Grow K while one more slab adds at least t bits.
                    let full = OptimalPartitions::new(h, bins, n)?;
                    let i = full
                        .by_count
                        .windows(2)
                        .position(|w| w[1].information - w[0].information < t);
                    i.map_or(n, |i| i + 1)
                }
            };
            let slabs = match optimal.get(k) {
                Some(o) => o.slabs.clone(),
                None => OptimalPartitions::new(h, bins, k)?
                    .get(k)
                    .map(|o| o.slabs.clone())
                    .unwrap_or_default(),
            };
            (slabs, Vec::new())
        }
    })
}

/// Partitions `volume` along `axis`.
pub fn partition(
    volume: &Volume,
    axis: [f64; 3],
    params: &PartitionParams,
    monitor: &Monitor,
) -> Result<Partition> {
    if volume.is_constant() {
        return Err(Error::Degenerate(format!(
            "the volume is constant (every voxel is {}): there is nothing to partition",
            volume.stats().min
        )));
    }
    let stack = SliceStack::new(volume, axis, &params.stack, monitor)?;
    let n = stack.slices();
    if n < 2 {
        return Err(Error::Degenerate(format!(
            "only {n} slice along the axis: nothing to partition"
        )));
    }
    if let Stop::Slabs(k) = params.stop
        && !(1..=n).contains(&k)
    {
        return Err(Error::InvalidParameter(format!(
            "--slabs {k} is not between 1 and the {n} slices"
        )));
    }
    let bins = stack.bins();
    let h = stack.slice_histograms();
    let top = SplitHistory::new(&h, bins);
    let wanted = match params.stop {
        Stop::Slabs(k) => k,
        Stop::Threshold(_) => 1,
    };
    let limit = wanted.max(COMPARE_SLABS).min(n);
    let optimal = OptimalPartitions::new(&h, bins, limit)?;
    let (slabs, steps) = choose(&stack, &h, &top, &optimal, params, monitor)?;
    monitor.check()?;
    let columns = Columns::new(&stack);
    let boundary_nmi = consecutive_nmi(&stack, &columns, &slabs, monitor)?;
    let singles: Vec<Slab> = (0..n).map(|s| (s, s + 1)).collect();
    let nmi_curve = consecutive_nmi(&stack, &columns, &singles, monitor)?;
    let gains = Gains::new(&h, bins);
    let total = gains.total();
    let ratio = |x: f64| {
        if total > 0.0 {
            (x / total).max(0.0)
        } else {
            0.0
        }
    };
    let boundary_gain = slabs
        .windows(2)
        .map(|w| {
            ratio(
                gains.scaled(w[0].0, w[1].1)
                    - gains.scaled(w[0].0, w[0].1)
                    - gains.scaled(w[1].0, w[1].1),
            )
        })
        .collect();
    let information =
        ratio(gains.scaled(0, n) - slabs.iter().map(|&(a, b)| gains.scaled(a, b)).sum::<f64>());
    let comparison = optimal
        .by_count
        .iter()
        .enumerate()
        .map(|(i, o)| Comparison {
            slabs: i + 1,
            optimal: o.information,
            greedy: top.information(i + 1),
        })
        .collect();
    Ok(Partition {
        axis: stack.axis(),
        method: params.method,
        slices: n,
        thickness: stack.thickness(),
        offset: stack.offset(),
        info: describe(&stack, &h, &slabs),
        slabs,
        steps,
        boundary_nmi,
        boundary_gain,
        information,
        entropy: top.entropy,
        nmi_curve,
        gain_curve: top.gain_curve().to_vec(),
        comparison,
    })
}

/// The NMI of the two slabs at each boundary of `slabs` (one pass over the stack).
pub fn slab_nmi(stack: &SliceStack, slabs: &[Slab], monitor: &Monitor) -> Result<Vec<f64>> {
    consecutive_nmi(stack, &Columns::new(stack), slabs, monitor)
}

/// ΔI of each boundary of `slabs`: the information lost by merging the two slabs there, bits.
pub fn boundary_gains(histograms: &[u64], bins: usize, slabs: &[Slab]) -> Vec<f64> {
    let gains = Gains::new(histograms, bins);
    let total = gains.total();
    slabs
        .windows(2)
        .map(|w| {
            let lost = gains.scaled(w[0].0, w[1].1)
                - gains.scaled(w[0].0, w[0].1)
                - gains.scaled(w[1].0, w[1].1);
            if total > 0.0 {
                (lost / total).max(0.0)
            } else {
                0.0
            }
        })
        .collect()
}

/// A label volume: the index of the slab each voxel lies in (u8, or u16 above 255 slabs), with
/// the volume's dimensions and spacing. A voxel belongs to the slice whose centre is nearest
/// along the axis.
pub fn label_volume(volume: &Volume, p: &Partition) -> Result<Volume> {
    let mut slab_of = vec![0u16; p.slices];
    for (i, &(a, b)) in p.slabs.iter().enumerate() {
        slab_of[a..b].fill(i as u16);
    }
    let [nx, ny, _] = volume.dims();
    let s = volume.spacing();
    let last = p.slices as f64 - 1.0;
    let mut labels = vec![0.0f32; volume.len()];
    labels
        .par_chunks_mut(nx * ny)
        .enumerate()
        .for_each(|(z, plane)| {
            for (i, l) in plane.iter_mut().enumerate() {
                let pos = [
                    (i % nx) as f64 * s[0],
                    (i / nx) as f64 * s[1],
                    z as f64 * s[2],
                ];
                let k = ((dot(pos, p.axis) - p.offset) / p.thickness)
                    .round()
                    .clamp(0.0, last);
                *l = f32::from(slab_of[k as usize]);
            }
        });
    let ty = if p.slabs.len() <= 256 {
        VoxelType::U8
    } else {
        VoxelType::U16
    };
    Volume::new(volume.dims(), volume.spacing(), ty, labels)
}
