//! The two status lines: what the last step did (or a prompt or message), and where we are.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::{Color, Modifier};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Paragraph, Widget};
use slabscope::partition::Method;
use slabscope::volume::background::BackgroundRule;
use slabscope::{AnalysisParams, Progress};

use crate::tui::event::Ask;
use crate::tui::theme::Theme;

/// A line of text being typed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Prompt {
    /// What it asks for.
    pub ask: Ask,
    /// What has been typed.
    pub text: String,
}

/// The status lines' state.
pub struct StatusBar {
    /// A prompt being typed.
    pub prompt: Option<Prompt>,
    /// The last message for the user.
    pub message: Option<String>,
    /// What the last step did.
    pub explanation: Option<String>,
    /// The method.
    pub method: Method,
    /// Position, slab count and threshold.
    pub position: Option<String>,
    /// Background work under way, each with its progress.
    pub jobs: Vec<(&'static str, Progress)>,
    /// The analysis settings, short.
    pub settings: String,
    /// What the user should know about the terminal (how to let images through tmux), shown
    /// for as long as it holds.
    pub notice: Option<String>,
    /// Which of a folder's volumes is open (`2/12 name`).
    pub volume: Option<String>,
    /// What is shown is a preview: at which resolution (`preview: 1/4 resolution`).
    pub resolution: Option<String>,
    /// Colours.
    pub theme: Theme,
}

impl StatusBar {
    /// Empty lines, with the settings of `params`.
    pub fn new(params: &AnalysisParams, theme: Theme) -> Self {
        Self {
            prompt: None,
            message: None,
            explanation: None,
            method: params.method,
            position: None,
            jobs: Vec::new(),
            settings: settings_text(params),
            notice: None,
            volume: None,
            resolution: None,
            theme,
        }
    }

    fn first_line(&self) -> Line<'static> {
        if let Some(p) = &self.prompt {
            let what = match p.ask {
                Ask::Axis => "axis (x, y, z or DX,DY,DZ)",
                Ask::Threshold => "threshold (empty clears)",
                Ask::Find => "find a volume by name",
                Ask::Manifest => "write the marked volumes as a manifest to",
                Ask::Overwrite => "that file exists: Enter replaces it, or another name",
            };
            Line::from(vec![
                Span::styled(format!("{what}> "), self.theme.fg(Color::Cyan)),
                Span::raw(format!("{}█", p.text)),
            ])
        } else if let Some(m) = &self.message {
            // A note or an error may quote a file's metadata: nothing of it drawn raw.
            let m = slabscope::error::names::controls(m).into_owned();
            Line::from(Span::styled(m, self.theme.fg(Color::Yellow)))
        } else if let Some(e) = &self.explanation {
            Line::from(Span::styled(e.clone(), self.theme.fg(Color::Green)))
        } else {
            Line::from("")
        }
    }

    fn second_line(&self, width: u16) -> Line<'static> {
        let method = match self.method {
            Method::TopDown => "top-down",
            Method::BottomUp => "bottom-up",
            Method::Optimal => "optimal",
        };
        let mut parts = vec![Span::styled(
            format!(" {method} "),
            self.theme.selected().add_modifier(Modifier::BOLD),
        )];
        if let Some(v) = &self.volume {
            parts.push(Span::styled(format!(" {v} "), self.theme.fg(Color::Green)));
        }
        if let Some(r) = &self.resolution {
            parts.push(Span::styled(
                format!(" {r} "),
                self.theme.fg(Color::Yellow).add_modifier(Modifier::BOLD),
            ));
        }
        if let Some(p) = &self.position {
            parts.push(Span::raw(format!(" {p} ")));
        }
        for (job, p) in &self.jobs {
            let text = format!(" {job}: {} {:.0}% ", p.phase, p.fraction * 100.0);
            parts.push(Span::styled(text, self.theme.fg(Color::Cyan)));
        }
        if let Some(n) = &self.notice {
            parts.push(Span::styled(format!(" {n} "), self.theme.fg(Color::Yellow)));
        }
        if width >= 100 {
            parts.push(Span::styled(
                format!(" {} ", self.settings),
                self.theme.fg(Color::DarkGray),
            ));
        }
        let hints = if width >= 140 {
            " n/p step  +/- slabs  m method  Tab pane  ? help  q quit"
        } else {
            " n/p  +/-  m  ? help  q quit"
        };
        parts.push(Span::styled(hints, self.theme.fg(Color::DarkGray)));
        Line::from(parts)
    }
}

/// `32 bins, L 3, level 1`, with the phases, spacings and background when set.
pub fn settings_text(p: &AnalysisParams) -> String {
    let v = &p.view;
    let mut parts = vec![
        format!("{} bins", v.sampling.bins),
        format!("L {}", v.block),
        format!("level {}", v.level),
    ];
    if v.phases > 0 {
        parts.push(format!("phases {}", v.phases));
    }
    if let Some(x) = v.sampling.ray_spacing {
        parts.push(format!("rays {x} mm"));
    }
    if let Some(y) = v.sampling.sample_spacing {
        parts.push(format!("samples {y} mm"));
    }
    parts.push(match p.background {
        BackgroundRule::Auto => "background auto".into(),
        BackgroundRule::None => "background none".into(),
        BackgroundRule::Below(v) => format!("background ≤ {v}"),
    });
    parts.join(", ")
}

impl Widget for &StatusBar {
    fn render(self, area: Rect, buf: &mut Buffer) {
        Paragraph::new(vec![self.first_line(), self.second_line(area.width)]).render(area, buf);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_message_quoting_metadata_is_drawn_escaped() {
        let mut bar = StatusBar::new(&AnalysisParams::default(), Theme::default());
        let hostile = "axes z\u{1b}]0;pwned\u{7}\u{202e}\u{9b}\u{7f} have no known length unit";
        bar.message = Some(hostile.into());
        let mut buf = Buffer::empty(Rect::new(0, 0, 160, 2));
        (&bar).render(Rect::new(0, 0, 160, 2), &mut buf);
        let drawn: String = buf
            .content()
            .iter()
            .map(ratatui::buffer::Cell::symbol)
            .collect();
        assert!(
            drawn.contains("z\\u{1b}]0;pwned\\u{7}\\u{202e}\\u{9b}\\u{7f} have"),
            "{drawn}"
        );
        assert!(!drawn.chars().any(|c| c.is_control() || c == '\u{202e}'));
    }
}
