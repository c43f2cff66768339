//! The preview pane: the exploded view from the ray caster, as an inline image.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::widgets::{Paragraph, Widget, Wrap};
use ratatui_image::Image;
use ratatui_image::protocol::Protocol;
use slabscope::render::{Gap, Mode};

use crate::tui::event::{Load, Look};
use crate::tui::theme::Theme;

/// The preview pane's state.
pub struct PreviewPane {
    /// Camera, gaps and colours.
    pub look: Look,
    /// The image, encoded for the terminal.
    pub image: Load<Box<Protocol>>,
    /// The image's size in cells.
    pub cells: (u16, u16),
    /// The newest render request; only its result is shown.
    pub generation: u64,
    /// Whether it has the focus.
    pub focused: bool,
    /// Colours.
    pub theme: Theme,
}

impl PreviewPane {
    /// An empty pane.
    pub fn new(theme: Theme) -> Self {
        Self {
            look: Look::default(),
            image: Load::Idle,
            cells: (0, 0),
            generation: 0,
            focused: false,
            theme,
        }
    }

    /// The title: what the picture shows and how.
    fn title(&self) -> String {
        let l = &self.look;
        format!(
            " Exploded view: {} {} {}, spread {:.1}, {} gaps, az {:.0}° el {:.0}°{} ",
            if l.mode == Mode::Dvr { "DVR" } else { "MIP" },
            l.preset.name(),
            l.colormap.name(),
            l.spread,
            if l.gap == Gap::Similarity {
                "similarity"
            } else {
                "uniform"
            },
            l.camera.azimuth,
            l.camera.elevation,
            if l.solo { ", selected slab alone" } else { "" }
        )
    }
}

impl Widget for &PreviewPane {
    fn render(self, area: Rect, buf: &mut Buffer) {
        let block = self.theme.block(self.title(), self.focused);
        let inner = block.inner(area);
        block.render(area, buf);
        match &self.image {
            Load::Ready(protocol) => Image::new(protocol).render(inner, buf),
            Load::Running(_) => Paragraph::new("rendering…").render(inner, buf),
            Load::Failed(e) => Paragraph::new(format!("render failed: {e}"))
                .wrap(Wrap { trim: true })
                .render(inner, buf),
            Load::Idle => {}
        }
    }
}
