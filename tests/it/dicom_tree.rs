//! DICOM series over a tree of folders: a series whose files lie in two folders is one volume
//! (as dcm2niix assembles it), named by the folder holding both, which every subcommand and a
//! manifest reopen; what a folder left out is said once.

use std::path::{Path, PathBuf};

use slabscope::LoadOptions;
use slabscope::formats::{DicomOptions, dicom};

use crate::common::{dicom_data, rows, run, s};

/// What every image of the fixtures holds at column `i`, row `j`, slice `k` along the normal,
/// less the rescale's 1024.
fn stored(i: usize, j: usize, k: usize) -> f32 {
    ((3 * i + 5 * j + 11 * k) % 1000) as f32 - 1024.0
}

fn copy(files: &[PathBuf], to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for f in files {
        std::fs::copy(f, to.join(f.file_name().unwrap())).unwrap();
    }
}

/// `study/` holding the `ct` fixture with its axial series split between `study/a` and
/// `study/b` (alternate files), the sagittal series and the localizer in `study/a`; and the
/// axial series' UID.
fn split_study(root: &Path) -> (PathBuf, String) {
    let listing = dicom::list_series(&dicom_data("ct"), &LoadOptions::default()).unwrap();
    let axial = listing
        .series
        .iter()
        .find(|s| s.description == "Abdomen 2.5")
        .unwrap();
    assert_eq!(axial.files.len(), 12);
    let study = root.join("study");
    let (a, b): (Vec<_>, Vec<_>) = axial
        .files
        .iter()
        .enumerate()
        .partition(|(i, _)| i % 2 == 0);
    let strip = |v: Vec<(usize, &PathBuf)>| -> Vec<PathBuf> {
        v.into_iter().map(|(_, f)| f.clone()).collect()
    };
    copy(&strip(a), &study.join("a"));
    copy(&strip(b), &study.join("b"));
    for s in listing.series.iter().filter(|s| s.key != axial.key) {
        copy(&s.files, &study.join("a"));
    }
    copy(&[dicom_data("ct/LOCALIZER")], &study.join("a"));
    (study, axial.key.clone())
}

fn noting_localizer(rows: &[serde_json::Value]) -> usize {
    rows.iter()
        .filter(|r| {
            r["problems"]
                .as_array()
                .unwrap()
                .iter()
                .any(|p| p.as_str().unwrap().contains("localizer"))
        })
        .count()
}

#[test]
fn a_series_split_across_two_folders_is_one_volume_with_its_slices_in_order() {
    let dir = tempfile::tempdir().unwrap();
    let (study, uid) = split_study(dir.path());
    let out = run(&["triage", s(&study), "--json", "--phases", "0"]);
    assert!(out.ok, "{}", out.stderr);
    let all = rows(&out.stdout);
    let named: Vec<(String, String)> = all
        .iter()
        .map(|r| {
            let path = r["path"].as_str().unwrap();
            let rel = path.strip_prefix(s(&study)).unwrap().to_string();
            (rel, r["dicom"]["description"].as_str().unwrap().to_string())
        })
        .collect();
    let expected = [("", "Abdomen 2.5"), ("/a", "Sagittal MPR")];
    let expected: Vec<(String, String)> = expected
        .iter()
        .map(|(p, d)| (p.to_string(), d.to_string()))
        .collect();
    assert_eq!(
        named, expected,
        "one row for the split series, named by study/"
    );
    assert_eq!(all[0]["series"], uid.as_str());
    assert_eq!(
        all[0]["dims"],
        serde_json::json!([24, 20, 12]),
        "{:#}",
        all[0]
    );
    assert_eq!(noting_localizer(&all), 1, "{}", out.stdout);
    // The row's path and series reopen the same volume: every slice, in order along the normal.
    let opts = LoadOptions {
        dicom: DicomOptions {
            series: Some(uid.clone()),
            ..DicomOptions::default()
        },
        ..LoadOptions::default()
    };
    let l = slabscope::load(&study, &opts).unwrap();
    let v = &l.volume;
    assert_eq!((v.dims(), v.spacing()), ([24, 20, 12], [0.8, 0.7, 2.5]));
    for (i, j, k) in
        (0..12).flat_map(|k| (0..20).flat_map(move |j| (0..24).map(move |i| (i, j, k))))
    {
        assert_eq!(v.value([i, j, k]), stored(i, j, k), "voxel ({i}, {j}, {k})");
    }
    let whole = slabscope::load(&dicom_data("ct"), &opts).unwrap();
    assert_eq!(v.transform().matrix, whole.volume.transform().matrix);
    let info = run(&["info", s(&study), "--series", &uid, "--json"]);
    assert!(info.ok, "{}", info.stderr);
    let info: serde_json::Value = serde_json::from_str(&info.stdout).unwrap();
    assert_eq!(info["dims"], serde_json::json!([24, 20, 12]));
    let analyzed = run(&[
        "analyze",
        s(&study),
        "--series",
        &uid,
        "--axis",
        "z",
        "--json",
    ]);
    assert!(analyzed.ok, "{}", analyzed.stderr);
    // A folder alone holds half of it.
    let half = slabscope::load(&study.join("b"), &opts).unwrap();
    assert_eq!(half.volume.dims(), [24, 20, 6]);
    lists_and_reads_back(dir.path(), &study, &uid, &all);
}

/// The list names the series by `study` with `uid`, and its manifest gives the walk's rows.
fn lists_and_reads_back(dir: &Path, study: &Path, uid: &str, all: &[serde_json::Value]) {
    let list = run(&["triage", s(study), "--list"]);
    assert!(list.ok, "{}", list.stderr);
    assert!(
        list.stdout
            .lines()
            .any(|l| l == format!("{}\t{uid}", s(study))),
        "{}",
        list.stdout
    );
    let manifest = dir.join("manifest.txt");
    std::fs::write(&manifest, &list.stdout).unwrap();
    let again = run(&[
        "triage",
        "--manifest",
        s(&manifest),
        "--json",
        "--phases",
        "0",
    ]);
    assert!(again.ok, "{}", again.stderr);
    assert_eq!(rows(&again.stdout), all);
}

/// A folder's localizer is said once: on its first series' row, and on the row of the one
/// series `--series` picks, in a walk and through a manifest alike.
#[test]
fn a_localizer_is_counted_once_whatever_the_selection() {
    let ct = dicom_data("ct");
    let out = run(&["triage", s(&ct), "--json", "--phases", "0"]);
    assert!(out.ok, "{}", out.stderr);
    let all = rows(&out.stdout);
    assert_eq!(
        (all.len(), noting_localizer(&all)),
        (2, 1),
        "{}",
        out.stdout
    );
    let note = "left out 1 localizer image";
    assert_eq!(all[0]["problems"][0], note, "{:#}", all[0]);
    let second = all[1]["series"].as_str().unwrap();
    let picked = run(&[
        "triage",
        s(&ct),
        "--json",
        "--phases",
        "0",
        "--series",
        second,
    ]);
    assert!(picked.ok, "{}", picked.stderr);
    let picked = rows(&picked.stdout);
    assert_eq!(picked.len(), 1);
    assert_eq!(picked[0]["problems"][0], note, "{:#}", picked[0]);
    let dir = tempfile::tempdir().unwrap();
    let manifest = dir.path().join("m.txt");
    std::fs::write(&manifest, run(&["triage", s(&ct), "--list"]).stdout).unwrap();
    for k in ["1/2", "2/2"] {
        let shard = run(&["triage", "--manifest", s(&manifest), "--shard", k, "--json"]);
        let shard = rows(&shard.stdout);
        let want = usize::from(k == "1/2");
        assert_eq!(noting_localizer(&shard), want, "shard {k}: {shard:#?}");
    }
}
