//! What the terminal can do, shared by the TUI and `preview`: which image protocol to speak, the
//! size of a cell in pixels, the largest sixel image, tmux. Detection is one synchronous query
//! in raw mode before any UI starts ([`query`]); the choice from its replies is a pure function
//! ([`choose`]), tested against replies recorded from real terminals. [`image`] encodes and
//! places images.

pub mod image;
pub mod query;
pub mod tmux;

use std::io::{self, IsTerminal, Write};
use std::os::fd::{AsFd, BorrowedFd, OwnedFd};
use std::time::Duration;

use clap::ValueEnum;
use query::Replies;
use tmux::Passthrough;

/// How images reach the terminal, as the user asks for it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Protocol {
    /// Ask the terminal: kitty, iTerm2 or sixel where it speaks them, else half-blocks.
    Auto,
    /// The kitty graphics protocol.
    Kitty,
    /// iTerm2 inline images.
    Iterm,
    /// Sixel graphics.
    Sixel,
    /// Unicode half-blocks with colours: works everywhere.
    Blocks,
}

impl Protocol {
    /// The protocol a name gives (as `--protocol` and `SLABSCOPE_PROTOCOL` spell it).
    pub fn from_name(name: &str) -> Option<Self> {
        <Self as ValueEnum>::from_str(name.trim(), true).ok()
    }
}

/// How images are drawn, once decided.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Graphics {
    /// Half-blocks: two pixels a cell, in colour.
    Blocks,
    /// Sixel images.
    Sixel,
    /// iTerm2 inline images.
    Iterm,
    /// kitty images placed at the cursor (every kitty version has them).
    Kitty,
}

impl Graphics {
    /// The name shown to the user.
    pub fn name(self) -> &'static str {
        match self {
            Self::Blocks => "half-blocks",
            Self::Sixel => "sixel",
            Self::Iterm => "iTerm2",
            Self::Kitty => "kitty",
        }
    }
}

/// The environment variables that say something about the terminal.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Env {
    /// `TERM`.
    pub term: String,
    /// `TERM_PROGRAM`, or `LC_TERMINAL` (which SSH forwards by default) when that is empty.
    pub program: String,
    /// `$TMUX` is set: slabscope runs inside tmux.
    pub tmux: bool,
    /// `SLABSCOPE_PROTOCOL`.
    pub protocol: Option<String>,
}

impl Env {
    /// The current process's environment.
    pub fn current() -> Self {
        let var = |k: &str| std::env::var(k).unwrap_or_default();
        let program = match var("TERM_PROGRAM") {
            p if p.is_empty() => var("LC_TERMINAL"),
            p => p,
        };
        Self {
            term: var("TERM"),
            program,
            tmux: !var("TMUX").is_empty(),
            protocol: std::env::var("SLABSCOPE_PROTOCOL")
                .ok()
                .filter(|p| !p.is_empty()),
        }
    }
}

/// What the terminal can do.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Caps {
    /// How images are drawn.
    pub graphics: Graphics,
    /// A cell's size in pixels, `(width, height)`.
    pub cell: (u16, u16),
    /// The largest image the terminal takes, pixels (sixel's XTSMGRAPHICS geometry).
    pub max_image: Option<(u32, u32)>,
    /// Sixel colour registers.
    pub colors: u16,
    /// The emulator and its version, when it says (XTVERSION).
    pub emulator: Option<String>,
    /// Image sequences go through tmux's passthrough.
    pub tmux: bool,
    /// Something the user should know, e.g. how to let images through tmux.
    pub note: Option<String>,
    /// Keys typed while the terminal was asked (printable characters and Ctrl-C).
    pub typed: String,
}

/// The cell size assumed when the terminal does not say.
const DEFAULT_CELL: (u16, u16) = (8, 16);

impl Caps {
    /// Half-blocks with the default cell size.
    #[cfg(test)]
    pub fn blocks() -> Self {
        Self {
            graphics: Graphics::Blocks,
            cell: DEFAULT_CELL,
            max_image: None,
            colors: 256,
            emulator: None,
            tmux: false,
            note: None,
            typed: String::new(),
        }
    }

    /// The image size in pixels for an area of `cells`: one image pixel per screen pixel (two
    /// a cell for half-blocks), scaled down, keeping the area's aspect, to fit the largest image
    /// the terminal takes.
    pub fn image_size(&self, (cols, rows): (u16, u16)) -> (u32, u32) {
        if self.graphics == Graphics::Blocks {
            return (u32::from(cols), 2 * u32::from(rows));
        }
        let (w, h) = (
            u32::from(cols) * u32::from(self.cell.0),
            u32::from(rows) * u32::from(self.cell.1),
        );
        let Some((mw, mh)) = self.max_image.filter(|&(mw, mh)| mw > 0 && mh > 0) else {
            return (w.max(1), h.max(1));
        };
        let scale = (f64::from(mw) / f64::from(w.max(1)))
            .min(f64::from(mh) / f64::from(h.max(1)))
            .min(1.0);
        (
            ((f64::from(w) * scale) as u32).max(1),
            ((f64::from(h) * scale) as u32).max(1),
        )
    }
}

/// The emulator's name from an XTVERSION reply such as `kitty(0.26.5)` or `tmux 3.3a`.
fn emulator_name(reply: &str) -> String {
    reply
        .split(['(', ' '])
        .next()
        .unwrap_or(reply)
        .to_ascii_lowercase()
}

/// Chooses the graphics and sizes from what the terminal said (`replies`, `None` when it was not
/// asked), the environment, tmux's passthrough and the tty's own pixel size for `cells`.
pub fn choose(
    choice: Protocol,
    env: &Env,
    passthrough: Option<Passthrough>,
    replies: Option<&Replies>,
    tty_pixels: Option<((u16, u16), (u16, u16))>,
) -> Caps {
    let mut notes = Vec::new();
    let choice = match (choice, &env.protocol) {
        (Protocol::Auto, Some(name)) => Protocol::from_name(name).unwrap_or_else(|| {
            notes.push(format!(
                "SLABSCOPE_PROTOCOL={name:?} is not auto, kitty, iterm, sixel or blocks"
            ));
            Protocol::Auto
        }),
        (c, _) => c,
    };
    let empty = Replies::default();
    let r = replies.unwrap_or(&empty);
    let emulator = r.version.clone();
    let name = emulator.as_deref().map(emulator_name).unwrap_or_default();
    let program = env.program.to_ascii_lowercase();
    let iterm = ["iterm", "wezterm"]
        .iter()
        .any(|p| name.contains(p) || program.contains(p));
    let graphics = match choice {
        Protocol::Kitty => Graphics::Kitty,
        Protocol::Iterm => Graphics::Iterm,
        Protocol::Sixel => Graphics::Sixel,
        Protocol::Auto if passthrough == Some(Passthrough::Off) => Graphics::Blocks,
        Protocol::Auto if r.kitty_graphics => Graphics::Kitty,
        Protocol::Auto if iterm => Graphics::Iterm,
        Protocol::Auto if r.sixel() => Graphics::Sixel,
        // No answer at all: what the environment says, else half-blocks.
        Protocol::Auto if replies.is_none() && env.term == "xterm-kitty" => Graphics::Kitty,
        Protocol::Auto | Protocol::Blocks => Graphics::Blocks,
    };
    // Said only when the images were asked of the terminal: one who chose a protocol chose it.
    if passthrough == Some(Passthrough::Off) && choice == Protocol::Auto {
        notes.push(format!(
            "tmux keeps images from the terminal: `{}` lets them through (then restart slabscope)",
            tmux::ENABLE
        ));
    }
    let cell = cell_size(r, passthrough.is_some(), tty_pixels);
    if cell.is_none() && graphics != Graphics::Blocks {
        notes.push("the terminal does not say its cell size: assuming 8x16 pixels".into());
    }
    Caps {
        graphics,
        cell: cell.unwrap_or(DEFAULT_CELL),
        max_image: r.sixel_geometry.filter(|_| graphics == Graphics::Sixel),
        colors: r.sixel_colors.unwrap_or(256).clamp(2, 256),
        emulator,
        tmux: passthrough.is_some(),
        note: (!notes.is_empty()).then(|| notes.join("; ")),
        typed: r.typed.clone(),
    }
}

/// A cell's size: as the terminal says it (`CSI 16 t`), else the tty's pixel size over its cells,
/// else (outside tmux, where the window is the terminal's) the window's pixels over the cells.
fn cell_size(
    r: &Replies,
    tmux: bool,
    tty_pixels: Option<((u16, u16), (u16, u16))>,
) -> Option<(u16, u16)> {
    let per_cell = |(pw, ph): (u16, u16), (cols, rows): (u16, u16)| {
        (pw > 0 && ph > 0 && cols > 0 && rows > 0).then(|| (pw / cols, ph / rows))
    };
    r.cell
        .filter(|&(w, h)| w > 0 && h > 0)
        .or_else(|| tty_pixels.and_then(|(px, cells)| per_cell(px, cells)))
        .or_else(|| {
            let cells = tty_pixels.map(|(_, c)| c)?;
            r.window
                .filter(|_| !tmux)
                .and_then(|px| per_cell(px, cells))
        })
        .filter(|&(w, h)| w > 0 && h > 0)
}

/// The terminal's input: stdin when it is a terminal, else `/dev/tty`.
pub fn tty_input() -> io::Result<OwnedFd> {
    let stdin = io::stdin();
    if stdin.is_terminal() {
        return stdin.as_fd().try_clone_to_owned();
    }
    Ok(std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open("/dev/tty")?
        .into())
}

/// The tty's size in pixels and cells, when it knows it.
fn tty_pixels(fd: BorrowedFd) -> Option<((u16, u16), (u16, u16))> {
    let ws = rustix::termios::tcgetwinsize(fd).ok()?;
    Some(((ws.ws_xpixel, ws.ws_ypixel), (ws.ws_col, ws.ws_row)))
}

/// How long the terminal may take to answer (over SSH, a round trip).
pub const QUERY_TIMEOUT: Duration = Duration::from_millis(800);

/// Finds out what the terminal can do. The terminal must already be in raw mode (the TUI stays
/// in it; `preview` leaves it after); nothing is queried when `choice` names a protocol, except
/// the sizes, which come from the tty and, for sixel, from the terminal.
pub fn detect(choice: Protocol, output: &mut impl Write) -> io::Result<Caps> {
    let env = Env::current();
    let input = tty_input()?;
    let passthrough = env.tmux.then(Passthrough::ask);
    let can_ask = passthrough != Some(Passthrough::Off);
    let must_ask = matches!(choice, Protocol::Auto | Protocol::Sixel | Protocol::Kitty);
    let replies = if can_ask && must_ask {
        Some(query::ask(
            &input,
            output,
            passthrough.is_some(),
            QUERY_TIMEOUT,
        )?)
    } else {
        None
    };
    Ok(choose(
        choice,
        &env,
        passthrough,
        replies.as_ref(),
        tty_pixels(input.as_fd()),
    ))
}

#[cfg(test)]
mod tests;
