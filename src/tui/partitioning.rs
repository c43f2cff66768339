//! Where the user stands in the histories along the current axis: the method, the position in its
//! history, the threshold that chose it, and the words that explain the last step.

use std::sync::Arc;

use slabscope::partition::{Method, Slab, StackParams, Stop, slab_text};
use slabscope::{Histories, Progress};

use super::event::{Effect, Task};

/// The partition being stepped through.
pub struct Partitioning {
    /// The histories along the axis.
    pub histories: Task<Arc<Histories>>,
    /// The axis being partitioned.
    pub axis: Option<[f64; 3]>,
    /// Partition method.
    pub method: Method,
    /// Position in the method's history.
    pub position: usize,
    /// Stop by threshold instead of by position.
    pub threshold: Option<f64>,
    /// How the slices are cut.
    pub stack: StackParams,
    /// The pyramid level of `histories` (0: full resolution).
    pub level: usize,
    /// The same histories at full resolution, computed in the background to replace a
    /// preview's.
    pub upgrading: Task<()>,
    /// The slab count asked for, for histories still to come.
    slabs: usize,
    generation: u64,
}

/// What a job's histories did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Finished {
    /// Nothing: they were for an older request.
    Stale,
    /// They are shown (or their error is).
    Shown,
    /// Full-resolution histories replaced a preview's.
    Upgraded,
}

impl Partitioning {
    /// Nothing computed yet; `stop` chooses the first position once the histories are there.
    pub fn new(method: Method, stop: Stop, stack: StackParams) -> Self {
        let (slabs, threshold) = match stop {
            Stop::Slabs(k) => (k, None),
            Stop::Threshold(t) => (4, Some(t)),
        };
        Self {
            histories: Task::Idle,
            axis: None,
            method,
            position: slabs.saturating_sub(1),
            threshold,
            stack,
            level: 0,
            upgrading: Task::Idle,
            slabs,
            generation: 0,
        }
    }

    /// The number of the newest histories requested.
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// The histories, when ready.
    pub fn ready(&self) -> Option<&Arc<Histories>> {
        self.histories.ready()
    }

    /// The slabs shown now, when the histories are ready.
    pub fn slabs(&self) -> Option<Vec<Slab>> {
        self.ready().map(|h| h.slabs(self.method, self.position))
    }

    /// The slab count shown now.
    pub fn slab_count(&self) -> Option<usize> {
        self.ready()
            .map(|h| h.slab_count(self.method, self.position))
    }

    /// Starts the histories along `axis` on pyramid level `level`.
    pub fn start(&mut self, axis: [f64; 3], level: usize) -> Effect {
        self.keep_slab_count();
        self.axis = Some(axis);
        self.generation += 1;
        self.histories = Task::started("slicing");
        (self.level, self.upgrading) = (level, Task::Idle);
        Effect::Analyze(self.generation, axis, self.stack.clone(), level)
    }

    /// Starts the histories shown, a preview's, again at full resolution; they stay shown until
    /// the new ones replace them.
    pub fn upgrade(&mut self) -> Option<Effect> {
        let axis = self
            .axis
            .filter(|_| self.level > 0 && self.ready().is_some())?;
        self.generation += 1;
        self.upgrading = Task::started("slicing");
        Some(Effect::Analyze(
            self.generation,
            axis,
            self.stack.clone(),
            0,
        ))
    }

    /// Whether a preview's histories are shown and no upgrade has started or failed.
    pub fn awaits_upgrade(&self) -> bool {
        self.level > 0 && self.ready().is_some() && matches!(self.upgrading, Task::Idle)
    }

    /// Remembers the slab count shown, for the histories that come next.
    fn keep_slab_count(&mut self) {
        if let Some(k) = self.slab_count() {
            self.slabs = k;
        }
    }

    /// Takes the histories of request `generation` on pyramid level `level`.
    pub fn finish(
        &mut self,
        generation: u64,
        level: usize,
        result: Result<Arc<Histories>, String>,
    ) -> Finished {
        if generation != self.generation {
            return Finished::Stale;
        }
        let upgraded = self.upgrading.running() && level == 0;
        match result {
            Ok(h) => {
                self.keep_slab_count();
                self.position = match self.threshold {
                    Some(t) => h.position_for_threshold(self.method, t),
                    None => h.position_for(self.method, self.slabs),
                };
                (self.histories, self.level, self.upgrading) = (Task::Ready(h), level, Task::Idle);
            }
            Err(e) if upgraded => self.upgrading = Task::Failed(e),
            Err(e) => self.histories = Task::Failed(e),
        }
        if upgraded {
            Finished::Upgraded
        } else {
            Finished::Shown
        }
    }

    /// Records the progress of the computation running on pyramid level `level`.
    pub fn progress(&mut self, p: Progress, level: usize) {
        if self.upgrading.running() && level == 0 {
            self.upgrading = Task::Running(p);
        } else if self.histories.running() && level == self.level {
            self.histories = Task::Running(p);
        }
    }

    /// Moves `by` steps; the message to show when already at an end.
    pub fn step(&mut self, by: isize) -> Result<(), &'static str> {
        let Some(h) = self.ready() else { return Ok(()) };
        let position =
            (self.position as isize + by).clamp(0, h.last(self.method) as isize) as usize;
        if position == self.position {
            return Err(if by > 0 {
                "at the end of the history"
            } else {
                "at the start of the history"
            });
        }
        self.threshold = None;
        self.position = position;
        Ok(())
    }

    /// Goes to the start or the end of the history.
    pub fn step_to(&mut self, end: bool) {
        if let Some(h) = self.ready() {
            self.position = if end { h.last(self.method) } else { 0 };
            self.threshold = None;
        }
    }

    /// One slab more or fewer (`by`).
    pub fn change_slabs(&mut self, by: isize) {
        if let Some(h) = self.ready() {
            let k = h.slab_count(self.method, self.position) as isize + by;
            self.position = h.position_for(self.method, k.max(1) as usize);
            self.threshold = None;
        }
    }

    /// Switches to the next method, keeping the slab count (or the threshold).
    pub fn cycle_method(&mut self) {
        let k = self.slab_count();
        self.method = match self.method {
            Method::TopDown => Method::BottomUp,
            Method::BottomUp => Method::Optimal,
            Method::Optimal => Method::TopDown,
        };
        if let Some(h) = self.ready() {
            self.position = match self.threshold {
                Some(t) => h.position_for_threshold(self.method, t),
                None => h.position_for(self.method, k.unwrap_or(self.slabs)),
            };
        }
    }

    /// Stops at `threshold`, or clears it.
    pub fn set_threshold(&mut self, threshold: Option<f64>) {
        self.threshold = threshold;
        if let (Some(t), Some(h)) = (threshold, self.ready()) {
            self.position = h.position_for_threshold(self.method, t);
        }
    }

    /// `step 3/39  4 slabs  threshold 0.01`.
    pub fn position_text(&self) -> Option<String> {
        let h = self.ready()?;
        let threshold = self
            .threshold
            .map_or_else(String::new, |t| format!("  threshold {t}"));
        Some(format!(
            "step {}/{}  {} slabs{threshold}",
            self.position,
            h.last(self.method),
            h.slab_count(self.method, self.position),
        ))
    }

    /// One sentence on the last step taken to reach the position, for teaching.
    pub fn explain(&self) -> Option<String> {
        let h = self.ready()?;
        let (method, position) = (self.method, self.position);
        Some(match (method, position) {
            _ if !h.has(method) => format!("{} is not available here", method.name()),
            (Method::TopDown, 0) => format!(
                "top-down starts with one slab of {} slices; n splits it",
                h.slices()
            ),
            (Method::TopDown, p) => {
                let s = &h.top().steps[p - 1];
                let candidates: usize = h.slabs(method, p - 1).iter().map(|(a, b)| b - a - 1).sum();
                format!(
                    "split {} at {}: ΔI {:.4} bits, the largest of {candidates} cuts; I = {:.4} bits",
                    slab_text(s.split),
                    s.at,
                    s.gain,
                    s.information
                )
            }
            (Method::BottomUp, 0) => format!(
                "bottom-up starts with {} one-slice slabs; n merges the most similar pair",
                h.slices()
            ),
            (Method::BottomUp, p) => {
                let bottom = h.bottom()?;
                let m = &bottom.steps[p - 1];
                format!(
                    "merged {} and {}: NMI {:.4}, the highest of {} adjacent pairs",
                    slab_text(m.merge.0),
                    slab_text(m.merge.1),
                    m.nmi,
                    h.slab_count(method, p - 1) - 1
                )
            }
            (Method::Optimal, p) => {
                let k = p + 1;
                let best = h.optimal()?.by_count[p].information;
                let greedy = h.top().information(k);
                format!(
                    "the best {k} slabs keep I = {best:.4} bits; greedy top-down {greedy:.4} ({:.4} less)",
                    best - greedy
                )
            }
        })
    }
}
