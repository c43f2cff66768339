//! The lesson pane's subject follows the focus: the selected viewpoint beside the best while the
//! viewpoint list has it, else the last step taken. A new subject (another axis, ray, step,
//! method or histories) asks for its numbers in the background; the pane shows the newest.

use std::sync::Arc;

use slabscope::partition::Method;

use super::{App, Pane};
use crate::tui::event::{Effect, Task};
use crate::tui::lesson::{Lesson, LessonRequest, Subject};

impl App {
    /// Opens or closes the lesson.
    pub(super) fn toggle_lesson(&mut self) -> Vec<Effect> {
        let lesson = &mut self.lesson;
        lesson.open = !lesson.open;
        (lesson.subject, lesson.lesson) = (None, Task::Idle);
        self.ray = (0, 0);
        self.sync_focus();
        vec![]
    }

    /// Whether ← → move the lesson's ray.
    pub(super) fn moves_ray(&self) -> bool {
        self.lesson.open && matches!(self.lesson.subject, Some(Subject::Axis { .. }))
    }

    /// Moves the lesson's ray `by` rays along the lattice's first in-plane direction.
    pub(super) fn move_ray(&mut self, by: isize) -> Vec<Effect> {
        self.ray.0 += by as i64;
        vec![]
    }

    /// What the lesson should explain now, when it can.
    fn lesson_subject(&self) -> Option<Subject> {
        if self
            .tour
            .as_ref()
            .is_some_and(|t| t.page == super::tour::MODES)
        {
            self.views.views.ready()?;
            Some(Subject::Modes {
                axis: self.views.selected()?,
            })
        } else if self.focus == Pane::Views {
            let views = self.views.views.ready()?;
            Some(Subject::Axis {
                selected: self.views.selected()?,
                best: views.best().axis,
                offset: self.ray,
            })
        } else if let Some((generation, upto)) = self.shown_best_merge() {
            self.part.ready()?;
            Some(Subject::BestMerge { upto, generation })
        } else {
            self.part.ready()?;
            Some(Subject::Step {
                method: self.part.method,
                position: self.part.position,
                generation: self.part.generation(),
            })
        }
    }

    /// The histories' generation and the step shown, while the tour's merge page shows the
    /// merge of the highest NMI taken to it.
    fn shown_best_merge(&self) -> Option<(u64, usize)> {
        let pinned = self.tour.as_ref()?.best_merge;
        (pinned && self.focus != Pane::Views && self.part.method == Method::BottomUp)
            .then(|| (self.part.generation(), self.part.position))
    }

    /// Asks for the lesson of what is selected when that changed.
    pub(super) fn sync_lesson(&mut self) -> Vec<Effect> {
        if !self.lesson.open {
            return vec![];
        }
        let Some(subject) = self.lesson_subject() else {
            let why = if self.focus == Pane::Views {
                "The view search is not done yet: its numbers follow it."
            } else {
                "The partition is not ready yet: its steps follow it."
            };
            self.lesson.subject = None;
            self.lesson.lesson = Task::Ready(Box::new(Lesson::Nothing(why.into())));
            return vec![];
        };
        if self.lesson.subject.as_ref() == Some(&subject) {
            return vec![];
        }
        self.lesson.generation += 1;
        self.lesson.subject = Some(subject.clone());
        self.lesson.lesson = Task::started("explaining");
        let view = self
            .views
            .views
            .ready()
            .map_or_else(|| self.params.view.clone(), |v| v.params.clone());
        vec![Effect::Lesson(Box::new(LessonRequest {
            generation: self.lesson.generation,
            subject,
            volume: self.shown_volume().or(self.volume.ready()).cloned(),
            view,
            histories: self.part.ready().map(Arc::clone),
        }))]
    }

    /// The numbers of lesson request `generation` came.
    pub(super) fn on_lesson(&mut self, generation: u64, result: Result<Box<Lesson>, String>) {
        if generation == self.lesson.generation {
            self.lesson.lesson = match result {
                Ok(lesson) => Task::Ready(lesson),
                Err(e) => Task::Failed(e),
            };
        }
    }
}
