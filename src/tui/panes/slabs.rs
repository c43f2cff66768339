//! The slabs pane: the current partition, each slab's slices, millimetres, entropy and mean, and
//! the NMI or ΔI at the boundary to the next.

use ratatui::buffer::Buffer;
use ratatui::layout::{Constraint, Rect};
use ratatui::style::{Color, Modifier};
use ratatui::widgets::{Row, Table, Widget};
use slabscope::partition::Method;

use super::placeholder;
use crate::tui::app::App;
use crate::tui::ui::Theme;

/// The slabs pane.
pub struct SlabsPane<'a> {
    /// The state.
    pub app: &'a App,
    /// Colours.
    pub theme: Theme,
    /// Whether it has the focus.
    pub focused: bool,
}

impl Widget for SlabsPane<'_> {
    fn render(self, area: Rect, buf: &mut Buffer) {
        let app = self.app;
        let Some(analysis) = app.analysis.ready() else {
            let block = self.theme.block(" Slabs ".into(), self.focused);
            let inner = block.inner(area);
            block.render(area, buf);
            placeholder(
                &app.analysis,
                "partition",
                "waiting for the best axis…",
                self.theme,
                inner,
                buf,
            );
            return;
        };
        let slabs = analysis.slabs(app.method, app.position);
        let info = analysis.describe(&slabs);
        let nmi = analysis.known_nmi(app.method, app.position);
        let gains = analysis.gains(&slabs);
        let title = format!(" Slabs: {} of {} slices ", slabs.len(), analysis.slices());
        let next_header = if app.method == Method::BottomUp {
            "NMI→"
        } else {
            "ΔI→"
        };
        // The mean where there is room, and the millimetre range where there is more.
        let (medium, wide) = (area.width >= 41, area.width >= 56);
        let mut header = vec!["#", "slices", "mm"];
        if wide {
            header.push("from–to mm");
        }
        header.push("H");
        if medium {
            header.push("mean");
        }
        header.push(next_header);
        let header =
            Row::new(header).style(self.theme.fg(Color::DarkGray).add_modifier(Modifier::BOLD));
        let visible = usize::from(area.height.saturating_sub(3));
        let first = app.slab_row.saturating_sub(visible.saturating_sub(1));
        let rows: Vec<Row> = info
            .iter()
            .enumerate()
            .skip(first)
            .take(visible)
            .map(|(i, s)| {
                let next = match (&nmi, gains.get(i)) {
                    (Some(n), _) if i + 1 < slabs.len() => {
                        format!("{:.4}", n.get(i).copied().unwrap_or(f64::NAN))
                    }
                    (None, Some(g)) => format!("{g:.4}"),
                    _ => String::new(),
                };
                let mean = s.mean.map_or_else(|| "-".into(), |m| format!("{m:.1}"));
                let mark = if s.near_empty { " ∅" } else { "" };
                let thickness = format!("{:.1}", s.mm.1 - s.mm.0);
                let mut cells = vec![
                    format!("{i}{mark}"),
                    super::slices_text(s.slices),
                    thickness,
                ];
                if wide {
                    cells.push(format!("{:.1}–{:.1}", s.mm.0, s.mm.1));
                }
                cells.push(format!("{:.2}", s.entropy));
                if medium {
                    cells.push(mean);
                }
                cells.push(next);
                let row = Row::new(cells);
                match (i == app.slab_row, self.focused) {
                    (true, true) => row.style(self.theme.selected()),
                    (true, false) => row.style(self.theme.fg(Color::Yellow)),
                    _ if s.near_empty => row.style(self.theme.fg(Color::DarkGray)),
                    _ => row,
                }
            })
            .collect();
        let mut widths = vec![
            Constraint::Length(3),
            Constraint::Length(8),
            Constraint::Length(5),
        ];
        if wide {
            widths.push(Constraint::Length(13));
        }
        widths.push(Constraint::Length(4));
        if medium {
            widths.push(Constraint::Length(7));
        }
        widths.push(Constraint::Min(6));
        Table::new(rows, widths)
            .header(header)
            .block(self.theme.block(title, self.focused))
            .render(area, buf);
    }
}
