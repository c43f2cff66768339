//! The screen layout and drawing: a pure function of the app's state.

use ratatui::Frame;
use ratatui::layout::{Alignment, Constraint, Direction, Layout, Rect};
use ratatui::widgets::{Block, Borders, Paragraph, Wrap};

use super::app::App;
use super::panes;

/// The smallest terminal the layout works in.
pub const MIN_SIZE: (u16, u16) = (60, 18);

/// Where each pane goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Areas {
    /// Viewpoints.
    pub views: Rect,
    /// Slabs.
    pub slabs: Rect,
    /// Curves.
    pub curves: Rect,
    /// Preview.
    pub preview: Rect,
    /// The two status lines.
    pub status: Rect,
    /// The tour's page, above the status lines (no rows outside a tour).
    pub tour: Rect,
    /// A folder's volumes, below the panes (no rows without a folder).
    pub files: Rect,
}

/// The layout of a screen of size `area` (with room for the tour's page when `tour`, and for
/// the pane of a folder of `folder` volumes below the others), or `None` when it is too small.
pub fn areas(area: Rect, tour: bool, folder: Option<usize>) -> Option<Areas> {
    if area.width < MIN_SIZE.0 || area.height < MIN_SIZE.1 {
        return None;
    }
    let page = match (tour, area.height) {
        (false, _) => 0,
        (true, ..36) => 6,
        (true, _) => 8,
    };
    let files = folder.map_or(0, |n| {
        panes::files::height(n, area.height.saturating_sub(page + 2))
    });
    let [body, files, tour, status] = Layout::vertical([
        Constraint::Min(0),
        Constraint::Length(files),
        Constraint::Length(page),
        Constraint::Length(2),
    ])
    .areas(area);
    let [top, bottom] =
        Layout::vertical([Constraint::Percentage(56), Constraint::Percentage(44)]).areas(body);
    let left = if area.width >= 140 { 34 } else { 42 };
    let [views, preview] = Layout::horizontal([
        Constraint::Percentage(left),
        Constraint::Percentage(100 - left),
    ])
    .areas(top);
    let [slabs, curves] = Layout::new(
        Direction::Horizontal,
        [
            Constraint::Percentage(left),
            Constraint::Percentage(100 - left),
        ],
    )
    .areas(bottom);
    Some(Areas {
        views,
        slabs,
        curves,
        preview,
        status,
        tour,
        files,
    })
}

/// `a` with the preview over the four panes (the tour's last page, the exploded view large):
/// the others get no cells.
pub fn enlarged(a: Areas) -> Areas {
    let none = |r: Rect| Rect::new(r.x, r.y, 0, 0);
    Areas {
        preview: a.views.union(a.preview).union(a.slabs).union(a.curves),
        views: none(a.views),
        slabs: none(a.slabs),
        curves: none(a.curves),
        ..a
    }
}

/// The folder's volumes when `app`'s pane of them shows: how many.
pub fn folder(app: &App) -> Option<usize> {
    app.files
        .as_ref()
        .filter(|f| f.shown)
        .map(|f| f.paths.len())
}

/// The cells the preview image fills, for a screen of size `area` (and the tour's page, and a
/// folder's pane of `folder` volumes), over the four panes when `large`.
pub fn preview_cells(
    area: Rect,
    tour: bool,
    folder: Option<usize>,
    large: bool,
) -> Option<(u16, u16)> {
    let a = areas(area, tour, folder)?;
    let a = if large { enlarged(a) } else { a };
    let inner = Block::default().borders(Borders::ALL).inner(a.preview);
    Some((inner.width, inner.height))
}

/// Draws the whole screen.
pub fn draw(frame: &mut Frame, app: &App) {
    let area = frame.area();
    frame.render_widget(Block::default().style(app.theme.base()), area);
    let Some(mut a) = areas(area, app.tour.is_some(), folder(app)) else {
        let text = format!(
            "The terminal is {}x{}: slabscope needs at least {}x{}. Enlarge it, or press q to quit.",
            area.width, area.height, MIN_SIZE.0, MIN_SIZE.1
        );
        frame.render_widget(
            Paragraph::new(text)
                .wrap(Wrap { trim: true })
                .alignment(Alignment::Center),
            area,
        );
        return;
    };
    let large = app.preview_large();
    if large {
        a = enlarged(a);
    } else {
        frame.render_widget(&app.views, a.views);
        frame.render_widget(&app.slabs, a.slabs);
        frame.render_widget(&app.curves, a.curves);
    }
    frame.render_widget(&app.preview, a.preview);
    frame.render_widget(&app.status, a.status);
    if app.lesson.open {
        let body = Rect {
            height: area.height - a.status.height - a.tour.height - a.files.height,
            ..area
        };
        frame.render_widget(&app.lesson, body);
    }
    // A figure the terminal draws as an image is the preview's picture.
    let image = app.figure_as_image();
    if let Some(board) = app
        .board()
        .filter(|b| !(app.lesson.open || image && b.is_figure()))
    {
        // A worked example's lines want the width of the row; a figure sits beside the list.
        let place = if board.is_figure() {
            a.preview
        } else {
            a.views.union(a.preview)
        };
        frame.render_widget(&board, place);
    }
    if let Some(tour) = &app.tour {
        frame.render_widget(
            panes::tour::TourPage {
                tour,
                theme: app.theme,
            },
            a.tour,
        );
    }
    match app.files.as_ref() {
        Some(files) if files.shown => frame.render_widget(files, a.files),
        // kitty's thumbnails are a layer of their own: taken away with the pane.
        Some(files) => {
            if let Some(t) = files.thumbs.as_ref().filter(|t| !t.hide.is_empty()) {
                crate::term::image::hide(&t.hide, a.status, frame.buffer_mut());
            }
        }
        None => {}
    }
    if app.help {
        frame.render_widget(&panes::help::Help { theme: app.theme }, area);
    }
}
