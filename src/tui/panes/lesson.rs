//! The lesson pane (key `x`): the numbers behind the selected viewpoint or the step shown, as
//! text (the library's sentences, so they read the same with half-blocks as with images), with a
//! strip of one ray's samples, bar charts of a split's histograms and its gain at every cut, and
//! a merge's joint histogram as a heat map. Drawn over the panes; condensed on a small terminal.

use ratatui::buffer::Buffer;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Color, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Clear, Paragraph, Sparkline, Widget, Wrap};
use slabscope::explain::text;
use slabscope::explain::{AxisLesson, MergeLesson, RayPlane, RaySamples, SplitLesson};

use super::heat::{self, tick_line};
use super::placeholder;
use crate::tui::event::Task;
use crate::tui::lesson::{Lesson, Subject};
use crate::tui::theme::Theme;

/// The lesson pane's state.
pub struct LessonPane {
    /// Whether it shows.
    pub open: bool,
    /// What the lesson asked for last is about.
    pub subject: Option<Subject>,
    /// The number of the newest request.
    pub generation: u64,
    /// The numbers, or the gauge of their job.
    pub lesson: Task<Box<Lesson>>,
    /// Colours.
    pub theme: Theme,
}

/// Terminals at least this tall get the full sentences and the taller charts.
const ROOMY_HEIGHT: u16 = 36;

impl LessonPane {
    /// A closed pane.
    pub fn new(theme: Theme) -> Self {
        Self {
            open: false,
            subject: None,
            generation: 0,
            lesson: Task::Idle,
            theme,
        }
    }

    fn title(&self) -> String {
        let what = match &self.subject {
            Some(Subject::Axis { .. }) => "why this viewpoint (← → another ray)",
            Some(Subject::Step { .. }) => "why this step (n p step)",
            Some(Subject::BestMerge { .. }) => {
                "a merge of slices alike (n p step from the step shown)"
            }
            Some(Subject::Modes { .. }) => "the paper beside this tool's defaults",
            None => "",
        };
        format!(" Lesson: {what}  x closes ")
    }
}

impl Widget for &LessonPane {
    fn render(self, area: Rect, buf: &mut Buffer) {
        Clear.render(area, buf);
        buf.set_style(area, self.theme.base());
        let block = self.theme.block(self.title(), true);
        let inner = block.inner(area);
        block.render(area, buf);
        let roomy = area.height >= ROOMY_HEIGHT;
        match &self.lesson {
            Task::Ready(lesson) => match lesson.as_ref() {
                Lesson::Axis {
                    selected,
                    ray,
                    plane,
                    best,
                } => {
                    // The plane of rays beside the words where the terminal is wide, below
                    // them where it is tall, else not at all.
                    let (words, picture) = match plane.as_ref().filter(|_| self.theme.color) {
                        Some(p) if inner.width >= 130 => {
                            let [w, p_area] = Layout::horizontal([
                                Constraint::Min(80),
                                Constraint::Percentage(35),
                            ])
                            .areas(inner);
                            (w, Some((p, p_area)))
                        }
                        Some(p) if roomy => {
                            let [w, p_area] =
                                Layout::vertical([Constraint::Min(20), Constraint::Percentage(30)])
                                    .areas(inner);
                            (w, Some((p, p_area)))
                        }
                        _ => (inner, None),
                    };
                    let lines = axis(selected, ray.as_ref(), best, roomy, words.width, self.theme);
                    paragraph(lines, words, buf);
                    if let Some((p, area)) = picture {
                        plane_picture(p, selected.bins, area, buf);
                    }
                }
                Lesson::Split(s) => split(s, self.theme, inner, buf),
                Lesson::Merge(m, of) => merge(m, *of, None, self.theme, inner, buf),
                Lesson::BestMerge { merge: m, upto, of } => {
                    merge(m, *of, Some(*upto), self.theme, inner, buf);
                }
                Lesson::Modes(m) => paragraph(
                    text::mode_lines(m).into_iter().map(Line::from).collect(),
                    inner,
                    buf,
                ),
                Lesson::Optimal(o) => paragraph(
                    text::optimal_lines(o).into_iter().map(Line::from).collect(),
                    inner,
                    buf,
                ),
                Lesson::Nothing(why) => paragraph(vec![Line::from(why.clone())], inner, buf),
            },
            Task::Running(_) | Task::Failed(_) | Task::Idle => {
                let load = self.lesson.status();
                placeholder(&load, "lesson", "", self.theme, inner, buf);
            }
        }
    }
}

fn paragraph(lines: Vec<Line<'static>>, area: Rect, buf: &mut Buffer) {
    Paragraph::new(lines)
        .wrap(Wrap { trim: false })
        .render(area, buf);
}

/// The colour of bin `b` of `bins`: a grey ramp, dark to light.
fn bin_color(b: u8, bins: usize) -> Color {
    let v = 40 + (215 * usize::from(b) / bins.saturating_sub(1).max(1)) as u8;
    Color::Rgb(v, v, v)
}

/// A cell for bin `b`: a coloured block, or without colours a shade by the bin.
fn bin_span(b: Option<u8>, bins: usize, theme: Theme) -> Span<'static> {
    match b {
        None => Span::raw("·"),
        Some(b) if theme.color => Span::styled("█", Style::default().fg(bin_color(b, bins))),
        Some(b) => {
            const SHADES: [&str; 5] = [" ", "░", "▒", "▓", "█"];
            Span::raw(SHADES[usize::from(b) * SHADES.len() / bins.max(1)])
        }
    }
}

/// `[ 0.000, 0.000, 1.000] (z)`.
fn axis_name(axis: [f64; 3]) -> String {
    slabscope::Axis::new(axis).map_or_else(|_| format!("{axis:?}"), slabscope::Axis::labelled)
}

/// The selected axis's ray and numbers beside the best's (once, when it is the best).
fn axis(
    selected: &AxisLesson,
    ray: Option<&RaySamples>,
    best: &AxisLesson,
    roomy: bool,
    width: u16,
    theme: Theme,
) -> Vec<Line<'static>> {
    let top = if roomy { 5 } else { 1 };
    let mut lines = Vec::new();
    if let Some(ray) = ray {
        lines.extend(ray_lines(ray, selected.bins, width, roomy, theme));
    } else {
        lines.push(Line::from(
            "This ray misses the volume: ← → move to another.",
        ));
    }
    let mut words = text::axis_lines(
        &format!("Selected {}", axis_name(selected.axis)),
        selected,
        top,
    );
    if selected.axis == best.axis {
        words.push("It is the best axis: no other has a lower h.".to_string());
    } else {
        words.extend(text::axis_lines(
            &format!("Best {}", axis_name(best.axis)),
            best,
            top,
        ));
        words.push(text::rate_sentence("selected", selected, "best", best));
    }
    lines.extend(words.into_iter().map(Line::from));
    lines
}

/// The ray each of `rows` pixel rows shows, of `n` rays picked evenly (`rows` ≤ `n`): the
/// lesson's ray `selected` on its nearest row and on no other (a row that would show it again
/// shows its neighbour), so one ▶ marks it.
fn picked_rays(n: usize, rows: usize, selected: Option<usize>) -> Vec<usize> {
    let own = selected.map(|s| s * rows / n);
    (0..rows)
        .map(|y| match (y * n / rows, selected) {
            (_, Some(s)) if own == Some(y) => s,
            (r, Some(s)) if r == s && s + 1 < n => s + 1,
            (r, Some(s)) if r == s => s.saturating_sub(1),
            (r, _) => r,
        })
        .collect()
}

/// The plane of rays holding the lesson's ray: a pixel row a ray (half blocks), a column a
/// sample, grey by bin, the lesson's ray in yellow and marked ▶; rays and samples picked
/// evenly where there are more than fit.
fn plane_picture(plane: &RayPlane, bins: usize, area: Rect, buf: &mut Buffer) {
    if area.height < 3 || area.width < 12 {
        return;
    }
    let title = format!(
        "The plane of rays j = {}: a row a ray, the lesson's in yellow",
        plane.j
    );
    Paragraph::new(title)
        .wrap(Wrap { trim: true })
        .render(Rect { height: 2, ..area }, buf);
    let (rows, cols) = (
        usize::from(area.height - 2) * 2,
        usize::from(area.width - 1),
    );
    let (n, k) = (plane.rays.len(), plane.bins[0].len());
    let (shown_rows, shown_cols) = (n.min(rows), k.min(cols));
    let picked = picked_rays(n, shown_rows, plane.selected);
    let pick = |y: usize| picked[y];
    let colour = |r: usize, x: usize| -> Color {
        match plane.bins[r][x * k / shown_cols] {
            None => Color::Rgb(0, 0, 0),
            Some(b) => {
                let Color::Rgb(v, _, _) = bin_color(b, bins) else {
                    return Color::Reset;
                };
                if Some(r) == plane.selected {
                    Color::Rgb(v, v, v / 4)
                } else {
                    Color::Rgb(v, v, v)
                }
            }
        }
    };
    for line in 0..shown_rows.div_ceil(2) {
        let (top, bottom) = (
            pick(2 * line),
            (2 * line + 1 < shown_rows).then(|| pick(2 * line + 1)),
        );
        let marked = plane
            .selected
            .is_some_and(|s| s == top || Some(s) == bottom);
        let mut spans = vec![Span::raw(if marked { "▶" } else { " " })];
        for x in 0..shown_cols {
            let bg = bottom.map_or(Color::Rgb(0, 0, 0), |b| colour(b, x));
            spans.push(Span::styled(
                "▀",
                Style::default().fg(colour(top, x)).bg(bg),
            ));
        }
        let y = area.y + 2 + line as u16;
        if y < area.y + area.height {
            Paragraph::new(Line::from(spans)).render(
                Rect {
                    y,
                    height: 1,
                    ..area
                },
                buf,
            );
        }
    }
}

/// The ray as a strip of its samples coloured by bin, its bins as numbers, and where it runs;
/// on a small terminal the strip takes at most two lines and the numbers one.
fn ray_lines(
    ray: &RaySamples,
    bins: usize,
    width: u16,
    roomy: bool,
    theme: Theme,
) -> Vec<Line<'static>> {
    let width = usize::from(width.max(8));
    let (strip_rows, number_rows) = if roomy { (usize::MAX, 4) } else { (2, 1) };
    let shown = ray.bins.len().min(width.saturating_mul(strip_rows));
    let (a, b) = ray.ends;
    let at = |p: [f64; 3]| format!("({:.1}, {:.1}, {:.1})", p[0], p[1], p[2]);
    let part = if shown < ray.bins.len() {
        format!(", the first {shown}")
    } else {
        String::new()
    };
    let mut lines = vec![Line::from(format!(
        "Ray ({}, {}): {} samples from voxel {} to {}{part}, a cell each by bin:",
        ray.ray.0,
        ray.ray.1,
        ray.bins.len(),
        at(a),
        at(b)
    ))];
    for chunk in ray.bins[..shown].chunks(width) {
        lines.push(Line::from(
            chunk
                .iter()
                .map(|&b| bin_span(b, bins, theme))
                .collect::<Vec<_>>(),
        ));
    }
    let mut numbers = String::from("bins:");
    for b in &ray.bins {
        let next = b.map_or(" ·".to_string(), |b| format!(" {b}"));
        if numbers.chars().count() + next.len() + 2 > width * number_rows {
            numbers.push_str(" …");
            break;
        }
        numbers.push_str(&next);
    }
    lines.push(Line::from(numbers));
    lines
}

/// Rows `lines` take wrapped at `width`.
fn wrapped_rows(lines: &[String], width: u16) -> u16 {
    let w = usize::from(width.max(1));
    lines
        .iter()
        .map(|l| l.chars().count().div_ceil(w).max(1) as u16)
        .sum()
}

/// A split: its sentences, the two parts' and their union's histograms as bars (log counts),
/// and the gain at every cut of the slab with the one taken marked; the bars take the rows the
/// sentences leave.
fn split(s: &SplitLesson, theme: Theme, area: Rect, buf: &mut Buffer) {
    let mut words = text::split_lines(s, s.step.max(1));
    words[0] = format!(
        "Split {}: slices {}–{} cut at slice {}",
        s.step,
        s.split.0,
        s.split.1 - 1,
        s.at
    );
    let used = wrapped_rows(&words, area.width);
    let bar = (area.height.saturating_sub(used + 3) / 4).clamp(1, 6);
    let [top, rest] =
        Layout::vertical([Constraint::Min(3), Constraint::Length(4 * bar + 3)]).areas(area);
    paragraph(words.into_iter().map(Line::from).collect(), top, buf);
    let rows = Layout::vertical([
        Constraint::Length(bar),
        Constraint::Length(bar),
        Constraint::Length(bar),
        Constraint::Length(1),
        Constraint::Length(bar),
        Constraint::Length(1),
        Constraint::Length(1),
    ])
    .split(rest);
    for (row, (label, counts)) in rows.iter().zip([
        ("part 1", &s.first),
        ("part 2", &s.second),
        ("union", &s.union),
    ]) {
        bars(label, counts, theme, *row, buf);
    }
    // The three histograms share their bins: ticked once, under them.
    let each = bar_width(rows[0], s.first.len());
    let last = s.first.len().saturating_sub(1);
    ticks(
        "bin",
        &[(0, 0), (last / 2 * each, last / 2), (last * each, last)],
        rows[3],
        buf,
    );
    gains(s, theme, rows[4], rows[5], buf);
    let (first, end) = (s.split.0 + 1, s.split.1 - 1);
    let width = usize::from(rows[6].width.saturating_sub(LABEL));
    let n = s.gains.len().max(1);
    let column = |slice: usize| (slice - first) * width.min(n) / n;
    ticks("slice", &[(0, first), (column(end), end)], rows[6], buf);
}

/// The columns of the label left of each chart of the split.
const LABEL: u16 = 11;

/// The columns a bin takes in a bar chart of `bins` bins in `area` (label included).
fn bar_width(area: Rect, bins: usize) -> usize {
    (usize::from(area.width.saturating_sub(LABEL)) / bins.max(1)).clamp(1, 3)
}

/// [`tick_line`] drawn in `area`, under a chart of the split.
fn ticks(name: &str, at: &[(usize, usize)], area: Rect, buf: &mut Buffer) {
    let line = tick_line(name, usize::from(LABEL), at, usize::from(area.width));
    Paragraph::new(line).render(area, buf);
}

/// A labelled bar chart of `counts` on a log scale, as many columns a bin as fit; the label
/// says the largest count, the chart's top.
fn bars(label: &str, counts: &[u64], theme: Theme, area: Rect, buf: &mut Buffer) {
    let [l, chart] =
        Layout::horizontal([Constraint::Length(LABEL), Constraint::Min(0)]).areas(area);
    let most = counts.iter().copied().max().unwrap_or(0);
    Paragraph::new(vec![
        Line::from(format!("{label} log")),
        Line::from(format!("≤{}", text::grouped(most))),
    ])
    .render(l, buf);
    let each = bar_width(area, counts.len());
    let data: Vec<u64> = counts
        .iter()
        .flat_map(|&c| std::iter::repeat_n(((c as f64).ln_1p() * 1000.0) as u64, each))
        .collect();
    Sparkline::default()
        .data(&data)
        .style(theme.fg(Color::Cyan))
        .render(chart, buf);
}

/// The gain at every cut of the slab, squeezed to the width (the largest of each column's cuts),
/// and a mark under the cut taken.
fn gains(s: &SplitLesson, theme: Theme, area: Rect, mark: Rect, buf: &mut Buffer) {
    let [l, chart] =
        Layout::horizontal([Constraint::Length(LABEL), Constraint::Min(0)]).areas(area);
    let most = s.gains.iter().copied().fold(0.0f64, f64::max);
    Paragraph::new(vec![
        Line::from("ΔI cuts"),
        Line::from(format!("≤{most:.4}")),
    ])
    .render(l, buf);
    let n = s.gains.len().max(1);
    let columns = usize::from(chart.width).clamp(1, n);
    let column = |i: usize| i * columns / n;
    let mut squeezed = vec![0u64; columns];
    let top = s.gains.iter().copied().fold(0.0f64, f64::max).max(1e-300);
    for (i, &g) in s.gains.iter().enumerate() {
        let v = (g / top * 1e6) as u64;
        let c = &mut squeezed[column(i)];
        *c = (*c).max(v);
    }
    Sparkline::default()
        .data(&squeezed)
        .style(theme.fg(Color::Yellow))
        .render(chart, buf);
    let at = usize::from(chart.x - area.x) + column(s.at - s.split.0 - 1);
    let said = format!("cut at {} (ΔI {:.4})", s.at, s.gain);
    let line = if at + 2 + said.chars().count() <= usize::from(mark.width) {
        format!("{}▲ {said}", " ".repeat(at))
    } else {
        let pad = (at + 1).saturating_sub(said.chars().count() + 2);
        format!("{}{said} ▲", " ".repeat(pad))
    };
    Paragraph::new(line).render(mark, buf);
}

/// A merge, one of `of` in its history: its sentences and, in the rows they leave, the joint
/// histogram as a heat map. `upto`: the step shown, when the merge is the highest NMI's of
/// those taken to it, which a first line says.
fn merge(
    m: &MergeLesson,
    of: usize,
    upto: Option<usize>,
    theme: Theme,
    area: Rect,
    buf: &mut Buffer,
) {
    let of = of.max(m.step);
    let mut words = text::merge_lines(m, of);
    if let Some(upto) = upto {
        words.insert(
            0,
            format!(
                "The example: of the {upto} merges taken to the slabs shown, the one of the \
                 highest NMI below 1 (n p step on from merge {upto}, the last):"
            ),
        );
    }
    // Where the sentences leave the joint histogram less than its rows at two bins a cell, the
    // same numbers in a few lines, the map beside them.
    if wrapped_rows(&words, area.width) + heat::rows(m.bins, 2, area.width) <= area.height {
        let used = wrapped_rows(&words, area.width);
        let [top, map] =
            Layout::vertical([Constraint::Length(used), Constraint::Min(0)]).areas(area);
        paragraph(words.into_iter().map(Line::from).collect(), top, buf);
        heat::heat_map(m, m.bins, theme, map, buf);
        return;
    }
    let mut brief = text::merge_brief(m, of);
    if let Some(upto) = upto {
        brief.insert(
            0,
            format!("Example: the highest NMI below 1 of the {upto} merges taken (n p step on):"),
        );
    }
    let [left, map] =
        Layout::horizontal([Constraint::Min(0), Constraint::Length(heat::BESIDE)]).areas(area);
    paragraph(brief.into_iter().map(Line::from).collect(), left, buf);
    heat::heat_map(m, m.bins, theme, map, buf);
}

#[cfg(test)]
mod tests {
    use super::picked_rays;

    #[test]
    fn the_lessons_ray_shows_on_one_row_only() {
        for n in 1..40 {
            for rows in 1..=n {
                for s in 0..n {
                    let picked = picked_rays(n, rows, Some(s));
                    let marked = picked.iter().filter(|&&r| r == s).count();
                    assert_eq!(marked, 1, "ray {s} of {n} on {rows} rows: {picked:?}");
                }
            }
        }
    }
}
