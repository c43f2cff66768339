//! The preview pane: the exploded view from the ray caster, as an inline image.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::widgets::{Paragraph, Widget, Wrap};
use slabscope::render::{Gap, Mode};

use crate::term::image::{TermImage, hide};
use crate::tui::event::{PictureSettings, Task};
use crate::tui::theme::Theme;

/// The preview pane's state.
pub struct PreviewPane {
    /// Camera, gaps and colours.
    pub look: PictureSettings,
    /// The image, encoded for the terminal.
    pub image: Task<Box<TermImage>>,
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
    /// The slice view instead of the exploded view.
    pub slices: bool,
    /// The slice view's pointer, a physical point (`None`: the volume's centre).
    pub pointer: Option<[f64; 3]>,
    /// What the slice view reads at its pointer, shown on the bottom border.
    pub caption: Option<String>,
    /// The colour window the last picture used.
    pub window: Option<(f32, f32)>,
    /// The title of the tour's figure the picture shows instead of the exploded view.
    pub figure: Option<String>,
    /// Colours.
    pub theme: Theme,
}

impl PreviewPane {
    /// Whether the terminal draws images (sixel, kitty, iTerm2), not half-blocks.
    pub fn draws_images(&self) -> bool {
        !matches!(self.graphics, "" | "half-blocks")
    }

    /// An empty pane.
    pub fn new(theme: Theme) -> Self {
        Self {
            look: PictureSettings::default(),
            image: Task::Idle,
            covered: false,
            hide: String::new(),
            graphics: "",
            cells: (0, 0),
            generation: 0,
            focused: false,
            slices: false,
            pointer: None,
            caption: None,
            window: None,
            figure: None,
            theme,
        }
    }

    /// The title: what the picture shows and how.
    fn title(&self) -> String {
        if let Some(figure) = &self.figure {
            return figure.clone();
        }
        let l = &self.look;
        let bytes = match &self.image {
            Task::Ready(i) if !self.graphics.is_empty() => {
                format!(" [{} {} KB]", self.graphics, i.bytes.div_ceil(1024))
            }
            _ => String::new(),
        };
        let window = l
            .window
            .map(|(lo, hi)| format!(", window {} .. {}", short(lo), short(hi)))
            .unwrap_or_default();
        if self.slices {
            return format!(
                " Slices: the slice at the cursor, the selected slab's faces (v: exploded \
                 view), {} {}{window}{bytes} ",
                l.preset.name(),
                l.colormap.name()
            );
        }
        format!(
            " Exploded view: {} {} {}{window}, spread {:.1}, {} gaps, az {:.0}° el {:.0}°{}{bytes} ",
            match l.mode {
                Mode::Cut => "cut faces",
                Mode::Dvr => "DVR",
                Mode::Mip => "MIP",
            },
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

/// A window bound in few characters.
fn short(v: f32) -> String {
    if v.abs() >= 100.0 || v == v.round() {
        format!("{v:.0}")
    } else {
        format!("{v:.3}")
    }
}

impl Widget for &PreviewPane {
    fn render(self, area: Rect, buf: &mut Buffer) {
        let mut block = self.theme.block(self.title(), self.focused);
        // The readout goes on the bottom border, so that the picture keeps its place.
        if let Some(caption) = self.caption.as_ref().filter(|_| self.slices) {
            block = block.title_bottom(format!(" {caption} "));
        }
        let inner = block.inner(area);
        block.render(area, buf);
        match &self.image {
            Task::Ready(_) if self.covered => hide(&self.hide, inner, buf),
            Task::Ready(image) => image.as_ref().render(inner, buf),
            Task::Running(_) => Paragraph::new("rendering…").render(inner, buf),
            Task::Failed(e) => Paragraph::new(format!("render failed: {e}"))
                .wrap(Wrap { trim: true })
                .render(inner, buf),
            Task::Idle => {}
        }
    }
}
