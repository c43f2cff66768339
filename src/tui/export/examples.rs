//! The well-chosen examples the pages show beside the analysis's own steps: the merge of the
//! highest NMI bottom-up took (two slices nearly alike, a joint histogram along its diagonal),
//! where the last merge, the one that leaves the slab count, may join slabs barely alike.

use anyhow::Result;
use slabscope::explain::{MergeLesson, example_merge, merge_lesson};
use slabscope::partition::{Histories, Method, Scope, Step};
use slabscope::{Analysis, AnalysisParams, Monitor, Volume};

/// The merge of the highest NMI among those `bottom` took (the first on ties, below 1 unless
/// every one's is: [`example_merge`]), explained on the histories along its axis with the stack
/// `params` give; `None` when it took none.
pub fn best_merge(
    volume: &Volume,
    bottom: &Analysis,
    params: &AnalysisParams,
    monitor: &Monitor,
) -> Result<Option<MergeLesson>> {
    let nmis: Vec<_> = bottom
        .partition
        .steps
        .iter()
        .map(|s| match s {
            Step::Merge { nmi, .. } => Some(*nmi),
            Step::Split { .. } => None,
        })
        .collect();
    let Some(step) = example_merge(&nmis) else {
        return Ok(None);
    };
    let stack = AnalysisParams {
        method: Method::BottomUp,
        ..params.clone()
    }
    .stack();
    let scope = Scope {
        bottom_up: true,
        optimal_slabs: 0,
        ..Scope::ALL
    };
    let histories = Histories::new(volume, bottom.axis(), &stack, scope, monitor)?;
    Ok(Some(merge_lesson(&histories, step, monitor)?))
}
