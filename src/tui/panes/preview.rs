//! The preview pane: the exploded view from the ray caster, as an inline image.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::widgets::{Paragraph, Widget, Wrap};
use ratatui_image::Image;
use slabscope::render::Mode;

use crate::tui::app::{App, Load};
use crate::tui::ui::Theme;

/// The preview pane.
pub struct PreviewPane<'a> {
    /// The state.
    pub app: &'a App,
    /// Colours.
    pub theme: Theme,
    /// Whether it has the focus.
    pub focused: bool,
}

impl Widget for PreviewPane<'_> {
    fn render(self, area: Rect, buf: &mut Buffer) {
        let l = &self.app.look;
        let title = format!(
            " Exploded view: {} {} {}, spread {:.1}, {} gaps, az {:.0}° el {:.0}°{} ",
            if l.mode == Mode::Dvr { "DVR" } else { "MIP" },
            l.preset.name(),
            l.colormap.name(),
            l.spread,
            if l.gap == slabscope::render::Gap::Similarity {
                "similarity"
            } else {
                "uniform"
            },
            l.camera.azimuth,
            l.camera.elevation,
            if l.solo { ", selected slab alone" } else { "" }
        );
        let block = self.theme.block(title, self.focused);
        let inner = block.inner(area);
        block.render(area, buf);
        match &self.app.preview {
            Load::Ready(protocol) => Image::new(protocol).render(inner, buf),
            Load::Running(_) => Paragraph::new("rendering…").render(inner, buf),
            Load::Failed(e) => Paragraph::new(format!("render failed: {e}"))
                .wrap(Wrap { trim: true })
                .render(inner, buf),
            Load::Idle => Paragraph::new("").render(inner, buf),
        }
    }
}
