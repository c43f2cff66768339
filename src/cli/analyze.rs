//! `slabscope analyze FILE`: the view search (and, with the partition, the slabs), as a table or
//! as the JSON object of docs/design.md §3.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::Result;
use clap::Args;
use slabscope::explain::StepsShown;
use slabscope::formats::{VolumeOutput, stage};
use slabscope::report::{curves_csv, stage_labels};
use slabscope::request::Level;
use slabscope::{Monitor, SlabsReport};

use super::args::{AnalysisArgs, LoadArgs};
use super::params::{self, Flags};

/// Arguments of `slabscope analyze`.
#[derive(Debug, Args)]
pub struct AnalyzeArgs {
    /// The volume: a file, or a folder of TIFF slices.
    pub file: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub views: Flags<params::Views>,
    /// Explain the chosen axis and the steps taken: the block counts behind the entropy rates
    /// of the chosen and the worst axis, each split's part histograms, JS and gain, each
    /// merge's joint histogram and NMI, the optimum beside greedy. For the last 32 steps, the
    /// last N, or all (put FILE first: --explain takes an optional value).
    #[arg(long, value_name = "all|N", num_args = 0..=1, default_missing_value = "32",
          value_parser = parse_explain)]
    pub explain: Option<StepsShown>,
    #[command(flatten)]
    pub resolution: Flags<params::Resolution>,
    #[command(flatten)]
    pub analysis: AnalysisArgs,
    /// Write every voxel's slab as a label volume at the source's shape and world geometry (the
    /// slab's index + 1; 0 for background and missing voxels): NRRD (.nrrd) or NIfTI (.nii,
    /// .nii.gz), by the extension.
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
    pub timeout: Flags<params::Timeout>,
    #[command(flatten)]
    pub load: LoadArgs,
}

/// The files `args` writes, checked before anything is read: a labels file's format known, and
/// none the input or an existing file unless `--force`.
fn outputs(args: &AnalyzeArgs) -> Result<Vec<&Path>> {
    if let Some(path) = &args.export_labels {
        VolumeOutput::for_path(path)?;
    }
    let outputs: Vec<&Path> = [&args.export_labels, &args.export_slabs, &args.curves]
        .into_iter()
        .flatten()
        .map(PathBuf::as_path)
        .collect();
    super::check_outputs(&outputs, std::slice::from_ref(&args.file), args.force)?;
    Ok(outputs)
}

pub fn run(args: &AnalyzeArgs) -> Result<()> {
    super::progress::stop_after_given(&args.timeout)?;
    let outputs = outputs(args)?;
    let name = slabscope::error::shown(&args.file);
    let context = |e: slabscope::Error| anyhow::Error::from(e).context(name.clone());
    let (resolution, named) = args.resolution.given.resolution_named().map_err(context)?;
    // A store's coarser dataset serves a coarser level without level 0, unless the
    // labels of every voxel of level 0 are asked.
    let loaded = match &args.export_labels {
        None => super::load_serving(&args.file, &args.load, resolution)?,
        Some(_) => super::load(&args.file, &args.load)?,
    };
    super::check_outputs(&outputs, &loaded.sources, args.force)?;
    let full = &loaded.volume;
    let level = Level::Asked(resolution, named);
    level.wanted(full).map_err(context)?;
    let mut request = args.analysis.request(
        args.views.given.switch(&slabscope::params::table::VIEWS)?,
        level,
        args.load.options()?.max_memory,
    )?;
    request.params.explain = args.explain;
    let planned = request.plan(full)?;
    if args.export_labels.is_some() {
        // A plane of labels beside the analysis: refused before it rather than after it (the
        // labels themselves are written a few planes at a time, never held whole, and the
        // background's mask goes to a scratch file when memory has no room for it).
        request.budget.labels(&args.file, full, &planned.plan, 1)?;
    }
    let analysed = super::args::analyze(&name, planned)?;
    let (volume, analysis) = (analysed.level().as_ref(), &analysed.analysis);
    let part = &analysis.partition;
    // Every export is written in full before any is put in place, and the report printed only
    // then: an error leaves no export behind and nothing on standard output.
    let mut staged = Vec::new();
    if let Some(path) = &args.export_labels {
        let room = request
            .budget
            .labels(&args.file, full, &analysed.plan, part.slabs.len())?;
        staged.push(stage_labels(
            path,
            full,
            volume,
            part,
            room,
            &Monitor::none(),
        )?);
    }
    if let Some(path) = &args.export_slabs {
        let text = slabscope::report::to_json(&SlabsReport::new(&name, volume, part))?;
        staged.push(stage(path, |mut f| f.write_all(text.as_bytes()))?);
    }
    if let Some(path) = &args.curves {
        let text = curves_csv(part);
        staged.push(stage(path, |mut f| f.write_all(text.as_bytes()))?);
    }
    let report = if args.json {
        Some(analysed.report(&name, full)?)
    } else {
        None
    };
    for s in staged {
        s.persist(args.force)?;
    }
    if let Some(report) = report {
        outln!("{}", slabscope::report::to_json(&report)?);
    } else {
        super::text::print_analysis(&name, volume, analysis);
        if let Some(explain) = &analysis.explain {
            super::explain::print(explain);
        }
    }
    Ok(())
}

/// `all`, or a number of steps (at least 1).
fn parse_explain(s: &str) -> Result<StepsShown, String> {
    match s.trim() {
        "all" => Ok(StepsShown::All),
        t => match t.parse::<usize>() {
            Ok(n) if n >= 1 => Ok(StepsShown::Last(n)),
            _ => Err(format!(
                "{s:?} is not all or a number of steps from 1 (--explain takes an optional value: put \
                 FILE before it)"
            )),
        },
    }
}
