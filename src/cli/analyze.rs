//! `slabscope analyze FILE`: the view search (and, with the partition, the slabs), as a table or
//! as the JSON object of DESIGN.md §3.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use serde_json::{Value, json};
use slabscope::Volume;
use slabscope::progress::Monitor;
use slabscope::view::{AxisEntropy, ViewParams, ViewSearch, icosphere, search};
use slabscope::volume::dims_string;

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
    #[command(flatten)]
    pub view: ViewArgs,
    #[command(flatten)]
    pub load: LoadArgs,
}

/// Options of the view search.
#[derive(Debug, Args, Clone)]
pub struct ViewArgs {
    /// Quantization bins.
    #[arg(long, default_value_t = 32, value_parser = clap::value_parser!(u16).range(2..=256))]
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

pub fn run(args: &AnalyzeArgs) -> Result<()> {
    let loaded = super::load(&args.file, &args.load)?;
    let volume = &loaded.volume;
    let views = run_search(volume, &args.view.params())?;
    let name = args.file.display().to_string();
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&to_json(&name, volume, &views))?
        );
    } else {
        print_views(&name, volume, &views);
    }
    Ok(())
}

/// The object of DESIGN.md §3.
fn to_json(name: &str, volume: &Volume, views: &ViewSearch) -> Value {
    let s = volume.stats();
    json!({
        "file": name,
        "dims": volume.dims(),
        "spacing": volume.spacing(),
        "range": [s.min, s.max],
        "params": views.params,
        "views": views.views,
        "best_axis": views.best().axis,
        "uncertain": views.uncertain,
        "refined": views.refined,
    })
}

/// "x", "y" or "z" for a coordinate axis, else nothing.
pub fn axis_name(axis: [f64; 3]) -> &'static str {
    match axis.map(|c| c.abs() > 1.0 - 1e-9) {
        [true, _, _] => " (x)",
        [_, true, _] => " (y)",
        [_, _, true] => " (z)",
        _ => "",
    }
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
    let margin = v
        .views
        .get(1)
        .map(|next| next.entropy_rate - v.views[0].entropy_rate);
    print!(
        "best     {}{} h = {:.4} bits/sample",
        format_axis(best.axis).trim(),
        axis_name(best.axis),
        best.entropy_rate
    );
    if let Some(m) = margin {
        print!(", {m:.4} below the runner-up");
    }
    println!();
    if v.uncertain {
        println!("         uncertain: its spread over shifted lattices exceeds that margin");
    }
}
