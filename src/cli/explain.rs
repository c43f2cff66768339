//! `analyze --explain` as text: the library's lesson lines, under a heading.

use slabscope::explain::{Explain, text};

/// Prints the lessons of `explain` after the analysis.
pub fn print(explain: &Explain) {
    outln!();
    outln!("Explained (the numbers behind the axis and the steps)");
    for line in text::lines(explain, |a| axis_title(a.axis, a.world.anatomy.as_deref())) {
        outln!("  {}", slabscope::error::names::controls(&line));
    }
}

/// `[ 0.000, 0.000, 1.000] (z), I→S axial`.
fn axis_title(axis: [f64; 3], anatomy: Option<&str>) -> String {
    let named = super::text::axis_text(axis);
    match anatomy {
        Some(a) => format!("{named}, {a}"),
        None => named,
    }
}
