//! The file list of a folder opened in the TUI: one line a volume, filled with its triage row
//! as the background triage completes it, the open volume marked; an overlay like the help.

use std::path::PathBuf;

use ratatui::buffer::Buffer;
use ratatui::layout::{Constraint, Rect};
use ratatui::style::{Color, Modifier};
use ratatui::widgets::{Clear, Row, StatefulWidget, Table, TableState, Widget};
use slabscope::triage::{Entry, TriageRow};

use crate::tui::theme::Theme;

/// The volumes of a folder and what triage found of each.
pub struct FilesPane {
    /// The folder, for names relative to it.
    pub root: PathBuf,
    /// The volumes, sorted.
    pub paths: Vec<Entry>,
    /// Each volume's row, once triage has it.
    pub rows: Vec<Option<TriageRow>>,
    /// The cursor.
    pub row: usize,
    /// The volume open in the other panes.
    pub open: usize,
    /// Whether the list shows.
    pub shown: bool,
    /// Colours.
    pub theme: Theme,
}

impl FilesPane {
    /// The list of `paths` under `root`, the first open and the list showing.
    pub fn new(root: PathBuf, paths: Vec<Entry>, theme: Theme) -> Self {
        let rows = vec![None; paths.len()];
        Self {
            root,
            paths,
            rows,
            row: 0,
            open: 0,
            shown: true,
            theme,
        }
    }

    /// The name of volume `i`, relative to the folder.
    pub fn name(&self, i: usize) -> String {
        self.paths[i].name_under(&self.root)
    }

    /// How many rows triage has filled.
    fn done(&self) -> usize {
        self.rows.iter().filter(|r| r.is_some()).count()
    }

    fn line(&self, i: usize) -> Row<'static> {
        let mark = if i == self.open { "●" } else { " " };
        let name = self.name(i);
        let cells = match &self.rows[i] {
            None => vec![mark.into(), "…".into(), String::new(), String::new(), name],
            Some(r) => {
                let dims = r
                    .dims
                    .map(|d| format!("{}x{}x{}", d[0], d[1], d[2]))
                    .unwrap_or_default();
                let axis = match &r.error {
                    Some(e) => format!("error: {}", slabscope::error::names::controls(e)),
                    None => r.axis_name().unwrap_or_default(),
                };
                let status = if r.error.is_some() { "!!" } else { "ok" };
                vec![
                    mark.into(),
                    status.into(),
                    r.format.clone().unwrap_or_default(),
                    dims,
                    format!("{name}  {axis}"),
                ]
            }
        };
        let style = match &self.rows[i] {
            Some(r) if r.error.is_some() => self.theme.fg(Color::Red),
            _ => self.theme.fg(Color::Reset),
        };
        Row::new(cells).style(style)
    }
}

impl Widget for &FilesPane {
    fn render(self, area: Rect, buf: &mut Buffer) {
        let w = area.width.saturating_sub(4).min(110);
        let h = (self.paths.len() as u16 + 3).min(area.height.saturating_sub(2));
        let list = Rect {
            x: area.x + (area.width - w) / 2,
            y: area.y + (area.height - h) / 2,
            width: w,
            height: h,
        };
        Clear.render(list, buf);
        buf.set_style(list, self.theme.base());
        let title = format!(
            " {} volumes in {} ({} looked at) · Enter opens, PgUp PgDn step, Esc or F closes ",
            self.paths.len(),
            slabscope::error::shown(&self.root),
            self.done()
        );
        let rows = (0..self.paths.len()).map(|i| self.line(i));
        let table = Table::new(
            rows,
            [
                Constraint::Length(1),
                Constraint::Length(2),
                Constraint::Length(11),
                Constraint::Length(13),
                Constraint::Min(10),
            ],
        )
        .block(self.theme.block(title, true))
        .row_highlight_style(
            self.theme
                .fg(Color::Yellow)
                .add_modifier(Modifier::REVERSED),
        );
        let mut state = TableState::default().with_selected(Some(self.row));
        StatefulWidget::render(table, list, buf, &mut state);
    }
}
