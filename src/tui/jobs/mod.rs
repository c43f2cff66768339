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

use slabscope::budget::{Budget, GLANCE_VOXELS, Purpose};
use slabscope::{AnalysisParams, Histories, LoadOptions, Monitor, Progress, Scope, Volume, search};

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
        }
    }

    /// Sees a message before the app does: a loaded volume, or the file's preview level read
    /// before it, (re)starts the render worker.
    fn observe(&mut self, msg: &JobMsg) {
        match msg {
            JobMsg::Loaded(Ok((volume, _))) => self.open.full = Some(Arc::clone(volume)),
            JobMsg::Preview(volume, _) => self.open.preview = Some(Arc::clone(volume)),
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
                self.spawn(Job::Load, move |_, send| {
                    load_volume(source.as_ref(), &load, send)
                });
            }
            Effect::SearchViews(params, level) => {
                let Some(source) = self.open.level(level) else {
                    return;
                };
                let delay = self.full_delay(level);
                self.spawn(Job::Views(level), move |monitor, send| {
                    let on = source.get();
                    if level > 0 {
                        send(JobMsg::Coarse(Arc::clone(&on)));
                    }
                    let result = wait(delay, monitor).and_then(|()| search(&on, &params, monitor));
                    JobMsg::Views(level, result.map(Box::new).map_err(|e| e.to_string()))
                });
            }
            Effect::Analyze(generation, axis, params, level) => {
                let Some(source) = self.open.level(level) else {
                    return;
                };
                let delay = self.full_delay(level);
                self.spawn(Job::Analysis(level), move |monitor, _| {
                    let on = source.get();
                    let result = wait(delay, monitor)
                        .and_then(|()| Histories::new(&on, axis, &params, Scope::ALL, monitor));
                    let result = result.map(Arc::new).map_err(|e| e.to_string());
                    JobMsg::Analysis(generation, level, result)
                });
            }
            Effect::RankGain(params, level) => {
                let Some(source) = self.open.level(level) else {
                    return;
                };
                self.spawn(Job::Gain, move |monitor, _| {
                    let on = source.get();
                    let result = slabscope::analysis::rank_by_gain(&on, &params, monitor);
                    JobMsg::Gain(level, result.map(Box::new).map_err(|e| e.to_string()))
                });
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
                    self.spawn(Job::Export, move |monitor, _| {
                        JobMsg::Exported(
                            export(&volume, &request, monitor).map_err(|e| e.to_string()),
                        )
                    });
                }
            }
            Effect::Quit => self.load_cancel.store(true, Ordering::Relaxed),
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
                let prefix = format!("{}: ", slabscope::error::shown(&entry.path));
                let describe = |e: slabscope::Error| {
                    let m = e.to_string();
                    m.strip_prefix(&prefix).map_or(m.clone(), str::to_string)
                };
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

/// Loads `source` (None: the built-in dataset) with `load`, a series in `source` taking the
/// place of the options'. A coarse pyramid level the file holds is sent first, as a preview.
fn load_volume(
    source: Option<&slabscope::triage::Entry>,
    load: &LoadOptions,
    send: &dyn Fn(JobMsg),
) -> JobMsg {
    let loaded = match source {
        Some(entry) => {
            let load = entry.options(load);
            // A preview that cannot be read is no error: level 0's load says what is wrong.
            let preview = slabscope::formats::load_preview(&entry.path, &load, GLANCE_VOXELS);
            if let Ok(Some(p)) = preview {
                send(JobMsg::Preview(Arc::new(p.volume), p.notes));
            }
            let max_memory = load.max_memory;
            slabscope::load(&entry.path, &load).and_then(|l| within_memory(l, max_memory))
        }
        None => slabscope::builtin_dataset().map(|v| (Arc::new(v), Vec::new())),
    };
    JobMsg::Loaded(loaded.map_err(|e| e.to_string()))
}

/// The volume the TUI works on: `loaded`'s, or beyond the memory budget the finest pyramid level
/// whose analysis fits, said in a note.
fn within_memory(
    loaded: slabscope::formats::Loaded,
    max_memory: u64,
) -> slabscope::Result<(Arc<Volume>, Vec<String>)> {
    let plan = Budget::new(max_memory).plan(&loaded.volume, Purpose::Picture)?;
    let mut notes = loaded.notes;
    notes.extend(plan.note);
    Ok((plan.partition, notes))
}

#[cfg(test)]
mod tests {
    use std::sync::mpsc::channel;
    use std::time::Instant;

    use slabscope::partition::Method;
    use slabscope::{AnalysisParams, Renderer, Scope};

    use super::worker::render;
    use super::*;
    use crate::term::{Caps, Graphics};
    use crate::tui::event::PictureSettings;

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

    /// Opening another volume stops the load under way (a Zarr store of 64,000 absent chunks:
    /// seconds of reading), which ends cancelled rather than reading on.
    #[test]
    fn opening_another_volume_stops_the_load_under_way() {
        let dir = tempfile::tempdir().unwrap();
        let store = dir.path().join("slow.zarr");
        std::fs::create_dir(&store).unwrap();
        let meta = r#"{"zarr_format": 3, "node_type": "array", "shape": [320, 320, 320],
            "data_type": "uint8", "fill_value": 0,
            "chunk_grid": {"name": "regular", "configuration": {"chunk_shape": [8, 8, 8]}},
            "chunk_key_encoding": {"name": "default", "configuration": {"separator": "/"}},
            "codecs": [{"name": "bytes", "configuration": {"endian": "little"}}]}"#;
        std::fs::write(store.join("zarr.json"), meta).unwrap();
        let (tx, rx) = channel();
        let entry = slabscope::triage::Entry::file(&store);
        let mut jobs = Jobs::new(tx, Caps::blocks(), Some(entry), LoadOptions::default());
        jobs.run(Effect::Load);
        jobs.run(Effect::Open(slabscope::triage::Entry::file("next.nii")));
        match rx.recv().unwrap() {
            Event::Job(JobMsg::Epoch(0, msg)) => match *msg {
                JobMsg::Loaded(Err(e)) => assert_eq!(e, slabscope::Error::Cancelled.to_string()),
                _ => panic!("not the load's end"),
            },
            _ => panic!("not the first volume's message"),
        }
    }

    #[test]
    fn background_triage_waits_while_the_open_volume_works() {
        let (tx, rx) = channel();
        let mut jobs = Jobs::new(tx, Caps::blocks(), None, LoadOptions::default());
        jobs.run(Effect::PauseTriage(true));
        let unreadable = slabscope::triage::Entry::failed("gone.nii", "cannot be read");
        let params = Box::new(AnalysisParams::default());
        jobs.run(Effect::Triage(vec![unreadable], params));
        // Until the triage thread waits at the gate (no clock: it gets there or the test hangs).
        while jobs.triage_gate.waiting() == 0 {
            std::thread::yield_now();
        }
        assert!(rx.try_recv().is_err(), "held: no row");
        jobs.run(Effect::PauseTriage(false));
        match rx.recv().unwrap() {
            Event::Job(JobMsg::Triaged(0, row)) => {
                assert_eq!(row.error.as_deref(), Some("cannot be read"));
            }
            _ => panic!("not a row"),
        }
    }

    #[test]
    fn a_file_preview_serves_its_level_until_forgotten() {
        let (tx, _rx) = channel();
        let mut jobs = Jobs::new(tx, Caps::blocks(), None, LoadOptions::default());
        assert!(jobs.open.level(1).is_none(), "nothing read yet");
        let full = Arc::new(slabscope::volume::phantom::body([8, 8, 8], 1).unwrap());
        let coarse = full.coarser(1);
        jobs.observe(&JobMsg::Preview(Arc::clone(&coarse), vec![]));
        assert!(matches!(jobs.open.level(1), Some(Source::Held(v)) if Arc::ptr_eq(&v, &coarse)));
        assert!(jobs.open.level(0).is_none() && jobs.open.level(2).is_none());
        jobs.observe(&JobMsg::Loaded(Ok((Arc::clone(&full), vec![]))));
        assert!(
            matches!(jobs.open.level(1), Some(Source::Held(_))),
            "kept for level 1"
        );
        assert!(matches!(jobs.open.level(2), Some(Source::Coarser(_, 2))));
        // Forgotten: level 1 comes from level 0, and what the jobs sent before is dropped.
        let done = |epoch| JobMsg::Epoch(epoch, Box::new(JobMsg::Exported(Ok("x".into()))));
        jobs.run(Effect::Forget);
        assert!(matches!(jobs.open.level(1), Some(Source::Coarser(_, 1))));
        assert!(jobs.admit(done(0)).is_none());
        assert!(jobs.admit(done(1)).is_some());
        assert_eq!(jobs.open.level(1).unwrap().get().dims(), coarse.dims());
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
        let whole = PictureJob {
            generation: 1,
            level: 0,
            slabs: Vec::new(),
            axis: [0.0, 0.0, 1.0],
            nmi: None,
            histories: None,
            look: PictureSettings::default(),
            highlight: None,
            cells,
            slice: None,
            figure: None,
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
            let step = PictureJob {
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
