//! The numbers behind each step (docs/design.md §6): every number the lesson shows is recomputed
//! here from the counts and histograms it shows beside it, to 1e-9, and the chosen axis's rate is
//! the view's.

use serde_json::Value;
use slabscope::explain::{Explain, StepsShown, table_entropy};
use slabscope::measure::{entropy, normalized_mutual_information};
use slabscope::partition::Method;
use slabscope::progress::Monitor;
use slabscope::volume::phantom;
use slabscope::{Analysis, AnalysisParams, Stop, Volume, analyze};

use crate::common::{run, s};

const EPS: f64 = 1e-9;

fn explained(volume: &Volume, method: Method, slabs: usize, shown: StepsShown) -> Analysis {
    let params = AnalysisParams {
        method,
        stop: Stop::Slabs(slabs),
        explain: Some(shown),
        ..AnalysisParams::default()
    };
    analyze(volume, &params, &Monitor::none()).unwrap()
}

fn body() -> Volume {
    phantom::body([40, 36, 56], 3).unwrap()
}

fn close(a: f64, b: f64, what: &str) {
    assert!((a - b).abs() < EPS, "{what}: {a} against {b}");
}

/// The block tables give the entropies and the rate; the chosen axis's rate is the view's, the
/// worst's the last view's.
fn check_axes(explain: &Explain, analysis: &Analysis) {
    let views = analysis.views.as_ref().unwrap();
    assert_eq!(explain.axes.len(), 2);
    for (a, view) in explain
        .axes
        .iter()
        .zip([views.best(), views.views.last().unwrap()])
    {
        let l = &a.lesson;
        assert_eq!(l.axis, view.axis);
        assert_eq!(l.entropy_rate, view.entropy_rate, "{:?}", a.role);
        assert_eq!(l.rays, view.rays);
        assert_eq!(l.samples, view.samples);
        assert_eq!(l.block_entropies.len(), l.block);
        close(table_entropy(&l.blocks), l.h_long(), "H(X^L)");
        close(table_entropy(&l.short_blocks), l.h_short(), "H(X^(L-1))");
        close(l.h_long() - l.h_short(), l.entropy_rate, "h");
        let blocks: u64 = l.blocks.iter().map(|b| b.count).sum();
        assert_eq!(blocks, view.blocks);
        assert!(l.blocks.windows(2).all(|w| w[0].count >= w[1].count));
        assert!(l.blocks.iter().all(|b| b.symbols.len() == l.block));
    }
    assert!(explain.axes[0].lesson.entropy_rate <= explain.axes[1].lesson.entropy_rate);
}

#[test]
fn splits_recompute_from_their_histograms() {
    let v = body();
    let analysis = explained(&v, Method::TopDown, 6, StepsShown::All);
    let e = analysis.explain.as_ref().unwrap();
    check_axes(e, &analysis);
    let p = &analysis.partition;
    assert_eq!(e.steps_taken, 5);
    assert_eq!(e.splits.len(), 5);
    for (lesson, step) in e.splits.iter().zip(&p.steps) {
        let slabscope::partition::Step::Split { split, at, gain } = step else {
            panic!("{step:?}")
        };
        assert_eq!((lesson.split, lesson.at), (*split, *at));
        let union: Vec<u64> = lesson
            .first
            .iter()
            .zip(&lesson.second)
            .map(|(a, b)| a + b)
            .collect();
        assert_eq!(union, lesson.union);
        let (v1, v2) = (
            lesson.first.iter().sum::<u64>() as f64,
            lesson.second.iter().sum::<u64>() as f64,
        );
        let (h1, h2, hu) = (
            entropy(lesson.first.clone()),
            entropy(lesson.second.clone()),
            entropy(union),
        );
        let js = hu - v1 / (v1 + v2) * h1 - v2 / (v1 + v2) * h2;
        close(js, lesson.js, "JS");
        close((v1 + v2) / lesson.total as f64 * js, *gain, "ΔI");
        close(lesson.gain, *gain, "the lesson's ΔI");
        // The cut taken is the best of its slab, the lowest on ties.
        let best = lesson.gains.iter().copied().fold(f64::MIN, f64::max);
        let first_best = lesson.gains.iter().position(|&g| g == best).unwrap();
        assert_eq!(lesson.split.0 + 1 + first_best, lesson.at);
        close(
            lesson.gains[lesson.at - lesson.split.0 - 1],
            *gain,
            "gains[at]",
        );
    }
    close(
        e.splits.last().unwrap().information,
        p.information,
        "I after the last split",
    );
    let o = e.optimal.as_ref().unwrap();
    assert_eq!(o.slabs, 6);
    assert!(o.optimal + EPS >= o.greedy);
    close(o.greedy, p.information, "greedy");
    let bounds: Vec<usize> = p.slabs.iter().skip(1).map(|s| s.0).collect();
    assert_eq!(o.greedy_boundaries, bounds);
}

#[test]
fn merges_recompute_from_their_joint_histograms() {
    let v = body();
    let analysis = explained(&v, Method::BottomUp, 4, StepsShown::Last(3));
    let e = analysis.explain.as_ref().unwrap();
    check_axes(e, &analysis);
    let p = &analysis.partition;
    assert_eq!(e.steps_taken, p.steps.len());
    assert_eq!(e.merges.len(), 3);
    let bins = analysis.views.as_ref().unwrap().params.sampling.bins;
    for (lesson, step) in e.merges.iter().zip(&p.steps[p.steps.len() - 3..]) {
        let slabscope::partition::Step::Merge { merge, nmi } = step else {
            panic!("{step:?}")
        };
        assert_eq!(lesson.merge, *merge);
        let mut joint = vec![0u64; bins * bins];
        for &[x, y, n] in &lesson.joint {
            assert!(n > 0);
            joint[x as usize * bins + y as usize] = n;
        }
        close(
            normalized_mutual_information(&joint, bins, bins),
            *nmi,
            "NMI",
        );
        let rows: Vec<u64> = joint.chunks(bins).map(|r| r.iter().sum()).collect();
        let cols: Vec<u64> = (0..bins)
            .map(|c| joint.iter().skip(c).step_by(bins).sum())
            .collect();
        close(entropy(rows), lesson.h_x, "H(X)");
        close(entropy(cols), lesson.h_y, "H(Y)");
        close(entropy(joint.clone()), lesson.h_xy, "H(X,Y)");
        close(lesson.h_x + lesson.h_y - lesson.h_xy, lesson.mi, "MI");
        close(lesson.mi / lesson.h_xy, lesson.nmi, "NMI = MI / H(X,Y)");
        // The two slabs are neighbours.
        assert_eq!(merge.0.1, merge.1.0);
        let r = lesson.runner_up.as_ref().unwrap();
        assert!(r.nmi <= lesson.nmi && r.merge != lesson.merge);
    }
}

#[test]
fn the_last_steps_are_shown_unless_all() {
    let v = body();
    let some = explained(&v, Method::TopDown, 8, StepsShown::Last(2));
    let e = some.explain.unwrap();
    assert_eq!((e.steps_taken, e.splits.len()), (7, 2));
    assert_eq!(e.splits[0].step, 6);
    assert!(e.merges.is_empty());
    let without = analyze(&v, &AnalysisParams::default(), &Monitor::none()).unwrap();
    assert!(without.explain.is_none());
}

#[test]
fn analyze_explain_prints_the_numbers_and_the_json_carries_them() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("body.nrrd");
    assert!(run(&["phantom", "body", "--dims", "40x36x56", "-o", s(&file)]).ok);
    let text = run(&["analyze", s(&file), "--explain"]);
    assert!(text.ok, "{}", text.stderr);
    for needle in [
        "Explained",
        "The chosen axis",
        "The worst axis",
        "h = H(X^3) − H(X^2) = ",
        "JS = H(p1 + p2) − π1·H(p1) − π2·H(p2) = ",
        "ΔI = (v1 + v2) / v_T · JS = ",
        "Optimum into 4 slabs",
    ] {
        assert!(
            text.stdout.contains(needle),
            "no {needle:?} in\n{}",
            text.stdout
        );
    }
    let json = run(&[
        "analyze",
        s(&file),
        "--method",
        "bottomup",
        "--explain",
        "all",
        "--json",
    ]);
    assert!(json.ok, "{}", json.stderr);
    let v: Value = serde_json::from_str(&json.stdout).unwrap();
    let e = &v["explain"];
    let taken = e["steps_taken"].as_u64().unwrap();
    assert_eq!(e["merges"].as_array().unwrap().len() as u64, taken);
    let chosen = &e["axes"][0];
    assert_eq!(chosen["role"], "chosen");
    assert_eq!(chosen["entropy_rate"], v["views"][0]["entropy_rate"]);
    // An explanation that is not all or a number says what it wants, and where FILE goes.
    let bad = run(&["analyze", "--explain", s(&file)]);
    assert!(!bad.ok);
    assert!(bad.stderr.contains("put FILE before it"), "{}", bad.stderr);
}

#[test]
fn a_lessons_ray_is_its_row_of_the_plane_of_rays() {
    let v = body();
    let params = slabscope::ViewParams::default();
    for axis in [[0.0, 0.0, 1.0], [0.3, -0.5, 0.81]] {
        for offset in [(0, 0), (3, -2)] {
            let ray = slabscope::explain::ray_samples(&v, axis, &params, offset)
                .unwrap()
                .unwrap();
            let plane = slabscope::explain::ray_plane(&v, axis, &params, offset)
                .unwrap()
                .unwrap();
            let row = plane.selected.expect("the ray is in its plane");
            assert_eq!(plane.rays[row], ray.ray.0);
            assert_eq!(plane.j, ray.ray.1);
            // Its samples, at their columns, and nothing else on its row.
            let shown = &plane.bins[row];
            let first = shown.iter().position(Option::is_some).unwrap();
            assert_eq!(&shown[first..first + ray.bins.len()], &ray.bins[..]);
            assert!(shown[first + ray.bins.len()..].iter().all(Option::is_none));
            assert!(plane.bins.iter().all(|r| r.len() == shown.len()));
            assert!(plane.rays.windows(2).all(|w| w[0] < w[1]));
        }
    }
}
