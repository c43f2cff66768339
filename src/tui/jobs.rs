//! Background work for the TUI: loading, the view search, the histories and exports each on their
//! own thread with a shared cancellation flag, and a render worker that always takes the newest
//! request (a newer one replaces a queued one and cancels the one in flight). Every effect
//! carries the data it needs; nothing here reads the app.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, Sender, channel};

use image::RgbaImage;
use slabscope::geometry::{self, min_spacing};
use slabscope::partition::Slab;
use slabscope::render::slice::{self, SliceParams};
use slabscope::render::{Gap, Stack, paste_centred};
use slabscope::volume::io::{NrrdEncoding, write_atomic, write_nrrd};
use slabscope::{
    Analysis, AnalysisReport, Histories, Layout, LoadOptions, Monitor, Partition, Progress,
    RenderParams, Renderer, Scope, Volume, label_volume, search,
};
use tiny_skia::Pixmap;

use super::event::{
    Effect, Event, ExportRequest, Job, JobMsg, Look, RenderRequest, Rendered, SliceRequest,
};
use crate::term::image::encode;
use crate::term::{Caps, Graphics};

/// Runs effects in the background and reports through the event channel.
pub struct Jobs {
    events: Sender<Event>,
    cancel: Arc<AtomicBool>,
    renders: Option<Sender<RenderRequest>>,
    render_cancel: Arc<AtomicBool>,
    caps: Caps,
    source: Option<slabscope::triage::Entry>,
    load: LoadOptions,
    volume: Option<Arc<Volume>>,
    /// Which volume is open: one more at each [`Effect::Open`].
    epoch: u64,
}

impl Jobs {
    /// Jobs reporting to `events`, loading `source` (None: the built-in dataset).
    pub fn new(
        events: Sender<Event>,
        caps: Caps,
        source: Option<slabscope::triage::Entry>,
        load: LoadOptions,
    ) -> Self {
        Self {
            events,
            cancel: Arc::new(AtomicBool::new(false)),
            renders: None,
            render_cancel: Arc::new(AtomicBool::new(false)),
            caps,
            source,
            load,
            volume: None,
            epoch: 0,
        }
    }

    /// Sees a message before the app does: a loaded volume starts the render worker.
    fn observe(&mut self, msg: &JobMsg) {
        if let JobMsg::Loaded(Ok((volume, _))) = msg {
            self.volume = Some(Arc::clone(volume));
            self.renders = Some(start_renderer(
                Arc::clone(volume),
                self.caps.clone(),
                (self.events.clone(), self.epoch),
                Arc::clone(&self.render_cancel),
            ));
        }
    }

    /// Carries out `effect`.
    pub fn run(&mut self, effect: Effect) {
        match effect {
            Effect::Load => self.spawn(Job::Load, {
                let (source, load) = (self.source.clone(), self.load.clone());
                move |_| {
                    let loaded = match &source {
                        Some(entry) => {
                            let load = LoadOptions {
                                series: entry.series.clone().or(load.series),
                                ..load
                            };
                            slabscope::load(&entry.path, &load)
                                .map(|l| (Arc::new(l.volume), l.notes))
                        }
                        None => slabscope::builtin_dataset().map(|v| (Arc::new(v), Vec::new())),
                    };
                    JobMsg::Loaded(loaded.map_err(|e| e.to_string()))
                }
            }),
            Effect::SearchViews(params) => {
                let Some(volume) = self.volume.clone() else {
                    return;
                };
                self.spawn(Job::Views, move |monitor| {
                    JobMsg::Views(
                        search(&volume, &params, monitor)
                            .map(Box::new)
                            .map_err(|e| e.to_string()),
                    )
                });
            }
            Effect::Analyze(generation, axis, params) => {
                let Some(volume) = self.volume.clone() else {
                    return;
                };
                self.spawn(Job::Analysis, move |monitor| {
                    let result = Histories::new(&volume, axis, &params, Scope::ALL, monitor);
                    JobMsg::Analysis(generation, result.map(Arc::new).map_err(|e| e.to_string()))
                });
            }
            Effect::Open(path) => {
                // The next volume: its own load, views, histories and renders; what the jobs of
                // the last one still send is dropped.
                self.epoch += 1;
                self.source = Some(path);
                self.volume = None;
                self.renders = None;
            }
            Effect::Triage(paths, params) => {
                let (events, load) = (self.events.clone(), self.load.clone());
                std::thread::spawn(move || {
                    let how = slabscope::triage::Look {
                        load,
                        params: *params,
                        timeout: std::time::Duration::from_secs(60),
                        fast: true,
                        tile: None,
                    };
                    for (i, entry) in paths.iter().enumerate() {
                        // The list names the file: its errors need not.
                        let prefix = format!("{}: ", entry.path.display());
                        let describe = |e: slabscope::Error| {
                            let m = e.to_string();
                            m.strip_prefix(&prefix).map_or(m.clone(), str::to_string)
                        };
                        let row = slabscope::triage::look(entry, &how, &|_| {}, &describe).row;
                        if events
                            .send(Event::Job(JobMsg::Triaged(i, Box::new(row))))
                            .is_err()
                        {
                            break;
                        }
                    }
                });
            }
            Effect::Render(request) => {
                if let Some(tx) = &self.renders {
                    self.render_cancel.store(true, Ordering::Relaxed);
                    let _ = tx.send(*request);
                }
            }
            Effect::Cancel => {
                self.cancel.store(true, Ordering::Relaxed);
                self.render_cancel.store(true, Ordering::Relaxed);
                self.cancel = Arc::new(AtomicBool::new(false));
            }
            Effect::Export(request) => {
                if let Some(volume) = self.volume.clone() {
                    self.spawn(Job::Export, move |monitor| {
                        JobMsg::Exported(
                            export(&volume, &request, monitor).map_err(|e| e.to_string()),
                        )
                    });
                }
            }
            Effect::Quit => {}
        }
    }

    /// Runs `work` on its own thread with a monitor that reports `job`'s progress.
    fn spawn(&self, job: Job, work: impl FnOnce(&Monitor) -> JobMsg + Send + 'static) {
        let (events, cancel, epoch) = (self.events.clone(), Arc::clone(&self.cancel), self.epoch);
        std::thread::spawn(move || {
            let send = |msg: JobMsg| {
                let _ = events.send(Event::Job(JobMsg::Epoch(epoch, Box::new(msg))));
            };
            let progress = |p: Progress| send(JobMsg::Progress(job, p));
            let monitor = Monitor::new(Some(&cancel), Some(&progress));
            send(work(&monitor));
        });
    }

    /// The message the app should see of `msg`: none when it belongs to a volume no longer
    /// open.
    pub fn admit(&mut self, msg: JobMsg) -> Option<JobMsg> {
        let msg = match msg {
            JobMsg::Epoch(epoch, _) if epoch != self.epoch => return None,
            JobMsg::Epoch(_, inner) => *inner,
            msg => msg,
        };
        self.observe(&msg);
        Some(msg)
    }
}

/// Writes the view (PNG), the analysis (JSON) and the labels (NRRD) of the request's partition
/// to the current folder under names not taken yet; says what it wrote.
fn export(volume: &Volume, r: &ExportRequest, monitor: &Monitor) -> slabscope::Result<String> {
    let part = Partition::new(&r.histories, r.method, r.position, monitor)?;
    let stem = Path::new(&r.name)
        .file_stem()
        .map_or_else(|| "builtin".into(), |s| s.to_string_lossy().into_owned());
    let png = free_name(&format!("{stem}-slabscope"), "png");
    let json = free_name(&format!("{stem}-slabscope"), "json");
    let labels = free_name(&format!("{stem}-slabscope-labels"), "nrrd");
    let layout = Layout::exploded(&part, r.look.gap, r.look.spread);
    let render = RenderParams {
        width: 1280,
        height: 960,
        mode: r.look.mode,
        preset: r.look.preset,
        colormap: r.look.colormap,
        window: r.look.window,
        camera: r.look.camera,
        highlight: r.highlight.filter(|&h| h < part.slabs.len()),
        solo: r.look.solo,
        ..RenderParams::default()
    };
    let image = Renderer::new(volume)?.render(&layout, &render, monitor)?;
    write_new(&png, &image.png()?)?;
    let analysis = Analysis {
        views: r.views.clone(),
        notes: slabscope::analysis::notes(volume, &r.view_params, &part),
        partition: part,
    };
    let report = AnalysisReport::new(&r.name, volume, &r.view_params, &analysis)?;
    let text = slabscope::report::to_json(&report)?;
    write_new(&json, text.as_bytes())?;
    monitor.start("writing labels", 1);
    let labelled = label_volume(volume, &analysis.partition)?;
    write_nrrd(&labels, &labelled, NrrdEncoding::Gzip, false)?;
    Ok(format!(
        "wrote {}, {} and {}",
        png.display(),
        json.display(),
        labels.display()
    ))
}

/// Writes `bytes` to `path`, which must not exist.
fn write_new(path: &Path, bytes: &[u8]) -> slabscope::Result<()> {
    use std::io::Write;
    write_atomic(path, false, |mut file| file.write_all(bytes))
}

/// `stem.ext` in the current folder, or `stem-1.ext`, `stem-2.ext`, … when taken.
fn free_name(stem: &str, ext: &str) -> PathBuf {
    let name = |i: u32| {
        if i == 0 {
            PathBuf::from(format!("{stem}.{ext}"))
        } else {
            PathBuf::from(format!("{stem}-{i}.{ext}"))
        }
    };
    (0..u32::MAX)
        .map(name)
        .find(|p| !p.exists())
        .unwrap_or_else(|| name(u32::MAX))
}

/// The render worker: owns the volume and its renderer, renders the newest request, encodes it
/// for the terminal and sends it back.
fn start_renderer(
    volume: Arc<Volume>,
    caps: Caps,
    (events, epoch): (Sender<Event>, u64),
    cancel: Arc<AtomicBool>,
) -> Sender<RenderRequest> {
    let (tx, rx) = channel::<RenderRequest>();
    std::thread::spawn(move || {
        let events = EpochSender { events, epoch };
        let renderer = match Renderer::new(&volume) {
            Ok(r) => r,
            Err(e) => {
                let _ = events.send(Event::Job(JobMsg::Rendered(0, Err(e.to_string()))));
                return;
            }
        };
        while let Some(request) = newest(&rx) {
            cancel.store(false, Ordering::Relaxed);
            let monitor = Monitor::new(Some(&cancel), None);
            let generation = request.generation;
            match render(&renderer, &caps, &request, &monitor) {
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
    });
    tx
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
fn newest(rx: &Receiver<RenderRequest>) -> Option<RenderRequest> {
    let mut request = rx.recv().ok()?;
    while let Ok(newer) = rx.try_recv() {
        request = newer;
    }
    Some(request)
}

fn render(
    renderer: &Renderer,
    caps: &Caps,
    r: &RenderRequest,
    monitor: &Monitor,
) -> anyhow::Result<Box<Rendered>> {
    let look = &r.look;
    let geometry = r.histories.as_ref().map(|h| {
        let stack = h.stack();
        Stack {
            axis: stack.axis(),
            slices: stack.slices(),
            thickness: stack.thickness(),
            offset: stack.offset(),
        }
    });
    // One image pixel per screen pixel, as large as the terminal takes.
    let (width, height) = caps.image_size(r.cells);
    let (width, height) = (width.max(1), height.max(1));
    let (pixmap, caption, window) = match (r.slice, &geometry) {
        (Some(s), Some(stack)) if !r.slabs.is_empty() => {
            let highlight = r.highlight.unwrap_or(0).min(r.slabs.len() - 1);
            let view = SliceView {
                stack,
                slab: (highlight, r.slabs[highlight]),
                request: s,
                size: (width, height),
            };
            let (pixmap, caption, window) = view.draw(renderer, look)?;
            (pixmap, Some(caption), window)
        }
        _ => {
            let layout = match (&r.histories, &geometry) {
                (Some(h), Some(stack)) if !r.slabs.is_empty() => {
                    let nmi = match (&r.nmi, look.gap) {
                        (Some(nmi), _) => Some(nmi.clone()),
                        (None, Gap::Similarity) => Some(h.boundary_nmi(&r.slabs, monitor)?),
                        (None, Gap::Uniform) => None,
                    };
                    Layout::from_slabs(stack, &r.slabs, nmi.as_deref(), look.gap, look.spread)
                }
                _ => Layout::whole(r.axis),
            };
            let params = RenderParams {
                width,
                height,
                mode: look.mode,
                preset: look.preset,
                colormap: look.colormap,
                window: look.window,
                camera: look.camera,
                highlight: r.highlight,
                solo: look.solo,
                outlines: true,
                labels: height >= 120,
                ..RenderParams::default()
            };
            let image = renderer.render(&layout, &params, monitor)?;
            (image.pixmap, None, image.window)
        }
    };
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

/// The slice view: the slice under the cursor, large, with the pointer's cross; beside it the
/// selected slab's faces, its last slice above its first.
struct SliceView<'a> {
    stack: &'a Stack,
    slab: (usize, Slab),
    request: SliceRequest,
    size: (u32, u32),
}

impl SliceView<'_> {
    /// The picture, the readout at the pointer (slice, voxel, world position, value) and the
    /// colour window.
    fn draw(
        &self,
        renderer: &Renderer,
        look: &Look,
    ) -> anyhow::Result<(Pixmap, String, (f32, f32))> {
        let volume = renderer.volume();
        let spacing = volume.spacing();
        let transfer = renderer.transfer(look.colours(), min_spacing(spacing))?;
        let (w, h) = self.size;
        let mut canvas = Pixmap::new(w, h).ok_or_else(|| anyhow::anyhow!("no room for slices"))?;
        canvas.fill(tiny_skia::Color::from_rgba8(12, 12, 18, 255));
        let stack = self.stack;
        let index = self.request.index.min(stack.slices.saturating_sub(1));
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
        let p = self.request.pointer;
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
    let value = volume.voxels()[ijk[0] + dims[0] * (ijk[1] + dims[1] * ijk[2])];
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
    use std::time::Instant;

    use slabscope::partition::Method;
    use slabscope::{AnalysisParams, Scope};

    use super::*;
    use crate::term::Caps;
    use crate::tui::event::Look;

    #[test]
    fn messages_of_a_volume_no_longer_open_are_dropped() {
        let (tx, _rx) = channel();
        let mut jobs = Jobs::new(tx, Caps::blocks(), None, LoadOptions::default());
        let done = |epoch| JobMsg::Epoch(epoch, Box::new(JobMsg::Exported(Ok("x".into()))));
        assert!(matches!(jobs.admit(done(0)), Some(JobMsg::Exported(_))));
        jobs.run(Effect::Open(slabscope::triage::Entry::file("next.nii")));
        assert!(jobs.admit(done(0)).is_none(), "the last volume's");
        assert!(matches!(jobs.admit(done(1)), Some(JobMsg::Exported(_))));
        // The folder's triage rows are for every volume: never dropped.
        let row = slabscope::triage::TriageRow::failed("a", "b".into());
        assert!(jobs.admit(JobMsg::Triaged(0, Box::new(row))).is_some());
    }

    /// Not a test but a measurement: `cargo test --release --bin slabscope preview_timing --
    /// --ignored --nocapture` prints, for the built-in dataset, the time to the first image
    /// after start, and the time and bytes of an image after a step at 1000×600 pixels, per
    /// protocol.
    #[test]
    #[ignore = "a benchmark: prints timings, asserts nothing about them"]
    fn preview_timing() {
        let start = Instant::now();
        let volume = slabscope::builtin_dataset().unwrap();
        let renderer = Renderer::new(&volume).unwrap();
        let cells = (125, 37);
        let sixel = Caps {
            graphics: Graphics::Sixel,
            cell: (8, 16),
            ..Caps::blocks()
        };
        let whole = RenderRequest {
            generation: 1,
            slabs: Vec::new(),
            axis: [0.0, 0.0, 1.0],
            nmi: None,
            histories: None,
            look: Look::default(),
            highlight: None,
            cells,
            slice: None,
        };
        let first = render(&renderer, &sixel, &whole, &Monitor::none()).unwrap();
        println!(
            "first image (load, render, sixel) {:.0} ms after start, {} KB",
            start.elapsed().as_secs_f64() * 1e3,
            first.image.bytes / 1024
        );
        let params = AnalysisParams::default();
        let h = Arc::new(
            Histories::new(
                &volume,
                [0.0, 0.0, 1.0],
                &params.stack(),
                Scope::ALL,
                &Monitor::none(),
            )
            .unwrap(),
        );
        for (name, graphics) in [
            ("sixel", Graphics::Sixel),
            ("kitty", Graphics::Kitty),
            ("iTerm2", Graphics::Iterm),
            ("half-blocks", Graphics::Blocks),
        ] {
            let caps = Caps {
                graphics,
                ..sixel.clone()
            };
            let step = RenderRequest {
                slabs: h.slabs(Method::TopDown, 4),
                histories: Some(Arc::clone(&h)),
                ..whole.clone()
            };
            let mut times = Vec::new();
            let mut bytes = 0;
            for _ in 0..5 {
                let t = Instant::now();
                bytes = render(&renderer, &caps, &step, &Monitor::none())
                    .unwrap()
                    .image
                    .bytes;
                times.push(t.elapsed().as_secs_f64() * 1e3);
            }
            times.sort_by(f64::total_cmp);
            println!(
                "{name:>11}: an image after a step at 1000x592 px in {:.0} ms (median of 5), {} KB",
                times[2],
                bytes / 1024
            );
        }
    }
}
