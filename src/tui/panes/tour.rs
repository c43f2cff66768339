//! The tour's page: its title, its paragraph and the keys that turn it, below the panes it sets.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::widgets::{Paragraph, Widget, Wrap};

use crate::tui::app::tour::Tour;
use crate::tui::keymap;
use crate::tui::theme::Theme;

/// The page shown.
pub struct TourPage<'a> {
    /// Where the tour is.
    pub tour: &'a Tour,
    /// Colours.
    pub theme: Theme,
}

impl Widget for TourPage<'_> {
    fn render(self, area: Rect, buf: &mut Buffer) {
        let page = self.tour.current();
        let title = format!(
            " Tour ({}), {}: {}  ({}) ",
            self.tour.mode(),
            self.tour.counter(),
            page.title,
            keymap::tour_hints()
        );
        let text = match &self.tour.numbers {
            Some(n) => format!("{} {n}", page.text),
            None => page.text.to_string(),
        };
        Paragraph::new(text)
            .wrap(Wrap { trim: true })
            .style(self.theme.base())
            .block(self.theme.block(title, true))
            .render(area, buf);
    }
}
