//! The axes ranked by partition gain (`i`, or `--gain` and `--axis-by gain` at the start), in
//! the background: once ranked, the viewpoints list shows both scores and `i` switches its order
//! and the sphere's colours between them; with `--axis-by gain` the partition follows the gain's
//! best.

use slabscope::analysis::{AxisBy, GainRanking};
use slabscope::geometry::AxisChoice;

use super::App;
use super::upgrade::{axis_text, same};
use crate::tui::event::{Effect, Task};

impl App {
    /// `i`: ranks the axes by gain, or once ranked switches the order the list and the sphere
    /// follow.
    pub(super) fn rank_gain(&mut self) -> Vec<Effect> {
        match &self.views.gain {
            Task::Ready(_) => {
                self.views.by_gain = !self.views.by_gain;
                self.views.row = 0;
                self.status.message = Some(
                    if self.views.by_gain {
                        "axes by partition gain, highest first (i: by entropy rate)"
                    } else {
                        "axes by entropy rate, lowest first (i: by partition gain)"
                    }
                    .into(),
                );
                vec![]
            }
            Task::Running(_) => vec![],
            Task::Idle | Task::Failed(_) => self.start_gain(),
        }
    }

    /// Starts the gain ranking on the volume, once it is loaded: on the level shown (a
    /// preview's first, whose views it scores; full resolution follows with the full views).
    pub(super) fn start_gain(&mut self) -> Vec<Effect> {
        self.start_gain_at(self.views_level())
    }

    /// The pyramid level of the views shown: a preview's until full resolution's are in.
    fn views_level(&self) -> usize {
        match &self.upgrade {
            Some(r) if !matches!(r.views, Task::Ready(())) => r.level,
            _ => 0,
        }
    }

    /// Starts the gain ranking on pyramid level `level`.
    pub(super) fn start_gain_at(&mut self, level: usize) -> Vec<Effect> {
        if !self.has_level(level) {
            return vec![];
        }
        self.gain_level = level;
        self.views.gain = Task::started("ranking axes by partition gain");
        self.sync_status();
        vec![Effect::RankGain(Box::new(self.params.clone()), level)]
    }

    /// Whether the gain ranking shown (or under way) is a preview's while full resolution's
    /// views are in: it is then ranked again at full resolution.
    pub(super) fn gain_behind(&self) -> bool {
        self.gain_level > self.views_level()
            && !matches!(self.views.gain, Task::Idle | Task::Failed(_))
    }

    /// Whether a ranking of pyramid level `level` scores the views shown.
    pub(super) fn gain_fits(&self, level: usize) -> bool {
        level == self.gain_level
    }

    /// Whether the gain ranking picks the axis: `--axis-by gain` with no axis named.
    pub(super) fn gain_picks(&self) -> bool {
        self.params.axis_by == AxisBy::Gain && self.params.axis == AxisChoice::Best
    }

    /// Which ranking picked the axis partitioned: none when the user chose another.
    pub(super) fn picked_by(&self, gain: &GainRanking) -> Option<AxisBy> {
        let axis = self.part.axis?;
        let entropy = self.views.views.ready().map(|v| v.best().axis);
        if self.gain_picks() && same(axis, gain.refined.axis) {
            Some(AxisBy::Gain)
        } else if entropy.is_some_and(|e| same(axis, e)) {
            Some(AxisBy::Entropy)
        } else {
            None
        }
    }

    /// The gain ranking finished: both scores in the list, ordered by the gain, the verdict on
    /// the status line, and with `--axis-by gain` the partition along its best.
    pub(super) fn on_gain(
        &mut self,
        level: usize,
        result: Result<Box<GainRanking>, String>,
    ) -> Vec<Effect> {
        if !self.gain_fits(level) {
            return vec![];
        }
        let gain = match result {
            Ok(g) => *g,
            Err(e) => {
                self.status.message = Some(format!("gain ranking failed: {e}"));
                self.views.gain = Task::Failed(e);
                self.sync_status();
                return vec![];
            }
        };
        if let Task::Ready(views) = &mut self.views.views {
            gain.annotate(views);
        }
        let best = gain.refined.axis;
        self.status.message = Some(self.gain_verdict(&gain));
        self.views.gain = Task::Ready(gain);
        self.views.by_gain = true;
        self.views.row = 0;
        let mut effects = if self.gain_picks() && !self.part.axis.is_some_and(|a| same(a, best)) {
            self.analyze_chosen(best)
        } else {
            vec![]
        };
        if self.gain_behind() {
            effects.extend(self.start_gain_at(0));
        }
        self.sync_status();
        effects
    }

    /// The gain's best, its margin of certainty, and whether the entropy rate agrees.
    fn gain_verdict(&self, gain: &GainRanking) -> String {
        let best = &gain.refined;
        let sure = if gain.uncertain() {
            format!("uncertain ({} ≈)", gain.contenders.len() - 1)
        } else {
            "clear".into()
        };
        let keeps = format!(
            "{:.4} bits in {} slabs, {sure}",
            best.gain_phases.mean, gain.sampling.slabs
        );
        match self.views.views.ready().map(|v| v.best().axis) {
            Some(h) if gain.disagrees_with(h).is_some() => format!(
                "entropy rate prefers {}; slabs keep most along {} ({keeps})",
                axis_text(h),
                axis_text(best.axis)
            ),
            Some(_) => format!(
                "by gain {} ({keeps}): the entropy rate agrees",
                axis_text(best.axis)
            ),
            None => format!("by gain {} ({keeps})", axis_text(best.axis)),
        }
    }
}
