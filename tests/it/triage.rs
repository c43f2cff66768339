//! `slabscope triage`: a folder mixing formats, broken files among them, one row each with the
//! right problems; exit statuses; shards whose union is one run; manifests.

use std::path::Path;

use serde_json::Value;

use crate::common::{Ran, data, rows, run, s};

/// A tree of volumes in every format, a folder of slices, two broken files and a stray text
/// file.
fn archive(root: &Path) {
    let copy = |from: &str, to: &str| {
        let to = root.join(to);
        std::fs::create_dir_all(to.parent().unwrap()).unwrap();
        std::fs::copy(data(from), to).unwrap();
    };
    copy("ramp_u8.nii", "mr/ramp_u8.nii");
    copy("ramp_4d_um.nii.gz", "mr/four.nii.gz");
    copy("ramp_u16_be.nrrd", "ct/a.nrrd");
    copy("ramp_i16_detached.nhdr", "ct/ramp_i16_detached.nhdr");
    copy("ramp_i16_detached.raw", "ct/ramp_i16_detached.raw");
    copy("ramp_i16.mha", "ct/deeper/b.mha");
    for f in ["slice_1.tif", "slice_2.tif", "slice_10.tif"] {
        copy(&format!("ramp_slices/{f}"), &format!("stack/{f}"));
    }
    std::fs::write(root.join("mr/broken.nii"), b"not a volume at all").unwrap();
    let truncated = std::fs::read(data("ramp_u16_be.nrrd")).unwrap();
    std::fs::write(
        root.join("ct/truncated.nrrd"),
        &truncated[..truncated.len() - 7],
    )
    .unwrap();
    std::fs::write(root.join("README.txt"), b"notes").unwrap();
}

#[test]
fn every_volume_is_a_row_and_broken_files_are_rows_with_their_error() {
    let dir = tempfile::tempdir().unwrap();
    archive(dir.path());
    let root = dir.path().to_str().unwrap();
    let Ran {
        code,
        stdout,
        stderr,
        ..
    } = run(&["triage", root, "--json", "--slabs", "2"]);
    assert_eq!(code, 1, "some failed: {stderr}");
    let rows = rows(&stdout);
    let names: Vec<String> = rows
        .iter()
        .map(|r| {
            let p = r["path"].as_str().unwrap();
            p.strip_prefix(root).unwrap().to_string()
        })
        .collect();
    assert_eq!(
        names,
        [
            "/ct/a.nrrd",
            "/ct/deeper/b.mha",
            "/ct/ramp_i16_detached.nhdr",
            "/ct/truncated.nrrd",
            "/mr/broken.nii",
            "/mr/four.nii.gz",
            "/mr/ramp_u8.nii",
            "/stack",
        ],
        "sorted; the slices one volume; the data file and the text file left out"
    );
    let row = |name: &str| &rows[names.iter().position(|n| n == name).unwrap()];
    for ok in [
        "/ct/a.nrrd",
        "/ct/deeper/b.mha",
        "/mr/ramp_u8.nii",
        "/stack",
    ] {
        let r = row(ok);
        assert!(r["error"].is_null(), "{ok}: {r}");
        assert_eq!(r["dims"], serde_json::json!([5, 4, 3]), "{ok}");
        assert_eq!(r["slabs"].as_array().unwrap().len(), 2, "{ok}");
        assert!(r["best_axis"].is_array(), "{ok}");
    }
    assert_eq!(row("/stack")["format"], "tiff-folder");
    assert_eq!(row("/mr/ramp_u8.nii")["orientation"], "RAS");
    let four = row("/mr/four.nii.gz");
    assert!(
        four["problems"][0]
            .as_str()
            .unwrap()
            .contains("4D file with 2 volumes")
    );
    let broken = row("/mr/broken.nii")["error"].as_str().unwrap().to_string();
    assert!(broken.contains("not start like a NIfTI"), "{broken}");
    assert!(
        !broken.contains(root),
        "the row names the file, its error need not: {broken}"
    );
    let truncated = row("/ct/truncated.nrrd")["error"]
        .as_str()
        .unwrap()
        .to_string();
    assert!(truncated.contains("truncated"), "{truncated}");
    // The table and CSV say the same, one line a volume after a header.
    let Ran {
        code,
        stdout: table,
        ..
    } = run(&["triage", root, "--slabs", "2"]);
    assert_eq!((code, table.lines().count()), (1, 9));
    assert!(table.lines().nth(4).unwrap().starts_with("!! "));
    let Ran { stdout: csv, .. } = run(&["triage", root, "--csv", "--slabs", "2"]);
    assert_eq!(csv.lines().count(), 9);
    assert!(csv.starts_with("path,series,format,dims,"));
    // Everything loads: 0.
    let good = dir.path().join("ct/deeper");
    let Ran { code, stderr, .. } = run(&["triage", good.to_str().unwrap(), "--slabs", "2"]);
    assert_eq!(code, 0, "{stderr}");
}

#[test]
fn shards_concatenate_to_one_run_and_manifests_replace_the_walk() {
    let dir = tempfile::tempdir().unwrap();
    archive(dir.path());
    let root = dir.path().to_str().unwrap();
    let Ran { stdout: whole, .. } = run(&["triage", root, "--json", "--slabs", "2"]);
    let mut joined = String::new();
    for k in 1..=3 {
        let shard = format!("{k}/3");
        let Ran { stdout: part, .. } =
            run(&["triage", root, "--json", "--slabs", "2", "--shard", &shard]);
        joined.push_str(&part);
    }
    assert_eq!(joined, whole);
    let Ran {
        code, stdout: list, ..
    } = run(&["triage", "--list", root]);
    assert_eq!(
        (code, list.lines().count()),
        (0, 1 + 8),
        "a header, then a volume a line"
    );
    let manifest = dir.path().join("manifest.txt");
    std::fs::write(&manifest, &list).unwrap();
    let m = manifest.to_str().unwrap();
    let Ran {
        stdout: from_manifest,
        ..
    } = run(&["triage", "--manifest", m, "--json", "--slabs", "2"]);
    assert_eq!(from_manifest, whole);
    let Ran { stdout: second, .. } = run(&[
        "triage",
        "--manifest",
        m,
        "--json",
        "--slabs",
        "2",
        "--shard",
        "2/3",
    ]);
    let Ran { stdout: direct, .. } =
        run(&["triage", root, "--json", "--slabs", "2", "--shard", "2/3"]);
    assert_eq!(second, direct);
}

#[test]
fn errors_before_any_row_exit_with_2_and_bad_shards_are_refused() {
    let Ran {
        code,
        stdout,
        stderr,
        ..
    } = run(&["triage", "--manifest", "/nonexistent/manifest"]);
    assert_eq!(code, 2);
    assert!(
        stdout.is_empty() && stderr.contains("/nonexistent/manifest"),
        "{stderr}"
    );
    for bad in ["0/3", "4/3", "3", "a/b"] {
        let Ran { code, stderr, .. } = run(&["triage", ".", "--shard", bad]);
        assert_ne!(code, 0, "{bad}");
        assert!(stderr.contains("is not K/N"), "{bad}: {stderr}");
    }
    // A folder of volumes is not itself a volume: analysing it is an error, info lists it.
    let dir = tempfile::tempdir().unwrap();
    archive(dir.path());
    let ct = dir.path().join("ct");
    let Ran { code, stderr, .. } = run(&["analyze", ct.to_str().unwrap()]);
    assert_eq!(code, 1);
    assert!(stderr.contains("a folder of volumes"), "{stderr}");
    let Ran {
        code,
        stdout,
        stderr,
        ..
    } = run(&["info", ct.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0, "{stderr}");
    let listed: Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(listed["volumes"].as_array().unwrap().len(), 4, "{listed}");
}

/// A small volume (loaded within milliseconds) asked for a search of a minute or more (the
/// icosphere's level 4, 64 phases, the full lattice): stopped in the analysis at half a
/// second, however fast the machine, its row keeps what the load found. (The default search
/// of a larger volume, which this test ran before, took about the timeout itself.)
#[test]
fn a_volume_past_the_timeout_is_a_row_with_that_error() {
    let dir = tempfile::tempdir().unwrap();
    let big = dir.path().join("big.nrrd");
    let Ran { code, stderr, .. } = run(&[
        "phantom",
        "body",
        "--dims",
        "64x64x96",
        "-o",
        big.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stderr}");
    let heavy = ["--full", "--level", "4", "--phases", "64"];
    let Ran { code, stdout, .. } = run(&[
        &[
            "triage",
            big.to_str().unwrap(),
            "--json",
            "--timeout",
            "0.5",
        ][..],
        &heavy[..],
    ]
    .concat());
    assert_eq!(code, 1);
    let rows = rows(&stdout);
    let error = rows[0]["error"].as_str().unwrap();
    assert_eq!(error, "the analysis took longer than the 0.5 s timeout");
    assert_eq!(
        rows[0]["dims"],
        serde_json::json!([64, 64, 96]),
        "loaded before it stopped"
    );
}

#[test]
fn the_fast_path_finds_the_full_searchs_axis_on_a_body() {
    use slabscope::triage::{TriagePlan, look};
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("body.nrrd");
    let v = slabscope::volume::phantom::body([64, 64, 96], 3).unwrap();
    slabscope::formats::write_nrrd(&path, &v, slabscope::formats::NrrdEncoding::Raw, false)
        .unwrap();
    let row = |fast: bool| {
        let how = TriagePlan {
            load: slabscope::LoadOptions::default(),
            params: slabscope::AnalysisParams::default(),
            timeout: std::time::Duration::from_secs(600),
            fast,
            tile: None,
        };
        look(
            &slabscope::triage::Entry::file(path.clone()),
            &how,
            &|_| {},
            &|e| e.to_string(),
        )
        .row
    };
    let (fast, full) = (row(true), row(false));
    assert!(fast.error.is_none() && full.error.is_none());
    assert_eq!(fast.best_axis, full.best_axis);
    assert_eq!(fast.best_axis, Some([0.0, 0.0, 1.0]), "head to feet");
    assert_eq!(
        fast.slabs, full.slabs,
        "the partition is at full resolution either way"
    );
}

#[test]
fn the_contact_sheet_has_a_cell_per_volume() {
    let dir = tempfile::tempdir().unwrap();
    archive(dir.path());
    let root = dir.path().to_str().unwrap();
    let out = dir.path().join("sheet.png");
    let o = out.to_str().unwrap();
    let Ran {
        code,
        stdout,
        stderr,
        ..
    } = run(&["triage", root, "--slabs", "2", "--sheet", o, "--tile", "64"]);
    assert_eq!(code, 1, "{stderr}");
    assert_eq!(stdout.lines().count(), 9);
    // 8 volumes, cells of 128x64 in 2 columns and 4 rows, 6 pixels apart.
    let png = tiny_skia::Pixmap::load_png(&out).unwrap();
    assert_eq!((png.width(), png.height()), (2 * 134 + 6, 4 * 70 + 6));
    // The first volume (a.nrrd) drew; the broken file's cell (the fifth) is empty.
    let pixel = |x: u32, y: u32| {
        let i = 4 * (y * png.width() + x) as usize;
        [png.data()[i], png.data()[i + 1], png.data()[i + 2]]
    };
    assert_eq!(
        pixel(6 + 100, 2 * 70 + 6 + 40),
        [30, 30, 38],
        "an empty cell"
    );
    assert_ne!(pixel(6 + 64 + 20, 6 + 20), [30, 30, 38], "a drawn cell");
    // An existing sheet is not overwritten unasked, and nothing is looked at.
    let Ran {
        code,
        stdout,
        stderr,
        ..
    } = run(&["triage", root, "--sheet", o]);
    assert_eq!(code, 2);
    assert!(
        stdout.is_empty() && stderr.contains("already exists"),
        "{stderr}"
    );
}

#[test]
fn volumes_looked_at_together_share_the_budget_and_a_large_one_is_looked_at_alone() {
    let dir = tempfile::tempdir().unwrap();
    // Compressed, so decoded into memory (a mapped file is not the budget's).
    let data: Vec<f32> = (0..64_000)
        .map(|i| ((i / 1600) * 6 + i % 5) as f32)
        .collect();
    let volume = slabscope::Volume::new([40; 3], [1.0; 3], slabscope::VoxelType::U8, data).unwrap();
    for name in ["a.nii.gz", "b.nii.gz", "c.nii.gz"] {
        slabscope::formats::write_nifti(&dir.path().join(name), &volume, true, false).unwrap();
    }
    let root = dir.path().to_str().unwrap();
    // Each 40³ volume takes 64,000 bytes, held as its u8: more than half of 100,000, less than
    // all of it (and its analysis runs on pyramid level 1, which fits: 20³ f32, its stack and
    // 35 slices' sums, 62,160 bytes).
    let triage = |memory: &str| {
        run(&[
            "triage",
            root,
            "--json",
            "--slabs",
            "2",
            "--max-memory",
            memory,
        ])
    };
    let Ran {
        code,
        stdout,
        stderr,
        ..
    } = triage("100000");
    assert_eq!(code, 0, "{stderr}");
    assert!(
        rows(&stdout).iter().all(|r| r["error"].is_null()),
        "{stdout}"
    );
    let Ran { code, stdout, .. } = triage("50000");
    assert_eq!(code, 1);
    let error = rows(&stdout)[0]["error"].as_str().unwrap().to_string();
    assert!(error.contains("raise it with --max-memory"), "{error}");
}

#[test]
fn triage_shards_any_k_of_n_up_to_u64_max_and_an_empty_shard_is_a_note() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["a.nii", "b.nii", "c.nii"] {
        std::fs::copy(data("ramp_u8.nii"), dir.path().join(name)).unwrap();
    }
    let root = dir.path().to_str().unwrap();
    for (k_n, want) in [
        ("9223372036854775808/9223372036854775808", Some("c.nii")),
        ("18446744073709551615/18446744073709551615", Some("c.nii")),
        ("18446744073709551614/18446744073709551615", None),
        ("1/18446744073709551615", None),
        ("3/3", Some("c.nii")),
    ] {
        let shard = format!("--shard={k_n}");
        let Ran {
            code,
            stdout,
            stderr,
            ..
        } = run(&["triage", root, "--list", &shard]);
        assert_eq!(code, 0, "{k_n}: {stderr}");
        let listed: Vec<&str> = stdout.lines().skip(1).collect();
        if let Some(name) = want {
            assert_eq!(listed, [format!("{root}/{name}")], "{k_n}");
            assert!(stderr.is_empty(), "{k_n}: {stderr}");
        } else {
            assert!(listed.is_empty(), "{k_n}: {stdout}");
            assert!(
                stderr.contains(&format!("note: shard {k_n} of 3 volumes is empty")),
                "{k_n}: {stderr}"
            );
        }
    }
    let Ran { code, stdout, .. } = run(&["triage", root, "--json", "--shard=1/9"]);
    assert_eq!(
        (code, stdout.as_str()),
        (0, ""),
        "an empty shard: no rows, exit 0"
    );
}

#[test]
fn triage_gives_one_row_per_file_however_spelled_and_nothing_found_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let archive = dir.path().join("archive");
    std::fs::create_dir(&archive).unwrap();
    std::fs::copy(data("ramp_u8.nii"), archive.join("a.nii")).unwrap();
    std::fs::copy(data("ramp_u8.nii"), archive.join("b.nii")).unwrap();
    let absolute = archive.join("a.nii");
    let out = crate::common::slabscope()
        .current_dir(dir.path())
        .args(["triage", "--list", "archive", "./archive/a.nii"])
        .arg(&absolute)
        .output()
        .unwrap();
    let listed = String::from_utf8(out.stdout).unwrap();
    assert_eq!(
        listed.lines().count(),
        1 + 2,
        "a.nii once, b.nii once: {listed}"
    );
    // The same through a manifest that names a file twice.
    let manifest = dir.path().join("m.txt");
    let twice = format!(
        "{0}\n{0}\n{1}/./a.nii\n",
        absolute.display(),
        archive.display()
    );
    std::fs::write(&manifest, twice).unwrap();
    let Ran { code, stdout, .. } = run(&["triage", "--manifest", s(&manifest), "--list"]);
    assert_eq!((code, stdout.lines().count()), (0, 2), "{stdout}");
    // Nothing at all: an error, exit 2, not a silent success.
    let empty = dir.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let Ran {
        code,
        stdout,
        stderr,
        ..
    } = run(&["triage", s(&empty)]);
    assert_eq!((code, stdout.as_str()), (2, ""));
    assert!(
        stderr.contains(&format!("no volumes found under {}", empty.display())),
        "{stderr}"
    );
    std::fs::write(&manifest, "\n\n").unwrap();
    let Ran { code, stderr, .. } = run(&["triage", "--manifest", s(&manifest)]);
    assert_eq!(code, 2);
    assert!(
        stderr.contains("no volumes found in the manifest"),
        "{stderr}"
    );
}

/// A FIFO mounted over a file's name (in a private mount namespace: the directory listing says
/// a regular file, the name opens a FIFO) does not block the walk: it is looked at without
/// waiting and the volumes beside it are listed and triaged. Skipped where `unshare` cannot make
/// a mount namespace (not root, or no user namespaces).
#[test]
fn the_walk_is_never_blocked_by_a_fifo_mounted_over_a_file() {
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join("scans");
    std::fs::create_dir(&folder).unwrap();
    std::fs::copy(data("ramp_u8.nii"), folder.join("ramp.nii")).unwrap();
    std::fs::write(folder.join("scan0001"), b"").unwrap();
    let fifo = dir.path().join("pipe");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    let works = std::process::Command::new("unshare")
        .args(["--mount", "true"])
        .status()
        .is_ok_and(|s| s.success());
    if !made.is_ok_and(|s| s.success()) || !works {
        eprintln!(
            "skipped: mkfifo or a private mount namespace (unshare --mount) is not available"
        );
        return;
    }
    let script = format!(
        "mount --bind '{}' '{}/scan0001' && exec timeout 20 '{}' triage --json '{}'",
        s(&fifo),
        s(&folder),
        crate::common::binary(),
        s(&folder)
    );
    let out = std::process::Command::new("unshare")
        .args(["--mount", "sh", "-c", &script])
        .output()
        .unwrap();
    assert_ne!(out.status.code(), Some(124), "the walk blocked");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let rows = rows(&stdout);
    assert!(
        rows.iter()
            .any(|r| r["path"].as_str().unwrap().ends_with("ramp.nii") && r["error"].is_null()),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A folder nested past the walk's limit, a folder that cannot be read and a broken DICOM file
/// beside a volume are each a row naming them and their problem; the good volumes are rows too,
/// and the run exits 1. The unreadable folder needs an unprivileged user: as root the walk runs
/// under `setpriv` as nobody, and that part is skipped without it.
#[test]
fn a_bad_folder_or_file_is_a_row_and_the_walk_goes_on() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().join("archive");
    std::fs::create_dir(&root).unwrap();
    std::fs::copy(data("ramp_u8.nii"), root.join("good.nii")).unwrap();
    let mut deep = root.join("deep");
    for _ in 0..70 {
        deep = deep.join("d");
    }
    std::fs::create_dir_all(&deep).unwrap();
    std::fs::copy(data("ramp_u8.nii"), deep.join("buried.nii")).unwrap();
    let mixed = root.join("mixed");
    std::fs::create_dir(&mixed).unwrap();
    std::fs::copy(data("ramp_u8.nii"), mixed.join("ok.nii")).unwrap();
    std::fs::write(mixed.join("bad.dcm"), b"").unwrap();
    let locked = root.join("locked");
    std::fs::create_dir(&locked).unwrap();
    std::fs::copy(data("ramp_u8.nii"), locked.join("hidden.nii")).unwrap();
    let unprivileged = as_nobody(&[&dir.path().to_path_buf(), &root, &locked]);
    if unprivileged.is_some() {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o000)).unwrap();
    }
    let args = ["triage", s(&root), "--json", "--slabs", "2"];
    let out = if let Some(command) = &unprivileged {
        let out = std::process::Command::new(command[0])
            .args(&command[1..])
            .arg(crate::common::binary())
            .args(args)
            .output()
            .unwrap();
        Ran::from(out)
    } else {
        eprintln!(
            "skipped the unreadable folder: not root, no setpriv, or nobody cannot run the binary"
        );
        run(&args)
    };
    assert_eq!(out.code, 1, "{}", out.stderr);
    let rows = rows(&out.stdout);
    let row = |suffix: &str| {
        rows.iter()
            .find(|r| r["path"].as_str().unwrap().ends_with(suffix))
            .unwrap_or_else(|| panic!("no row for {suffix}: {}", out.stdout))
    };
    for good in ["archive/good.nii", "mixed/ok.nii"] {
        assert!(row(good)["error"].is_null(), "{good}: {}", row(good));
    }
    let error = |suffix: &str| row(suffix)["error"].as_str().unwrap().to_string();
    assert!(
        error("/d").contains("nest deeper than 64"),
        "{}",
        error("/d")
    );
    let bad = error("mixed/bad.dcm");
    assert!(bad.contains("not a DICOM file"), "{bad}");
    if unprivileged.is_some() {
        let e = error("archive/locked");
        assert!(e.contains("Permission denied"), "{e}");
    }
}

/// The command that runs a program as nobody, when the tests run as root, `setpriv` is there
/// and nobody can run slabscope, with `paths` opened to everyone so that nobody can walk them.
fn as_nobody(paths: &[&std::path::PathBuf]) -> Option<Vec<&'static str>> {
    use std::os::unix::fs::PermissionsExt;
    let root = std::process::Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| o.stdout.trim_ascii() == b"0");
    // Nobody must be able to run the binary itself (a clone under a private home cannot).
    let setpriv = std::process::Command::new("setpriv")
        .args(["--reuid=65534", "--regid=65534", "--clear-groups"])
        .arg(crate::common::binary())
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !(root && setpriv) {
        return None;
    }
    for p in paths {
        std::fs::set_permissions(p, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
    Some(vec![
        "setpriv",
        "--reuid=65534",
        "--regid=65534",
        "--clear-groups",
    ])
}

/// `--series` means in `triage` what it means in `info` and `analyze`: the position `info`
/// shows (`--series N`) or the UID, and only that series' rows.
#[test]
fn triage_series_takes_what_info_lists() {
    let ct = crate::common::dicom_data("ct");
    let listing = run(&["info", s(&ct)]);
    assert!(listing.ok, "{}", listing.stderr);
    let line = listing
        .stdout
        .lines()
        .find(|l| l.contains("Sagittal MPR"))
        .unwrap()
        .to_string();
    let n = line
        .rsplit("--series ")
        .next()
        .unwrap()
        .trim_end_matches(')');
    let by_position = run(&["triage", s(&ct), "--json", "--series", n]);
    assert!(by_position.ok, "{}", by_position.stderr);
    let rows = rows(&by_position.stdout);
    assert_eq!(rows.len(), 1, "{}", by_position.stdout);
    assert_eq!(rows[0]["dicom"]["description"], "Sagittal MPR");
    let uid = rows[0]["series"].as_str().unwrap().to_string();
    let by_uid = run(&["triage", s(&ct), "--json", "--series", &uid]);
    assert_eq!(
        crate::common::rows(&by_uid.stdout)[0]["series"],
        uid.as_str()
    );
    let analyzed = run(&["analyze", s(&ct), "--json", "--series", n, "--axis", "z"]);
    assert!(analyzed.ok, "{}", analyzed.stderr);
    let none = run(&["triage", s(&ct), "--series", "9"]);
    assert_eq!(none.code, 2);
    assert!(
        none.stderr.contains("no DICOM series 9 found under"),
        "{}",
        none.stderr
    );
}

/// A folder's localizer is counted once: on its first series' row, not repeated on the others.
#[test]
fn a_folders_localizer_is_noted_once() {
    let ct = crate::common::dicom_data("ct");
    let out = run(&["triage", s(&ct), "--json"]);
    assert!(out.ok, "{}", out.stderr);
    let rows = rows(&out.stdout);
    assert_eq!(rows.len(), 2, "{}", out.stdout);
    let noting: Vec<bool> = rows
        .iter()
        .map(|r| {
            r["problems"]
                .as_array()
                .unwrap()
                .iter()
                .any(|p| p.as_str().unwrap().contains("localizer"))
        })
        .collect();
    assert_eq!(noting, [true, false], "{}", out.stdout);
}

#[test]
fn a_run_stops_when_its_reader_stops_taking_rows() {
    use slabscope::triage::{Source, TriagePlan, look_all, select};
    let dir = tempfile::tempdir().unwrap();
    archive(dir.path());
    let opts = slabscope::LoadOptions::default();
    let paths = [dir.path().to_path_buf()];
    let all = select(Source::Paths(&paths), &opts, None).unwrap().volumes;
    assert!(all.len() >= 6, "{all:?}");
    let how = TriagePlan {
        load: opts,
        params: slabscope::AnalysisParams::default(),
        timeout: std::time::Duration::from_secs(60),
        fast: true,
        tile: None,
    };
    let mut seen = Vec::new();
    look_all(&all, &how, 2, None, &|_, e| e.to_string(), |i, _| {
        seen.push(i);
        seen.len() < 2
    });
    assert_eq!(seen, [0, 1], "rows in order, none after the reader stopped");
}
