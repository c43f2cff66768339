//! The protocol choice and the sizes, against replies recorded from real terminals (xterm,
//! mlterm, kitty 0.26 under Xvfb, tmux 3.3a inside xterm) and written from the protocols'
//! documentation (kitty 0.35, `WezTerm`, iTerm2), and a terminal that never answers.

use super::query::{Replies, parse};
use super::tmux::Passthrough;
use super::*;

pub(crate) const XTERM: &[u8] =
    b"\x1bP>|XTerm(379)\x1b\\\x1b[?2;0;1000;1000S\x1b[?1;0;256S\x1b[?63;1;2;4;6;9;15;16;22;28c";
pub(crate) const MLTERM: &[u8] =
    b"\x1b[6;22;10t\x1b[4;660;1000t\x1b[?1;3;0S\x1b[?1;0;1024S\x1b[?63;1;2;3;4;6;7;15;18;22;29c";
pub(crate) const KITTY_OLD: &[u8] =
    b"\x1bP>|kitty(0.26.5)\x1b\\\x1b_Gi=31;OK\x1b\\\x1b[6;20;9t\x1b[4;400;639t\x1b[?62;c";
const KITTY_NEW: &[u8] =
    b"\x1bP>|kitty(0.35.2)\x1b\\\x1b_Gi=31;OK\x1b\\\x1b[6;40;18t\x1b[4;1600;2880t\x1b[?62;c";
const WEZTERM: &[u8] =
    b"\x1bP>|WezTerm 20240203-110809-5046fc22\x1b\\\x1b[6;17;8t\x1b[?65;4;6;18;22c";
const ITERM2: &[u8] = b"\x1bP>|iTerm2 3.5.0\x1b\\\x1b[6;34;16t\x1b[?62;4c";
/// tmux's own answers to unwrapped queries: no images.
const TMUX_ITSELF: &[u8] = b"\x1bP>|tmux 3.3a\x1b\\\x1b[?1;2c";

fn env() -> Env {
    Env {
        term: "xterm-256color".into(),
        ..Env::default()
    }
}

fn caps(bytes: &[u8], pixels: Option<((u16, u16), (u16, u16))>) -> Caps {
    choose(Protocol::Auto, &env(), None, Some(&parse(bytes)), pixels)
}

#[test]
fn each_terminal_gets_the_protocol_it_draws_best() {
    let xterm = caps(XTERM, Some(((604, 394), (100, 30))));
    assert_eq!(xterm.graphics, Graphics::Sixel);
    assert_eq!(xterm.cell, (6, 13), "from the tty's pixels");
    assert_eq!(xterm.max_image, Some((1000, 1000)));
    assert_eq!(caps(MLTERM, None).graphics, Graphics::Sixel);
    assert_eq!(caps(MLTERM, None).cell, (10, 22));
    assert_eq!(caps(KITTY_OLD, None).graphics, Graphics::Kitty);
    assert_eq!(caps(KITTY_NEW, None).graphics, Graphics::Kitty);
    assert_eq!(caps(KITTY_NEW, None).cell, (18, 40));
    assert_eq!(caps(WEZTERM, None).graphics, Graphics::Iterm);
    assert_eq!(caps(ITERM2, None).graphics, Graphics::Iterm);
    assert!(caps(XTERM, None).note.is_some(), "no cell size: said so");
}

#[test]
fn a_terminal_that_never_answers_gets_half_blocks() {
    let silent = choose(
        Protocol::Auto,
        &env(),
        None,
        Some(&Replies::default()),
        None,
    );
    assert_eq!(silent.graphics, Graphics::Blocks);
    assert_eq!(silent.cell, (8, 16));
    let kitty_env = Env {
        term: "xterm-kitty".into(),
        ..Env::default()
    };
    assert_eq!(
        choose(Protocol::Auto, &kitty_env, None, None, None).graphics,
        Graphics::Kitty,
        "not asked: the environment decides"
    );
}

#[test]
fn the_user_and_slabscope_protocol_override_detection() {
    let r = parse(XTERM);
    let forced = choose(Protocol::Blocks, &env(), None, Some(&r), None);
    assert_eq!(forced.graphics, Graphics::Blocks);
    let mut e = env();
    e.protocol = Some("kitty".into());
    assert_eq!(
        choose(Protocol::Auto, &e, None, Some(&r), None).graphics,
        Graphics::Kitty
    );
    assert_eq!(
        choose(Protocol::Sixel, &e, None, Some(&r), None).graphics,
        Graphics::Sixel,
        "--protocol wins over the environment"
    );
    e.protocol = Some("png".into());
    let bad = choose(Protocol::Auto, &e, None, Some(&r), None);
    assert_eq!(bad.graphics, Graphics::Sixel);
    assert!(bad.note.unwrap().contains("SLABSCOPE_PROTOCOL=\"png\""));
    let ssh = Env {
        program: "iTerm2".into(),
        ..env()
    };
    assert_eq!(
        choose(Protocol::Auto, &ssh, None, Some(&Replies::default()), None).graphics,
        Graphics::Iterm,
        "LC_TERMINAL=iTerm2 forwarded over SSH"
    );
}

#[test]
fn tmux_passes_the_outer_terminal_or_says_how() {
    let tmux_env = Env {
        tmux: true,
        ..env()
    };
    let on = choose(
        Protocol::Auto,
        &tmux_env,
        Some(Passthrough::Allowed),
        Some(&parse(XTERM)),
        Some(((600, 377), (100, 29))),
    );
    assert_eq!(
        (on.graphics, on.tmux, on.cell),
        (Graphics::Sixel, true, (6, 13))
    );
    let off = choose(
        Protocol::Auto,
        &tmux_env,
        Some(Passthrough::Off),
        Some(&parse(TMUX_ITSELF)),
        None,
    );
    assert_eq!(off.graphics, Graphics::Blocks);
    assert!(off.note.unwrap().contains(tmux::ENABLE));
    // Half-blocks chosen by name: nothing to say about tmux's passthrough.
    let blocks = choose(
        Protocol::Blocks,
        &tmux_env,
        Some(Passthrough::Off),
        Some(&parse(TMUX_ITSELF)),
        None,
    );
    assert_eq!((blocks.graphics, blocks.note), (Graphics::Blocks, None));
    // The outer window's pixels say nothing about a tmux pane's cells.
    let r = Replies {
        window: Some((1000, 660)),
        ..Replies::default()
    };
    assert_eq!(cell_size(&r, true, Some(((0, 0), (50, 20)))), None);
    assert_eq!(
        cell_size(&r, false, Some(((0, 0), (100, 30)))),
        Some((10, 22))
    );
}

#[test]
fn images_fill_the_area_and_never_exceed_the_sixel_limit() {
    let mut c = caps(XTERM, Some(((1920, 1040), (320, 80))));
    assert_eq!(c.image_size((100, 30)), (600, 390));
    // A wide pane: scaled down to 1000 px wide, keeping the pane's aspect.
    assert_eq!(c.image_size((200, 50)), (1000, 541));
    c.graphics = Graphics::Blocks;
    assert_eq!(c.image_size((40, 10)), (40, 20), "two pixels a cell");
}
