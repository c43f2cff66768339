//! The tour's merge page on volumes whose bottom-up histories differ: its example is the
//! history's merge of the highest NMI below 1 among those taken to the slabs shown (found here
//! by a loop of its own, its NMI worked out again from the lesson's joint histogram), at the slab
//! count the analysis is given, and new histories (full resolution) give their own.

use std::sync::Arc;

use slabscope::partition::{Method, Stop};
use slabscope::volume::phantom;
use slabscope::{AnalysisParams, Histories, Monitor, Scope, ViewSearch, Volume, search};

use super::lesson::answer;
use super::{PLAIN, feed, screens};
use crate::tui::app::tour::{COMPARED, MERGE};
use crate::tui::app::{App, Screen};
use crate::tui::event::{Action, Task};
use crate::tui::lesson::{Lesson, Subject};

/// `volume`, its view search, and its histories along the best axis by the defaults.
fn analysed(volume: Volume) -> (Arc<Volume>, ViewSearch, Arc<Histories>) {
    let volume = Arc::new(volume);
    let params = AnalysisParams::default();
    let views = search(&volume, &params.view, &Monitor::none()).unwrap();
    let axis = views.best().axis;
    let histories = Histories::new(&volume, axis, &params.stack(), Scope::ALL, &Monitor::none());
    (volume, views, Arc::new(histories.unwrap()))
}

/// An app analysing with `stop`, handed the volume, its view search and its histories.
fn app_on(analysed: &(Arc<Volume>, ViewSearch, Arc<Histories>), stop: Stop) -> App {
    let params = AnalysisParams {
        stop,
        ..AnalysisParams::default()
    };
    let screen = Screen {
        theme: PLAIN,
        ..Screen::default()
    };
    let (mut app, _) = App::new("volume.nrrd".into(), params, screen);
    let (volume, views, histories) = analysed;
    feed(&mut app, volume, views, histories);
    app
}

/// The first of the highest NMI below 1 among the first `upto` merges (numbered from 1), or of
/// all when every one's is 1.
pub(super) fn highest(histories: &Histories, upto: usize) -> usize {
    let steps = &histories.bottom().unwrap().steps[..upto];
    let first_highest = |keep: &dyn Fn(f64) -> bool| {
        let mut best: Option<usize> = None;
        for (i, s) in steps.iter().enumerate() {
            if keep(s.nmi) && best.is_none_or(|b| s.nmi > steps[b].nmi) {
                best = Some(i);
            }
        }
        best
    };
    let below_one = first_highest(&|nmi| nmi < 1.0);
    below_one.or_else(|| first_highest(&|_| true)).unwrap() + 1
}

/// `MI / H(X,Y)` of a joint histogram's cells `[x, y, count]`, bits.
fn nmi_of(joint: &[[u64; 3]], bins: usize) -> f64 {
    let total: u64 = joint.iter().map(|c| c[2]).sum();
    let (mut xs, mut ys) = (vec![0u64; bins], vec![0u64; bins]);
    for &[x, y, n] in joint {
        xs[x as usize] += n;
        ys[y as usize] += n;
    }
    let h = |counts: &mut dyn Iterator<Item = u64>| -> f64 {
        counts
            .filter(|&n| n > 0)
            .map(|n| {
                let p = n as f64 / total as f64;
                -p * p.log2()
            })
            .sum()
    };
    let h_xy = h(&mut joint.iter().map(|c| c[2]));
    (h(&mut xs.into_iter()) + h(&mut ys.into_iter()) - h_xy) / h_xy
}

/// Turns `app`'s tour to the merge page and checks its example against `histories` with
/// `given` slabs given to the analysis; the slab count shown and the example's step.
fn check_merge_page(
    app: &mut App,
    histories: &Histories,
    given: usize,
    case: &str,
) -> (usize, usize) {
    let effects = app.update(Action::TurnPage(MERGE as isize));
    // The count where bottom-up's history shows structure, said on the page.
    let structure = slabscope::explain::structure(histories.bottom().unwrap());
    let slabs = structure.as_ref().map_or(given, |s| s.at.slabs);
    let numbers = app.tour.as_ref().unwrap().numbers.clone();
    assert_eq!(
        numbers,
        structure.as_ref().map(slabscope::explain::structure_brief),
        "{case}"
    );
    assert_eq!(app.part.method, Method::BottomUp, "{case}");
    assert_eq!(app.part.slab_count(), Some(slabs), "{case}");
    let upto = histories.slices() - slabs;
    assert_eq!(app.part.position, upto, "{case}");
    let subject = answer(app, effects);
    assert!(
        matches!(subject, Subject::BestMerge { upto: u, .. } if u == upto),
        "{case}: {subject:?}"
    );
    let Task::Ready(lesson) = &app.lesson.lesson else {
        panic!("{case}: no lesson")
    };
    let Lesson::BestMerge { merge, of, .. } = lesson.as_ref() else {
        panic!("{case}: the best merge's lesson")
    };
    let steps = &histories.bottom().unwrap().steps;
    assert_eq!(*of, steps.len(), "{case}");
    let step = highest(histories, upto);
    assert_eq!(merge.step, step, "{case}");
    assert_eq!(merge.merge, steps[step - 1].merge, "{case}");
    // A joint histogram of more than one cell, its NMI worked out again.
    assert!(merge.h_xy > 0.0, "{case}: {merge:?}");
    let nmi = nmi_of(&merge.joint, merge.bins);
    assert!((nmi - steps[step - 1].nmi).abs() < 1e-9, "{case}: {nmi}");
    let of = *of;
    let screen = &screens(app, 160, 48, vec![])[0];
    assert!(
        screen.contains(&format!("Merge {step} of {of}")),
        "{screen}"
    );
    (slabs, step)
}

#[test]
fn the_merge_pages_example_is_each_historys_merge_of_the_highest_nmi() {
    let body = analysed(phantom::body([20, 20, 36], 7).unwrap());
    // Between the third split's gain and the fourth's; the count the test expects is counted
    // from the gains themselves.
    let gains: Vec<f64> = body.2.top().steps.iter().map(|s| s.gain).collect();
    let threshold = f64::midpoint(gains[2], gains[3]);
    let layers = |dims, normal, seed| analysed(phantom::layers(dims, normal, seed).unwrap());
    let cases = [
        (
            "layers along z",
            layers([18, 18, 30], [0.0, 0.0, 1.0], 3),
            Stop::Slabs(4),
        ),
        (
            "tilted layers",
            layers([24, 16, 20], [1.0, 0.3, 0.0], 5),
            Stop::Slabs(3),
        ),
        (
            "Shepp-Logan",
            analysed(phantom::shepp_logan([22, 22, 22]).unwrap()),
            Stop::Slabs(5),
        ),
        ("the body at a threshold", body, Stop::Threshold(threshold)),
    ];
    let (mut examples, mut counts) = (vec![], vec![]);
    for (case, analysed, stop) in &cases {
        let mut app = app_on(analysed, *stop);
        app.start_tour(false);
        let h = &analysed.2;
        // The count the analysis is given: K, or top-down's at the threshold.
        let slabs = match *stop {
            Stop::Slabs(k) => k,
            Stop::Threshold(t) => 1 + h.top().steps.iter().take_while(|s| s.gain >= t).count(),
        };
        let (shown, step) = check_merge_page(&mut app, h, slabs, case);
        examples.push((h.slices(), h.slices() - shown, step));
        counts.push((slabs, shown));
        // Top-down against bottom-up at the same count.
        app.update(Action::TurnPage(1));
        assert_eq!(app.tour.as_ref().unwrap().page, COMPARED);
        assert_eq!(
            (app.part.method, app.part.slab_count()),
            (Method::BottomUp, Some(slabs)),
            "{case}"
        );
    }
    // Four histories, and the rule picks more than the last merge taken.
    let before_the_last = examples
        .iter()
        .filter(|(_, upto, step)| step < upto)
        .count();
    assert!(before_the_last >= 2, "{examples:?}");
    // The merge page's count is the history's, not the one given, in some of them.
    assert!(
        counts.iter().any(|(given, shown)| given != shown),
        "{counts:?}"
    );
}
