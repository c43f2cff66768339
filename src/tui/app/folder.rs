//! A folder opened in the TUI: its pane of volumes below the others, the volume opened from it,
//! its keys (marks, order, filters, finding by name, the manifest of the marked volumes), and
//! background triage held while the open volume's own work runs.

use std::path::{Path, PathBuf};

use slabscope::AnalysisParams;

use super::{App, Pane, Screen};
use crate::tui::event::{Action, Ask, Effect, FolderKey, Written};
use crate::tui::panes::files::FilesPane;
use crate::tui::panes::status::Prompt;

/// The file the manifest prompt offers.
pub const MANIFEST_NAME: &str = "slabscope-marked.txt";

impl App {
    /// A fresh app for the volumes of the folder `root` (`paths`, sorted, at least one): the
    /// first opens, the folder's pane shows with the focus, and triage fills it in the
    /// background, held until the first volume's work is done.
    pub fn for_folder(
        root: PathBuf,
        paths: Vec<slabscope::triage::Entry>,
        params: AnalysisParams,
        screen: Screen,
    ) -> (Self, Vec<Effect>) {
        let name = paths[0].name();
        let (mut app, mut effects) = Self::new(name, params, screen);
        let files = FilesPane::new(root, paths.clone(), app.theme);
        app.status.volume = Some(format!(
            "volume 1 of {}: {}",
            files.paths.len(),
            files.name(0)
        ));
        app.files = Some(files);
        app.focus = Pane::Files;
        app.sync_focus();
        effects.extend(app.sync_triage());
        effects.push(Effect::Triage(paths, Box::new(app.params.clone())));
        (app, effects)
    }

    /// Opens volume `i` of the folder: every pane starts afresh (the look and the folder's pane
    /// stay).
    pub(super) fn open(&mut self, i: usize) -> Vec<Effect> {
        let Some(mut files) = self.files.take() else {
            return vec![];
        };
        if i >= files.paths.len() {
            self.files = Some(files);
            return vec![];
        }
        let path = files.paths[i].clone();
        (files.open, files.row) = (i, i);
        self.files = Some(files);
        let focus = self.focus;
        let effects = self.start_afresh(path.name());
        self.focus = focus;
        self.sync_focus();
        if let Some(files) = &self.files {
            self.status.volume = Some(format!(
                "volume {} of {}: {}",
                i + 1,
                files.paths.len(),
                files.name(i)
            ));
        }
        let mut out = vec![Effect::Cancel, Effect::Open(path)];
        out.extend(effects);
        out
    }

    /// The folder's keys: `PgUp` `PgDn` open the volume before or after the open one, `F` shows or
    /// hides the pane, its own keys mark, sort and filter; with the pane focused the arrows move
    /// in it and Enter opens. `Err` with the action when it is not the folder's.
    pub(super) fn on_files(&mut self, action: Action) -> Result<Vec<Effect>, Action> {
        let Some(files) = self.files.as_mut() else {
            return match action {
                Action::Folder(_) => {
                    Ok(self.say("no folder is open: `slabscope FOLDER` opens one"))
                }
                action => Err(action),
            };
        };
        let focused = self.focus == Pane::Files;
        match action {
            Action::Page(by) => {
                return Ok(match files.beside_open(by) {
                    Some(next) => self.open(next),
                    None => vec![],
                });
            }
            Action::ToggleFiles => {
                files.shown = !files.shown;
                if !files.shown && focused {
                    self.focus = Pane::Views;
                }
                self.sync_focus();
            }
            Action::Folder(key) => {
                match key {
                    FolderKey::Mark => files.toggle_mark(),
                    FolderKey::Sort => files.sort_by_next(false),
                    FolderKey::Reverse => files.sort_by_next(true),
                    FolderKey::Errors => files.toggle_errors(),
                    FolderKey::Uncertain => files.toggle_uncertain(),
                    FolderKey::Format => files.cycle_format(),
                }
                files.shown = true;
            }
            Action::Move(by) | Action::Sideways(by) if focused => files.step(by),
            Action::Select if focused => {
                let row = files.row;
                return Ok(if row == files.open {
                    vec![]
                } else {
                    self.open(row)
                });
            }
            action => return Err(action),
        }
        Ok(vec![])
    }

    /// `/` and `M`: a prompt for a part of a name, or for the manifest's file (with the marked
    /// volumes).
    pub(super) fn ask_folder(&mut self, ask: Ask) -> Vec<Effect> {
        let Some(files) = self.files.as_mut() else {
            return self.say("no folder is open: `slabscope FOLDER` opens one");
        };
        files.shown = true;
        let text = match ask {
            Ask::Manifest if files.marked.is_empty() => {
                return self.say("no volume is marked: Space marks the one under the cursor");
            }
            Ask::Manifest => MANIFEST_NAME.to_string(),
            _ => String::new(),
        };
        self.status.prompt = Some(Prompt { ask, text });
        vec![]
    }

    /// A character typed into the prompt for a name: the cursor goes to the first row that
    /// matches.
    pub(super) fn typed_find(&mut self) {
        if let (Some(files), Some(p)) = (self.files.as_mut(), &self.status.prompt)
            && p.ask == Ask::Find
        {
            files.find(&p.text);
        }
    }

    /// The prompt for a name or a manifest accepted.
    pub(super) fn submit_folder(&mut self, prompt: &Prompt) -> Vec<Effect> {
        let Some(files) = self.files.as_mut() else {
            return vec![];
        };
        let text = prompt.text.trim();
        match prompt.ask {
            Ask::Find if !text.is_empty() && !files.find(text) => {
                self.say(&format!("no volume's name holds {text:?}"))
            }
            Ask::Manifest | Ask::Overwrite if text.is_empty() => self.say("no file named"),
            Ask::Manifest | Ask::Overwrite => {
                // The same name again, once told it exists, replaces it.
                let force = prompt.ask == Ask::Overwrite && files.exists.as_deref() == Some(text);
                vec![Effect::WriteManifest(
                    PathBuf::from(text),
                    files.marked_entries(),
                    force,
                )]
            }
            _ => vec![],
        }
    }

    /// The manifest's file written, or not: a file that exists is asked about again.
    pub(super) fn on_manifest(&mut self, path: &Path, written: Written) -> Vec<Effect> {
        let name = slabscope::error::shown(path);
        match written {
            Written::Done(n) => {
                self.status.message = Some(format!(
                    "wrote {n} volume(s) to {name}: `slabscope triage --manifest {name}` reads it"
                ));
            }
            Written::Exists => {
                if let Some(files) = self.files.as_mut() {
                    files.exists = Some(name.clone());
                }
                self.status.prompt = Some(Prompt {
                    ask: Ask::Overwrite,
                    text: name,
                });
            }
            Written::Failed(e) => self.status.message = Some(e),
        }
        vec![]
    }

    fn say(&mut self, message: &str) -> Vec<Effect> {
        self.status.message = Some(message.to_string());
        vec![]
    }

    /// Whether the open volume's own work runs: loading, the view search, the gain ranking,
    /// the histories, full resolution, a picture.
    pub fn busy(&self) -> bool {
        self.volume.running()
            || self.views.views.running()
            || self.views.gain.running()
            || self.part.histories.running()
            || self.part.upgrading.running()
            || self.upgrade.as_ref().is_some_and(|r| r.views.running())
            || self.preview.image.running()
    }

    /// Holds background triage while the open volume's work runs, lets it go on after: the
    /// effect that says so when that changed.
    pub(super) fn sync_triage(&mut self) -> Vec<Effect> {
        let busy = self.files.is_some() && self.busy();
        if busy == self.triage_held {
            return vec![];
        }
        self.triage_held = busy;
        vec![Effect::PauseTriage(busy)]
    }
}
