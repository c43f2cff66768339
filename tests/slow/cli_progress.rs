//! The CLI's progress line in a real terminal (tmux): drawn on stderr with the phase or the
//! volumes and the time elapsed, and cleared when the work ends, rows printed clear of it.
//! Skipped where tmux is absent. The work is bounded by `--timeout`, not timed: a view search of
//! 2562 viewpoints on 192³ voxels runs far longer than the few seconds it is given.

use crate::common::{binary, data};
use crate::tui_smoke::{Tmux, large_phantom};

/// Whether a line of `screen` is the progress bar.
fn bar_line(screen: &str) -> Option<&str> {
    screen
        .lines()
        .find(|l| l.starts_with('[') && l.contains("elapsed"))
}

#[test]
fn analyze_shows_the_phase_and_its_time_then_clears_the_line() {
    let _alone = crate::one_at_a_time();
    if !crate::have_tmux("the analyze progress test") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let file = large_phantom(dir.path());
    let command = format!(
        "{} analyze {} --level 4 --timeout 4 > {}; echo EXITED $?; sleep 60",
        binary(),
        file.display(),
        dir.path().join("report.txt").display()
    );
    let tmux = Tmux::start("cliprogress", &command, (100, 12));
    let screen = tmux.wait_for("% view search", 60);
    let bar = bar_line(&screen).unwrap_or_else(|| panic!("a bar with the time:\n{screen}"));
    assert!(bar.contains("% view search  "), "{bar}");
    let screen = tmux.wait_for("EXITED", 60);
    assert!(
        screen.contains("stopped at the --timeout of 4 s") && screen.contains("EXITED 1"),
        "{screen}"
    );
    assert!(bar_line(&screen).is_none(), "the bar is cleared:\n{screen}");
    assert!(!screen.contains("view search  "), "{screen}");
}

#[test]
fn triage_counts_the_volumes_and_prints_rows_clear_of_the_bar() {
    let _alone = crate::one_at_a_time();
    if !crate::have_tmux("the triage progress test") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    // body192 sorts first and holds the bar for its 3 s; then a volume and a broken file.
    large_phantom(dir.path());
    std::fs::copy(data("ramp_u8.nii"), dir.path().join("ramp_u8.nii")).unwrap();
    std::fs::write(dir.path().join("zz_broken.nii"), b"no volume").unwrap();
    let command = format!(
        "{} triage {} --level 4 --timeout 3; echo EXITED $?; sleep 60",
        binary(),
        dir.path().display()
    );
    let tmux = Tmux::start("triageprogress", &command, (200, 16));
    let screen = tmux.wait_for("/3 volumes", 60);
    let bar = bar_line(&screen).unwrap_or_else(|| panic!("a bar with the time:\n{screen}"));
    assert!(bar.contains("/3 volumes  "), "{bar}");
    let screen = tmux.wait_for("EXITED", 60);
    assert!(screen.contains("EXITED 1"), "one volume failed:\n{screen}");
    assert!(bar_line(&screen).is_none(), "the bar is cleared:\n{screen}");
    // Every row starts a line of its own: none runs into the bar.
    let rows: Vec<&str> = screen
        .lines()
        .filter(|l| l.contains(".nrrd") || l.contains(".nii"))
        .collect();
    assert_eq!(rows.len(), 3, "{screen}");
    assert!(
        rows.iter()
            .all(|r| r.starts_with("ok ") || r.starts_with("!! ")),
        "{screen}"
    );
}
