//! The headless command line: one file per subcommand, each a thin layer over the library, and
//! the wording of library errors in flag terms.

mod analyze;
pub mod args;
mod info;
mod phantom;
mod progress;
mod render;
mod text;

use std::path::Path;

use anyhow::{Result, bail};
use clap::Subcommand;
use slabscope::{Error, Loaded};

pub use args::{AnalysisArgs, LoadArgs};

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

/// Runs a subcommand.
pub fn run(command: Command) -> Result<()> {
    match command {
        Command::Info(args) => info::run(&args),
        Command::Analyze(args) => analyze::run(&args),
        Command::Phantom(args) => phantom::run(&args),
        Command::Render(args) => render::run_render(&args),
        Command::Preview(args) => render::run_preview(&args),
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
        return Err(Error::Exists {
            path: path.to_path_buf(),
        }
        .into());
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

/// The flags the library's parameter names stand for on the command line.
const FLAGS: &[(&str, &str)] = &[
    ("bins", "--bins"),
    ("block", "--block"),
    ("level", "--level"),
    ("phases", "--phases"),
    ("ray_spacing", "--ray-spacing"),
    ("sample_spacing", "--sample-spacing"),
    ("slabs", "--slabs"),
    ("threshold", "--threshold"),
    ("axis", "--axis"),
    ("step", "--step"),
    ("size", "--size"),
    ("spacing", "--spacing"),
];

/// One error for people, on one line: each cause in the chain, library errors worded in the
/// CLI's terms (the flag for a parameter, the flag that lifts a limit or allows an overwrite).
pub fn error_message(e: &anyhow::Error) -> String {
    e.chain()
        .map(|cause| match cause.downcast_ref::<Error>() {
            Some(e) => in_flag_terms(e),
            None => cause.to_string(),
        })
        .collect::<Vec<_>>()
        .join(": ")
}

fn in_flag_terms(e: &Error) -> String {
    match e {
        Error::InvalidParameter {
            parameter,
            value,
            expected,
        } => match FLAGS.iter().find(|(p, _)| p == parameter) {
            Some((_, flag)) => format!("{flag} {value}: expected {expected}"),
            None => e.to_string(),
        },
        Error::TooLarge { .. } => format!("{e} (raise it with --max-memory)"),
        Error::RawUndescribed {
            path,
            missing,
            detail,
        } => {
            let flags: Vec<&str> = missing
                .iter()
                .map(|m| match *m {
                    "dims" => "--dims NXxNYxNZ",
                    _ => "--type u8|i8|u16|i16|u32|i32|f32|f64",
                })
                .collect();
            format!("{}: {detail}: give {}", path.display(), flags.join(" and "))
        }
        Error::Exists { .. } => format!("{e} (use --force to overwrite it)"),
        _ => e.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn library_errors_are_worded_in_flags() {
        let e = anyhow::Error::from(Error::invalid("ray_spacing", 0, "a positive number of mm"))
            .context("ct.nii");
        assert_eq!(
            error_message(&e),
            "ct.nii: --ray-spacing 0: expected a positive number of mm"
        );
        let e = anyhow::Error::from(Error::Exists {
            path: "out.png".into(),
        });
        assert_eq!(
            error_message(&e),
            "out.png: already exists (use --force to overwrite it)"
        );
        let e = anyhow::Error::from(Error::invalid("dims", "0x1x1", "one voxel"));
        assert_eq!(error_message(&e), "dims 0x1x1: expected one voxel");
    }
}
