//! Background work for the TUI: loading, the view search, the histories and exports each on their
//! own thread with a shared cancellation flag, and a render worker that always takes the newest
//! request (a newer one replaces a queued one and cancels the one in flight). Every effect
//! carries the data it needs; nothing here reads the app.

mod export;
mod gate;
mod worker;

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::Sender;
use std::time::Duration;

use slabscope::budget::GLANCE_VOXELS;
use slabscope::partition::StackParams;
use slabscope::request::{AnalysisRequest, Level};
use slabscope::view::ViewParams;
use slabscope::volume::Resolution;
use slabscope::{AnalysisParams, LoadOptions, Monitor, Progress, Volume};

use super::event::{Effect, Event, Job, JobMsg, PictureJob};
use super::preview_level;
use crate::term::Caps;
use export::export;
pub use gate::Gate;
use worker::start_renderer;

/// The tile of the thumbnails background triage draws, pixels: the exploded view this square,
/// the three mid slices beside it (as in `triage --sheet`).
pub const THUMBNAIL_TILE: u32 = 32;

/// Runs effects in the background and reports through the event channel.
pub struct Jobs {
    events: Sender<Event>,
    cancel: Arc<AtomicBool>,
    /// The load's own cancellation: raised when another volume is opened and at quitting, not
    /// by Escape (which stops the work on a volume, not its reading).
    load_cancel: Arc<AtomicBool>,
    renders: Option<Sender<PictureJob>>,
    render_cancel: Arc<AtomicBool>,
    caps: Caps,
    source: Option<slabscope::triage::Entry>,
    load: LoadOptions,
    open: Open,
    /// Which volume is open: one more at each [`Effect::Open`].
    epoch: u64,
    /// The test hook's wait before a preview is upgraded to full resolution.
    full_delay: Duration,
    /// Holds background triage while the open volume's work runs.
    triage_gate: Gate,
    /// Holds the reading of a remote store's level 0 until the first picture of its preview is
    /// drawn (at most [`FIRST_PICTURE_WAIT`]), so that the first picture fetches no chunk of it.
    first_picture: Gate,
}

/// The longest a remote store's level 0 waits for the first picture of its preview (a picture
/// the app never asks, in a terminal too small for it, must not hold the load back for ever).
const FIRST_PICTURE_WAIT: Duration = Duration::from_secs(5);

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
            load_cancel: Arc::new(AtomicBool::new(false)),
            renders: None,
            render_cancel: Arc::new(AtomicBool::new(false)),
            caps,
            source,
            load,
            open: Open::default(),
            epoch: 0,
            full_delay: std::env::var("SLABSCOPE_TEST_FULL_DELAY_MS")
                .ok()
                .and_then(|ms| ms.parse().ok())
                .map_or(Duration::ZERO, Duration::from_millis),
            triage_gate: Gate::default(),
            first_picture: Gate::default(),
        }
    }

    /// Sees a message before the app does: a loaded volume, or the file's preview level read
    /// before it, (re)starts the render worker.
    fn observe(&mut self, msg: &JobMsg) {
        match msg {
            JobMsg::Loaded(Ok((volume, _))) => self.open.full = Some(Arc::clone(volume)),
            JobMsg::Preview(volume, _) => self.open.preview = Some(Arc::clone(volume)),
            // The first picture drawn (or failed): a remote store's level 0 may be read.
            JobMsg::Rendered(..) => {
                self.first_picture.hold(false);
                return;
            }
            _ => return,
        }
        self.start_renderer();
    }

    fn start_renderer(&mut self) {
        self.renders = Some(start_renderer(
            self.open.clone(),
            self.caps.clone(),
            (self.events.clone(), self.epoch),
            Arc::clone(&self.render_cancel),
        ));
    }

    /// Carries out `effect`.
    pub fn run(&mut self, effect: Effect) {
        match effect {
            Effect::Load => {
                let (source, mut load) = (self.source.clone(), self.load.clone());
                load.cancel = slabscope::Cancel::new(Arc::clone(&self.load_cancel));
                let request = self.request(AnalysisParams::default());
                // A new gate each load: a load before it, stopped, is let through.
                self.first_picture.hold(false);
                self.first_picture = Gate::default();
                let remote = source
                    .as_ref()
                    .is_some_and(|e| slabscope::formats::remote::is_url(&e.path));
                self.first_picture.hold(remote);
                let first_picture = self.first_picture.clone();
                self.spawn(Job::Load, move |_, send| {
                    let wait = || {
                        first_picture.wait_at_most(FIRST_PICTURE_WAIT);
                    };
                    load_volume(source.as_ref(), &load, &request, &(send, &wait))
                });
            }
            effect @ (Effect::SearchViews(..) | Effect::Analyze(..) | Effect::RankGain(..)) => {
                self.analyse(effect);
            }
            Effect::Lesson(request) => {
                self.spawn(Job::Lesson, move |monitor, _| {
                    let result = request.compute(monitor).map(Box::new);
                    JobMsg::Lesson(request.generation, result)
                });
            }
            Effect::Open(path) => self.open_next(path),
            Effect::Forget => self.forget(),
            Effect::Triage(paths, params) => self.triage(paths, *params),
            Effect::PauseTriage(on) => self.triage_gate.hold(on),
            Effect::WriteManifest(path, entries, force) => self.write(path, &entries, force),
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
                if let Some(volume) = self.open.full.clone() {
                    let max_memory = self.load.max_memory;
                    self.spawn(Job::Export, move |monitor, _| {
                        JobMsg::Exported(
                            export(&volume, &request, max_memory, monitor)
                                .map_err(|e| e.to_string()),
                        )
                    });
                }
            }
            Effect::Quit => self.load_cancel.store(true, Ordering::Relaxed),
        }
    }

    /// Carries out an effect of the analysis (the view search, the histories, the gain
    /// ranking) as a step of the library's request on the pyramid level it names.
    fn analyse(&self, effect: Effect) {
        match effect {
            Effect::SearchViews(view, level) => {
                let Some(source) = self.open.level(level) else {
                    return;
                };
                let delay = self.full_delay(level);
                let request = self.request(AnalysisParams {
                    view,
                    ..AnalysisParams::default()
                });
                self.spawn(Job::Views(level), move |monitor, send| {
                    let on = source.get();
                    if level > 0 {
                        send(JobMsg::Coarse(Arc::clone(&on)));
                    }
                    let result = wait(delay, monitor).and_then(|()| request.on(on).views(monitor));
                    JobMsg::Views(level, result.map(Box::new).map_err(|e| e.to_string()))
                });
            }
            Effect::Analyze(generation, axis, stack, level) => {
                let Some(source) = self.open.level(level) else {
                    return;
                };
                let delay = self.full_delay(level);
                let request = self.request(cutting(&stack));
                self.spawn(Job::Analysis(level), move |monitor, _| {
                    let on = source.get();
                    let result =
                        wait(delay, monitor).and_then(|()| request.on(on).histories(axis, monitor));
                    let result = result.map(Arc::new).map_err(|e| e.to_string());
                    JobMsg::Analysis(generation, level, result)
                });
            }
            Effect::RankGain(params, level) => {
                let Some(source) = self.open.level(level) else {
                    return;
                };
                let request = self.request(*params);
                self.spawn(Job::Gain, move |monitor, _| {
                    let result = request.on(source.get()).gain(monitor);
                    JobMsg::Gain(level, result.map(Box::new).map_err(|e| e.to_string()))
                });
            }
            _ => {}
        }
    }

    /// The library's request for an analysis by `params` within the memory budget, at the level
    /// a picture is drawn from: the volume worked on is the one its plan gives when it loads
    /// ([`load_volume`]), and the jobs' work runs on that volume or its glance as it is
    /// ([`AnalysisRequest::on`]).
    fn request(&self, params: AnalysisParams) -> AnalysisRequest {
        AnalysisRequest {
            level: Level::Picture,
            ..AnalysisRequest::new(params, self.load.max_memory)
        }
    }

    /// Writes the manifest of `entries` (a small file: at once) and says how that went.
    fn write(&self, path: std::path::PathBuf, entries: &[slabscope::triage::Entry], force: bool) {
        let written = write_manifest(&path, entries, force);
        let _ = self
            .events
            .send(Event::Job(JobMsg::Manifest(path, written)));
    }

    /// The next volume: its own load, views, histories and renders; the last one's load stops,
    /// and what the jobs of the last one still send is dropped.
    fn open_next(&mut self, path: slabscope::triage::Entry) {
        self.load_cancel.store(true, Ordering::Relaxed);
        // A load waiting for its first picture goes on to find itself stopped.
        self.first_picture.hold(false);
        self.load_cancel = Arc::new(AtomicBool::new(false));
        self.epoch += 1;
        self.source = Some(path);
        self.open = Open::default();
        self.renders = None;
    }

    /// The file's preview level dropped, and what the jobs started before still send: the app
    /// starts afresh on the volume loaded.
    fn forget(&mut self) {
        self.epoch += 1;
        self.open.preview = None;
        if self.open.full.is_some() {
            self.start_renderer();
        }
    }

    /// Triages `paths` on a thread of its own, one row at a time to the folder's list, until
    /// they are done or the app has gone.
    fn triage(&self, paths: Vec<slabscope::triage::Entry>, params: AnalysisParams) {
        let (events, load) = (self.events.clone(), self.load.clone());
        let gate = self.triage_gate.clone();
        std::thread::spawn(move || {
            let how = slabscope::triage::TriagePlan {
                load,
                params,
                timeout: std::time::Duration::from_secs(60),
                fast: true,
                tile: Some(THUMBNAIL_TILE),
            };
            for (i, entry) in paths.iter().enumerate() {
                // The open volume's work first: its view search, histories and picture.
                gate.wait();
                // The list names the file: its errors need not.
                let describe = |e: slabscope::Error| e.within(&entry.path);
                let looked = slabscope::triage::look(entry, &how, &|_| {}, &describe);
                let thumbnail = looked.cell.and_then(|cell| {
                    let (w, h) = (cell.width(), cell.height());
                    image::RgbaImage::from_raw(w, h, cell.data().to_vec())
                });
                let row = JobMsg::Triaged(i, Box::new(looked.row));
                if events.send(Event::Job(row)).is_err() {
                    break;
                }
                if let Some(t) = thumbnail {
                    let _ = events.send(Event::Job(JobMsg::Thumbnail(i, Box::new(t))));
                }
            }
        });
    }

    /// Runs `work` on its own thread with a monitor that reports `job`'s progress and a way to
    /// send messages before its last.
    fn spawn(
        &self,
        job: Job,
        work: impl FnOnce(&Monitor, &dyn Fn(JobMsg)) -> JobMsg + Send + 'static,
    ) {
        let (events, cancel, epoch) = (self.events.clone(), Arc::clone(&self.cancel), self.epoch);
        std::thread::spawn(move || {
            let send = |msg: JobMsg| {
                let _ = events.send(Event::Job(JobMsg::Epoch(epoch, Box::new(msg))));
            };
            let progress = |p: Progress| send(JobMsg::Progress(job, p));
            let monitor = Monitor::new(Some(&cancel), Some(&progress));
            send(work(&monitor, &send));
        });
    }

    /// How long a full-resolution job on `volume` waits before it starts: nothing, but with the
    /// test hook `SLABSCOPE_TEST_FULL_DELAY_MS`, which holds back the jobs that upgrade a preview
    /// so that a test sees the preview first.
    fn full_delay(&self, level: usize) -> Duration {
        match (level, self.open.full.as_deref().map(preview_level)) {
            (0, Some(1..)) => self.full_delay,
            _ => Duration::ZERO,
        }
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

/// Writes `entries` as a manifest (the escaped form, each path made absolute so that it reads
/// from any folder) to `path`: never over a file that exists unless `force`, never over
/// anything but a regular file.
pub(super) fn write_manifest(
    path: &std::path::Path,
    entries: &[slabscope::triage::Entry],
    force: bool,
) -> super::event::Written {
    use std::io::Write;

    use super::event::Written;
    let absolute: Vec<slabscope::triage::Entry> = entries
        .iter()
        .map(|e| slabscope::triage::Entry {
            path: std::path::absolute(&e.path).unwrap_or_else(|_| e.path.clone()),
            ..e.clone()
        })
        .collect();
    let mut text = slabscope::triage::manifest_lines(&absolute)
        .collect::<Vec<_>>()
        .join("\n");
    text.push('\n');
    match slabscope::formats::write_atomic(path, force, |mut f| f.write_all(text.as_bytes())) {
        Ok(()) => Written::Done(entries.len()),
        Err(slabscope::Error::Exists { .. }) => Written::Exists,
        Err(e) => Written::Failed(e.to_string()),
    }
}

/// The volume the jobs work on: level 0 once loaded, and the pyramid level the file holds that
/// was read before it (an OME-Zarr store's preview).
#[derive(Clone, Default)]
pub(super) struct Open {
    full: Option<Arc<Volume>>,
    preview: Option<Arc<Volume>>,
}

impl Open {
    /// Where pyramid level `level` comes from: the file's preview where it is that level, else
    /// level 0 once loaded.
    pub(super) fn level(&self, level: usize) -> Option<Source> {
        match (&self.preview, &self.full) {
            (Some(p), _) if p.level().index == level => Some(Source::Held(Arc::clone(p))),
            (_, Some(full)) => Some(Source::Coarser(Arc::clone(full), level)),
            _ => None,
        }
    }

    /// Level 0, once loaded.
    pub(super) fn full(&self) -> Option<&Arc<Volume>> {
        self.full.as_ref()
    }
}

/// Where a job's pyramid level comes from.
pub(super) enum Source {
    /// A level held as it is.
    Held(Arc<Volume>),
    /// A level of this volume, read or built when first asked for.
    Coarser(Arc<Volume>, usize),
}

impl Source {
    /// The level (building it may take long: on a job's thread).
    pub(super) fn get(self) -> Arc<Volume> {
        match self {
            Self::Held(v) => v,
            Self::Coarser(v, k) => v.coarser(k),
        }
    }
}

/// Waits `delay` unless cancelled first.
fn wait(delay: Duration, monitor: &Monitor) -> slabscope::Result<()> {
    let end = std::time::Instant::now() + delay;
    while std::time::Instant::now() < end {
        monitor.check()?;
        std::thread::sleep(Duration::from_millis(10));
    }
    monitor.check()
}

/// An analysis that cuts its slices as `stack` says: the histories' request.
fn cutting(stack: &StackParams) -> AnalysisParams {
    AnalysisParams {
        view: ViewParams {
            sampling: stack.sampling,
            ..ViewParams::default()
        },
        background: stack.background,
        ..AnalysisParams::default()
    }
}

/// Loads `source` (None: the built-in dataset) with `load`, a series in `source` taking the
/// place of the options', and plans `request` on it: the volume worked on is the level its plan
/// gives. A coarse pyramid level the file holds is sent first, as a preview (by `send`, the
/// first of `to`), and level 0 read once `to`'s second returns (for a remote store, when the
/// preview's first picture is drawn); where level 0's analysis would not fit the memory budget,
/// the coarsest of the file's datasets that serves the level that fits is read instead, never
/// level 0 ([`slabscope::budget::unread_level_within`]).
fn load_volume(
    source: Option<&slabscope::triage::Entry>,
    load: &LoadOptions,
    request: &AnalysisRequest,
    to: &(&dyn Fn(JobMsg), &dyn Fn()),
) -> JobMsg {
    let (send, first_picture) = *to;
    let loaded = match source {
        Some(entry) => {
            let load = entry.options(load);
            // A preview that cannot be read is no error: level 0's load says what is wrong.
            let preview = slabscope::formats::load_preview(&entry.path, &load, GLANCE_VOXELS);
            let mut beyond = None;
            if let Ok(Some(p)) = preview {
                beyond = slabscope::budget::unread_level_within(&p.volume, load.max_memory);
                send(JobMsg::Preview(Arc::new(p.volume), p.notes));
                first_picture();
            }
            // Level 0 beyond the budget: the store's dataset that serves the level that fits,
            // level 0 never read.
            let served = beyond
                .map(|k| slabscope::formats::load_serving(&entry.path, &load, Resolution::Level(k)))
                .transpose()
                .map(Option::flatten);
            match served {
                Ok(Some(loaded)) => worked_on(loaded, request),
                Ok(None) => slabscope::load(&entry.path, &load).and_then(|l| worked_on(l, request)),
                Err(e) => Err(e),
            }
        }
        None => slabscope::builtin_dataset().map(|v| (Arc::new(v), Vec::new())),
    };
    JobMsg::Loaded(loaded.map_err(|e| e.to_string()))
}

/// The volume the TUI works on: the level `request`'s plan partitions on `loaded`'s (itself, or
/// beyond the memory budget the finest pyramid level whose analysis fits, said in a note).
fn worked_on(
    loaded: slabscope::formats::Loaded,
    request: &AnalysisRequest,
) -> slabscope::Result<(Arc<Volume>, Vec<String>)> {
    let plan = request.plan(&loaded.volume)?.plan;
    let mut notes = loaded.notes;
    notes.extend(plan.note);
    Ok((plan.partition, notes))
}

#[cfg(test)]
mod tests;
