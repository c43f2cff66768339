//! Asking the terminal what it can do: one burst of queries, read back in raw mode until the
//! primary device attributes arrive (every terminal answers those, in order, so everything asked
//! before them is in) or a timeout passes. No thread is left reading: the reads happen here, on
//! the caller's thread, before the UI starts its own input loop.

use std::io::{self, Write};
use std::os::fd::AsFd;
use std::time::{Duration, Instant};

use rustix::event::{PollFd, PollFlags, Timespec, poll};

use super::tmux;

/// What a terminal said about itself.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Replies {
    /// XTVERSION: the emulator and its version, e.g. `XTerm(379)` or `kitty(0.26.5)`.
    pub version: Option<String>,
    /// Whether the kitty graphics query was answered `OK`.
    pub kitty_graphics: bool,
    /// `CSI 16 t`: the size of a cell in pixels, `(width, height)`.
    pub cell: Option<(u16, u16)>,
    /// `CSI 14 t`: the size of the text area in pixels, `(width, height)`.
    pub window: Option<(u16, u16)>,
    /// XTSMGRAPHICS: the largest sixel image, `(width, height)` pixels.
    pub sixel_geometry: Option<(u32, u32)>,
    /// XTSMGRAPHICS: sixel colour registers.
    pub sixel_colors: Option<u16>,
    /// DA1: the primary device attributes (4 means sixel).
    pub attributes: Option<Vec<u16>>,
    /// What the user typed while the terminal answered (printable characters and Ctrl-C), to be
    /// taken as keys rather than lost.
    pub typed: String,
}

impl Replies {
    /// Whether the primary device attributes say the terminal draws sixels.
    pub fn sixel(&self) -> bool {
        self.attributes.as_ref().is_some_and(|a| a.contains(&4))
    }
}

/// The queries, in the order the replies are expected, DA1 last. Inside tmux each goes through
/// the passthrough to the outer terminal.
pub fn request(passthrough: bool) -> String {
    let queries = [
        "\x1b[>0q",
        "\x1b_Gi=31,s=1,v=1,a=q,t=d,f=24;AAAA\x1b\\",
        "\x1b[16t",
        "\x1b[14t",
        "\x1b[?2;1;0S",
        "\x1b[?1;1;0S",
        "\x1b[c",
    ];
    if passthrough {
        queries.iter().map(|q| tmux::wrap(q)).collect()
    } else {
        queries.concat()
    }
}

/// Reads `input` (already in raw mode) until a DA1 reply arrives or `timeout` passes, and
/// returns what was read. Reads at most 64 KiB: a terminal says far less about itself.
pub fn read_replies(input: impl AsFd, timeout: Duration) -> io::Result<Vec<u8>> {
    let start = Instant::now();
    let mut buf = Vec::new();
    let mut chunk = [0u8; 1024];
    while buf.len() < 1 << 16 && !has_da1(&buf) {
        let Some(left) = timeout.checked_sub(start.elapsed()) else {
            break;
        };
        let wait = Timespec {
            tv_sec: left.as_secs() as i64,
            tv_nsec: i64::from(left.subsec_nanos()),
        };
        let mut fds = [PollFd::new(&input, PollFlags::IN)];
        match poll(&mut fds, Some(&wait)) {
            Ok(0) => break,
            Ok(_) => match rustix::io::read(&input, &mut chunk) {
                Ok(0) => break,
                Ok(n) => buf.extend_from_slice(&chunk[..n]),
                Err(rustix::io::Errno::INTR | rustix::io::Errno::AGAIN) => {}
                Err(e) => return Err(e.into()),
            },
            Err(rustix::io::Errno::INTR) => {}
            Err(e) => return Err(e.into()),
        }
    }
    Ok(buf)
}

/// Writes the queries and reads the replies; `input` must be in raw mode.
pub fn ask(
    input: impl AsFd,
    output: &mut impl Write,
    passthrough: bool,
    timeout: Duration,
) -> io::Result<Replies> {
    output.write_all(request(passthrough).as_bytes())?;
    output.flush()?;
    Ok(parse(&read_replies(input, timeout)?))
}

/// Whether `buf` holds a complete DA1 reply, `ESC [ ? … c`.
fn has_da1(buf: &[u8]) -> bool {
    csi_sequences(buf).any(|(params, end)| end == b'c' && params.starts_with(b"?"))
}

/// The control sequences `ESC [ params final` in `bytes`, as (params, final byte).
fn csi_sequences(bytes: &[u8]) -> impl Iterator<Item = (&[u8], u8)> {
    let mut i = 0;
    std::iter::from_fn(move || {
        while i + 1 < bytes.len() {
            if bytes[i] == 0x1b && bytes[i + 1] == b'[' {
                let start = i + 2;
                let len = bytes[start..]
                    .iter()
                    .position(|b| (0x40..=0x7e).contains(b))?;
                i = start + len + 1;
                return Some((&bytes[start..start + len], bytes[start + len]));
            }
            i += 1;
        }
        None
    })
}

/// The numbers of a parameter string such as `?2;0;1000;1000`.
fn numbers(params: &[u8]) -> Vec<u32> {
    String::from_utf8_lossy(params)
        .trim_start_matches(['?', '>'])
        .split(';')
        .map(|p| p.parse().unwrap_or(0))
        .collect()
}

/// The string terminated by ST (`ESC \`) or BEL that follows `intro` in `bytes`.
fn string_after<'a>(bytes: &'a [u8], intro: &[u8]) -> Option<&'a [u8]> {
    let at = bytes.windows(intro.len()).position(|w| w == intro)? + intro.len();
    let rest = &bytes[at..];
    let end = rest
        .windows(2)
        .position(|w| w == b"\x1b\\")
        .or_else(|| rest.iter().position(|&b| b == 0x07))?;
    Some(&rest[..end])
}

/// The bytes of `input` outside escape sequences (CSI, and DCS, APC and OSC strings), kept when
/// printable or Ctrl-C: keys typed while the replies came in.
fn typed(input: &[u8]) -> String {
    let mut out = String::new();
    let mut i = 0;
    while i < input.len() {
        match input[i] {
            0x1b if i + 1 < input.len() => {
                let rest = &input[i + 2..];
                let len = match input[i + 1] {
                    b'[' => rest
                        .iter()
                        .position(|b| (0x40..=0x7e).contains(b))
                        .map(|p| p + 1),
                    b'P' | b'_' | b']' => rest
                        .windows(2)
                        .position(|w| w == b"\x1b\\")
                        .map(|p| p + 2)
                        .or_else(|| rest.iter().position(|&b| b == 0x07).map(|p| p + 1)),
                    _ => Some(0),
                };
                i += 2 + len.unwrap_or(rest.len());
            }
            b @ (0x20..=0x7e | 0x03) => {
                out.push(char::from(b));
                i += 1;
            }
            _ => i += 1,
        }
    }
    out
}

/// What the replies in `bytes` say, whatever their order and whatever else is mixed in.
pub fn parse(bytes: &[u8]) -> Replies {
    let mut r = Replies {
        typed: typed(bytes),
        version: string_after(bytes, b"\x1bP>|").map(|v| String::from_utf8_lossy(v).into_owned()),
        kitty_graphics: string_after(bytes, b"\x1b_G")
            .is_some_and(|s| s.split(|&b| b == b';').nth(1) == Some(b"OK")),
        ..Replies::default()
    };
    for (params, end) in csi_sequences(bytes) {
        let n = numbers(params);
        let small = |i: usize| u16::try_from(n[i]).unwrap_or(u16::MAX);
        match (end, params.first(), n.as_slice()) {
            (b't', _, [6, _, _]) => r.cell = Some((small(2), small(1))),
            (b't', _, [4, _, _]) => r.window = Some((small(2), small(1))),
            (b'S', Some(b'?'), [2, 0, w, h]) => r.sixel_geometry = Some((*w, *h)),
            (b'S', Some(b'?'), [1, 0, _]) => r.sixel_colors = Some(small(2)),
            (b'c', Some(b'?'), _) => {
                r.attributes = Some(n.iter().map(|&a| u16::try_from(a).unwrap_or(0)).collect());
            }
            _ => {}
        }
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::term::tests::{KITTY_OLD, MLTERM, XTERM};

    #[test]
    fn xterm_says_its_version_sixel_geometry_and_colours() {
        let r = parse(XTERM);
        assert_eq!(r.version.as_deref(), Some("XTerm(379)"));
        assert_eq!(r.sixel_geometry, Some((1000, 1000)));
        assert_eq!(r.sixel_colors, Some(256));
        assert!(r.sixel() && !r.kitty_graphics);
        assert_eq!(r.cell, None, "xterm does not answer window ops by default");
    }

    #[test]
    fn mlterm_and_kitty_say_their_cell_size() {
        let m = parse(MLTERM);
        assert_eq!((m.cell, m.window), (Some((10, 22)), Some((1000, 660))));
        assert_eq!(m.sixel_geometry, None, "mlterm refuses the geometry query");
        assert!(m.sixel());
        let k = parse(KITTY_OLD);
        assert_eq!(k.version.as_deref(), Some("kitty(0.26.5)"));
        assert!(k.kitty_graphics && !k.sixel());
        assert_eq!(k.cell, Some((9, 20)));
    }

    #[test]
    fn a_refused_kitty_query_and_noise_are_not_support() {
        let r = parse(b"\x1b_Gi=31;EINVAL:bad\x1b\\ junk \x1b[?1;2c");
        assert!(!r.kitty_graphics);
        assert_eq!(r.attributes, Some(vec![1, 2]));
        assert_eq!(parse(b""), Replies::default());
        assert!(
            !has_da1(b"\x1b[?63;1;2"),
            "an incomplete reply is not the end"
        );
        assert!(has_da1(b"\x1b[?1;2c"));
    }

    #[test]
    fn keys_typed_while_the_terminal_answers_are_kept() {
        let mut bytes = b"q".to_vec();
        bytes.extend_from_slice(XTERM);
        bytes.extend_from_slice(b"n\x03");
        assert_eq!(parse(&bytes).typed, "qn\u{3}");
        assert_eq!(parse(KITTY_OLD).typed, "", "replies alone are no keys");
    }

    #[test]
    fn tmux_passthrough_wraps_every_query() {
        let q = request(true);
        assert_eq!(q.matches("\x1bPtmux;").count(), 7);
        assert!(q.contains("\x1bPtmux;\x1b\x1b[c\x1b\\"));
        assert!(!request(false).contains("tmux"));
    }
}
