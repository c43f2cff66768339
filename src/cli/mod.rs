//! The headless command line: one file per subcommand, each a thin layer over the library, and
//! the wording of library errors in flag terms.

/// `println!` for the report on standard output: a reader that has gone (`slabscope info F |
/// head`) ends slabscope quietly instead of with a panic.
macro_rules! outln {
    () => { $crate::cli::emit(format_args!("\n")) };
    ($($t:tt)*) => { $crate::cli::emit(format_args!("{}\n", format_args!($($t)*))) };
}

/// `print!` for the report on standard output, as [`outln!`].
macro_rules! out {
    ($($t:tt)*) => { $crate::cli::emit(format_args!($($t)*)) };
}

mod analyze;
pub mod args;
#[cfg(test)]
mod doc_lines;
mod explain;
mod info;
pub mod params;
mod phantom;
mod progress;
mod render;
mod slice;
mod text;
mod triage;

use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use clap::Subcommand;
use slabscope::error::names::controls;
use slabscope::error::shown;
use slabscope::formats::{check_output, same_file};
use slabscope::params::Terms;
use slabscope::{Error, Loaded};

pub use args::{AnalysisArgs, LoadArgs, TourArgs};

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
    /// Write one slice across the slab axis to a PNG file, oriented as radiologists read it.
    Slice(slice::SliceArgs),
    /// Every volume under folders or among files, one row each: format, geometry, problems,
    /// best axis, slabs (exit status 1 when some failed, 2 when none could be listed).
    Triage(triage::TriageArgs),
    /// Write a synthetic volume with known structure.
    Phantom(phantom::PhantomArgs),
}

impl Command {
    /// How the command reads its input, for a command that reads one.
    pub fn load(&self) -> Option<&LoadArgs> {
        match self {
            Self::Info(a) => Some(&a.load),
            Self::Analyze(a) => Some(&a.load),
            Self::Render(a) => Some(&a.scene.load),
            Self::Preview(a) => Some(&a.scene.load),
            Self::Slice(a) => Some(&a.load),
            Self::Triage(a) => Some(&a.load),
            Self::Phantom(_) => None,
        }
    }
}

/// Bounds the work of the whole process to `--threads` threads when it is given: rayon's
/// global pool, built before any work.
pub fn use_threads(load: Option<&LoadArgs>) -> Result<()> {
    if let Some(n) = load.map(LoadArgs::threads).transpose()?.flatten() {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
            .map_err(|e| anyhow::anyhow!("--threads {n}: {e}"))?;
    }
    Ok(())
}

/// Runs a subcommand; the exit status it asks for (0 unless `triage` says otherwise).
pub fn run(command: Command) -> Result<u8> {
    remove_staged_on_signals();
    if let Command::Triage(args) = &command {
        return triage::run(args);
    }
    match command {
        Command::Info(args) => info::run(&args),
        Command::Analyze(args) => analyze::run(&args),
        Command::Phantom(args) => phantom::run(&args),
        Command::Render(args) => render::run_render(&args),
        Command::Preview(args) => render::run_preview(&args),
        Command::Slice(args) => slice::run(&args),
        Command::Triage(_) => unreachable!("run above"),
    }
    .map(|()| 0)
}

/// On SIGINT, SIGTERM or SIGHUP, removes the outputs staged and not yet in place, then ends as
/// the signal would have ended the process.
fn remove_staged_on_signals() {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) else {
        return;
    };
    std::thread::spawn(move || {
        if let Some(signal) = signals.forever().next() {
            slabscope::formats::remove_staged();
            let _ = signal_hook::low_level::emulate_default_handler(signal);
            std::process::exit(128 + signal);
        }
    });
}

/// Loads `path`, printing the loader's notes to stderr.
pub fn load(path: &Path, args: &LoadArgs) -> Result<Loaded> {
    load_by(path, args, slabscope::load)
}

/// [`load`], of a Zarr store the coarsest of its datasets that serves the pyramid level
/// `resolution` picks, without its level 0 ([`slabscope::formats::load_serving`]), when it
/// holds one.
pub fn load_serving(
    path: &Path,
    args: &LoadArgs,
    resolution: slabscope::volume::Resolution,
) -> Result<Loaded> {
    load_by(
        path,
        args,
        |path, opts| match slabscope::formats::load_serving(path, opts, resolution)? {
            Some(loaded) => Ok(loaded),
            None => slabscope::load(path, opts),
        },
    )
}

/// [`load`] by `read`.
fn load_by(
    path: &Path,
    args: &LoadArgs,
    read: impl FnOnce(&Path, &slabscope::LoadOptions) -> slabscope::Result<Loaded>,
) -> Result<Loaded> {
    let opts = args.options()?;
    let loaded = progress::while_reading(path, || read(path, &opts)).map_err(|e| {
        match e {
            // Stopped at the `--timeout`: said of the file, and of its loading.
            Error::Cancelled => anyhow::Error::from(e).context(format!("{}: loading", shown(path))),
            e => e.into(),
        }
    })?;
    for n in &loaded.notes {
        note(path, n);
    }
    test_delay();
    Ok(loaded)
}

/// Prints a note about `path` to stderr, on one line, nothing in it raw.
pub fn note(path: &Path, text: &str) {
    eprintln!("slabscope: note: {}: {}", shown(path), controls(text));
}

/// With `SLABSCOPE_TEST_DELAY_MS` set, waits that long after a load: a test hook, so that a test
/// can change the file between the load and the work (a mapped file cut short).
fn test_delay() {
    if let Some(ms) = std::env::var("SLABSCOPE_TEST_DELAY_MS")
        .ok()
        .and_then(|v| v.parse().ok())
    {
        std::thread::sleep(std::time::Duration::from_millis(ms));
    }
}

/// The picture format the name of `out` asks for, after checking, before any work, that `out`
/// may be written by a command reading `input`.
pub fn picture_output(
    out: &Path,
    input: &Path,
    force: bool,
) -> Result<slabscope::render::ImageOutput> {
    let format = slabscope::render::ImageOutput::for_path(out)?;
    check_outputs(&[out], &[input.to_path_buf()], force)?;
    Ok(format)
}

/// Checks, before any work, the files a command will write: each may be written (a new file,
/// or with `--force` an existing regular file, in a folder that takes new files), none is one of
/// `inputs` (`--force` or not), and no two are the same file.
pub fn check_outputs(outputs: &[&Path], inputs: &[PathBuf], force: bool) -> Result<()> {
    for (i, out) in outputs.iter().enumerate() {
        check_output(out, force)?;
        if inputs.iter().any(|input| same_path(out, input)) {
            bail!(
                "{}: is an input of this command; slabscope never writes over its input",
                shown(out)
            );
        }
        if outputs[..i].iter().any(|o| same_path(o, out)) {
            bail!("{}: given for two outputs", shown(out));
        }
    }
    Ok(())
}

/// Whether two paths name one file: the same file, or (for files yet to be made) the same name
/// in the same folder.
fn same_path(a: &Path, b: &Path) -> bool {
    let resolved = |p: &Path| {
        let dir = p
            .parent()
            .filter(|d| !d.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        dir.canonicalize()
            .ok()
            .map(|d| d.join(p.file_name().unwrap_or_default()))
    };
    same_file(a, b) || (resolved(a).is_some() && resolved(a) == resolved(b))
}

/// Writes `bytes` to `path` atomically; an existing file is replaced only when `force` is set.
pub fn write_new(path: &Path, bytes: &[u8], force: bool) -> Result<()> {
    use std::io::Write;
    slabscope::formats::write_atomic(path, force, |mut file| file.write_all(bytes))?;
    Ok(())
}

/// One error for people, on one line: each cause in the chain, library errors worded in the
/// CLI's terms by the library (`Terms::Flags`: the flag for a parameter, the flag that lifts a
/// limit or allows an overwrite), a cancellation as the timeout that caused it, control
/// characters escaped whatever a cause quotes.
pub fn error_message(e: &anyhow::Error) -> String {
    let message = e
        .chain()
        .map(|cause| match cause.downcast_ref::<Error>() {
            Some(Error::Cancelled) => progress::timed_out().unwrap_or_else(|| cause.to_string()),
            Some(e) => e.in_terms(Terms::Flags),
            None => cause.to_string(),
        })
        .collect::<Vec<_>>()
        .join(": ");
    controls(&message).into_owned()
}

/// Writes to standard output; a closed pipe ends the process quietly (its outputs are already
/// in place: reports print last), any other failure with a one-line error.
pub(crate) fn emit(args: std::fmt::Arguments<'_>) {
    use std::io::Write;
    if let Err(e) = std::io::stdout().lock().write_fmt(args) {
        if e.kind() == std::io::ErrorKind::BrokenPipe {
            std::process::exit(0);
        }
        eprintln!("slabscope: error: writing to standard output: {e}");
        std::process::exit(1);
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
        let e = anyhow::Error::from(Error::NotRegularFile {
            path: "pipe.json".into(),
        });
        assert_eq!(
            error_message(&e),
            "pipe.json: not a regular file: slabscope writes only regular files, --force or not"
        );
        let e = anyhow::Error::from(Error::invalid("dims", "0x1x1", "one voxel"));
        assert_eq!(error_message(&e), "--dims 0x1x1: expected one voxel");
    }
}
