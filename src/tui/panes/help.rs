//! The help overlay: every key, and the words the screens use, side by side where the terminal
//! is wide, one above the other where it is tall.

use ratatui::buffer::Buffer;
use ratatui::layout::{Constraint, Rect};
use ratatui::style::{Color, Modifier};
use ratatui::widgets::{Clear, Row, Table, Widget};

use crate::tui::keymap::{BINDINGS, GLOSSARY, help};
use crate::tui::theme::Theme;

/// The help overlay, centred over the screen.
pub struct Help {
    /// Colours.
    pub theme: Theme,
}

/// Width of one table.
const WIDTH: u16 = 64;

impl Help {
    fn table(&self, title: &str, rows: &[(&str, &str)], area: Rect, buf: &mut Buffer) {
        Clear.render(area, buf);
        buf.set_style(area, self.theme.base());
        let rows = rows
            .iter()
            .map(|(k, v)| Row::new([k.to_string(), v.to_string()]));
        Table::new(rows, [Constraint::Length(13), Constraint::Min(0)])
            .block(self.theme.block(title.into(), true))
            .style(self.theme.fg(Color::Reset).add_modifier(Modifier::empty()))
            .render(area, buf);
    }
}

impl Widget for &Help {
    fn render(self, area: Rect, buf: &mut Buffer) {
        let (keys, words) = (BINDINGS.len() as u16 + 2, GLOSSARY.len() as u16 + 2);
        let help = help();
        let width = WIDTH.min(area.width);
        let centred = |w: u16, h: u16| Rect {
            x: area.x + (area.width - w) / 2,
            y: area.y + (area.height - h.min(area.height)) / 2,
            width: w,
            height: h.min(area.height),
        };
        let key_title = " Keys (Esc or ? closes) ";
        let word_title = " Words (slice ranges are inclusive) ";
        if area.width > 2 * WIDTH {
            let both = centred(2 * WIDTH + 1, keys.max(words));
            self.table(
                key_title,
                &help,
                Rect {
                    width: WIDTH,
                    ..both
                },
                buf,
            );
            let right = Rect {
                x: both.x + WIDTH + 1,
                width: WIDTH,
                height: words.min(both.height),
                ..both
            };
            self.table(word_title, GLOSSARY, right, buf);
        } else if area.height >= keys + words {
            let both = centred(width, keys + words);
            self.table(
                key_title,
                &help,
                Rect {
                    height: keys,
                    ..both
                },
                buf,
            );
            let below = Rect {
                y: both.y + keys,
                height: words,
                ..both
            };
            self.table(word_title, GLOSSARY, below, buf);
        } else {
            self.table(key_title, &help, centred(width, keys), buf);
        }
    }
}
