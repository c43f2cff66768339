//! Colours, or none when `NO_COLOR` is set, or the high-contrast theme for projectors
//! (`--theme contrast`: every text colour at least 7:1 against its black background): the one
//! place the TUI's styles come from.

use clap::ValueEnum;
use ratatui::style::{Color, Modifier, Style};
use ratatui::widgets::{Block, Borders};

/// The TUI's styles.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Theme {
    /// Whether to use colours.
    pub color: bool,
    /// The high-contrast colours (with colours on).
    pub contrast: bool,
}

/// The themes `--theme` names.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum ThemeChoice {
    /// The terminal's own colours with the TUI's accents.
    #[default]
    Default,
    /// White and bright colours on black, every text colour at least 7:1 (WCAG AAA), for
    /// projectors and low vision.
    Contrast,
}

/// The contrast theme's background.
const BLACK: Color = Color::Rgb(0, 0, 0);

impl Theme {
    /// From the environment: no colours when `NO_COLOR` is set and not empty.
    pub fn from_env() -> Self {
        Self {
            color: std::env::var_os("NO_COLOR").is_none_or(|v| v.is_empty()),
            contrast: false,
        }
    }

    /// This theme, high-contrast when `choice` asks for it.
    #[must_use]
    pub fn with(self, choice: ThemeChoice) -> Self {
        Self {
            contrast: choice == ThemeChoice::Contrast,
            ..self
        }
    }

    fn high(self) -> bool {
        self.color && self.contrast
    }

    /// `style` with foreground `c`, or plain without colours.
    pub fn fg(self, c: Color) -> Style {
        if self.high() {
            Style::default().fg(high_contrast(c)).bg(BLACK)
        } else if self.color {
            Style::default().fg(c)
        } else {
            Style::default()
        }
    }

    /// The style everything is drawn over: white on black in the contrast theme, else the
    /// terminal's own.
    pub fn base(self) -> Style {
        if self.high() {
            Style::default().fg(Color::Rgb(255, 255, 255)).bg(BLACK)
        } else {
            Style::default()
        }
    }

    /// The style of something selected: reversed (and bold with colours).
    pub fn selected(self) -> Style {
        let reversed = Style::default().add_modifier(Modifier::REVERSED);
        if self.color {
            reversed.add_modifier(Modifier::BOLD)
        } else {
            reversed
        }
    }

    /// A pane's frame, brighter when focused.
    pub fn block(self, title: String, focused: bool) -> Block<'static> {
        let style = if focused {
            self.fg(Color::Cyan).add_modifier(Modifier::BOLD)
        } else {
            self.fg(Color::DarkGray)
        };
        Block::default()
            .borders(Borders::ALL)
            .border_style(style)
            .title(title)
    }
}

/// The contrast theme's colour in place of `c`: white for the greys, bright and light tints
/// of the others, each at least 7:1 against black.
pub fn high_contrast(c: Color) -> Color {
    match c {
        Color::Red | Color::LightRed => Color::Rgb(255, 128, 128),
        Color::Green | Color::LightGreen => Color::Rgb(0, 255, 0),
        Color::Yellow | Color::LightYellow => Color::Rgb(255, 255, 0),
        Color::Blue | Color::LightBlue => Color::Rgb(160, 160, 255),
        Color::Magenta | Color::LightMagenta => Color::Rgb(255, 128, 255),
        Color::Cyan | Color::LightCyan => Color::Rgb(0, 255, 255),
        Color::Rgb(r, g, b) if contrast_ratio((r, g, b), (0, 0, 0)) >= 7.0 => c,
        _ => Color::Rgb(255, 255, 255),
    }
}

/// The WCAG contrast ratio of two sRGB colours, 1 to 21.
pub fn contrast_ratio(a: (u8, u8, u8), b: (u8, u8, u8)) -> f64 {
    let luminance = |(r, g, b): (u8, u8, u8)| {
        let lin = |c: u8| {
            let c = f64::from(c) / 255.0;
            if c <= 0.039_28 {
                c / 12.92
            } else {
                ((c + 0.055) / 1.055).powf(2.4)
            }
        };
        0.2126 * lin(r) + 0.7152 * lin(g) + 0.0722 * lin(b)
    };
    let (la, lb) = (luminance(a), luminance(b));
    (la.max(lb) + 0.05) / (la.min(lb) + 0.05)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_contrast_theme_keeps_every_colour_at_seven_to_one() {
        assert!((contrast_ratio((255, 255, 255), (0, 0, 0)) - 21.0).abs() < 1e-9);
        assert!((contrast_ratio((0, 0, 0), (0, 0, 0)) - 1.0).abs() < 1e-9);
        let theme = Theme {
            color: true,
            contrast: true,
        };
        let named = [
            Color::Reset,
            Color::Black,
            Color::Red,
            Color::Green,
            Color::Yellow,
            Color::Blue,
            Color::Magenta,
            Color::Cyan,
            Color::Gray,
            Color::DarkGray,
            Color::LightRed,
            Color::LightGreen,
            Color::LightYellow,
            Color::LightBlue,
            Color::LightMagenta,
            Color::LightCyan,
            Color::White,
            Color::Rgb(40, 40, 60),
            Color::Rgb(250, 250, 250),
        ];
        let rgb = |c: Color| match c {
            Color::Rgb(r, g, b) => (r, g, b),
            other => panic!("{other:?} is not an exact colour"),
        };
        for c in named {
            let style = theme.fg(c);
            let (fg, bg) = (rgb(style.fg.unwrap()), rgb(style.bg.unwrap()));
            let ratio = contrast_ratio(fg, bg);
            assert!(ratio >= 7.0, "{c:?}: {fg:?} on {bg:?} is {ratio:.2}:1");
        }
        let base = theme.base();
        assert!(contrast_ratio(rgb(base.fg.unwrap()), rgb(base.bg.unwrap())) >= 7.0);
        // Without colours, the contrast theme is plain too.
        let plain = Theme {
            color: false,
            contrast: true,
        };
        assert_eq!(plain.fg(Color::Red), Style::default());
    }
}
