//! The tour: each page sets the panes it speaks of (the pane focused, the viewpoint, the method
//! and slab count, the lesson), turning stops at both ends, and the page shows below the panes.

use slabscope::partition::Method;

use super::lesson::answer;
use super::{ready_app, ready_paper_app, screens};
use slabscope::explain::text::grouped;

use crate::tui::app::tour::{Board, MERGE, MODES, PAGES, Row, SHOWN, Tour};

/// The page of blocks and H(X^L) on the volume, with the axis's lesson.
const BLOCKS: usize = 4;
/// The page of the slices' curves.
const CURVES: usize = 7;
use crate::tui::event::{Action, Effect, Task};
use crate::tui::lesson::{Lesson, Subject};

#[test]
fn every_page_sets_the_panes_it_speaks_of() {
    let mut app = ready_app();
    app.tour = Some(Tour::new(false));
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
        let structured = app
            .part
            .ready()
            .and_then(|h| h.bottom().and_then(slabscope::explain::structure))
            .map(|s| s.at.slabs);
        assert_eq!(
            app.part.slab_count(),
            Some(s.slabs_with(SHOWN, structured)),
            "page {}",
            i + 1
        );
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
    app.tour = Some(Tour::new(false));
    app.update(Action::TurnPage(0));
    let shots = screens(&mut app, 80, 24, vec![]);
    let screen = &shots[0];
    assert!(screen.contains("Tour (defaults), page 1 of 16"), "{screen}");
    assert!(screen.contains("Slabs:"), "{screen}");
    insta::assert_snapshot!("tour_page_1_80x24", screen);
}

#[test]
fn in_paper_mode_the_lists_h_is_the_lessons_h() {
    let mut app = ready_paper_app();
    app.tour = Some(Tour::new(true));
    let effects = app.update(Action::TurnPage(BLOCKS as isize));
    answer(&mut app, effects);
    let views = app.views.views.ready().unwrap();
    let listed = slabscope::view::score(&views.views[0]);
    let Task::Ready(lesson) = &app.lesson.lesson else {
        panic!("no lesson")
    };
    let Lesson::Axis { selected, .. } = lesson.as_ref() else {
        panic!("an axis lesson")
    };
    assert_eq!(listed, selected.entropy_rate);
    let listed = listed.to_owned();
    assert!(views.views[0].phases.is_none());
    let screen = &screens(&mut app, 160, 48, vec![])[0];
    assert!(
        screen.contains("Tour (paper mode), page 5 of 16"),
        "{screen}"
    );
    // The lesson and, once it is closed, the list show it alike.
    let h = format!("{listed:.4}");
    assert!(
        screen.contains(&format!("= {h} bits per sample")),
        "{screen}"
    );
    app.update(Action::ToggleLesson);
    let screen = &screens(&mut app, 160, 48, vec![])[0];
    assert!(screen.contains(&h), "{screen}");
}

#[test]
fn the_modes_page_shows_both_numbers_side_by_side() {
    for (paper, mut app) in [(false, ready_app()), (true, ready_paper_app())] {
        app.tour = Some(Tour::new(paper));
        let effects = app.update(Action::TurnPage(MODES as isize));
        answer(&mut app, effects);
        let Task::Ready(lesson) = &app.lesson.lesson else {
            panic!("no lesson")
        };
        let Lesson::Modes(m) = lesson.as_ref() else {
            panic!("the modes' lesson")
        };
        let m = m.clone();
        let phases = m.phases.unwrap();
        let (small, large) = (
            screens(&mut app, 80, 24, vec![]).remove(0),
            screens(&mut app, 160, 48, vec![]).remove(0),
        );
        for n in [
            format!("{:.4}", m.paper_h),
            format!("{:.4}", phases.mean),
            grouped(m.voxels),
            grouped(m.without_background()),
        ] {
            assert!(large.contains(&n), "{n} not in\n{large}");
        }
        let name = if paper { "paper" } else { "defaults" };
        insta::assert_snapshot!(format!("tour_modes_{name}_80x24"), small);
        insta::assert_snapshot!(format!("tour_modes_{name}_160x48"), large);
    }
}

#[test]
fn the_status_line_holds_only_the_pages_words() {
    // The terminal's note (tmux's passthrough), while the volume loads: the TUI says it, the
    // tour's first page, waiting for the same, does not.
    let waiting = |tour: bool| {
        let screen = crate::tui::app::Screen {
            theme: super::PLAIN,
            note: Some("tmux keeps images from the terminal".into()),
            ..Default::default()
        };
        let params = slabscope::AnalysisParams::default();
        let (mut app, _) = crate::tui::app::App::new("body.nrrd".into(), params, screen);
        if tour {
            app.start_tour(false);
        }
        screens(&mut app, 80, 24, vec![]).remove(0)
    };
    let outside = waiting(false);
    assert!(outside.contains("tmux keeps images"), "{outside}");
    let first = waiting(true);
    assert!(first.contains("page 1 of 16"), "{first}");
    assert!(!first.contains("tmux"), "{first}");
    // What full resolution said is gone with the page it was said on.
    let mut app = ready_app();
    app.start_tour(false);
    app.update(Action::TurnPage(0));
    app.status.message = Some("full resolution moved the cuts".into());
    app.update(Action::TurnPage(1));
    assert_eq!(app.status.message, None);
    let screen = &screens(&mut app, 80, 24, vec![])[0];
    assert!(!screen.contains("moved"), "{screen}");
}

#[test]
fn the_contrast_theme_draws_every_pane_on_its_own_background() {
    let contrast = crate::tui::theme::Theme {
        color: true,
        contrast: true,
    };
    let mut app = super::ready_app_with(contrast);
    app.tour = Some(Tour::new(false));
    app.update(Action::TurnPage(CURVES as isize));
    for (w, h) in [(80, 24), (160, 48)] {
        let mut terminal =
            ratatui::Terminal::new(ratatui::backend::TestBackend::new(w, h)).unwrap();
        terminal
            .draw(|frame| crate::tui::ui::draw(frame, &app))
            .unwrap();
        let buffer = terminal.backend().buffer();
        let black = ratatui::style::Color::Rgb(0, 0, 0);
        // Every pane but the preview (whose picture has its own colours) is black.
        let a = crate::tui::ui::areas(buffer.area, true, None).unwrap();
        let mut unpainted = Vec::new();
        for pane in [a.views, a.slabs, a.curves, a.tour, a.status] {
            for position in pane.positions() {
                if buffer[position].bg != black {
                    unpainted.push((position.x, position.y));
                }
            }
        }
        assert!(unpainted.is_empty(), "{w}x{h}: not black at {unpainted:?}");
        // The curves' axes: the slices under the lower chart, each curve named on its own.
        let screen = super::text(buffer);
        assert!(screen.contains("NMI") && screen.contains("ΔI"), "{screen}");
        insta::assert_snapshot!(format!("tour_curves_contrast_{w}x{h}"), screen);
    }
}

#[test]
fn the_figures_and_worked_examples_stand_in_the_pictures_place() {
    let mut app = ready_app();
    app.tour = Some(Tour::new(false));
    let boards: Vec<(usize, Board)> = PAGES
        .iter()
        .enumerate()
        .filter_map(|(i, p)| Some((i, p.board?)))
        .collect();
    assert_eq!(boards.len(), 5);
    // Each worked example comes before the page of the volume's numbers it prepares.
    assert_eq!(PAGES[BLOCKS].board, None);
    assert_eq!(boards[2], (BLOCKS - 1, Board::Blocks));
    let w = slabscope::explain::worked();
    for (page, board) in boards {
        app.tour.as_mut().unwrap().page = page;
        app.tour.as_mut().unwrap().applied = false;
        app.update(Action::TurnPage(0));
        assert!(
            app.preview.covered,
            "page {}: the picture is not covered",
            page + 1
        );
        for (w_, h) in [(80, 24), (160, 48)] {
            let screen = screens(&mut app, w_, h, vec![]).remove(0);
            let words: Vec<String> = match board {
                Board::Sphere => vec!["Fig. 1a".into(), "●".into()],
                Board::Rays => vec!["Fig. 1b".into(), "●".into(), "•".into()],
                Board::Blocks => vec![format!("{:.4} bits per sample", w.ray.entropy_rate)],
                Board::Js => vec![format!("= {:.4} bits", w.js.js)],
                Board::Nmi => vec![format!("NMI = MI / H(X,Y) = {:.4}", w.nmi.nmi)],
            };
            for word in words {
                assert!(
                    screen.contains(&word),
                    "{word} not on page {}:\n{screen}",
                    page + 1
                );
            }
            insta::assert_snapshot!(format!("tour_board_{}_{w_}x{h}", page + 1), screen);
        }
    }
    // The next page without a board uncovers the picture.
    app.tour.as_mut().unwrap().page = 0;
    app.update(Action::TurnPage(0));
    assert!(!app.preview.covered);
}

/// The render a page asks for, if any.
fn render_of(effects: &[Effect]) -> Option<&crate::tui::event::PictureJob> {
    effects.iter().find_map(|e| match e {
        Effect::Render(job) => Some(job.as_ref()),
        _ => None,
    })
}

#[test]
fn the_figures_are_the_preview_s_picture_where_the_terminal_draws_images() {
    for graphics in ["sixel", "half-blocks"] {
        let mut app = ready_app();
        app.preview.graphics = graphics;
        app.preview.cells = (60, 20);
        app.tour = Some(Tour::new(false));
        app.update(Action::TurnPage(0));
        let images = graphics == "sixel";
        for (page, board) in [(1, Board::Sphere), (2, Board::Rays)] {
            assert_eq!(PAGES[page].board, Some(board));
            let effects = app.update(Action::TurnPage(1));
            let job = render_of(&effects).expect("the page renders");
            // Through the image protocol the figure is the picture, not covered by the board;
            // on half-blocks the board draws it in braille over the covered picture.
            assert_eq!(job.figure.is_some(), images, "{graphics} page {}", page + 1);
            assert_eq!(app.preview.covered, !images, "{graphics} page {}", page + 1);
            assert_eq!(app.figure_as_image(), images);
            let title = app.preview.figure.clone().unwrap_or_default();
            assert_eq!(title.contains("Fig. 1"), images, "{title}");
            if let Some(figure) = &job.figure {
                use slabscope::explain::figure::Ink;
                // The best viewpoint marked on the sphere; the rays' five samples.
                let dots = |ink| figure.dots.iter().filter(|d| d.ink == ink).count();
                match board {
                    Board::Sphere => assert_eq!(dots(Ink::Best), 1),
                    _ => assert_eq!(dots(Ink::Sample), 5),
                }
            }
        }
        // The next page's worked example covers the picture, which is the exploded view again.
        let effects = app.update(Action::TurnPage(1));
        let job = render_of(&effects).expect("the page renders");
        assert!(job.figure.is_none() && app.preview.figure.is_none());
        assert!(app.preview.covered);
    }
}

#[test]
fn the_pages_show_the_slab_count_given() {
    let mut app = ready_app();
    app.params.stop = slabscope::Stop::Slabs(6);
    app.tour = Some(Tour::new(false));
    app.update(Action::TurnPage(0));
    assert_eq!(app.part.slab_count(), Some(6));
    let turn_to = |app: &mut crate::tui::app::App, page: usize| {
        let at = app.tour.as_ref().unwrap().page;
        app.update(Action::TurnPage(page as isize - at as isize));
        assert_eq!(app.tour.as_ref().unwrap().page, page);
    };
    // The curves keep their one slab, the first split its two.
    turn_to(&mut app, CURVES);
    assert_eq!(app.part.slab_count(), Some(1));
    let split = PAGES
        .iter()
        .position(|p| p.title == "The first split")
        .unwrap();
    turn_to(&mut app, split);
    assert_eq!(app.part.slab_count(), Some(2));
    // Top-down and bottom-up are compared at the count given.
    turn_to(&mut app, crate::tui::app::tour::COMPARED);
    assert_eq!(app.part.slab_count(), Some(6));
    let numbers = app.tour.as_ref().unwrap().numbers.clone().unwrap();
    assert!(numbers.starts_with("Here 6 slabs keep"), "{numbers}");
}

#[test]
fn the_merge_page_shows_the_merge_of_the_highest_nmi_and_the_steps_stay_reachable() {
    let mut app = ready_app();
    app.tour = Some(Tour::new(false));
    let effects = app.update(Action::TurnPage(MERGE as isize));
    let upto = app.part.position;
    let subject = answer(&mut app, effects);
    assert!(
        matches!(subject, Subject::BestMerge { upto: u, .. } if u == upto),
        "{subject:?}"
    );
    let h = std::sync::Arc::clone(app.part.ready().unwrap());
    let steps = &h.bottom().unwrap().steps[..upto];
    let Task::Ready(lesson) = &app.lesson.lesson else {
        panic!("no lesson")
    };
    let Lesson::BestMerge { merge, upto: u, of } = lesson.as_ref() else {
        panic!("the best merge's lesson")
    };
    assert_eq!((*u, *of), (upto, h.last(Method::BottomUp)));
    // The first of the highest NMI below 1 among the merges taken to the slabs shown (this
    // volume's first merge joins two slices each of one bin, NMI 1 by convention).
    assert_eq!(merge.step, super::tour_merge::highest(&h, upto));
    let taken = &steps[merge.step - 1];
    assert_eq!(taken.merge, merge.merge);
    assert!(steps.iter().any(|s| s.nmi > taken.nmi), "{}", taken.nmi);
    assert!(merge.h_xy > 0.0, "{merge:?}");
    assert!((merge.nmi - taken.nmi).abs() < 1e-12, "{}", merge.nmi);
    // Not the last on this volume: the page's example differs from the step shown.
    assert!(merge.step < upto, "{} of {upto}", merge.step);
    let (step, of) = (merge.step, *of);
    for (w, hgt) in [(80, 24), (160, 48)] {
        let screen = &screens(&mut app, w, hgt, vec![])[0];
        // On a small terminal the example's numbers in a few lines, the heat map beside them.
        let example = if w == 80 {
            "Example: the highest NMI below 1"
        } else {
            "The example: of the"
        };
        assert!(screen.contains(example), "{screen}");
        assert!(
            screen.contains(&format!("Merge {step} of {of}")),
            "{screen}"
        );
    }
    // p steps back from the step shown, and the lesson follows the steps from then on, even
    // back at the page's step.
    let effects = app.update(Action::Step(-1));
    assert!(matches!(
        answer(&mut app, effects),
        Subject::Step { position, .. } if position == upto - 1
    ));
    let effects = app.update(Action::Step(1));
    assert!(matches!(
        answer(&mut app, effects),
        Subject::Step { position, .. } if position == upto
    ));
    let Task::Ready(lesson) = &app.lesson.lesson else {
        panic!("no lesson")
    };
    assert!(matches!(lesson.as_ref(), Lesson::Merge(m, _) if m.step == upto));
    // Turning back to the page shows its example again.
    app.update(Action::TurnPage(1));
    let effects = app.update(Action::TurnPage(-1));
    assert!(matches!(
        answer(&mut app, effects),
        Subject::BestMerge { .. }
    ));
}

#[test]
fn the_last_page_shows_the_exploded_view_large() {
    let mut app = ready_app();
    app.tour = Some(Tour::new(false));
    app.update(Action::TurnPage(PAGES.len() as isize - 1));
    assert!(app.preview_large());
    for (w, h) in [(80, 24), (160, 48)] {
        let screen = &screens(&mut app, w, h, vec![])[0];
        // The preview over the four panes: as wide as the screen, down to the tour's page.
        let area = ratatui::layout::Rect::new(0, 0, w, h);
        let cells = crate::tui::ui::preview_cells(area, true, None, true).unwrap();
        let page = if h < 36 { 6 } else { 8 };
        assert_eq!(cells, (w - 2, h - page - 2 - 2));
        assert_eq!(app.preview.cells, cells, "the picture asked at that size");
        let first = screen.lines().next().unwrap();
        assert!(first.starts_with("┌ Exploded view"), "{screen}");
        assert!(
            !screen.contains("Slabs") && !screen.contains("Curves"),
            "{screen}"
        );
    }
    // The page before, the lesson or the help: the panes as ever.
    app.update(Action::ToggleLesson);
    assert!(!app.preview_large());
    app.update(Action::ToggleLesson);
    app.update(Action::TurnPage(-1));
    assert!(!app.preview_large());
    screens(&mut app, 160, 48, vec![]);
    let area = ratatui::layout::Rect::new(0, 0, 160, 48);
    let small = crate::tui::ui::preview_cells(area, true, None, false).unwrap();
    assert!(small.0 < 120, "{small:?}");
    assert_eq!(app.preview.cells, small);
}
