//! What the lesson pane (key `x`) explains, and its numbers, computed in the background from the
//! library's `explain` (the same values `analyze --explain` prints).

use std::sync::Arc;

use slabscope::explain::{
    AxisLesson, MergeLesson, ModeLesson, OptimalLesson, RayPlane, RaySamples, SplitLesson,
    axis_lesson, example_merge, merge_lesson, mode_lesson, optimal_lesson, ray_plane, ray_samples,
    split_lesson,
};
use slabscope::partition::Method;
use slabscope::{Histories, Monitor, ViewParams, Volume};

/// What the lesson is about: the selected viewpoint beside the best, or the step shown.
#[derive(Clone, Debug, PartialEq)]
pub enum Subject {
    /// The selected axis beside the best, and the ray shown: `offset` rays from the central one.
    Axis {
        /// The selected axis.
        selected: [f64; 3],
        /// The best axis of the view search.
        best: [f64; 3],
        /// The ray's offset from the central ray, along the lattice's two in-plane directions.
        offset: (i64, i64),
    },
    /// The paper's numbers beside the defaults' for the selected axis (the tour's page on the
    /// modes).
    Modes {
        /// The selected axis.
        axis: [f64; 3],
    },
    /// The last step taken to reach `position` of `method`'s history (for the optimum: the
    /// partition into `position + 1` slabs).
    Step {
        /// The method.
        method: Method,
        /// The position in its history.
        position: usize,
        /// The histories' request generation, so that new histories are a new subject.
        generation: u64,
    },
    /// The merge of the highest NMI below 1 among the first `upto` bottom-up took (the tour's
    /// page on a merge: the last one may join slabs barely alike;
    /// [`example_merge`]), beside the step shown, `upto`.
    BestMerge {
        /// The step shown: the merges taken to the slab count shown.
        upto: usize,
        /// The histories' request generation.
        generation: u64,
    },
}

/// A lesson to compute.
#[derive(Clone)]
pub struct LessonRequest {
    /// Its number: only the newest request's answer is shown.
    pub generation: u64,
    /// What it explains.
    pub subject: Subject,
    /// The volume (or pyramid level) the views were searched on.
    pub volume: Option<Arc<Volume>>,
    /// The view search's parameters, spacings resolved.
    pub view: ViewParams,
    /// The histories the step belongs to.
    pub histories: Option<Arc<Histories>>,
}

/// A lesson's numbers.
pub enum Lesson {
    /// The selected axis beside the best, each with the ray through (or near) the centre.
    Axis {
        /// The selected axis's numbers.
        selected: Box<AxisLesson>,
        /// Its ray.
        ray: Option<RaySamples>,
        /// The plane of rays the ray lies in.
        plane: Option<RayPlane>,
        /// The best axis's numbers.
        best: Box<AxisLesson>,
    },
    /// A top-down split.
    Split(Box<SplitLesson>),
    /// A bottom-up merge, and the merges of its history.
    Merge(Box<MergeLesson>, usize),
    /// The merge of the highest NMI among the first `upto` (the step shown), and the merges of
    /// its history.
    BestMerge {
        /// The merge.
        merge: Box<MergeLesson>,
        /// The step shown.
        upto: usize,
        /// The merges of the history.
        of: usize,
    },
    /// The optimum beside greedy top-down.
    Optimal(OptimalLesson),
    /// The paper's numbers beside the defaults'.
    Modes(Box<ModeLesson>),
    /// Nothing to explain yet, and why.
    Nothing(String),
}

impl LessonRequest {
    /// The lesson's numbers (a pass over the volume for an axis, over the stack for a merge).
    pub fn compute(&self, monitor: &Monitor) -> Result<Lesson, String> {
        let text = |e: slabscope::Error| e.to_string();
        match &self.subject {
            Subject::Axis {
                selected,
                best,
                offset,
            } => {
                let volume = self
                    .volume
                    .as_deref()
                    .ok_or("the volume is not loaded yet")?;
                let lesson = |axis| axis_lesson(volume, axis, &self.view, monitor).map(Box::new);
                Ok(Lesson::Axis {
                    selected: lesson(*selected).map_err(text)?,
                    ray: ray_samples(volume, *selected, &self.view, *offset).map_err(text)?,
                    plane: ray_plane(volume, *selected, &self.view, *offset).map_err(text)?,
                    best: lesson(*best).map_err(text)?,
                })
            }
            Subject::Modes { axis } => {
                let volume = self
                    .volume
                    .as_deref()
                    .ok_or("the volume is not loaded yet")?;
                let lesson = mode_lesson(volume, *axis, &self.view, monitor).map_err(text)?;
                Ok(Lesson::Modes(Box::new(lesson)))
            }
            Subject::Step {
                method, position, ..
            } => {
                let h = self
                    .histories
                    .as_deref()
                    .ok_or("the partition is not ready yet")?;
                let position = *position;
                Ok(match method {
                    _ if position == 0 && *method != Method::Optimal => Lesson::Nothing(
                        "No step taken yet: n takes the first, and the lesson follows it.".into(),
                    ),
                    Method::TopDown => {
                        Lesson::Split(Box::new(split_lesson(h, position).map_err(text)?))
                    }
                    Method::BottomUp => {
                        let m = merge_lesson(h, position, monitor).map_err(text)?;
                        Lesson::Merge(Box::new(m), h.last(Method::BottomUp))
                    }
                    Method::Optimal => match optimal_lesson(h, position + 1) {
                        Some(o) => Lesson::Optimal(o),
                        None => Lesson::Nothing("The optimum was not computed here.".into()),
                    },
                })
            }
            Subject::BestMerge { upto, .. } => {
                let h = self
                    .histories
                    .as_deref()
                    .ok_or("the partition is not ready yet")?;
                let steps = h.bottom().map_or(&[][..], |b| &b.steps);
                let nmis: Vec<_> = steps.iter().take(*upto).map(|s| Some(s.nmi)).collect();
                let step = example_merge(&nmis).ok_or("no merge taken yet")?;
                Ok(Lesson::BestMerge {
                    merge: Box::new(merge_lesson(h, step, monitor).map_err(text)?),
                    upto: *upto,
                    of: h.last(Method::BottomUp),
                })
            }
        }
    }
}
