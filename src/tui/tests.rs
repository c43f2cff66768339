//! Tests of the TUI without a terminal: `update` for every action, each pane rendered into a
//! buffer, and whole-app snapshots driven by keys and fake job results on a `TestBackend`.
//!
//! Snapshots live in `src/tui/snapshots/`; `INSTA_UPDATE=always cargo test` rewrites them.

use std::sync::{Arc, OnceLock};

use crossterm::event::{KeyCode, KeyEvent, KeyModifiers};
use image::{Rgba, RgbaImage};
use ratatui::Terminal;
use ratatui::backend::TestBackend;
use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::widgets::Widget;
use slabscope::partition::{Method, StackParams};
use slabscope::render::{Mode, Preset};
use slabscope::view::{ViewParams, ViewSearch, search};
use slabscope::volume::phantom;
use slabscope::{AnalysisParams, Histories, Monitor, Progress, Scope, Volume};

use super::app::{App, Pane, Screen};
use super::event::{Action, Ask, Effect, Event, Job, JobMsg, Rendered, Task};
use super::panes;
use super::theme::Theme;
use super::{Runner, handle, redraw};
use crate::term::Caps;
use crate::term::image::{TermImage, encode};

/// Records effects instead of running them.
#[derive(Default)]
struct Recorder(Vec<Effect>);

impl Runner for Recorder {
    fn run(&mut self, effect: Effect) {
        self.0.push(effect);
    }
}

const PLAIN: Theme = Theme {
    color: false,
    contrast: false,
};

/// A small volume, its view search and its histories along the best axis, computed once for all
/// tests.
fn fixture() -> &'static (Arc<Volume>, ViewSearch, Arc<Histories>) {
    static FIXTURE: OnceLock<(Arc<Volume>, ViewSearch, Arc<Histories>)> = OnceLock::new();
    FIXTURE.get_or_init(|| {
        let volume = Arc::new(phantom::body([24, 24, 40], 1).unwrap());
        let views = search(&volume, &ViewParams::default(), &Monitor::none()).unwrap();
        let histories = Histories::new(
            &volume,
            views.best().axis,
            &StackParams::default(),
            Scope::ALL,
            &Monitor::none(),
        )
        .unwrap();
        (volume, views, Arc::new(histories))
    })
}

/// The fixture's volume searched and partitioned the paper's way (`tour --paper`).
fn paper_fixture() -> &'static (ViewSearch, Arc<Histories>) {
    static FIXTURE: OnceLock<(ViewSearch, Arc<Histories>)> = OnceLock::new();
    FIXTURE.get_or_init(|| {
        let volume = &fixture().0;
        let views = search(volume, &ViewParams::paper(), &Monitor::none()).unwrap();
        let stack = StackParams {
            background: slabscope::volume::background::BackgroundRule::None,
            ..StackParams::default()
        };
        let histories = Histories::new(
            volume,
            views.best().axis,
            &stack,
            Scope::ALL,
            &Monitor::none(),
        );
        (views, Arc::new(histories.unwrap()))
    })
}

/// An app in paper mode taken through loading, the view search and the analysis.
fn ready_paper_app() -> App {
    let (volume, ..) = fixture();
    let (views, analysis) = paper_fixture();
    let params = slabscope::params::Given::new()
        .with(&slabscope::params::table::PAPER, "true")
        .analysis()
        .unwrap();
    let screen = Screen {
        theme: PLAIN,
        ..Screen::default()
    };
    let (mut app, _) = App::new("body.nrrd".into(), params, screen);
    feed(&mut app, volume, views, analysis);
    app
}

/// Hands `app` the volume, its view search and its histories, as the jobs would report them.
fn feed(app: &mut App, volume: &Arc<Volume>, views: &ViewSearch, histories: &Arc<Histories>) {
    app.update(Action::Job(JobMsg::Loaded(Ok((
        Arc::clone(volume),
        vec![],
    )))));
    app.update(Action::Job(JobMsg::Views(0, Ok(Box::new(views.clone())))));
    app.update(Action::Job(JobMsg::Analysis(
        1,
        0,
        Ok(Arc::clone(histories)),
    )));
}

/// An app with the default parameters.
fn new_app(name: &str, theme: Theme) -> (App, Vec<Effect>) {
    let screen = Screen {
        theme,
        ..Screen::default()
    };
    App::new(name.into(), AnalysisParams::default(), screen)
}

/// An app taken through loading, the view search and the analysis, as the jobs would report.
fn ready_app() -> App {
    ready_app_with(PLAIN)
}

fn ready_app_with(theme: Theme) -> App {
    let (volume, views, analysis) = fixture();
    let (mut app, effects) = new_app("body.nrrd", theme);
    assert!(matches!(effects[..], [Effect::Load]));
    let effects = app.update(Action::Job(JobMsg::Loaded(Ok((
        Arc::clone(volume),
        vec![],
    )))));
    assert!(
        matches!(effects[..], [Effect::SearchViews(_, 0)]),
        "{effects:?}"
    );
    let effects = app.update(Action::Job(JobMsg::Views(0, Ok(Box::new(views.clone())))));
    match &effects[..] {
        [Effect::Analyze(1, axis, _, 0)] => assert_eq!(*axis, views.best().axis),
        other => panic!("{other:?}"),
    }
    app.update(Action::Job(JobMsg::Analysis(
        1,
        0,
        Ok(Arc::clone(analysis)),
    )));
    app
}

fn key(c: char) -> Event {
    Event::Key(KeyEvent::new(KeyCode::Char(c), KeyModifiers::NONE))
}

mod folder;
mod gain;
mod keys;
mod lesson;
mod pages;
mod tour;
mod tour_merge;
mod upgrade;

#[test]
fn the_analysis_opens_on_four_top_down_slabs() {
    let app = ready_app();
    assert_eq!(app.part.method, Method::TopDown);
    assert_eq!(app.part.slabs().unwrap().len(), 4);
    assert_eq!(app.part.position, 3);
}

#[test]
fn stepping_moves_through_the_history_and_stops_at_its_ends() {
    let mut app = ready_app();
    app.preview.cells = (40, 12);
    let effects = app.update(Action::Step(1));
    assert_eq!(app.part.slabs().unwrap().len(), 5);
    assert!(
        matches!(effects[..], [Effect::Render(_)]),
        "a step re-renders"
    );
    app.update(Action::StepTo(false));
    assert_eq!(app.part.position, 0);
    assert!(app.update(Action::Step(-1)).is_empty());
    assert_eq!(app.part.position, 0);
    assert_eq!(
        app.status.message.as_deref(),
        Some("at the start of the history")
    );
    app.update(Action::StepTo(true));
    let last = app.part.ready().unwrap().last(Method::TopDown);
    assert_eq!(app.part.position, last);
    assert_eq!(
        app.part.slabs().unwrap().len(),
        40,
        "every slice its own slab"
    );
    app.update(Action::Step(1));
    assert_eq!(
        app.status.message.as_deref(),
        Some("at the end of the history")
    );
}

#[test]
fn switching_method_keeps_the_slab_count() {
    let mut app = ready_app();
    for method in [Method::BottomUp, Method::Optimal, Method::TopDown] {
        app.update(Action::CycleMethod);
        assert_eq!(app.part.method, method);
        assert_eq!(app.part.slabs().unwrap().len(), 4, "{method:?}");
    }
    app.update(Action::CycleMethod);
    app.update(Action::Step(1));
    assert_eq!(
        app.part.slabs().unwrap().len(),
        3,
        "a bottom-up step merges"
    );
    app.update(Action::Slabs(2));
    assert_eq!(app.part.slabs().unwrap().len(), 5);
    app.update(Action::Slabs(-10));
    assert_eq!(app.part.slabs().unwrap().len(), 1);
}

#[test]
fn prompts_take_an_axis_and_a_threshold() {
    let mut app = ready_app();
    app.update(Action::Ask(Ask::Axis));
    for c in "0,1,1".chars() {
        app.update(Action::Type(c));
    }
    app.update(Action::Erase);
    app.update(Action::Type('2'));
    match &app.update(Action::Submit)[..] {
        [Effect::Analyze(2, axis, _, 0)] => {
            assert_eq!(
                *axis,
                slabscope::Axis::new([0.0, 1.0, 2.0]).unwrap().direction()
            );
        }
        other => panic!("{other:?}"),
    }
    assert!(app.part.histories.running());
    let mut app = ready_app();
    app.update(Action::Ask(Ask::Axis));
    app.update(Action::Type('w'));
    assert!(app.update(Action::Submit).is_empty());
    assert!(
        app.status
            .message
            .as_deref()
            .unwrap()
            .contains("is not x, y, z")
    );
    app.update(Action::Ask(Ask::Threshold));
    for c in "0.002".chars() {
        app.update(Action::Type(c));
    }
    app.update(Action::Submit);
    assert_eq!(app.part.threshold, Some(0.002));
    assert_eq!(
        app.part.position,
        app.part.ready().unwrap().top().steps_above(0.002)
    );
    app.update(Action::Ask(Ask::Threshold));
    app.update(Action::Escape);
    assert!(app.status.prompt.is_none(), "Esc closes a prompt");
}

#[test]
fn selecting_a_viewpoint_partitions_along_it() {
    let mut app = ready_app();
    app.update(Action::Move(2));
    assert_eq!(app.views.row, 2);
    let axis = fixture().1.views[2].axis;
    match &app.update(Action::Select)[..] {
        [Effect::Analyze(2, a, _, 0)] => assert_eq!(*a, axis),
        other => panic!("{other:?}"),
    }
    app.update(Action::Move(-10));
    assert_eq!(app.views.row, 0, "the cursor stops at the top");
}

#[test]
fn stale_results_are_dropped() {
    let mut app = ready_app();
    app.update(Action::Ask(Ask::Axis));
    app.update(Action::Type('x'));
    app.update(Action::Submit);
    // A late result of the first request (generation 1) does not replace the running one.
    app.update(Action::Job(JobMsg::Analysis(
        1,
        0,
        Ok(Arc::clone(&fixture().2)),
    )));
    assert!(app.part.histories.running());
    app.preview.cells = (20, 8);
    app.update(Action::Orbit(15.0, 0.0));
    app.update(Action::Orbit(15.0, 0.0));
    let image = Box::new(rendered(20, 8));
    app.update(Action::Job(JobMsg::Rendered(1, Ok(image))));
    assert!(
        !matches!(app.preview.image, Task::Ready(_)),
        "an older render is not shown"
    );
}

#[test]
fn escape_cancels_running_work_and_quit_quits() {
    let (mut app, _) = new_app("x", PLAIN);
    app.views.views = Task::Running(Progress {
        phase: "view search",
        fraction: 0.4,
    });
    assert!(matches!(app.update(Action::Escape)[..], [Effect::Cancel]));
    assert!(matches!(app.views.views, Task::Failed(_)));
    app.update(Action::ToggleHelp);
    assert!(app.help);
    assert!(app.update(Action::Escape).is_empty());
    assert!(!app.help, "Esc closes the help first");
    assert!(matches!(
        app.update(Action::Quit)[..],
        [Effect::Cancel, Effect::Quit]
    ));
    assert!(app.quit);
}

#[test]
fn the_look_changes_re_render() {
    let mut app = ready_app();
    assert!(
        app.update(Action::Orbit(15.0, 0.0)).is_empty(),
        "no preview area yet"
    );
    app.update(Action::PreviewArea(30, 10));
    assert!(
        app.update(Action::PreviewArea(30, 10)).is_empty(),
        "same size: nothing to do"
    );
    let render = |effects: Vec<Effect>| match effects.into_iter().next() {
        Some(Effect::Render(r)) => r,
        other => panic!("{other:?}"),
    };
    let r = render(app.update(Action::Orbit(15.0, -30.0)));
    assert_eq!(
        (r.look.camera.azimuth, r.look.camera.elevation),
        (60.0, -10.0),
        "30° + two orbits of 15°"
    );
    assert_eq!(r.slabs.len(), 4);
    assert_eq!(render(app.update(Action::ToggleMode)).look.mode, Mode::Dvr);
    assert_eq!(render(app.update(Action::ToggleMode)).look.mode, Mode::Mip);
    assert_eq!(render(app.update(Action::ToggleMode)).look.mode, Mode::Cut);
    for _ in 0..30 {
        app.update(Action::Spread(0.1));
    }
    assert_eq!(app.preview.look.spread, 2.0, "spread is capped");
    app.focus = Pane::Slabs;
    let r = render(app.update(Action::Move(1)));
    assert_eq!(r.highlight, Some(1), "the selected slab is highlighted");
    let r = render(app.update(Action::ToggleSolo));
    assert!(r.look.solo);
    assert!(matches!(
        app.update(Action::Export)[..],
        [Effect::Export(_)]
    ));
    app.update(Action::Focus(1));
    assert_eq!(app.focus, Pane::Curves);
    app.update(Action::Move(5));
    assert_eq!(app.curves.cursor, 5);
}

#[test]
fn progress_updates_the_gauges() {
    let (mut app, _) = new_app("x", PLAIN);
    let half = Progress {
        phase: "loading",
        fraction: 0.5,
    };
    app.update(Action::Job(JobMsg::Progress(Job::Load, half)));
    assert!(matches!(app.volume, Task::Running(p) if p == half));
    app.update(Action::Job(JobMsg::Loaded(Err("x: truncated".into()))));
    assert!(matches!(app.volume, Task::Failed(_)));
}

/// A half-blocks image of `w × h` cells: a diagonal gradient.
fn tiny_protocol(w: u16, h: u16) -> TermImage {
    let caps = Caps::blocks();
    let (pw, ph) = caps.image_size((w, h));
    let image = RgbaImage::from_fn(pw, ph, |x, y| {
        Rgba([(x * 255 / pw) as u8, (y * 255 / ph) as u8, 128, 255])
    });
    encode(&image, (w, h), &caps).unwrap()
}

/// A render job's result: a gradient in half-blocks.
fn rendered(w: u16, h: u16) -> Rendered {
    Rendered {
        image: tiny_protocol(w, h),
        caption: None,
        window: Some((0.0, 1.0)),
    }
}

/// The characters of a buffer, one line per row.
fn text(buffer: &Buffer) -> String {
    let area = buffer.area;
    (area.y..area.y + area.height)
        .map(|y| {
            (area.x..area.x + area.width)
                .map(|x| buffer[(x, y)].symbol())
                .collect::<String>()
        })
        .collect::<Vec<_>>()
        .join("\n")
}

fn pane(widget: impl Widget, w: u16, h: u16) -> String {
    let mut buffer = Buffer::empty(Rect::new(0, 0, w, h));
    widget.render(buffer.area, &mut buffer);
    text(&buffer)
}

#[test]
fn panes_render_into_buffers() {
    let mut app = ready_app();
    app.focus = Pane::Slabs;
    app.views.focused = false;
    insta::assert_snapshot!("views", pane(&app.views, 40, 12));
    app.views.focused = true;
    insta::assert_snapshot!("views_wide_with_sphere", pane(&app.views, 90, 14));
    app.slabs.focused = true;
    insta::assert_snapshot!("slabs", pane(&app.slabs, 60, 9));
    insta::assert_snapshot!("curves", pane(&app.curves, 60, 12));
    insta::assert_snapshot!("status", pane(&app.status, 110, 2));
    insta::assert_snapshot!("help", pane(&panes::help::Help { theme: PLAIN }, 70, 24));
}

/// Runs `events` through the app on a test terminal of `w × h`, returning the screen after each.
fn screens(app: &mut App, w: u16, h: u16, events: Vec<Event>) -> Vec<String> {
    let mut terminal = Terminal::new(TestBackend::new(w, h)).unwrap();
    let mut runner = Recorder::default();
    let mut out = Vec::new();
    redraw(&mut terminal, app, &mut runner).unwrap();
    out.push(text(terminal.backend().buffer()));
    for event in events {
        handle(app, &mut runner, event);
        redraw(&mut terminal, app, &mut runner).unwrap();
        out.push(text(terminal.backend().buffer()));
    }
    out
}

#[test]
fn whole_app_snapshots() {
    let mut app = ready_app();
    let cells = super::ui::preview_cells(Rect::new(0, 0, 100, 30), false, None, false).unwrap();
    let events = vec![
        Event::Job(JobMsg::Rendered(
            1,
            Ok(Box::new(rendered(cells.0, cells.1))),
        )),
        key('m'),
        Event::Key(KeyEvent::new(KeyCode::Home, KeyModifiers::NONE)),
        key('n'),
    ];
    let shots = screens(&mut app, 100, 30, events);
    insta::assert_snapshot!("app_top_down", shots[1]);
    insta::assert_snapshot!("app_bottom_up_one_merge", shots[4]);
    let mut small = ready_app();
    insta::assert_snapshot!("app_80x24", screens(&mut small, 80, 24, vec![])[0]);
    insta::assert_snapshot!(
        "app_too_small",
        screens(&mut ready_app(), 50, 15, vec![])[0]
    );
}

/// Not a test but a measurement: `cargo test --release --bin slabscope tui_step_timing -- --ignored
/// --nocapture` prints the time of one step forward or back, from the key to the redrawn screen.
#[test]
#[ignore = "a benchmark: prints timings, asserts nothing about them"]
fn tui_step_timing() {
    for (w, h) in [(80, 24), (200, 60)] {
        let mut app = ready_app_with(Theme {
            color: true,
            contrast: false,
        });
        let mut terminal = Terminal::new(TestBackend::new(w, h)).unwrap();
        let mut runner = Recorder::default();
        redraw(&mut terminal, &mut app, &mut runner).unwrap();
        let steps = 400;
        let start = std::time::Instant::now();
        for i in 0..steps {
            handle(
                &mut app,
                &mut runner,
                key(if i % 2 == 0 { 'n' } else { 'p' }),
            );
            redraw(&mut terminal, &mut app, &mut runner).unwrap();
        }
        let per = start.elapsed().as_secs_f64() * 1e3 / f64::from(steps);
        println!("{w}x{h}: {per:.3} ms per step and redraw");
    }
}

#[test]
fn the_slice_view_follows_the_cursor_and_its_pointer() {
    let mut app = ready_app();
    app.preview.cells = (40, 12);
    let render = |effects: Vec<Effect>| match effects.into_iter().next() {
        Some(Effect::Render(r)) => r,
        other => panic!("{other:?}"),
    };
    assert!(render(app.update(Action::Orbit(0.0, 0.0))).slice.is_none());
    let r = render(app.update(Action::ToggleSlices));
    let first = r.slice.expect("the slice view asks for a slice");
    assert_eq!(first.index, app.curves.cursor);
    // The curves' cursor picks the slice.
    app.focus = Pane::Curves;
    let r = render(app.update(Action::Move(5)));
    assert_eq!(r.slice.unwrap().index, first.index + 5);
    // In the preview, the arrows move the pointer by a voxel across the screen.
    app.focus = Pane::Preview;
    let r = render(app.update(Action::Sideways(1)));
    let moved = r.slice.unwrap().pointer;
    let step: f64 = (0..3)
        .map(|m| (moved[m] - first.pointer[m]).powi(2))
        .sum::<f64>()
        .sqrt();
    let spacing = app.volume.ready().unwrap().spacing();
    let voxel = spacing.iter().copied().fold(f64::INFINITY, f64::min);
    assert!((step - voxel).abs() < 1e-9, "{step} vs {voxel}");
    let r = render(app.update(Action::Move(1)));
    assert_ne!(r.slice.unwrap().pointer, moved, "up and down move it too");
    assert!(render(app.update(Action::ToggleSlices)).slice.is_none());
}

#[test]
fn window_keys_narrow_widen_and_move_the_window() {
    let mut app = ready_app();
    app.preview.cells = (40, 12);
    let window = |effects: Vec<Effect>| match effects.into_iter().next() {
        Some(Effect::Render(r)) => r.look.window.expect("a window"),
        other => panic!("{other:?}"),
    };
    let (lo, hi) = window(app.update(Action::WindowWidth(1.0)));
    let (nlo, nhi) = window(app.update(Action::WindowWidth(0.8)));
    assert!(((nhi - nlo) - 0.8 * (hi - lo)).abs() < 1e-3 * (hi - lo));
    assert!((f32::midpoint(nlo, nhi) - f32::midpoint(lo, hi)).abs() < 1e-3 * (hi - lo));
    let (mlo, mhi) = window(app.update(Action::WindowLevel(0.05)));
    assert!((mlo - nlo - 0.05 * (nhi - nlo)).abs() < 1e-3 * (hi - lo));
    assert!((mhi - mlo - (nhi - nlo)).abs() < 1e-3 * (hi - lo));
    // A new transfer function starts from its own window again: the one its picture used.
    app.update(Action::CycleTransfer);
    assert_eq!(app.preview.look.window, None);
    let picture = Rendered {
        window: Some((10.0, 30.0)),
        ..rendered(40, 12)
    };
    let generation = app.preview.generation;
    app.update(Action::Job(JobMsg::Rendered(
        generation,
        Ok(Box::new(picture)),
    )));
    assert_eq!(window(app.update(Action::WindowWidth(0.5))), (15.0, 25.0));
}

#[test]
fn transfer_functions_that_do_not_fit_are_skipped() {
    let mut app = ready_app();
    let stats = app.volume.ready().unwrap().stats();
    let mut seen = vec![app.preview.look.preset];
    for _ in 0..4 {
        app.update(Action::CycleTransfer);
        seen.push(app.preview.look.preset);
    }
    for p in &seen {
        assert!(p.suits(stats), "{p:?}");
    }
    let ct = stats.min <= -500.0;
    assert_eq!(seen.contains(&Preset::CtBone), ct, "{seen:?}");
}
