//! Everything known along one axis: the slice stack, all three histories and the curves, so that
//! stepping, switching method and changing the slab count never recompute.

use std::sync::Arc;

use slabscope::Volume;
use slabscope::error::Result;
use slabscope::partition::{
    MergeHistory, Method, OptimalPartitions, SlabInfo, SliceStack, SplitHistory, StackParams,
    boundary_gains, describe,
};
use slabscope::progress::Monitor;

/// The most slabs the optimal method is computed for.
pub const OPTIMAL_SLABS: usize = 32;

/// The histories and curves along one axis.
pub struct Analysis {
    /// The slices, quantized.
    pub stack: Arc<SliceStack>,
    /// Per-slice histograms, `slices × bins`.
    pub histograms: Vec<u64>,
    /// Top-down splits.
    pub top: SplitHistory,
    /// Bottom-up merges.
    pub bottom: MergeHistory,
    /// The optimum for 1 ..= `OPTIMAL_SLABS` slabs.
    pub optimal: OptimalPartitions,
}

impl Analysis {
    /// Slices `volume` along `axis` and runs every method to the end.
    pub fn compute(
        volume: &Volume,
        axis: [f64; 3],
        params: &StackParams,
        monitor: &Monitor,
    ) -> Result<Self> {
        let stack = SliceStack::new(volume, axis, params, monitor)?;
        let histograms = stack.slice_histograms();
        let top = SplitHistory::new(&histograms, stack.bins());
        let bottom = MergeHistory::new(&stack, monitor)?;
        let optimal =
            OptimalPartitions::new(&histograms, stack.bins(), OPTIMAL_SLABS.min(stack.slices()))?;
        Ok(Self {
            stack: Arc::new(stack),
            histograms,
            top,
            bottom,
            optimal,
        })
    }

    /// Number of slices.
    pub fn slices(&self) -> usize {
        self.stack.slices()
    }

    /// The last position of `method`'s history: splits, merges, or slab counts minus one.
    pub fn last(&self, method: Method) -> usize {
        match method {
            Method::TopDown => self.top.steps.len(),
            Method::BottomUp => self.bottom.steps.len(),
            Method::Optimal => self.optimal.by_count.len().saturating_sub(1),
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
            Method::BottomUp => self.slices() - k,
        }
    }

    /// The position reached when `method` stops at `threshold`.
    pub fn position_for_threshold(&self, method: Method, threshold: f64) -> usize {
        match method {
            Method::TopDown => self.top.steps_above(threshold),
            Method::BottomUp => self.bottom.steps_above(threshold),
            Method::Optimal => {
                let by = &self.optimal.by_count;
                by.windows(2)
                    .position(|w| w[1].information - w[0].information < threshold)
                    .unwrap_or(by.len() - 1)
            }
        }
    }

    /// The slabs at `position` of `method`'s history.
    pub fn slabs(&self, method: Method, position: usize) -> Vec<(usize, usize)> {
        match method {
            Method::TopDown => self.top.slabs_after(position),
            Method::BottomUp => self.bottom.slabs_after(position),
            Method::Optimal => self.optimal.by_count[position.min(self.last(method))]
                .slabs
                .clone(),
        }
    }

    /// What each slab holds.
    pub fn describe(&self, slabs: &[(usize, usize)]) -> Vec<SlabInfo> {
        describe(&self.stack, &self.histograms, slabs)
    }

    /// ΔI of each boundary of `slabs`.
    pub fn gains(&self, slabs: &[(usize, usize)]) -> Vec<f64> {
        boundary_gains(&self.histograms, self.stack.bins(), slabs)
    }

    /// NMI of each boundary, where the history knows it (bottom-up: the pairs before the next
    /// merge).
    pub fn known_nmi(&self, method: Method, position: usize) -> Option<Vec<f64>> {
        match method {
            Method::BottomUp => self.bottom.steps.get(position).map(|m| m.pairs.clone()),
            Method::TopDown | Method::Optimal => None,
        }
    }

    /// The NMI between each slice and the next.
    pub fn nmi_curve(&self) -> &[f64] {
        self.bottom.slice_nmi()
    }

    /// ΔI of cutting the whole stack at each slice.
    pub fn gain_curve(&self) -> &[f64] {
        self.top.gain_curve()
    }

    /// One sentence on the last step taken to reach `position`, for teaching.
    pub fn explain(&self, method: Method, position: usize) -> String {
        let range = crate::tui::panes::slices_text;
        match method {
            Method::TopDown if position == 0 => {
                format!(
                    "top-down starts with one slab of {} slices; n splits it",
                    self.slices()
                )
            }
            Method::TopDown => {
                let s = &self.top.steps[position - 1];
                let candidates: usize = self
                    .top
                    .slabs_after(position - 1)
                    .iter()
                    .map(|(a, b)| b - a - 1)
                    .sum();
                format!(
                    "split {} at {}: ΔI {:.4} bits, the largest of {candidates} cuts; I = {:.4} bits",
                    range(s.split),
                    s.at,
                    s.gain,
                    s.information
                )
            }
            Method::BottomUp if position == 0 => {
                format!(
                    "bottom-up starts with {} one-slice slabs; n merges the most similar pair",
                    self.slices()
                )
            }
            Method::BottomUp => {
                let m = &self.bottom.steps[position - 1];
                format!(
                    "merged {} and {}: NMI {:.4}, the highest of {} adjacent pairs",
                    range(m.merge.0),
                    range(m.merge.1),
                    m.nmi,
                    m.pairs.len()
                )
            }
            Method::Optimal => {
                let k = position + 1;
                let opt = &self.optimal.by_count[position.min(self.last(method))];
                let greedy = self.top.information(k);
                format!(
                    "the best {k} slabs keep I = {:.4} bits; greedy top-down {greedy:.4} ({:.4} less)",
                    opt.information,
                    opt.information - greedy
                )
            }
        }
    }
}
