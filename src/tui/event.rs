//! What flows through the TUI: events into the loop, actions into [`App::update`], effects out of
//! it, and the messages background jobs send back.
//!
//! [`App::update`]: super::app::App::update

use std::sync::Arc;

use crossterm::event::KeyEvent;
use slabscope::params::Scene;
use slabscope::partition::{Method, Slab, StackParams};
use slabscope::render::{CameraParams, Colormap, Gap, Mode, Preset, RenderParams};
use slabscope::{Histories, Progress, ViewParams, ViewSearch, Volume};

use crate::term::image::TermImage;

/// Everything the loop waits for.
pub enum Event {
    /// A key press.
    Key(KeyEvent),
    /// The terminal changed size.
    Resize,
    /// A background job's message.
    Job(JobMsg),
}

/// Something computed in the background: not asked for yet, under way, done, or failed.
pub enum Task<T> {
    /// Not asked for.
    Idle,
    /// Under way, with its phase and the fraction done.
    Running(Progress),
    /// Done.
    Ready(T),
    /// Failed, with the message.
    Failed(String),
}

impl<T> Task<T> {
    /// Under way, at the start of `phase`.
    pub fn started(phase: &'static str) -> Self {
        Self::Running(Progress {
            phase,
            fraction: 0.0,
        })
    }

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

    /// The same state without the value, for a pane that shows only the gauge or the error.
    pub fn status(&self) -> Task<()> {
        match self {
            Self::Idle => Task::Idle,
            Self::Running(p) => Task::Running(*p),
            Self::Ready(_) => Task::Ready(()),
            Self::Failed(e) => Task::Failed(e.clone()),
        }
    }
}

/// Background work that can be running.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Job {
    /// Loading the volume.
    Load,
    /// The view search on a pyramid level (0: full resolution).
    Views(usize),
    /// The histories along an axis on a pyramid level (0: full resolution).
    Analysis(usize),
    /// Ranking the axes by partition gain.
    Gain,
    /// Writing the exports.
    Export,
    /// Computing the lesson's numbers.
    Lesson,
}

/// A job's message back to the UI.
pub enum JobMsg {
    /// Progress of a job.
    Progress(Job, Progress),
    /// The volume loaded (with the loader's notes), or why not.
    Loaded(Result<(Arc<Volume>, Vec<String>), String>),
    /// A coarse pyramid level of the volume is built: the preview computes on it.
    Coarse(Arc<Volume>),
    /// A coarse pyramid level the file holds (an OME-Zarr store's), read before level 0 (with
    /// the loader's notes): the preview computes on it while level 0 loads.
    Preview(Arc<Volume>, Vec<String>),
    /// The view search's result on a pyramid level (0: full resolution).
    Views(usize, Result<Box<ViewSearch>, String>),
    /// The histories along the axis of request `generation`, on a pyramid level.
    Analysis(u64, usize, Result<Arc<Histories>, String>),
    /// The axes ranked by partition gain on a pyramid level (0: full resolution).
    Gain(usize, Result<Box<slabscope::analysis::GainRanking>, String>),
    /// A render of request `generation`.
    Rendered(u64, Result<Box<Rendered>, String>),
    /// An export finished: what was written, or why not.
    Exported(Result<String, String>),
    /// The lesson of request `generation`.
    Lesson(u64, Result<Box<crate::tui::lesson::Lesson>, String>),
    /// Background triage's row of volume `index` of the folder.
    Triaged(usize, Box<slabscope::triage::TriageRow>),
    /// Background triage's thumbnail of volume `index`: its exploded view and mid slices.
    Thumbnail(usize, Box<image::RgbaImage>),
    /// A manifest of the marked volumes, to this file: written, or why not.
    Manifest(std::path::PathBuf, Written),
    /// A message of a job started for the volume open in `epoch` (the jobs drop it once
    /// another volume is open; the app never sees this wrapper).
    Epoch(u64, Box<JobMsg>),
}

/// What came of writing a file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Written {
    /// Written, with this many lines of volumes.
    Done(usize),
    /// Not written: the file exists, and was not to be replaced.
    Exists,
    /// Not written, and why (one line naming the file).
    Failed(String),
}

/// A picture for the preview pane, and the slice view's readout.
pub struct Rendered {
    /// The picture, encoded for the terminal.
    pub image: TermImage,
    /// What the slice view reads at its pointer.
    pub caption: Option<String>,
    /// The colour window the picture used, for the window and level keys to start from (none
    /// for a figure of the paper's).
    pub window: Option<(f32, f32)>,
}

/// Everything the user can do, and what jobs report.
pub enum Action {
    /// Leave.
    Quit,
    /// Show or hide the key help.
    ToggleHelp,
    /// Move the focus to the next or previous pane.
    Focus(isize),
    /// Move the cursor of the focused pane (up and down).
    Move(isize),
    /// Move the cursor of the focused pane sideways (the slice view's pointer; elsewhere as
    /// [`Action::Move`]).
    Sideways(isize),
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
    /// Cut faces, DVR or MIP.
    ToggleMode,
    /// The slice view or the exploded view.
    ToggleSlices,
    /// Show or hide a folder's pane.
    ToggleFiles,
    /// A key of the folder's pane: marks, order, filters.
    Folder(FolderKey),
    /// Multiply the window's width by this factor.
    WindowWidth(f32),
    /// Move the window's level by this fraction of its width.
    WindowLevel(f32),
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
    /// Leave the background out of the slabs, or count every voxel.
    ToggleBackground,
    /// Rank the axes by partition gain, once ranked switch the list's order and the sphere's
    /// colours between the entropy rate and the gain.
    RankGain,
    /// Show or hide the lesson: the numbers behind the selected viewpoint or the step shown.
    ToggleLesson,
    /// Turn the tour's page forward or back.
    TurnPage(isize),
    /// Write the view (PNG), the analysis (JSON) and the labels (NRRD).
    Export,
    /// The preview pane's size in cells changed.
    PreviewArea(u16, u16),
    /// A job's message.
    Job(JobMsg),
}

/// What a prompt asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ask {
    /// An axis: x, y, z or DX,DY,DZ.
    Axis,
    /// A threshold (empty clears it).
    Threshold,
    /// Part of a volume's name, in the folder's pane.
    Find,
    /// The file to write the marked volumes to, as a manifest.
    Manifest,
    /// That file again, which exists: the same name replaces it.
    Overwrite,
}

/// What a key of the folder's pane does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FolderKey {
    /// Mark the cursor's volume, or take its mark away.
    Mark,
    /// Sort by the next column.
    Sort,
    /// Sort the other way.
    Reverse,
    /// Only the failed volumes, or all.
    Errors,
    /// Only the uncertain volumes, or all.
    Uncertain,
    /// Only the volumes of the next format, or all.
    Format,
}

/// The look of the exploded view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PictureSettings {
    /// Camera.
    pub camera: CameraParams,
    /// Spread.
    pub spread: f64,
    /// Gaps.
    pub gap: Gap,
    /// Cut faces, DVR or MIP.
    pub mode: Mode,
    /// Transfer function.
    pub preset: Preset,
    /// Colour map.
    pub colormap: Colormap,
    /// The window set with the window and level keys, replacing the preset's.
    pub window: Option<(f32, f32)>,
    /// Selected slab alone.
    pub solo: bool,
}

impl PictureSettings {
    /// The library's look.
    pub fn colours(&self) -> slabscope::render::TransferChoice {
        slabscope::render::TransferChoice {
            preset: self.preset,
            colormap: self.colormap,
            window: self.window,
        }
    }

    /// The library's scene of these settings for a `width × height` picture highlighting slab
    /// `highlight`: the library's defaults for the rest (shading, step, outlines, background),
    /// the slabs' numbers written only in a picture 120 pixels high or more, where they fit, and
    /// the other slabs not faded, as the user steps through them.
    pub fn scene(&self, (width, height): (u32, u32), highlight: Option<usize>) -> Scene {
        let defaults = Scene::default().params;
        Scene {
            params: RenderParams {
                width,
                height,
                mode: self.mode,
                preset: self.preset,
                colormap: self.colormap,
                window: self.window,
                camera: self.camera,
                highlight,
                solo: self.solo,
                labels: height >= 120,
                ..defaults
            },
            gap: self.gap,
            spread: self.spread,
        }
    }
}

impl Default for PictureSettings {
    /// The library's scene's defaults ([`Scene::default`]), the window of the preset's.
    fn default() -> Self {
        let Scene {
            params,
            gap,
            spread,
        } = Scene::default();
        Self {
            camera: params.camera,
            spread,
            gap,
            mode: params.mode,
            preset: params.preset,
            colormap: params.colormap,
            window: params.window,
            solo: params.solo,
        }
    }
}

/// What the preview pane's render worker draws, at which size: the exploded view of the slabs
/// on screen (from their histories, as the user steps) or the slice view, encoded for the
/// terminal. The exploded view is the library's `request::RenderRequest` of the
/// [`scene`](PictureSettings::scene) of `look`, drawn from `level` by the worker's renderer.
#[derive(Clone)]
pub struct PictureJob {
    /// Job number; only the newest result is shown.
    pub generation: u64,
    /// The pyramid level of the volume the slabs and the slice view are on (0: full
    /// resolution).
    pub level: usize,
    /// The slabs (empty: the whole volume, seen around `axis`).
    pub slabs: Vec<Slab>,
    /// The axis.
    pub axis: [f64; 3],
    /// NMI at each boundary, where known.
    pub nmi: Option<Vec<f64>>,
    /// The histories, for the slabs' geometry and unknown NMIs.
    pub histories: Option<Arc<Histories>>,
    /// Camera, gaps and colours.
    pub look: PictureSettings,
    /// The selected slab.
    pub highlight: Option<usize>,
    /// Preview size in cells.
    pub cells: (u16, u16),
    /// The slice view instead of the exploded view.
    pub slice: Option<SliceCursor>,
    /// One of the paper's figures instead (a tour page's, drawn through the image protocol; the
    /// board draws it in braille on half-blocks).
    pub figure: Option<Box<slabscope::explain::figure::Drawing>>,
}

#[cfg(test)]
impl PictureJob {
    /// The whole volume along z on level 0, unpartitioned, in `cells`: the tests' first picture.
    pub fn whole(cells: (u16, u16)) -> Self {
        Self {
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
        }
    }
}

/// Where the slice view looks: the slice under the curves' cursor and the pointer on it (the
/// library's `request::SliceRequest` is `slabscope slice`'s picture).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SliceCursor {
    /// The slice under the curves' cursor.
    pub index: usize,
    /// The pointer: a physical point (voxel indices times spacing), read where it projects
    /// onto the slice.
    pub pointer: [f64; 3],
}

/// What to export: everything the export job needs, so that it reads nothing of the app.
#[derive(Clone)]
pub struct ExportRequest {
    /// The volume's name, for the file names and the report.
    pub name: String,
    /// The histories along the axis.
    pub histories: Arc<Histories>,
    /// The view search, when done.
    pub views: Option<ViewSearch>,
    /// The gain ranking, when done, and the ranking that picked the axis (none when the user
    /// did).
    pub gain: Option<(
        slabscope::analysis::GainRanking,
        Option<slabscope::analysis::AxisBy>,
    )>,
    /// The view search's parameters.
    pub view_params: ViewParams,
    /// The method and position in its history.
    pub method: Method,
    /// The position in the method's history.
    pub position: usize,
    /// The pyramid level the histories were computed on (0: full resolution).
    pub level: usize,
    /// The look of the picture.
    pub look: PictureSettings,
    /// The selected slab.
    pub highlight: Option<usize>,
}

/// What the event loop does on the app's behalf.
#[derive(Clone)]
pub enum Effect {
    /// Load the volume.
    Load,
    /// Run the view search on a pyramid level (0: full resolution).
    SearchViews(ViewParams, usize),
    /// Compute the histories along `axis` as request `generation`, on a pyramid level.
    Analyze(u64, [f64; 3], StackParams, usize),
    /// Rank every axis by partition gain with these parameters, on a pyramid level.
    RankGain(Box<slabscope::AnalysisParams>, usize),
    /// Compute a lesson's numbers.
    Lesson(Box<crate::tui::lesson::LessonRequest>),
    /// Render.
    Render(Box<PictureJob>),
    /// Write exports.
    Export(Box<ExportRequest>),
    /// Load this volume instead (a folder's next volume).
    Open(slabscope::triage::Entry),
    /// Triage these volumes in the background with these parameters, one row each as it
    /// completes.
    Triage(
        Vec<slabscope::triage::Entry>,
        Box<slabscope::AnalysisParams>,
    ),
    /// Write these volumes as a manifest to this file, replacing it when asked (true).
    WriteManifest(std::path::PathBuf, Vec<slabscope::triage::Entry>, bool),
    /// Hold background triage at its next volume (true) while the open volume's work runs, or
    /// let it go on (false).
    PauseTriage(bool),
    /// Cancel running jobs.
    Cancel,
    /// Drop what the jobs started for the open volume still send, and the file's preview level:
    /// the app starts afresh on the volume loaded.
    Forget,
    /// Leave.
    Quit,
}

impl std::fmt::Debug for Effect {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Load => write!(f, "Load"),
            Self::SearchViews(_, level) => write!(f, "SearchViews(level {level})"),
            Self::Analyze(g, axis, _, level) => write!(f, "Analyze({g}, {axis:?}, level {level})"),
            Self::RankGain(_, level) => write!(f, "RankGain(level {level})"),
            Self::Lesson(r) => write!(f, "Lesson({}, {:?})", r.generation, r.subject),
            Self::Render(r) => write!(f, "Render({})", r.generation),
            Self::Export(r) => write!(f, "Export({:?} at {})", r.method, r.position),
            Self::Open(p) => write!(f, "Open({})", p.name()),
            Self::Triage(p, _) => write!(f, "Triage({} volumes)", p.len()),
            Self::WriteManifest(p, e, force) => write!(
                f,
                "WriteManifest({}, {} volumes{})",
                p.display(),
                e.len(),
                if *force { ", replacing" } else { "" }
            ),
            Self::PauseTriage(on) => write!(f, "PauseTriage({on})"),
            Self::Cancel => write!(f, "Cancel"),
            Self::Forget => write!(f, "Forget"),
            Self::Quit => write!(f, "Quit"),
        }
    }
}
