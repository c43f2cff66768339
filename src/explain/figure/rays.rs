//! The paper's Fig. 1b: from a viewpoint's plane, parallel rays cast through the volume's box,
//! the samples along one of them, seen obliquely.

use serde::Serialize;

use super::{Drawing, Ink, View};
use crate::error::Result;
use crate::geometry::{dot, frame};

/// Fig. 1b: the drawing and what it shows.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RaysFigure {
    /// The segments and dots.
    pub drawing: Drawing,
    /// The rays drawn.
    pub rays: usize,
    /// Where the shown ray's samples are drawn, first to last along the ray.
    pub samples: Vec<[f64; 2]>,
}

/// The volume of physical size `size` (its box scaled to a longest side of 2, centred) with
/// `across × across` rays cast along `-axis` from a square plane on the `axis` side, and
/// `samples` samples along the central ray inside the box, seen from `view`.
pub fn rays_figure(
    size: [f64; 3],
    axis: [f64; 3],
    across: usize,
    samples: usize,
    view: &View,
) -> Result<RaysFigure> {
    let (d, u, v) = frame(axis)?;
    let longest = size.iter().copied().fold(f64::MIN_POSITIVE, f64::max);
    let half = size.map(|s| s / longest);
    let reach = dot(half, half).sqrt();
    let at = |p: [f64; 3]| view.project(p);
    let mut drawing = Drawing::default();
    box_edges(half, view, &mut drawing);
    // The plane beyond the box on the viewpoint's side, as wide as the box is across.
    let out = reach * 1.4;
    let point = |t: f64, a: f64, b: f64| -> [f64; 3] {
        std::array::from_fn(|k| d[k] * t + u[k] * a + v[k] * b)
    };
    let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
    for k in 0..4 {
        let ((a0, b0), (a1, b1)) = (corners[k], corners[(k + 1) % 4]);
        drawing.line(
            at(point(out, a0 * reach, b0 * reach)),
            at(point(out, a1 * reach, b1 * reach)),
            Ink::Plane,
        );
    }
    let spot = |i: usize| ((i as f64 + 0.5) / across as f64 * 2.0 - 1.0) * reach * 0.8;
    for i in 0..across {
        for j in 0..across {
            let (a, b) = (spot(i), spot(j));
            drawing.line(at(point(out, a, b)), at(point(-out, a, b)), Ink::Ray);
        }
    }
    // The ray through the centre, and its samples where it crosses the box.
    drawing.line(
        at(point(out, 0.0, 0.0)),
        at(point(-out, 0.0, 0.0)),
        Ink::Axis,
    );
    let inside = (0..3)
        .filter(|&k| d[k].abs() > 1e-12)
        .map(|k| half[k] / d[k].abs())
        .fold(f64::INFINITY, f64::min);
    let positions: Vec<[f64; 2]> = (0..samples)
        .map(|s| {
            let t = inside - (s as f64 + 0.5) / samples as f64 * 2.0 * inside;
            at(point(t, 0.0, 0.0))
        })
        .collect();
    for &p in &positions {
        drawing.dot(p, Ink::Sample);
    }
    drawing.dot(at(point(out, 0.0, 0.0)), Ink::Best);
    drawing.fit(0.1);
    Ok(RaysFigure {
        drawing,
        rays: across * across,
        samples: positions,
    })
}

/// The 12 edges of the box `±half`, those between two faces turned away drawn as hidden.
fn box_edges(half: [f64; 3], view: &View, drawing: &mut Drawing) {
    for along in 0..3 {
        let (p, q) = ((along + 1) % 3, (along + 2) % 3);
        for (sp, sq) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            let end = |s: f64| {
                let mut c = [0.0; 3];
                (c[along], c[p], c[q]) = (s * half[along], sp * half[p], sq * half[q]);
                view.project(c)
            };
            let normal = |k: usize, s: f64| {
                let mut n = [0.0; 3];
                n[k] = s;
                n
            };
            let seen = view.faces(normal(p, sp)) || view.faces(normal(q, sq));
            drawing.line(
                end(-1.0),
                end(1.0),
                if seen { Ink::Front } else { Ink::Back },
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fig_1b_casts_parallel_rays_from_the_plane_and_samples_the_central_one() {
        let view = View::default();
        let f = rays_figure([100.0, 50.0, 200.0], [0.0, 0.0, 1.0], 3, 7, &view).unwrap();
        assert_eq!(f.rays, 9);
        assert_eq!(f.drawing.count(Ink::Ray), (9, 0));
        assert_eq!(f.drawing.count(Ink::Plane), (4, 0));
        // A box seen obliquely: nine edges in sight, three hidden.
        assert_eq!(f.drawing.count(Ink::Front), (9, 0));
        assert_eq!(f.drawing.count(Ink::Back), (3, 0));
        // Seven samples inside the box (z from 1 down to -1, the box's longest side), evenly
        // spaced on the drawn central ray.
        assert_eq!(f.samples.len(), 7);
        assert_eq!(f.drawing.count(Ink::Sample), (0, 7));
        for (k, s) in f.samples.iter().enumerate() {
            let z = 1.0 - (k as f64 + 0.5) / 7.0 * 2.0;
            let expected = view.project([0.0, 0.0, z]);
            assert!((s[0] - expected[0]).abs() < 1e-12 && (s[1] - expected[1]).abs() < 1e-12);
        }
        // Every ray is parallel to the axis on the screen.
        let dir = view.project([0.0, 0.0, 1.0]);
        for s in f.drawing.segments.iter().filter(|s| s.ink == Ink::Ray) {
            let r = [s.to[0] - s.from[0], s.to[1] - s.from[1]];
            assert!((r[0] * dir[1] - r[1] * dir[0]).abs() < 1e-9);
        }
    }

    #[test]
    fn a_zero_axis_is_refused() {
        assert!(rays_figure([1.0; 3], [0.0; 3], 3, 5, &View::default()).is_err());
    }
}
