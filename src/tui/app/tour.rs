//! The tour's pages set the panes: once the views and the histories are in, each page focuses a
//! pane, selects the best or the worst viewpoint, shows a method at a slab count and opens or
//! closes the lesson; the user may then do anything, and the next page sets them again.

use super::App;
use crate::tui::event::{Effect, Load};
use crate::tui::tour::{self, Row};

impl App {
    /// Turns the tour's page.
    pub(super) fn turn_page(&mut self, by: isize) -> Vec<Effect> {
        if let Some(t) = self.tour.as_mut() {
            t.turn(by);
        }
        vec![]
    }

    /// Sets the panes for the tour's page when it has not been and its data is in.
    pub(super) fn sync_tour(&mut self) -> Vec<Effect> {
        let Some(t) = self.tour.clone().filter(|t| !t.applied) else {
            return vec![];
        };
        let (Some(views), Some(h)) = (self.views.views.ready(), self.part.ready().cloned()) else {
            return vec![];
        };
        let h = h.as_ref();
        let s = t.current().setup;
        let numbers = tour::page_numbers(t.page, h, s.slabs);
        let worst = views
            .views
            .iter()
            .rposition(slabscope::view::AxisEntropy::measured)
            .unwrap_or(0);
        // The optimum is not computed for a very long stack: the page shows top-down then.
        let (method, position) = match tour::position(h, s.method, s.slabs) {
            Some(p) => (s.method, p),
            None => (
                slabscope::partition::Method::TopDown,
                h.position_for(slabscope::partition::Method::TopDown, s.slabs),
            ),
        };
        self.views.row = match s.row {
            Row::Best => 0,
            Row::Worst => worst,
        };
        self.focus = s.focus;
        (self.part.method, self.part.position) = (method, position);
        self.part.set_threshold(None);
        if self.lesson.open != s.lesson {
            self.lesson.open = s.lesson;
            (self.lesson.subject, self.lesson.lesson) = (None, Load::Idle);
        }
        self.ray = (0, 0);
        if let Some(t) = self.tour.as_mut() {
            (t.applied, t.numbers) = (true, numbers);
        }
        self.sync_focus();
        self.after_step()
    }
}
