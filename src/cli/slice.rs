//! `slabscope slice FILE --axis A --index I -o OUT.png`: one slice across the slab axis, as
//! radiologists read it when the orientation is known.

use std::path::PathBuf;

use anyhow::{Result, bail};
use clap::Args;
use slabscope::geometry::min_spacing;
use slabscope::render::{ImageOutput, Renderer, Stack, encode, slice};

use super::args::{AnalysisArgs, LoadArgs};
use super::render::{LookArgs, load_and_partition, parse_size};

/// Arguments of `slabscope slice`.
#[derive(Debug, Args)]
pub struct SliceArgs {
    /// The volume: a file, or a folder of TIFF slices.
    pub file: PathBuf,
    /// Output picture: PNG, or JPEG for a .jpg or .jpeg name.
    #[arg(short, long, value_name = "OUT.png")]
    pub output: PathBuf,
    /// The slice, counted from 0 along the axis (default: the middle one).
    #[arg(long, value_name = "I")]
    pub index: Option<usize>,
    /// The size the slice is scaled to fit, keeping its shape.
    #[arg(long, value_name = "WxH", default_value = "512x512", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Overwrite OUT if it exists.
    #[arg(long)]
    pub force: bool,
    /// No orientation letters on the edges.
    #[arg(long)]
    pub no_letters: bool,
    #[command(flatten)]
    pub look: LookArgs,
    #[command(flatten)]
    pub analysis: AnalysisArgs,
    #[command(flatten)]
    pub load: LoadArgs,
}

pub fn run(args: &SliceArgs) -> Result<()> {
    let format = ImageOutput::for_path(&args.output)?;
    super::check_outputs(
        &[&args.output],
        std::slice::from_ref(&args.file),
        args.force,
    )?;
    let (loaded, part) = load_and_partition(
        &args.file,
        &args.load,
        &args.analysis,
        Some((&args.output, args.force)),
    )?;
    let stack = Stack::of(&part);
    let index = args.index.unwrap_or(stack.slices / 2);
    if index >= stack.slices {
        bail!(
            "--index {index}: there are {} slices along this axis (numbered from 0)",
            stack.slices
        );
    }
    let volume = &loaded.volume;
    let transfer =
        Renderer::new(volume)?.transfer(args.look.look(), min_spacing(volume.spacing()))?;
    let params = slice::SliceParams {
        fit: args.size,
        letters: !args.no_letters,
        ..slice::SliceParams::default()
    };
    let position = stack.offset + index as f64 * stack.thickness;
    let image = slice::slice(volume, &transfer, stack.axis, position, &params)?;
    super::write_new(&args.output, &encode(&image.pixmap, format)?, args.force)
}
