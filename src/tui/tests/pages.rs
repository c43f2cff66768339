//! Every page of the tour as it shows, at 80×24 and 160×48, in the plain and the contrast theme:
//! snapshots of the whole screen once the page's lesson (if it opens one) is in.

use super::{ready_app_with, screens};
use crate::tui::app::App;
use crate::tui::app::tour::{PAGES, Tour};
use crate::tui::event::{Action, Effect, JobMsg};
use crate::tui::theme::Theme;
use slabscope::progress::Monitor;

/// Answers the lesson `effects` ask for, if they ask for one.
fn answer_any(app: &mut App, effects: Vec<Effect>) {
    for e in effects {
        if let Effect::Lesson(request) = e {
            let result = request.compute(&Monitor::none()).map(Box::new);
            app.update(Action::Job(JobMsg::Lesson(request.generation, result)));
        }
    }
}

#[test]
fn every_page_at_both_sizes_in_both_themes() {
    let themes = [
        (
            "plain",
            Theme {
                color: false,
                contrast: false,
            },
        ),
        (
            "contrast",
            Theme {
                color: true,
                contrast: true,
            },
        ),
    ];
    for (name, theme) in themes {
        let mut app = ready_app_with(theme);
        app.tour = Some(Tour::new(false));
        let effects = app.update(Action::TurnPage(0));
        answer_any(&mut app, effects);
        for (i, page) in PAGES.iter().enumerate() {
            for (w, h) in [(80, 24), (160, 48)] {
                let screen = screens(&mut app, w, h, vec![]).remove(0);
                let title = format!("page {} of {}: {}", i + 1, PAGES.len(), page.title);
                let head: String = title.chars().take(usize::from(w) - 40).collect();
                assert!(screen.contains(&head), "{head} not in\n{screen}");
                paragraph_ends(&app, &screen, i);
                insta::assert_snapshot!(format!("tour_{name}_page_{:02}_{w}x{h}", i + 1), screen);
                if theme.contrast && page.board.is_some() {
                    board_is_black(&app, w, h, i);
                }
            }
            let effects = app.update(Action::TurnPage(1));
            answer_any(&mut app, effects);
        }
    }
}

/// The tour's box on `screen` ends with the last word of page `i`'s paragraph and numbers:
/// none is cut off at the box's last row.
fn paragraph_ends(app: &App, screen: &str, i: usize) {
    let tour = app.tour.as_ref().unwrap();
    let text = match &tour.numbers {
        Some(n) => format!("{} {n}", PAGES[i].text),
        None => PAGES[i].text.to_string(),
    };
    let last_word = text.split_whitespace().last().unwrap();
    let rows: Vec<&str> = screen
        .lines()
        .skip_while(|l| !l.contains(" Tour ("))
        .skip(1)
        .take_while(|l| !l.starts_with('└'))
        .map(|l| l.trim_matches(|c: char| c == '│' || c.is_whitespace()))
        .filter(|l| !l.is_empty())
        .collect();
    let end = rows.last().copied().unwrap_or_default();
    assert!(
        end.ends_with(last_word),
        "page {}: the box ends with {end:?}, not {last_word:?}\n{screen}",
        i + 1
    );
}

/// The board of page `i` (in the exploded view's place) is drawn on the contrast theme's black.
fn board_is_black(app: &App, w: u16, h: u16, i: usize) {
    let backend = ratatui::backend::TestBackend::new(w, h);
    let mut terminal = ratatui::Terminal::new(backend).unwrap();
    terminal
        .draw(|frame| crate::tui::ui::draw(frame, app))
        .unwrap();
    let buffer = terminal.backend().buffer();
    let a = crate::tui::ui::areas(buffer.area, true, None).unwrap();
    let black = ratatui::style::Color::Rgb(0, 0, 0);
    let grey: Vec<_> = a
        .preview
        .positions()
        .filter(|&p| buffer[p].bg != black)
        .collect();
    assert!(
        grey.is_empty(),
        "page {} at {w}x{h}: not black at {grey:?}",
        i + 1
    );
}
