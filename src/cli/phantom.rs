//! `slabscope phantom KIND -o OUT.nrrd`: write a synthetic volume with known structure.

use std::path::PathBuf;

use anyhow::{Result, bail};
use clap::{Args, ValueEnum};
use slabscope::formats::{NrrdEncoding, VolumeOutput, write_phantom};
use slabscope::volume::phantom::Recipe;

/// The phantoms.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum Kind {
    /// Six materials in parallel layers normal to --normal (the paper's synthetic model), u8.
    Layers,
    /// A CT-like figure in Hounsfield-like units, head at high z, i16.
    Body,
    /// The 3D modified Shepp-Logan head, f32 in [0, 1].
    SheppLogan,
}

/// Arguments of `slabscope phantom`.
#[derive(Debug, Args)]
pub struct PhantomArgs {
    /// Which phantom.
    pub kind: Kind,
    /// Output file, in the format its extension names: .nrrd, .nii or .nii.gz.
    #[arg(short, long, value_name = "OUT.nrrd")]
    pub output: PathBuf,
    /// A cube of N voxels a side.
    #[arg(long, value_name = "N", conflicts_with = "dims")]
    pub size: Option<usize>,
    /// Dimensions NXxNYxNZ (default: 96 cubed for layers and shepp-logan, 128x128x208 for body).
    #[arg(long, value_name = "NXxNYxNZ", value_parser = super::args::parse_dims_arg)]
    pub dims: Option<[usize; 3]>,
    /// Seed of the noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Normal of the layers, DX,DY,DZ (default: the cube diagonal).
    #[arg(long, value_name = "DX,DY,DZ", default_value = "1,1,1")]
    pub normal: String,
    /// Store raw bytes instead of gzip (.nrrd; .nii is raw and .nii.gz gzip by their names).
    #[arg(long)]
    pub raw: bool,
    /// Overwrite OUT if it exists.
    #[arg(long)]
    pub force: bool,
}

pub fn run(args: &PhantomArgs) -> Result<()> {
    super::check_outputs(&[&args.output], &[], args.force)?;
    let format = VolumeOutput::for_path(&args.output)?;
    if args.raw && format != VolumeOutput::Nrrd {
        bail!(
            "--raw is for .nrrd output: {} is raw or gzip by its name",
            args.output.display()
        );
    }
    let default = match args.kind {
        Kind::Body => [128, 128, 208],
        Kind::Layers | Kind::SheppLogan => [96; 3],
    };
    let dims = args.dims.or(args.size.map(|n| [n; 3])).unwrap_or(default);
    let recipe = match args.kind {
        Kind::Layers => {
            let Some(normal) = slabscope::geometry::parse_triple(&args.normal) else {
                bail!("--normal {:?} is not three numbers DX,DY,DZ", args.normal);
            };
            Recipe::layers(dims, normal, args.seed)?
        }
        Kind::Body => Recipe::body(dims, args.seed)?,
        Kind::SheppLogan => Recipe::shepp_logan(dims)?,
    };
    let encoding = if args.raw {
        NrrdEncoding::Raw
    } else {
        NrrdEncoding::Gzip
    };
    // Made and written a chunk of voxels at a time: a phantom of any size in a few tens of MiB.
    write_phantom(&args.output, &recipe, encoding, args.force)?;
    Ok(())
}
