//! Background work for the TUI: loading, the view search, the histories and exports each on their
//! own thread with a shared cancellation flag, and a render worker that always takes the newest
//! request (a newer one replaces a queued one and cancels the one in flight). Every effect
//! carries the data it needs; nothing here reads the app.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, Sender, channel};

use image::{DynamicImage, RgbaImage};
use ratatui::layout::Size;
use ratatui_image::Resize;
use ratatui_image::picker::Picker;
use slabscope::render::{Gap, Stack};
use slabscope::volume::io::{NrrdEncoding, write_atomic, write_nrrd};
use slabscope::{
    Analysis, AnalysisReport, Error, Histories, Layout, LoadOptions, Monitor, Partition, Progress,
    RenderParams, Renderer, Scope, Volume, label_volume, search,
};

use super::event::{Effect, Event, ExportRequest, Job, JobMsg, RenderRequest};

/// The largest preview render, pixels: terminals rarely show more, and it bounds the time.
const MAX_PREVIEW: (u32, u32) = (1280, 960);

/// Runs effects in the background and reports through the event channel.
pub struct Jobs {
    events: Sender<Event>,
    cancel: Arc<AtomicBool>,
    renders: Option<Sender<RenderRequest>>,
    render_cancel: Arc<AtomicBool>,
    picker: Picker,
    source: Option<PathBuf>,
    load: LoadOptions,
    volume: Option<Arc<Volume>>,
}

impl Jobs {
    /// Jobs reporting to `events`, loading `source` (None: the built-in dataset).
    pub fn new(
        events: Sender<Event>,
        picker: Picker,
        source: Option<PathBuf>,
        load: LoadOptions,
    ) -> Self {
        Self {
            events,
            cancel: Arc::new(AtomicBool::new(false)),
            renders: None,
            render_cancel: Arc::new(AtomicBool::new(false)),
            picker,
            source,
            load,
            volume: None,
        }
    }

    /// Sees a message before the app does: a loaded volume starts the render worker.
    pub fn observe(&mut self, msg: &JobMsg) {
        if let JobMsg::Loaded(Ok((volume, _))) = msg {
            self.volume = Some(Arc::clone(volume));
            self.renders = Some(start_renderer(
                Arc::clone(volume),
                self.picker.clone(),
                self.events.clone(),
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
                        Some(path) => {
                            slabscope::load(path, &load).map(|l| (Arc::new(l.volume), l.notes))
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
        let (events, cancel) = (self.events.clone(), Arc::clone(&self.cancel));
        std::thread::spawn(move || {
            let progress = |p: Progress| {
                let _ = events.send(Event::Job(JobMsg::Progress(job, p)));
            };
            let monitor = Monitor::new(Some(&cancel), Some(&progress));
            let msg = work(&monitor);
            let _ = events.send(Event::Job(msg));
        });
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
        camera: r.look.camera,
        highlight: r.highlight.filter(|&h| h < part.slabs.len()),
        solo: r.look.solo,
        ..RenderParams::default()
    };
    let image = Renderer::new(volume)?.render(&layout, &render, monitor)?;
    write_new(&png, &image.png()?)?;
    let analysis = Analysis {
        views: r.views.clone(),
        partition: part,
    };
    let report = AnalysisReport::new(&r.name, volume, &r.view_params, &analysis)?;
    let text = serde_json::to_string_pretty(&report).map_err(|e| Error::Encode(e.to_string()))?;
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
    picker: Picker,
    events: Sender<Event>,
    cancel: Arc<AtomicBool>,
) -> Sender<RenderRequest> {
    let (tx, rx) = channel::<RenderRequest>();
    std::thread::spawn(move || {
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
            match render(&renderer, &picker, &request, &monitor) {
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
    picker: &Picker,
    r: &RenderRequest,
    monitor: &Monitor,
) -> anyhow::Result<Box<ratatui_image::protocol::Protocol>> {
    let look = &r.look;
    let layout = match &r.histories {
        Some(h) if !r.slabs.is_empty() => {
            let stack = h.stack();
            let nmi = match (&r.nmi, look.gap) {
                (Some(nmi), _) => Some(nmi.clone()),
                (None, Gap::Similarity) => Some(h.boundary_nmi(&r.slabs, monitor)?),
                (None, Gap::Uniform) => None,
            };
            let geometry = Stack {
                axis: stack.axis(),
                slices: stack.slices(),
                thickness: stack.thickness(),
                offset: stack.offset(),
            };
            Layout::from_slabs(&geometry, &r.slabs, nmi.as_deref(), look.gap, look.spread)
        }
        _ => Layout::whole(r.axis),
    };
    // One image pixel per font pixel: the protocol maps pixels to cells by the font size (and
    // half-blocks then average them down to two per cell).
    let (cols, rows) = (u32::from(r.cells.0), u32::from(r.cells.1));
    let font = picker.font_size();
    let (width, height) = (
        (cols * u32::from(font.width)).min(MAX_PREVIEW.0),
        (rows * u32::from(font.height)).min(MAX_PREVIEW.1),
    );
    let params = RenderParams {
        width: width.max(1),
        height: height.max(1),
        mode: look.mode,
        preset: look.preset,
        colormap: look.colormap,
        camera: look.camera,
        highlight: r.highlight,
        solo: look.solo,
        outlines: true,
        labels: height >= 120,
        ..RenderParams::default()
    };
    let image = renderer.render(&layout, &params, monitor)?;
    let rgba = RgbaImage::from_raw(width, height, image.pixmap.data().to_vec())
        .ok_or_else(|| anyhow::anyhow!("render buffer has the wrong size"))?;
    let size = Size::new(r.cells.0, r.cells.1);
    Ok(Box::new(picker.new_protocol(
        DynamicImage::ImageRgba8(rgba),
        size,
        Resize::Fit(None),
    )?))
}
