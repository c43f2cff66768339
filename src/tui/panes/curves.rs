//! The curves pane: along the axis, the NMI between consecutive slices and the ΔI of cutting the
//! whole stack at each slice, with the current slab boundaries and the slice cursor.

use std::sync::Arc;

use ratatui::buffer::Buffer;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::Color;
use ratatui::symbols::Marker;
use ratatui::widgets::{Axis, Chart, Dataset, GraphType, Widget};
use slabscope::Histories;

use super::placeholder;
use crate::tui::event::Task;
use crate::tui::theme::Theme;

/// The curves along the axis and where the slabs meet.
pub struct Curves {
    /// The histories, which hold the curves.
    pub histories: Arc<Histories>,
    /// The first slice of every slab but the first.
    pub boundaries: Vec<usize>,
}

/// The curves pane's state.
pub struct CurvesPane {
    /// The curves, or the gauge of the histories behind them.
    pub curves: Task<Curves>,
    /// The slice under the cursor.
    pub cursor: usize,
    /// Whether it has the focus.
    pub focused: bool,
    /// Colours.
    pub theme: Theme,
}

impl CurvesPane {
    /// An empty pane.
    pub fn new(theme: Theme) -> Self {
        Self {
            curves: Task::Idle,
            cursor: 0,
            focused: false,
            theme,
        }
    }

    /// Number of slices the cursor moves over.
    pub fn len(&self) -> usize {
        self.curves.ready().map_or(0, |c| c.histories.slices())
    }
}

/// A curve to plot: its values at cuts 1 .. n, its name and colour.
struct Curve<'a> {
    values: &'a [f64],
    name: &'static str,
    short: &'static str,
    color: Color,
}

/// The x axis's labels: the slices at its ends and middle (the lower chart's, which the upper
/// shares; the pane's title says they are slices), or none.
fn slice_labels(n: usize, shown: bool) -> Vec<String> {
    if shown {
        vec!["0".into(), (n / 2).to_string(), n.to_string()]
    } else {
        vec![]
    }
}

/// One chart: a curve over the cuts, vertical lines at the boundaries and the cursor; the
/// slices written under it when `x_labels`. Drawn on the theme's own background.
fn chart(
    curve: &Curve,
    boundaries: &[usize],
    (cursor, x_labels): (usize, bool),
    theme: Theme,
    area: Rect,
    buf: &mut Buffer,
) {
    let n = curve.values.len() + 1;
    let top = curve
        .values
        .iter()
        .copied()
        .fold(0.0f64, f64::max)
        .max(1e-9);
    let points: Vec<(f64, f64)> = curve
        .values
        .iter()
        .enumerate()
        .map(|(i, &v)| ((i + 1) as f64, v))
        .collect();
    let lines: Vec<Vec<(f64, f64)>> = boundaries
        .iter()
        .map(|&c| vec![(c as f64, 0.0), (c as f64, top)])
        .collect();
    let cursor_line = vec![(cursor as f64, 0.0), (cursor as f64, top)];
    let line = |data| {
        Dataset::default()
            .graph_type(GraphType::Line)
            .marker(Marker::Braille)
            .data(data)
    };
    let mut sets: Vec<Dataset> = lines
        .iter()
        .map(|l| line(l).style(theme.fg(Color::DarkGray)))
        .collect();
    sets.push(line(&cursor_line).style(theme.fg(Color::Yellow)));
    sets.push(line(&points).name(curve.name).style(theme.fg(curve.color)));
    Chart::new(sets)
        .style(theme.base())
        .x_axis(
            Axis::default()
                .bounds([0.0, n as f64])
                .labels(slice_labels(n, x_labels))
                .style(theme.fg(Color::DarkGray)),
        )
        .y_axis(
            Axis::default()
                .bounds([0.0, top])
                // The curve's name between its ends: the chart's legend on its axis.
                .labels([
                    format!("{:.2}", 0.0),
                    curve.short.into(),
                    format!("{top:.3}"),
                ])
                .style(theme.fg(Color::DarkGray)),
        )
        .render(area, buf);
}

impl Widget for &CurvesPane {
    fn render(self, area: Rect, buf: &mut Buffer) {
        let Task::Ready(curves) = &self.curves else {
            let block = self.theme.block(" Curves ".into(), self.focused);
            let inner = block.inner(area);
            block.render(area, buf);
            placeholder(
                &self.curves.status(),
                "histories",
                "",
                self.theme,
                inner,
                buf,
            );
            return;
        };
        let h = &curves.histories;
        let (nmi, gain) = (h.nmi_curve(), h.gain_curve());
        let c = self.cursor.min(h.slices() - 1);
        let at = |v: &[f64]| {
            c.checked_sub(1)
                .and_then(|i| v.get(i))
                .map_or_else(|| "-".into(), |x| format!("{x:.4}"))
        };
        let title = format!(" Curves at slice {c}: NMI {} ΔI {} ", at(nmi), at(gain));
        let block = self.theme.block(title, self.focused);
        let inner = block.inner(area);
        block.render(area, buf);
        let [top, bottom] =
            Layout::vertical([Constraint::Percentage(50), Constraint::Percentage(50)]).areas(inner);
        let nmi = Curve {
            values: nmi,
            name: "NMI slice to slice",
            short: "NMI",
            color: Color::Cyan,
        };
        let gain = Curve {
            values: gain,
            name: "ΔI of a first cut",
            short: "ΔI",
            color: Color::Magenta,
        };
        chart(&nmi, &curves.boundaries, (c, false), self.theme, top, buf);
        chart(
            &gain,
            &curves.boundaries,
            (c, true),
            self.theme,
            bottom,
            buf,
        );
    }
}
