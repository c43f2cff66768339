//! The terminal UI: `slabscope [FILE]`. Events (keys, resizes, job messages) become actions;
//! [`app::App::update`] is the only place state changes and returns effects that [`jobs::Jobs`]
//! carries out in the background; drawing is a pure function of the state. The loop is generic
//! over the ratatui backend, so tests drive it on a `TestBackend`.

pub mod app;
pub mod event;
pub mod export;
pub mod jobs;
pub mod keymap;
pub mod lesson;
pub mod panes;
pub mod partitioning;
pub mod theme;
pub mod ui;

#[cfg(test)]
mod tests;

use std::io::{IsTerminal, Write, stdout};
use std::path::PathBuf;
use std::sync::mpsc::{Receiver, Sender, channel};

use anyhow::{Result, bail};
use crossterm::event::{Event as TermEvent, KeyCode, KeyEvent, KeyModifiers};
use crossterm::execute;
use crossterm::terminal::{
    EnterAlternateScreen, LeaveAlternateScreen, disable_raw_mode, enable_raw_mode,
};
use ratatui::Terminal;
use ratatui::backend::{Backend, CrosstermBackend};
use slabscope::triage::{Folder, discover, folder_kind, picks_in_folder};
use slabscope::{AnalysisParams, LoadOptions};

use crate::term::{self, Protocol};
use app::{App, Screen};
use event::{Action, Effect, Event, JobMsg};
use jobs::Jobs;
use theme::Theme;

/// The pyramid level of `volume`'s preview (the budget planner's glance): 0 when it is small
/// enough to compute at full resolution at once.
pub fn preview_level(volume: &slabscope::Volume) -> usize {
    slabscope::budget::glance_level(volume)
}

/// What the TUI opens and how.
pub struct Options {
    /// The volume (None: the built-in dataset).
    pub file: Option<PathBuf>,
    /// How to read it.
    pub load: LoadOptions,
    /// The image protocol, or `Auto` to ask the terminal.
    pub protocol: Protocol,
    /// How to analyse it.
    pub analysis: AnalysisParams,
    /// The colours.
    pub theme: theme::ThemeChoice,
    /// Run the guided tour, and how.
    pub tour: Option<TourMode>,
}

/// How the tour runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TourMode {
    /// Paper mode: the paper's single lattice and every voxel (`tour --paper`).
    pub paper: bool,
}

/// The folder `file` names, with the volumes it holds, when it opens with a pane of them: a folder of
/// volumes does, its first volume open; so does a folder of DICOM files with several series,
/// unless `load` names one.
fn folder_to_list(
    file: Option<&PathBuf>,
    load: &LoadOptions,
) -> Result<Option<(PathBuf, Vec<slabscope::triage::Entry>)>> {
    let kind = match file {
        Some(dir) if dir.is_dir() && !picks_in_folder(load) => Some(folder_kind(dir)?),
        _ => None,
    };
    Ok(match (file, kind) {
        (Some(dir), Some(Folder::Collection | Folder::Series | Folder::Empty)) => {
            let paths = discover(std::slice::from_ref(dir), load)?;
            if paths.is_empty() {
                bail!(
                    "{}: holds no volume slabscope reads",
                    slabscope::error::shown(dir)
                );
            }
            Some((dir.clone(), paths)).filter(|(_, p)| kind != Some(Folder::Series) || p.len() > 1)
        }
        _ => None,
    })
}

/// Opens the TUI and runs it until the user quits.
pub fn run(options: Options) -> Result<()> {
    let Options {
        file,
        load,
        protocol,
        analysis,
        theme,
        tour,
    } = options;
    let name = file.as_ref().map_or_else(
        || slabscope::BUILTIN_NAME.to_string(),
        |p| slabscope::error::shown(p),
    );
    // A file that cannot be opened is an error before the screen changes.
    if let Some(path) = &file {
        slabscope::formats::check_input(path)?;
    }
    let folder = folder_to_list(file.as_ref(), &load)?;
    let file = match &folder {
        Some((_, paths)) => Some(paths[0].clone()),
        None => file.map(slabscope::triage::Entry::file),
    };
    if !std::io::stdout().is_terminal() || term::tty_input().is_err() {
        bail!(
            "the TUI needs a terminal, and this has none (over SSH, `ssh -t`); \
             `slabscope analyze`, `render` and `preview` work without one"
        );
    }
    // Raw mode first, then the terminal's answers are read here, on this thread, so that no
    // reader is left behind to race the UI for the keyboard.
    enable_raw_mode()?;
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        restore("");
        default_hook(info);
    }));
    let caps = match term::detect(protocol, &mut stdout()) {
        Ok(caps) => caps,
        Err(e) => {
            restore("");
            return Err(e.into());
        }
    };
    let thumbs = panes::thumbs::Thumbs::new(&caps);
    // On quitting, the preview's picture and the thumbnails' are taken away.
    let hide = term::image::hide_sequence(&caps);
    let quit_hide = format!("{hide}{}", thumbs.as_ref().map_or("", |t| &t.hide));
    let result = (|| {
        execute!(stdout(), EnterAlternateScreen)?;
        let mut terminal = Terminal::new(CrosstermBackend::new(stdout()))?;
        let (tx, rx) = channel();
        // Keys typed while the terminal answered come first.
        for c in caps.typed.chars() {
            let key = match c {
                '\x03' => KeyEvent::new(KeyCode::Char('c'), KeyModifiers::CONTROL),
                c => KeyEvent::new(KeyCode::Char(c), KeyModifiers::NONE),
            };
            let _ = tx.send(Event::Key(key));
        }
        spawn_input(tx.clone());
        let screen = Screen {
            theme: Theme::from_env().with(theme),
            hide: hide.clone(),
            note: caps.note.clone(),
            graphics: caps.graphics.name(),
        };
        let mut jobs = Jobs::new(tx, caps, file, load);
        let (mut app, effects) = match folder {
            Some((root, paths)) => App::for_folder(root, paths, analysis, screen),
            None => App::new(name.clone(), analysis, screen),
        };
        if let Some(files) = app.files.as_mut() {
            files.thumbs = thumbs;
        }
        if let Some(mode) = tour {
            app.start_tour(mode.paper);
        }
        run_loop(&mut terminal, &mut app, &rx, &mut jobs, effects)?;
        // The user saw why; the exit status says so too.
        match &app.volume {
            // A folder's volumes are browsed: one that fails is a line in the list.
            event::Task::Failed(e) if app.files.is_none() => bail!("{e}"),
            _ => Ok(()),
        }
    })();
    restore(&quit_hide);
    let _ = std::panic::take_hook();
    result
}

/// Takes images away (`hide`), leaves the alternate screen and raw mode; safe to call twice.
fn restore(hide: &str) {
    let mut out = stdout();
    let _ = out.write_all(hide.as_bytes());
    let _ = execute!(out, LeaveAlternateScreen, crossterm::cursor::Show);
    let _ = disable_raw_mode();
}

/// Reads terminal events on their own thread.
fn spawn_input(tx: Sender<Event>) {
    std::thread::spawn(move || {
        while let Ok(ev) = crossterm::event::read() {
            let sent = match ev {
                TermEvent::Key(k) => tx.send(Event::Key(k)),
                TermEvent::Resize(..) => tx.send(Event::Resize),
                _ => Ok(()),
            };
            if sent.is_err() {
                break;
            }
        }
    });
}

/// Something that carries out effects: the real jobs, or a test's recorder.
pub trait Runner {
    /// Carries out `effect`.
    fn run(&mut self, effect: Effect);
    /// Sees a job message before the app does: the message the app gets, if any.
    fn admit(&mut self, msg: JobMsg) -> Option<JobMsg> {
        Some(msg)
    }
}

impl Runner for Jobs {
    fn run(&mut self, effect: Effect) {
        Jobs::run(self, effect);
    }

    fn admit(&mut self, msg: JobMsg) -> Option<JobMsg> {
        Jobs::admit(self, msg)
    }
}

/// Applies `action` and runs its effects.
pub fn dispatch(app: &mut App, runner: &mut impl Runner, action: Action) {
    for effect in app.update(action) {
        runner.run(effect);
    }
}

/// Tells the app the preview's size for a screen of `size`, then draws.
pub fn redraw<B: Backend>(
    terminal: &mut Terminal<B>,
    app: &mut App,
    runner: &mut impl Runner,
) -> Result<()>
where
    B::Error: Send + Sync + 'static,
{
    let size = terminal.size()?;
    if let Some((w, h)) = ui::preview_cells(
        ratatui::layout::Rect::new(0, 0, size.width, size.height),
        app.tour.is_some(),
        ui::folder(app),
        app.preview_large(),
    ) {
        dispatch(app, runner, Action::PreviewArea(w, h));
    }
    terminal.draw(|frame| ui::draw(frame, app))?;
    Ok(())
}

/// Applies one event.
pub fn handle(app: &mut App, runner: &mut impl Runner, event: Event) {
    let action = match event {
        Event::Key(key) => keymap::action(key, app.status.prompt.is_some(), app.tour.is_some()),
        Event::Resize => None,
        Event::Job(msg) => runner.admit(msg).map(Action::Job),
    };
    if let Some(action) = action {
        dispatch(app, runner, action);
    }
}

/// Draws, waits for an event, applies it; until the app quits.
pub fn run_loop<B: Backend>(
    terminal: &mut Terminal<B>,
    app: &mut App,
    events: &Receiver<Event>,
    runner: &mut impl Runner,
    initial: Vec<Effect>,
) -> Result<()>
where
    B::Error: Send + Sync + 'static,
{
    for effect in initial {
        runner.run(effect);
    }
    while !app.quit {
        redraw(terminal, app, runner)?;
        let Ok(event) = events.recv() else { break };
        handle(app, runner, event);
    }
    Ok(())
}
