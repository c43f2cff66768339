//! The orbit camera: azimuth and elevation around the slab axis, zoom, orthographic or
//! perspective, with the axis pointing up in the image so the slabs stack vertically.

use crate::error::Result;
use crate::geometry::{DisplayFrame, cross, dot, frame, normalize};

/// Vertical field of view of the perspective camera, degrees.
const FOV_DEGREES: f64 = 30.0;

/// Where the camera is and how it projects.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraParams {
    /// Angle around the axis, degrees.
    pub azimuth: f64,
    /// Angle above the slab planes, degrees (90 looks straight down the axis).
    pub elevation: f64,
    /// Magnification: 1 fits the scene.
    pub zoom: f64,
    /// Perspective instead of orthographic projection.
    pub perspective: bool,
}

impl Default for CameraParams {
    /// Oblique to the axis, so that every gap between slabs shows.
    fn default() -> Self {
        Self {
            azimuth: 30.0,
            elevation: 20.0,
            zoom: 1.0,
            perspective: false,
        }
    }
}

/// A camera set up for one image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    center: [f64; 3],
    /// Unit vector from the centre towards the eye.
    back: [f64; 3],
    right: [f64; 3],
    up: [f64; 3],
    half_w: f64,
    half_h: f64,
    /// Distance of the eye from the centre (perspective), or of the ray origins (orthographic).
    distance: f64,
    perspective: bool,
    /// The zoom asked for, applied again after [`fit`](Self::fit).
    zoom: f64,
    width: u32,
    height: u32,
}

impl Camera {
    /// A camera looking at a scene of bounding-sphere `radius` around `center`, orbiting the
    /// `axis`, for a `width × height` image.
    pub fn new(
        center: [f64; 3],
        radius: f64,
        axis: [f64; 3],
        p: &CameraParams,
        width: u32,
        height: u32,
    ) -> Result<Self> {
        Self::oriented(center, radius, axis, None, p, width, height)
    }

    /// As [`new`](Self::new), oriented by `display` when the world is known: its `up` (which
    /// replaces `axis`) points up in the image, azimuth 0 looks from its `front`, and a mirrored
    /// voxel space is mirrored back, so that the picture shows the anatomy as it is.
    pub fn oriented(
        center: [f64; 3],
        radius: f64,
        axis: [f64; 3],
        display: Option<DisplayFrame>,
        p: &CameraParams,
        width: u32,
        height: u32,
    ) -> Result<Self> {
        let (d, mut u, mut v) = frame(display.map_or(axis, |f| f.up))?;
        if let Some(f) = display.and_then(|f| {
            let along = dot(f.front, d);
            normalize(std::array::from_fn(|m| f.front[m] - along * d[m]))
        }) {
            u = f;
            v = cross(d, u);
        }
        // Azimuth turns the same way in the world, and right is right, in a mirrored space.
        let mirrored = display.is_some_and(|f| f.mirrored);
        if mirrored {
            v = v.map(|c| -c);
        }
        let (az, el) = (
            p.azimuth.to_radians(),
            p.elevation.clamp(-89.9, 89.9).to_radians(),
        );
        let back: [f64; 3] = std::array::from_fn(|m| {
            el.cos() * (az.cos() * u[m] + az.sin() * v[m]) + el.sin() * d[m]
        });
        let back = normalize(back).expect("unit combination");
        // The axis, made perpendicular to the view, points up.
        let along = dot(d, back);
        let up = normalize(std::array::from_fn(|m| d[m] - along * back[m]))
            .expect("elevation is below 90 degrees");
        let mut right = cross(up, back);
        if mirrored {
            right = right.map(|c| -c);
        }
        let aspect = f64::from(width) / f64::from(height.max(1));
        let zoom = p.zoom.max(1e-3);
        let half_fov = (FOV_DEGREES / 2.0).to_radians();
        let (half_h, distance) = if p.perspective {
            let distance = radius / half_fov.sin() / zoom;
            (distance * half_fov.tan(), distance)
        } else {
            (radius / zoom, radius * 2.0 + 1.0)
        };
        Ok(Self {
            center,
            back,
            right,
            up,
            half_w: half_h * aspect,
            half_h,
            distance,
            perspective: p.perspective,
            zoom,
            width,
            height,
        })
    }

    /// Pans and scales the view so that `points` fill the image, but for `margin` of its
    /// width and height on every side and `room` more of its width on the left; then applies
    /// the zoom the camera was made with (around the new centre). Orthographic cameras fit
    /// exactly; perspective ones move the eye, to within a few per cent.
    pub fn fit(&mut self, points: &[[f64; 3]], margin: f64, room: f64) {
        let (w, h) = (f64::from(self.width), f64::from(self.height));
        let (target_w, target_h) = (w * (1.0 - 2.0 * margin - room), h * (1.0 - 2.0 * margin));
        if points.is_empty() || target_w <= 1.0 || target_h <= 1.0 {
            return;
        }
        let target_x = w * (margin + room) + target_w / 2.0;
        // The scene's bounding sphere, which the eye must stay out of.
        let radius = points
            .iter()
            .map(|p| {
                let r: [f64; 3] = std::array::from_fn(|m| p[m] - self.center[m]);
                dot(r, r).sqrt()
            })
            .fold(0.0, f64::max);
        let zoom = self.zoom;
        self.half_h *= zoom;
        self.distance *= if self.perspective { zoom } else { 1.0 };
        for _ in 0..if self.perspective { 6 } else { 1 } {
            let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
            for &p in points {
                let (x, y) = self.project(p);
                (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
            }
            if !(x1 > x0 || y1 > y0) || ![x0, x1, y0, y1].iter().all(|v| v.is_finite()) {
                break;
            }
            // Pan the box's centre to the image's, then scale it into the target, then pan it
            // to the target's centre.
            let (px, py) = (2.0 * self.half_w / w, 2.0 * self.half_h / h);
            let (dx, dy) = (
                f64::midpoint(x0, x1) - w / 2.0,
                h / 2.0 - f64::midpoint(y0, y1),
            );
            let ratio = ((x1 - x0) / target_w).max((y1 - y0) / target_h).max(1e-9);
            let shift_x = dx * px - (target_x - w / 2.0) * px * ratio;
            self.center = std::array::from_fn(|m| {
                self.center[m] + shift_x * self.right[m] + dy * py * self.up[m]
            });
            if self.perspective {
                self.distance = (self.distance * ratio).max(radius * 1.05);
                self.half_h = self.distance * (FOV_DEGREES / 2.0).to_radians().tan();
            } else {
                self.half_h *= ratio;
            }
            self.half_w = self.half_h * w / h;
        }
        if self.perspective {
            self.distance = (self.distance / zoom).max(radius * 1.05);
            self.half_h = self.distance * (FOV_DEGREES / 2.0).to_radians().tan();
            self.half_w = self.half_h * w / h;
        } else {
            self.half_h /= zoom;
            self.half_w /= zoom;
            // Ray origins stay outside the scene whatever the pan.
            self.distance = self.distance.max(3.0 * radius + 1.0);
        }
    }

    /// The parameter along the ray through its pixel at which world point `p` lies.
    pub fn depth(&self, p: [f64; 3]) -> f64 {
        let rel: [f64; 3] = std::array::from_fn(|m| p[m] - self.center[m]);
        if self.perspective {
            let eye: [f64; 3] = std::array::from_fn(|m| self.distance * self.back[m] - rel[m]);
            dot(eye, eye).sqrt()
        } else {
            self.distance - dot(rel, self.back)
        }
    }

    /// Origin and unit direction of the ray through the centre of pixel `(x, y)` (y down).
    pub fn ray(&self, x: u32, y: u32) -> ([f64; 3], [f64; 3]) {
        let sx = ((f64::from(x) + 0.5) / f64::from(self.width) * 2.0 - 1.0) * self.half_w;
        let sy = (1.0 - (f64::from(y) + 0.5) / f64::from(self.height) * 2.0) * self.half_h;
        let on_plane: [f64; 3] =
            std::array::from_fn(|m| self.center[m] + sx * self.right[m] + sy * self.up[m]);
        if self.perspective {
            let eye: [f64; 3] =
                std::array::from_fn(|m| self.center[m] + self.distance * self.back[m]);
            let dir = normalize(std::array::from_fn(|m| on_plane[m] - eye[m]))
                .expect("eye is off the plane");
            (eye, dir)
        } else {
            let origin = std::array::from_fn(|m| on_plane[m] + self.distance * self.back[m]);
            (origin, self.back.map(|c| -c))
        }
    }

    /// The unit directions to the right and up in the image, in the scene's space.
    pub fn axes(&self) -> ([f64; 3], [f64; 3]) {
        (self.right, self.up)
    }

    /// How far apart neighbouring pixels' rays are where they meet the scene whose hull is
    /// `points`: everywhere the same for an orthographic camera; for a perspective one, at the
    /// nearest depth (along the view) of any of them, where the rays are closest, so the
    /// smallest spacing of rays anywhere in the scene.
    pub fn pixel_size(&self, points: &[[f64; 3]]) -> f64 {
        let pixel = 2.0 * self.half_h / f64::from(self.height.max(1));
        if !self.perspective {
            return pixel;
        }
        let nearest = points
            .iter()
            .map(|p| {
                let rel: [f64; 3] = std::array::from_fn(|m| p[m] - self.center[m]);
                self.distance - dot(rel, self.back)
            })
            .fold(f64::INFINITY, f64::min);
        if nearest.is_finite() {
            pixel * nearest.max(0.0) / self.distance
        } else {
            pixel
        }
    }

    /// A direction in the image: its components to the right and up (y up), and towards the
    /// viewer.
    pub fn screen_direction(&self, d: [f64; 3]) -> (f64, f64, f64) {
        (dot(d, self.right), dot(d, self.up), dot(d, self.back))
    }

    /// The image position (x right, y down, in pixels) of a world point.
    pub fn project(&self, p: [f64; 3]) -> (f64, f64) {
        let rel: [f64; 3] = std::array::from_fn(|m| p[m] - self.center[m]);
        let (mut sx, mut sy) = (dot(rel, self.right), dot(rel, self.up));
        if self.perspective {
            // Similar triangles from the eye onto the plane through the centre.
            let depth = self.distance - dot(rel, self.back);
            sx *= self.distance / depth;
            sy *= self.distance / depth;
        }
        (
            f64::midpoint(sx / self.half_w, 1.0) * f64::from(self.width),
            (1.0 - sy / self.half_h) / 2.0 * f64::from(self.height),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rays_and_projection_agree() {
        for perspective in [false, true] {
            let p = CameraParams {
                azimuth: 40.0,
                elevation: 25.0,
                zoom: 1.3,
                perspective,
            };
            let cam = Camera::new([5.0, 6.0, 7.0], 10.0, [0.0, 0.0, 1.0], &p, 64, 48).unwrap();
            for (x, y) in [(0, 0), (10, 40), (63, 47), (32, 24)] {
                let (o, d) = cam.ray(x, y);
                for t in [5.0, 20.0] {
                    let q: [f64; 3] = std::array::from_fn(|m| o[m] + t * d[m]);
                    let (px, py) = cam.project(q);
                    assert!(
                        (px - (f64::from(x) + 0.5)).abs() < 1e-6,
                        "{perspective}: {px} vs {x}"
                    );
                    assert!(
                        (py - (f64::from(y) + 0.5)).abs() < 1e-6,
                        "{perspective}: {py} vs {y}"
                    );
                }
            }
        }
    }

    #[test]
    fn pixel_sizes_are_the_spacing_of_neighbouring_rays() {
        for perspective in [false, true] {
            let p = CameraParams {
                perspective,
                ..CameraParams::default()
            };
            let cam = Camera::new([0.0; 3], 10.0, [0.0, 0.0, 1.0], &p, 64, 48).unwrap();
            // Where rays of the middle row cross the plane 3 mm nearer than the centre.
            let near: [f64; 3] = cam.back.map(|c| 3.0 * c);
            let at = |x: u32| -> [f64; 3] {
                let (o, d) = cam.ray(x, 24);
                let t = (3.0 - dot(o, cam.back)) / dot(d, cam.back);
                std::array::from_fn(|m| o[m] + t * d[m])
            };
            let (a, b) = (at(32), at(33));
            let apart = dot(std::array::from_fn(|m| b[m] - a[m]), cam.right);
            let pixel = cam.pixel_size(&[near, [0.0; 3]]);
            assert!(
                (apart - pixel).abs() < 1e-9 * pixel,
                "{perspective}: {apart} vs {pixel}"
            );
            if perspective {
                assert!(pixel < cam.pixel_size(&[]), "nearer, closer together");
            } else {
                assert_eq!(pixel, cam.pixel_size(&[]));
            }
        }
    }

    #[test]
    fn the_front_is_seen_at_azimuth_zero() {
        // Up along z, looking from +y with no elevation: +x is to the left in the image.
        let p = CameraParams {
            azimuth: 0.0,
            elevation: 0.0,
            ..CameraParams::default()
        };
        let display = |mirrored| DisplayFrame {
            up: [0.0, 0.0, 1.0],
            front: [0.0, 1.0, 0.0],
            mirrored,
        };
        let cam = |mirrored| {
            Camera::oriented(
                [0.0; 3],
                10.0,
                [1.0, 0.0, 0.0],
                Some(display(mirrored)),
                &p,
                100,
                100,
            )
            .unwrap()
        };
        let (x, _, toward) = cam(false).screen_direction([1.0, 0.0, 0.0]);
        assert!((x + 1.0).abs() < 1e-12 && toward.abs() < 1e-12);
        // A mirrored voxel space is shown mirrored back.
        let (x, _, _) = cam(true).screen_direction([1.0, 0.0, 0.0]);
        assert!((x - 1.0).abs() < 1e-12);
        let cam = cam(false);
        let (_, _, toward) = cam.screen_direction([0.0, 1.0, 0.0]);
        assert!((toward - 1.0).abs() < 1e-12);
        let (_, up, _) = cam.screen_direction([0.0, 0.0, 1.0]);
        assert!((up - 1.0).abs() < 1e-12);
    }

    #[test]
    fn the_axis_points_up() {
        let cam = Camera::new(
            [0.0; 3],
            10.0,
            [0.0, 0.0, 1.0],
            &CameraParams::default(),
            100,
            100,
        )
        .unwrap();
        let (_, low) = cam.project([0.0, 0.0, -5.0]);
        let (_, high) = cam.project([0.0, 0.0, 5.0]);
        assert!(high < low, "higher along the axis is higher in the image");
    }
}
