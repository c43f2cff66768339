//! Hostile file names (terminal escapes, line breaks, tabs, invalid UTF-8, leading dashes) in
//! every output: escaped by one rule, never raw; and manifests that carry them losslessly.

use std::ffi::OsStr;
use std::os::unix::ffi::OsStrExt;
use std::path::{Path, PathBuf};
use std::process::Output;

use serde_json::Value;

use crate::common::{data, dicom_data, slabscope};

/// Runs `slabscope` with `args` (any bytes).
fn run_os(args: &[&OsStr]) -> Output {
    slabscope().args(args).output().unwrap()
}

/// The path `dir/name`, `name` any bytes.
fn named(dir: &Path, name: &[u8]) -> PathBuf {
    dir.join(OsStr::from_bytes(name))
}

/// Fails when `bytes` holds a control character other than the line feeds that end lines.
fn nothing_raw(what: &str, bytes: &[u8]) {
    let text = String::from_utf8(bytes.to_vec()).unwrap_or_else(|e| panic!("{what}: {e}"));
    let raw: Vec<char> = text
        .chars()
        .filter(|c| c.is_control() && *c != '\n')
        .collect();
    assert!(raw.is_empty(), "{what}: raw {raw:?} in {text}");
}

const ESC_NAME: &[u8] = b"esc\x1b[31mRED\x1b[0m\x07.nii";
const ESC_SHOWN: &str = "esc\\u{1b}[31mRED\\u{1b}[0m\\u{7}.nii";

/// A folder with volumes under hostile names, a 4D one (whose note names it), and a DICOM
/// series with a gap between two hostile names.
fn hostile_folder() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path();
    for name in [
        ESC_NAME,
        b"new\nline.nii",
        b"tab\there.nii",
        b"p\xff.nii",
        b"p\xfe.nii",
    ] {
        std::fs::copy(data("ramp_u8.nii"), named(root, name)).unwrap();
    }
    std::fs::copy(data("ramp_4d_um.nii.gz"), named(root, b"four\x1b.nii.gz")).unwrap();
    std::fs::create_dir(root.join("gap")).unwrap();
    for f in std::fs::read_dir(dicom_data("gap")).unwrap() {
        let f = f.unwrap().path();
        let name = f.file_name().unwrap().as_bytes().to_vec();
        let name = match name.as_slice() {
            b"slice04.dcm" => b"s04\x1b].dcm".to_vec(),
            b"slice06.dcm" => b"s06\n.dcm".to_vec(),
            _ => name,
        };
        std::fs::copy(&f, named(&root.join("gap"), &name)).unwrap();
    }
    dir
}

#[test]
fn triage_table_csv_and_json_escape_every_name_and_never_print_one_raw() {
    let dir = hostile_folder();
    let root = dir.path().as_os_str();
    let triage = |extra: &[&str]| {
        let mut args: Vec<&OsStr> = vec![OsStr::new("triage"), root];
        args.extend(extra.iter().map(OsStr::new));
        args.extend(["--phases", "0", "--slabs", "2"].map(OsStr::new));
        run_os(&args)
    };
    let table = triage(&[]);
    nothing_raw("table", &table.stdout);
    nothing_raw("table stderr", &table.stderr);
    let text = String::from_utf8(table.stdout).unwrap();
    assert_eq!(
        text.lines().count(),
        8,
        "a header and one line a volume: {text}"
    );
    assert!(text.contains(ESC_SHOWN), "{text}");
    assert!(text.contains("new\\nline.nii") && text.contains("tab\\there.nii"));
    assert!(
        text.contains("p\\xff.nii") && text.contains("p\\xfe.nii"),
        "{text}"
    );
    assert!(
        text.contains("s04\\u{1b}].dcm") && text.contains("s06\\n.dcm"),
        "the gap names the files either side: {text}"
    );
    let csv = triage(&["--csv"]);
    nothing_raw("csv", &csv.stdout);
    let csv = String::from_utf8(csv.stdout).unwrap();
    assert_eq!(csv.lines().count(), 8, "{csv}");
    assert!(csv.lines().any(|l| l.contains(ESC_SHOWN)), "{csv}");
    let json = triage(&["--json"]);
    nothing_raw("json", &json.stdout);
    let rows: Vec<Value> = String::from_utf8(json.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let root_shown = dir.path().to_str().unwrap();
    let paths: Vec<&str> = rows.iter().map(|r| r["path"].as_str().unwrap()).collect();
    assert!(
        paths.contains(&format!("{root_shown}/{ESC_SHOWN}").as_str()),
        "{paths:?}"
    );
    assert!(
        paths.contains(&format!("{root_shown}/p\\xff.nii").as_str()),
        "{paths:?}"
    );
    assert!(
        paths.contains(&format!("{root_shown}/p\\xfe.nii").as_str()),
        "{paths:?}"
    );
    for r in &rows {
        assert!(r["error"].is_null(), "{r}");
    }
}

#[test]
fn info_listings_notes_and_errors_escape_every_name() {
    let dir = hostile_folder();
    let root = dir.path().as_os_str();
    let root_shown = dir.path().to_str().unwrap();
    let info = run_os(&[OsStr::new("info"), root]);
    assert!(
        info.status.success(),
        "{}",
        String::from_utf8_lossy(&info.stderr)
    );
    nothing_raw("info listing", &info.stdout);
    let listing = String::from_utf8(info.stdout).unwrap();
    assert!(
        listing.contains(ESC_SHOWN) && listing.contains("p\\xfe.nii"),
        "{listing}"
    );
    let info = run_os(&[OsStr::new("info"), root, OsStr::new("--json")]);
    nothing_raw("info --json", &info.stdout);
    let listed: Value = serde_json::from_slice(&info.stdout).unwrap();
    let listed: Vec<&str> = listed["volumes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v["path"].as_str().unwrap())
        .collect();
    assert_eq!(listed.len(), 7, "{listed:?}");
    assert!(
        listed.contains(&format!("{root_shown}/{ESC_SHOWN}").as_str()),
        "{listed:?}"
    );
    // The loader's note on stderr names the file escaped.
    let four = named(dir.path(), b"four\x1b.nii.gz");
    let info = run_os(&[OsStr::new("info"), four.as_os_str()]);
    nothing_raw("note", &info.stderr);
    let note = String::from_utf8(info.stderr).unwrap();
    assert!(
        note.contains("note: ") && note.contains("four\\u{1b}.nii.gz: 4D file"),
        "{note}"
    );
    // An error names it escaped too.
    let missing = named(dir.path(), b"gone\x1b\n.nii");
    let info = run_os(&[OsStr::new("info"), missing.as_os_str()]);
    nothing_raw("error", &info.stderr);
    assert!(String::from_utf8_lossy(&info.stderr).contains("gone\\u{1b}\\n.nii"));
}

/// Names a manifest must carry: line breaks, tabs (one before a UID-like tail), ESC, invalid
/// UTF-8, leading dashes, backslashes and escape-like text, a leading `#`, spaces at the ends.
const HOSTILE: [&[u8]; 14] = [
    b"new\nline.nii",
    b"cr\rhere.nii",
    b"tab\there.nii",
    b"looks\t1.2.3.nii",
    b"esc\x1b[2J.nii",
    b"bell\x07.nii",
    b"p\xff.nii",
    b"p\xfe.nii",
    b"-lead.nii",
    b"--help.nii",
    b"back\\slash\\x41.nii",
    b"#hash.nii",
    b" spaced .nii",
    b"\xe2\x80\xaeright-to-left.nii",
];

/// `slabscope triage ARGS...` and its standard output (which must be all there is, exit 0).
fn triage_ok(args: &[&OsStr]) -> Vec<u8> {
    let out = run_os(&[&[OsStr::new("triage")], args].concat());
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out.stdout
}

#[test]
fn a_listed_manifest_reads_back_to_exactly_the_same_volumes_whatever_their_names() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().join("archive");
    std::fs::create_dir(&root).unwrap();
    for name in HOSTILE {
        std::fs::copy(data("ramp_u8.nii"), named(&root, name)).unwrap();
    }
    // A DICOM series in a folder with a hostile name: a line with a tab and its UID.
    let series = named(&root, b"se\nries\t\x1b\xff");
    std::fs::create_dir(&series).unwrap();
    for f in std::fs::read_dir(dicom_data("rescale")).unwrap() {
        let f = f.unwrap().path();
        std::fs::copy(&f, series.join(f.file_name().unwrap())).unwrap();
    }
    let list = triage_ok(&[OsStr::new("--list"), root.as_os_str()]);
    let text = String::from_utf8(list.clone()).unwrap();
    let tabs: Vec<&str> = text.lines().filter(|l| l.contains('\t')).collect();
    assert_eq!(
        tabs.len(),
        1,
        "the tab before the series' UID alone: {tabs:?}"
    );
    nothing_raw("--list", text.replace('\t', " ").as_bytes());
    assert_eq!(text.lines().count(), 1 + HOSTILE.len() + 1, "{text}");
    assert!(text.starts_with("# slabscope manifest 2"), "{text}");
    let manifest = dir.path().join("manifest.txt");
    std::fs::write(&manifest, &list).unwrap();
    let m = manifest.as_os_str();
    let relisted = triage_ok(&[OsStr::new("--manifest"), m, OsStr::new("--list")]);
    assert_eq!(relisted, list, "the same entries, the same order");
    let json = ["--json", "--phases", "0", "--slabs", "2"].map(OsStr::new);
    let walked = triage_ok(&[&[root.as_os_str()][..], &json].concat());
    let read = triage_ok(&[&[OsStr::new("--manifest"), m][..], &json].concat());
    assert_eq!(read, walked, "every volume found, none lost");
    let rows: Vec<Value> = String::from_utf8(read)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(rows.len(), HOSTILE.len() + 1);
    let mut paths: Vec<PathBuf> = rows
        .iter()
        .map(|r| {
            assert!(r["error"].is_null(), "{r}");
            slabscope::error::names::unescape_path(r["path"].as_str().unwrap()).unwrap()
        })
        .collect();
    paths.dedup();
    let mut want: Vec<PathBuf> = HOSTILE.iter().map(|n| named(&root, n)).collect();
    want.push(series.clone());
    want.sort();
    paths.sort();
    assert_eq!(paths, want, "each JSON path reads back to its file's bytes");
}

#[test]
fn the_plain_tab_separated_manifest_still_reads() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path();
    let back = named(root, b"back\\slash.nii");
    let odd = named(root, b"odd\xff.nii");
    std::fs::copy(data("ramp_u8.nii"), &back).unwrap();
    std::fs::copy(data("ramp_u8.nii"), &odd).unwrap();
    let series = root.join("series");
    std::fs::create_dir(&series).unwrap();
    for f in std::fs::read_dir(dicom_data("rescale")).unwrap() {
        let f = f.unwrap().path();
        std::fs::copy(&f, series.join(f.file_name().unwrap())).unwrap();
    }
    let json = ["--json", "--phases", "0", "--slabs", "2"].map(OsStr::new);
    let walked = triage_ok(&[&[root.as_os_str()][..], &json].concat());
    let uid = serde_json::from_slice::<Value>(walked.split(|&b| b == b'\n').nth(2).unwrap())
        .unwrap()["series"]
        .as_str()
        .unwrap()
        .to_string();
    // As `find` and older lists write it: paths as they are, a tab before a UID.
    let mut plain = Vec::new();
    for p in [&back, &odd] {
        plain.extend_from_slice(p.as_os_str().as_bytes());
        plain.push(b'\n');
    }
    plain.extend_from_slice(format!("{}\t{uid}\r\n\n", series.display()).as_bytes());
    let manifest = root.join("plain.txt");
    std::fs::write(&manifest, plain).unwrap();
    let read = triage_ok(&[&[OsStr::new("--manifest"), manifest.as_os_str()][..], &json].concat());
    assert_eq!(read, walked);
}
