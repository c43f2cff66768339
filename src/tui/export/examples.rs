//! The well-chosen examples the merge pages show beside the analysis's own steps, as the TUI's
//! tour shows them: bottom-up at the slab count where its history shows structure
//! ([`structure`]), the merge of the highest NMI taken to it (two slices nearly alike, a joint
//! histogram along its diagonal) where the last merge may join slabs barely alike, and why the
//! boundaries of the analysis's own count stand where they do.

use anyhow::Result;
use serde_json::{Value, json};
use slabscope::explain::text;
use slabscope::explain::{
    Boundaries, MergeLesson, Structure, boundaries, example_merge, merge_lesson, structure,
};
use slabscope::partition::{Histories, Method, Scope};
use slabscope::{AnalysisParams, Monitor, Volume};

/// The merge pages' examples.
pub struct Merges {
    /// The slab count where bottom-up's history shows structure, and why; `None` when it shows
    /// none (the pages keep the analysis's count).
    pub structure: Option<Structure>,
    /// The count the merge page shows: the structure's, or the analysis's.
    pub slabs: usize,
    /// The merge of the highest NMI taken to `slabs` slabs (below 1 unless every one's is:
    /// [`example_merge`]).
    pub best: Option<MergeLesson>,
    /// The last merge taken to `slabs` slabs.
    pub last: Option<MergeLesson>,
    /// What holds the boundaries at the analysis's own count, beside top-down's.
    pub given: Option<Boundaries>,
}

/// The merge pages' examples of bottom-up along `axis`, whose analysis gives `given` slabs, on
/// the histories of the stack `params` give.
pub fn merges(
    volume: &Volume,
    axis: [f64; 3],
    params: &AnalysisParams,
    given: usize,
    monitor: &Monitor,
) -> Result<Merges> {
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
    let histories = Histories::new(volume, axis, &stack, scope, monitor)?;
    let Some(history) = histories.bottom() else {
        anyhow::bail!("the bottom-up history was not computed");
    };
    let structure = structure(history);
    let slabs = structure.as_ref().map_or(given, |s| s.at.slabs);
    let taken = history.slices.saturating_sub(slabs);
    let nmis: Vec<_> = history.steps[..taken].iter().map(|m| Some(m.nmi)).collect();
    let lesson = |step: Option<usize>| -> Result<Option<MergeLesson>> {
        Ok(step
            .map(|s| merge_lesson(&histories, s, monitor))
            .transpose()?)
    };
    let best = lesson(example_merge(&nmis))?;
    let last = lesson((taken > 0).then_some(taken))?;
    Ok(Merges {
        structure,
        slabs,
        best,
        last,
        given: boundaries(history, given),
    })
}

impl Merges {
    /// The numbers and lines of the page of a merge: bottom-up at the count where its history
    /// shows structure and why, the example the TUI's page shows in full (the merge of the
    /// highest NMI below 1 unless every merge's NMI is 1: [`example_merge`]), and the last
    /// merge to the count in a line after it.
    pub fn page(&self) -> (Value, Vec<String>) {
        let Some(last) = &self.last else {
            return (Value::Null, Vec::new());
        };
        let mut numbers = json!(last);
        numbers["slabs"] = json!(self.slabs);
        numbers["structure"] = json!(self.structure);
        let taken = last.step;
        let mut lines: Vec<String> = self
            .structure
            .iter()
            .map(slabscope::explain::structure_sentence)
            .collect();
        let Some(best) = &self.best else {
            lines.extend(text::merge_lines(last, taken));
            return (numbers, lines);
        };
        numbers["highest_nmi"] = json!(best);
        let below = if best.nmi < 1.0 { " below 1" } else { "" };
        lines.push(format!("The merge of the highest NMI{below}:"));
        lines.extend(text::merge_lines(best, taken));
        lines.push(format!(
            "The last merge, to {} slabs: step {}, {} and {}, NMI = {:.4}",
            self.slabs,
            last.step,
            super::charts::slices(last.merge.0),
            super::charts::slices(last.merge.1),
            last.nmi
        ));
        (numbers, lines)
    }
}
