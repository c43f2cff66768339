//! The paper's figures (`explain::figure`) drawn as pictures with tiny-skia: dark ink on white,
//! as they would stand on a slide, the far side faint, the chosen viewpoint and the samples in
//! colour.

use tiny_skia::{FillRule, Paint, PathBuilder, Pixmap, Stroke, Transform};

use crate::error::{Error, Result};
use crate::explain::figure::{Drawing, Ink};

/// An ink's colour (RGBA) and its width relative to the picture's shorter side.
fn pen(ink: Ink) -> ([u8; 4], f32) {
    match ink {
        Ink::Outline => ([40, 40, 40, 255], 0.006),
        Ink::Front | Ink::Plane => ([30, 30, 30, 255], 0.004),
        Ink::Back | Ink::Hidden => ([150, 150, 150, 255], 0.003),
        Ink::Viewpoint => ([20, 20, 20, 255], 0.014),
        Ink::Axis => ([200, 40, 40, 255], 0.005),
        Ink::Best => ([220, 30, 30, 255], 0.026),
        Ink::Ray => ([60, 110, 200, 255], 0.003),
        Ink::Sample => ([20, 150, 60, 255], 0.016),
    }
}

/// `drawing` on a white `width × height` picture, its extent fitted in, aspect kept.
pub fn draw_figure(drawing: &Drawing, width: u32, height: u32) -> Result<Pixmap> {
    let mut pixmap = Pixmap::new(width, height)
        .ok_or_else(|| Error::Encode(format!("a figure of {width}×{height} pixels")))?;
    pixmap.fill(tiny_skia::Color::WHITE);
    let [x0, y0, x1, y1] = drawing.extent;
    let (w, h) = (f64::from(width), f64::from(height));
    let scale = (w / (x1 - x0).max(1e-12)).min(h / (y1 - y0).max(1e-12));
    let (cx, cy) = (f64::midpoint(x0, x1), f64::midpoint(y0, y1));
    let at = |[x, y]: [f64; 2]| {
        (
            (w / 2.0 + (x - cx) * scale) as f32,
            (h / 2.0 - (y - cy) * scale) as f32,
        )
    };
    let side = width.min(height) as f32;
    let paint = |rgba: [u8; 4]| {
        let mut p = Paint::default();
        p.set_color_rgba8(rgba[0], rgba[1], rgba[2], rgba[3]);
        p.anti_alias = true;
        p
    };
    for s in &drawing.segments {
        let (rgba, width) = pen(s.ink);
        let mut pb = PathBuilder::new();
        let (a, b) = (at(s.from), at(s.to));
        pb.move_to(a.0, a.1);
        pb.line_to(b.0, b.1);
        let Some(path) = pb.finish() else { continue };
        let stroke = Stroke {
            width: (width * side).max(1.0),
            ..Stroke::default()
        };
        pixmap.stroke_path(&path, &paint(rgba), &stroke, Transform::identity(), None);
    }
    for d in &drawing.dots {
        let (rgba, diameter) = pen(d.ink);
        let (x, y) = at(d.at);
        let Some(circle) = PathBuilder::from_circle(x, y, (diameter * side / 2.0).max(1.0)) else {
            continue;
        };
        pixmap.fill_path(
            &circle,
            &paint(rgba),
            FillRule::Winding,
            Transform::identity(),
            None,
        );
    }
    Ok(pixmap)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::explain::figure::{View, sphere_figure};

    #[test]
    fn the_best_viewpoint_is_red_where_it_projects() {
        let view = View::default();
        let f = sphere_figure(1, [0.0, 0.0, 1.0], &view);
        let (w, h) = (400, 300);
        let pixmap = draw_figure(&f.drawing, w, h).unwrap();
        let [x0, y0, x1, y1] = f.drawing.extent;
        let scale = (400.0 / (x1 - x0)).min(300.0 / (y1 - y0));
        let [bx, by] = f.viewpoints[f.best].at;
        let px = (200.0 + (bx - f64::midpoint(x0, x1)) * scale).round() as u32;
        let py = (150.0 - (by - f64::midpoint(y0, y1)) * scale).round() as u32;
        let c = pixmap.pixel(px, py).unwrap();
        assert_eq!((c.red(), c.green(), c.blue()), (220, 30, 30));
        // The corners are the white page.
        let corner = pixmap.pixel(0, 0).unwrap();
        assert_eq!(
            (corner.red(), corner.green(), corner.blue()),
            (255, 255, 255)
        );
        assert!(draw_figure(&f.drawing, 0, 10).is_err());
    }
}
