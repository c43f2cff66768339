use super::{Structure, boundaries, boundaries_sentence, structure, structure_sentence};
use crate::partition::{Merge, MergeHistory, Slab};

/// A history of `slices` slices whose merges remove the boundaries at `cuts` in order, with the
/// NMIs `nmis`: each merge joins the slab ending at the cut with the one starting there.
fn history(slices: usize, cuts: &[usize], nmis: &[f64]) -> MergeHistory {
    let mut starts: Vec<usize> = (0..=slices).collect();
    let steps = cuts
        .iter()
        .zip(nmis)
        .map(|(&cut, &nmi)| {
            let i = starts.iter().position(|&s| s == cut).expect("a boundary");
            let merge: (Slab, Slab) = ((starts[i - 1], cut), (cut, starts[i + 1]));
            starts.remove(i);
            Merge {
                merge,
                nmi,
                pairs: Vec::new(),
            }
        })
        .collect();
    MergeHistory::of_steps(slices, steps)
}

/// The NMIs of the last twelve merges of the built-in body's bottom-up history, from 13 slabs
/// to one (as `analyze --method bottomup --slabs 1` gives them).
const BODY: [f64; 12] = [
    0.0138, 0.0106, 0.0108, 0.0094, 0.007, 0.0032, 0.0031, 0.0023, 0.002, 0.0014, 0.0013, 0.003,
];

#[test]
fn the_count_is_where_the_merges_nmi_falls_furthest() {
    // 13 slices, the boundaries removed from the last to the second.
    let cuts: Vec<usize> = (1..13).rev().collect();
    let h = history(13, &cuts, &BODY);
    let s = structure(&h).unwrap();
    // From 9 slabs to 8 the NMI is 0.007, from 8 to 7 it is 0.0032: a fall of 0.0038, the
    // largest between 3 and 8 slabs (9 to 8 and beyond are outside the counts).
    assert_eq!(s.at.slabs, 8);
    assert_eq!((s.last_nmi, s.at.next_nmi), (0.007, 0.0032));
    // Eight slabs: slices 0 to 6 single, then 7–12 built by the five merges taken.
    assert_eq!(h.slabs_after(5).len(), 8);
    assert_eq!(s.at.next, ((6, 7), (7, 13)));
    assert_eq!(s.at.largest, (7, 13));
    assert_eq!(s.at.built, Some((0.0138, 0.007)));
}

#[test]
fn ties_take_the_smallest_count_and_no_fall_gives_none() {
    // The fall at a count is from the merge that reached it to the next one.
    let h = history(6, &[5, 4, 3, 2, 1], &[0.9, 0.5, 0.4, 0.3, 0.2]);
    // Counts 3 to 5 can be reached with a merge after: falls 0.4 (to 5), 0.1 (4), 0.1 (3).
    assert_eq!(structure(&h).unwrap().at.slabs, 5);
    // Equal falls of 0.25 (exact in binary) at 4 and 3 slabs: the smaller count.
    let h = history(6, &[5, 4, 3, 2, 1], &[0.75, 0.75, 0.5, 0.25, 0.0]);
    assert_eq!(structure(&h).unwrap().at.slabs, 3);
    // Rising NMIs never fall.
    let h = history(6, &[5, 4, 3, 2, 1], &[0.1, 0.2, 0.3, 0.4, 0.5]);
    assert_eq!(structure(&h), None);
    // Three slices cannot reach 3 slabs with a merge before it.
    let h = history(3, &[2, 1], &[0.5, 0.1]);
    assert_eq!(structure(&h), None);
}

#[test]
fn boundaries_need_a_merge_after_the_count() {
    let h = history(4, &[3, 1, 2], &[0.8, 0.6, 0.2]);
    assert_eq!(boundaries(&h, 1), None);
    assert_eq!(boundaries(&h, 5), None);
    // Four single slices: the largest is the first, built by no merge.
    let b = boundaries(&h, 4).unwrap();
    assert_eq!(
        (b.next, b.next_nmi, b.largest, b.built),
        (((2, 3), (3, 4)), 0.8, (0, 1), None)
    );
    let b = boundaries(&h, 2).unwrap();
    assert_eq!((b.largest, b.built), ((0, 2), Some((0.6, 0.6))));
    assert_eq!(
        boundaries_sentence(&b),
        "Bottom-up's boundaries stand where neighbours are least alike: at 2 slabs its next \
         merge would join slices 0–1 and slices 2–3 at NMI 0.2000, and no two neighbours left \
         are more alike. Its largest slab, slices 0–1 (2 slices), was built by merges of NMI \
         0.6000 down to 0.6000: slices alike."
    );
}

#[test]
fn the_structure_sentence_names_the_count_and_the_fall() {
    let cuts: Vec<usize> = (1..13).rev().collect();
    let s: Structure = structure(&history(13, &cuts, &BODY)).unwrap();
    let text = structure_sentence(&s);
    assert!(
        text.starts_with(
            "Bottom-up is shown at 8 slabs, where the NMI of its merges falls furthest between \
             3 and 8 slabs (a dendrogram cut at its largest gap): from 0.0070, the last merge \
             taken, to 0.0032, the next. Bottom-up's boundaries"
        ),
        "{text}"
    );
}
