//! The slow process-level suites, one binary for all of them: the TUI in real terminals and in
//! tmux, the CLI's progress line in tmux, hostile files and options, and the mutation harness.
//! Each runs the real binary under a timeout, so they run one at a time: on a 2-core machine,
//! tests running side by side would starve each other's timeouts. Every test here starts with
//! [`one_at_a_time`], which makes that hold under plain `cargo test` (no `--test-threads=1`
//! needed, and filters still work).
//!
//! `cargo test --test slow` runs them all; `cargo test --test slow mutants` one suite.

#![allow(clippy::unwrap_used)] // tests fail loudly by design

use std::sync::{Mutex, MutexGuard, PoisonError};

#[path = "../common/mod.rs"]
mod common;

mod bombs;
mod budget;
mod cli_progress;
mod hostile;
mod mutants;
mod real_terminal;
#[cfg(feature = "remote")]
mod remote;
mod tui_glance;
mod tui_smoke;

/// Holds off every other test of this binary until the returned guard is dropped (at the end
/// of the calling test). A test that failed while holding it does not stop the others.
pub fn one_at_a_time() -> MutexGuard<'static, ()> {
    static ALONE: Mutex<()> = Mutex::new(());
    ALONE.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Whether tmux is installed; when not, says which test is skipped (`what`) and how to install it.
fn have_tmux(what: &str) -> bool {
    let have = std::process::Command::new("tmux")
        .arg("-V")
        .output()
        .is_ok();
    if !have {
        eprintln!("SKIPPED: tmux is not installed, so {what} cannot run (apt-get install tmux)");
    }
    have
}
