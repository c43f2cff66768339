//! What the terminal can do, shared by the TUI and `preview`: the image protocol to speak.

use clap::ValueEnum;

/// How images reach the terminal.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Protocol {
    /// Detect kitty, iTerm2 or sixel support; else half-blocks.
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
