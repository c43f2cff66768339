//! The keys written once: the help shows only keys its rows bind, no key is bound twice, the
//! tour's words name keys that do what they say, and docs/tui.md's key table names every key
//! bound and no other.

use std::collections::HashSet;

use crossterm::event::{KeyCode, KeyEvent, KeyModifiers};

use crate::tui::app::tour::PAGES;
use crate::tui::event::Action;
use crate::tui::keymap::{self, BINDINGS, Binding, Key, PROMPT, TOUR};

/// The key a word names (`Tab`, `PgUp`, `Ctrl-C`, …), if it names one.
fn named(word: &str) -> Option<Key> {
    let code = match word {
        "Tab" => KeyCode::Tab,
        "S-Tab" | "Shift-Tab" => KeyCode::BackTab,
        "Enter" => KeyCode::Enter,
        "Esc" => KeyCode::Esc,
        "Home" => KeyCode::Home,
        "End" => KeyCode::End,
        "PgUp" => KeyCode::PageUp,
        "PgDn" => KeyCode::PageDown,
        "Backspace" => KeyCode::Backspace,
        "Space" => KeyCode::Char(' '),
        "F1" => KeyCode::F(1),
        _ => {
            let c = word.strip_prefix("Ctrl-")?;
            let c = c.chars().next()?.to_ascii_lowercase();
            return Some(Key {
                code: KeyCode::Char(c),
                ctrl: true,
            });
        }
    };
    Some(Key { code, ctrl: false })
}

/// The key of one character (the arrows are the arrow keys).
fn char_key(c: char) -> Key {
    let code = match c {
        '↑' => KeyCode::Up,
        '↓' => KeyCode::Down,
        '←' => KeyCode::Left,
        '→' => KeyCode::Right,
        c => KeyCode::Char(c),
    };
    Key { code, ctrl: false }
}

/// The keys `text` names, as the help and the docs write them: words separated by spaces,
/// commas and parentheses (a comma or parenthesis alone is the key), `/` and `or` between
/// them (the slash key itself in backticks), and any other word a key a character (`hjkl`,
/// `↑↓←→`).
fn keys_named(text: &str) -> Vec<Key> {
    let mut keys = Vec::new();
    for word in text.split_whitespace() {
        if word.trim_end_matches(',') == "`/`" {
            keys.push(char_key('/'));
            continue;
        }
        let mut w = word.trim_matches('`');
        while w.chars().count() > 1 && (w.ends_with(',') || w.ends_with(')')) {
            w = &w[..w.len() - 1];
        }
        while w.chars().count() > 1 && w.starts_with('(') {
            w = &w[1..];
        }
        match named(w) {
            Some(k) => keys.push(k),
            None if w == "/" || w == "or" => {}
            None => keys.extend(w.chars().map(char_key)),
        }
    }
    keys
}

/// Every key of `table`'s rows.
fn bound(table: &[Binding]) -> Vec<Key> {
    table.iter().flat_map(|b| b.does).map(|(k, _)| *k).collect()
}

/// The first column of every row of docs/tui.md's table under `## Every key`.
fn documented_keys() -> Vec<String> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/tui.md");
    let text = std::fs::read_to_string(path).expect("docs/tui.md");
    let table = text
        .lines()
        .skip_while(|l| l.trim() != "## Every key")
        .skip(1)
        .skip_while(|l| !l.starts_with('|'))
        .take_while(|l| l.starts_with('|'))
        .skip(2);
    table
        .map(|l| l.split('|').nth(1).unwrap_or_default().trim().to_string())
        .collect()
}

#[test]
fn the_help_shows_the_keys_its_rows_bind() {
    for b in BINDINGS.iter().chain(TOUR).chain(PROMPT) {
        let shown = keys_named(b.keys);
        assert!(!shown.is_empty(), "{:?} shows no key", b.keys);
        let does = bound(std::slice::from_ref(b));
        for k in shown {
            assert!(
                does.contains(&k),
                "{:?} shows {k:?}, which it does not bind",
                b.keys
            );
        }
    }
    assert_eq!(keymap::help().len(), BINDINGS.len());
    assert_eq!(
        keymap::tour_hints(),
        "Space → PgDn . next, ← PgUp b back, q quits"
    );
}

#[test]
fn no_key_is_bound_twice_in_one_mode() {
    for table in [BINDINGS, TOUR, PROMPT] {
        let keys = bound(table);
        let unique: HashSet<Key> = keys.iter().copied().collect();
        assert_eq!(unique.len(), keys.len(), "{keys:?}");
    }
}

#[test]
fn the_key_table_of_the_docs_names_every_key_bound_and_no_other() {
    let rows = documented_keys();
    assert!(rows.len() >= 20, "{rows:?}");
    let documented: HashSet<Key> = rows.iter().flat_map(|r| keys_named(r)).collect();
    let bound: HashSet<Key> = [BINDINGS, TOUR, PROMPT]
        .into_iter()
        .flat_map(bound)
        .collect();
    let missing: Vec<_> = bound.difference(&documented).collect();
    let extra: Vec<_> = documented.difference(&bound).collect();
    assert!(
        missing.is_empty() && extra.is_empty(),
        "bound but not in docs/tui.md's key table: {missing:?}\n\
         in docs/tui.md's key table but not bound: {extra:?}"
    );
}

/// The action of `c` in the tour.
fn in_tour(c: char) -> Action {
    let key = KeyEvent::new(KeyCode::Char(c), KeyModifiers::NONE);
    keymap::action(key, false, true).unwrap_or_else(|| panic!("{c:?} is not bound in the tour"))
}

#[test]
fn the_tour_names_keys_that_do_what_it_says() {
    let says = |page: usize, words: &str| {
        let text = PAGES[page]
            .text
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ");
        assert!(
            text.contains(words),
            "page {} no longer says {words:?}",
            page + 1
        );
    };
    says(
        10,
        "n and p step through the history; + and - change the slab count",
    );
    assert!(matches!(in_tour('n'), Action::Step(1)));
    assert!(matches!(in_tour('p'), Action::Step(-1)));
    assert!(matches!(in_tour('+'), Action::Slabs(1)));
    assert!(matches!(in_tour('-'), Action::Slabs(-1)));
    says(13, "m switches the method");
    assert!(matches!(in_tour('m'), Action::CycleMethod));
    says(
        15,
        "Orbit with [ ] { }, change the look with r f c; q ends the tour",
    );
    for c in ['[', ']', '{', '}'] {
        assert!(matches!(in_tour(c), Action::Orbit(..)), "{c}");
    }
    assert!(matches!(in_tour('r'), Action::ToggleMode));
    assert!(matches!(in_tour('f'), Action::CycleTransfer));
    assert!(matches!(in_tour('c'), Action::CycleColormap));
    assert!(matches!(in_tour('q'), Action::Quit));
    assert!(matches!(in_tour(' '), Action::TurnPage(1)));
}

#[test]
fn a_presenters_remote_turns_pages_in_the_tour_and_volumes_outside_it() {
    for (code, touring, by) in [
        (KeyCode::PageDown, true, 1),
        (KeyCode::PageUp, true, -1),
        (KeyCode::PageDown, false, 1),
        (KeyCode::PageUp, false, -1),
    ] {
        let turned = match keymap::action(KeyEvent::from(code), false, touring) {
            Some(Action::TurnPage(n)) if touring => n,
            Some(Action::Page(n)) if !touring => n,
            _ => panic!("{code:?} (touring: {touring}) does not turn"),
        };
        assert_eq!(turned, by, "{code:?} (touring: {touring})");
    }
}

#[test]
fn ctrl_c_quits_even_in_a_prompt_and_other_keys_type() {
    let key = |c, m| KeyEvent::new(KeyCode::Char(c), m);
    let quit = keymap::action(key('c', KeyModifiers::CONTROL), true, false);
    assert!(matches!(quit, Some(Action::Quit)));
    let typed = keymap::action(key('q', KeyModifiers::NONE), true, false);
    assert!(matches!(typed, Some(Action::Type('q'))));
    let erase = KeyEvent::new(KeyCode::Backspace, KeyModifiers::NONE);
    assert!(matches!(
        keymap::action(erase, true, false),
        Some(Action::Erase)
    ));
    // A key bound without Ctrl answers with it too, as it always has.
    let lesson = keymap::action(key('x', KeyModifiers::CONTROL), false, false);
    assert!(matches!(lesson, Some(Action::ToggleLesson)));
    assert!(
        keymap::action(key('c', KeyModifiers::NONE), false, false)
            .is_some_and(|a| matches!(a, Action::CycleColormap))
    );
}
