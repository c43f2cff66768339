//! The paper's figures as drawings: the viewpoint sphere of Fig. 1a ([`sphere_figure`]) and the
//! rays cast from a viewpoint's plane through the volume of Fig. 1b ([`rays_figure`]), projected
//! obliquely into segments and dots of a kind each ([`Ink`]). Nothing here knows how they are
//! shown: the TUI draws them in braille, `render::figure` as a picture.

mod rays;
mod sphere;

use serde::Serialize;

pub use rays::{RaysFigure, rays_figure};
pub use sphere::{SphereFigure, Viewpoint, sphere_figure};

use crate::geometry::{cross, dot, normalize};

/// What a mark is, for the presenter to choose its colour and weight.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Ink {
    /// The sphere's silhouette.
    Outline,
    /// An edge on the near side (of the wireframe sphere or the volume's box).
    Front,
    /// An edge on the far side, hidden in the paper's figure: drawn faint.
    Back,
    /// A viewpoint on the near side.
    Viewpoint,
    /// A viewpoint on the far side.
    Hidden,
    /// The chosen axis through the sphere's centre, or the ray whose samples are shown.
    Axis,
    /// The chosen viewpoint.
    Best,
    /// The viewpoint's plane the rays start from.
    Plane,
    /// A ray.
    Ray,
    /// A sample along the shown ray.
    Sample,
}

/// A straight mark from one point to another.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Segment {
    /// Where it starts, in the drawing's coordinates (y up).
    pub from: [f64; 2],
    /// Where it ends.
    pub to: [f64; 2],
    /// What it is.
    pub ink: Ink,
}

/// A round mark.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Dot {
    /// Its centre, in the drawing's coordinates (y up).
    pub at: [f64; 2],
    /// What it is.
    pub ink: Ink,
}

/// A figure: segments and dots in drawing order (what is behind first), within an extent.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Drawing {
    /// The segments.
    pub segments: Vec<Segment>,
    /// The dots, drawn over the segments.
    pub dots: Vec<Dot>,
    /// What the drawing covers: x min, y min, x max, y max (y up).
    pub extent: [f64; 4],
}

impl Drawing {
    fn line(&mut self, from: [f64; 2], to: [f64; 2], ink: Ink) {
        self.segments.push(Segment { from, to, ink });
    }

    fn dot(&mut self, at: [f64; 2], ink: Ink) {
        self.dots.push(Dot { at, ink });
    }

    /// Sets the extent to everything drawn, `margin` around it.
    fn fit(&mut self, margin: f64) {
        let mut e = [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ];
        let points = self
            .segments
            .iter()
            .flat_map(|s| [s.from, s.to])
            .chain(self.dots.iter().map(|d| d.at));
        for [x, y] in points {
            e = [e[0].min(x), e[1].min(y), e[2].max(x), e[3].max(y)];
        }
        if e[0].is_finite() {
            self.extent = [e[0] - margin, e[1] - margin, e[2] + margin, e[3] + margin];
        }
    }

    /// The marks of one ink: segments, then dots.
    pub fn count(&self, ink: Ink) -> (usize, usize) {
        (
            self.segments.iter().filter(|s| s.ink == ink).count(),
            self.dots.iter().filter(|d| d.ink == ink).count(),
        )
    }
}

/// An orthographic camera looking at the origin from a direction, z up on the screen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// The screen's x direction.
    pub right: [f64; 3],
    /// The screen's y direction.
    pub up: [f64; 3],
    /// From the origin towards the viewer.
    pub toward: [f64; 3],
}

impl View {
    /// Looking from `azimuth` degrees about z (from +x) and `elevation` degrees above the x-y
    /// plane (below 90°), as the paper's figures look at the sphere and the volume.
    pub fn oblique(azimuth: f64, elevation: f64) -> Self {
        let (a, e) = (
            azimuth.to_radians(),
            elevation.clamp(-89.0, 89.0).to_radians(),
        );
        let toward = [e.cos() * a.cos(), e.cos() * a.sin(), e.sin()];
        let z = [0.0, 0.0, 1.0];
        let up = normalize(std::array::from_fn(|k| z[k] - dot(z, toward) * toward[k]))
            .expect("the elevation is below 90°");
        Self {
            right: cross(up, toward),
            up,
            toward,
        }
    }

    /// Looking across `axis` and a little along it, so that rays along it run from the left of
    /// the screen to the right (as the paper's Fig. 1b draws them); `None` for a zero axis.
    pub fn across(axis: [f64; 3]) -> Option<Self> {
        let (d, u, v) = crate::geometry::frame(axis).ok()?;
        let toward = normalize(std::array::from_fn(|k| {
            -0.55 * d[k] + 0.7 * u[k] + 0.45 * v[k]
        }))?;
        let up = normalize(std::array::from_fn(|k| v[k] - dot(v, toward) * toward[k]))?;
        let right = cross(up, toward);
        // The viewpoint's side (+axis) on the left.
        let flip = if dot(right, d) > 0.0 { -1.0 } else { 1.0 };
        Some(Self {
            right: right.map(|c| c * flip),
            up: up.map(|c| c * flip),
            toward,
        })
    }

    /// Where `p` falls on the screen.
    pub fn project(&self, p: [f64; 3]) -> [f64; 2] {
        [dot(p, self.right), dot(p, self.up)]
    }

    /// Whether a surface of outward normal `n` faces the viewer.
    pub fn faces(&self, n: [f64; 3]) -> bool {
        dot(n, self.toward) > 0.0
    }
}

impl Default for View {
    /// The figures' view: from azimuth 30°, elevation 20° (the exploded view's default camera).
    fn default() -> Self {
        Self::oblique(30.0, 20.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_view_is_orthonormal_and_looks_from_its_direction() {
        let v = View::oblique(30.0, 20.0);
        for (a, b) in [(v.right, v.up), (v.up, v.toward), (v.right, v.toward)] {
            assert!(dot(a, b).abs() < 1e-12);
        }
        assert!((dot(cross(v.right, v.up), v.toward) - 1.0).abs() < 1e-12);
        // The viewer's own direction falls on the centre; z points up the screen.
        let c = v.project(v.toward);
        assert!(c[0].abs() < 1e-12 && c[1].abs() < 1e-12);
        assert!(v.project([0.0, 0.0, 1.0])[1] > 0.0);
        assert!(v.faces(v.toward) && !v.faces(v.toward.map(|c| -c)));
        // Across an axis: still a right-handed screen, the axis pointing left.
        let a = View::across([0.0, 0.0, 1.0]).unwrap();
        assert!((dot(cross(a.right, a.up), a.toward) - 1.0).abs() < 1e-12);
        let p = a.project([0.0, 0.0, 1.0]);
        assert!(p[0] < 0.0 && p[0].abs() > p[1].abs(), "{p:?}");
    }
}
