//! What a tour page draws in the exploded view's place: the paper's Fig. 1a (the viewpoint
//! sphere) and Fig. 1b (rays from a viewpoint's plane) in braille from the library's drawings,
//! or a worked example's lines, every number the library's.

use ratatui::buffer::Buffer;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::Color;
use ratatui::symbols::Marker;
use ratatui::text::{Line, Span};
use ratatui::widgets::canvas::{Canvas, Context, Line as Stroke};
use ratatui::widgets::{Paragraph, Widget, Wrap};
use slabscope::explain::figure::{Drawing, Ink, View, rays_figure, sphere_figure};
use slabscope::explain::worked;
use slabscope::geometry::Axis;

use crate::tui::app::tour::Board;
use crate::tui::theme::Theme;

/// A page's board and what it is drawn from.
pub struct BoardPane {
    /// What it shows.
    pub board: Board,
    /// The best axis and the icosphere's level, once the view search is in.
    pub best: Option<([f64; 3], usize)>,
    /// The volume's physical size, once it is loaded.
    pub size: Option<[f64; 3]>,
    /// Colours.
    pub theme: Theme,
}

/// The rows from which the sphere is drawn as a wireframe with its far side.
const WIREFRAME_ROWS: u16 = 14;

/// An ink's colour on the terminal.
fn colour(ink: Ink) -> Color {
    match ink {
        Ink::Outline | Ink::Front | Ink::Plane => Color::Gray,
        Ink::Back | Ink::Hidden => Color::DarkGray,
        Ink::Viewpoint => Color::White,
        Ink::Axis | Ink::Best => Color::Red,
        Ink::Ray => Color::Blue,
        Ink::Sample => Color::Green,
    }
}

impl BoardPane {
    /// Whether it shows one of the paper's figures (else a worked example).
    pub fn is_figure(&self) -> bool {
        matches!(self.board, Board::Sphere | Board::Rays)
    }

    /// The pane's title.
    pub fn title(&self) -> String {
        let axis = self
            .best
            .and_then(|(a, _)| Axis::new(a).ok())
            .map(|a| a.name().map_or_else(|| a.to_string(), str::to_string))
            .map(|a| format!(": best axis {a}"))
            .unwrap_or_default();
        match self.board {
            Board::Sphere => format!(" Fig. 1a, the viewpoint sphere{axis} "),
            Board::Rays => " Fig. 1b: rays from the viewpoint's plane, one ray's samples ".into(),
            Board::Blocks => " Worked example: a ray of five samples (§4) ".into(),
            Board::Js => " Worked example: JS of two histograms (eq. 5, 6) ".into(),
            Board::Nmi => " Worked example: MI and NMI of a 2×2 table (eq. 7, 8) ".into(),
        }
    }

    /// The drawing shown in `rows` rows, `None` for a worked example or before its data is in.
    /// Below [`WIREFRAME_ROWS`] the sphere's wireframe and far side would run together: it is
    /// drawn as its outline, its near viewpoints and the best axis.
    pub fn drawing(&self, rows: u16) -> Option<(Drawing, &'static str)> {
        let view = View::default();
        match self.board {
            Board::Sphere => {
                let (axis, level) = self.best?;
                let mut f = sphere_figure(level, axis, &view);
                if rows < WIREFRAME_ROWS {
                    let far = [Ink::Back, Ink::Hidden, Ink::Front];
                    f.drawing.segments.retain(|s| !far.contains(&s.ink));
                    f.drawing.dots.retain(|d| !far.contains(&d.ink));
                    return Some((
                        f.drawing,
                        "near viewpoints; red: the best axis, its viewpoint",
                    ));
                }
                let legend = "dots: viewpoints (grey behind); red: the best axis and its viewpoint";
                Some((f.drawing, legend))
            }
            Board::Rays => {
                let axis = self.best?.0;
                let across = View::across(axis).unwrap_or(view);
                let across_n = if rows < WIREFRAME_ROWS { 2 } else { 3 };
                let f = rays_figure(self.size?, axis, across_n, 5, &across).ok()?;
                Some((
                    f.drawing,
                    "blue: parallel rays; red: one ray, green: its samples x0 … x4",
                ))
            }
            Board::Blocks | Board::Js | Board::Nmi => None,
        }
    }

    /// The worked example's lines.
    fn lines(&self) -> Vec<String> {
        let w = worked();
        match self.board {
            Board::Blocks => w.ray.lines(),
            Board::Js => w.js.lines(),
            Board::Nmi => w.nmi.lines(),
            Board::Sphere | Board::Rays => Vec::new(),
        }
    }
}

impl Widget for &BoardPane {
    fn render(self, area: Rect, buf: &mut Buffer) {
        ratatui::widgets::Clear.render(area, buf);
        buf.set_style(area, self.theme.base());
        let block = self.theme.block(self.title(), false);
        let inner = block.inner(area);
        block.render(area, buf);
        let Some((drawing, legend)) = self.drawing(inner.height.saturating_sub(1)) else {
            let lines = match self.board {
                Board::Sphere | Board::Rays => vec!["waiting for the view search…".to_string()],
                _ => self.lines(),
            };
            Paragraph::new(lines.into_iter().map(Line::from).collect::<Vec<_>>())
                .wrap(Wrap { trim: false })
                .style(self.theme.base())
                .render(inner, buf);
            return;
        };
        let [picture, words] =
            Layout::vertical([Constraint::Min(1), Constraint::Length(1)]).areas(inner);
        draw(&drawing, self.theme, picture, buf);
        Paragraph::new(legend)
            .style(self.theme.fg(Color::DarkGray))
            .render(words, buf);
    }
}

/// `drawing` in braille over `area`, its extent fitted in with square dots.
pub fn draw(drawing: &Drawing, theme: Theme, area: Rect, buf: &mut Buffer) {
    if area.width < 4 || area.height < 2 {
        return;
    }
    // A braille cell is 2 × 4 dots and about twice as tall as wide: dots are square.
    let (dots_x, dots_y) = (f64::from(area.width) * 2.0, f64::from(area.height) * 4.0);
    let [x0, y0, x1, y1] = drawing.extent;
    let scale = (dots_x / (x1 - x0).max(1e-12)).min(dots_y / (y1 - y0).max(1e-12));
    let (cx, cy) = (f64::midpoint(x0, x1), f64::midpoint(y0, y1));
    let (hx, hy) = (dots_x / scale / 2.0, dots_y / scale / 2.0);
    let ink = |i: Ink| theme.fg(colour(i)).fg.unwrap_or(Color::Reset);
    let mut canvas = Canvas::default()
        .marker(Marker::Braille)
        .x_bounds([cx - hx, cx + hx])
        .y_bounds([cy - hy, cy + hy])
        .paint(|ctx: &mut Context<'_>| {
            // What is behind first, each kind on its own layer so that the nearer one's colour
            // wins a shared cell.
            for group in [
                &[Ink::Back, Ink::Hidden][..],
                &[Ink::Outline, Ink::Front, Ink::Plane, Ink::Ray],
                &[Ink::Axis],
            ] {
                for s in drawing.segments.iter().filter(|s| group.contains(&s.ink)) {
                    ctx.draw(&Stroke::new(
                        s.from[0],
                        s.from[1],
                        s.to[0],
                        s.to[1],
                        ink(s.ink),
                    ));
                }
                ctx.layer();
            }
            // Dots as characters, a braille dot being too small to see: the nearer last.
            for kind in [Ink::Hidden, Ink::Viewpoint, Ink::Sample, Ink::Best] {
                let mark = match kind {
                    Ink::Hidden => "·",
                    Ink::Best => "●",
                    _ => "•",
                };
                for d in drawing.dots.iter().filter(|d| d.ink == kind) {
                    let style = theme.fg(colour(kind));
                    ctx.print(d.at[0], d.at[1], Span::styled(mark, style));
                }
            }
        });
    if let Some(bg) = theme.base().bg {
        canvas = canvas.background_color(bg);
    }
    canvas.render(area, buf);
}
