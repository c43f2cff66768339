//! The numbers behind each step, for teaching (docs/design.md §6): why the chosen axis has the
//! lowest entropy rate (its block counts beside the worst axis's), why top-down split where it
//! did (the parts' histograms, JS and ΔI), why bottom-up merged what it did (the joint histogram
//! and NMI), and what the optimum keeps beside greedy splitting. `analyze --explain`, the TUI's
//! lesson pane and the tour all show these values, computed here once.

mod axis;
pub mod figure;
mod modes;
mod steps;
mod structure;
pub mod text;
mod worked;

use serde::Serialize;

pub use axis::{
    AxisLesson, BlockCount, RayPlane, RaySamples, axis_lesson, axis_lesson_within, ray_plane,
    ray_samples, table_entropy,
};
pub use modes::{ModeLesson, mode_lesson};
pub use steps::{
    MergeLesson, OptimalLesson, RunnerUp, SplitLesson, example_merge, highest_nmi_merge,
    merge_lesson, merge_lessons, optimal_lesson, split_lesson,
};

pub use structure::{
    Boundaries, COUNTS, Structure, boundaries, boundaries_brief, boundaries_sentence, structure,
    structure_brief, structure_sentence,
};
pub use worked::{JsExample, NmiExample, RayExample, Worked, worked};

use crate::error::Result;
use crate::partition::{Histories, Method, Partition};
use crate::progress::Monitor;
use crate::view::{ViewParams, ViewSearch};
use crate::volume::Volume;

/// Steps explained by default: the last this many of the method's history.
pub const DEFAULT_STEPS: usize = 32;

/// Which steps to explain.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StepsShown {
    /// The last this many steps taken.
    Last(usize),
    /// Every step taken.
    All,
}

impl Default for StepsShown {
    fn default() -> Self {
        Self::Last(DEFAULT_STEPS)
    }
}

/// The role of an axis in the lesson.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum AxisRole {
    /// The axis partitioned along.
    Chosen,
    /// The axis of the highest entropy rate on the sphere: the least structured view.
    Worst,
}

/// One axis of the lesson with its role.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ExplainedAxis {
    /// Which axis this is.
    pub role: AxisRole,
    /// Its numbers.
    #[serde(flatten)]
    pub lesson: AxisLesson,
}

/// Everything `analyze --explain` shows.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Explain {
    /// The chosen axis, then (when the view search ran) the worst.
    pub axes: Vec<ExplainedAxis>,
    /// The partition's method.
    pub method: Method,
    /// Steps the method took.
    pub steps_taken: usize,
    /// The top-down splits explained, oldest first.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub splits: Vec<SplitLesson>,
    /// The bottom-up merges explained, oldest first.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub merges: Vec<MergeLesson>,
    /// The optimum at the partition's slab count beside top-down's, when it was computed.
    pub optimal: Option<OptimalLesson>,
    /// What could not be explained, and why.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
}

/// The lesson of an analysis: its axes on `views_volume` (the level the view search ran on) by
/// the search's parameters, counted slab by slab within `room` bytes when the search was
/// ([`axis_lesson_within`]), and the steps of `partition` from the `histories` it came from.
pub fn explain(
    (views_volume, room): (&Volume, Option<u64>),
    search: Option<&ViewSearch>,
    view: &ViewParams,
    histories: &Histories,
    partition: &Partition,
    shown: StepsShown,
    monitor: &Monitor,
) -> Result<Explain> {
    let params = search.map_or(view, |s| &s.params);
    let mut axes = vec![ExplainedAxis {
        role: AxisRole::Chosen,
        lesson: axis_lesson_within(views_volume, partition.axis, params, room, monitor)?,
    }];
    if let Some(worst) = search.and_then(|s| s.views.iter().rev().find(|v| v.measured())) {
        axes.push(ExplainedAxis {
            role: AxisRole::Worst,
            lesson: axis_lesson_within(views_volume, worst.axis, params, room, monitor)?,
        });
    }
    let taken = partition.steps.len();
    let first = match shown {
        StepsShown::All => 0,
        StepsShown::Last(n) => taken.saturating_sub(n),
    };
    let mut out = Explain {
        axes,
        method: partition.method,
        steps_taken: taken,
        splits: Vec::new(),
        merges: Vec::new(),
        optimal: optimal_lesson(histories, partition.slabs.len()),
        notes: Vec::new(),
    };
    match partition.method {
        Method::TopDown => {
            out.splits = (first + 1..=taken)
                .map(|s| split_lesson(histories, s))
                .collect::<Result<_>>()?;
        }
        Method::BottomUp => {
            out.merges = merge_lessons(histories, first + 1..=taken, monitor)?;
        }
        Method::Optimal => {}
    }
    if out.optimal.is_none() && partition.slabs.len() > 1 {
        out.notes
            .push("the optimum is not compared: it was not computed for this stack".to_string());
    }
    Ok(out)
}
