//! The headless command line: one file per subcommand, each a thin layer over the library.

mod analyze;

pub use analyze::analysis_json;
pub use render::Protocol;
mod info;
mod phantom;
mod progress;
mod render;

use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use clap::{Args, Parser, Subcommand};
use slabscope::volume::io::{RawOptions, default_max_memory, parse_bytes};
use slabscope::volume::{Endian, VoxelType};
use slabscope::{LoadOptions, Loaded};

/// Similarity-based exploded views of 3D volumes.
#[derive(Debug, Parser)]
#[command(
    name = "slabscope",
    version,
    about,
    args_conflicts_with_subcommands = true
)]
pub struct Cli {
    /// Volume to open (default: the built-in dataset).
    pub file: Option<PathBuf>,
    /// Terminal image protocol of the preview (default: asked of the terminal).
    #[arg(long, value_enum, default_value_t = Protocol::Auto)]
    pub protocol: Protocol,
    #[command(flatten)]
    pub load: LoadArgs,
    #[command(subcommand)]
    pub command: Option<Command>,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Dimensions, spacing, voxel type, range, mean and histogram of a volume.
    Info(info::InfoArgs),
    /// The most structured view and the slabs along it: views, best axis, partition, steps.
    Analyze(analyze::AnalyzeArgs),
    /// Render the exploded view to a PNG file.
    Render(render::RenderArgs),
    /// Show the exploded view inline in the terminal.
    Preview(render::PreviewArgs),
    /// Write a synthetic volume with known structure.
    Phantom(phantom::PhantomArgs),
}

/// How to read the input: needed only for headerless raw files, and to change the memory limit.
#[derive(Debug, Args, Clone, Default)]
pub struct LoadArgs {
    /// Dimensions of a headerless raw file, NXxNYxNZ (makes any file load as raw).
    #[arg(long, value_name = "NXxNYxNZ", value_parser = parse_dims_arg)]
    pub dims: Option<[usize; 3]>,
    /// Voxel type of a raw file: u8, i8, u16, i16, u32, i32, f32 or f64.
    #[arg(long = "type", value_name = "TYPE", value_parser = parse_type_arg)]
    pub voxel_type: Option<VoxelType>,
    /// Voxel spacing of a raw file in mm, SX,SY,SZ.
    #[arg(long, value_name = "SX,SY,SZ", value_parser = parse_spacing_arg)]
    pub spacing: Option<[f64; 3]>,
    /// Byte order of a raw file.
    #[arg(long, value_name = "little|big", value_parser = parse_endian_arg)]
    pub endian: Option<Endian>,
    /// Bytes to skip at the start of a raw file.
    #[arg(long, value_name = "BYTES")]
    pub offset: Option<u64>,
    /// The most memory the loaded volume may take, e.g. 8G (default: half the physical memory).
    #[arg(long, value_name = "BYTES", value_parser = parse_bytes_arg)]
    pub max_memory: Option<u64>,
}

impl LoadArgs {
    /// The library's load options.
    pub fn options(&self) -> LoadOptions {
        LoadOptions {
            max_memory: self.max_memory.unwrap_or_else(default_max_memory),
            raw: RawOptions {
                dims: self.dims,
                voxel_type: self.voxel_type,
                spacing: self.spacing,
                endian: self.endian,
                offset: self.offset,
            },
        }
    }
}

fn parse_dims_arg(s: &str) -> Result<[usize; 3], String> {
    slabscope::volume::io::parse_dims(s)
        .ok_or_else(|| format!("{s:?} is not NXxNYxNZ, e.g. 256x256x113"))
}

fn parse_type_arg(s: &str) -> Result<VoxelType, String> {
    VoxelType::parse(s)
        .ok_or_else(|| format!("{s:?} is not one of u8, i8, u16, i16, u32, i32, f32, f64"))
}

/// Parses three comma-separated numbers.
pub fn parse_triple(s: &str) -> Option<[f64; 3]> {
    let v: Vec<f64> = s
        .split(',')
        .map(|p| p.trim().parse().ok())
        .collect::<Option<_>>()?;
    <[f64; 3]>::try_from(v).ok()
}

fn parse_spacing_arg(s: &str) -> Result<[f64; 3], String> {
    parse_triple(s)
        .filter(|v| v.iter().all(|x| x.is_finite() && *x > 0.0))
        .ok_or_else(|| format!("{s:?} is not three positive numbers SX,SY,SZ"))
}

fn parse_endian_arg(s: &str) -> Result<Endian, String> {
    match s {
        "little" => Ok(Endian::Little),
        "big" => Ok(Endian::Big),
        _ => Err(format!("{s:?} is not little or big")),
    }
}

fn parse_bytes_arg(s: &str) -> Result<u64, String> {
    parse_bytes(s).ok_or_else(|| format!("{s:?} is not a size such as 512M or 8G"))
}

/// Runs the parsed command line.
pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Some(Command::Info(args)) => info::run(&args),
        Some(Command::Analyze(args)) => analyze::run(&args),
        Some(Command::Phantom(args)) => phantom::run(&args),
        Some(Command::Render(args)) => render::run_render(&args),
        Some(Command::Preview(args)) => render::run_preview(&args),
        None => crate::tui::run(cli.file, cli.load.options(), cli.protocol),
    }
}

/// Loads `path`, printing the loader's notes to stderr.
pub fn load(path: &Path, args: &LoadArgs) -> Result<Loaded> {
    let loaded = slabscope::load(path, &args.options())?;
    for note in &loaded.notes {
        eprintln!("slabscope: note: {}: {note}", path.display());
    }
    Ok(loaded)
}

/// Fails unless `path` may be written: it must not exist unless `force` is set.
pub fn check_writable(path: &Path, force: bool) -> Result<()> {
    if path.exists() && !force {
        bail!(
            "{}: already exists (use --force to overwrite it)",
            path.display()
        );
    }
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    if !dir.is_dir() {
        bail!(
            "{}: folder {} does not exist",
            path.display(),
            dir.display()
        );
    }
    Ok(())
}

/// Writes `bytes` to `path` atomically; an existing file is replaced only when `force` is set.
pub fn write_new(path: &Path, bytes: &[u8], force: bool) -> Result<()> {
    use std::io::Write;
    slabscope::volume::io::write_atomic(path, force, |mut file| file.write_all(bytes))?;
    Ok(())
}
