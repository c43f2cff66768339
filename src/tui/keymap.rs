//! The keys, written once: each mode's table of bindings (keys, what they do in words, and the
//! action of each key), from which [`action`] answers a key, the help overlay ([`help`]) and the
//! tour's hints ([`TOUR`]) are made, and against which a test checks docs/tui.md's key table.
//! While a prompt is open, keys type into it.

use crossterm::event::{KeyCode, KeyEvent, KeyEventKind, KeyModifiers};

use super::event::{Action, Ask, FolderKey};

/// A key: its code, and whether Ctrl is held (a key bound without Ctrl answers with any
/// modifier).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Key {
    /// The key's code.
    pub code: KeyCode,
    /// Whether it is bound with Ctrl held.
    pub ctrl: bool,
}

/// A key bound and its action (a function, as an action is made anew each time).
pub type Bound = (Key, fn() -> Action);

/// One row of a table of bindings: its keys as the help shows them, what they do in words, and
/// the action of each key bound (the shown ones and any alias, such as `=` for `+`).
pub struct Binding {
    /// The keys, as the help shows them.
    pub keys: &'static str,
    /// What they do, in words.
    pub help: &'static str,
    /// Each key bound and its action.
    pub does: &'static [Bound],
}

const fn ch(c: char) -> Key {
    code(KeyCode::Char(c))
}

const fn code(code: KeyCode) -> Key {
    Key { code, ctrl: false }
}

const fn ctrl(c: char) -> Key {
    Key {
        code: KeyCode::Char(c),
        ctrl: true,
    }
}

const fn row(keys: &'static str, help: &'static str, does: &'static [Bound]) -> Binding {
    Binding { keys, help, does }
}

/// The keys of the panes, in the order the help lists them.
pub const BINDINGS: &[Binding] = &[
    row(
        "Tab / S-Tab",
        "next / previous pane",
        &[
            (code(KeyCode::Tab), || Action::Focus(1)),
            (code(KeyCode::BackTab), || Action::Focus(-1)),
        ],
    ),
    row(
        "↑↓←→ hjkl",
        "move in the pane: axis, slab, slice, pointer",
        &[
            (code(KeyCode::Up), || Action::Move(-1)),
            (ch('k'), || Action::Move(-1)),
            (code(KeyCode::Down), || Action::Move(1)),
            (ch('j'), || Action::Move(1)),
            (code(KeyCode::Left), || Action::Sideways(-1)),
            (ch('h'), || Action::Sideways(-1)),
            (code(KeyCode::Right), || Action::Sideways(1)),
            (ch('l'), || Action::Sideways(1)),
        ],
    ),
    row(
        "Enter",
        "partition along the selected axis",
        &[(code(KeyCode::Enter), || Action::Select)],
    ),
    row(
        "a",
        "type an axis: x, y, z or DX,DY,DZ",
        &[(ch('a'), || Action::Ask(Ask::Axis))],
    ),
    row(
        "m",
        "method: top-down, bottom-up, optimal",
        &[(ch('m'), || Action::CycleMethod)],
    ),
    row(
        "n p  . ,",
        "one split or merge forward / back",
        &[
            (ch('n'), || Action::Step(1)),
            (ch('p'), || Action::Step(-1)),
            (ch('.'), || Action::Step(1)),
            (ch(','), || Action::Step(-1)),
        ],
    ),
    row(
        "Home End",
        "start / end of the history",
        &[
            (code(KeyCode::Home), || Action::StepTo(false)),
            (code(KeyCode::End), || Action::StepTo(true)),
        ],
    ),
    row(
        "+ -",
        "one slab more / fewer",
        &[
            (ch('+'), || Action::Slabs(1)),
            (ch('-'), || Action::Slabs(-1)),
            (ch('='), || Action::Slabs(1)),
            (ch('_'), || Action::Slabs(-1)),
        ],
    ),
    row(
        "t",
        "threshold (empty clears)",
        &[(ch('t'), || Action::Ask(Ask::Threshold))],
    ),
    row(
        "b  i",
        "background out / counted; rank by gain, h / gain",
        &[
            (ch('b'), || Action::ToggleBackground),
            (ch('i'), || Action::RankGain),
        ],
    ),
    row(
        "[ ] { }",
        "orbit: azimuth, elevation",
        &[
            (ch('['), || Action::Orbit(-15.0, 0.0)),
            (ch(']'), || Action::Orbit(15.0, 0.0)),
            (ch('{'), || Action::Orbit(0.0, -10.0)),
            (ch('}'), || Action::Orbit(0.0, 10.0)),
        ],
    ),
    row(
        "z Z  s S",
        "zoom in / out; spread less / more",
        &[
            (ch('z'), || Action::Zoom(1.25)),
            (ch('Z'), || Action::Zoom(0.8)),
            (ch('s'), || Action::Spread(-0.1)),
            (ch('S'), || Action::Spread(0.1)),
        ],
    ),
    row(
        "g r",
        "gaps: similarity / uniform; cut / DVR / MIP",
        &[
            (ch('g'), || Action::ToggleGap),
            (ch('r'), || Action::ToggleMode),
        ],
    ),
    row(
        "v",
        "slice view: slice at the cursor, slab's faces",
        &[(ch('v'), || Action::ToggleSlices)],
    ),
    row(
        "w W < >",
        "window narrower / wider, level lower / higher",
        &[
            (ch('w'), || Action::WindowWidth(0.8)),
            (ch('W'), || Action::WindowWidth(1.25)),
            (ch('<'), || Action::WindowLevel(-0.05)),
            (ch('>'), || Action::WindowLevel(0.05)),
        ],
    ),
    row(
        "f c  o P",
        "transfer fn, colours; slab alone; perspective",
        &[
            (ch('f'), || Action::CycleTransfer),
            (ch('c'), || Action::CycleColormap),
            (ch('o'), || Action::ToggleSolo),
            (ch('P'), || Action::TogglePerspective),
        ],
    ),
    row(
        "e  x",
        "export; lesson: the numbers behind axis or step",
        &[
            (ch('e'), || Action::Export),
            (ch('x'), || Action::ToggleLesson),
        ],
    ),
    row(
        "F PgUp PgDn",
        "folder's pane; open the volume before / after",
        &[
            (ch('F'), || Action::ToggleFiles),
            (code(KeyCode::PageUp), || Action::Page(-1)),
            (code(KeyCode::PageDown), || Action::Page(1)),
        ],
    ),
    row(
        "Space M /",
        "folder: mark, marked to a manifest, find",
        &[
            (ch(' '), || Action::Folder(FolderKey::Mark)),
            (ch('M'), || Action::Ask(Ask::Manifest)),
            (ch('/'), || Action::Ask(Ask::Find)),
        ],
    ),
    row(
        "O D  E U T",
        "folder: sort, reverse; errors, ≈, format only",
        &[
            (ch('O'), || Action::Folder(FolderKey::Sort)),
            (ch('D'), || Action::Folder(FolderKey::Reverse)),
            (ch('E'), || Action::Folder(FolderKey::Errors)),
            (ch('U'), || Action::Folder(FolderKey::Uncertain)),
            (ch('T'), || Action::Folder(FolderKey::Format)),
        ],
    ),
    row(
        "Esc",
        "cancel work, close help",
        &[(code(KeyCode::Esc), || Action::Escape)],
    ),
    row(
        "? q",
        "help, quit",
        &[
            (ch('?'), || Action::ToggleHelp),
            (code(KeyCode::F(1)), || Action::ToggleHelp),
            (ch('q'), || Action::Quit),
            (ctrl('c'), || Action::Quit),
            (ctrl('d'), || Action::Quit),
        ],
    ),
];

/// The tour's keys, before those of the panes; its page's title shows them as hints. `PgUp` and
/// `PgDn`, which a presenter's remote sends, turn pages here (outside the tour they open a
/// folder's volumes), and so do `b` and `.`, which some remotes send (outside the tour the
/// background's toggle and a step).
pub const TOUR: &[Binding] = &[
    row(
        "Space → PgDn .",
        "next",
        &[
            (ch(' '), || Action::TurnPage(1)),
            (code(KeyCode::Right), || Action::TurnPage(1)),
            (code(KeyCode::PageDown), || Action::TurnPage(1)),
            (ch('.'), || Action::TurnPage(1)),
        ],
    ),
    row(
        "← PgUp b",
        "back",
        &[
            (code(KeyCode::Left), || Action::TurnPage(-1)),
            (code(KeyCode::PageUp), || Action::TurnPage(-1)),
            (ch('b'), || Action::TurnPage(-1)),
        ],
    ),
    row("q", "quits", &[(ch('q'), || Action::Quit)]),
];

/// The keys of an open prompt: these, and any other character types itself.
pub const PROMPT: &[Binding] = &[row(
    "Backspace Enter Esc",
    "erase, accept, close",
    &[
        (code(KeyCode::Backspace), || Action::Erase),
        (code(KeyCode::Enter), || Action::Submit),
        (code(KeyCode::Esc), || Action::Escape),
    ],
)];

/// The action `table` binds to `key`.
fn find(table: &[Binding], key: Key) -> Option<Action> {
    table
        .iter()
        .flat_map(|b| b.does)
        .find(|(k, _)| *k == key)
        .map(|(_, action)| action())
}

/// The action of `key`, if any; `typing` when a prompt is open, `touring` in the tour (whose
/// keys come before the panes'). A key bound with Ctrl works everywhere, a prompt included.
pub fn action(key: KeyEvent, typing: bool, touring: bool) -> Option<Action> {
    if key.kind == KeyEventKind::Release {
        return None;
    }
    if key.modifiers.contains(KeyModifiers::CONTROL)
        && let Some(action) = [BINDINGS, TOUR, PROMPT].into_iter().find_map(|t| {
            find(
                t,
                Key {
                    code: key.code,
                    ctrl: true,
                },
            )
        })
    {
        return Some(action);
    }
    let plain = code(key.code);
    if typing {
        return find(PROMPT, plain).or(match key.code {
            KeyCode::Char(c) => Some(Action::Type(c)),
            _ => None,
        });
    }
    touring
        .then(|| find(TOUR, plain))
        .flatten()
        .or_else(|| find(BINDINGS, plain))
}

/// The key help: (keys, what they do), a row a binding of the panes.
pub fn help() -> Vec<(&'static str, &'static str)> {
    BINDINGS.iter().map(|b| (b.keys, b.help)).collect()
}

/// The tour's hints: `Space → PgDn . next, ← PgUp b back, q quits`.
pub fn tour_hints() -> String {
    TOUR.iter()
        .map(|b| format!("{} {}", b.keys, b.help))
        .collect::<Vec<_>>()
        .join(", ")
}

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
