//! The preview pane: the exploded view from the ray caster, as an inline image.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::widgets::{Paragraph, Widget, Wrap};
use slabscope::render::{Gap, Mode};

use crate::term::image::{TermImage, hide};
use crate::tui::event::{Load, Look};
use crate::tui::theme::Theme;

/// The preview pane's state.
pub struct PreviewPane {
    /// Camera, gaps and colours.
    pub look: Look,
    /// The image, encoded for the terminal.
    pub image: Load<Box<TermImage>>,
    /// Something (the help) covers the pane: the image is taken away until it closes, and
    /// sent again then.
    pub covered: bool,
    /// What takes a drawn image away where it is a layer of its own (kitty).
    pub hide: String,
    /// How images are drawn, in words.
    pub graphics: &'static str,
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
            covered: false,
            hide: String::new(),
            graphics: "",
            cells: (0, 0),
            generation: 0,
            focused: false,
            theme,
        }
    }

    /// The title: what the picture shows and how.
    fn title(&self) -> String {
        let l = &self.look;
        let bytes = match &self.image {
            Load::Ready(i) if !self.graphics.is_empty() => {
                format!(" [{} {} KB]", self.graphics, i.bytes.div_ceil(1024))
            }
            _ => String::new(),
        };
        format!(
            " Exploded view: {} {} {}, spread {:.1}, {} gaps, az {:.0}° el {:.0}°{}{bytes} ",
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
            Load::Ready(_) if self.covered => hide(&self.hide, inner, buf),
            Load::Ready(image) => image.as_ref().render(inner, buf),
            Load::Running(_) => Paragraph::new("rendering…").render(inner, buf),
            Load::Failed(e) => Paragraph::new(format!("render failed: {e}"))
                .wrap(Wrap { trim: true })
                .render(inner, buf),
            Load::Idle => {}
        }
    }
}
