//! Where bottom-up's history shows structure, and why its boundaries fall where they do: the
//! tour's bottom-up pages show the slab count at which the NMI of its merges falls furthest (as
//! a dendrogram is cut at its largest gap between successive merge heights), and say what holds
//! each boundary there, from the history itself.

use std::fmt::Write as _;
use std::ops::RangeInclusive;

use serde::Serialize;

use super::text::slices;
use crate::partition::{MergeHistory, Slab};

/// The slab counts the structured count is chosen among: few enough to read in a table and a
/// picture, more than top-down's first split.
pub const COUNTS: RangeInclusive<usize> = 3..=8;

/// Why bottom-up's partition into `slabs` slabs has its boundaries where they are.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Boundaries {
    /// The slab count.
    pub slabs: usize,
    /// The merge it would take next, from `slabs` slabs to one fewer: the two neighbours most
    /// alike of those left.
    pub next: (Slab, Slab),
    /// Their NMI: no two neighbours left are more alike.
    pub next_nmi: f64,
    /// The slab of the most slices (the first on ties).
    pub largest: Slab,
    /// The highest and the lowest NMI of the merges that built `largest`; `None` for a slab of
    /// one slice.
    pub built: Option<(f64, f64)>,
}

/// The slab count at which bottom-up's history shows structure.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Structure {
    /// The NMI of the last merge taken to reach the count, from one slab more.
    pub last_nmi: f64,
    /// The partition at the count, and what holds its boundaries.
    pub at: Boundaries,
}

/// What holds the boundaries of `history`'s partition into `slabs` slabs: `None` when the
/// history does not reach that count and take one merge after it (`slabs` of 1, or more than
/// the slices).
pub fn boundaries(history: &MergeHistory, slabs: usize) -> Option<Boundaries> {
    let taken = history.slices.checked_sub(slabs)?;
    let next = history.steps.get(taken).filter(|_| slabs > 1)?;
    let parts = history.slabs_after(taken);
    // The first of the most slices on ties: `max_by_key` keeps the last, so count from the end.
    let largest = *parts.iter().rev().max_by_key(|(a, b)| b - a)?;
    let inside = history.steps[..taken]
        .iter()
        .filter(|m| m.merge.0.0 >= largest.0 && m.merge.1.1 <= largest.1)
        .map(|m| m.nmi);
    let built = inside.fold(None, |seen: Option<(f64, f64)>, nmi| {
        Some(seen.map_or((nmi, nmi), |(hi, lo)| (hi.max(nmi), lo.min(nmi))))
    });
    Some(Boundaries {
        slabs,
        next: next.merge,
        next_nmi: next.nmi,
        largest,
        built,
    })
}

/// The count among [`COUNTS`] at which the NMI of `history`'s merges falls furthest, from the
/// last merge taken to reach it to the next one, the smallest count on ties; `None` when the
/// history reaches none of them with a merge before and after, or its NMI never falls there.
pub fn structure(history: &MergeHistory) -> Option<Structure> {
    let nmi_from = |slabs: usize| Some(history.steps.get(history.slices.checked_sub(slabs)?)?.nmi);
    let mut best: Option<(usize, f64, f64)> = None;
    for slabs in COUNTS {
        let (Some(last), Some(next)) = (nmi_from(slabs + 1), nmi_from(slabs)) else {
            continue;
        };
        let fall = last - next;
        if fall > 0.0 && best.is_none_or(|(_, l, n)| fall > l - n) {
            best = Some((slabs, last, next));
        }
    }
    let (slabs, last_nmi, _) = best?;
    Some(Structure {
        last_nmi,
        at: boundaries(history, slabs)?,
    })
}

/// The sentence on what holds `b`'s boundaries.
pub fn boundaries_sentence(b: &Boundaries) -> String {
    let (x, y) = b.next;
    let mut text = format!(
        "Bottom-up's boundaries stand where neighbours are least alike: at {} slabs its next \
         merge would join {} and {} at NMI {:.4}, and no two neighbours left are more alike.",
        b.slabs,
        slices(x),
        slices(y),
        b.next_nmi
    );
    if let Some((hi, lo)) = b.built {
        let (a, z) = b.largest;
        let _ = write!(
            text,
            " Its largest slab, {} ({} slices), was built by merges of NMI {hi:.4} down to \
             {lo:.4}: slices alike.",
            slices(b.largest),
            z - a
        );
    }
    text
}

/// The sentence on why the bottom-up pages show `s`'s count, then what holds its boundaries.
pub fn structure_sentence(s: &Structure) -> String {
    format!(
        "Bottom-up is shown at {} slabs, where the NMI of its merges falls furthest between {} \
         and {} slabs (a dendrogram cut at its largest gap): from {:.4}, the last merge taken, \
         to {:.4}, the next. {}",
        s.at.slabs,
        COUNTS.start(),
        COUNTS.end(),
        s.last_nmi,
        s.at.next_nmi,
        boundaries_sentence(&s.at)
    )
}

/// [`structure_sentence`] in a line, for the tour's page on a small terminal.
pub fn structure_brief(s: &Structure) -> String {
    format!(
        "Shown at {} slabs, where the merges' NMI falls furthest: {:.4}, then {:.4}.",
        s.at.slabs, s.last_nmi, s.at.next_nmi
    )
}

/// [`boundaries_sentence`] in a line, for the tour's page on a small terminal.
pub fn boundaries_brief(b: &Boundaries) -> String {
    format!(
        "Bottom-up cuts where neighbours are least alike: no pair left has NMI above {:.4}.",
        b.next_nmi
    )
}

#[cfg(test)]
mod tests;
