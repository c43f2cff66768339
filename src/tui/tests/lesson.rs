//! The lesson pane: `x` asks for the numbers of what is selected (the viewpoint beside the best,
//! or the step shown), stepping asks again, and every number shows as text at 80×24 and 160×50.

use slabscope::Monitor;
use slabscope::partition::Method;

use super::{pane, ready_app};
use crate::tui::app::{App, Pane};
use crate::tui::event::{Action, Effect, JobMsg, Task};
use crate::tui::lesson::{Lesson, Subject};

/// Runs the lesson request among `effects` as the jobs would and hands the app its answer;
/// returns the subject it was about.
pub(super) fn answer(app: &mut App, effects: Vec<Effect>) -> Subject {
    let request = effects
        .into_iter()
        .find_map(|e| match e {
            Effect::Lesson(r) => Some(r),
            _ => None,
        })
        .expect("a lesson request");
    let result = request.compute(&Monitor::none()).map(Box::new);
    app.update(Action::Job(JobMsg::Lesson(request.generation, result)));
    request.subject.clone()
}

/// The pane as text, its lines joined (numbers are never cut by the wrapping).
fn shown(app: &App, w: u16, h: u16) -> String {
    pane(&app.lesson, w, h)
}

fn lesson(app: &App) -> &Lesson {
    match &app.lesson.lesson {
        Task::Ready(l) => l,
        Task::Failed(e) => panic!("the lesson failed: {e}"),
        _ => panic!("no lesson yet"),
    }
}

fn assert_shows(text: &str, numbers: &[f64]) {
    for n in numbers {
        let n = format!("{n:.4}");
        assert!(text.contains(&n), "{n} is not shown in\n{text}");
    }
}

#[test]
fn a_viewpoints_lesson_shows_its_blocks_beside_the_best() {
    let mut app = ready_app();
    assert_eq!(app.focus, Pane::Views);
    let effects = app.update(Action::ToggleLesson);
    assert!(app.lesson.open);
    let subject = answer(&mut app, effects);
    assert!(
        matches!(subject, Subject::Axis { offset: (0, 0), .. }),
        "{subject:?}"
    );
    // Another viewpoint: its own lesson, beside the best.
    let effects = app.update(Action::Move(1));
    let Subject::Axis { selected, best, .. } = answer(&mut app, effects) else {
        panic!("an axis lesson")
    };
    assert_ne!(selected, best);
    let Lesson::Axis {
        selected: s,
        best: b,
        ray,
        plane,
    } = lesson(&app)
    else {
        panic!("an axis lesson")
    };
    assert!(ray.as_ref().is_some_and(|r| !r.bins.is_empty()));
    assert!(plane.as_ref().is_some_and(|p| p.selected.is_some()));
    let numbers: Vec<f64> = [s, b]
        .iter()
        .flat_map(|l| l.block_entropies.iter().copied().chain([l.entropy_rate]))
        .collect();
    let (small, large) = (shown(&app, 80, 22), shown(&app, 160, 48));
    assert_shows(&small, &numbers);
    assert_shows(&large, &numbers);
    let first = &s.blocks[0];
    assert!(large.contains(&format!(
        "{} ×",
        slabscope::explain::text::block_text(&first.symbols)
    )));
    insta::assert_snapshot!("lesson_axis_80x22", small);
    insta::assert_snapshot!("lesson_axis_160x48", large);
    // ← → move to the neighbouring rays: a new request.
    let effects = app.update(Action::Sideways(1));
    let Subject::Axis { offset, .. } = answer(&mut app, effects) else {
        panic!("an axis lesson")
    };
    assert_eq!(offset, (1, 0));
}

#[test]
fn a_steps_lesson_follows_the_steps_and_the_method() {
    let mut app = ready_app();
    app.update(Action::Focus(1));
    let effects = app.update(Action::ToggleLesson);
    let subject = answer(&mut app, effects);
    assert_eq!(
        subject,
        Subject::Step {
            method: Method::TopDown,
            position: 3,
            generation: 1
        }
    );
    let Lesson::Split(split) = lesson(&app) else {
        panic!("a split lesson")
    };
    let mut numbers = vec![split.js, split.gain, split.information];
    numbers.extend(split.weights);
    numbers.extend(split.entropies);
    let (small, large) = (shown(&app, 80, 22), shown(&app, 160, 48));
    assert_shows(&small, &numbers);
    assert_shows(&large, &numbers);
    // The histograms' shared bins and the cuts' slices are ticked, each chart's top said.
    for text in [&small, &large] {
        assert!(text.contains("bin 0") && text.contains("slice"), "{text}");
        assert!(text.contains(&format!("≤{:.4}", split.gain)), "{text}");
    }
    insta::assert_snapshot!("lesson_split_80x22", small);
    insta::assert_snapshot!("lesson_split_160x48", large);
    // Stepping back explains the split now last.
    let effects = app.update(Action::Step(-1));
    assert!(matches!(
        answer(&mut app, effects),
        Subject::Step { position: 2, .. }
    ));
    // Bottom-up: the merge's joint histogram and NMI.
    let effects = app.update(Action::CycleMethod);
    assert!(matches!(
        answer(&mut app, effects),
        Subject::Step {
            method: Method::BottomUp,
            ..
        }
    ));
    let Lesson::Merge(merge, of) = lesson(&app) else {
        panic!("a merge lesson")
    };
    // One merge of the whole history, as the status line counts its steps.
    let history = app.part.ready().unwrap().last(Method::BottomUp);
    assert_eq!(*of, history);
    let numbers = [merge.h_x, merge.h_y, merge.h_xy, merge.mi, merge.nmi];
    let (small, large) = (shown(&app, 80, 22), shown(&app, 160, 48));
    assert_shows(&small, &numbers);
    assert_shows(&large, &numbers);
    // The heat map's axes: X's bins down, Y's across, and its colour scale up to the most.
    for text in [&small, &large] {
        assert!(text.contains("X's bin down, Y's across"), "{text}");
        assert!(
            text.contains("   1  ") && text.contains(" counts"),
            "{text}"
        );
    }
    insta::assert_snapshot!("lesson_merge_80x22", small);
    insta::assert_snapshot!("lesson_merge_160x48", large);
    // The optimum beside greedy.
    let effects = app.update(Action::CycleMethod);
    answer(&mut app, effects);
    let Lesson::Optimal(o) = lesson(&app) else {
        panic!("the optimum's lesson")
    };
    let (small, large) = (shown(&app, 80, 22), shown(&app, 160, 48));
    assert_shows(&small, &[o.optimal, o.greedy]);
    assert_shows(&large, &[o.optimal, o.greedy]);
    for b in &o.optimal_boundaries {
        assert!(small.contains(&b.to_string()));
    }
    insta::assert_snapshot!("lesson_optimal_80x22", small);
    insta::assert_snapshot!("lesson_optimal_160x48", large);
    // Esc closes the lesson, and nothing more is asked for.
    assert!(app.update(Action::Escape).is_empty());
    assert!(!app.lesson.open);
    assert!(
        app.update(Action::Step(1))
            .iter()
            .all(|e| !matches!(e, Effect::Lesson(_)))
    );
}
