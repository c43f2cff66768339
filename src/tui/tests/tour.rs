//! The tour: each page sets the panes it speaks of (the pane focused, the viewpoint, the method
//! and slab count, the lesson), turning stops at both ends, and the page shows below the panes.

use slabscope::partition::Method;

use super::{ready_app, screens};
use crate::tui::app::tour::{PAGES, Row, Tour};
use crate::tui::event::{Action, Effect};

#[test]
fn every_page_sets_the_panes_it_speaks_of() {
    let mut app = ready_app();
    app.tour = Some(Tour::new());
    app.update(Action::TurnPage(-1));
    let last_view = app.views.len() - 1;
    let mut seen_lessons = 0;
    for (i, page) in PAGES.iter().enumerate() {
        let tour = app.tour.as_ref().unwrap();
        assert_eq!((tour.page, tour.applied), (i, true), "page {}", i + 1);
        let s = page.setup;
        assert_eq!(app.focus, s.focus, "page {}", i + 1);
        assert_eq!(app.lesson.open, s.lesson, "page {}", i + 1);
        assert_eq!(app.part.method, s.method, "page {}", i + 1);
        assert_eq!(app.part.slab_count(), Some(s.slabs), "page {}", i + 1);
        let row = match s.row {
            Row::Best => 0,
            Row::Worst => last_view,
        };
        assert_eq!(app.views.row, row, "page {}", i + 1);
        let effects = app.update(Action::TurnPage(1));
        seen_lessons += usize::from(effects.iter().any(|e| matches!(e, Effect::Lesson(_))));
    }
    // The pages with the lesson open asked for it (the first of two alike pages only once).
    assert!(seen_lessons >= 4, "{seen_lessons} lesson requests");
    // Past the last page the tour stays there; back goes back.
    assert_eq!(app.tour.as_ref().unwrap().page, PAGES.len() - 1);
    app.update(Action::TurnPage(-1));
    assert_eq!(app.tour.as_ref().unwrap().page, PAGES.len() - 2);
    assert_eq!(app.part.method, Method::Optimal);
    // Page 10 adds the volume's own numbers.
    app.update(Action::TurnPage(-1));
    let numbers = app.tour.as_ref().unwrap().numbers.clone().unwrap();
    assert!(numbers.contains("bits top-down and"), "{numbers}");
}

#[test]
fn the_page_shows_below_the_panes() {
    let mut app = ready_app();
    app.tour = Some(Tour::new());
    app.update(Action::TurnPage(0));
    let shots = screens(&mut app, 80, 24, vec![]);
    let screen = &shots[0];
    assert!(screen.contains("Tour, page 1 of 12"), "{screen}");
    assert!(screen.contains("Slabs:"), "{screen}");
    insta::assert_snapshot!("tour_page_1_80x24", screen);
}
