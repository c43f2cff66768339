//! The curves pane: along the axis, the NMI between consecutive slices and the ΔI of cutting the
//! whole stack at each slice, with the current slab boundaries and the slice cursor.

use ratatui::buffer::Buffer;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::Color;
use ratatui::symbols::Marker;
use ratatui::widgets::{Axis, Chart, Dataset, GraphType, Widget};

use super::placeholder;
use crate::tui::app::App;
use crate::tui::ui::Theme;

/// The curves pane.
pub struct CurvesPane<'a> {
    /// The state.
    pub app: &'a App,
    /// Colours.
    pub theme: Theme,
    /// Whether it has the focus.
    pub focused: bool,
}

/// A curve to plot: its values at cuts 1 .. n, its name and colour.
struct Curve<'a> {
    values: &'a [f64],
    name: &'static str,
    color: Color,
}

/// One chart: a curve over the cuts, vertical lines at the boundaries and the cursor.
fn chart(
    curve: &Curve,
    boundaries: &[usize],
    cursor: usize,
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
        .x_axis(
            Axis::default()
                .bounds([0.0, n as f64])
                .style(theme.fg(Color::DarkGray)),
        )
        .y_axis(
            Axis::default()
                .bounds([0.0, top])
                .labels([format!("{:.2}", 0.0), format!("{top:.3}")])
                .style(theme.fg(Color::DarkGray)),
        )
        .render(area, buf);
}

impl Widget for CurvesPane<'_> {
    fn render(self, area: Rect, buf: &mut Buffer) {
        let app = self.app;
        let Some(analysis) = app.analysis.ready() else {
            let block = self.theme.block(" Curves ".into(), self.focused);
            let inner = block.inner(area);
            block.render(area, buf);
            placeholder(&app.analysis, "histories", "", self.theme, inner, buf);
            return;
        };
        let (nmi, gain) = (analysis.nmi_curve(), analysis.gain_curve());
        let c = app.cursor.min(analysis.slices() - 1);
        let at = |v: &[f64]| {
            c.checked_sub(1)
                .and_then(|i| v.get(i))
                .map_or_else(|| "-".into(), |x| format!("{x:.4}"))
        };
        let title = format!(" Curves at slice {c}: NMI {} ΔI {} ", at(nmi), at(gain));
        let block = self.theme.block(title, self.focused);
        let inner = block.inner(area);
        block.render(area, buf);
        let boundaries: Vec<usize> = analysis
            .slabs(app.method, app.position)
            .iter()
            .skip(1)
            .map(|s| s.0)
            .collect();
        let [top, bottom] =
            Layout::vertical([Constraint::Percentage(50), Constraint::Percentage(50)]).areas(inner);
        let nmi = Curve {
            values: nmi,
            name: "NMI slice to slice",
            color: Color::Cyan,
        };
        let gain = Curve {
            values: gain,
            name: "ΔI of a first cut",
            color: Color::Magenta,
        };
        chart(&nmi, &boundaries, c, self.theme, top, buf);
        chart(&gain, &boundaries, c, self.theme, bottom, buf);
    }
}
