//! tmux between slabscope and the terminal: its passthrough, which carries image sequences to
//! the outer terminal only when `allow-passthrough` is on, and only when every ESC inside is
//! doubled. slabscope never changes tmux's options; it says which one to change.

use std::process::{Command, Stdio};

/// The command that lets images through tmux.
pub const ENABLE: &str = "tmux set -g allow-passthrough on";

/// Wraps `seq` for tmux's passthrough: `ESC P tmux ;`, the sequence with every ESC doubled
/// (so that an inner string terminator does not end the passthrough early), `ESC \`.
pub fn wrap(seq: &str) -> String {
    let mut out = String::with_capacity(seq.len() + seq.len() / 64 + 16);
    out.push_str("\x1bPtmux;");
    for c in seq.chars() {
        if c == '\x1b' {
            out.push('\x1b');
        }
        out.push(c);
    }
    out.push_str("\x1b\\");
    out
}

/// Whether tmux lets sequences through to the outer terminal.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Passthrough {
    /// `allow-passthrough` is `on` or `all` (or tmux is older than 3.3, which always lets
    /// them through).
    Allowed,
    /// `allow-passthrough` is `off`: images cannot reach the terminal.
    Off,
}

impl Passthrough {
    /// Asks the tmux server this process runs under (through `$TMUX`) for the pane's
    /// effective `allow-passthrough`.
    pub fn ask() -> Self {
        let out = Command::new("tmux")
            .args(["show-options", "-Apv", "allow-passthrough"])
            .stdin(Stdio::null())
            .stderr(Stdio::null())
            .output();
        match out {
            Ok(o) if o.status.success() => Self::from_option(&String::from_utf8_lossy(&o.stdout)),
            // An older tmux without the option passes everything through.
            _ => Self::Allowed,
        }
    }

    /// The state `allow-passthrough`'s value gives.
    pub fn from_option(value: &str) -> Self {
        match value.trim() {
            "off" => Self::Off,
            _ => Self::Allowed,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_escape_inside_is_doubled() {
        let sixel = "\x1bPq#0;2;0;0;0~~\x1b\\";
        assert_eq!(
            wrap(sixel),
            "\x1bPtmux;\x1b\x1bPq#0;2;0;0;0~~\x1b\x1b\\\x1b\\",
            "the sixel's own terminator is escaped, so only the last ST ends the passthrough"
        );
        let inner = wrap(sixel);
        let body = &inner["\x1bPtmux;".len()..inner.len() - 2];
        assert!(
            !body.replace("\x1b\x1b", "").contains('\x1b'),
            "no lone ESC inside"
        );
    }

    #[test]
    fn passthrough_follows_the_option() {
        assert_eq!(Passthrough::from_option("off\n"), Passthrough::Off);
        assert_eq!(Passthrough::from_option("on\n"), Passthrough::Allowed);
        assert_eq!(Passthrough::from_option("all"), Passthrough::Allowed);
    }
}
