//! The render worker: a thread that owns the volume and its renderer, takes the newest request,
//! renders it (the exploded view, or the slice view with its readout) and encodes it for the
//! terminal.

use std::cell::OnceCell;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, Sender, channel};

use image::RgbaImage;
use slabscope::geometry::{self, min_spacing};
use slabscope::partition::Slab;
use slabscope::render::slice::{self, SliceParams};
use slabscope::render::{Stack, draw_figure, paste_centred};
use slabscope::request::{RenderRequest, Shown};
use slabscope::{Monitor, Renderer, Volume};
use tiny_skia::Pixmap;

use super::Open;
use crate::term::image::encode;
use crate::term::{Caps, Graphics};
use crate::tui::event::{Event, JobMsg, PictureJob, PictureSettings, Rendered, SliceCursor};

/// The render worker: owns the volume and its renderer, renders the newest request, encodes it
/// for the terminal and sends it back.
pub(super) fn start_renderer(
    open: Open,
    caps: Caps,
    (events, epoch): (Sender<Event>, u64),
    cancel: Arc<AtomicBool>,
) -> Sender<PictureJob> {
    let (tx, rx) = channel::<PictureJob>();
    std::thread::spawn(move || {
        let events = EpochSender { events, epoch };
        let serve = move || serve(&rx, &open, &caps, &events, &cancel);
        // Threads of its own: on the global pool a picture would wait behind the view search's
        // and the histories' work, which keep every thread of it busy for as long as they run
        // (the first picture of a 96³ volume came after the view search, a minute on a busy
        // machine). The pool's threads end with the worker.
        let threads = std::thread::available_parallelism().map_or(2, usize::from);
        match rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(|i| format!("slabscope-render-{i}"))
            .build()
        {
            Ok(pool) => pool.install(serve),
            Err(_) => serve(),
        }
    });
    tx
}

/// Renders the newest of the requests `rx` takes until it closes, and sends the pictures.
fn serve(
    rx: &Receiver<PictureJob>,
    open: &Open,
    caps: &Caps,
    events: &EpochSender,
    cancel: &AtomicBool,
) {
    // The preview's pyramid level and its renderer, and level 0's, each made when first
    // asked for.
    let coarse: OnceCell<Arc<Volume>> = OnceCell::new();
    let (mut full, mut preview) = (None, None);
    while let Some(request) = newest(rx) {
        cancel.store(false, Ordering::Relaxed);
        let monitor = Monitor::new(Some(cancel), None);
        let generation = request.generation;
        let renderer = match (request.level, open.full(), open.level(request.level)) {
            (0, Some(volume), _) => made_for(&mut full, volume),
            (k, _, Some(source)) if k > 0 => {
                made_for(&mut preview, coarse.get_or_init(|| source.get()))
            }
            _ => Err(anyhow::anyhow!(
                "pyramid level {} is not loaded yet",
                request.level
            )),
        };
        let result = renderer.and_then(|r| render(r, caps, &request, &monitor));
        match result {
            Err(e)
                if matches!(
                    e.downcast_ref::<slabscope::Error>(),
                    Some(slabscope::Error::Cancelled)
                ) => {}
            result => {
                let _ = events.send(Event::Job(JobMsg::Rendered(
                    generation,
                    result.map_err(|e| format!("{e:#}")),
                )));
            }
        }
    }
}

/// The renderer in `slot`, made for `volume` the first time.
fn made_for<'a, 'v>(
    slot: &'a mut Option<Renderer<'v>>,
    volume: &'v Volume,
) -> anyhow::Result<&'a Renderer<'v>> {
    if slot.is_none() {
        *slot = Some(Renderer::new(volume)?);
    }
    Ok(slot.as_ref().expect("made above"))
}

/// Sends a volume's messages marked with its epoch.
struct EpochSender {
    events: Sender<Event>,
    epoch: u64,
}

impl EpochSender {
    fn send(&self, event: Event) -> Result<(), std::sync::mpsc::SendError<Event>> {
        match event {
            Event::Job(msg) => self
                .events
                .send(Event::Job(JobMsg::Epoch(self.epoch, Box::new(msg)))),
            other => self.events.send(other),
        }
    }
}

/// Waits for a request, then takes the newest one queued.
fn newest(rx: &Receiver<PictureJob>) -> Option<PictureJob> {
    let mut request = rx.recv().ok()?;
    while let Ok(newer) = rx.try_recv() {
        request = newer;
    }
    Some(request)
}

/// Renders `r` with `renderer` as large as the terminal takes it (the exploded view, or the
/// slice view when asked), encoded for the terminal of `caps`.
pub(super) fn render(
    renderer: &Renderer,
    caps: &Caps,
    r: &PictureJob,
    monitor: &Monitor,
) -> anyhow::Result<Box<Rendered>> {
    // One image pixel per screen pixel, as large as the terminal takes.
    let (width, height) = caps.image_size(r.cells);
    let (width, height) = (width.max(1), height.max(1));
    let (pixmap, caption, window) = picture(renderer, r, (width, height), monitor)?;
    let rgba = RgbaImage::from_raw(width, height, pixmap.data().to_vec())
        .ok_or_else(|| anyhow::anyhow!("render buffer has the wrong size"))?;
    let cells = match caps.graphics {
        Graphics::Blocks => r.cells,
        _ => (
            (width.div_ceil(u32::from(caps.cell.0)) as u16).min(r.cells.0),
            (height.div_ceil(u32::from(caps.cell.1)) as u16).min(r.cells.1),
        ),
    };
    Ok(Box::new(Rendered {
        image: encode(&rgba, cells, caps).map_err(|e| anyhow::anyhow!(e))?,
        caption,
        window,
    }))
}

/// A picture drawn, the slice view's readout and the colour window used.
pub(super) type Drawn = (Pixmap, Option<String>, Option<(f32, f32)>);

/// The picture of `r`, `width × height` pixels, drawn with `renderer`: a figure of the paper's,
/// the slice view with its readout, or the exploded view as the library's render request draws
/// it; and the colour window it used (none for a figure).
pub(super) fn picture(
    renderer: &Renderer,
    r: &PictureJob,
    (width, height): (u32, u32),
    monitor: &Monitor,
) -> anyhow::Result<Drawn> {
    let look = &r.look;
    let histories = r.histories.as_deref().filter(|_| !r.slabs.is_empty());
    Ok(match (r.figure.as_deref(), r.slice, histories) {
        (Some(drawing), ..) => (draw_figure(drawing, width, height)?, None, None),
        (None, Some(s), Some(h)) => {
            let highlight = r.highlight.unwrap_or(0).min(r.slabs.len() - 1);
            let view = SliceView {
                stack: &Stack::of_slices(h.stack()),
                slab: (highlight, r.slabs[highlight]),
                cursor: s,
                size: (width, height),
            };
            let (pixmap, caption, window) = view.draw(renderer, look)?;
            (pixmap, Some(caption), Some(window))
        }
        _ => {
            let shown = match histories {
                Some(histories) => Shown::Stepped {
                    histories,
                    slabs: &r.slabs,
                    nmi: r.nmi.as_deref(),
                },
                None => Shown::Whole(r.axis),
            };
            // A slab past the ones shown (the list a step behind) is highlighted nowhere.
            let highlight = r.highlight.filter(|&h| h < shown.count());
            let request = RenderRequest {
                scene: look.scene((width, height), highlight),
                faces: false,
            };
            let image = request.exploded(renderer, &shown, monitor)?;
            (image.pixmap, None, Some(image.window))
        }
    })
}

/// The slice view: the slice under the cursor, large, with the pointer's cross; beside it the
/// selected slab's faces, its last slice above its first.
struct SliceView<'a> {
    stack: &'a Stack,
    slab: (usize, Slab),
    cursor: SliceCursor,
    size: (u32, u32),
}

impl SliceView<'_> {
    /// The picture, the readout at the pointer (slice, voxel, world position, value) and the
    /// colour window.
    fn draw(
        &self,
        renderer: &Renderer,
        look: &PictureSettings,
    ) -> anyhow::Result<(Pixmap, String, (f32, f32))> {
        let volume = renderer.volume();
        let spacing = volume.spacing();
        let transfer = renderer.transfer(look.colours(), min_spacing(spacing))?;
        let (w, h) = self.size;
        let mut canvas = Pixmap::new(w, h).ok_or_else(|| anyhow::anyhow!("no room for slices"))?;
        canvas.fill(tiny_skia::Color::from_rgba8(12, 12, 18, 255));
        let stack = self.stack;
        let index = self.cursor.index.min(stack.slices.saturating_sub(1));
        // The slice takes three fifths of a wide pane, the faces the rest.
        let side = if w > h { w * 2 / 5 } else { 0 };
        let params = |fit: (u32, u32)| SliceParams {
            fit: (fit.0.max(1), fit.1.max(1)),
            background: [0, 0, 0],
            ..SliceParams::default()
        };
        let main = slice::slice(
            volume,
            &transfer,
            stack.axis,
            stack.position(index),
            &params((w - side, h)),
        )?;
        let origin = paste_centred(&mut canvas, &main.pixmap, (0, 0, w - side, h));
        // The pointer, moved onto the plane.
        let n = stack.axis;
        let p = self.cursor.pointer;
        let off = stack.position(index) - geometry::dot(p, n);
        let on_plane: [f64; 3] = std::array::from_fn(|m| p[m] + off * n[m]);
        let (px, py) = main.pixel_of(on_plane);
        cross_hair(
            &mut canvas,
            (
                origin.0 as f32 + px as f32 + 0.5,
                origin.1 as f32 + py as f32 + 0.5,
            ),
        );
        let (k, (a, b)) = self.slab;
        if side > 8 {
            for (row, s) in slice::face_slices((a, b)).into_iter().enumerate() {
                let face = slice::slice(
                    volume,
                    &transfer,
                    stack.axis,
                    stack.position(s),
                    &params((side - 4, h / 2 - 2)),
                )?;
                let area = (w - side + 2, row as u32 * (h / 2) + 1, side - 4, h / 2 - 2);
                paste_centred(&mut canvas, &face.pixmap, area);
            }
        }
        Ok((
            canvas,
            readout(volume, on_plane, index, stack.slices, k, (a, b)),
            transfer.window(),
        ))
    }
}

/// What the slice view reads at physical point `p`.
fn readout(
    volume: &Volume,
    p: [f64; 3],
    index: usize,
    slices: usize,
    k: usize,
    (a, b): Slab,
) -> String {
    let (spacing, dims) = (volume.spacing(), volume.dims());
    let ijk: [usize; 3] =
        std::array::from_fn(|m| ((p[m] / spacing[m]).round().max(0.0) as usize).min(dims[m] - 1));
    let value = volume.value(ijk);
    let t = volume.transform();
    let world = t.apply(ijk.map(|i| i as f64));
    let place = if t.known {
        let named = |v: f64, pos: char, neg: char| {
            format!("{}{:.1}", if v >= 0.0 { pos } else { neg }, v.abs())
        };
        format!(
            "{} {} {} mm",
            named(world[0], 'R', 'L'),
            named(world[1], 'A', 'P'),
            named(world[2], 'S', 'I')
        )
    } else {
        format!("{:.1}, {:.1}, {:.1} mm", world[0], world[1], world[2])
    };
    // The reading first: the pane's border may be narrow.
    format!(
        "voxel {},{},{} = {value} · {place} · slice {index}/{} · slab {k}: faces {a}, {}",
        ijk[0],
        ijk[1],
        ijk[2],
        slices - 1,
        b.saturating_sub(1),
    )
}

/// A yellow cross with an open centre at `(x, y)`.
fn cross_hair(canvas: &mut Pixmap, (x, y): (f32, f32)) {
    let mut paint = tiny_skia::Paint::default();
    paint.set_color_rgba8(255, 220, 90, 230);
    let (gap, arm) = (3.0, 9.0);
    let mut pb = tiny_skia::PathBuilder::new();
    for (dx, dy) in [(1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)] {
        pb.move_to(x + dx * gap, y + dy * gap);
        pb.line_to(x + dx * (gap + arm), y + dy * (gap + arm));
    }
    if let Some(path) = pb.finish() {
        canvas.stroke_path(
            &path,
            &paint,
            &tiny_skia::Stroke::default(),
            tiny_skia::Transform::identity(),
            None,
        );
    }
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::AtomicUsize;
    use std::time::Duration;

    use super::*;

    /// A picture is drawn while every thread of rayon's global pool is busy, as the view search
    /// keeps them: the worker has threads of its own. (On the global pool it would wait until
    /// they are let go, which here is only after the picture.)
    #[test]
    fn a_picture_does_not_wait_for_rayons_global_pool() {
        let volume = Arc::new(slabscope::volume::phantom::body([24, 24, 32], 1).unwrap());
        let open = Open {
            full: Some(volume),
            preview: None,
        };
        let threads = rayon::current_num_threads();
        let (busy, release) = (
            Arc::new(AtomicUsize::new(0)),
            Arc::new(AtomicBool::new(false)),
        );
        for _ in 0..threads {
            let (busy, release) = (Arc::clone(&busy), Arc::clone(&release));
            rayon::spawn(move || {
                busy.fetch_add(1, Ordering::SeqCst);
                while !release.load(Ordering::SeqCst) {
                    std::thread::sleep(Duration::from_millis(1));
                }
            });
        }
        while busy.load(Ordering::SeqCst) < threads {
            std::thread::sleep(Duration::from_millis(1));
        }
        let (tx, rx) = channel();
        let cancel = Arc::new(AtomicBool::new(false));
        let renders = start_renderer(open, Caps::blocks(), (tx, 3), cancel);
        renders.send(PictureJob::whole((40, 12))).unwrap();
        // A bound only for failing: the picture takes milliseconds.
        let got = rx.recv_timeout(Duration::from_secs(120));
        release.store(true, Ordering::SeqCst);
        let Ok(Event::Job(JobMsg::Epoch(3, msg))) = got else {
            panic!("no picture while the global pool was busy");
        };
        let JobMsg::Rendered(1, Ok(r)) = *msg else {
            panic!("not the picture");
        };
        assert_eq!(r.image.cells, (40, 12));
    }
}
