//! The requests against the steps they stand for, written out as the front ends wrote them.

use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use super::*;
use crate::analysis::{AnalysisParams, analyze_planned, memory_needed};
use crate::budget::{Budget, Purpose};
use crate::error::Error;
use crate::params::{Given, table};
use crate::progress::Monitor;
use crate::render::slice::{SliceParams, numbered};
use crate::render::{Layout, Renderer, TransferChoice};
use crate::report::{AnalysisReport, to_json};
use crate::volume::{Resolution, Volume, phantom};

fn body() -> Volume {
    phantom::body([24, 24, 40], 1).unwrap()
}

/// The analysis as `analyze` and Python wrote it before the request: the level, the budget's
/// plan, the analysis on it, the report with where it ran.
fn by_hand(volume: &Volume, params: &AnalysisParams, max_memory: u64) -> String {
    let plan = Budget::new(max_memory)
        .plan(
            volume,
            Purpose::Analysis {
                wanted: 0,
                every_voxel: false,
                params,
            },
        )
        .unwrap();
    let analysis = analyze_planned(&plan, params, &Monitor::none()).unwrap();
    let report = AnalysisReport::new("body", volume, &params.view, &analysis)
        .unwrap()
        .computed_on(&plan.partition)
        .views_on(&plan.views);
    to_json(&report).unwrap()
}

#[test]
fn the_analysis_request_gives_the_sequence_it_stands_for() {
    let volume = body();
    let params = AnalysisParams::default();
    // Room for everything, and room only for pyramid level 1's analysis (the partition then
    // counted on every voxel, strip by strip): the same report either way as by hand.
    for max_memory in [u64::MAX, memory_needed(&volume, 1)] {
        let request = AnalysisRequest::new(params.clone(), max_memory);
        let done = request.run(&volume, &Monitor::none()).unwrap();
        let json = to_json(&done.report("body", &volume).unwrap()).unwrap();
        assert_eq!(json, by_hand(&volume, &params, max_memory), "{max_memory}");
        assert_eq!(done.analysis.partition.slabs.len(), 4);
    }
    let tight = AnalysisRequest::new(params, memory_needed(&volume, 1))
        .run(&volume, &Monitor::none())
        .unwrap();
    assert!(
        tight.plan.note.is_some(),
        "the budget moved the view search"
    );
    assert_eq!(tight.plan.views.dims(), [12, 12, 20]);
}

#[test]
fn the_level_asked_for_and_a_pictures_level() {
    let volume = body();
    let mut request = AnalysisRequest::new(AnalysisParams::default(), u64::MAX);
    request.level = Level::Asked(Resolution::Level(1), true);
    let done = request.run(&volume, &Monitor::none()).unwrap();
    assert_eq!(done.level().dims(), [12, 12, 20]);
    let report = done.report("body", &volume).unwrap();
    assert_eq!(report.resolution.pyramid_level, 1);
    // A level past the last names `resolution`.
    request.level = Level::Asked(Resolution::Level(9), true);
    assert!(matches!(
        request.plan(&volume),
        Err(Error::InvalidParameter {
            parameter: "resolution",
            ..
        })
    ));
    // A picture's analysis runs on the level that fits, never streamed.
    request.level = Level::Picture;
    request.budget = Budget::new(memory_needed(&volume, 1));
    let planned = request.plan(&volume).unwrap();
    assert_eq!(planned.plan.partition.dims(), [12, 12, 20]);
    assert!(planned.plan.streamed.is_none());
}

#[test]
fn a_request_cancelled_through_its_monitor_stops() {
    let volume = body();
    let cancel = AtomicBool::new(true);
    let monitor = Monitor::new(Some(&cancel), None);
    let request = AnalysisRequest::new(AnalysisParams::default(), u64::MAX);
    assert!(matches!(
        request.run(&volume, &monitor),
        Err(Error::Cancelled)
    ));
    let done = request.run(&volume, &Monitor::none()).unwrap();
    let render = RenderRequest {
        scene: Given::new().scene(64, 48).unwrap(),
        faces: false,
    };
    assert!(matches!(
        render.render(&done, &monitor),
        Err(Error::Cancelled)
    ));
    let faces = RenderRequest {
        faces: true,
        ..render
    };
    assert!(matches!(
        faces.render(&done, &monitor),
        Err(Error::Cancelled)
    ));
    let slice = SliceRequest {
        params: AnalysisParams::default(),
        axis: None,
        index: None,
        look: TransferChoice::default(),
        picture: SliceParams::default(),
    };
    assert!(matches!(
        slice.run(&volume, &monitor),
        Err(Error::Cancelled)
    ));
}

#[test]
fn a_default_that_does_not_fit_is_blamed_on_the_default() {
    // Three slices along z: the default of 4 slabs does not fit; 4 given does not either.
    let volume = phantom::body([16, 16, 3], 1).unwrap();
    for (given, default) in [
        (Given::new().with(&table::AXIS, "z"), true),
        (
            Given::new()
                .with(&table::AXIS, "z")
                .with(&table::SLABS, "4"),
            false,
        ),
    ] {
        let mut request = AnalysisRequest::new(given.analysis().unwrap(), u64::MAX);
        request.given = Some(given);
        match request.run(&volume, &Monitor::none()) {
            Err(Error::DefaultUnfit { parameter, .. }) => {
                assert!(default && parameter == "slabs");
            }
            Err(Error::InvalidParameter { parameter, .. }) => {
                assert!(!default && parameter == "slabs");
            }
            other => panic!("{other:?}"),
        }
    }
}

#[test]
fn the_render_request_draws_what_the_renderer_draws() {
    let volume = body();
    let done = AnalysisRequest::new(AnalysisParams::default(), u64::MAX)
        .run(&volume, &Monitor::none())
        .unwrap();
    let scene = Given::new().scene(64, 48).unwrap();
    let part = &done.analysis.partition;
    let layout = Layout::exploded(part, scene.gap, scene.spread);
    let expected = Renderer::new(&volume)
        .unwrap()
        .render(&layout, &scene.params, &Monitor::none())
        .unwrap()
        .pixmap;
    let request = RenderRequest {
        scene: scene.clone(),
        faces: false,
    };
    let drawn = request.render(&done, &Monitor::none()).unwrap();
    assert_eq!(drawn.data(), expected.data());
    // A slab past the four, and a strip too small for their faces, name their parameters.
    let mut past = request.clone();
    past.scene.params.highlight = Some(4);
    let e = past.render(&done, &Monitor::none()).unwrap_err();
    assert_eq!(
        e.to_string(),
        "highlight 4: there are only 4 slabs (numbered from 0)"
    );
    let faces = RenderRequest {
        scene: Given::new().scene(30, 30).unwrap(),
        faces: true,
    };
    let e = faces.render(&done, &Monitor::none()).unwrap_err();
    assert_eq!(
        e.to_string(),
        "size 30x30: too small for the faces of 4 slabs"
    );
    // 640 less five gaps of 4, in four columns; 480 less three gaps, in two rows.
    assert_eq!(faces_tile((640, 480), 4).unwrap(), (155, 234));
    let strip = RenderRequest {
        scene: Given::new().scene(200, 100).unwrap(),
        faces: true,
    }
    .render(&done, &Monitor::none())
    .unwrap();
    assert_eq!((strip.width(), strip.height()), (4 * 49 + 4, 2 * 44 + 12));
}

#[test]
fn the_slice_request_draws_the_slice_numbered_draws() {
    let volume = Arc::new(body());
    let params = Given::new().with(&table::AXIS, "y").analysis().unwrap();
    let request = SliceRequest {
        params: params.clone(),
        axis: None,
        index: Some(3),
        look: TransferChoice::default(),
        picture: SliceParams {
            fit: (64, 64),
            ..SliceParams::default()
        },
    };
    let axis = request.axis(&volume, &Monitor::none()).unwrap();
    assert_eq!(axis, [0.0, 1.0, 0.0]);
    assert_eq!(request.slices(&volume, &Monitor::none()).unwrap(), 24);
    // The axis the view search found is kept: the request then searches no more (a cancelled
    // monitor stops no search), and draws what numbered draws across it.
    let mut kept = SliceRequest {
        params: AnalysisParams::default(),
        ..request.clone()
    };
    let found = kept.find_axis(&volume, &Monitor::none()).unwrap();
    assert_eq!(kept.axis, Some(found));
    let expected = numbered(
        &volume,
        axis,
        &params.stack(),
        Some(3),
        TransferChoice::default(),
        &request.picture,
    )
    .unwrap();
    let drawn = request.run(&volume, &Monitor::none()).unwrap();
    assert_eq!(drawn.data(), expected.pixmap.data());
    let cancelled = AtomicBool::new(true);
    let drawn = kept
        .run(&volume, &Monitor::new(Some(&cancelled), None))
        .unwrap();
    let across = numbered(
        &volume,
        found,
        &kept.params.stack(),
        Some(3),
        TransferChoice::default(),
        &kept.picture,
    )
    .unwrap();
    assert_eq!(drawn.data(), across.pixmap.data());
    let past = SliceRequest {
        index: Some(24),
        ..request
    };
    assert!(matches!(
        past.run(&volume, &Monitor::none()),
        Err(Error::InvalidParameter {
            parameter: "index",
            ..
        })
    ));
}

/// The steps of a planned request one at a time (the TUI's jobs: the views, then every
/// method's histories along an axis) give what the whole run gives, within the budget and
/// beyond it (the view search and the partition then on pyramid level 1).
#[test]
fn a_planned_request_step_by_step_gives_what_the_run_gives() {
    use crate::partition::Method;
    let volume = body();
    let params = AnalysisParams::default();
    for max_memory in [u64::MAX, memory_needed(&volume, 1)] {
        let request = AnalysisRequest::new(params.clone(), max_memory);
        let done = request.run(&volume, &Monitor::none()).unwrap();
        let planned = request.plan(&volume).unwrap();
        assert!(
            planned.plan.streamed.is_none(),
            "too small to count in strips"
        );
        let views = planned.views(&Monitor::none()).unwrap();
        let found = done.analysis.views.as_ref().unwrap();
        assert_eq!(views.views, found.views, "{max_memory}");
        let axis = views.best().axis;
        assert_eq!(axis, done.analysis.axis());
        let h = planned.histories(axis, &Monitor::none()).unwrap();
        let position = h.position(params.method, params.stop).unwrap();
        assert_eq!(
            h.slabs(params.method, position),
            done.analysis.partition.slabs
        );
        // In memory, every method's history is there.
        assert!(h.has(Method::BottomUp) && h.has(Method::Optimal));
    }
}

/// Views counted in parts on every voxel are refused by a plan the budget moved to a coarser
/// level, the budget named as the cause.
#[test]
fn views_of_every_voxel_are_refused_on_a_coarser_level() {
    let volume = body();
    let params = AnalysisParams::default();
    let views = crate::view::search(&volume, &params.view, &Monitor::none()).unwrap();
    let request = AnalysisRequest::new(params, memory_needed(&volume, 1));
    let planned = request.plan(&volume).unwrap();
    assert_eq!(planned.plan.views.level().index, 1);
    let e = planned.run_with(Some(views), &Monitor::none()).unwrap_err();
    assert!(matches!(e, Error::TooCoarse { .. }), "{e:?}");
    let text = e.to_string();
    assert!(text.starts_with("the views, counted in parts on every voxel, cannot finish an analysis of pyramid level 1, because "), "{text}");
}

/// A request on a level the planner chose before runs there as it is, whatever its budget:
/// the histories are those of that level, every method's.
#[test]
fn a_request_on_a_level_chosen_before_runs_there() {
    use crate::partition::{Histories, Method, Scope};
    let volume = body();
    let glance = volume.coarser(1);
    let params = AnalysisParams::default();
    let request = AnalysisRequest::new(params.clone(), 1);
    let on = request.on(Arc::clone(&glance));
    let views = on.views(&Monitor::none()).unwrap();
    let by_hand = crate::view::search(&glance, &params.view, &Monitor::none()).unwrap();
    assert_eq!(views.views, by_hand.views);
    let axis = views.best().axis;
    let h = on.histories(axis, &Monitor::none()).unwrap();
    let by_hand =
        Histories::new(&glance, axis, &params.stack(), Scope::ALL, &Monitor::none()).unwrap();
    assert_eq!(h.slices(), by_hand.slices());
    assert_eq!(h.nmi_curve(), by_hand.nmi_curve());
    for method in [Method::TopDown, Method::BottomUp, Method::Optimal] {
        assert!(h.has(method), "{method:?}");
        let last = by_hand.last(method);
        assert_eq!(
            h.slabs(method, last),
            by_hand.slabs(method, last),
            "{method:?}"
        );
    }
    let gain = on.gain(&Monitor::none()).unwrap();
    let by_hand = crate::analysis::rank_by_gain(&glance, &params, &Monitor::none()).unwrap();
    assert_eq!(gain.refined.axis, by_hand.refined.axis);
}

/// A plan that counts its slabs strip by strip gives the histories the request's own method
/// reads, counted so: the same slabs as in memory, with no bottom-up history.
#[test]
fn histories_of_a_plan_counted_in_strips_are_the_methods_own() {
    use crate::partition::{Histories, Method, Scope};
    let volume = body();
    let params = AnalysisParams::default();
    let request = AnalysisRequest::new(params.clone(), u64::MAX);
    let mut planned = request.on(Arc::new(volume.clone()));
    let room = crate::partition::streamed_memory_floor(&volume, params.view.sampling.bins);
    planned.plan.streamed = Some(room);
    let axis = [0.0, 0.0, 1.0];
    let h = planned.histories(axis, &Monitor::none()).unwrap();
    assert!(!h.has(Method::BottomUp));
    let whole =
        Histories::new(&volume, axis, &params.stack(), Scope::ALL, &Monitor::none()).unwrap();
    assert_eq!(h.slices(), whole.slices());
    let (at, whole_at) = (
        h.position(params.method, params.stop).unwrap(),
        whole.position(params.method, params.stop).unwrap(),
    );
    assert_eq!(
        h.slabs(params.method, at),
        whole.slabs(params.method, whole_at)
    );
    assert_eq!(h.slabs(params.method, at).len(), 4);
}

/// Every voxel asked for by name beyond the budget: the view search with the refinement and
/// the gain ranking is counted slab by slab (`view::streamed`'s tests hold the search bit for
/// bit to the search in memory, and the next tests the gain ranking and the lesson beside it),
/// with the lesson or without.
#[test]
fn a_refined_search_of_every_voxel_beyond_the_budget_is_streamed() {
    let volume = phantom::body([256, 256, 256], 1).unwrap();
    let refine = |explain: bool| AnalysisParams {
        view: crate::view::ViewParams {
            refine: true,
            ..crate::view::ViewParams::default()
        },
        gain: true,
        explain: explain.then(crate::explain::StepsShown::default),
        ..AnalysisParams::default()
    };
    for explain in [false, true] {
        let request = AnalysisRequest {
            level: Level::Asked(Resolution::Full, true),
            ..AnalysisRequest::new(refine(explain), memory_needed(&volume, 0) - 1)
        };
        let planned = request.plan(&volume).unwrap();
        let note = &planned.plan.note;
        assert!(planned.plan.views_streamed.is_some(), "{explain}: {note:?}");
        assert!(planned.plan.streamed.is_some(), "{explain}: {note:?}");
    }
}

/// The lesson of an analysis whose views are counted slab by slab and whose slabs strip by
/// strip: its block tables and entropies, the chosen axis's and the worst's, are those of the
/// lesson in memory, every count.
#[test]
fn the_lesson_beside_views_counted_slab_by_slab_is_the_one_in_memory() {
    let volume = phantom::body([40, 36, 52], 3).unwrap();
    for block in [3, 4] {
        let params = AnalysisParams {
            view: crate::view::ViewParams {
                block,
                ..crate::view::ViewParams::default()
            },
            explain: Some(crate::explain::StepsShown::All),
            ..AnalysisParams::default()
        };
        let request = AnalysisRequest::new(params.clone(), u64::MAX);
        let in_memory = request.run(&volume, &Monitor::none()).unwrap();
        let mut planned = request.on(Arc::new(volume.clone()));
        let bins = params.view.sampling.bins;
        // The least room: slabs of one plane of cells, the most seams to join.
        planned.plan.views_streamed =
            Some(crate::view::streamed_memory_floor(&volume, &params.view));
        planned.plan.streamed = Some(crate::partition::streamed_memory_floor(&volume, bins));
        let done = planned.run(&Monitor::none()).unwrap();
        let (streamed, whole) = (
            done.analysis.explain.as_ref().unwrap(),
            in_memory.analysis.explain.as_ref().unwrap(),
        );
        assert_eq!(streamed.axes.len(), 2);
        assert!(streamed.axes[0].lesson.blocks.len() > 10, "{block}");
        assert_eq!(streamed, whole, "L = {block}");
    }
}

/// The gain ranking (picking the axis) beside a view search and a partition counted slab by
/// slab and strip by strip: the report of the analysis in memory.
#[test]
fn the_gain_ranking_beside_views_counted_slab_by_slab_is_the_one_in_memory() {
    let volume = body();
    let params = AnalysisParams {
        gain: true,
        axis_by: crate::analysis::AxisBy::Gain,
        ..AnalysisParams::default()
    };
    let request = AnalysisRequest::new(params.clone(), u64::MAX);
    let in_memory = request.run(&volume, &Monitor::none()).unwrap();
    let mut planned = request.on(Arc::new(volume.clone()));
    let bins = params.view.sampling.bins;
    planned.plan.views_streamed = Some(crate::view::streamed_memory_floor(&volume, &params.view));
    planned.plan.streamed = Some(crate::partition::streamed_memory_floor(&volume, bins));
    let done = planned.run(&Monitor::none()).unwrap();
    assert!(done.analysis.gain.is_some());
    // The same report but for the notes on how the slice stack was counted.
    let json = |a: &Analysed| {
        let mut report = serde_json::to_value(a.report("body", &volume).unwrap()).unwrap();
        report["notes"].take();
        report["partition"]["notes"].take();
        report
    };
    assert_eq!(json(&done), json(&in_memory));
}
