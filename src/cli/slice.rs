//! `slabscope slice FILE --axis A --index I -o OUT.png`: one slice across the slab axis, as
//! radiologists read it when the orientation is known.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use slabscope::Monitor;
use slabscope::render::encode;
use slabscope::render::slice::SliceParams;
use slabscope::request::SliceRequest;

use super::args::{AnalysisArgs, LoadArgs};
use super::progress::with_bar;
use slabscope::params::table;

use super::params::{self, Flags};
use super::render::LookArgs;

/// Arguments of `slabscope slice`.
#[derive(Debug, Args)]
pub struct SliceArgs {
    /// The volume: a file, or a folder of TIFF slices.
    pub file: PathBuf,
    /// Output picture: PNG, or JPEG for a .jpg or .jpeg name.
    #[arg(short, long, value_name = "OUT.png")]
    pub output: PathBuf,
    #[command(flatten)]
    pub index: Flags<params::Index>,
    #[command(flatten)]
    pub size: Flags<params::SliceSize>,
    /// Overwrite OUT if it exists.
    #[arg(long)]
    pub force: bool,
    #[command(flatten)]
    pub no_letters: Flags<params::NoLetters>,
    #[command(flatten)]
    pub look: LookArgs,
    #[command(flatten)]
    pub analysis: AnalysisArgs,
    #[command(flatten)]
    pub load: LoadArgs,
}

pub fn run(args: &SliceArgs) -> Result<()> {
    let format = super::picture_output(&args.output, &args.file, args.force)?;
    let loaded = super::load(&args.file, &args.load)?;
    super::check_outputs(&[&args.output], &loaded.sources, args.force)?;
    let volume = &loaded.volume;
    // The axis, and where its slices lie: no partition is needed (a 3-slice volume has a
    // middle slice, if not 4 slabs).
    let mut request = SliceRequest {
        params: args.analysis.params(false)?,
        axis: None,
        index: args.index.given.value(&table::INDEX)?,
        look: args.look.look()?,
        picture: SliceParams {
            fit: args.size.given.size(&table::SLICE_SIZE)?,
            letters: !args.no_letters.given.switch(&table::NO_LETTERS)?,
            ..SliceParams::default()
        },
    };
    let name = slabscope::error::shown(&args.file);
    with_bar(|monitor| request.find_axis(volume, monitor))
        .map_err(|e| anyhow::Error::from(e).context(name))?;
    let image = request.run(volume, &Monitor::none())?;
    super::write_new(&args.output, &encode(&image, format)?, args.force)
}
