//! The paper's Fig. 1a: the icosphere of viewpoints as a wireframe seen obliquely, every
//! viewpoint a dot (faint on the far side), each axis a pair of opposite viewpoints, the chosen
//! axis drawn through the centre and its viewpoint on the near side marked.

use serde::Serialize;

use super::{Drawing, Ink, View};
use crate::geometry::{canonical, dot};
use crate::view::icosphere;

/// One viewpoint of the sphere as drawn.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Viewpoint {
    /// Its unit direction.
    pub direction: [f64; 3],
    /// Where it is drawn.
    pub at: [f64; 2],
    /// Whether it is on the near side.
    pub front: bool,
}

/// Fig. 1a: the drawing and what it shows.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SphereFigure {
    /// The segments and dots.
    pub drawing: Drawing,
    /// Every viewpoint of the icosphere, in its order.
    pub viewpoints: Vec<Viewpoint>,
    /// Each axis as the indices of its two viewpoints, the canonical direction first, in the
    /// order of `icosphere::axes`.
    pub pairs: Vec<[usize; 2]>,
    /// The chosen viewpoint: of the pair nearest the chosen axis, the one on the near side.
    pub best: usize,
}

/// Points of the sphere's silhouette drawn.
const OUTLINE: usize = 96;

/// The icosphere of `level` seen from `view`, with the viewpoint nearest `chosen` (or its
/// opposite) marked.
pub fn sphere_figure(level: usize, chosen: [f64; 3], view: &View) -> SphereFigure {
    let (points, faces) = icosphere::mesh(level);
    let viewpoints: Vec<Viewpoint> = points
        .iter()
        .map(|&p| Viewpoint {
            direction: p,
            at: view.project(p),
            front: view.faces(p),
        })
        .collect();
    let pairs = pairs(&points);
    let nearest = pairs
        .iter()
        .max_by(|a, b| {
            let closeness = |i: usize| dot(points[i], chosen).abs();
            closeness(a[0]).total_cmp(&closeness(b[0]))
        })
        .copied()
        .unwrap_or([0, 0]);
    let best = if viewpoints[nearest[1]].front && !viewpoints[nearest[0]].front {
        nearest[1]
    } else {
        nearest[0]
    };
    let mut d = Drawing::default();
    let mut edges: Vec<(usize, usize)> = faces
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    // The far side first, then the silhouette, then the near side over them.
    let near =
        |&(a, b): &(usize, usize)| view.faces(std::array::from_fn(|k| points[a][k] + points[b][k]));
    for &(a, b) in edges.iter().filter(|e| !near(e)) {
        d.line(viewpoints[a].at, viewpoints[b].at, Ink::Back);
    }
    for k in 0..OUTLINE {
        let angle = |k: usize| std::f64::consts::TAU * k as f64 / OUTLINE as f64;
        let (a, b) = (angle(k), angle(k + 1));
        d.line([a.cos(), a.sin()], [b.cos(), b.sin()], Ink::Outline);
    }
    for &(a, b) in edges.iter().filter(|e| near(e)) {
        d.line(viewpoints[a].at, viewpoints[b].at, Ink::Front);
    }
    let opposite = if best == nearest[0] {
        nearest[1]
    } else {
        nearest[0]
    };
    d.line(viewpoints[opposite].at, viewpoints[best].at, Ink::Axis);
    for (_, v) in viewpoints.iter().enumerate().filter(|&(i, _)| i != best) {
        d.dot(v.at, if v.front { Ink::Viewpoint } else { Ink::Hidden });
    }
    d.dot(viewpoints[best].at, Ink::Best);
    d.fit(0.08);
    SphereFigure {
        drawing: d,
        viewpoints,
        pairs,
        best,
    }
}

/// Each antipodal pair of `points` once, the canonical direction first, in order of the
/// canonical one's first appearance (the order of `icosphere::axes`).
fn pairs(points: &[[f64; 3]]) -> Vec<[usize; 2]> {
    // Points matched by their coordinates rounded as `icosphere::axes` rounds them: linear in
    // the points (the drawing is made as the pane is drawn).
    let key = |p: [f64; 3]| p.map(|c| (c * 1e9).round() as i64);
    let at: std::collections::HashMap<[i64; 3], usize> = points
        .iter()
        .enumerate()
        .map(|(i, &p)| (key(p), i))
        .collect();
    let mut paired = vec![false; points.len()];
    let mut out = Vec::with_capacity(points.len() / 2);
    for (i, &p) in points.iter().enumerate() {
        if paired[i] {
            continue;
        }
        if let Some(&j) = at.get(&key(p.map(|c| -c))) {
            paired[i] = true;
            paired[j] = true;
            out.push(if canonical(p) == p { [i, j] } else { [j, i] });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fig_1a_has_42_viewpoints_21_axes_and_the_best_marked_where_it_projects() {
        let view = View::default();
        let chosen = [0.0, 0.0, 1.0];
        let f = sphere_figure(1, chosen, &view);
        assert_eq!(f.viewpoints.len(), 42);
        assert_eq!(f.drawing.dots.len(), 42);
        assert_eq!(f.pairs.len(), 21);
        // The pairs are the library's axes, in its order, each two opposite viewpoints.
        let axes = icosphere::axes(1);
        for (pair, axis) in f.pairs.iter().zip(&axes) {
            assert_eq!(f.viewpoints[pair[0]].direction, *axis);
            assert!(dot(f.viewpoints[pair[1]].direction, *axis) < -1.0 + 1e-12);
        }
        let mut all: Vec<usize> = f.pairs.iter().flatten().copied().collect();
        all.sort_unstable();
        assert_eq!(all, (0..42).collect::<Vec<_>>());
        // +z seen from above the equator: the best is +z itself, drawn once where it projects.
        let marked = f.viewpoints[f.best].direction;
        assert!(dot(marked, chosen) > 1.0 - 1e-12, "{marked:?}");
        let best: Vec<_> = f
            .drawing
            .dots
            .iter()
            .filter(|d| d.ink == Ink::Best)
            .collect();
        assert_eq!(best.len(), 1);
        assert_eq!(best[0].at, view.project(marked));
        // The axis through the centre, 120 edges, the near side's viewpoints drawn as such.
        assert_eq!(f.drawing.count(Ink::Axis), (1, 0));
        let (front, back) = (f.drawing.count(Ink::Front).0, f.drawing.count(Ink::Back).0);
        assert_eq!(front + back, 120);
        let near = f.viewpoints.iter().filter(|v| v.front).count();
        assert_eq!(f.drawing.count(Ink::Viewpoint).1 + 1, near);
        assert!(f.drawing.extent[0] < -1.0 && f.drawing.extent[3] > 1.0);
    }

    #[test]
    fn the_near_one_of_the_pair_is_marked() {
        let view = View::default();
        // -x is the canonical +x's opposite; seen from azimuth 30° +x is the near one.
        let f = sphere_figure(1, [-1.0, 0.0, 0.0], &view);
        assert!(dot(f.viewpoints[f.best].direction, [1.0, 0.0, 0.0]) > 1.0 - 1e-12);
        // Seen from behind, the far one of the canonical pair is drawn instead.
        let behind = View::oblique(210.0, 20.0);
        let f = sphere_figure(1, [1.0, 0.0, 0.0], &behind);
        assert!(dot(f.viewpoints[f.best].direction, [-1.0, 0.0, 0.0]) > 1.0 - 1e-12);
        assert!(f.viewpoints[f.best].front);
    }
}
