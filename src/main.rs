//! The `slabscope` binary: argument parsing and dispatch. With a subcommand the CLI runs it;
//! without one the TUI opens. The two front ends import nothing of each other.

mod cli;
mod term;
mod tui;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;

/// Similarity-based exploded views of 3D volumes.
#[derive(Debug, Parser)]
#[command(
    name = "slabscope",
    version,
    about,
    args_conflicts_with_subcommands = true
)]
struct Cli {
    #[command(flatten)]
    tui: TuiArgs,
    #[command(subcommand)]
    command: Option<Command>,
}

/// What the TUI opens and how: the TUI's arguments, and the tour's.
#[derive(Debug, clap::Args)]
struct TuiArgs {
    /// Volume to open in the TUI (default: the built-in dataset).
    file: Option<PathBuf>,
    #[command(flatten)]
    look: TuiLook,
    #[command(flatten)]
    analysis: cli::AnalysisArgs,
    #[command(flatten)]
    load: cli::LoadArgs,
}

/// How the TUI draws.
#[derive(Clone, Copy, Debug, clap::Args)]
struct TuiLook {
    /// Terminal image protocol of the preview (default: asked of the terminal).
    #[arg(long, value_enum, default_value_t = term::Protocol::Auto)]
    protocol: term::Protocol,
    /// Colours: default, or contrast (white and bright colours on black, every text colour at
    /// least 7:1, for projectors).
    #[arg(long, value_enum, default_value_t = tui::theme::ThemeChoice::Default)]
    theme: tui::theme::ThemeChoice,
}

/// The subcommands: the CLI's, and the tour, which opens the TUI.
#[derive(Debug, clap::Subcommand)]
enum Command {
    #[command(flatten)]
    Cli(cli::Command),
    /// A guided tour of the paper's method in 16 pages on the TUI's live panes (Space, → or Page
    /// Down next, ← or Page Up back, q quits), or written for slides with --export
    Tour(TourArgs),
}

/// The tour's arguments: the TUI's, and paper mode.
#[derive(Debug, clap::Args)]
struct TourArgs {
    #[command(flatten)]
    tui: TuiArgs,
    #[command(flatten)]
    tour: cli::TourArgs,
    /// Write the pages into this folder instead (tour.md, tour.json and the pictures as PNG),
    /// without a terminal; the folder is made, or must be empty
    #[arg(long, value_name = "DIR")]
    export: Option<PathBuf>,
    /// With --export: write over the tour's files in a folder that is not empty
    #[arg(long, requires = "export")]
    force: bool,
}

/// Writes the tour's pages into `dir` (`tour --export`).
fn export_tour(t: TourArgs, dir: PathBuf) -> anyhow::Result<u8> {
    let mut args = t.tui;
    let paper = t.tour.paper();
    if paper {
        args.analysis
            .given
            .set(&slabscope::params::table::PAPER, "true");
    }
    tui::export::export(&tui::export::ExportOptions {
        dir,
        force: t.force,
        file: args.file,
        load: args.load.options()?,
        analysis: args.analysis.params(true)?,
        paper,
    })
    .map(|()| 0)
}

/// Opens the TUI as `args` say, with the tour when `tour`.
fn open_tui(mut args: TuiArgs, tour: Option<cli::TourArgs>) -> anyhow::Result<u8> {
    let paper = tour.as_ref().is_some_and(cli::TourArgs::paper);
    if paper {
        args.analysis
            .given
            .set(&slabscope::params::table::PAPER, "true");
    }
    tui::run(tui::Options {
        load: args.load.options()?,
        analysis: args.analysis.params(true)?,
        file: args.file,
        protocol: args.look.protocol,
        theme: args.look.theme,
        tour: tour.map(|_| tui::TourMode { paper }),
    })
    .map(|()| 0)
}

fn main() -> ExitCode {
    slabscope::volume::mapped::install_fault_handler();
    let args = Cli::parse();
    let load = match &args.command {
        Some(Command::Cli(command)) => command.load(),
        Some(Command::Tour(t)) => Some(&t.tui.load),
        None => Some(&args.tui.load),
    };
    let result = cli::use_threads(load).and_then(|()| match args.command {
        Some(Command::Cli(command)) => cli::run(command),
        Some(Command::Tour(mut t)) => match t.export.take() {
            Some(dir) => export_tour(t, dir),
            None => open_tui(t.tui, Some(t.tour)),
        },
        None => open_tui(args.tui, None),
    });
    let code = match result {
        Ok(code) => ExitCode::from(code),
        Err(e) => {
            eprintln!("slabscope: error: {}", cli::error_message(&e));
            ExitCode::FAILURE
        }
    };
    report_peak_memory();
    code
}

/// With `SLABSCOPE_REPORT_PEAK` set, prints the process's peak resident memory to stderr at the
/// end (Linux), for the tests that hold slabscope to its memory budget.
fn report_peak_memory() {
    if std::env::var_os("SLABSCOPE_REPORT_PEAK").is_none() {
        return;
    }
    let peak = std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
            line.split_whitespace().nth(1)?.parse::<u64>().ok()
        });
    if let Some(kib) = peak {
        eprintln!("slabscope: peak memory: {kib} KiB");
    }
}
