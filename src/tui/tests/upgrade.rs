//! A large volume's preview in the TUI: a coarse pyramid level shows first, and full resolution
//! replaces it in place.

use std::sync::{Arc, OnceLock};

use slabscope::partition::{Method, StackParams};
use slabscope::volume::phantom;
use slabscope::{AnalysisParams, Histories, Monitor, Scope, ViewParams, ViewSearch, Volume};

use crate::tui::app::{App, Screen};
use crate::tui::event::{Action, Effect, JobMsg, Task};

/// A volume just over the preview's size, its preview level, the preview's view search and
/// both resolutions' histories along z.
struct Big {
    volume: Arc<Volume>,
    coarse: Arc<Volume>,
    views: ViewSearch,
    along_z: [Arc<Histories>; 2],
}

fn big() -> &'static Big {
    static BIG: OnceLock<Big> = OnceLock::new();
    BIG.get_or_init(|| {
        let volume = Arc::new(phantom::body([130, 130, 132], 1).unwrap());
        assert_eq!(crate::tui::preview_level(&volume), 1, "65×65×66");
        let coarse = volume.coarser(1);
        let mut views =
            slabscope::search(&coarse, &ViewParams::default(), &Monitor::none()).unwrap();
        // Put z first, so that both resolutions' best is the axis of the histories.
        let z = views
            .views
            .iter()
            .position(|v| v.axis == [0.0, 0.0, 1.0])
            .unwrap();
        views.views.swap(0, z);
        views.refined = None;
        let along_z = [&volume, &coarse].map(|v| {
            let h = Histories::new(
                v,
                [0.0, 0.0, 1.0],
                &StackParams::default(),
                Scope::ALL,
                &Monitor::none(),
            );
            Arc::new(h.unwrap())
        });
        Big {
            volume,
            coarse,
            views,
            along_z,
        }
    })
}

fn job(app: &mut App, msg: JobMsg) -> Vec<Effect> {
    app.update(Action::Job(msg))
}

/// An app on the big volume taken through its preview: loaded, the preview's views and
/// histories shown.
fn previewed() -> (App, Vec<Effect>) {
    let b = big();
    let (mut app, _) = App::new("big".into(), AnalysisParams::default(), Screen::default());
    app.preview.cells = (40, 12);
    let effects = job(
        &mut app,
        JobMsg::Loaded(Ok((Arc::clone(&b.volume), vec![]))),
    );
    assert!(
        matches!(effects[0], Effect::SearchViews(_, 1)),
        "{effects:?}"
    );
    match &effects[1] {
        Effect::Render(r) => assert_eq!(r.level, 1, "the first picture is the preview's"),
        other => panic!("{other:?}"),
    }
    job(&mut app, JobMsg::Coarse(Arc::clone(&b.coarse)));
    let effects = job(&mut app, JobMsg::Views(1, Ok(Box::new(b.views.clone()))));
    assert!(
        matches!(effects[..], [Effect::Analyze(1, [0.0, 0.0, 1.0], _, 1)]),
        "{effects:?}"
    );
    let effects = job(
        &mut app,
        JobMsg::Analysis(1, 1, Ok(Arc::clone(&b.along_z[1]))),
    );
    (app, effects)
}

#[test]
fn a_large_volume_shows_its_preview_then_full_resolution_in_place() {
    let b = big();
    let (mut app, effects) = previewed();
    // The preview shows, labelled; the full-resolution view search starts, and a picture.
    assert!(
        matches!(effects[0], Effect::SearchViews(_, 0)),
        "{effects:?}"
    );
    assert!(matches!(&effects[1], Effect::Render(r) if r.level == 1 && r.slabs.len() == 4));
    assert_eq!(
        app.status.resolution.as_deref(),
        Some("preview: 1/2 resolution")
    );
    assert!(app.status.jobs.iter().any(|(j, _)| *j == "full resolution"));
    // The user moves on while full resolution runs: bottom-up, 6 slabs.
    app.update(Action::CycleMethod);
    app.update(Action::Slabs(2));
    assert_eq!(app.part.slab_count(), Some(6));
    // The full search agrees on the axis: the full histories start, the preview stays.
    let effects = job(&mut app, JobMsg::Views(0, Ok(Box::new(b.views.clone()))));
    assert!(
        matches!(effects[..], [Effect::Analyze(2, [0.0, 0.0, 1.0], _, 0)]),
        "{effects:?}"
    );
    assert_eq!(app.part.level, 1);
    assert!(
        app.part.ready().is_some(),
        "the preview's histories stay shown"
    );
    let effects = job(
        &mut app,
        JobMsg::Analysis(2, 0, Ok(Arc::clone(&b.along_z[0]))),
    );
    // Replaced in place: the method and slab count kept, the label gone, a new picture.
    assert_eq!(app.part.level, 0);
    assert!(Arc::ptr_eq(app.part.ready().unwrap(), &b.along_z[0]));
    assert_eq!(
        (app.part.method, app.part.slab_count()),
        (Method::BottomUp, Some(6))
    );
    assert_eq!(app.status.resolution, None);
    assert!(app.status.jobs.is_empty());
    assert!(matches!(&effects[..], [Effect::Render(r)] if r.level == 0 && r.slabs.len() == 6));
    let said = app.status.message.clone().unwrap();
    assert!(said.starts_with("full resolution"), "{said}");
}

#[test]
fn a_new_best_axis_at_full_resolution_is_said_and_followed() {
    let b = big();
    let (mut app, _) = previewed();
    let mut full = b.views.clone();
    full.views.swap(0, 1);
    let new_best = full.views[0].axis;
    let effects = job(&mut app, JobMsg::Views(0, Ok(Box::new(full))));
    // Previewed along the new axis first, then upgraded.
    assert!(
        matches!(effects[..], [Effect::Analyze(2, a, _, 1)] if a == new_best),
        "{effects:?}"
    );
    let said = app.status.message.clone().unwrap();
    assert!(
        said.starts_with("full resolution: the best axis is"),
        "{said}"
    );
}

#[test]
fn an_axis_the_user_chose_is_kept_and_upgraded_at_once() {
    let b = big();
    let (mut app, _) = previewed();
    app.update(Action::Ask(crate::tui::event::Ask::Axis));
    app.update(Action::Type('y'));
    let effects = app.update(Action::Submit);
    assert!(
        matches!(effects[..], [Effect::Analyze(2, [0.0, 1.0, 0.0], _, 1)]),
        "{effects:?}"
    );
    let along_y = Histories::new(
        &b.coarse,
        [0.0, 1.0, 0.0],
        &StackParams::default(),
        Scope::ALL,
        &Monitor::none(),
    );
    let effects = job(
        &mut app,
        JobMsg::Analysis(2, 1, Ok(Arc::new(along_y.unwrap()))),
    );
    // Not the best axis: no need to wait for the full view search.
    assert!(
        effects
            .iter()
            .any(|e| matches!(e, Effect::Analyze(3, [0.0, 1.0, 0.0], _, 0))),
        "{effects:?}"
    );
    // The full search then keeps the user's axis.
    let mut full = b.views.clone();
    full.views.swap(0, 1);
    let effects = job(&mut app, JobMsg::Views(0, Ok(Box::new(full))));
    assert!(effects.is_empty(), "{effects:?}");
    assert_eq!(app.part.axis, Some([0.0, 1.0, 0.0]));
}

#[test]
fn escape_cancels_full_resolution_and_the_preview_stays() {
    let (mut app, _) = previewed();
    let effects = app.update(Action::Escape);
    assert!(matches!(effects[..], [Effect::Cancel]), "{effects:?}");
    assert!(app.part.ready().is_some());
    let label = app.status.resolution.clone().unwrap();
    assert_eq!(label, "preview: 1/2 resolution, full resolution stopped");
    // The cancelled search's late answer changes nothing.
    let effects = job(&mut app, JobMsg::Views(0, Err("cancelled".into())));
    assert!(effects.is_empty());
    assert!(matches!(app.views.views, Task::Ready(_)));
    // Nor what Esc said (the answer may come before or after the key: tmux saw both).
    let said = app.status.message.clone().unwrap_or_default();
    assert!(said.starts_with("cancelled: the preview stays"), "{said}");
}

#[test]
fn a_level_the_file_holds_shows_before_level_0_has_loaded() {
    let b = big();
    let (mut app, _) = App::new("store".into(), AnalysisParams::default(), Screen::default());
    app.preview.cells = (40, 12);
    // An OME-Zarr store's level 1, read before its level 0.
    let effects = job(
        &mut app,
        JobMsg::Preview(Arc::clone(&b.coarse), vec!["a note".into()]),
    );
    assert!(
        matches!(effects[0], Effect::SearchViews(_, 1)),
        "{effects:?}"
    );
    assert!(matches!(&effects[1], Effect::Render(r) if r.level == 1));
    assert_eq!(app.status.message.as_deref(), Some("a note"));
    let label = app.status.resolution.clone().unwrap();
    assert_eq!(
        label,
        "preview: 1/2 resolution (the file's level 1, its own value range)"
    );
    assert!(app.status.jobs.iter().any(|(j, _)| *j == "full resolution"));
    // The preview's views and histories: nothing at full resolution before level 0 is loaded.
    let effects = job(&mut app, JobMsg::Views(1, Ok(Box::new(b.views.clone()))));
    assert!(
        matches!(effects[..], [Effect::Analyze(1, [0.0, 0.0, 1.0], _, 1)]),
        "{effects:?}"
    );
    let effects = job(
        &mut app,
        JobMsg::Analysis(1, 1, Ok(Arc::clone(&b.along_z[1]))),
    );
    assert!(
        !effects.iter().any(|e| matches!(e, Effect::SearchViews(..))),
        "{effects:?}"
    );
    assert!(matches!(&effects[..], [Effect::Render(r)] if r.level == 1 && r.slabs.len() == 4));
    assert!(app.update(Action::Export).is_empty());
    let said = app.status.message.clone().unwrap();
    assert!(said.starts_with("nothing to export until"), "{said}");
    // Level 0 arrives: the full view search starts; the preview stays until it is upgraded.
    let effects = job(
        &mut app,
        JobMsg::Loaded(Ok((Arc::clone(&b.volume), vec![]))),
    );
    assert!(
        matches!(effects[..], [Effect::SearchViews(_, 0)]),
        "{effects:?}"
    );
    assert_eq!(app.part.level, 1);
    let effects = job(&mut app, JobMsg::Views(0, Ok(Box::new(b.views.clone()))));
    assert!(
        matches!(effects[..], [Effect::Analyze(2, [0.0, 0.0, 1.0], _, 0)]),
        "{effects:?}"
    );
    let effects = job(
        &mut app,
        JobMsg::Analysis(2, 0, Ok(Arc::clone(&b.along_z[0]))),
    );
    assert_eq!(app.part.level, 0);
    assert_eq!(app.status.resolution, None);
    assert!(app.status.jobs.is_empty());
    assert!(matches!(&effects[..], [Effect::Render(r)] if r.level == 0));
}

#[test]
fn a_file_preview_after_level_0_or_on_level_0_is_ignored() {
    let b = big();
    let (mut app, _) = App::new("store".into(), AnalysisParams::default(), Screen::default());
    job(
        &mut app,
        JobMsg::Loaded(Ok((Arc::clone(&b.volume), vec![]))),
    );
    let effects = job(&mut app, JobMsg::Preview(Arc::clone(&b.coarse), vec![]));
    assert!(effects.is_empty(), "{effects:?}");
    assert!(!app.upgrade.as_ref().unwrap().from_file);
    let (mut app, _) = App::new("store".into(), AnalysisParams::default(), Screen::default());
    let effects = job(&mut app, JobMsg::Preview(Arc::clone(&b.volume), vec![]));
    assert!(effects.is_empty(), "{effects:?}");
    assert!(app.upgrade.is_none());
}

#[test]
fn level_0_failing_under_a_file_preview_says_so_and_the_preview_stays() {
    let b = big();
    let (mut app, _) = App::new("store".into(), AnalysisParams::default(), Screen::default());
    job(&mut app, JobMsg::Preview(Arc::clone(&b.coarse), vec![]));
    job(&mut app, JobMsg::Views(1, Ok(Box::new(b.views.clone()))));
    job(
        &mut app,
        JobMsg::Analysis(1, 1, Ok(Arc::clone(&b.along_z[1]))),
    );
    job(
        &mut app,
        JobMsg::Loaded(Err("store: chunk 0/0/0 is cut short".into())),
    );
    assert!(app.part.ready().is_some());
    let label = app.status.resolution.clone().unwrap();
    assert!(label.ends_with(", full resolution stopped"), "{label}");
    let said = app.status.message.clone().unwrap();
    assert!(
        said.starts_with("store: chunk 0/0/0 is cut short"),
        "{said}"
    );
}

#[test]
fn a_level_0_beyond_the_budget_starts_afresh_without_the_file_preview() {
    let b = big();
    let (mut app, _) = App::new("store".into(), AnalysisParams::default(), Screen::default());
    app.preview.cells = (40, 12);
    job(&mut app, JobMsg::Preview(Arc::clone(&b.coarse), vec![]));
    job(&mut app, JobMsg::Views(1, Ok(Box::new(b.views.clone()))));
    // Level 0 did not fit: what loaded is itself level 1, of which the file's is no preview.
    let effects = job(
        &mut app,
        JobMsg::Loaded(Ok((Arc::clone(&b.coarse), vec![]))),
    );
    assert!(
        matches!(
            effects[..],
            [
                Effect::Cancel,
                Effect::Forget,
                Effect::SearchViews(_, 0),
                ..
            ]
        ),
        "{effects:?}"
    );
    assert!(app.upgrade.is_none());
    assert!(matches!(app.views.views, Task::Running(_)));
    assert_eq!(app.status.resolution, None);
}

#[test]
fn the_tours_merge_page_shows_the_new_histories_merge_of_the_highest_nmi() {
    use super::lesson::answer;
    use super::tour_merge::highest;
    use crate::tui::lesson::{Lesson, Subject};
    let b = big();
    let (mut app, _) = previewed();
    app.start_tour(false);
    let example = |app: &App| match &app.lesson.lesson {
        Task::Ready(l) => match l.as_ref() {
            Lesson::BestMerge { merge, upto, .. } => (merge.step, *upto),
            _ => panic!("not the best merge's lesson"),
        },
        _ => panic!("no lesson"),
    };
    // The preview's 66 slices to the count where its bottom-up history shows structure.
    let shown = slabscope::explain::structure(b.along_z[1].bottom().unwrap())
        .unwrap()
        .at
        .slabs;
    let upto = 66 - shown;
    let effects = app.update(Action::TurnPage(crate::tui::app::tour::MERGE as isize));
    assert!(matches!(
        answer(&mut app, effects),
        Subject::BestMerge { upto: u, .. } if u == upto
    ));
    let preview = highest(&b.along_z[1], upto);
    assert_eq!(example(&app), (preview, upto));
    // Full resolution's 132 slices replace them in place at the count shown: the example theirs.
    job(&mut app, JobMsg::Views(0, Ok(Box::new(b.views.clone()))));
    let effects = job(
        &mut app,
        JobMsg::Analysis(2, 0, Ok(Arc::clone(&b.along_z[0]))),
    );
    assert_eq!(
        (app.part.method, app.part.slab_count()),
        (Method::BottomUp, Some(shown))
    );
    let upto = 132 - shown;
    assert!(matches!(
        answer(&mut app, effects),
        Subject::BestMerge { upto: u, .. } if u == upto
    ));
    let full = highest(&b.along_z[0], upto);
    assert_eq!(example(&app), (full, upto));
    let steps = &b.along_z[0].bottom().unwrap().steps;
    assert!(
        full < upto && steps[full - 1].nmi > steps[upto - 1].nmi,
        "{full}"
    );
}

/// A picture of the preview marked so that it can be told from any other when shown.
fn picture(caption: &str) -> crate::tui::event::Rendered {
    crate::tui::event::Rendered {
        caption: Some(caption.into()),
        ..super::rendered(40, 12)
    }
}

/// The generation of the render request among `effects`.
fn rendering(effects: &[Effect]) -> u64 {
    match effects.iter().find(|e| matches!(e, Effect::Render(_))) {
        Some(Effect::Render(r)) => r.generation,
        _ => panic!("no render in {effects:?}"),
    }
}

/// A picture of a store's preview that comes after level 0 was adopted shows while the preview
/// does, labelled as the preview's; once full resolution is shown, a late one of the preview is
/// never shown in its place: each render request has its generation, and only the newest
/// request's picture is taken.
#[test]
fn a_late_picture_of_the_file_preview_is_never_shown_as_full_resolution() {
    let b = big();
    let (mut app, _) = App::new("store".into(), AnalysisParams::default(), Screen::default());
    app.preview.cells = (40, 12);
    let first = rendering(&job(
        &mut app,
        JobMsg::Preview(Arc::clone(&b.coarse), vec![]),
    ));
    job(&mut app, JobMsg::Views(1, Ok(Box::new(b.views.clone()))));
    let effects = job(
        &mut app,
        JobMsg::Analysis(1, 1, Ok(Arc::clone(&b.along_z[1]))),
    );
    let slabs = rendering(&effects);
    assert!(slabs > first);
    job(
        &mut app,
        JobMsg::Loaded(Ok((Arc::clone(&b.volume), vec![]))),
    );
    // Adopted, the preview still shown: its picture is taken, under the preview's label.
    job(
        &mut app,
        JobMsg::Rendered(slabs, Ok(Box::new(picture("preview")))),
    );
    assert!(matches!(app.preview.image, Task::Ready(_)));
    assert_eq!(app.preview.caption.as_deref(), Some("preview"));
    let label = app.status.resolution.clone().unwrap();
    assert!(label.starts_with("preview: 1/2 resolution"), "{label}");
    // Full resolution replaces it and asks for its own picture.
    job(&mut app, JobMsg::Views(0, Ok(Box::new(b.views.clone()))));
    let effects = job(
        &mut app,
        JobMsg::Analysis(2, 0, Ok(Arc::clone(&b.along_z[0]))),
    );
    assert_eq!(
        (app.part.level, app.status.resolution.as_deref()),
        (0, None)
    );
    let full = rendering(&effects);
    assert!(matches!(&effects[..], [Effect::Render(r)] if r.level == 0));
    // The preview's pictures still under way come late: neither is shown.
    for late in [first, slabs] {
        job(
            &mut app,
            JobMsg::Rendered(late, Ok(Box::new(picture("late preview")))),
        );
        assert_eq!(app.preview.caption.as_deref(), Some("preview"));
    }
    job(
        &mut app,
        JobMsg::Rendered(full, Ok(Box::new(picture("level 0")))),
    );
    assert_eq!(app.preview.caption.as_deref(), Some("level 0"));
}

/// Beyond the budget the store's level that fits is opened afresh, and the fresh app's first
/// render request has the generation the preview's first had: the jobs' epoch, moved by
/// `Effect::Forget`, is what keeps the preview's late picture (sent under the old epoch by its
/// render worker) from being shown as the new volume's.
#[test]
fn a_late_picture_of_the_file_preview_is_dropped_when_the_app_starts_afresh() {
    use crate::term::Caps;
    use crate::tui::jobs::Jobs;
    let b = big();
    let (tx, _rx) = std::sync::mpsc::channel();
    let mut jobs = Jobs::new(tx, Caps::blocks(), None, slabscope::LoadOptions::default());
    let (mut app, _) = App::new("store".into(), AnalysisParams::default(), Screen::default());
    app.preview.cells = (40, 12);
    let deliver = |jobs: &mut Jobs, app: &mut App, epoch, msg| {
        let admitted = jobs.admit(JobMsg::Epoch(epoch, Box::new(msg)));
        admitted.map(|msg| app.update(Action::Job(msg)))
    };
    let preview = JobMsg::Preview(Arc::clone(&b.coarse), vec![]);
    let first = rendering(&deliver(&mut jobs, &mut app, 0, preview).unwrap());
    // What loaded is itself level 1 (level 0 did not fit): everything starts afresh.
    let loaded = JobMsg::Loaded(Ok((Arc::clone(&b.coarse), vec![])));
    let effects = deliver(&mut jobs, &mut app, 0, loaded).unwrap();
    assert!(matches!(effects[..2], [Effect::Cancel, Effect::Forget]));
    assert_eq!(rendering(&effects), first, "the generations start again");
    for effect in effects {
        if matches!(effect, Effect::Cancel | Effect::Forget) {
            jobs.run(effect);
        }
    }
    // The preview's picture, under way before, comes: dropped with its epoch.
    let late = JobMsg::Rendered(first, Ok(Box::new(picture("late preview"))));
    assert!(deliver(&mut jobs, &mut app, 0, late).is_none());
    assert!(!matches!(app.preview.image, Task::Ready(_)));
    // The new volume's own picture is shown.
    let own = JobMsg::Rendered(first, Ok(Box::new(picture("level 1"))));
    assert!(deliver(&mut jobs, &mut app, 1, own).is_some());
    assert_eq!(app.preview.caption.as_deref(), Some("level 1"));
}
