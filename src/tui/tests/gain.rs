//! The gain ranking in the TUI: `i` starts it, its result orders the list and the sphere by the
//! gain with both scores shown, `i` again switches back; `--axis-by gain` partitions along it.

use std::sync::Arc;

use slabscope::analysis::{AxisBy, rank_by_gain};
use slabscope::{AnalysisParams, Monitor};

use super::{PLAIN, fixture, pane, ready_app};
use crate::tui::app::{App, Screen};
use crate::tui::event::{Action, Effect, JobMsg, Task};

fn gain_result() -> JobMsg {
    let ranking = rank_by_gain(&fixture().0, &AnalysisParams::default(), &Monitor::none());
    JobMsg::Gain(0, ranking.map(Box::new).map_err(|e| e.to_string()))
}

#[test]
fn i_ranks_by_gain_then_switches_the_order() {
    let mut app = ready_app();
    let entropy_best = fixture().1.best().axis;
    assert!(matches!(
        app.update(Action::RankGain)[..],
        [Effect::RankGain(_, 0)]
    ));
    assert!(app.views.gain.running());
    assert!(
        app.update(Action::RankGain).is_empty(),
        "one ranking at a time"
    );
    app.update(Action::Job(gain_result()));
    let Task::Ready(gain) = &app.views.gain else {
        panic!("the ranking is in")
    };
    let gain_best = gain.views[0].axis;
    assert!(app.views.by_gain);
    assert_eq!(app.views.selected(), Some(gain_best));
    let message = app.status.message.clone().unwrap();
    assert!(message.contains("bits in 4 slabs"), "{message}");
    let text = pane(&app.views, 60, 12);
    assert!(text.contains("axes by the gain of 4 slabs"), "{text}");
    // Both scores on every row.
    let views = app.views.views.ready().unwrap();
    assert!(views.views.iter().all(|v| v.gain_phases.is_some()));
    app.update(Action::RankGain);
    assert!(!app.views.by_gain);
    assert_eq!(app.views.selected(), Some(entropy_best));
    // The axis partitioned did not change.
    assert_eq!(app.part.axis, Some(entropy_best));
}

#[test]
fn axis_by_gain_partitions_along_the_gains_best() {
    let (volume, views, _) = fixture();
    let params = AnalysisParams {
        axis_by: AxisBy::Gain,
        ..AnalysisParams::default()
    };
    let screen = Screen {
        theme: PLAIN,
        ..Screen::default()
    };
    let (mut app, _) = App::new("body.nrrd".into(), params, screen);
    let effects = app.update(Action::Job(JobMsg::Loaded(Ok((
        Arc::clone(volume),
        vec![],
    )))));
    assert!(
        effects.iter().any(|e| matches!(e, Effect::RankGain(_, 0))),
        "{effects:?}"
    );
    // The view search's best does not start the partition: the gain's does.
    let effects = app.update(Action::Job(JobMsg::Views(0, Ok(Box::new(views.clone())))));
    assert!(
        !effects.iter().any(|e| matches!(e, Effect::Analyze(..))),
        "{effects:?}"
    );
    let effects = app.update(Action::Job(gain_result()));
    let best = app.views.gain.ready().unwrap().refined.axis;
    assert!(
        matches!(effects[..], [Effect::Analyze(_, a, _, 0)] if a == best),
        "{effects:?}"
    );
}

#[test]
fn a_heavy_view_search_is_said_in_the_status_line() {
    let mut params = AnalysisParams::default();
    (params.view.level, params.view.phases, params.view.refine) = (4, 64, true);
    let screen = Screen {
        theme: PLAIN,
        ..Screen::default()
    };
    let (mut app, _) = App::new("body.nrrd".into(), params, screen);
    app.update(Action::Job(JobMsg::Loaded(Ok((
        Arc::clone(&fixture().0),
        vec![],
    )))));
    let message = app.status.message.clone().unwrap_or_default();
    assert!(
        message.contains("times the default's work") && message.contains("Esc cancels"),
        "{message}"
    );
    // The default is not heavy.
    let (mut app, _) = App::new(
        "body.nrrd".into(),
        AnalysisParams::default(),
        Screen::default(),
    );
    app.update(Action::Job(JobMsg::Loaded(Ok((
        Arc::clone(&fixture().0),
        vec![],
    )))));
    assert!(app.status.message.is_none(), "{:?}", app.status.message);
}

#[test]
fn a_previews_gain_ranking_is_ranked_again_with_full_resolutions_views() {
    use slabscope::volume::phantom;
    use slabscope::{ViewParams, search};
    let volume = Arc::new(phantom::body([160, 128, 128], 2).unwrap());
    let params = AnalysisParams {
        gain: true,
        ..AnalysisParams::default()
    };
    let screen = Screen {
        theme: PLAIN,
        ..Screen::default()
    };
    let (mut app, _) = App::new("big.nrrd".into(), params.clone(), screen);
    let effects = app.update(Action::Job(JobMsg::Loaded(Ok((
        Arc::clone(&volume),
        vec![],
    )))));
    // The preview's level is searched and ranked first.
    assert!(
        effects.iter().any(|e| matches!(e, Effect::RankGain(_, 1))),
        "{effects:?}"
    );
    let coarse = volume.coarser(1);
    let views = search(&coarse, &ViewParams::default(), &Monitor::none()).unwrap();
    app.update(Action::Job(JobMsg::Coarse(Arc::clone(&coarse))));
    app.update(Action::Job(JobMsg::Views(1, Ok(Box::new(views.clone())))));
    let ranking = rank_by_gain(&coarse, &params, &Monitor::none()).map_err(|e| e.to_string());
    app.update(Action::Job(JobMsg::Gain(1, ranking.map(Box::new))));
    assert!(matches!(app.views.gain, Task::Ready(_)));
    assert!(
        app.views.views.ready().unwrap().views[0]
            .partition_gain
            .is_some()
    );
    // A stale ranking of another level is dropped.
    let other = rank_by_gain(&coarse, &params, &Monitor::none()).map_err(|e| e.to_string());
    assert!(
        app.update(Action::Job(JobMsg::Gain(2, other.map(Box::new))))
            .is_empty()
    );
    // Full resolution's views come (here, the same numbers stand in for them): they are ranked
    // again, at full resolution, and until then carry no preview's gains.
    let effects = app.update(Action::Job(JobMsg::Views(0, Ok(Box::new(views)))));
    assert!(
        effects.iter().any(|e| matches!(e, Effect::RankGain(_, 0))),
        "{effects:?}"
    );
    assert!(app.views.gain.running());
    assert!(
        app.views.views.ready().unwrap().views[0]
            .partition_gain
            .is_none()
    );
}
