//! The TUI's state and its one mutator, [`App::update`]: actions in, effects out, no I/O. The app
//! dispatches: each pane owns its state, and the app brings the panes up to date when the
//! partition changes. Here: the state, what the jobs' messages do to it and how the panes are kept
//! in step; the keys are handled in `keys`.

mod folder;
mod gain;
mod keys;
mod lesson;
pub mod tour;
mod upgrade;

use std::sync::Arc;

use slabscope::{AnalysisParams, Progress, Volume};

use super::event::{Effect, ExportRequest, Job, JobMsg, PictureJob, SliceCursor, Task};
use super::panes::curves::{Curves, CurvesPane};
use super::panes::files::FilesPane;
use super::panes::lesson::LessonPane;
use super::panes::preview::PreviewPane;
use super::panes::slabs::{SlabTable, SlabsPane};
use super::panes::status::StatusBar;
use super::panes::views::ViewsPane;
use super::partitioning::Partitioning;
use super::theme::Theme;

/// The panes that take the keyboard's focus.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pane {
    /// A folder's volumes.
    Files,
    /// The viewpoint list.
    Views,
    /// The slab table.
    Slabs,
    /// The NMI and ΔI curves.
    Curves,
    /// The exploded view.
    Preview,
}

impl Pane {
    const ORDER: [Pane; 5] = [
        Pane::Files,
        Pane::Views,
        Pane::Slabs,
        Pane::Curves,
        Pane::Preview,
    ];

    /// The pane `by` from this one, the folder's only when it shows (`folder`).
    fn step(self, by: isize, folder: bool) -> Self {
        let order = if folder {
            &Self::ORDER[..]
        } else {
            &Self::ORDER[1..]
        };
        let i = order.iter().position(|p| *p == self).unwrap_or(0) as isize;
        order[(i + by).rem_euclid(order.len() as isize) as usize]
    }
}

/// What the app knows of the screen it draws on.
#[derive(Clone, Debug, Default)]
pub struct Screen {
    /// Colours.
    pub theme: Theme,
    /// What takes a drawn image away where it is a layer of its own (kitty).
    pub hide: String,
    /// What the user should know about the terminal, such as how to let images through tmux.
    pub note: Option<String>,
    /// How images are drawn, in words.
    pub graphics: &'static str,
}

/// The whole state of the TUI.
pub struct App {
    /// The volume's name.
    pub name: String,
    /// How to analyse it.
    pub params: AnalysisParams,
    /// Colours.
    pub theme: Theme,
    /// The volume.
    pub volume: Task<Arc<Volume>>,
    /// The partition being stepped through.
    pub part: Partitioning,
    /// The focused pane.
    pub focus: Pane,
    /// Whether the help overlay shows.
    pub help: bool,
    /// Whether to leave.
    pub quit: bool,
    /// The viewpoints.
    pub views: ViewsPane,
    /// The slabs.
    pub slabs: SlabsPane,
    /// The curves.
    pub curves: CurvesPane,
    /// The exploded view.
    pub preview: PreviewPane,
    /// The status lines.
    pub status: StatusBar,
    /// An export under way, with its progress.
    export: Task<()>,
    /// A folder's volumes, when the TUI was opened on one.
    pub files: Option<FilesPane>,
    /// The screen, for a fresh start on another volume.
    screen: Screen,
    /// On a large volume, the preview and its upgrade to full resolution.
    pub upgrade: Option<upgrade::Upgrade>,
    /// The lesson: the numbers behind the selected viewpoint or the step.
    pub lesson: LessonPane,
    /// The lesson's ray: its offset from the central one.
    ray: (i64, i64),
    /// The guided tour, when the app runs it.
    pub tour: Option<tour::Tour>,
    /// The pyramid level of the gain ranking shown or under way.
    gain_level: usize,
    /// Whether background triage is held while the open volume's work runs.
    triage_held: bool,
}

impl App {
    /// A fresh app for the volume called `name`; the first effects load it.
    pub fn new(name: String, params: AnalysisParams, screen: Screen) -> (Self, Vec<Effect>) {
        let theme = screen.theme;
        let kept = screen.clone();
        let mut app = Self {
            views: ViewsPane::new(&name, theme),
            slabs: SlabsPane::new(theme),
            curves: CurvesPane::new(theme),
            preview: PreviewPane::new(theme),
            status: StatusBar::new(&params, theme),
            part: Partitioning::new(params.method, params.stop, params.stack()),
            name,
            params,
            theme,
            volume: Task::started("loading"),
            focus: Pane::Views,
            help: false,
            quit: false,
            export: Task::Idle,
            files: None,
            screen: kept,
            upgrade: None,
            lesson: LessonPane::new(theme),
            ray: (0, 0),
            tour: None,
            gain_level: 0,
            triage_held: false,
        };
        app.preview.hide = screen.hide;
        app.preview.graphics = screen.graphics;
        app.status.notice = screen.note;
        (app, vec![Effect::Load])
    }

    /// Every pane afresh for the volume called `name` (the look, the list and the volume's
    /// place in it stay); the effects that load it.
    fn start_afresh(&mut self, name: String) -> Vec<Effect> {
        let (fresh, effects) = Self::new(name, self.params.clone(), self.screen.clone());
        let old = std::mem::replace(self, fresh);
        self.preview.look = old.preview.look;
        self.preview.cells = old.preview.cells;
        self.status.volume = old.status.volume;
        self.files = old.files;
        self.triage_held = old.triage_held;
        // A tour goes on at its page, set again for the new volume.
        self.tour = old.tour.map(|t| tour::Tour {
            applied: false,
            numbers: None,
            best_merge: false,
            ..t
        });
        if self.tour.is_some() {
            // The terminal's note is not the tour's page.
            self.status.notice = None;
        }
        self.sync_focus();
        effects
    }

    /// Starts the histories along `axis`.
    fn analyze(&mut self, axis: [f64; 3]) -> Vec<Effect> {
        let effect = self.part.start(axis, self.first_level());
        self.curves.cursor = 0;
        self.slabs.row = 0;
        self.sync();
        vec![effect]
    }

    /// After the position, the method or the slab count changed: new panes, a new picture.
    fn after_step(&mut self) -> Vec<Effect> {
        if self.part.ready().is_none() {
            return vec![];
        }
        self.status.message = None;
        self.sync();
        self.render()
    }

    fn export(&mut self) -> Vec<Effect> {
        if self.volume.ready().is_none() {
            self.status.message = Some("nothing to export until the volume has loaded".into());
            return vec![];
        }
        let Some(histories) = self.part.ready() else {
            self.status.message = Some("nothing to export yet: the partition is not ready".into());
            return vec![];
        };
        let request = ExportRequest {
            name: self.name.clone(),
            histories: Arc::clone(histories),
            views: self.views.views.ready().cloned(),
            gain: self.views.gain.ready().cloned().map(|g| {
                let by = self.picked_by(&g);
                (g, by)
            }),
            view_params: self.params.view.clone(),
            method: self.part.method,
            position: self.part.position,
            level: self.part.level,
            look: self.preview.look,
            highlight: Some(self.slabs.row),
        };
        self.export = Task::started("exporting");
        self.sync();
        vec![Effect::Export(Box::new(request))]
    }

    /// A render of the current state, when there is somewhere to show it.
    fn render(&mut self) -> Vec<Effect> {
        let level = self.shown_level();
        let Some(volume) = self.shown_volume().or(self.volume.ready()).cloned() else {
            return vec![];
        };
        let (w, h) = self.preview.cells;
        if w < 4 || h < 2 {
            return vec![];
        }
        self.preview.generation += 1;
        let slabs = self.part.slabs().unwrap_or_default();
        let histories = self.part.ready();
        let axis = self.part.axis.unwrap_or_else(|| {
            if volume.dims()[2] > 1 {
                [0.0, 0.0, 1.0]
            } else {
                [0.0, 1.0, 0.0]
            }
        });
        if !matches!(self.preview.image, Task::Ready(_)) {
            self.preview.image = Task::started("rendering");
        }
        let figure = self.figure();
        self.preview.figure = figure.as_ref().map(|(_, title)| title.clone());
        vec![Effect::Render(Box::new(PictureJob {
            figure: figure.map(|(drawing, _)| Box::new(drawing)),
            generation: self.preview.generation,
            level,
            highlight: (!slabs.is_empty()).then_some(self.slabs.row),
            nmi: histories.and_then(|h| h.known_nmi(self.part.method, self.part.position)),
            histories: histories.cloned(),
            slabs,
            axis,
            look: self.preview.look,
            cells: self.preview.cells,
            slice: (self.preview.slices && histories.is_some()).then(|| SliceCursor {
                index: self.curves.cursor,
                pointer: self.preview.pointer.unwrap_or_else(|| centre(&volume)),
            }),
        }))]
    }

    fn on_job(&mut self, msg: JobMsg) -> Vec<Effect> {
        match msg {
            JobMsg::Progress(job, p) => {
                self.on_progress(job, p);
                vec![]
            }
            JobMsg::Loaded(Ok((volume, notes))) => self.on_loaded(volume, &notes),
            JobMsg::Loaded(Err(e)) => {
                self.status.message = Some(format!("{e} (q quits)"));
                self.views.idle = format!("cannot load the volume: {e}");
                self.volume = Task::Failed(e);
                self.sync_status();
                vec![]
            }
            JobMsg::Preview(volume, notes) => self.on_preview(&volume, &notes),
            JobMsg::Coarse(volume) => {
                if let Some(r) = self.upgrade.as_mut() {
                    r.coarse = Some(volume);
                }
                vec![]
            }
            JobMsg::Views(level, result) => self.on_views(level, result),
            JobMsg::Gain(level, result) => self.on_gain(level, result),
            JobMsg::Lesson(generation, result) => {
                self.on_lesson(generation, result);
                vec![]
            }
            JobMsg::Analysis(generation, level, result) => {
                self.on_histories(generation, level, result)
            }
            JobMsg::Rendered(generation, result) => {
                if generation == self.preview.generation {
                    self.preview.image = match result {
                        Ok(r) => {
                            self.preview.caption = r.caption;
                            self.preview.window = r.window.or(self.preview.window);
                            Task::Ready(Box::new(r.image))
                        }
                        Err(e) => Task::Failed(e),
                    };
                }
                vec![]
            }
            // The jobs unwrap these before the app sees them.
            JobMsg::Epoch(..) => vec![],
            JobMsg::Triaged(i, row) => {
                if let Some(files) = self.files.as_mut() {
                    files.fill(i, *row);
                }
                vec![]
            }
            JobMsg::Thumbnail(i, image) => {
                if let Some(slot) = self.files.as_mut().and_then(|f| f.thumbnails.get_mut(i)) {
                    *slot = Some(*image);
                }
                vec![]
            }
            JobMsg::Manifest(path, written) => self.on_manifest(&path, written),
            JobMsg::Exported(result) => {
                self.export = Task::Idle;
                self.status.message = Some(match result {
                    Ok(m) => m,
                    Err(e) => format!("export failed: {e}"),
                });
                self.sync();
                vec![]
            }
        }
    }

    /// A volume loaded: the view search starts, and the partition along the axis asked for;
    /// or the file's preview level shows, and is upgraded.
    fn on_loaded(&mut self, volume: Arc<Volume>, notes: &[String]) -> Vec<Effect> {
        if self.upgrade.as_ref().is_some_and(|r| r.from_file) {
            return self.adopt(volume, notes);
        }
        self.status.message = notes.first().cloned();
        if let Some(heavy) = self.params.heavy_work(volume.dims(), volume.spacing()) {
            self.status.message = Some(format!("{heavy}: it may take long; Esc cancels it"));
        }
        let level = crate::tui::preview_level(&volume);
        self.upgrade = (level > 0).then(|| upgrade::Upgrade::new(level, volume.dims()));
        self.volume = Task::Ready(Arc::clone(&volume));
        self.begin(&volume, level)
    }

    /// The first jobs on `volume`, which is pyramid level `level` of what is open: the view
    /// search, the gain ranking when it picks the axis, the histories along an axis asked for,
    /// and a picture.
    fn begin(&mut self, volume: &Volume, level: usize) -> Vec<Effect> {
        let chosen = self
            .params
            .axis
            .resolve(volume.transform(), volume.spacing());
        self.views.views = Task::started("view search");
        let mut effects = vec![Effect::SearchViews(self.params.view.clone(), level)];
        if self.params.ranks_by_gain() {
            effects.extend(self.start_gain());
        }
        match chosen {
            Ok(Some(axis)) => effects.extend(self.analyze(axis.direction())),
            Ok(None) => {}
            Err(e) => self.status.message = Some(e.to_string()),
        }
        self.sync();
        effects.extend(self.render());
        effects
    }

    fn on_progress(&mut self, job: Job, p: Progress) {
        match job {
            Job::Load if self.volume.running() => self.volume = Task::Running(p),
            Job::Views(0) if self.upgrade.is_some() => self.upgrade_progress(p),
            Job::Views(_) if self.views.views.running() => self.views.views = Task::Running(p),
            Job::Analysis(level) => self.part.progress(p, level),
            Job::Export if self.export.running() => self.export = Task::Running(p),
            Job::Gain if self.views.gain.running() => self.views.gain = Task::Running(p),
            Job::Lesson if self.lesson.lesson.running() => self.lesson.lesson = Task::Running(p),
            _ => return,
        }
        self.sync_status();
        if matches!(job, Job::Analysis(_)) {
            self.sync();
        }
    }

    /// Brings every pane up to date with the partition.
    fn sync(&mut self) {
        let part = &self.part;
        match &part.histories {
            Task::Ready(h) => {
                let table = SlabTable::new(h, part.method, part.position);
                let boundaries = table.info.iter().skip(1).map(|s| s.slices.0).collect();
                self.slabs.row = self.slabs.row.min(table.info.len().saturating_sub(1));
                self.slabs.table = Task::Ready(table);
                self.curves.curves = Task::Ready(Curves {
                    histories: Arc::clone(h),
                    boundaries,
                });
            }
            other => {
                self.slabs.table = pending(other);
                self.curves.curves = pending(other);
            }
        }
        self.views.current = part.axis;
        self.sync_status();
        self.sync_focus();
    }

    /// The status lines: method, position, explanation and the jobs under way.
    fn sync_status(&mut self) {
        let s = &mut self.status;
        s.method = self.part.method;
        s.position = self.part.position_text();
        s.explanation = self.part.explain();
        s.jobs.clear();
        for (job, load) in [
            ("views", self.views.views.status()),
            ("gain", self.views.gain.status()),
            ("histories", self.part.histories.status()),
            ("export", self.export.status()),
        ] {
            if let Task::Running(p) = load {
                s.jobs.push((job, p));
            }
        }
        let (label, gauges) = self.resolution_status();
        self.status.resolution = label;
        for p in gauges {
            self.status.jobs.push((self.final_words(), p));
        }
    }

    fn sync_focus(&mut self) {
        self.views.focused = self.focus == Pane::Views;
        self.slabs.focused = self.focus == Pane::Slabs;
        self.curves.focused = self.focus == Pane::Curves;
        self.preview.focused = self.focus == Pane::Preview;
        if let Some(files) = self.files.as_mut() {
            files.focused = self.focus == Pane::Files;
            files.covered = self.help;
        }
        // A tour page's figure or worked example stands in the picture's place; a figure drawn
        // through the image protocol is the picture.
        let board = self
            .tour
            .as_ref()
            .is_some_and(|t| t.current().board.is_some());
        let drawn = board && self.figure_as_image();
        self.preview.covered = self.help || self.lesson.open || (board && !drawn);
    }

    /// Whether the tour's page shows one of the paper's figures as the preview's picture: the
    /// terminal draws images (not half-blocks), and the figure's data is in.
    pub fn figure_as_image(&self) -> bool {
        self.preview.draws_images() && self.figure().is_some()
    }

    /// The board the tour's page shows in the exploded view's place, if any.
    pub fn board(&self) -> Option<crate::tui::panes::board::BoardPane> {
        let board = self.tour.as_ref()?.current().board?;
        let best = self.views.views.ready().and_then(|s| {
            let best = s.views.first()?;
            Some((best.axis, s.params.level))
        });
        let size = self.volume.ready().map(|v| {
            let (d, s) = (v.dims(), v.spacing());
            std::array::from_fn(|k| d[k] as f64 * s[k])
        });
        Some(crate::tui::panes::board::BoardPane {
            board,
            best,
            size,
            theme: self.theme,
        })
    }

    /// The tour page's figure for the image protocol, and its title, when the terminal draws
    /// images and the figure's data is in.
    fn figure(&self) -> Option<(slabscope::explain::figure::Drawing, String)> {
        if !self.preview.draws_images() {
            return None;
        }
        let board = self
            .board()
            .filter(crate::tui::panes::board::BoardPane::is_figure)?;
        let (drawing, legend) = board.drawing(u16::MAX)?;
        Some((drawing, format!("{}— {legend} ", board.title())))
    }
}

/// The state of something not ready, for a pane that shows its gauge or error.
fn pending<T, U>(load: &Task<T>) -> Task<U> {
    match load {
        Task::Running(p) => Task::Running(*p),
        Task::Failed(e) => Task::Failed(e.clone()),
        Task::Idle | Task::Ready(_) => Task::Idle,
    }
}

/// The centre of `volume`, in mm from voxel (0, 0, 0).
fn centre(volume: &Volume) -> [f64; 3] {
    let (dims, spacing) = (volume.dims(), volume.spacing());
    std::array::from_fn(|m| (dims[m] - 1) as f64 * spacing[m] / 2.0)
}
