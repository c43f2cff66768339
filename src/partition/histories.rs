//! Everything known along one axis: the slice stack, the top-down, bottom-up and optimal
//! histories, and the curves, so that stepping, switching method, changing the slab count or the
//! threshold never recompute. A position in a method's history is how many steps were taken (for
//! the optimal method, the slab count minus one); every rule that maps a slab count or a
//! threshold to a position is written here once.

use std::sync::Arc;

use super::bottom_up::{Columns, add_consecutive_joints, consecutive_nmi};
use super::top_down::Gains;
use super::{
    COMPARE_MAX_SLICES, MAX_SLICES, MergeHistory, Method, OptimalPartitions, Slab, SlabInfo,
    SliceStack, SplitHistory, StackParams, Step, Stop, describe,
};
use crate::error::{Error, Result};
use crate::progress::Monitor;
use crate::volume::Volume;

/// Which histories to compute beyond top-down, which is always there.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Scope {
    /// Compute the bottom-up history (the costly one: a pass over the stack per merge pair).
    pub bottom_up: bool,
    /// The optimal partitions into 1 ..= this many slabs (0: none). Skipped when the stack has
    /// more than `optimal_max_slices` slices.
    pub optimal_slabs: usize,
    /// The longest stack the optimum is computed for: its table grows with the square of the
    /// slices (8 bytes each), so [`COMPARE_MAX_SLICES`] when it is only compared with greedy,
    /// [`MAX_SLICES`] when it is the method asked for.
    pub optimal_max_slices: usize,
    /// The most top-down splits to take.
    pub top_steps: usize,
}

impl Scope {
    /// Every history, the optimum up to 32 slabs and top-down to 4096 splits: what an interactive
    /// front end steps through.
    pub const ALL: Self = Self {
        bottom_up: true,
        optimal_slabs: 32,
        optimal_max_slices: COMPARE_MAX_SLICES,
        top_steps: 4096,
    };
}

/// The histories of all three methods along one axis.
pub struct Histories {
    stack: Arc<SliceStack>,
    histograms: Vec<u64>,
    gains: Gains,
    top: SplitHistory,
    bottom: Option<MergeHistory>,
    optimal: Option<OptimalPartitions>,
    /// The longest stack the optimum was to be computed for.
    optimal_max_slices: usize,
    nmi_curve: Vec<f64>,
}

impl Histories {
    /// Slices `volume` along `axis` and runs the methods `scope` asks for to the end.
    pub fn new(
        volume: &Volume,
        axis: [f64; 3],
        params: &StackParams,
        scope: Scope,
        monitor: &Monitor,
    ) -> Result<Self> {
        Self::check_not_constant(volume)?;
        let stack = SliceStack::new(volume, axis, params, monitor)?;
        Self::of_stack(stack, scope, monitor)
    }

    /// An error for a constant volume, which has nothing to partition.
    pub(crate) fn check_not_constant(volume: &Volume) -> Result<()> {
        if volume.is_constant() {
            return Err(Error::Degenerate(format!(
                "the volume is constant (every voxel is {}): there is nothing to partition",
                volume.stats().min
            )));
        }
        Ok(())
    }

    /// An error for fewer than two slices, which have nothing to partition.
    pub(crate) fn check_slices(n: usize) -> Result<()> {
        if n < 2 {
            return Err(Error::Degenerate(format!(
                "only {n} slice along the axis: nothing to partition"
            )));
        }
        Ok(())
    }

    /// The histories of a stack already cut.
    pub fn of_stack(stack: SliceStack, scope: Scope, monitor: &Monitor) -> Result<Self> {
        let n = stack.slices();
        Self::check_slices(n)?;
        monitor.start("slice histograms and curves", 2);
        let histograms = stack.slice_histograms();
        monitor.advance(1)?;
        let bottom = if scope.bottom_up {
            Some(MergeHistory::new(&stack, monitor)?)
        } else {
            None
        };
        let nmi_curve = if let Some(b) = &bottom {
            b.slice_nmi().to_vec()
        } else {
            let singles: Vec<Slab> = (0..n).map(|s| (s, s + 1)).collect();
            let nmi = consecutive_nmi(&stack, &Columns::new(&stack), &singles, monitor)?;
            monitor.advance(1)?;
            nmi
        };
        Self::of_parts(stack, histograms, nmi_curve, bottom, scope)
    }

    /// The histories of a stack whose columns were not kept ([`Cutter::summary`]): its slice
    /// histograms and NMI curve counted strip by strip, with no bottom-up history. The NMI at
    /// slab boundaries is then the caller's to count ([`boundary_nmi`](Self::boundary_nmi) is
    /// an error).
    ///
    /// [`Cutter::summary`]: super::stack::Cutter::summary
    pub(crate) fn of_summary(
        summary: SliceStack,
        histograms: Vec<u64>,
        nmi_curve: Vec<f64>,
        scope: Scope,
    ) -> Result<Self> {
        Self::of_parts(summary, histograms, nmi_curve, None, scope)
    }

    /// The histories from a stack's histograms, NMI curve and bottom-up history.
    fn of_parts(
        stack: SliceStack,
        histograms: Vec<u64>,
        nmi_curve: Vec<f64>,
        bottom: Option<MergeHistory>,
        scope: Scope,
    ) -> Result<Self> {
        let (n, bins) = (stack.slices(), stack.bins());
        Self::check_slices(n)?;
        let top = SplitHistory::with_limit(&histograms, bins, scope.top_steps);
        let optimal_max_slices = scope.optimal_max_slices.min(MAX_SLICES);
        let optimal = if scope.optimal_slabs > 0 && n <= optimal_max_slices {
            Some(OptimalPartitions::new(
                &histograms,
                bins,
                scope.optimal_slabs.min(n),
            )?)
        } else {
            None
        };
        Ok(Self {
            gains: Gains::new(&histograms, bins),
            stack: Arc::new(stack),
            histograms,
            top,
            bottom,
            optimal,
            optimal_max_slices,
            nmi_curve,
        })
    }

    /// The slices, quantized.
    pub fn stack(&self) -> &Arc<SliceStack> {
        &self.stack
    }

    /// Number of slices.
    pub fn slices(&self) -> usize {
        self.stack.slices()
    }

    /// The top-down history.
    pub fn top(&self) -> &SplitHistory {
        &self.top
    }

    /// The bottom-up history, when it was computed.
    pub fn bottom(&self) -> Option<&MergeHistory> {
        self.bottom.as_ref()
    }

    /// The optimal partitions, when they were computed.
    pub fn optimal(&self) -> Option<&OptimalPartitions> {
        self.optimal.as_ref()
    }

    /// Whether `method`'s history was computed.
    pub fn has(&self, method: Method) -> bool {
        match method {
            Method::TopDown => true,
            Method::BottomUp => self.bottom.is_some(),
            Method::Optimal => self.optimal.is_some(),
        }
    }

    /// An error naming `method` when its history was not computed.
    fn require(&self, method: Method) -> Result<()> {
        if self.has(method) {
            return Ok(());
        }
        let n = self.slices();
        Err(match method {
            Method::Optimal if n > self.optimal_max_slices => Error::invalid(
                "slices",
                n,
                format!(
                    "at most {} for the optimal partition (its table grows with the square of \
                     the slices)",
                    self.optimal_max_slices
                ),
            ),
            _ => Error::invalid("method", method.name(), "a history that was computed"),
        })
    }

    /// The last position of `method`'s history: splits, merges, or slab counts minus one.
    pub fn last(&self, method: Method) -> usize {
        match method {
            Method::TopDown => self.top.steps.len(),
            Method::BottomUp => self.bottom.as_ref().map_or(0, |b| b.steps.len()),
            Method::Optimal => self
                .optimal
                .as_ref()
                .map_or(0, |o| o.by_count.len().saturating_sub(1)),
        }
    }

    /// The slab count at `position` of `method`'s history.
    pub fn slab_count(&self, method: Method, position: usize) -> usize {
        match method {
            Method::TopDown | Method::Optimal => position + 1,
            Method::BottomUp => self.slices() - position,
        }
    }

    /// The position of `method`'s history with `k` slabs (clamped to what the history has).
    pub fn position_for(&self, method: Method, k: usize) -> usize {
        let k = k.clamp(1, self.slices());
        match method {
            Method::TopDown | Method::Optimal => (k - 1).min(self.last(method)),
            Method::BottomUp => (self.slices() - k).min(self.last(method)),
        }
    }

    /// The position reached when `method` stops at `threshold`: top-down stops when the best ΔI
    /// falls below it, bottom-up when the largest NMI does, the optimal method when one more slab
    /// would add less than it to I(slab; intensity).
    pub fn position_for_threshold(&self, method: Method, threshold: f64) -> usize {
        match method {
            Method::TopDown => self.top.steps_above(threshold),
            Method::BottomUp => self.bottom.as_ref().map_or(0, |b| b.steps_above(threshold)),
            Method::Optimal => self.optimal.as_ref().map_or(0, |o| {
                o.by_count
                    .windows(2)
                    .position(|w| w[1].information - w[0].information < threshold)
                    .unwrap_or(o.by_count.len() - 1)
            }),
        }
    }

    /// The position where `method` stops by `stop`; an error when a slab count is outside
    /// `1 ..= slices` or the method's history was not computed.
    pub fn position(&self, method: Method, stop: Stop) -> Result<usize> {
        self.require(method)?;
        match stop {
            Stop::Slabs(k) => {
                let n = self.slices();
                if !(1..=n).contains(&k) || (method == Method::Optimal && k > self.last(method) + 1)
                {
                    return Err(Error::invalid(
                        "slabs",
                        k,
                        format!("between 1 and the {n} slices"),
                    ));
                }
                Ok(self.position_for(method, k))
            }
            Stop::Threshold(t) => Ok(self.position_for_threshold(method, t)),
        }
    }

    /// The slabs at `position` of `method`'s history, in slice order.
    pub fn slabs(&self, method: Method, position: usize) -> Vec<Slab> {
        let position = position.min(self.last(method));
        match (method, &self.bottom, &self.optimal) {
            (Method::BottomUp, Some(b), _) => b.slabs_after(position),
            (Method::Optimal, _, Some(o)) => o.by_count[position].slabs.clone(),
            (Method::TopDown, ..) => self.top.slabs_after(position),
            _ => vec![(0, self.slices())],
        }
    }

    /// The steps taken to reach `position` of `method`'s history, in order (none for the
    /// optimal method, which takes no steps).
    pub fn steps(&self, method: Method, position: usize) -> Vec<Step> {
        match (method, &self.bottom) {
            (Method::TopDown, _) => self.top.steps[..position.min(self.top.steps.len())]
                .iter()
                .map(|s| Step::Split {
                    split: s.split,
                    at: s.at,
                    gain: s.gain,
                })
                .collect(),
            (Method::BottomUp, Some(b)) => b.steps[..position.min(b.steps.len())]
                .iter()
                .map(|m| Step::Merge {
                    merge: m.merge,
                    nmi: m.nmi,
                })
                .collect(),
            _ => Vec::new(),
        }
    }

    /// What each of `slabs` holds.
    pub fn describe(&self, slabs: &[Slab]) -> Vec<SlabInfo> {
        describe(&self.stack, &self.histograms, slabs)
    }

    /// ΔI of each boundary of `slabs`: the information lost by merging the two slabs there, bits.
    pub fn boundary_gains(&self, slabs: &[Slab]) -> Vec<f64> {
        slabs
            .windows(2)
            .map(|w| self.gains.merge_loss(w[0].0, w[0].1, w[1].1))
            .collect()
    }

    /// I(slab; intensity) of `slabs`, bits.
    pub fn information(&self, slabs: &[Slab]) -> f64 {
        self.gains.information(slabs)
    }

    /// H(intensity) of the stack: the most any partition can keep, bits.
    pub fn entropy(&self) -> f64 {
        self.top.entropy
    }

    /// NMI of each boundary at `position` where the history knows it (bottom-up: the pairs before
    /// the next merge), without a pass over the stack.
    pub fn known_nmi(&self, method: Method, position: usize) -> Option<Vec<f64>> {
        match (method, &self.bottom) {
            (Method::BottomUp, Some(b)) => b
                .steps
                .get(position)
                .map(|m| m.pairs.clone())
                .filter(|p| !p.is_empty()),
            _ => None,
        }
    }

    /// The NMI of the two slabs at each boundary of `slabs` (one pass over the stack); an error
    /// for histories of a stack whose columns were not kept.
    pub fn boundary_nmi(&self, slabs: &[Slab], monitor: &Monitor) -> Result<Vec<f64>> {
        self.require_columns()?;
        consecutive_nmi(&self.stack, &Columns::new(&self.stack), slabs, monitor)
    }

    /// The histogram of slab `[a, b)`'s samples, the background left out (`bins` counts): what
    /// top-down's gains are computed from.
    pub fn slab_histogram(&self, (a, b): Slab) -> Vec<u64> {
        let bins = self.stack.bins();
        let mut h = vec![0u64; bins];
        for slice in self.histograms[a * bins..b * bins].chunks_exact(bins) {
            h.iter_mut().zip(slice).for_each(|(t, c)| *t += c);
        }
        h
    }

    /// `ΔI` of every cut strictly inside `slab`, bits: the cut at `slab.0 + 1 + i` is entry `i`.
    pub fn cut_gains(&self, (a, b): Slab) -> Vec<f64> {
        self.gains.curve(a, b)
    }

    /// The joint histograms of pairs of adjacent slabs (`bins × bins` each, row-major: rows are
    /// the first slab's symbol, columns the second's), each summed over every pair of their
    /// slices at corresponding pixels: what bottom-up's NMI is computed from. The stack's columns
    /// are sorted once, then one pass over them a pair, reporting a unit a pair. An error for
    /// histories of a stack whose columns were not kept.
    pub fn joint_histograms(
        &self,
        pairs: &[(Slab, Slab)],
        monitor: &Monitor,
    ) -> Result<Vec<Vec<u64>>> {
        self.require_columns()?;
        let bins = self.stack.bins();
        let columns = Columns::new(&self.stack);
        pairs
            .iter()
            .map(|&(first, second)| {
                let mut joint = vec![0u64; bins * bins];
                add_consecutive_joints(
                    Some(&self.stack),
                    &columns,
                    &[first, second],
                    &mut joint,
                    monitor,
                )?;
                monitor.advance(1)?;
                Ok(joint)
            })
            .collect()
    }

    /// An error for histories of a stack whose columns were not kept.
    fn require_columns(&self) -> Result<()> {
        if self.stack.pixels() == 0 {
            return Err(Error::invalid(
                "stack",
                "streamed",
                "the slices' columns, which a stack counted strip by strip does not keep",
            ));
        }
        Ok(())
    }

    /// What the histories leave out, for the user: the optimum on a stack too long for it, a
    /// top-down history stopped short of single slices.
    pub fn notes(&self) -> Vec<String> {
        let n = self.slices();
        let mut notes = Vec::new();
        if self.optimal.is_none() && n > self.optimal_max_slices {
            notes.push(format!(
                "the optimal partition is skipped: {n} slices, more than the {} it is computed \
                 for (its table grows with the square of the slices)",
                self.optimal_max_slices
            ));
        }
        if self.top.steps.len() + 1 < n && self.top.steps.len() >= Scope::ALL.top_steps {
            notes.push(format!(
                "top-down history kept to its first {} splits of {n} slices",
                self.top.steps.len()
            ));
        }
        notes
    }

    /// The NMI between each slice and the next.
    pub fn nmi_curve(&self) -> &[f64] {
        &self.nmi_curve
    }

    /// ΔI of cutting the whole stack at each slice 1 .. slices.
    pub fn gain_curve(&self) -> &[f64] {
        self.top.gain_curve()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::partition::SliceStack;

    /// Eight slices of 16 pixels: four of material 0, then four of material 1, textured so that
    /// neighbouring slices share structure.
    fn two_materials() -> Histories {
        let slices: Vec<Vec<u8>> = (0..8u8)
            .map(|s| (0..16u8).map(|p| 2 * (s / 4) + (p % 2)).collect())
            .collect();
        let stack = SliceStack::from_slices(&slices, 4).unwrap();
        Histories::of_stack(stack, Scope::ALL, &Monitor::none()).unwrap()
    }

    #[test]
    fn positions_and_slab_counts_agree_for_every_method() {
        let h = two_materials();
        assert_eq!(h.last(Method::TopDown), 7);
        assert_eq!(h.last(Method::BottomUp), 7);
        assert_eq!(h.last(Method::Optimal), 7);
        for method in [Method::TopDown, Method::BottomUp, Method::Optimal] {
            for k in 1..=8 {
                let p = h.position_for(method, k);
                assert_eq!(h.slab_count(method, p), k, "{method:?}");
                assert_eq!(h.slabs(method, p).len(), k, "{method:?}");
                assert_eq!(h.position(method, Stop::Slabs(k)).unwrap(), p);
            }
            assert!(h.position(method, Stop::Slabs(9)).is_err());
            assert!(h.position(method, Stop::Slabs(0)).is_err());
        }
        assert_eq!(h.slabs(Method::TopDown, 1), vec![(0, 4), (4, 8)]);
        assert_eq!(h.slabs(Method::Optimal, 1), vec![(0, 4), (4, 8)]);
    }

    #[test]
    fn the_sharp_boundary_keeps_one_bit_and_thresholds_stop_at_it() {
        let h = two_materials();
        let two = h.slabs(Method::TopDown, 1);
        assert!((h.information(&two) - 1.0).abs() < 1e-12);
        assert_eq!(h.boundary_gains(&two).len(), 1);
        assert!((h.boundary_gains(&two)[0] - 1.0).abs() < 1e-12);
        // Top-down's first split gains 1 bit, every later one 0.
        assert_eq!(h.position_for_threshold(Method::TopDown, 0.5), 1);
        // The optimum gains 1 bit from one slab to two, nothing after.
        assert_eq!(h.position_for_threshold(Method::Optimal, 0.5), 1);
        assert_eq!(h.steps(Method::TopDown, 1).len(), 1);
        assert!(h.steps(Method::Optimal, 3).is_empty());
        assert_eq!(h.nmi_curve().len(), 7);
        assert_eq!(h.gain_curve().len(), 7);
    }

    #[test]
    fn histories_not_computed_are_errors_not_answers() {
        let slices: Vec<Vec<u8>> = (0..4u8).map(|s| vec![s % 2; 4]).collect();
        let stack = SliceStack::from_slices(&slices, 2).unwrap();
        let scope = Scope {
            bottom_up: false,
            optimal_slabs: 0,
            optimal_max_slices: MAX_SLICES,
            top_steps: usize::MAX,
        };
        let h = Histories::of_stack(stack, scope, &Monitor::none()).unwrap();
        assert!(!h.has(Method::BottomUp));
        assert!(h.position(Method::BottomUp, Stop::Slabs(2)).is_err());
        assert!(h.position(Method::Optimal, Stop::Slabs(2)).is_err());
        assert_eq!(h.position(Method::TopDown, Stop::Slabs(2)).unwrap(), 1);
        assert_eq!(
            h.nmi_curve().len(),
            3,
            "the NMI curve is there without bottom-up"
        );
    }
}
