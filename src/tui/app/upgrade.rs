//! The first answer on a large volume, then full resolution in place: the view search, the
//! histories and the picture are computed on a coarse pyramid level (at most
//! [`GLANCE_VOXELS`](slabscope::budget::GLANCE_VOXELS) voxels) and shown at once, labelled as a
//! preview; the full-resolution view search and histories follow in the background and replace
//! them, keeping the user's axis, method and slab count. Every new axis is previewed first too.

use std::sync::Arc;

use slabscope::partition::Slab;
use slabscope::{Histories, Progress, ViewSearch, Volume};

use super::App;
use crate::tui::event::{Effect, Task};
use crate::tui::partitioning::Finished;

/// A preview being upgraded to full resolution.
pub struct Upgrade {
    /// The preview's pyramid level (at least 1).
    pub level: usize,
    /// How many voxels of the volume a preview voxel spans along its longest axis.
    pub factor: usize,
    /// The preview's volume, once built.
    pub coarse: Option<Arc<Volume>>,
    /// The full-resolution view search: not started until a preview's histories show.
    pub views: Task<()>,
    /// Whether the axis is the view search's best rather than the user's: the full search's
    /// best then takes its place.
    pub auto_axis: bool,
    /// Whether the preview is a level the file holds, read before level 0 (and quantized with
    /// its own range).
    pub from_file: bool,
}

impl Upgrade {
    /// A preview on pyramid level `level` of a volume of `dims`.
    pub fn new(level: usize, dims: [usize; 3]) -> Self {
        let longest = dims.into_iter().max().unwrap_or(1);
        let mut n = longest;
        for _ in 0..level {
            n = n.div_ceil(2);
        }
        Self {
            level,
            factor: longest.div_ceil(n),
            coarse: None,
            views: Task::Idle,
            auto_axis: false,
            from_file: false,
        }
    }

    /// A preview on `coarse`, a pyramid level the file holds, read before level 0.
    pub fn of_file(coarse: Arc<Volume>) -> Self {
        let level = coarse.level();
        Self {
            level: level.index,
            factor: level.factor.into_iter().max().unwrap_or(1),
            coarse: Some(coarse),
            views: Task::Idle,
            auto_axis: false,
            from_file: true,
        }
    }
}

impl App {
    /// A pyramid level the file holds, read before level 0: the preview computes on it while
    /// level 0 loads.
    pub(super) fn on_preview(&mut self, volume: &Arc<Volume>, notes: &[String]) -> Vec<Effect> {
        if !self.volume.running() || self.upgrade.is_some() || volume.level().index == 0 {
            return vec![];
        }
        self.status.message = notes.first().cloned();
        let level = volume.level().index;
        self.upgrade = Some(Upgrade::of_file(Arc::clone(volume)));
        self.begin(volume, level)
    }

    /// Level 0 loaded under the file's preview: the preview is upgraded as any other. Beyond
    /// the memory budget the volume worked on is itself a pyramid level, of which the file's
    /// is no preview: everything starts afresh on it.
    pub(super) fn adopt(&mut self, volume: Arc<Volume>, notes: &[String]) -> Vec<Effect> {
        if volume.level().index > 0 {
            // The volume is here: the fresh app's own load is not needed.
            let _ = self.start_afresh(self.name.clone());
            let mut effects = vec![Effect::Cancel, Effect::Forget];
            effects.extend(self.on_loaded(volume, notes));
            return effects;
        }
        // The preview's notes were said; what full resolution will cost was not.
        if let Some(heavy) = self.params.heavy_work(volume.dims(), volume.spacing()) {
            self.status.message = Some(format!("{heavy}: it may take long; Esc cancels it"));
        }
        self.volume = Task::Ready(volume);
        let effects = self.start_upgrade();
        self.sync_status();
        effects
    }

    /// Whether pyramid level `level` can be worked on: level 0 is loaded, or it is the file's
    /// preview.
    pub(super) fn has_level(&self, level: usize) -> bool {
        self.volume.ready().is_some()
            || self
                .upgrade
                .as_ref()
                .is_some_and(|r| r.from_file && r.level == level)
    }

    /// The pyramid level new histories start on: the preview's, or 0.
    pub(super) fn first_level(&self) -> usize {
        self.upgrade.as_ref().map_or(0, |r| r.level)
    }

    /// The pyramid level of what is shown: the histories', or before any the preview's.
    pub(super) fn shown_level(&self) -> usize {
        match self.part.histories {
            Task::Idle => self.first_level(),
            _ => self.part.level,
        }
    }

    /// The volume (or its pyramid level) that what is shown was computed on, once there.
    pub(super) fn shown_volume(&self) -> Option<&Arc<Volume>> {
        match self.shown_level() {
            0 => self.volume.ready(),
            _ => self.upgrade.as_ref().and_then(|r| r.coarse.as_ref()),
        }
    }

    /// Starts the histories along an axis the user chose: it stays when full resolution finds
    /// another best.
    pub(super) fn analyze_chosen(&mut self, axis: [f64; 3]) -> Vec<Effect> {
        if let Some(r) = self.upgrade.as_mut() {
            r.auto_axis = false;
        }
        self.analyze(axis)
    }

    /// A view search finished on pyramid level `level`.
    pub(super) fn on_views(
        &mut self,
        level: usize,
        result: Result<Box<ViewSearch>, String>,
    ) -> Vec<Effect> {
        let full = level == 0 && self.upgrade.is_some();
        let mut effects = vec![];
        // Views that come after the gain ranking carry its scores too.
        let result = result.map(|mut views| {
            if let Task::Ready(g) = &self.views.gain
                && self.gain_fits(level)
            {
                g.annotate(&mut views);
            }
            views
        });
        match result {
            Ok(views) if full => {
                let best = views.best().axis;
                let previous = self.views.views.ready().map(|v| v.best().axis);
                self.views.row = self.views.row.min(views.views.len().saturating_sub(1));
                self.views.views = Task::Ready(*views);
                let upgrade = self.upgrade.as_mut().expect("full is an upgrade");
                upgrade.views = Task::Ready(());
                let moved = upgrade.auto_axis
                    && !self.gain_picks()
                    && self.part.axis.is_some_and(|a| !same(a, best));
                // A preview's gain ranking scored the preview's views: rank these too.
                if self.gain_behind() {
                    effects.extend(self.start_gain_at(0));
                }
                if moved {
                    self.aside(format!(
                        "{}: the best axis is {} (the preview's was {})",
                        self.final_words(),
                        axis_text(best),
                        previous.map_or_else(|| "another".into(), axis_text)
                    ));
                    effects.extend(self.analyze(best));
                } else {
                    effects.extend(self.upgrade_histories());
                }
            }
            Ok(views) => {
                let best = views.best().axis;
                self.views.views = Task::Ready(*views);
                self.views.row = 0;
                if self.part.axis.is_none() && !self.gain_picks() {
                    if let Some(r) = self.upgrade.as_mut() {
                        r.auto_axis = true;
                    }
                    effects = self.analyze(best);
                }
            }
            Err(e) if full => {
                if let Some(r) = self.upgrade.as_mut() {
                    r.views = Task::Failed(e.clone());
                }
                self.say_failed(&e);
            }
            Err(e) => self.views.views = Task::Failed(e),
        }
        self.sync();
        effects
    }

    /// Says `words` about work the user did not ask for, outside the tour: there the status line
    /// belongs to the page.
    fn aside(&mut self, words: String) {
        if self.tour.is_none() {
            self.status.message = Some(words);
        }
    }

    /// Histories finished: shown, or a preview's replaced by full resolution.
    pub(super) fn on_histories(
        &mut self,
        generation: u64,
        level: usize,
        result: Result<Arc<Histories>, String>,
    ) -> Vec<Effect> {
        let before = self.part.ready().cloned().zip(self.part.slabs());
        let shift = self.preview_shift();
        match self.part.finish(generation, level, result) {
            Finished::Stale => return vec![],
            Finished::Shown => {}
            Finished::Upgraded => match (&before, self.part.ready(), &self.part.upgrading) {
                (Some((preview, shown)), Some(full), Task::Idle) => {
                    let full = Arc::clone(full);
                    let now = self.part.slabs().unwrap_or_default();
                    let words = compare((preview, shown), (&full, &now), shift, self.final_words());
                    self.aside(words);
                    self.carry_over(preview, &full, shift);
                }
                (_, _, Task::Failed(e)) => {
                    let e = e.clone();
                    self.say_failed(&e);
                }
                _ => {}
            },
        }
        let mut effects = self.start_upgrade();
        self.sync();
        effects.extend(self.render());
        effects
    }

    /// Once a preview shows and level 0 is loaded, the full-resolution view search starts, and
    /// the histories follow it (at once along an axis the user chose).
    fn start_upgrade(&mut self) -> Vec<Effect> {
        let mut effects = vec![];
        if self.part.awaits_upgrade()
            && self.volume.ready().is_some()
            && let Some(r) = self.upgrade.as_mut()
            && matches!(r.views, Task::Idle)
        {
            r.views = Task::started("view search");
            effects.push(Effect::SearchViews(self.params.view.clone(), 0));
        }
        effects.extend(self.upgrade_histories());
        effects
    }

    /// Starts the full-resolution histories when a preview's show and their axis is settled:
    /// the user's, or the best once the full-resolution view search is done.
    fn upgrade_histories(&mut self) -> Vec<Effect> {
        let Some(r) = &self.upgrade else {
            return vec![];
        };
        let settled = !r.auto_axis || matches!(r.views, Task::Ready(()));
        if !(settled && self.part.awaits_upgrade() && self.volume.ready().is_some()) {
            return vec![];
        }
        self.part.upgrade().into_iter().collect()
    }

    /// The progress of the full-resolution view search.
    pub(super) fn upgrade_progress(&mut self, p: Progress) {
        if let Some(r) = self.upgrade.as_mut().filter(|r| r.views.running()) {
            r.views = Task::Running(p);
        }
    }

    /// Where the preview's voxel (0, 0, 0) lies in the volume, mm from voxel (0, 0, 0).
    fn preview_shift(&self) -> [f64; 3] {
        match (
            self.volume.ready(),
            self.upgrade.as_ref().and_then(|r| r.coarse.as_ref()),
        ) {
            (Some(full), Some(coarse)) => {
                let (s, f) = (full.spacing(), coarse.level().factor);
                std::array::from_fn(|m| (f[m] as f64 - 1.0) / 2.0 * s[m])
            }
            _ => [0.0; 3],
        }
    }

    /// Keeps the curves' cursor and the slice view's pointer where they were on the preview.
    fn carry_over(&mut self, preview: &Histories, full: &Histories, shift: [f64; 3]) {
        let (a, b) = (preview.slices().max(2) - 1, full.slices().max(2) - 1);
        self.curves.cursor = (self.curves.cursor * b + a / 2) / a;
        if let Some(p) = self.preview.pointer.as_mut() {
            *p = std::array::from_fn(|m| p[m] + shift[m]);
        }
    }

    /// Cancels the full-resolution jobs: the preview stays; true if any was running.
    pub(super) fn cancel_upgrade(&mut self) -> bool {
        let mut any = false;
        if let Some(r) = self.upgrade.as_mut().filter(|r| r.views.running()) {
            r.views = Task::Failed("cancelled".into());
            any = true;
        }
        if self.part.upgrading.running() {
            self.part.upgrading = Task::Failed("cancelled".into());
            any = true;
        }
        any
    }

    /// Says that a full-resolution job failed, unless it was cancelled: whoever cancelled it
    /// has said so, and a cancelled job's answer may come after.
    fn say_failed(&mut self, e: &str) {
        if e != slabscope::Error::Cancelled.to_string() {
            self.status.message = Some(format!("{}: {e}", self.final_words()));
        }
    }

    /// What the preview is upgraded to, in words: full resolution, or beyond the memory budget
    /// the pyramid level the volume was loaded at.
    pub(super) fn final_words(&self) -> &'static str {
        match self.volume.ready().map(|v| v.level().index) {
            Some(l) if l > 0 => "the finest level that fits",
            _ => "full resolution",
        }
    }

    /// The status line's word on the resolution shown, and the full-resolution jobs' gauges.
    pub(super) fn resolution_status(&self) -> (Option<String>, Vec<Progress>) {
        let Some(r) = &self.upgrade else {
            return (None, vec![]);
        };
        // Against the file's resolution: the volume worked on may itself be a pyramid level
        // (beyond the memory budget).
        let base = self
            .volume
            .ready()
            .and_then(|v| v.level().factor.into_iter().max())
            .unwrap_or(1);
        let label = (self.shown_level() > 0).then(|| {
            let stopped = matches!(self.volume, Task::Failed(_))
                || matches!(r.views, Task::Failed(_))
                || matches!(self.part.upgrading, Task::Failed(_));
            format!(
                "preview: 1/{} resolution{}{}",
                r.factor * base,
                // Quantized with its own range: level 0's is not known before it loads.
                if r.from_file {
                    format!(" (the file's level {}, its own value range)", r.level)
                } else {
                    String::new()
                },
                if stopped {
                    format!(", {} stopped", self.final_words())
                } else {
                    String::new()
                }
            )
        });
        let mut gauges = vec![];
        for load in [
            self.volume.status(),
            r.views.status(),
            self.part.upgrading.status(),
        ] {
            if let Task::Running(p) = load {
                gauges.push(p);
            }
        }
        (label, gauges)
    }
}

/// Whether two unit axes are the same line.
pub(super) fn same(a: [f64; 3], b: [f64; 3]) -> bool {
    slabscope::geometry::dot(a, b).abs() > 1.0 - 1e-9
}

/// An axis in few characters.
pub(super) fn axis_text(a: [f64; 3]) -> String {
    slabscope::Axis::new(a).map_or_else(|_| format!("{a:?}"), |a| a.to_string())
}

/// What full resolution changed, in words: the slab count, or how far the cuts moved (in mm, the
/// preview's moved into the volume's frame by `shift`) against a preview slice's thickness.
fn compare(
    preview: (&Histories, &[Slab]),
    full: (&Histories, &[Slab]),
    shift: [f64; 3],
    words: &str,
) -> String {
    let along = slabscope::geometry::dot(shift, preview.0.stack().axis());
    let cuts = |(h, slabs): (&Histories, &[Slab]), offset: f64| -> Vec<f64> {
        let s = h.stack();
        slabs
            .iter()
            .skip(1)
            .map(|&(a, _)| offset + s.offset() + (a as f64 - 0.5) * s.thickness())
            .collect()
    };
    let (before, after) = (cuts(preview, along), cuts(full, 0.0));
    if before.len() != after.len() {
        return format!(
            "{words}: {} slabs where the preview had {}",
            after.len() + 1,
            before.len() + 1
        );
    }
    let moved = before
        .iter()
        .zip(&after)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    if moved <= preview.0.stack().thickness() + 1e-9 {
        format!(
            "{words}: the preview's {} slabs, cuts within a preview slice ({moved:.1} mm)",
            after.len() + 1
        )
    } else {
        format!("{words} moved the cuts: up to {moved:.1} mm from the preview's")
    }
}
