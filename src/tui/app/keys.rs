//! The app's key handling: [`App::update`] takes an action, lets an open prompt or the folder's pane
//! have it first, and turns it into a change of state (cursor, pointer, look, window, the
//! partition's position) and the effects that follow.

use slabscope::render::{Colormap, Gap, Mode, Preset};
use slabscope::volume::background::BackgroundRule;

use super::{App, Pane, centre};
use crate::tui::event::{Action, Ask, Effect, Task};
use crate::tui::panes::status::{Prompt, settings_text};

impl App {
    /// Applies `action`; returns what the event loop must do (and the lesson's numbers when
    /// what it explains changed).
    pub fn update(&mut self, action: Action) -> Vec<Effect> {
        let mut effects = self.apply(action);
        effects.extend(self.sync_tour());
        effects.extend(self.sync_lesson());
        effects.extend(self.sync_triage());
        effects
    }

    /// [`update`](Self::update) but for the lesson.
    fn apply(&mut self, action: Action) -> Vec<Effect> {
        let action = match self.on_prompt(action) {
            Ok(effects) => return effects,
            Err(action) => action,
        };
        let action = match self.on_files(action) {
            Ok(effects) => return effects,
            Err(action) => action,
        };
        self.leave_best_merge(&action);
        match action {
            Action::Quit => {
                self.quit = true;
                vec![Effect::Cancel, Effect::Quit]
            }
            Action::ToggleHelp => {
                self.help = !self.help;
                self.sync_focus();
                vec![]
            }
            Action::Escape => self.escape(),
            Action::Focus(by) => {
                let folder = self.files.as_ref().is_some_and(|f| f.shown);
                self.focus = self.focus.step(by, folder);
                self.sync_focus();
                vec![]
            }
            Action::Sideways(by) if self.moves_ray() => self.move_ray(by),
            Action::Sideways(by) if self.pointing() => self.move_pointer(by, 0),
            Action::Move(by) | Action::Sideways(by) => self.move_cursor(by),
            Action::Page(by) => self.move_cursor(by * 10),
            Action::ToggleSlices => {
                self.preview.slices = !self.preview.slices;
                self.preview.caption = None;
                self.render()
            }
            Action::WindowWidth(_) | Action::WindowLevel(_) => self.window(&action),
            Action::Select => self.select(),
            Action::Step(by) => match self.part.step(by) {
                Ok(()) => self.after_step(),
                Err(message) => {
                    self.status.message = Some(message.into());
                    vec![]
                }
            },
            Action::StepTo(end) => {
                self.part.step_to(end);
                self.after_step()
            }
            Action::Slabs(by) => {
                self.part.change_slabs(by);
                self.after_step()
            }
            Action::CycleMethod => {
                self.part.cycle_method();
                self.after_step()
            }
            Action::Ask(ask @ (Ask::Find | Ask::Manifest)) => self.ask_folder(ask),
            Action::Ask(ask) => {
                self.status.prompt = Some(Prompt {
                    ask,
                    text: String::new(),
                });
                vec![]
            }
            Action::Type(_) | Action::Erase | Action::Submit => vec![],
            Action::Export => self.export(),
            Action::ToggleBackground => self.toggle_background(),
            Action::RankGain => self.rank_gain(),
            Action::ToggleLesson => self.toggle_lesson(),
            Action::TurnPage(by) => self.turn_page(by),
            Action::PreviewArea(w, h) => {
                if (w, h) == self.preview.cells {
                    return vec![];
                }
                self.preview.cells = (w, h);
                self.render()
            }
            Action::Job(msg) => self.on_job(msg),
            look => self.restyle(&look),
        }
    }

    /// While a prompt is open, keys type into it: `Ok` with the effects when the prompt took the
    /// action, `Err` with the action when it goes on (jobs, resizes, quitting).
    fn on_prompt(&mut self, action: Action) -> Result<Vec<Effect>, Action> {
        let Some(prompt) = self.status.prompt.as_mut() else {
            return Err(action);
        };
        match action {
            Action::Type(c) => {
                prompt.text.push(c);
                self.typed_find();
            }
            Action::Erase => {
                prompt.text.pop();
            }
            Action::Escape => self.status.prompt = None,
            Action::Submit => return Ok(self.submit()),
            Action::Job(_) | Action::PreviewArea(..) | Action::Quit => return Err(action),
            _ => {}
        }
        Ok(vec![])
    }

    /// Changes the look of the preview, which re-renders.
    fn restyle(&mut self, action: &Action) -> Vec<Effect> {
        let stats = self.shown_volume().map(|v| v.stats());
        let l = &mut self.preview.look;
        match *action {
            Action::Orbit(az, el) => {
                l.camera.azimuth = (l.camera.azimuth + az).rem_euclid(360.0);
                l.camera.elevation = (l.camera.elevation + el).clamp(-85.0, 85.0);
            }
            Action::Zoom(f) => l.camera.zoom = (l.camera.zoom * f).clamp(0.25, 8.0),
            Action::Spread(d) => l.spread = (l.spread + d).clamp(0.0, 2.0),
            Action::ToggleMode => l.mode = next(&[Mode::Cut, Mode::Dvr, Mode::Mip], l.mode),
            Action::CycleTransfer => {
                // Only the presets that fit the volume: no CT windows on an MRI.
                let fits: Vec<Preset> = Preset::ALL
                    .into_iter()
                    .filter(|p| stats.is_none_or(|s| p.suits(s)))
                    .collect();
                l.preset = next(&fits, l.preset);
                l.window = None;
                self.preview.window = None;
            }
            Action::CycleColormap => l.colormap = next(&Colormap::ALL, l.colormap),
            Action::ToggleGap => l.gap = next(&[Gap::Uniform, Gap::Similarity], l.gap),
            Action::ToggleSolo => l.solo = !l.solo,
            Action::TogglePerspective => l.camera.perspective = !l.camera.perspective,
            _ => return vec![],
        }
        self.render()
    }

    fn escape(&mut self) -> Vec<Effect> {
        if self.help {
            self.help = false;
            self.sync_focus();
            return vec![];
        }
        if self.lesson.open {
            return self.toggle_lesson();
        }
        let upgrading = self.cancel_upgrade();
        let busy = self.views.views.running()
            || self.part.histories.running()
            || self.preview.image.running()
            || self.export.running();
        if !busy && !upgrading {
            return vec![];
        }
        if self.views.views.running() {
            self.views.views = Task::Failed("cancelled".into());
        }
        if self.part.histories.running() {
            self.part.histories = Task::Failed("cancelled".into());
        }
        // A picture cancelled sends nothing: it is not awaited.
        if self.preview.image.running() {
            self.preview.image = Task::Failed("cancelled".into());
        }
        self.export = Task::Idle;
        self.status.message = Some(if upgrading {
            "cancelled: the preview stays (Enter on an axis computes it again)".into()
        } else {
            "cancelled".into()
        });
        self.sync();
        vec![Effect::Cancel]
    }

    fn move_cursor(&mut self, by: isize) -> Vec<Effect> {
        let shift = |v: usize, len: usize| {
            (v as isize + by).clamp(0, len.saturating_sub(1) as isize) as usize
        };
        match self.focus {
            Pane::Views => {
                self.views.row = shift(self.views.row, self.views.len());
                vec![]
            }
            Pane::Slabs => {
                self.slabs.row = shift(self.slabs.row, self.slabs.len());
                self.render()
            }
            Pane::Curves => {
                self.curves.cursor = shift(self.curves.cursor, self.curves.len());
                if self.preview.slices {
                    self.render()
                } else {
                    vec![]
                }
            }
            Pane::Files => vec![],
            Pane::Preview if self.pointing() => self.move_pointer(0, by),
            Pane::Preview => self.restyle(&Action::Orbit(by as f64 * 15.0, 0.0)),
        }
    }

    /// Whether the arrows move the slice view's pointer.
    fn pointing(&self) -> bool {
        self.focus == Pane::Preview && self.preview.slices
    }

    /// Moves the slice view's pointer by voxels to the right and down on the screen.
    fn move_pointer(&mut self, right: isize, down: isize) -> Vec<Effect> {
        let (Some(volume), Some(axis)) = (self.shown_volume(), self.part.axis) else {
            return vec![];
        };
        let Ok(frame) = slabscope::render::slice::SliceFrame::new(volume, axis) else {
            return vec![];
        };
        let spacing = volume.spacing();
        let dims = volume.dims();
        let step = slabscope::geometry::min_spacing(spacing);
        let p = self.preview.pointer.unwrap_or_else(|| centre(volume));
        self.preview.pointer = Some(std::array::from_fn(|m| {
            let moved = p[m] + step * (right as f64 * frame.right[m] - down as f64 * frame.up[m]);
            moved.clamp(0.0, (dims[m] - 1) as f64 * spacing[m])
        }));
        self.render()
    }

    /// Narrows, widens or moves the window of the picture and the slices, starting from the
    /// one the last picture used (the preset's, worked out here only before any picture).
    fn window(&mut self, action: &Action) -> Vec<Effect> {
        let Some(volume) = self.shown_volume().cloned() else {
            return vec![];
        };
        let look = &mut self.preview.look;
        let (lo, hi) = match look.window.or(self.preview.window) {
            Some(w) => w,
            None => {
                match slabscope::render::Transfer::new(
                    &volume,
                    look.preset,
                    look.colormap,
                    1.0,
                    1.0,
                ) {
                    Ok(t) => t.window(),
                    Err(_) => return vec![],
                }
            }
        };
        let (level, width) = (f32::midpoint(lo, hi), (hi - lo).max(f32::EPSILON));
        let (level, width) = match *action {
            Action::WindowWidth(f) => (level, width * f),
            Action::WindowLevel(f) => (level + f * width, width),
            _ => (level, width),
        };
        look.window = Some((level - width / 2.0, level + width / 2.0));
        self.render()
    }

    fn select(&mut self) -> Vec<Effect> {
        match (self.focus, self.views.selected()) {
            (Pane::Views, Some(axis)) => self.analyze_chosen(axis),
            _ => vec![],
        }
    }

    fn submit(&mut self) -> Vec<Effect> {
        let Some(prompt) = self.status.prompt.take() else {
            return vec![];
        };
        if matches!(prompt.ask, Ask::Find | Ask::Manifest | Ask::Overwrite) {
            return self.submit_folder(&prompt);
        }
        let text = prompt.text.trim();
        match prompt.ask {
            Ask::Axis => {
                if let Ok(axis) = text.parse::<slabscope::Axis>() {
                    self.analyze_chosen(axis.direction())
                } else {
                    self.status.message = Some(format!("{text:?} is not x, y, z or DX,DY,DZ"));
                    vec![]
                }
            }
            Ask::Threshold if text.is_empty() => {
                self.part.set_threshold(None);
                self.status.message = Some("threshold cleared".into());
                self.sync();
                vec![]
            }
            Ask::Find | Ask::Manifest | Ask::Overwrite => vec![],
            Ask::Threshold => match text.parse::<f64>() {
                Ok(t) if t.is_finite() => {
                    self.part.set_threshold(Some(t));
                    self.after_step()
                }
                _ => {
                    self.status.message = Some(format!("{text:?} is not a number"));
                    vec![]
                }
            },
        }
    }

    /// Leaves the background out of the slabs (found automatically), or counts every voxel as
    /// the paper does; the histories along the axis are computed again.
    fn toggle_background(&mut self) -> Vec<Effect> {
        let rule = match self.params.background {
            BackgroundRule::None => BackgroundRule::Auto,
            _ => BackgroundRule::None,
        };
        self.params.background = rule;
        self.part.stack.background = rule;
        self.status.settings = settings_text(&self.params);
        self.status.message = Some(match rule {
            BackgroundRule::None => "background counted: every voxel is in the slabs".into(),
            _ => "background left out: the region connected to the border, found from it".into(),
        });
        match self.part.axis {
            Some(axis) => self.analyze(axis),
            None => vec![],
        }
    }
}

/// The element after `current` in `all`, wrapping around.
fn next<T: Copy + PartialEq>(all: &[T], current: T) -> T {
    let i = all.iter().position(|x| *x == current).unwrap_or(0);
    all[(i + 1) % all.len()]
}
