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
    /// Volume to open in the TUI (default: the built-in dataset).
    file: Option<PathBuf>,
    /// Terminal image protocol of the preview (default: asked of the terminal).
    #[arg(long, value_enum, default_value_t = term::Protocol::Auto)]
    protocol: term::Protocol,
    #[command(flatten)]
    analysis: cli::AnalysisArgs,
    #[command(flatten)]
    load: cli::LoadArgs,
    #[command(subcommand)]
    command: Option<cli::Command>,
}

fn main() -> ExitCode {
    slabscope::volume::io::mapped::install_fault_handler();
    let args = Cli::parse();
    let result = match args.command {
        Some(command) => cli::run(command),
        None => tui::run(tui::Options {
            file: args.file,
            load: args.load.options(),
            protocol: args.protocol,
            analysis: args.analysis.params(true),
        })
        .map(|()| 0),
    };
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
