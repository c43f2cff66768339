//! Issue #50's goal in tmux: a folder of six volumes of at most 256³ shows the open volume's
//! picture at once, with the folder's pane below it, and the keys answer throughout, while the
//! view search and the background triage run.
//!
//! The time to the first picture is measured and printed (`--nocapture` shows it), and held
//! only to a generous bound (20 s): the second is not robust on a 2-core machine shared
//! with builds (1.1 to 1.3 s here, the test build under a load of 9). What is held exactly is
//! the order: the picture shows while the view search still runs. Before the render worker had
//! threads of its own it waited behind the view search on rayon's global pool (9 s here; in a
//! debug build, minutes).

use std::time::{Duration, Instant};

use crate::common::{binary, slabscope};
use crate::tui_smoke::Tmux;

/// The six volumes, the open one (first in order) the largest.
const VOLUMES: [(&str, &str, &str); 6] = [
    ("body", "256", "a_body.nrrd"),
    ("shepp-logan", "128", "b_head.nii"),
    ("layers", "96", "c_layers.nrrd"),
    ("body", "64", "d_body.nii"),
    ("shepp-logan", "64", "e_head.nrrd"),
    ("layers", "48", "f_layers.nii"),
];

/// The screen's half-blocks right of the viewpoints' pane in its upper rows: the exploded view's
/// picture (the viewpoints' sphere map, also of half-blocks, lies left of column 56).
fn picture_cells(screen: &str) -> usize {
    screen
        .lines()
        .take(24)
        .map(|line| line.chars().skip(56).filter(|&c| c == '▀').count())
        .sum()
}

/// Waits until the screen shows `text` (or, `shown` false, no longer does), at most 30 s;
/// returns how long it took.
fn answered(tmux: &Tmux, text: &str, shown: bool) -> Duration {
    let start = Instant::now();
    loop {
        let screen = tmux.screen();
        if screen.contains(text) == shown {
            return start.elapsed();
        }
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "waited 30 s for {text:?} to be shown: {shown}; the screen shows:\n{screen}"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn a_folder_shows_the_open_volumes_picture_at_once_with_its_pane_and_keys_alive() {
    let _alone = crate::one_at_a_time();
    if !crate::have_tmux("the folder's first-picture test") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join("six");
    std::fs::create_dir(&folder).unwrap();
    for (kind, size, name) in VOLUMES {
        let out = slabscope()
            .args(["phantom", kind, "--size", size, "-o"])
            .arg(folder.join(name))
            .output()
            .unwrap();
        assert!(out.status.success(), "{out:?}");
    }
    let command = format!(
        "cd {} && {} six --protocol blocks; echo EXITED $?; sleep 60",
        dir.path().display(),
        binary()
    );
    let start = Instant::now();
    let tmux = Tmux::start("glance", &command, (160, 45));
    let screen = loop {
        let screen = tmux.screen();
        if picture_cells(&screen) > 500 {
            break screen;
        }
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "no picture after 20 s (the goal is 1 s):\n{screen}"
        );
        std::thread::sleep(Duration::from_millis(20));
    };
    let first = start.elapsed();
    eprintln!("the first picture {:.2} s after start", first.as_secs_f64());
    // The picture does not wait for the view search (some seconds on a 128³ preview level,
    // against a tenth of that for the picture).
    assert!(
        screen.contains("view search"),
        "the picture came only after the view search:\n{screen}"
    );
    assert!(
        screen.contains("6 volumes in six"),
        "the pane shows:\n{screen}"
    );
    assert!(screen.contains("a_body.nrrd"), "{screen}");
    // Keys answer while the open volume's work and the background triage run: the pane's
    // order, its filter, the help over it and away again.
    let mut slowest = Duration::ZERO;
    for (key, text, shown) in [
        ("O", "· by status", true),
        ("D", "· by status, reversed", true),
        ("O", "· by format", true),
        ("U", "only uncertain", true),
        ("U", "only uncertain", false),
        ("?", "Esc or ? closes", true),
        ("Escape", "Esc or ? closes", false),
    ] {
        tmux.keys(key);
        slowest = slowest.max(answered(&tmux, text, shown));
    }
    eprintln!("the slowest key answered in {:.2} s", slowest.as_secs_f64());
    // Still working: the picture stays while the keys were answered.
    assert!(picture_cells(&tmux.screen()) > 500, "{}", tmux.screen());
    tmux.keys("q");
    tmux.wait_for("EXITED 0", 30);
}
