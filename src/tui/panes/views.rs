//! The viewpoints pane: every axis with its entropy rate, lowest first, and a sphere map; once
//! the axes are ranked by partition gain, both scores, in either ranking's order.

use ratatui::buffer::Buffer;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Paragraph, Widget};
use slabscope::analysis::GainRanking;
use slabscope::view::{AxisEntropy, RankedBy, score};
use slabscope::{Axis, ViewSearch};

use super::placeholder;
use super::sphere::SphereMap;
use crate::tui::event::Task;
use crate::tui::theme::Theme;

/// The list's width: rank, axis, name and score.
const LIST: u16 = 38;

/// The list's width with the plane's short name (`ax`, `cor`, `sag`), when the orientation is
/// known.
const LIST_SHORT: u16 = 42;

/// The list's width with the anatomical name, when the orientation is known.
const LIST_WIDE: u16 = 51;

/// The compact row with both scores and its rank: mark, rank, axis and two scores.
const COMPACT_RANKED: u16 = 35;

/// What the gain's column adds to the list's width.
const GAIN_COLUMN: u16 = 7;

/// The viewpoints pane's state.
pub struct ViewsPane {
    /// The view search (each axis with its gain once that ranking is in).
    pub views: Task<ViewSearch>,
    /// The axes ranked by partition gain, when asked for.
    pub gain: Task<GainRanking>,
    /// Whether the list and the sphere follow the gain ranking (once it is in).
    pub by_gain: bool,
    /// The selected row.
    pub row: usize,
    /// The axis being partitioned.
    pub current: Option<[f64; 3]>,
    /// What to say before the search starts (loading, or why the volume did not load).
    pub idle: String,
    /// Whether it has the focus.
    pub focused: bool,
    /// Colours.
    pub theme: Theme,
}

impl ViewsPane {
    /// A pane waiting for the volume called `name`.
    pub fn new(name: &str, theme: Theme) -> Self {
        Self {
            views: Task::Idle,
            gain: Task::Idle,
            by_gain: false,
            row: 0,
            current: None,
            idle: format!("loading {name}…"),
            focused: true,
            theme,
        }
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.views.ready().map_or(0, |v| v.views.len())
    }

    /// The axis of the selected row.
    pub fn selected(&self) -> Option<[f64; 3]> {
        self.rows().get(self.row).map(|v| v.axis)
    }

    /// The gain ranking the list follows, when it does.
    fn ordered_by_gain(&self) -> Option<&GainRanking> {
        self.gain.ready().filter(|_| self.by_gain)
    }

    /// The rows in the order shown: the entropy rate's, or the gain ranking's.
    fn rows(&self) -> Vec<&AxisEntropy> {
        match (self.views.ready(), self.ordered_by_gain()) {
            (Some(v), Some(g)) => g.sorted(&v.views),
            (Some(v), None) => v.views.iter().collect(),
            (None, _) => Vec::new(),
        }
    }

    /// One row: a mark (● the axis partitioned, * the best, ≈ a contender of the best, by the
    /// ranking the list follows), the rank, the axis and its score (and its gain, once ranked),
    /// compact in a narrow list.
    fn line(&self, views: &ViewSearch, i: usize, v: &AxisEntropy, width: u16) -> Line<'static> {
        let axis = Axis::new(v.axis).unwrap_or(Axis::Z);
        let current = self
            .current
            .is_some_and(|a| Axis::new(a).is_ok_and(|a| a.angle(axis) < 1e-6));
        let contender = match self.ordered_by_gain() {
            Some(g) => g.contenders.iter().skip(1).any(|c| c.axis == v.axis),
            None => views
                .contenders
                .as_ref()
                .is_some_and(|c| c.iter().skip(1).any(|c| c.axis == v.axis)),
        };
        let gain = v.gain_phases.map(|g| g.mean);
        let (width, column) = match gain {
            Some(g) if width >= LIST + GAIN_COLUMN => (width - GAIN_COLUMN, format!(" {g:>6.4}")),
            _ => (width, String::new()),
        };
        let mark = match (current, i == 0, contender) {
            (true, ..) => "●",
            (_, true, _) => "*",
            (_, _, true) => "≈",
            _ => " ",
        };
        let oriented = v.world.oriented;
        let text = if oriented && width >= LIST_WIDE {
            // With the anatomy: `I→S axial`, `oblique`.
            let name = axis.name().unwrap_or(" ");
            let anatomy = v.world.anatomy_text().replace(", ", " ");
            format!(
                "{mark}{:>3} {axis} {name} {anatomy:<12} {:.4}",
                i + 1,
                score(v)
            )
        } else if oriented && width >= LIST_SHORT {
            // The plane in three letters: `ax`, `cor`, `sag`, blank when oblique.
            let name = axis.name().unwrap_or(" ");
            let plane = v.world.anatomy.as_deref().map_or("", |a| {
                let plane = a.rsplit(' ').next().unwrap_or("");
                &plane[..plane.len().min(3)]
            });
            let plane = if plane == "axi" { "ax" } else { plane };
            format!(
                "{mark}{:>3} {axis} {name} {plane:<3} {:.4}",
                i + 1,
                score(v)
            )
        } else if width >= LIST && column.is_empty() == gain.is_none() {
            let name = axis.name().map_or(String::new(), |n| format!(" {n}"));
            format!("{mark}{:>3} {axis}{name} {:.4}", i + 1, score(v))
        } else {
            // Both scores to three places once the gain is in, the rank left out where even
            // that does not fit.
            let h = score(v);
            match gain {
                Some(g) if width >= COMPACT_RANKED => {
                    format!("{mark}{:>2} {axis:.2} {h:.3} {g:.3}", i + 1)
                }
                Some(g) => format!("{mark}{axis:.2} {h:.3} {g:.3}"),
                None => format!("{mark}{:>2} {axis:.2} {h:.3}", i + 1),
            }
        };
        let text = text + &column;
        let mut style = if current {
            self.theme.fg(Color::Yellow)
        } else {
            self.theme.fg(Color::Reset)
        };
        if i == self.row && self.focused {
            style = style.patch(self.theme.selected());
        } else if i == self.row {
            style = style.add_modifier(Modifier::BOLD);
        }
        Line::from(Span::styled(text, style))
    }

    /// The list's area and the sphere map's, which takes the right part of a wide pane or the
    /// bottom of a tall one.
    fn split(inner: Rect, oriented: bool, gain: bool) -> (Rect, Option<Rect>) {
        let extra = if gain { GAIN_COLUMN } else { 0 };
        let list = extra
            + match inner.width.saturating_sub(extra) {
                w if oriented && w >= LIST_WIDE + 32 => LIST_WIDE,
                w if oriented && w >= LIST_SHORT + 32 => LIST_SHORT,
                _ => LIST,
            };
        if inner.width >= list + 32 {
            let [l, m] =
                Layout::horizontal([Constraint::Length(list), Constraint::Min(0)]).areas(inner);
            (l, Some(m))
        } else if inner.height >= 22 {
            let [l, m] =
                Layout::vertical([Constraint::Min(0), Constraint::Length(inner.height / 2)])
                    .areas(inner);
            (l, Some(m))
        } else {
            (inner, None)
        }
    }
}

/// What the scores are: the mean entropy rate over phases, or the paper's.
fn what(v: &ViewSearch) -> String {
    match v.ranked_by {
        RankedBy::PhaseMean => format!("mean h over {} phases", v.params.phases),
        RankedBy::PaperLattice => "h on the paper's lattice".into(),
    }
}

/// `: clear` or `: uncertain (2 ≈)`, with phases.
fn verdict(v: &ViewSearch) -> String {
    match &v.contenders {
        Some(c) if c.len() > 1 => format!(": uncertain ({} ≈)", c.len() - 1),
        Some(_) => ": clear".into(),
        None => String::new(),
    }
}

impl Widget for &ViewsPane {
    fn render(self, area: Rect, buf: &mut Buffer) {
        let title = match (self.views.ready(), self.ordered_by_gain()) {
            (Some(v), Some(g)) => {
                let sure = if g.uncertain() {
                    format!(": uncertain ({} ≈)", g.contenders.len() - 1)
                } else {
                    ": clear".into()
                };
                let wide = format!(
                    " {} axes by the gain of {} slabs{sure} ",
                    v.views.len(),
                    g.sampling.slabs
                );
                // The long form where it fits between the corners, else the short one.
                if wide.chars().count() + 2 <= usize::from(area.width) {
                    wide
                } else {
                    format!(" {} axes by gain{sure} ", v.views.len())
                }
            }
            (Some(v), None) if area.width >= 44 => {
                format!(" {} axes by {}{} ", v.views.len(), what(v), verdict(v))
            }
            (Some(v), None) => format!(" {} axes, h{} ", v.views.len(), verdict(v)),
            (None, _) => " Viewpoints ".into(),
        };
        let block = self.theme.block(title, self.focused);
        let inner = block.inner(area);
        block.render(area, buf);
        let Task::Ready(views) = &self.views else {
            placeholder(
                &self.views.status(),
                "view search",
                &self.idle,
                self.theme,
                inner,
                buf,
            );
            return;
        };
        let oriented = views.views.first().is_some_and(|v| v.world.oriented);
        let gain = views.views.iter().any(|v| v.gain_phases.is_some());
        let (list, map) = ViewsPane::split(inner, oriented, gain);
        let rows = usize::from(list.height);
        let first = self.row.saturating_sub(rows.saturating_sub(1));
        let ordered = self.rows();
        let lines: Vec<Line> = ordered
            .iter()
            .enumerate()
            .skip(first)
            .take(rows)
            .map(|(i, v)| self.line(views, i, v, list.width))
            .collect();
        Paragraph::new(lines)
            .style(Style::default())
            .render(list, buf);
        if let Some(map) = map {
            SphereMap {
                views: &views.views,
                by_gain: self.ordered_by_gain().is_some(),
                current: self.current,
                theme: self.theme,
            }
            .render(map, buf);
        }
    }
}
