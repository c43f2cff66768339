//! A folder's volumes as a pane below the others: one line a volume with its triage row (status,
//! format, dims, best axis, uncertainty, slabs, problems) as the background triage fills it in,
//! the open volume marked ●; sorted by a column, filtered, found by name and marked for a
//! manifest. The cursor's row shows its error or problems in full under the table.

use std::cmp::Ordering;
use std::collections::BTreeSet;
use std::fmt::Write;
use std::path::PathBuf;

use image::RgbaImage;
use ratatui::buffer::Buffer;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Color, Modifier};
use ratatui::text::Line;
use ratatui::widgets::{Paragraph, Row, StatefulWidget, Table, TableState, Widget, Wrap};
use slabscope::triage::{Entry, TriageRow};

use super::thumbs::Thumbs;
use crate::tui::theme::Theme;

/// A column of the pane, which it can be sorted by.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Column {
    /// The name (the folder's sorted order).
    Name,
    /// Errors first, then looked at, then waiting.
    Status,
    /// The format read.
    Format,
    /// The number of voxels.
    Dims,
    /// The best axis' name.
    Axis,
    /// Uncertain first.
    Uncertain,
    /// The number of slabs.
    Slabs,
    /// The number of problems.
    Problems,
}

impl Column {
    /// Every column, in the order `O` steps through them.
    pub const ALL: [Column; 8] = [
        Column::Name,
        Column::Status,
        Column::Format,
        Column::Dims,
        Column::Axis,
        Column::Uncertain,
        Column::Slabs,
        Column::Problems,
    ];

    /// The column's name in the pane's title.
    pub fn label(self) -> &'static str {
        match self {
            Column::Name => "name",
            Column::Status => "status",
            Column::Format => "format",
            Column::Dims => "voxels",
            Column::Axis => "axis",
            Column::Uncertain => "uncertainty",
            Column::Slabs => "slabs",
            Column::Problems => "problems",
        }
    }
}

/// Which rows show: all, or only those that failed, are uncertain, or are of a format (each
/// condition on its own, together they all hold). A row triage has not reached yet shows only
/// when nothing filters.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Filter {
    /// Only the rows whose volume failed.
    pub errors: bool,
    /// Only the rows whose best axis has a contender.
    pub uncertain: bool,
    /// Only the rows of this format.
    pub format: Option<String>,
}

impl Filter {
    fn keeps(&self, row: Option<&TriageRow>) -> bool {
        let Some(r) = row else {
            return *self == Filter::default();
        };
        (!self.errors || r.error.is_some())
            && (!self.uncertain || r.uncertain == Some(true))
            && self
                .format
                .as_ref()
                .is_none_or(|f| r.format.as_ref() == Some(f))
    }

    /// The filter in words, for the title; empty when nothing filters.
    fn words(&self) -> String {
        let mut parts = Vec::new();
        if self.errors {
            parts.push("errors".to_string());
        }
        if self.uncertain {
            parts.push("uncertain".to_string());
        }
        if let Some(f) = &self.format {
            parts.push(f.clone());
        }
        parts.join(", ")
    }
}

/// The volumes of a folder and what triage found of each.
pub struct FilesPane {
    /// The folder, for names relative to it.
    pub root: PathBuf,
    /// The volumes, sorted.
    pub paths: Vec<Entry>,
    /// Each volume's row, once triage has it.
    pub rows: Vec<Option<TriageRow>>,
    /// Each volume's thumbnail (its exploded view and mid slices), once triage has drawn it.
    pub thumbnails: Vec<Option<RgbaImage>>,
    /// The cursor: the volume it is on (an index into `paths`).
    pub row: usize,
    /// The volume open in the other panes.
    pub open: usize,
    /// Whether the pane shows.
    pub shown: bool,
    /// Whether it has the keyboard's focus.
    pub focused: bool,
    /// The volumes marked for a manifest.
    pub marked: BTreeSet<usize>,
    /// The column sorted by, and whether in reverse.
    pub sort: (Column, bool),
    /// Which rows show.
    pub filter: Filter,
    /// The manifest's file the user was told exists: the same name again replaces it.
    pub exists: Option<String>,
    /// The thumbnails drawn with the terminal's image protocol (none with half-blocks).
    pub thumbs: Option<Thumbs>,
    /// Something (the help) covers the pane: its pictures are taken away until it closes.
    pub covered: bool,
    /// The volumes shown, in the order shown.
    order: Vec<usize>,
    /// Colours.
    pub theme: Theme,
}

impl FilesPane {
    /// The pane of `paths` under `root`, the first open and the pane showing.
    pub fn new(root: PathBuf, paths: Vec<Entry>, theme: Theme) -> Self {
        let rows = vec![None; paths.len()];
        let order = (0..paths.len()).collect();
        Self {
            root,
            thumbnails: vec![None; paths.len()],
            paths,
            rows,
            row: 0,
            open: 0,
            shown: true,
            focused: false,
            marked: BTreeSet::new(),
            sort: (Column::Name, false),
            filter: Filter::default(),
            exists: None,
            thumbs: None,
            covered: false,
            order,
            theme,
        }
    }

    /// The name of volume `i`, relative to the folder.
    pub fn name(&self, i: usize) -> String {
        self.paths[i].name_under(&self.root)
    }

    /// The volumes shown, in the order shown.
    pub fn order(&self) -> &[usize] {
        &self.order
    }

    /// How many rows triage has filled.
    pub fn done(&self) -> usize {
        self.rows.iter().filter(|r| r.is_some()).count()
    }

    /// Triage's row of volume `i`: it may move in a sorted or filtered order, the cursor stays
    /// on its volume.
    pub fn fill(&mut self, i: usize, row: TriageRow) {
        if let Some(slot) = self.rows.get_mut(i) {
            *slot = Some(row);
            self.refresh();
        }
    }

    /// Orders and filters the rows again; the cursor stays on its volume while it shows, else
    /// goes to the first shown.
    pub fn refresh(&mut self) {
        let mut order: Vec<usize> = (0..self.paths.len())
            .filter(|&i| self.filter.keeps(self.rows[i].as_ref()))
            .collect();
        let (column, reverse) = self.sort;
        order.sort_by(|&a, &b| self.compare(column, reverse, a, b).then(a.cmp(&b)));
        self.order = order;
        if !self.order.contains(&self.row) {
            self.row = self.order.first().copied().unwrap_or(self.row);
        }
    }

    /// Rows `a` and `b` in the order of `column` (`reverse`: the other way); but by name,
    /// rows not looked at yet come last and, after the others, rows without a value.
    fn compare(&self, column: Column, reverse: bool, a: usize, b: usize) -> Ordering {
        let (ra, rb) = (self.rows[a].as_ref(), self.rows[b].as_ref());
        let by = |f: &dyn Fn(&TriageRow) -> Option<Value>| match (ra.and_then(f), rb.and_then(f)) {
            (Some(x), Some(y)) if reverse => y.cmp(&x),
            (Some(x), Some(y)) => x.cmp(&y),
            (x, y) => x.is_none().cmp(&y.is_none()),
        };
        let pending = ra.is_none().cmp(&rb.is_none());
        let order = match column {
            Column::Name if reverse => return b.cmp(&a),
            Column::Name => return a.cmp(&b),
            Column::Status => by(&|r| Some(Value::N(usize::from(r.error.is_none())))),
            Column::Format => by(&|r| r.format.clone().map(Value::S)),
            Column::Dims => by(&|r| r.dims.map(|d| Value::N(d.iter().product()))),
            Column::Axis => by(&|r| r.axis_name().map(Value::S)),
            Column::Uncertain => by(&|r| r.uncertain.map(|u| Value::N(usize::from(!u)))),
            Column::Slabs => by(&|r| r.slabs.as_ref().map(|s| Value::N(s.len()))),
            Column::Problems => by(&|r| Some(Value::N(r.problems.len()))),
        };
        pending.then(order)
    }

    /// Where the cursor is in the order shown.
    pub fn cursor(&self) -> Option<usize> {
        self.order.iter().position(|&i| i == self.row)
    }

    /// Moves the cursor by `by` rows of the order shown, stopping at its ends.
    pub fn step(&mut self, by: isize) {
        if self.order.is_empty() {
            return;
        }
        let at = self.cursor().unwrap_or(0) as isize;
        let last = self.order.len() as isize - 1;
        self.row = self.order[(at + by).clamp(0, last) as usize];
    }

    /// The volume `by` rows from the open one in the order shown (the first shown when the
    /// open one is not), if it is another.
    pub fn beside_open(&self, by: isize) -> Option<usize> {
        let next = match self.order.iter().position(|&i| i == self.open) {
            Some(at) => {
                let last = self.order.len() as isize - 1;
                self.order[(at as isize + by).clamp(0, last) as usize]
            }
            None => *self.order.first()?,
        };
        (next != self.open).then_some(next)
    }

    /// Marks the cursor's volume, or takes its mark away; the cursor goes to the next row.
    pub fn toggle_mark(&mut self) {
        if self.order.contains(&self.row) && !self.marked.remove(&self.row) {
            self.marked.insert(self.row);
        }
        self.step(1);
    }

    /// The marked volumes, in the folder's order.
    pub fn marked_entries(&self) -> Vec<Entry> {
        self.marked.iter().map(|&i| self.paths[i].clone()).collect()
    }

    /// Sorts by the next column (`O`), or the other way (`D`).
    pub fn sort_by_next(&mut self, reverse_only: bool) {
        let (column, reverse) = self.sort;
        self.sort = if reverse_only {
            (column, !reverse)
        } else {
            let i = Column::ALL.iter().position(|c| *c == column).unwrap_or(0);
            (Column::ALL[(i + 1) % Column::ALL.len()], false)
        };
        self.refresh();
    }

    /// Shows only the failed rows, or all again.
    pub fn toggle_errors(&mut self) {
        self.filter.errors = !self.filter.errors;
        self.refresh();
    }

    /// Shows only the uncertain rows, or all again.
    pub fn toggle_uncertain(&mut self) {
        self.filter.uncertain = !self.filter.uncertain;
        self.refresh();
    }

    /// Shows only the rows of the next format triage found, after the last every format again.
    pub fn cycle_format(&mut self) {
        let formats: BTreeSet<&String> =
            self.rows.iter().flatten().flat_map(|r| &r.format).collect();
        let next = match &self.filter.format {
            None => formats.first().copied(),
            Some(f) => formats
                .range::<&String, _>((std::ops::Bound::Excluded(f), std::ops::Bound::Unbounded))
                .next()
                .copied(),
        };
        self.filter.format = next.cloned();
        self.refresh();
    }

    /// Moves the cursor to the first row shown from it on (then from the top) whose name holds
    /// `text` (ignoring case); whether one does.
    pub fn find(&mut self, text: &str) -> bool {
        let text = text.to_lowercase();
        let at = self.cursor().unwrap_or(0);
        let n = self.order.len();
        let found = (0..n)
            .map(|k| self.order[(at + k) % n])
            .find(|&i| self.name(i).to_lowercase().contains(&text));
        if let Some(i) = found {
            self.row = i;
        }
        found.is_some()
    }

    /// What the cursor's row says in full: its error, else its problems.
    pub fn detail(&self) -> Option<String> {
        self.cursor()?;
        let r = self.rows.get(self.row)?.as_ref()?;
        match &r.error {
            Some(e) => Some(format!("{}: {e}", self.name(self.row))),
            None if !r.problems.is_empty() => Some(format!(
                "{}: {}",
                self.name(self.row),
                r.problems.join("; ")
            )),
            None => None,
        }
    }

    fn line(&self, i: usize, wide: bool) -> Row<'static> {
        let open = if i == self.open { '●' } else { ' ' };
        let mark = if self.marked.contains(&i) { '+' } else { ' ' };
        let mut cells = vec![format!("{open}{mark}")];
        let name = slabscope::error::names::controls(&self.name(i)).into_owned();
        let Some(r) = &self.rows[i] else {
            cells.extend(["…".into(), String::new(), String::new(), String::new()]);
            cells.extend([String::new(), String::new(), name]);
            return Row::new(cells).style(self.theme.fg(Color::DarkGray));
        };
        let dims = r.dims.map(|d| format!("{}x{}x{}", d[0], d[1], d[2]));
        let problems = match (&r.error, wide) {
            (Some(e), _) => format!("error: {e}"),
            (None, true) => r.problems.join("; "),
            (None, false) if r.problems.is_empty() => String::new(),
            (None, false) => format!("{} problem(s)", r.problems.len()),
        };
        cells.extend([
            if r.error.is_some() { "!!" } else { "ok" }.to_string(),
            r.format.clone().unwrap_or_default(),
            dims.unwrap_or_default(),
            r.axis_name().unwrap_or_default(),
            if r.uncertain == Some(true) { "≈" } else { "" }.to_string(),
            r.slabs
                .as_ref()
                .map(|s| s.len().to_string())
                .unwrap_or_default(),
            format!("{name}  {problems}"),
        ]);
        let cells = cells
            .into_iter()
            .map(|c| slabscope::error::names::controls(&c).into_owned());
        let style = if r.error.is_some() {
            self.theme.fg(Color::Red)
        } else {
            self.theme.fg(Color::Reset)
        };
        Row::new(cells.collect::<Vec<_>>()).style(style)
    }

    /// The cursor's error (red) or problems (yellow), wrapped.
    fn draw_detail(&self, d: &str, area: Rect, buf: &mut Buffer) {
        let failed = self.rows[self.row]
            .as_ref()
            .is_some_and(|r| r.error.is_some());
        let colour = if failed { Color::Red } else { Color::Yellow };
        let d = slabscope::error::names::controls(d).into_owned();
        Paragraph::new(Line::from(d))
            .style(self.theme.fg(colour))
            .wrap(Wrap { trim: false })
            .render(area, buf);
    }

    /// The columns beside the table for thumbnails in a pane `width` wide with `rows` for the
    /// table, and those of the cursor's large thumbnail among them: with an image protocol the
    /// rows' column from 60 columns on, the large too from 140 where the cursor's volume has one;
    /// with half-blocks and colours only the large, from 140.
    fn beside(&self, width: u16, rows: u16) -> (u16, u16) {
        let has = self.thumbnails.get(self.row).is_some_and(Option::is_some);
        let large = has && width >= 140 && rows >= 5;
        match &self.thumbs {
            Some(t) if width >= 60 && rows >= 2 => {
                let large = if large { t.large_columns(rows) } else { 0 };
                (t.row_columns() + u16::from(large > 0) + large, large)
            }
            None if large && self.theme.color => (4 * rows, 4 * rows),
            _ => (0, 0),
        }
    }

    /// Draws the thumbnails into `area` beside the table, whose first row shown is `offset`:
    /// with the image protocol each row's and the cursor's large (`large` columns wide), with
    /// half-blocks the cursor's alone.
    fn draw_thumbnails(&self, area: Rect, offset: usize, large: u16, buf: &mut Buffer) {
        if area.width == 0 {
            return;
        }
        let thumbnail = self.thumbnails.get(self.row).and_then(Option::as_ref);
        let Some(thumbs) = &self.thumbs else {
            if let Some(t) = thumbnail {
                half_blocks(t, area, buf);
            }
            return;
        };
        let lines: Vec<super::thumbs::Line> = self
            .order
            .iter()
            .skip(offset)
            .take(usize::from(area.height.saturating_sub(1)))
            .map(|&i| (i, self.thumbnails[i].as_ref()))
            .collect();
        let large_one = (large > 0).then_some((self.row, thumbnail));
        thumbs.draw(area, &lines, large_one, large, self.covered, buf);
    }

    fn title(&self) -> String {
        let mut title = format!(
            " {} volumes in {}, {} looked at",
            self.paths.len(),
            slabscope::error::shown(&self.root),
            self.done()
        );
        if !self.marked.is_empty() {
            let _ = write!(title, ", {} marked", self.marked.len());
        }
        if self.sort != (Column::Name, false) {
            let reversed = if self.sort.1 { ", reversed" } else { "" };
            let _ = write!(title, " · by {}{reversed}", self.sort.0.label());
        }
        let filter = self.filter.words();
        if !filter.is_empty() {
            let _ = write!(title, " · only {filter} ({} shown)", self.order.len());
        }
        title.push(' ');
        title
    }
}

/// A value a column sorts by.
#[derive(PartialEq, Eq, PartialOrd, Ord)]
enum Value {
    N(usize),
    S(String),
}

/// Draws `image` scaled to fill `area` in half-blocks (averaging the pixels each covers): a
/// cell's upper half one pixel, its lower half the one below.
pub fn half_blocks(image: &RgbaImage, area: Rect, buf: &mut Buffer) {
    let (w, h) = (u32::from(area.width), 2 * u32::from(area.height));
    if w == 0 || h == 0 || image.width() == 0 || image.height() == 0 {
        return;
    }
    let scaled = image::imageops::resize(image, w, h, image::imageops::FilterType::Triangle);
    let at = |x: u32, y: u32| {
        let p = scaled.get_pixel(x, y);
        Color::Rgb(p[0], p[1], p[2])
    };
    for (dx, x) in (area.x..area.right()).enumerate() {
        for (dy, y) in (area.y..area.bottom()).enumerate() {
            let (px, py) = (dx as u32, 2 * dy as u32);
            buf[(x, y)]
                .set_symbol("▀")
                .set_fg(at(px, py))
                .set_bg(at(px, py + 1));
        }
    }
}

/// The columns' widths, on a wide pane (110 cells) or not.
fn widths(wide: bool) -> Vec<Constraint> {
    let widths: &[Constraint] = if wide {
        &[
            Constraint::Length(2),
            Constraint::Length(2),
            Constraint::Length(10),
            Constraint::Length(13),
            Constraint::Length(18),
            Constraint::Length(1),
            Constraint::Length(5),
            Constraint::Min(20),
        ]
    } else {
        &[
            Constraint::Length(2),
            Constraint::Length(2),
            Constraint::Length(9),
            Constraint::Length(11),
            Constraint::Length(5),
            Constraint::Length(1),
            Constraint::Length(3),
            Constraint::Min(10),
        ]
    };
    widths.to_vec()
}

/// The rows the pane takes on a screen with `body` rows for the panes: its table for `volumes`
/// (with a header and a border) and a line for the cursor's error, at most a third of the body.
pub fn height(volumes: usize, body: u16) -> u16 {
    (volumes as u16)
        .saturating_add(4)
        .clamp(5, (body / 3).max(5))
}

impl Widget for &FilesPane {
    fn render(self, area: Rect, buf: &mut Buffer) {
        let block = self.theme.block(self.title(), self.focused);
        let inner = block.inner(area);
        block.render(area, buf);
        let wide = inner.width >= 110;
        let detail = self.detail();
        // The detail, wrapped, under the table: up to three lines, a table line always left.
        let lines = detail.as_ref().map_or(0, |d| {
            let w = usize::from(inner.width.max(1));
            (d.chars().count().div_ceil(w) as u16).clamp(1, 3)
        });
        let lines = lines.min(inner.height.saturating_sub(2));
        let [table_area, detail_area] =
            Layout::vertical([Constraint::Min(0), Constraint::Length(lines)]).areas(inner);
        let (side, large) = self.beside(inner.width, table_area.height);
        let [table_area, thumb_area] =
            Layout::horizontal([Constraint::Min(0), Constraint::Length(side)]).areas(table_area);
        let widths = widths(wide);
        let slabs = if wide { "slabs" } else { "sl" };
        let header = Row::new([
            "",
            "st",
            "format",
            "dims",
            "axis",
            "≈",
            slabs,
            "name  problems",
        ])
        .style(self.theme.fg(Color::DarkGray).add_modifier(Modifier::BOLD));
        let rows = self.order.iter().map(|&i| self.line(i, wide));
        let table = Table::new(rows, widths)
            .header(header)
            .row_highlight_style(self.theme.selected());
        let mut state = TableState::default().with_selected(self.cursor());
        StatefulWidget::render(table, table_area, buf, &mut state);
        self.draw_thumbnails(thumb_area, state.offset(), large, buf);
        if self.order.is_empty() {
            let empty = if self.paths.is_empty() {
                "no volumes"
            } else {
                "no row passes the filter (E U T change it)"
            };
            Paragraph::new(empty).render(
                Rect {
                    y: table_area.y + 1,
                    height: 1.min(table_area.height.saturating_sub(1)),
                    ..table_area
                },
                buf,
            );
        }
        if let Some(d) = detail {
            self.draw_detail(&d, detail_area, buf);
        }
    }
}
