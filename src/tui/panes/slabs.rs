//! The slabs pane: the current partition, each slab's slices, millimetres, entropy and mean, and
//! the NMI or ΔI at the boundary to the next.

use ratatui::buffer::Buffer;
use ratatui::layout::{Constraint, Rect};
use ratatui::style::{Color, Modifier};
use ratatui::widgets::{Row, Table, Widget};
use slabscope::Histories;
use slabscope::geometry::WorldAxis;
use slabscope::partition::{BackgroundSummary, Method, SlabInfo, slab_text};

use super::placeholder;
use crate::tui::event::Task;
use crate::tui::theme::Theme;

/// The partition as the table shows it.
pub struct SlabTable {
    /// Slices of the stack.
    pub slices: usize,
    /// Whether the boundary values are NMI (bottom-up) or ΔI.
    pub method: Method,
    /// Each slab.
    pub info: Vec<SlabInfo>,
    /// The value at each slab's boundary with the next: NMI where the history knows it
    /// (bottom-up), else ΔI.
    pub next: Vec<f64>,
    /// What was left out as background.
    pub background: BackgroundSummary,
    /// The axis in the world: its anatomical name, and whether millimetres are world ones.
    pub world: WorldAxis,
    /// The unit lengths are shown in (mm, or µm and Å for small voxels), and its size per mm.
    pub unit: (&'static str, f64),
}

impl SlabTable {
    /// The table of `method` at `position` of `h`.
    pub fn new(h: &Histories, method: Method, position: usize) -> Self {
        let slabs = h.slabs(method, position);
        let next = match h.known_nmi(method, position) {
            Some(nmi) => nmi,
            None => h.boundary_gains(&slabs),
        };
        Self {
            slices: h.slices(),
            method,
            info: h.describe(&slabs),
            next,
            background: h.stack().background(),
            world: h.stack().world().clone(),
            unit: slabscope::geometry::length_unit(h.stack().thickness()),
        }
    }
}

/// The slabs pane's state.
pub struct SlabsPane {
    /// The table, or the gauge of the histories behind it.
    pub table: Task<SlabTable>,
    /// The selected slab.
    pub row: usize,
    /// Whether it has the focus.
    pub focused: bool,
    /// Colours.
    pub theme: Theme,
}

impl SlabsPane {
    /// An empty pane.
    pub fn new(theme: Theme) -> Self {
        Self {
            table: Task::Idle,
            row: 0,
            focused: false,
            theme,
        }
    }

    /// Number of slabs shown.
    pub fn len(&self) -> usize {
        self.table.ready().map_or(0, |t| t.info.len())
    }
}

/// Which columns fit: the mean where there is room, the millimetre range where there is more.
struct Columns {
    medium: bool,
    wide: bool,
    /// Whether the range is in world millimetres.
    world: bool,
    /// The unit of lengths, and its size per mm.
    unit: (&'static str, f64),
}

impl Columns {
    fn of(width: u16, world: bool, unit: (&'static str, f64)) -> Self {
        Self {
            medium: width >= 41,
            wide: width >= 56,
            world,
            unit,
        }
    }

    fn header(&self, method: Method) -> Vec<String> {
        let unit = self.unit.0;
        let mut h: Vec<String> = vec!["#".into(), "slices".into(), unit.into()];
        if self.wide {
            h.push(if self.world {
                format!("world {unit}")
            } else {
                format!("from–to {unit}")
            });
        }
        h.push("H".into());
        if self.medium {
            h.push("mean".into());
        }
        h.push(
            if method == Method::BottomUp {
                "NMI→"
            } else {
                "ΔI→"
            }
            .into(),
        );
        h
    }

    fn cells(&self, i: usize, s: &SlabInfo, next: Option<f64>) -> Vec<String> {
        let mark = if s.empty { " ∅" } else { "" };
        let mut cells = vec![
            format!("{i}{mark}"),
            slab_text(s.slices),
            format!("{:.1}", (s.mm.1 - s.mm.0) * self.unit.1),
        ];
        if self.wide {
            let per = self.unit.1;
            cells.push(format!(
                "{:.1}–{:.1}",
                s.world_mm.0 * per,
                s.world_mm.1 * per
            ));
        }
        cells.push(format!("{:.2}", s.entropy));
        if self.medium {
            cells.push(s.mean.map_or_else(|| "-".into(), |m| format!("{m:.1}")));
        }
        cells.push(next.map_or_else(String::new, |v| format!("{v:.4}")));
        cells
    }

    fn widths(&self) -> Vec<Constraint> {
        let mut w = vec![
            Constraint::Length(3),
            Constraint::Length(8),
            Constraint::Length(5),
        ];
        if self.wide {
            w.push(Constraint::Length(13));
        }
        w.push(Constraint::Length(4));
        if self.medium {
            w.push(Constraint::Length(7));
        }
        w.push(Constraint::Min(6));
        w
    }
}

impl Widget for &SlabsPane {
    fn render(self, area: Rect, buf: &mut Buffer) {
        let Task::Ready(table) = &self.table else {
            let block = self.theme.block(" Slabs ".into(), self.focused);
            let inner = block.inner(area);
            block.render(area, buf);
            let idle = "waiting for the best axis…";
            placeholder(
                &self.table.status(),
                "partition",
                idle,
                self.theme,
                inner,
                buf,
            );
            return;
        };
        let b = table.background;
        let left_out = if b.any() && area.width >= 50 {
            format!(", {:.0}% background left out", b.fraction * 100.0)
        } else {
            String::new()
        };
        let anatomy = match &table.world.anatomy {
            Some(a) if area.width >= 40 => format!(", {}", a.replace(", ", " ")),
            _ => String::new(),
        };
        let title = format!(
            " Slabs: {} of {} slices{anatomy}{left_out} ",
            table.info.len(),
            table.slices
        );
        let columns = Columns::of(area.width, table.world.oriented, table.unit);
        let header = Row::new(columns.header(table.method))
            .style(self.theme.fg(Color::DarkGray).add_modifier(Modifier::BOLD));
        let visible = usize::from(area.height.saturating_sub(3));
        let first = self.row.saturating_sub(visible.saturating_sub(1));
        let rows: Vec<Row> = table
            .info
            .iter()
            .enumerate()
            .skip(first)
            .take(visible)
            .map(|(i, s)| {
                let next = table.next.get(i).copied();
                let row = Row::new(columns.cells(i, s, next));
                match (i == self.row, self.focused) {
                    (true, true) => row.style(self.theme.selected()),
                    (true, false) => row.style(self.theme.fg(Color::Yellow)),
                    _ if s.empty => row.style(self.theme.fg(Color::DarkGray)),
                    _ => row,
                }
            })
            .collect();
        Table::new(rows, columns.widths())
            .header(header)
            .block(self.theme.block(title, self.focused))
            .render(area, buf);
    }
}
