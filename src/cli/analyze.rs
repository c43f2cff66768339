//! `slabscope analyze FILE`: the view search (and, with the partition, the slabs), as a table or
//! as the JSON object of DESIGN.md §3.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;
use slabscope::partition::Step;
use slabscope::report::curves_csv;
use slabscope::view::{AxisEntropy, ViewSearch, icosphere};
use slabscope::volume::dims_string;
use slabscope::volume::io::{NrrdEncoding, write_nrrd};
use slabscope::{Analysis, AnalysisReport, Axis, Partition, SlabsReport, Volume, label_volume};

use super::args::{AnalysisArgs, LoadArgs};
use super::progress::with_bar;

/// Arguments of `slabscope analyze`.
#[derive(Debug, Args)]
pub struct AnalyzeArgs {
    /// The volume: a file, or a folder of TIFF slices.
    pub file: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
    /// Also run the view search when --axis names an axis.
    #[arg(long)]
    pub views: bool,
    #[command(flatten)]
    pub analysis: AnalysisArgs,
    /// Write the slab index of every voxel as a label volume (NRRD).
    #[arg(long, value_name = "OUT.nrrd")]
    pub export_labels: Option<PathBuf>,
    /// Write the slab boundaries as slice indices, millimetres and fractions of the axis (JSON).
    #[arg(long, value_name = "OUT.json")]
    pub export_slabs: Option<PathBuf>,
    /// Write the NMI and ΔI curves along the axis (CSV).
    #[arg(long, value_name = "OUT.csv")]
    pub curves: Option<PathBuf>,
    /// Overwrite export files that exist.
    #[arg(long)]
    pub force: bool,
    #[command(flatten)]
    pub load: LoadArgs,
}

pub fn run(args: &AnalyzeArgs) -> Result<()> {
    for path in [&args.export_labels, &args.export_slabs, &args.curves]
        .into_iter()
        .flatten()
    {
        super::check_writable(path, args.force)?;
    }
    let loaded = super::load(&args.file, &args.load)?;
    let volume = &loaded.volume;
    let name = args.file.display().to_string();
    let params = args.analysis.params(args.views);
    let analysis = with_bar(|monitor| slabscope::analyze(volume, &params, monitor))
        .with_context(|| name.clone())?;
    let part = &analysis.partition;
    if args.json {
        let report = AnalysisReport::new(&name, volume, &params.view, &analysis)?;
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_analysis(&name, volume, &analysis);
    }
    if let Some(path) = &args.export_labels {
        let labels = label_volume(volume, part)?;
        write_nrrd(path, &labels, NrrdEncoding::Gzip, args.force)?;
    }
    if let Some(path) = &args.export_slabs {
        let text = serde_json::to_string_pretty(&SlabsReport::new(&name, part))?;
        super::write_new(path, text.as_bytes(), args.force)?;
    }
    if let Some(path) = &args.curves {
        super::write_new(path, curves_csv(part).as_bytes(), args.force)?;
    }
    Ok(())
}

fn print_analysis(name: &str, volume: &Volume, analysis: &Analysis) {
    if let Some(v) = &analysis.views {
        print_views(name, volume, v);
        println!();
    }
    print_partition(&analysis.partition);
}

fn print_partition(p: &Partition) {
    println!(
        "partition {} along {}: {} slices {} mm apart, {} slabs keeping I = {:.4} of {:.4} bits",
        p.method.name(),
        axis_text(p.axis),
        p.slices,
        p.thickness,
        p.slabs.len(),
        p.information,
        p.entropy
    );
    println!();
    println!(
        "  slab  slices          mm                     entropy       mean   next: NMI       ΔI"
    );
    for (i, s) in p.info.iter().enumerate() {
        let next = match (p.boundary_nmi.get(i), p.boundary_gain.get(i)) {
            (Some(n), Some(g)) => format!("{n:9.4} {g:8.4}"),
            _ => String::new(),
        };
        let mean = s.mean.map_or_else(|| "-".into(), |m| format!("{m:.2}"));
        let mark = if s.near_empty { "  nearly empty" } else { "" };
        println!(
            "  {i:4}  {:<14}  {:>9.1} .. {:>9.1}  {:8.4} {:>10}  {next}{mark}",
            format!("{}..{}", s.slices.0, s.slices.1),
            s.mm.0,
            s.mm.1,
            s.entropy,
            mean
        );
    }
    if !p.steps.is_empty() {
        println!();
        println!("steps");
        for (i, step) in p.steps.iter().enumerate() {
            match step {
                Step::Split { split, at, gain } => {
                    println!(
                        "  {:3}. split {}..{} at {at}: ΔI {gain:.4} bits",
                        i + 1,
                        split.0,
                        split.1
                    );
                }
                Step::Merge { merge, nmi } => println!(
                    "  {:3}. merge {}..{} with {}..{}: NMI {nmi:.4}",
                    i + 1,
                    merge.0.0,
                    merge.0.1,
                    merge.1.0,
                    merge.1.1
                ),
            }
        }
    }
    println!();
    println!("optimum  slabs  I optimal  I greedy top-down  shortfall");
    for c in &p.comparison {
        println!(
            "         {:5}  {:9.4}  {:17.4}  {:9.4}",
            c.slabs,
            c.optimal,
            c.greedy,
            c.optimal - c.greedy
        );
    }
    if p.info.iter().any(|s| s.near_empty) {
        println!();
        println!(
            "note     nearly empty slabs hold background or one intensity: their NMI with any neighbour is\n         \
             about 0, so bottom-up merges them last. --background VALUE leaves such voxels out."
        );
    }
}

/// `[ 0.000, 0.000, 1.000] (z)`, or without the name for an oblique axis.
fn axis_text(axis: [f64; 3]) -> String {
    match Axis::new(axis) {
        Ok(a) => match a.name() {
            Some(n) => format!("{a} ({n})"),
            None => a.to_string(),
        },
        Err(_) => format!("{axis:?}"),
    }
}

fn print_views(name: &str, volume: &Volume, v: &ViewSearch) {
    let p = &v.params;
    let [sx, sy, sz] = volume.spacing();
    println!(
        "volume   {name}: {} {}, spacing {sx} x {sy} x {sz} mm",
        dims_string(volume.dims()),
        volume.voxel_type()
    );
    println!(
        "views    {} viewpoints ({} axes, icosphere level {}), {} bins, blocks of {}, rays every {} mm, samples every {} mm",
        icosphere::icosphere(p.level).len(),
        v.views.len(),
        p.level,
        p.sampling.bins,
        p.block,
        p.sampling.ray_spacing.unwrap_or(1.0),
        p.sampling.sample_spacing.unwrap_or(1.0)
    );
    println!();
    let phases = p.phases > 0;
    print!("  rank    axis                          azim    elev   h (bits)   H(X^1)  H(X^L)/L");
    println!("{}", if phases { "   mean ± spread" } else { "" });
    let show = |rank: String, mark: &str, a: &AxisEntropy| {
        print!(
            "  {rank:>4} {mark:1}  {:<28} {:6.1}  {:6.1}   {:8.4} {:8.4}  {:8.4}",
            axis_text(a.axis),
            a.azimuth,
            a.elevation,
            a.entropy_rate,
            a.h1,
            a.per_symbol
        );
        match a.phases {
            Some(s) => println!("   {:.4} ± {:.4}", s.mean, s.range() / 2.0),
            None => println!(),
        }
    };
    for (i, a) in v.views.iter().enumerate() {
        show(
            (i + 1).to_string(),
            if i == 0 && v.refined.is_none() {
                "*"
            } else {
                ""
            },
            a,
        );
    }
    if let Some(r) = &v.refined {
        show("ref".into(), "*", r);
    }
    println!();
    let best = v.best();
    print!(
        "best     {} h = {:.4} bits/sample",
        axis_text(best.axis),
        best.entropy_rate
    );
    // The margin to the next candidate: the best sphere axis for a refined best, else the
    // sphere's runner-up.
    match (&v.refined, v.views.get(1)) {
        (Some(r), _) => print!(
            ", {:.4} below the best sphere axis",
            v.views[0].entropy_rate - r.entropy_rate
        ),
        (None, Some(next)) => print!(
            ", {:.4} below the runner-up",
            next.entropy_rate - best.entropy_rate
        ),
        (None, None) => {}
    }
    println!();
    if v.uncertain {
        let which = if v.refined.is_some() {
            "the best sphere axis"
        } else {
            "it"
        };
        println!(
            "         uncertain: {which} varies more over shifted lattices than its margin over the sphere's runner-up"
        );
    }
}
