//! The TUI's state and its one mutator, [`App::update`]: actions in, effects out, no I/O.

use std::sync::Arc;

use ratatui_image::protocol::Protocol;
use slabscope::Volume;
use slabscope::partition::{Method, StackParams};
use slabscope::render::{CameraParams, Colormap, Gap, Mode, Preset};
use slabscope::view::ViewSearch;

use super::analysis::Analysis;

/// Something computed in the background: not asked for yet, under way, done, or failed.
pub enum Load<T> {
    /// Not asked for.
    Idle,
    /// Under way, with the fraction done.
    Running(f64),
    /// Done.
    Ready(T),
    /// Failed, with the message.
    Failed(String),
}

impl<T> Load<T> {
    /// The value, when ready.
    pub fn ready(&self) -> Option<&T> {
        match self {
            Self::Ready(v) => Some(v),
            _ => None,
        }
    }

    /// Whether it is under way.
    pub fn running(&self) -> bool {
        matches!(self, Self::Running(_))
    }
}

/// The panes that take the keyboard's focus.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pane {
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
    const ORDER: [Pane; 4] = [Pane::Views, Pane::Slabs, Pane::Curves, Pane::Preview];

    fn step(self, by: isize) -> Self {
        let i = Self::ORDER.iter().position(|p| *p == self).unwrap_or(0) as isize;
        Self::ORDER[(i + by).rem_euclid(Self::ORDER.len() as isize) as usize]
    }
}

/// What a prompt asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ask {
    /// An axis: x, y, z or DX,DY,DZ.
    Axis,
    /// A threshold (empty clears it).
    Threshold,
}

/// A line of text being typed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Prompt {
    /// What it asks for.
    pub ask: Ask,
    /// What has been typed.
    pub text: String,
}

/// Background work that can be running.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Job {
    /// Loading the volume.
    Load,
    /// The view search.
    Views,
    /// The histories along an axis.
    Analysis,
    /// A render.
    Render,
}

/// A job's message back to the UI.
pub enum JobMsg {
    /// Progress of a job, 0 to 1.
    Progress(Job, f64),
    /// The volume loaded (with the loader's notes), or why not.
    Loaded(Result<(Arc<Volume>, Vec<String>), String>),
    /// The view search's result.
    Views(Result<Box<ViewSearch>, String>),
    /// The histories along the axis of request `generation`.
    Analysis(u64, Result<Arc<Analysis>, String>),
    /// A render of request `generation`.
    Rendered(u64, Result<Box<Protocol>, String>),
    /// An export finished: what was written, or why not.
    Exported(Result<String, String>),
}

/// Everything the user can do, and what jobs report.
pub enum Action {
    /// Leave.
    Quit,
    /// Show or hide the key help.
    ToggleHelp,
    /// Move the focus to the next or previous pane.
    Focus(isize),
    /// Move the cursor of the focused pane.
    Move(isize),
    /// Page the cursor of the focused pane.
    Page(isize),
    /// Act on the cursor (partition along the selected axis).
    Select,
    /// Take `n` more steps of the history (negative: back).
    Step(isize),
    /// Go to the start or the end of the history.
    StepTo(bool),
    /// One slab more or fewer.
    Slabs(isize),
    /// Switch method: top-down, bottom-up, optimal.
    CycleMethod,
    /// Start typing an axis or a threshold.
    Ask(Ask),
    /// A typed character for the prompt.
    Type(char),
    /// Delete the prompt's last character.
    Erase,
    /// Accept the prompt.
    Submit,
    /// Close the prompt or help, or cancel running work.
    Escape,
    /// Orbit the camera: degrees of azimuth and elevation.
    Orbit(f64, f64),
    /// Zoom by a factor.
    Zoom(f64),
    /// Change the spread by this much.
    Spread(f64),
    /// DVR or MIP.
    ToggleMode,
    /// Next transfer function.
    CycleTransfer,
    /// Next colour map.
    CycleColormap,
    /// Uniform or similarity gaps.
    ToggleGap,
    /// Show the selected slab alone, or all.
    ToggleSolo,
    /// Perspective or orthographic.
    TogglePerspective,
    /// Write the view (PNG), the analysis (JSON) and the labels (NRRD).
    Export,
    /// The preview pane's size in cells changed.
    PreviewArea(u16, u16),
    /// A job's message.
    Job(JobMsg),
}

/// What to render, at which size.
#[derive(Clone, Debug)]
pub struct RenderRequest {
    /// Request number; only the newest result is shown.
    pub generation: u64,
    /// The slabs (empty: the whole volume, seen around `axis`).
    pub slabs: Vec<(usize, usize)>,
    /// The axis.
    pub axis: [f64; 3],
    /// NMI at each boundary, where known.
    pub nmi: Option<Vec<f64>>,
    /// The slice stack, for the slabs' geometry and unknown NMIs.
    pub stack: Option<Arc<slabscope::partition::SliceStack>>,
    /// Camera and look.
    pub camera: CameraParams,
    /// DVR or MIP.
    pub mode: Mode,
    /// Transfer function.
    pub preset: Preset,
    /// Colour map.
    pub colormap: Colormap,
    /// Gaps.
    pub gap: Gap,
    /// Spread.
    pub spread: f64,
    /// The selected slab.
    pub highlight: Option<usize>,
    /// Show it alone.
    pub solo: bool,
    /// Preview size in cells.
    pub cells: (u16, u16),
}

/// What the event loop does on the app's behalf.
#[derive(Clone, Debug)]
pub enum Effect {
    /// Load the volume.
    Load,
    /// Run the view search.
    SearchViews,
    /// Compute the histories along `axis` as request `generation`.
    Analyze(u64, [f64; 3], StackParams),
    /// Render.
    Render(RenderRequest),
    /// Cancel running jobs.
    Cancel,
    /// Write exports for the current partition.
    Export,
    /// Leave.
    Quit,
}

/// The look of the exploded view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Look {
    /// Camera.
    pub camera: CameraParams,
    /// Spread.
    pub spread: f64,
    /// Gaps.
    pub gap: Gap,
    /// DVR or MIP.
    pub mode: Mode,
    /// Transfer function.
    pub preset: Preset,
    /// Colour map.
    pub colormap: Colormap,
    /// Selected slab alone.
    pub solo: bool,
}

impl Default for Look {
    fn default() -> Self {
        Self {
            camera: CameraParams::default(),
            spread: 0.3,
            gap: Gap::Similarity,
            mode: Mode::Dvr,
            preset: Preset::Auto,
            colormap: Colormap::Grey,
            solo: false,
        }
    }
}

/// The whole state of the TUI.
pub struct App {
    /// The volume's name.
    pub name: String,
    /// The volume.
    pub volume: Load<Arc<Volume>>,
    /// The view search.
    pub views: Load<ViewSearch>,
    /// The histories along the current axis.
    pub analysis: Load<Arc<Analysis>>,
    /// The axis being partitioned.
    pub axis: Option<[f64; 3]>,
    /// Partition method.
    pub method: Method,
    /// Position in the method's history.
    pub position: usize,
    /// Stop by threshold instead of by position.
    pub threshold: Option<f64>,
    /// Slice options.
    pub stack: StackParams,
    /// The focused pane.
    pub focus: Pane,
    /// Selected row of the viewpoint list.
    pub view_row: usize,
    /// Selected slab.
    pub slab_row: usize,
    /// Slice under the curve cursor.
    pub cursor: usize,
    /// The look of the preview.
    pub look: Look,
    /// The preview image.
    pub preview: Load<Box<Protocol>>,
    /// Preview size in cells.
    pub preview_cells: (u16, u16),
    /// A prompt being typed.
    pub prompt: Option<Prompt>,
    /// Whether the help overlay shows.
    pub help: bool,
    /// The last message for the user.
    pub message: Option<String>,
    /// Whether to leave.
    pub quit: bool,
    analysis_generation: u64,
    render_generation: u64,
}

impl App {
    /// A fresh app for the volume called `name`; the first effects load it.
    pub fn new(name: String) -> (Self, Vec<Effect>) {
        let app = Self {
            name,
            volume: Load::Running(0.0),
            views: Load::Idle,
            analysis: Load::Idle,
            axis: None,
            method: Method::TopDown,
            position: 3,
            threshold: None,
            stack: StackParams::default(),
            focus: Pane::Views,
            view_row: 0,
            slab_row: 0,
            cursor: 0,
            look: Look::default(),
            preview: Load::Idle,
            preview_cells: (0, 0),
            prompt: None,
            help: false,
            message: None,
            quit: false,
            analysis_generation: 0,
            render_generation: 0,
        };
        (app, vec![Effect::Load])
    }

    /// The slabs shown now, when the analysis is ready.
    pub fn slabs(&self) -> Option<Vec<(usize, usize)>> {
        self.analysis
            .ready()
            .map(|a| a.slabs(self.method, self.position))
    }

    /// Applies `action`; returns what the event loop must do.
    pub fn update(&mut self, action: Action) -> Vec<Effect> {
        if let Some(prompt) = &mut self.prompt {
            match action {
                Action::Type(c) => {
                    prompt.text.push(c);
                    return vec![];
                }
                Action::Erase => {
                    prompt.text.pop();
                    return vec![];
                }
                Action::Submit => return self.submit(),
                Action::Escape => {
                    self.prompt = None;
                    return vec![];
                }
                Action::Job(_) | Action::PreviewArea(..) | Action::Quit => {}
                _ => return vec![],
            }
        }
        match action {
            Action::Quit => {
                self.quit = true;
                vec![Effect::Cancel, Effect::Quit]
            }
            Action::ToggleHelp => {
                self.help = !self.help;
                vec![]
            }
            Action::Escape => self.escape(),
            Action::Focus(by) => {
                self.focus = self.focus.step(by);
                vec![]
            }
            Action::Move(by) => self.move_cursor(by),
            Action::Page(by) => self.move_cursor(by * 10),
            Action::Select => self.select(),
            Action::Step(by) => self.step(by),
            Action::StepTo(end) => self.step_to(end),
            Action::Slabs(by) => self.change_slabs(by),
            Action::CycleMethod => self.cycle_method(),
            Action::Ask(ask) => {
                self.prompt = Some(Prompt {
                    ask,
                    text: String::new(),
                });
                vec![]
            }
            Action::Type(_) | Action::Erase | Action::Submit => vec![],
            Action::Orbit(az, el) => self.restyle(|l| {
                l.camera.azimuth = (l.camera.azimuth + az).rem_euclid(360.0);
                l.camera.elevation = (l.camera.elevation + el).clamp(-85.0, 85.0);
            }),
            Action::Zoom(f) => {
                self.restyle(|l| l.camera.zoom = (l.camera.zoom * f).clamp(0.25, 8.0))
            }
            Action::Spread(d) => self.restyle(|l| l.spread = (l.spread + d).clamp(0.0, 2.0)),
            Action::ToggleMode => self.restyle(|l| {
                l.mode = if l.mode == Mode::Dvr {
                    Mode::Mip
                } else {
                    Mode::Dvr
                }
            }),
            Action::CycleTransfer => self.restyle(|l| l.preset = next(&Preset::ALL, l.preset)),
            Action::CycleColormap => {
                self.restyle(|l| l.colormap = next(&Colormap::ALL, l.colormap))
            }
            Action::ToggleGap => self.restyle(|l| {
                l.gap = if l.gap == Gap::Uniform {
                    Gap::Similarity
                } else {
                    Gap::Uniform
                }
            }),
            Action::ToggleSolo => self.restyle(|l| l.solo = !l.solo),
            Action::TogglePerspective => {
                self.restyle(|l| l.camera.perspective = !l.camera.perspective)
            }
            Action::Export => self.export(),
            Action::PreviewArea(w, h) => {
                if (w, h) == self.preview_cells {
                    return vec![];
                }
                self.preview_cells = (w, h);
                self.render()
            }
            Action::Job(msg) => self.on_job(msg),
        }
    }

    fn escape(&mut self) -> Vec<Effect> {
        if self.help {
            self.help = false;
            return vec![];
        }
        let busy = self.views.running() || self.analysis.running() || self.preview.running();
        if busy {
            if self.views.running() {
                self.views = Load::Failed("cancelled".into());
            }
            if self.analysis.running() {
                self.analysis = Load::Failed("cancelled".into());
            }
            self.message = Some("cancelled".into());
            return vec![Effect::Cancel];
        }
        vec![]
    }

    fn move_cursor(&mut self, by: isize) -> Vec<Effect> {
        let shift = |v: usize, len: usize| {
            (v as isize + by).clamp(0, len.saturating_sub(1) as isize) as usize
        };
        match self.focus {
            Pane::Views => {
                let len = self.views.ready().map_or(0, |v| v.views.len());
                self.view_row = shift(self.view_row, len);
                vec![]
            }
            Pane::Slabs => {
                let len = self.slabs().map_or(0, |s| s.len());
                self.slab_row = shift(self.slab_row, len);
                self.render()
            }
            Pane::Curves => {
                let len = self.analysis.ready().map_or(0, |a| a.slices());
                self.cursor = shift(self.cursor, len);
                vec![]
            }
            Pane::Preview => self.update(Action::Orbit(by as f64 * 15.0, 0.0)),
        }
    }

    fn select(&mut self) -> Vec<Effect> {
        if self.focus != Pane::Views {
            return vec![];
        }
        match self.views.ready().and_then(|v| v.views.get(self.view_row)) {
            Some(view) => {
                let axis = view.axis;
                self.analyze(axis)
            }
            None => vec![],
        }
    }

    /// Starts the histories along `axis`.
    fn analyze(&mut self, axis: [f64; 3]) -> Vec<Effect> {
        self.axis = Some(axis);
        self.analysis_generation += 1;
        self.analysis = Load::Running(0.0);
        self.cursor = 0;
        self.slab_row = 0;
        vec![Effect::Analyze(
            self.analysis_generation,
            axis,
            self.stack.clone(),
        )]
    }

    fn step(&mut self, by: isize) -> Vec<Effect> {
        let Some(a) = self.analysis.ready() else {
            return vec![];
        };
        let last = a.last(self.method) as isize;
        let position = (self.position as isize + by).clamp(0, last) as usize;
        if position == self.position {
            self.message = Some(
                if by > 0 {
                    "at the end of the history"
                } else {
                    "at the start of the history"
                }
                .into(),
            );
            return vec![];
        }
        self.threshold = None;
        self.set_position(position)
    }

    fn step_to(&mut self, end: bool) -> Vec<Effect> {
        let Some(a) = self.analysis.ready() else {
            return vec![];
        };
        let position = if end { a.last(self.method) } else { 0 };
        self.threshold = None;
        self.set_position(position)
    }

    fn set_position(&mut self, position: usize) -> Vec<Effect> {
        self.position = position;
        self.message = None;
        let k = self.slabs().map_or(1, |s| s.len());
        self.slab_row = self.slab_row.min(k - 1);
        self.render()
    }

    fn change_slabs(&mut self, by: isize) -> Vec<Effect> {
        let Some(a) = self.analysis.ready() else {
            return vec![];
        };
        let k = a.slab_count(self.method, self.position) as isize + by;
        let position = a.position_for(self.method, k.max(1) as usize);
        self.threshold = None;
        self.set_position(position)
    }

    fn cycle_method(&mut self) -> Vec<Effect> {
        let k = self
            .analysis
            .ready()
            .map(|a| a.slab_count(self.method, self.position));
        self.method = match self.method {
            Method::TopDown => Method::BottomUp,
            Method::BottomUp => Method::Optimal,
            Method::Optimal => Method::TopDown,
        };
        let Some(a) = self.analysis.ready() else {
            return vec![];
        };
        let position = match self.threshold {
            Some(t) => a.position_for_threshold(self.method, t),
            None => a.position_for(self.method, k.unwrap_or(4)),
        };
        self.set_position(position)
    }

    fn submit(&mut self) -> Vec<Effect> {
        let Some(prompt) = self.prompt.take() else {
            return vec![];
        };
        let text = prompt.text.trim();
        match prompt.ask {
            Ask::Axis => {
                if let Some(axis) = parse_axis(text) {
                    self.analyze(axis)
                } else {
                    self.message = Some(format!("{text:?} is not x, y, z or DX,DY,DZ"));
                    vec![]
                }
            }
            Ask::Threshold if text.is_empty() => {
                self.threshold = None;
                self.message = Some("threshold cleared".into());
                vec![]
            }
            Ask::Threshold => match text.parse::<f64>() {
                Ok(t) if t.is_finite() => {
                    self.threshold = Some(t);
                    match self.analysis.ready() {
                        Some(a) => {
                            let position = a.position_for_threshold(self.method, t);
                            self.set_position(position)
                        }
                        None => vec![],
                    }
                }
                _ => {
                    self.message = Some(format!("{text:?} is not a number"));
                    vec![]
                }
            },
        }
    }

    fn restyle(&mut self, change: impl FnOnce(&mut Look)) -> Vec<Effect> {
        change(&mut self.look);
        self.render()
    }

    fn export(&mut self) -> Vec<Effect> {
        if self.analysis.ready().is_none() {
            self.message = Some("nothing to export yet: the partition is not ready".into());
            return vec![];
        }
        vec![Effect::Export]
    }

    /// A render of the current state, when there is somewhere to show it.
    fn render(&mut self) -> Vec<Effect> {
        let Some(volume) = self.volume.ready() else {
            return vec![];
        };
        let (w, h) = self.preview_cells;
        if w < 4 || h < 2 {
            return vec![];
        }
        self.render_generation += 1;
        let slabs = self.slabs().unwrap_or_default();
        let nmi = self
            .analysis
            .ready()
            .and_then(|a| a.known_nmi(self.method, self.position));
        let stack = self.analysis.ready().map(|a| Arc::clone(&a.stack));
        let axis = self.axis.unwrap_or_else(|| {
            if volume.dims()[2] > 1 {
                [0.0, 0.0, 1.0]
            } else {
                [0.0, 1.0, 0.0]
            }
        });
        let keep = matches!(self.preview, Load::Ready(_));
        if !keep {
            self.preview = Load::Running(0.0);
        }
        vec![Effect::Render(RenderRequest {
            generation: self.render_generation,
            highlight: (!slabs.is_empty()).then_some(self.slab_row),
            slabs,
            axis,
            nmi,
            stack,
            camera: self.look.camera,
            mode: self.look.mode,
            preset: self.look.preset,
            colormap: self.look.colormap,
            gap: self.look.gap,
            spread: self.look.spread,
            solo: self.look.solo,
            cells: self.preview_cells,
        })]
    }

    fn on_job(&mut self, msg: JobMsg) -> Vec<Effect> {
        match msg {
            JobMsg::Progress(job, f) => {
                match job {
                    Job::Load if self.volume.running() => self.volume = Load::Running(f),
                    Job::Views if self.views.running() => self.views = Load::Running(f),
                    Job::Analysis if self.analysis.running() => self.analysis = Load::Running(f),
                    _ => {}
                }
                vec![]
            }
            JobMsg::Loaded(Ok((volume, notes))) => {
                self.message = notes.first().cloned();
                self.volume = Load::Ready(volume);
                self.views = Load::Running(0.0);
                let mut effects = vec![Effect::SearchViews];
                effects.extend(self.render());
                effects
            }
            JobMsg::Loaded(Err(e)) => {
                self.message = Some(format!("{e} (q quits)"));
                self.volume = Load::Failed(e);
                vec![]
            }
            JobMsg::Views(Ok(views)) => {
                let best = views.best().axis;
                self.views = Load::Ready(*views);
                self.view_row = 0;
                if self.axis.is_none() {
                    self.analyze(best)
                } else {
                    vec![]
                }
            }
            JobMsg::Views(Err(e)) => {
                self.views = Load::Failed(e);
                vec![]
            }
            JobMsg::Analysis(generation, result) => {
                if generation != self.analysis_generation {
                    return vec![];
                }
                match result {
                    Ok(a) => {
                        let position = match self.threshold {
                            Some(t) => a.position_for_threshold(self.method, t),
                            None => a.position_for(self.method, 4),
                        };
                        self.analysis = Load::Ready(a);
                        self.set_position(position)
                    }
                    Err(e) => {
                        self.analysis = Load::Failed(e);
                        vec![]
                    }
                }
            }
            JobMsg::Rendered(generation, result) => {
                if generation == self.render_generation {
                    self.preview = match result {
                        Ok(p) => Load::Ready(p),
                        Err(e) => Load::Failed(e),
                    };
                }
                vec![]
            }
            JobMsg::Exported(result) => {
                self.message = Some(match result {
                    Ok(m) => m,
                    Err(e) => format!("export failed: {e}"),
                });
                vec![]
            }
        }
    }
}

/// The element after `current` in `all`, wrapping around.
fn next<T: Copy + PartialEq>(all: &[T], current: T) -> T {
    let i = all.iter().position(|x| *x == current).unwrap_or(0);
    all[(i + 1) % all.len()]
}

/// `x`, `y`, `z` or `DX,DY,DZ`.
pub fn parse_axis(text: &str) -> Option<[f64; 3]> {
    match text {
        "x" => Some([1.0, 0.0, 0.0]),
        "y" => Some([0.0, 1.0, 0.0]),
        "z" => Some([0.0, 0.0, 1.0]),
        _ => {
            let v: Vec<f64> = text
                .split(',')
                .map(|p| p.trim().parse().ok())
                .collect::<Option<_>>()?;
            let a = <[f64; 3]>::try_from(v).ok()?;
            (a.iter().all(|c| c.is_finite()) && a.iter().any(|c| *c != 0.0)).then_some(a)
        }
    }
}
