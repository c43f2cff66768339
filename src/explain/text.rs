//! The lessons as sentences with their numbers, as `analyze --explain` prints them and the TUI's
//! lesson pane shows them: every number that decides a step, written out with the formula.

use super::{
    AxisLesson, AxisRole, BlockCount, Explain, MergeLesson, ModeLesson, OptimalLesson, SplitLesson,
};
use crate::partition::{Slab, slab_text};

/// `slices 12–40`, or `slice 7` for one.
pub(super) fn slices(s: Slab) -> String {
    let word = if s.1 <= s.0 + 1 { "slice" } else { "slices" };
    format!("{word} {}", slab_text(s))
}

/// `[3 3 4]`.
pub fn block_text(symbols: &[u8]) -> String {
    let inner: Vec<String> = symbols.iter().map(u8::to_string).collect();
    format!("[{}]", inner.join(" "))
}

/// `1,234,567`.
pub fn grouped(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// The `n` most frequent blocks of `table`: `[0 0 0] ×120,000 · [1 1 1] ×5,000`.
pub fn top_blocks(table: &[BlockCount], n: usize) -> String {
    let shown: Vec<String> = table
        .iter()
        .take(n)
        .map(|b| format!("{} ×{}", block_text(&b.symbols), grouped(b.count)))
        .collect();
    shown.join(" · ")
}

/// The lines of the paper's numbers beside the defaults' for one axis.
pub fn mode_lines(m: &ModeLesson) -> Vec<String> {
    let [x, y, z] = m.axis;
    let share = 100.0 * m.background as f64 / m.voxels.max(1) as f64;
    let mut lines = vec![
        format!("h along ({x:.2}, {y:.2}, {z:.2}), bits per sample:"),
        format!(
            "  the paper's lattice  h = {:.4}  (paper mode ranks by it)",
            m.paper_h
        ),
    ];
    if let Some(p) = m.phases {
        lines.push(format!(
            "  mean of {} lattices   h = {:.4}  (defaults rank by it; {:.4}–{:.4})",
            p.n, p.mean, p.min, p.max
        ));
    }
    lines.extend([
        "v_T, the samples the slabs count:".into(),
        format!(
            "  every voxel        v_T = {}  (the paper, paper mode)",
            grouped(m.voxels)
        ),
        format!(
            "  background out     v_T = {}  (defaults: {share:.1}% is background)",
            grouped(m.without_background()),
        ),
        "Why: one lattice lines up with some axes better than others, which moves h by more \
         than the axes differ; air around the object makes every slab's histogram alike."
            .into(),
    ]);
    lines
}

/// The lines of one axis's lesson, headed by `title` (the axis as the caller writes it).
pub fn axis_lines(title: &str, a: &AxisLesson, top: usize) -> Vec<String> {
    let l = a.block;
    let hs: Vec<String> = a
        .block_entropies
        .iter()
        .enumerate()
        .map(|(k, h)| format!("H(X^{}) = {h:.4}", k + 1))
        .collect();
    vec![
        format!(
            "{title}: {} rays, {} samples, {} bins, L = {l}",
            grouped(a.rays),
            grouped(a.samples),
            a.bins
        ),
        format!("  {} bits", hs.join("   ")),
        format!(
            "  h = H(X^{l}) − H(X^{}) = {:.4} − {:.4} = {:.4} bits per sample",
            l - 1,
            a.h_long(),
            a.h_short(),
            a.entropy_rate
        ),
        format!(
            "  {} distinct {l}-blocks, most frequent: {}",
            grouped(a.blocks.len() as u64),
            top_blocks(&a.blocks, top)
        ),
        format!(
            "  {} distinct {}-blocks, most frequent: {}",
            grouped(a.short_blocks.len() as u64),
            l - 1,
            top_blocks(&a.short_blocks, top)
        ),
    ]
}

/// Why the lower rate means more structure: `a` (called `a_name`) beside `b`.
pub fn rate_sentence(a_name: &str, a: &AxisLesson, b_name: &str, b: &AxisLesson) -> String {
    format!(
        "The lower h, the better a sample is predicted from the {} before it along its ray: the \
         {a_name} axis has {:.4} bits per sample, the {b_name} {:.4}, so the volume is more \
         structured along the {}.",
        a.block - 1,
        a.entropy_rate,
        b.entropy_rate,
        if a.entropy_rate <= b.entropy_rate {
            a_name
        } else {
            b_name
        }
    )
}

/// The lines of a split's lesson (`of`: the steps taken).
pub fn split_lines(s: &SplitLesson, of: usize) -> Vec<String> {
    let (a, b) = s.split;
    let [w1, w2] = s.weights;
    let [h1, h2, hu] = s.entropies;
    let [v1, v2] = s.samples;
    let mut best: Vec<(usize, f64)> = s
        .gains
        .iter()
        .enumerate()
        .map(|(i, &g)| (a + 1 + i, g))
        .collect();
    best.sort_by(|x, y| y.1.total_cmp(&x.1).then(x.0.cmp(&y.0)));
    let next = best
        .iter()
        .find(|(c, _)| *c != s.at)
        .map(|(c, g)| format!("; the next best cut of the slab, at {c}, gains {g:.4}"))
        .unwrap_or_default();
    vec![
        format!(
            "Split {} of {of}: {} cut at slice {}, into {} and {}",
            s.step,
            slices((a, b)),
            s.at,
            slices((a, s.at)),
            slices((s.at, b))
        ),
        format!(
            "  part 1: {} samples, π1 = {w1:.4}, H(p1) = {h1:.4} bits",
            grouped(v1)
        ),
        format!(
            "  part 2: {} samples, π2 = {w2:.4}, H(p2) = {h2:.4} bits",
            grouped(v2)
        ),
        format!(
            "  union:  {} samples of the stack's {}, H(p1 + p2) = {hu:.4} bits",
            grouped(v1 + v2),
            grouped(s.total)
        ),
        format!(
            "  JS = H(p1 + p2) − π1·H(p1) − π2·H(p2) = {hu:.4} − {w1:.4}·{h1:.4} − {w2:.4}·{h2:.4} \
             = {:.4} bits",
            s.js
        ),
        format!(
            "  ΔI = (v1 + v2) / v_T · JS = {} / {} · {:.4} = {:.4} bits, the best of the slab's {} \
             cuts{next}",
            grouped(v1 + v2),
            grouped(s.total),
            s.js,
            s.gain,
            s.gains.len()
        ),
        format!(
            "  I(slab; value) after the split: {:.4} bits",
            s.information
        ),
    ]
}

/// The lines of a merge's lesson (`of`: the steps taken).
pub fn merge_lines(m: &MergeLesson, of: usize) -> Vec<String> {
    let (x, y) = m.merge;
    let pairs: u64 = m.joint.iter().map(|c| c[2]).sum();
    let runner = format!("  {}", runner_up(m, slices));
    vec![
        format!(
            "Merge {} of {of}: {} (X) with {} (Y)",
            m.step,
            slices(x),
            slices(y)
        ),
        format!(
            "  joint histogram over corresponding pixels: {} pairs of samples in {} non-zero cells",
            grouped(pairs),
            grouped(m.joint.len() as u64)
        ),
        format!(
            "  H(X) = {:.4} bits, H(Y) = {:.4} bits, H(X,Y) = {:.4} bits",
            m.h_x, m.h_y, m.h_xy
        ),
        format!(
            "  MI = H(X) + H(Y) − H(X,Y) = {:.4} + {:.4} − {:.4} = {:.4} bits",
            m.h_x, m.h_y, m.h_xy, m.mi
        ),
        format!(
            "  NMI = MI / H(X,Y) = {:.4} / {:.4} = {:.4}, the largest of the adjacent pairs",
            m.mi, m.h_xy, m.nmi
        ),
        runner,
    ]
}

/// [`merge_lines`] in five short lines, for a small terminal where the joint histogram needs
/// the room: the merge, the entropies, MI, NMI, the runner-up.
pub fn merge_brief(m: &MergeLesson, of: usize) -> Vec<String> {
    let (x, y) = m.merge;
    vec![
        format!(
            "Merge {} of {of}: {} (X) with {} (Y)",
            m.step,
            slab_text(x),
            slab_text(y)
        ),
        format!(
            "H(X) {:.4}, H(Y) {:.4}, H(X,Y) {:.4} bits",
            m.h_x, m.h_y, m.h_xy
        ),
        format!(
            "MI = {:.4} + {:.4} − {:.4} = {:.4}",
            m.h_x, m.h_y, m.h_xy, m.mi
        ),
        format!("NMI = MI / H(X,Y) = {:.4}", m.nmi),
        runner_up(m, slab_text),
    ]
}

/// The line on a merge's runner-up pair, its slabs named by `name`.
fn runner_up(m: &MergeLesson, name: fn(Slab) -> String) -> String {
    m.runner_up.as_ref().map_or_else(
        || "runner-up: not kept (over 1024 slabs were left)".to_string(),
        |r| {
            format!(
                "runner-up: {} with {}, NMI {:.4}",
                name(r.merge.0),
                name(r.merge.1),
                r.nmi
            )
        },
    )
}

/// The lines of the optimum beside greedy splitting.
pub fn optimal_lines(o: &OptimalLesson) -> Vec<String> {
    let list = |b: &[usize]| {
        let s: Vec<String> = b.iter().map(usize::to_string).collect();
        if s.is_empty() {
            "none".to_string()
        } else {
            s.join(", ")
        }
    };
    let share = if o.optimal > 0.0 {
        format!(" ({:.1}% of it)", 100.0 * o.greedy / o.optimal)
    } else {
        String::new()
    };
    let same = o.optimal_boundaries == o.greedy_boundaries;
    vec![
        format!(
            "Optimum into {} slabs: I(slab; value) = {:.4} bits, the most any {} slabs keep \
             (every placement of the boundaries, by dynamic programming); greedy top-down keeps \
             {:.4} bits{share}",
            o.slabs, o.optimal, o.slabs, o.greedy
        ),
        format!(
            "  boundaries (first slice of each slab after the first): optimal {}; top-down {}{}",
            list(&o.optimal_boundaries),
            list(&o.greedy_boundaries),
            if same { ": the same" } else { "" }
        ),
    ]
}

/// Every line of `explain`, in the order `analyze --explain` prints them; `axis_title` writes
/// an axis for the heading.
pub fn lines(explain: &Explain, axis_title: impl Fn(&AxisLesson) -> String) -> Vec<String> {
    let mut out = Vec::new();
    for a in &explain.axes {
        let role = match a.role {
            AxisRole::Chosen => "chosen axis",
            AxisRole::Worst => "worst axis",
        };
        out.extend(axis_lines(
            &format!("The {role}, {}", axis_title(&a.lesson)),
            &a.lesson,
            5,
        ));
    }
    if let [chosen, worst] = &explain.axes[..] {
        out.push(rate_sentence(
            "chosen",
            &chosen.lesson,
            "worst",
            &worst.lesson,
        ));
    }
    let taken = explain.steps_taken;
    let shown = explain.splits.len() + explain.merges.len();
    if shown < taken {
        out.push(format!("The last {shown} of the {taken} steps:"));
    }
    for s in &explain.splits {
        out.extend(split_lines(s, taken));
    }
    for m in &explain.merges {
        out.extend(merge_lines(m, taken));
    }
    if let Some(o) = &explain.optimal {
        out.extend(optimal_lines(o));
    }
    out.extend(explain.notes.iter().map(|n| format!("note: {n}")));
    out
}
