//! The `slabscope` binary: argument parsing and dispatch to the CLI commands.

mod cli;
mod tui;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let args = cli::Cli::parse();
    match cli::run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("slabscope: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
