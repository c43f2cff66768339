//! `slabscope analyze FILE`: the view search (and, with the partition, the slabs), as a table or
//! as the JSON object of DESIGN.md §3.

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::{Args, ValueEnum};
use serde_json::{Value, json};
use slabscope::Volume;
use slabscope::partition::{
    Method, Partition, PartitionParams, StackParams, Step, Stop, label_volume, partition,
};
use slabscope::progress::Monitor;
use slabscope::view::{AxisEntropy, ViewParams, ViewSearch, icosphere, search};
use slabscope::volume::dims_string;
use slabscope::volume::io::{NrrdEncoding, write_nrrd};

use super::LoadArgs;
use super::progress::Bar;

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
    pub view: ViewArgs,
    #[command(flatten)]
    pub partition: PartitionArgs,
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

/// Where to cut the volume and how.
#[derive(Debug, Args, Clone)]
pub struct PartitionArgs {
    /// The axis: best (the view search's), x, y, z, or a direction DX,DY,DZ.
    #[arg(long, default_value = "best", value_parser = parse_axis)]
    pub axis: AxisChoice,
    /// How to find the slabs.
    #[arg(long, value_enum, default_value_t = MethodArg::Topdown)]
    pub method: MethodArg,
    /// Number of slabs.
    #[arg(long, value_name = "K", conflicts_with = "threshold")]
    pub slabs: Option<usize>,
    /// Stop when the best ΔI (topdown), the largest NMI (bottomup), or the gain of one more slab
    /// (optimal) falls below T.
    #[arg(long, value_name = "T", value_parser = finite)]
    pub threshold: Option<f64>,
    /// Leave voxels at or below this value out of every histogram.
    #[arg(long, value_name = "VALUE", value_parser = finite)]
    pub background: Option<f64>,
}

/// The axis to partition along.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AxisChoice {
    /// The view search's most structured axis.
    Best,
    /// A given direction.
    Direction([f64; 3]),
}

/// Parses `best`, `x`, `y`, `z` or `DX,DY,DZ`.
pub fn parse_axis(s: &str) -> Result<AxisChoice, String> {
    Ok(match s {
        "best" => AxisChoice::Best,
        "x" => AxisChoice::Direction([1.0, 0.0, 0.0]),
        "y" => AxisChoice::Direction([0.0, 1.0, 0.0]),
        "z" => AxisChoice::Direction([0.0, 0.0, 1.0]),
        _ => match super::parse_triple(s) {
            Some(d) if d.iter().all(|c| c.is_finite()) && d.iter().any(|c| *c != 0.0) => {
                AxisChoice::Direction(d)
            }
            _ => {
                return Err(format!(
                    "{s:?} is not best, x, y, z or a direction DX,DY,DZ"
                ));
            }
        },
    })
}

fn finite(s: &str) -> Result<f64, String> {
    s.parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| format!("{s:?} is not a number"))
}

/// The partition methods.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum MethodArg {
    /// Greedy splits by information gain (paper §5.1).
    Topdown,
    /// Greedy merges by normalized mutual information (paper §5.2).
    Bottomup,
    /// The partition that keeps the most information (dynamic programming).
    Optimal,
}

impl PartitionArgs {
    /// The library's parameters, with the view's bins and spacings.
    pub fn params(&self, view: &ViewArgs) -> PartitionParams {
        PartitionParams {
            method: match self.method {
                MethodArg::Topdown => Method::TopDown,
                MethodArg::Bottomup => Method::BottomUp,
                MethodArg::Optimal => Method::Optimal,
            },
            stop: match (self.slabs, self.threshold) {
                (_, Some(t)) => Stop::Threshold(t),
                (k, None) => Stop::Slabs(k.unwrap_or(4)),
            },
            stack: StackParams {
                bins: usize::from(view.bins),
                background: self.background.map(|b| b as f32),
                ray_spacing: view.ray_spacing,
                sample_spacing: view.sample_spacing,
            },
        }
    }
}

/// Options of the view search.
#[derive(Debug, Args, Clone)]
pub struct ViewArgs {
    /// Quantization bins.
    #[arg(long, default_value_t = 32, value_parser = clap::value_parser!(u16).range(2..=255))]
    pub bins: u16,
    /// Block length L of the entropy rate H(X^L) - H(X^(L-1)).
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u8).range(2..=4))]
    pub block: u8,
    /// Icosphere level: 0, 1, 2, 3 or 4 for 12, 42, 162, 642 or 2562 viewpoints.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u8).range(0..=4))]
    pub level: u8,
    /// Distance between rays in mm (default: the smallest voxel spacing).
    #[arg(long, value_name = "MM", value_parser = positive)]
    pub ray_spacing: Option<f64>,
    /// Distance between samples along a ray in mm (default: the smallest voxel spacing).
    #[arg(long, value_name = "MM", value_parser = positive)]
    pub sample_spacing: Option<f64>,
    /// Also compute h on N shifted lattices per axis and report its mean and spread.
    #[arg(long, value_name = "N", default_value_t = 0, value_parser = clap::value_parser!(u8).range(0..=64))]
    pub phases: u8,
    /// Refine the best axes on a finer local search, to within 2 degrees.
    #[arg(long)]
    pub refine: bool,
}

fn positive(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("{s:?} is not a positive number")),
    }
}

impl ViewArgs {
    /// The library's parameters.
    pub fn params(&self) -> ViewParams {
        ViewParams {
            bins: usize::from(self.bins),
            block: usize::from(self.block),
            level: usize::from(self.level),
            ray_spacing: self.ray_spacing,
            sample_spacing: self.sample_spacing,
            phases: usize::from(self.phases),
            refine: self.refine,
            ..ViewParams::default()
        }
    }
}

/// Runs the view search with a progress bar on stderr.
pub fn run_search(volume: &Volume, params: &ViewParams) -> Result<ViewSearch> {
    let bar = Bar::new("view search");
    let report = |f: f64| bar.set(f);
    let monitor = Monitor::new(None, Some(&report));
    Ok(search(volume, params, &monitor)?)
}

/// Runs a partition with a progress bar on stderr.
pub fn run_partition(
    volume: &Volume,
    axis: [f64; 3],
    params: &PartitionParams,
) -> Result<Partition> {
    let bar = Bar::new("partition");
    let report = |f: f64| bar.set(f);
    let monitor = Monitor::new(None, Some(&report));
    Ok(partition(volume, axis, params, &monitor)?)
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
    let search_views = args.views || args.partition.axis == AxisChoice::Best;
    let file = args.file.display().to_string();
    let views = if search_views {
        Some(run_search(volume, &args.view.params()).with_context(|| file.clone())?)
    } else {
        None
    };
    let axis = match (args.partition.axis, &views) {
        (AxisChoice::Direction(d), _) => d,
        (AxisChoice::Best, Some(v)) => v.best().axis,
        (AxisChoice::Best, None) => unreachable!("the view search runs for --axis best"),
    };
    let part = run_partition(volume, axis, &args.partition.params(&args.view))
        .with_context(|| file.clone())?;
    let name = args.file.display().to_string();
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&analysis_json(&name, volume, views.as_ref(), &part))?
        );
    } else {
        if let Some(v) = &views {
            print_views(&name, volume, v);
            println!();
        }
        print_partition(&part);
    }
    if let Some(path) = &args.export_labels {
        let labels = label_volume(volume, &part)?;
        write_nrrd(path, &labels, NrrdEncoding::Gzip, args.force)?;
    }
    if let Some(path) = &args.export_slabs {
        let text = serde_json::to_string_pretty(&slabs_json(&name, &part))?;
        super::write_new(path, text.as_bytes(), args.force)?;
    }
    if let Some(path) = &args.curves {
        super::write_new(path, curves_csv(&part).as_bytes(), args.force)?;
    }
    Ok(())
}

/// The object of DESIGN.md §3.
pub fn analysis_json(
    name: &str,
    volume: &Volume,
    views: Option<&ViewSearch>,
    part: &Partition,
) -> Value {
    let s = volume.stats();
    let mut out = json!({
        "file": name,
        "dims": volume.dims(),
        "spacing": volume.spacing(),
        "range": [s.min, s.max],
        "best_axis": views.map(|v| v.best().axis),
        "partition": part,
    });
    if let Some(v) = views {
        out["params"] = json!(v.params);
        out["views"] = json!(v.views);
        out["uncertain"] = json!(v.uncertain);
        if let Some(r) = &v.refined {
            out["refined"] = json!(r);
        }
    }
    out
}

/// The slab boundaries for renderers: slice indices, millimetres and fractions of the axis.
fn slabs_json(name: &str, p: &Partition) -> Value {
    let n = p.slices as f64;
    let slabs: Vec<Value> = p
        .info
        .iter()
        .enumerate()
        .map(|(i, s)| {
            json!({
                "index": i,
                "slices": [s.slices.0, s.slices.1],
                "mm": [s.mm.0, s.mm.1],
                "fraction": [s.slices.0 as f64 / n, s.slices.1 as f64 / n],
            })
        })
        .collect();
    json!({
        "file": name,
        "axis": p.axis,
        "method": p.method,
        "slices": p.slices,
        "thickness_mm": p.thickness,
        "slabs": slabs,
    })
}

/// `cut,mm,nmi,gain`: for each boundary between slice c-1 and c, its position, the NMI of the two
/// slices, and the ΔI of cutting the whole stack there.
fn curves_csv(p: &Partition) -> String {
    let mut out = String::from("cut,mm,nmi,gain\n");
    for c in 1..p.slices {
        let mm = p.offset + (c as f64 - 0.5) * p.thickness;
        let _ = writeln!(
            out,
            "{c},{mm},{},{}",
            p.nmi_curve[c - 1],
            p.gain_curve[c - 1]
        );
    }
    out
}

fn print_partition(p: &Partition) {
    println!(
        "partition {} along {}{}: {} slices {} mm apart, {} slabs keeping I = {:.4} of {:.4} bits",
        p.method.name(),
        format_axis(p.axis).trim(),
        axis_name(p.axis),
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

/// "x", "y" or "z" for a coordinate axis, else nothing.
pub fn axis_name(axis: [f64; 3]) -> &'static str {
    slabscope::partition::coordinate_axis(axis).map_or("", |m| [" (x)", " (y)", " (z)"][m])
}

/// `[ 0.526, -0.851,  0.000]`.
pub fn format_axis(axis: [f64; 3]) -> String {
    // Print -0.000 as 0.000.
    let c = axis.map(|c| if c.abs() < 5e-4 { 0.0 } else { c });
    format!("[{:6.3}, {:6.3}, {:6.3}]", c[0], c[1], c[2])
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
        p.bins,
        p.block,
        p.ray_spacing.unwrap_or(1.0),
        p.sample_spacing.unwrap_or(1.0)
    );
    println!();
    let phases = p.phases > 0;
    print!("  rank    axis                          azim    elev   h (bits)   H(X^1)  H(X^L)/L");
    println!("{}", if phases { "   mean ± spread" } else { "" });
    let show = |rank: String, mark: &str, a: &AxisEntropy| {
        print!(
            "  {rank:>4} {mark:1}  {:<28} {:6.1}  {:6.1}   {:8.4} {:8.4}  {:8.4}",
            format!("{}{}", format_axis(a.axis), axis_name(a.axis)),
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
        "best     {}{} h = {:.4} bits/sample",
        format_axis(best.axis).trim(),
        axis_name(best.axis),
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
