//! The analysis as text for people: the views with the verdict on the best, then the slabs.
//! Slab ranges read `slices 0–44`, inclusive; the JSON keeps half-open `[start, end)`.

use slabscope::analysis::{AxisBy, GainRanking};
use slabscope::geometry::WorldAxis;
use slabscope::partition::{Step, slab_text};
use slabscope::view::{AxisEntropy, RankedBy, ViewSearch, icosphere, score};
use slabscope::volume::dims_string;
use slabscope::{Analysis, Axis, Partition, Volume};

/// Prints the whole analysis of `volume`, read from `name`.
pub fn print_analysis(name: &str, volume: &Volume, analysis: &Analysis) {
    if let Some(v) = &analysis.views {
        let gain_pick = analysis
            .gain
            .as_ref()
            .filter(|_| analysis.axis_by == Some(AxisBy::Gain));
        print_views(name, volume, v, gain_pick);
        if let Some(g) = &analysis.gain {
            outln!();
            print_gain(v, g, analysis.axis_by);
        }
        outln!();
    }
    print_partition(&analysis.partition);
    print_notes(&analysis.notes);
}

/// `[ 0.000, 0.000, 1.000] (z)`, or without the name for an oblique axis.
pub(super) fn axis_text(axis: [f64; 3]) -> String {
    Axis::new(axis).map_or_else(|_| format!("{axis:?}"), Axis::labelled)
}

/// The axis with its anatomical name and world normal when the orientation is known:
/// `[ 0.000, 0.000, 1.000] (z), I→S axial, world normal [0.000, 0.000, 1.000]`.
fn world_axis_text(axis: [f64; 3], world: &WorldAxis) -> String {
    if !world.oriented {
        return axis_text(axis);
    }
    let [x, y, z] = world.world_axis;
    format!(
        "{} {}, world normal [{x:.3}, {y:.3}, {z:.3}]",
        axis_text(axis),
        world.anatomy_text()
    )
}

/// `1 slab`, `4 slabs`: `n` and the word for one or for many.
fn count(n: usize, one: &str, many: &str) -> String {
    if n == 1 {
        format!("1 {one}")
    } else {
        format!("{n} {many}")
    }
}

fn print_views(name: &str, volume: &Volume, v: &ViewSearch, gain_pick: Option<&GainRanking>) {
    let p = &v.params;
    let [sx, sy, sz] = volume.spacing();
    let orientation = volume.transform().axcodes().map_or_else(
        || "orientation unknown".to_string(),
        |c| format!("orientation {c}"),
    );
    outln!(
        "volume   {name}: {} {}, spacing {sx} x {sy} x {sz} mm, {orientation}",
        dims_string(volume.dims()),
        volume.voxel_type()
    );
    outln!(
        "views    {} viewpoints ({} axes, icosphere level {}), {} bins, blocks of {}, rays every {} mm, samples every {} mm",
        icosphere::icosphere(p.level).len(),
        v.views.len(),
        p.level,
        p.sampling.bins,
        p.block,
        p.sampling.ray_spacing.unwrap_or(1.0),
        p.sampling.sample_spacing.unwrap_or(1.0)
    );
    match v.ranked_by {
        RankedBy::PhaseMean => outln!(
            "         ranked by the mean of h over {} lattice phases: the paper's lattice and {} shifted \
             ones (each walking one block of rays in {} where the volume affords it)",
            p.phases,
            p.phases - 1,
            p.phase_subset
        ),
        RankedBy::PaperLattice => outln!("         ranked by h on the paper's lattice"),
    }
    outln!();
    let known = volume.transform().known;
    print_view_table(v, known, gain_pick);
    outln!();
    print_verdict(v);
}

/// The table of the views, the chosen axis marked: the entropy rate's best, or the gain's
/// (`gain_pick`, whose order the rows take) when the gain ranking picked the axis.
fn print_view_table(v: &ViewSearch, known: bool, gain_pick: Option<&GainRanking>) {
    let phases = v.ranked_by == RankedBy::PhaseMean;
    let gains = v.views.iter().any(|a| a.partition_gain.is_some());
    let anatomy = if known {
        format!("{:<15}", "anatomy")
    } else {
        String::new()
    };
    out!(
        "  rank    axis                          {anatomy}azim    elev   h (bits)   H(X^1)  H(X^L)/L"
    );
    out!("{}", if phases { "   mean h ± se" } else { "" });
    outln!(
        "{}",
        if gains {
            "     gain (bits)  mean ± se"
        } else {
            ""
        }
    );
    let show = |rank: String, mark: &str, a: &AxisEntropy| {
        let anatomy = if known {
            format!("{:<15}", a.world.anatomy_text())
        } else {
            String::new()
        };
        if !a.measured() {
            outln!(
                "  {rank:>4} {mark:1}  {:<28} {anatomy}{:6.1}  {:6.1}   too thin: no {} samples in a row",
                axis_text(a.axis),
                a.azimuth,
                a.elevation,
                v.params.block
            );
            return;
        }
        out!(
            "  {rank:>4} {mark:1}  {:<28} {anatomy}{:6.1}  {:6.1}   {:8.4} {:8.4}  {:8.4}",
            axis_text(a.axis),
            a.azimuth,
            a.elevation,
            a.entropy_rate,
            a.h1,
            a.per_symbol
        );
        if let Some(s) = a.phases {
            out!("   {:.4} ± {:.4}", s.mean, s.se());
        }
        match (a.partition_gain, a.gain_phases) {
            (Some(g), Some(s)) => outln!("   {g:9.4}  {:.4} ± {:.4}", s.mean, s.se()),
            _ => outln!(),
        }
    };
    let rows = gain_pick.map_or_else(|| v.views.iter().collect(), |g| g.sorted(&v.views));
    for (i, a) in rows.iter().enumerate() {
        let chosen = match gain_pick {
            Some(g) => a.axis == g.refined.axis,
            None => i == 0 && v.refined.is_none(),
        };
        show((i + 1).to_string(), if chosen { "*" } else { "" }, a);
    }
    if let Some(r) = &v.refined {
        show("ref".into(), if gain_pick.is_none() { "*" } else { "" }, r);
    }
}

/// The best axis, its margin, and whether it can be told from the others.
fn print_verdict(v: &ViewSearch) {
    let best = v.best();
    let what = match best.phases {
        Some(s) => format!(
            "mean h = {:.4} ± {:.4} bits/sample over {} ({:.4} on the paper's lattice)",
            s.mean,
            s.se(),
            count(s.n, "phase", "phases"),
            best.entropy_rate
        ),
        None => format!("h = {:.4} bits/sample", best.entropy_rate),
    };
    let next = match &v.refined {
        Some(_) => Some((&v.views[0], "the best sphere axis")),
        None => v
            .views
            .get(1)
            .filter(|n| n.measured())
            .map(|n| (n, "the runner-up")),
    };
    let margin = next.map_or_else(String::new, |(n, which)| {
        format!(", {:.4} below {which}", score(n) - score(best))
    });
    outln!(
        "best     {}\n         {what}{margin}",
        world_axis_text(best.axis, &best.world)
    );
    match &v.contenders {
        None => {}
        Some(c) if c.len() <= 1 => {
            outln!("         clear: no other axis lies within two standard errors of it");
        }
        Some(c) => {
            outln!(
                "         uncertain: {} within two standard errors of the difference, \
                 so the data cannot tell them from it:",
                count(c.len() - 1, "other axis", "other axes")
            );
            for other in &c[1..] {
                outln!(
                    "           {}  mean h {:.4} ± {:.4}",
                    axis_text(other.axis),
                    other.mean,
                    other.se
                );
            }
        }
    }
}

/// The gain ranking's verdict: its best axis, how sure, and whether the entropy rate agrees.
fn print_gain(v: &ViewSearch, g: &GainRanking, axis_by: Option<AxisBy>) {
    let best = &g.refined;
    let s = g.sampling;
    let sphere = &g.views[0];
    let from = if best.axis == sphere.axis {
        String::new()
    } else {
        format!(
            ", refined from the best sphere axis {} ({:.4} bits)",
            axis_text(sphere.axis),
            sphere.gain_phases.mean
        )
    };
    outln!(
        "by gain  {}\n         keeps {:.4} bits in {}{from}",
        world_axis_text(best.axis, &best.world),
        best.partition_gain,
        count(s.slabs, "top-down slab", "top-down slabs"),
    );
    let voxels = if s.every == 1 {
        "every voxel".to_string()
    } else {
        format!(
            "one voxel in {} along the two grid axes most across each axis",
            s.every
        )
    };
    outln!(
        "         mean {:.4} ± {:.4} over {} of {voxels}",
        best.gain_phases.mean,
        best.gain_phases.se(),
        count(best.gain_phases.n, "phase", "phases"),
    );
    if g.uncertain() {
        outln!(
            "         uncertain: {} within two standard errors of the difference:",
            count(
                g.contenders.len() - 1,
                "other axis keeps",
                "other axes keep"
            )
        );
        for other in &g.contenders[1..] {
            outln!(
                "           {}  mean gain {:.4} ± {:.4}",
                axis_text(other.axis),
                other.mean,
                other.se
            );
        }
    } else {
        outln!("         clear: no other axis keeps as much within two standard errors");
    }
    let entropy = v.best().axis;
    match g.disagrees_with(entropy) {
        Some(apart) => outln!(
            "         entropy rate prefers {}; slabs keep most along {} ({apart:.1}° apart)",
            axis_text(entropy),
            axis_text(best.axis),
        ),
        None => outln!(
            "         the entropy rate agrees ({:.1}° apart)",
            slabscope::view::axis_angle(entropy, best.axis)
        ),
    }
    if let Some(by) = axis_by {
        outln!("         the axis partitioned is chosen by {}", by.name());
    }
}

fn print_partition(p: &Partition) {
    outln!(
        "partition {} along {}:\n          {} {} mm apart, {} keeping I = {:.4} of {:.4} bits",
        p.method.name(),
        world_axis_text(p.axis, &p.world),
        count(p.slices, "slice", "slices"),
        p.thickness,
        count(p.slabs.len(), "slab", "slabs"),
        p.information,
        p.entropy
    );
    let b = p.background;
    match (b.mode, b.value) {
        ("none", _) => outln!("          background: none (every voxel counts)"),
        ("auto", None) => outln!("          background: none found at the border"),
        (mode, Some(t)) => outln!(
            "          background: {:.0}% of the voxels, {}, ≤ {t:.1}; left out of the slabs",
            b.fraction * 100.0,
            if mode == "auto" {
                "connected to the border"
            } else {
                "every voxel"
            }
        ),
        _ => {}
    }
    outln!();
    print_slab_table(p);
    print_steps(&p.steps);
    if p.comparison.is_empty() {
        return;
    }
    outln!();
    outln!("optimum  slabs  I optimal  I greedy top-down  shortfall");
    for c in &p.comparison {
        outln!(
            "         {:5}  {:9.4}  {:17.4}  {:9.4}",
            c.slabs,
            c.optimal,
            c.greedy,
            c.optimal - c.greedy
        );
    }
}

fn print_slab_table(p: &Partition) {
    // World millimetres along the world normal; without an orientation they count from voxel
    // (0, 0, 0) along the axis.
    let mm = if p.world.oriented { "world mm" } else { "mm" };
    outln!("  slab  slices         {mm:<22} entropy       mean  left out   next: NMI       ΔI");
    for (i, s) in p.info.iter().enumerate() {
        let next = match (p.boundary_nmi.get(i), p.boundary_gain.get(i)) {
            (Some(n), Some(g)) => format!("{n:9.4} {g:8.4}"),
            _ => String::new(),
        };
        let mean = s.mean.map_or_else(|| "-".into(), |m| format!("{m:.2}"));
        let mark = if s.empty { "  empty" } else { "" };
        outln!(
            "  {i:4}  {:<13}  {:>9.1} .. {:>9.1}  {:8.4} {:>10}  {:>7.1}%   {next}{mark}",
            slab_text(s.slices),
            s.world_mm.0,
            s.world_mm.1,
            s.entropy,
            mean,
            s.background_fraction * 100.0
        );
    }
}

fn print_steps(steps: &[Step]) {
    if steps.is_empty() {
        return;
    }
    outln!();
    outln!("steps");
    for (i, step) in steps.iter().enumerate() {
        match step {
            Step::Split { split, at, gain } => outln!(
                "  {:3}. split slices {} at {at}: ΔI {gain:.4} bits",
                i + 1,
                slab_text(*split)
            ),
            Step::Merge { merge, nmi } => outln!(
                "  {:3}. merge slices {} with {}: NMI {nmi:.4}",
                i + 1,
                slab_text(merge.0),
                slab_text(merge.1)
            ),
        }
    }
}

fn print_notes(notes: &[String]) {
    if !notes.is_empty() {
        outln!();
    }
    for n in notes {
        outln!("note     {}", slabscope::error::names::controls(n));
    }
}
