//! `slabscope analyze FILE`: the view search (and, with the partition, the slabs), as a table or
//! as the JSON object of DESIGN.md §3.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;
use slabscope::report::curves_csv;
use slabscope::volume::io::{VolumeOutput, write_volume};
use slabscope::{AnalysisReport, SlabsReport, label_volume};

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
    /// Write the slab index of every voxel as a label volume in the source's world geometry:
    /// NRRD (.nrrd) or NIfTI (.nii, .nii.gz), by the extension.
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
    if let Some(path) = &args.export_labels {
        VolumeOutput::for_path(path)?;
    }
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
        println!("{}", slabscope::report::to_json(&report)?);
    } else {
        super::text::print_analysis(&name, volume, &analysis);
    }
    if let Some(path) = &args.export_labels {
        let labels = label_volume(volume, part)?;
        write_volume(path, &labels, args.force)?;
    }
    if let Some(path) = &args.export_slabs {
        let text = slabscope::report::to_json(&SlabsReport::new(&name, volume, part))?;
        super::write_new(path, text.as_bytes(), args.force)?;
    }
    if let Some(path) = &args.curves {
        super::write_new(path, curves_csv(part).as_bytes(), args.force)?;
    }
    Ok(())
}
