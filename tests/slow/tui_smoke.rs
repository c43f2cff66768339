//! The real binary in a real terminal (tmux): it opens on the built-in dataset, shows the panes,
//! steps a merge, and quits leaving the terminal as it was; a large volume shows its preview first.
//! Skipped where tmux is absent.

use std::process::Command;
use std::time::{Duration, Instant};

use crate::common::{binary, data, dicom_data};

/// A tmux server of our own, so the test never touches the user's sessions.
pub(crate) struct Tmux {
    socket: String,
}

impl Tmux {
    /// A server of our own named for `name`, running `command` in a `cols`×`rows` window.
    pub(crate) fn start(name: &str, command: &str, (cols, rows): (u16, u16)) -> Self {
        let tmux = Tmux {
            socket: format!("slabscope-{name}-{}", std::process::id()),
        };
        let (cols, rows) = (cols.to_string(), rows.to_string());
        tmux.run(&[
            "new-session",
            "-d",
            "-s",
            "smoke",
            "-x",
            &cols,
            "-y",
            &rows,
            command,
        ]);
        tmux
    }

    fn run(&self, args: &[&str]) -> String {
        let out = Command::new("tmux")
            .arg("-L")
            .arg(&self.socket)
            .args(args)
            .output()
            .expect("tmux runs");
        String::from_utf8_lossy(&out.stdout).into_owned()
    }

    pub(crate) fn screen(&self) -> String {
        self.run(&["capture-pane", "-p", "-t", "smoke"])
    }

    /// Waits until the screen shows `text`, for at most `secs` seconds.
    pub(crate) fn wait_for(&self, text: &str, secs: u64) -> String {
        let start = Instant::now();
        loop {
            let screen = self.screen();
            if screen.contains(text) {
                return screen;
            }
            assert!(
                start.elapsed() < Duration::from_secs(secs),
                "waited {secs} s for {text:?}; the screen shows:\n{screen}"
            );
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    pub(crate) fn keys(&self, keys: &str) {
        self.run(&["send-keys", "-t", "smoke", keys]);
    }
}

impl Drop for Tmux {
    fn drop(&mut self) {
        let _ = Command::new("tmux")
            .arg("-L")
            .arg(&self.socket)
            .arg("kill-server")
            .output();
    }
}

#[test]
fn the_tui_opens_steps_a_merge_and_quits_cleanly() {
    let _alone = crate::one_at_a_time();
    if !crate::have_tmux("the TUI smoke test") {
        return;
    }
    let command = format!("{} --protocol blocks; echo EXITED $?; sleep 60", binary());
    let tmux = Tmux::start("smoke", &command, (100, 30));
    let screen = tmux.wait_for("Slabs:", 120);
    for pane in ["axes", "Exploded view", "Curves"] {
        assert!(screen.contains(pane), "{pane} missing:\n{screen}");
    }
    tmux.keys("m");
    tmux.wait_for("bottom-up", 60);
    tmux.keys("Home");
    tmux.wait_for("n merges the most similar pair", 30);
    tmux.keys("n");
    let screen = tmux.wait_for("merged", 30);
    assert!(screen.contains("step 1/"), "{screen}");
    tmux.keys("q");
    let screen = tmux.wait_for("EXITED 0", 30);
    assert!(
        !screen.contains("Exploded view"),
        "the alternate screen is gone:\n{screen}"
    );
}

#[test]
fn the_tour_runs_from_its_first_page_to_its_last_and_quits_with_0() {
    let _alone = crate::one_at_a_time();
    if !crate::have_tmux("the tour test") {
        return;
    }
    let command = format!(
        "{} tour --protocol blocks --theme contrast; echo EXITED $?; sleep 60",
        binary()
    );
    let tmux = Tmux::start("tour", &command, (80, 24));
    tmux.wait_for("page 1 of 16", 120);
    for page in 2..=16 {
        tmux.keys(if page % 2 == 0 { "Space" } else { "Right" });
        tmux.wait_for(&format!("page {page} of 16"), 60);
    }
    let screen = tmux.wait_for("The exploded view", 10);
    assert!(screen.contains("Exploded view"), "{screen}");
    tmux.keys("Space");
    std::thread::sleep(Duration::from_millis(300));
    tmux.wait_for("page 16 of 16", 10);
    tmux.keys("Left");
    tmux.wait_for("page 15 of 16", 10);
    tmux.wait_for("Optimum into 4 slabs", 60);
    tmux.keys("q");
    let screen = tmux.wait_for("EXITED 0", 30);
    assert!(
        !screen.contains("Tour ("),
        "the alternate screen is gone:\n{screen}"
    );
}

#[test]
fn a_folder_opens_with_its_pane_and_steps_through_its_volumes() {
    let _alone = crate::one_at_a_time();
    if !crate::have_tmux("the folder smoke test") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let volumes = dir.path().join("vols");
    std::fs::create_dir(&volumes).unwrap();
    for name in ["ramp_u8.nii", "ramp_i16.mha", "ramp_u16_be.nrrd"] {
        std::fs::copy(data(name), volumes.join(name)).unwrap();
    }
    std::fs::write(volumes.join("zz_broken.nii"), b"no volume").unwrap();
    let command = format!(
        "cd {} && {} vols --protocol blocks --slabs 2; echo EXITED $?; sleep 60",
        dir.path().display(),
        binary()
    );
    let tmux = Tmux::start("folder", &command, (120, 32));
    // The folder's pane, filled by triage: three volumes and the broken file's error; the
    // picture above it, not hidden.
    let screen = tmux.wait_for(", 4 looked at", 120);
    assert!(
        screen.contains("ramp_i16.mha") && screen.contains("ramp_u8.nii"),
        "{screen}"
    );
    assert!(
        screen.contains("zz_broken.nii  error: the name says NIfTI"),
        "{screen}"
    );
    assert!(screen.contains('▀'), "the picture shows:\n{screen}");
    // Enter on the second line opens it; PgDn the next.
    tmux.keys("Down");
    tmux.keys("Enter");
    tmux.wait_for("volume 2 of 4: ramp_u16_be.nrrd", 30);
    tmux.keys("NPage");
    tmux.wait_for("volume 3 of 4: ramp_u8.nii", 30);
    // The open volume marked and written as a manifest, which triage reads.
    tmux.keys("Space");
    tmux.keys("M");
    tmux.wait_for("manifest to> slabscope-marked.txt", 30);
    tmux.keys("Enter");
    tmux.wait_for("wrote 1 volume(s) to slabscope-marked.txt", 30);
    let out = crate::common::slabscope()
        .args(["triage", "--manifest"])
        .arg(dir.path().join("slabscope-marked.txt"))
        .output()
        .unwrap();
    let rows = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{out:?}");
    assert_eq!(rows.lines().count(), 2, "a header and one row:\n{rows}");
    assert!(rows.contains("vols/ramp_u8.nii"), "{rows}");
    // Only the failed volume.
    tmux.keys("E");
    tmux.wait_for("only errors (1 shown)", 30);
    tmux.keys("q");
    tmux.wait_for("EXITED 0", 30);
}

#[test]
fn a_folder_of_dicom_series_opens_as_a_list_of_series() {
    let _alone = crate::one_at_a_time();
    if !crate::have_tmux("the DICOM folder smoke test") {
        return;
    }
    let ct = dicom_data("ct");
    let command = format!(
        "{} {} --protocol blocks --slabs 2; echo EXITED $?; sleep 60",
        binary(),
        ct.display()
    );
    let tmux = Tmux::start("dicom", &command, (120, 32));
    // Two series (the localizer left out), named by number and description.
    let screen = tmux.wait_for(", 2 looked at", 120);
    assert!(
        screen.contains("[series 3 \"Abdomen 2.5\"]")
            && screen.contains("[series 4 \"Sagittal MPR\"]"),
        "{screen}"
    );
    assert!(!screen.contains("Topogram"), "{screen}");
    tmux.keys("NPage");
    tmux.wait_for("volume 2 of 2: [series 4 \"Sagittal MPR\"]", 30);
    tmux.keys("q");
    tmux.wait_for("EXITED 0", 30);
}

/// A body phantom of 192³ voxels (more than the preview's 2²¹), written by the binary.
pub(crate) fn large_phantom(dir: &std::path::Path) -> std::path::PathBuf {
    let path = dir.join("body192.nrrd");
    let out = Command::new(binary())
        .args(["phantom", "body", "--size", "192", "-o"])
        .arg(&path)
        .output()
        .unwrap();
    assert!(out.status.success(), "{out:?}");
    path
}

#[test]
fn a_large_volume_shows_a_preview_first_then_full_resolution_in_place() {
    let _alone = crate::one_at_a_time();
    if !crate::have_tmux("the TUI preview test") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let file = large_phantom(dir.path());
    // The test hook holds the full-resolution jobs back, so the preview is seen for certain.
    let command = format!(
        "SLABSCOPE_TEST_FULL_DELAY_MS=4000 {} {} --protocol blocks --phases 0; echo EXITED $?; \
         sleep 60",
        binary(),
        file.display()
    );
    let tmux = Tmux::start("preview", &command, (150, 36));
    let screen = tmux.wait_for("preview: 1/2 resolution", 120);
    let screen = if screen.contains("of 96 slices") {
        screen
    } else {
        tmux.wait_for("of 96 slices", 60)
    };
    // The gauge of the full-resolution work, once the preview's own jobs (its histories) have
    // given the status line back.
    let screen = if screen.contains("full resolution:") {
        screen
    } else {
        tmux.wait_for("full resolution:", 60)
    };
    assert!(
        screen.contains("preview: 1/2"),
        "still the preview:\n{screen}"
    );
    // Keys work on the preview; the slab count asked for is kept at full resolution.
    tmux.keys("+");
    tmux.wait_for("5 slabs", 30);
    let screen = tmux.wait_for("of 192 slices", 300);
    assert!(
        !screen.contains("preview: 1/2"),
        "the label goes:\n{screen}"
    );
    assert!(screen.contains("5 slabs"), "{screen}");
    assert!(
        screen.contains("full resolution: the preview's 5 slabs")
            || screen.contains("full resolution moved the cuts")
            || screen.contains("full resolution: 5 slabs"),
        "the status says what full resolution changed:\n{screen}"
    );
    tmux.keys("q");
    tmux.wait_for("EXITED 0", 30);
}

#[test]
fn escape_stops_full_resolution_and_keeps_the_preview() {
    let _alone = crate::one_at_a_time();
    if !crate::have_tmux("the TUI preview test") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let file = large_phantom(dir.path());
    let command = format!(
        "SLABSCOPE_TEST_FULL_DELAY_MS=600000 {} {} --protocol blocks --phases 0; echo EXITED $?; \
         sleep 60",
        binary(),
        file.display()
    );
    let tmux = Tmux::start("cancel", &command, (150, 36));
    tmux.wait_for("of 96 slices", 120);
    tmux.wait_for("full resolution: ", 30);
    tmux.keys("Escape");
    let screen = tmux.wait_for("full resolution stopped", 30);
    assert!(screen.contains("the preview stays"), "{screen}");
    assert!(screen.contains("of 96 slices"), "{screen}");
    // Quitting does not wait for the held-back job.
    tmux.keys("q");
    tmux.wait_for("EXITED 0", 10);
}
