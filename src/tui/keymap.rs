//! Keys to actions. While a prompt is open, keys type into it.

use crossterm::event::{KeyCode, KeyEvent, KeyEventKind, KeyModifiers};

use super::event::{Action, Ask};

/// The action of `key`, if any; `typing` when a prompt is open, `touring` in the tour (where
/// Space and → turn to the next page and ← to the one before).
pub fn action(key: KeyEvent, typing: bool, touring: bool) -> Option<Action> {
    if key.kind == KeyEventKind::Release {
        return None;
    }
    if key.modifiers.contains(KeyModifiers::CONTROL) && matches!(key.code, KeyCode::Char('c' | 'd'))
    {
        return Some(Action::Quit);
    }
    if typing {
        return match key.code {
            KeyCode::Char(c) => Some(Action::Type(c)),
            KeyCode::Backspace => Some(Action::Erase),
            KeyCode::Enter => Some(Action::Submit),
            KeyCode::Esc => Some(Action::Escape),
            _ => None,
        };
    }
    if touring {
        match key.code {
            KeyCode::Char(' ') | KeyCode::Right => return Some(Action::TurnPage(1)),
            KeyCode::Left => return Some(Action::TurnPage(-1)),
            _ => {}
        }
    }
    Some(match key.code {
        KeyCode::Char('q') => Action::Quit,
        KeyCode::Char('?') | KeyCode::F(1) => Action::ToggleHelp,
        KeyCode::Esc => Action::Escape,
        KeyCode::Tab => Action::Focus(1),
        KeyCode::BackTab => Action::Focus(-1),
        KeyCode::Up | KeyCode::Char('k') => Action::Move(-1),
        KeyCode::Down | KeyCode::Char('j') => Action::Move(1),
        KeyCode::Left | KeyCode::Char('h') => Action::Sideways(-1),
        KeyCode::Right | KeyCode::Char('l') => Action::Sideways(1),
        KeyCode::PageUp => Action::Page(-1),
        KeyCode::PageDown => Action::Page(1),
        KeyCode::Enter => Action::Select,
        KeyCode::Char('n' | '.') => Action::Step(1),
        KeyCode::Char('p' | ',') => Action::Step(-1),
        KeyCode::Home => Action::StepTo(false),
        KeyCode::End => Action::StepTo(true),
        KeyCode::Char('+' | '=') => Action::Slabs(1),
        KeyCode::Char('-' | '_') => Action::Slabs(-1),
        KeyCode::Char('m') => Action::CycleMethod,
        KeyCode::Char('a') => Action::Ask(Ask::Axis),
        KeyCode::Char('t') => Action::Ask(Ask::Threshold),
        KeyCode::Char('[') => Action::Orbit(-15.0, 0.0),
        KeyCode::Char(']') => Action::Orbit(15.0, 0.0),
        KeyCode::Char('{') => Action::Orbit(0.0, -10.0),
        KeyCode::Char('}') => Action::Orbit(0.0, 10.0),
        KeyCode::Char('z') => Action::Zoom(1.25),
        KeyCode::Char('Z') => Action::Zoom(0.8),
        KeyCode::Char('s') => Action::Spread(-0.1),
        KeyCode::Char('S') => Action::Spread(0.1),
        KeyCode::Char('r') => Action::ToggleMode,
        KeyCode::Char('v') => Action::ToggleSlices,
        KeyCode::Char('F') => Action::ToggleFiles,
        KeyCode::Char('w') => Action::WindowWidth(0.8),
        KeyCode::Char('W') => Action::WindowWidth(1.25),
        KeyCode::Char('<') => Action::WindowLevel(-0.05),
        KeyCode::Char('>') => Action::WindowLevel(0.05),
        KeyCode::Char('f') => Action::CycleTransfer,
        KeyCode::Char('c') => Action::CycleColormap,
        KeyCode::Char('g') => Action::ToggleGap,
        KeyCode::Char('o') => Action::ToggleSolo,
        KeyCode::Char('P') => Action::TogglePerspective,
        KeyCode::Char('e') => Action::Export,
        KeyCode::Char('b') => Action::ToggleBackground,
        KeyCode::Char('i') => Action::RankGain,
        KeyCode::Char('x') => Action::ToggleLesson,
        _ => return None,
    })
}

/// The key help: (keys, what they do).
pub const HELP: &[(&str, &str)] = &[
    ("Tab / S-Tab", "next / previous pane"),
    ("↑↓←→ hjkl", "move in the pane: axis, slab, slice, pointer"),
    ("Enter", "partition along the selected axis"),
    ("a", "type an axis: x, y, z or DX,DY,DZ"),
    ("m", "method: top-down, bottom-up, optimal"),
    ("n p  . ,", "one split or merge forward / back"),
    ("Home End", "start / end of the history"),
    ("+ -", "one slab more / fewer"),
    ("t", "threshold (empty clears)"),
    ("b  i", "background out / counted; rank by gain, h / gain"),
    ("[ ] { }", "orbit: azimuth, elevation"),
    ("z Z  s S", "zoom in / out; spread less / more"),
    ("g", "gaps: similarity / uniform"),
    ("r", "render: cut faces / DVR / MIP"),
    ("v", "slice view: slice at the cursor, slab's faces"),
    ("w W < >", "window narrower / wider, level lower / higher"),
    ("f c", "transfer function (those that fit), colours"),
    ("o P", "selected slab alone; perspective"),
    ("e  F", "export; a folder's file list (PgUp PgDn: volumes)"),
    ("x", "lesson: the numbers behind the axis or the step"),
    ("Esc", "cancel work, close help"),
    ("? q", "help, quit"),
];

/// The words on the screen: (term, what it means).
pub const GLOSSARY: &[(&str, &str)] = &[
    ("h", "entropy rate H(X^L) - H(X^L-1) along an axis:"),
    ("", "lower is more structured; mean over lattice phases"),
    ("H(X^L)", "entropy of L samples in a row, bits"),
    ("* ≈", "the best axis; a contender within 2 std. errors"),
    ("gain", "information K top-down slabs along an axis keep"),
    ("ΔI", "information a cut gains (JS divergence, weighted)"),
    ("I", "information the slabs keep about the intensity"),
    ("NMI", "normalized mutual information of two slabs"),
    ("JS", "Jensen-Shannon divergence of two histograms"),
    ("0–44", "slices 0 to 44, both included"),
    ("∅", "an empty slab: next to nothing but background"),
    (
        "R L A P S I",
        "slice edges: axial and coronal slices show the",
    ),
    ("", "patient's right on the left (radiological)"),
];
