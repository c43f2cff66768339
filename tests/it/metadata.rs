//! Hostile metadata (terminal escapes, a window-title sequence, BEL, DEL, a C1 control,
//! bidirectional overrides) in OME-Zarr, NRRD, NIfTI and OME-TIFF files, through every command and output
//! format: nothing of it reaches standard output or standard error raw, text shows it escaped by
//! the one rule (`slabscope::error::names`), and JSON stays valid and reads back to the text.

use std::path::{Path, PathBuf};
use std::process::Output;

use serde_json::Value;
use slabscope::error::names;

use crate::common::{data, slabscope};

/// An erase-screen, a bell, a window-title sequence, right-to-left and isolate overrides, DEL,
/// a C1 CSI and a right-to-left mark.
const HOSTILE: &str = "\u{1b}[2J\u{7}\u{1b}]0;pwned\u{7}\u{202e}\u{2066}\u{7f}\u{9b}\u{200f}";

/// Whether `c` must never be written raw: a control other than the line feeds that end lines,
/// or a bidirectional formatting character, or a line or paragraph separator.
fn hidden(c: char) -> bool {
    (c.is_control() && c != '\n')
        || matches!(
            c,
            '\u{061c}' | '\u{200e}' | '\u{200f}' | '\u{2028}'..='\u{202e}' | '\u{2066}'..='\u{2069}'
        )
}

/// Runs `slabscope` with `args`; fails when either stream holds anything raw or is not UTF-8.
/// Its status, standard output and standard error.
fn clean(args: &[&str]) -> (bool, String, String) {
    let out: Output = slabscope().args(args).output().unwrap();
    let text = |bytes: Vec<u8>, stream: &str| {
        let text = String::from_utf8(bytes).unwrap_or_else(|e| panic!("{args:?} {stream}: {e}"));
        let raw: Vec<char> = text.chars().filter(|&c| hidden(c)).collect();
        assert!(raw.is_empty(), "{args:?} {stream}: raw {raw:?} in {text}");
        text
    };
    let stdout = text(out.stdout, "stdout");
    let stderr = text(out.stderr, "stderr");
    (out.status.success(), stdout, stderr)
}

/// A copy of fixture store `name` at `to`.
fn copy_store(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        if e.file_type().unwrap().is_dir() {
            copy_store(&e.path(), &to.join(e.file_name()));
        } else {
            std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
        }
    }
}

/// An OME-Zarr store whose axis names, a unit, a dataset path and label name are hostile.
fn hostile_store(dir: &Path) -> PathBuf {
    let store = dir.join("hostile.ome.zarr");
    copy_store(&data("zarr/v04_blosc.ome.zarr"), &store);
    let level = format!("s1{HOSTILE}");
    std::fs::rename(store.join("s1"), store.join(&level)).unwrap();
    let attrs = store.join(".zattrs");
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(&attrs).unwrap()).unwrap();
    let m = &mut v["multiscales"][0];
    m["name"] = Value::from(HOSTILE);
    m["datasets"][1]["path"] = Value::from(level);
    for (axis, name) in m["axes"]
        .as_array_mut()
        .unwrap()
        .iter_mut()
        .zip(["z", "y", "x"])
    {
        axis["name"] = Value::from(format!("{name}{HOSTILE}"));
    }
    // Every axis in the unknown unit, so that their spacings keep the store's proportions (z in
    // parsecs beside x and y in micrometres made rays of 80,000 steps: 10 s a render).
    for axis in m["axes"].as_array_mut().unwrap() {
        axis["unit"] = Value::from(format!("parsec{HOSTILE}"));
    }
    std::fs::write(&attrs, serde_json::to_string(&v).unwrap()).unwrap();
    std::fs::create_dir(store.join("labels")).unwrap();
    let labels = serde_json::json!({ "labels": [format!("cells{HOSTILE}")] });
    std::fs::write(store.join("labels/.zattrs"), labels.to_string()).unwrap();
    std::fs::write(store.join("labels/.zgroup"), "{\"zarr_format\": 2}").unwrap();
    store
}

/// NRRD files: one read with hostile content, comments and key-value pairs (nothing of which
/// is shown), one whose encoding and one whose data file is hostile (errors that quote them).
fn hostile_nrrds(dir: &Path) -> [PathBuf; 3] {
    let raw = std::fs::read(data("ramp_i16_detached.raw")).unwrap();
    let header = |extra: &str| -> Vec<u8> {
        let mut h = format!(
            "NRRD0005\n# {HOSTILE}\ntype: int16\ndimension: 3\nsizes: 5 4 3\nendian: little\n\
             content: {HOSTILE}\nkey{HOSTILE}:={HOSTILE}\n{extra}"
        )
        .into_bytes();
        h.extend(b"# a raw C1 byte \x9b\n");
        h
    };
    let shown = dir.join("content.nrrd");
    let mut bytes = header("encoding: raw\n");
    bytes.extend(b"\n");
    bytes.extend(&raw);
    std::fs::write(&shown, bytes).unwrap();
    let encoding = dir.join("encoding.nrrd");
    let mut bytes = header(&format!("encoding: {HOSTILE}\n"));
    bytes.extend(b"\n");
    bytes.extend(&raw);
    std::fs::write(&encoding, bytes).unwrap();
    let detached = dir.join("detached.nhdr");
    let mut bytes = header(&format!("encoding: raw\ndata file: gone{HOSTILE}.raw\n"));
    bytes.extend(b"\n");
    std::fs::write(&detached, bytes).unwrap();
    [shown, encoding, detached]
}

/// NIfTI-1 files: one with a hostile description, auxiliary file and intent name (read), one
/// whose magic is an escape sequence (an error that quotes it).
fn hostile_niftis(dir: &Path) -> [PathBuf; 2] {
    let mut bytes = std::fs::read(data("ramp_u8.nii")).unwrap();
    let h = HOSTILE.as_bytes();
    for (at, len) in [(148, 80), (228, 24), (328, 16)] {
        let n = h.len().min(len);
        bytes[at..at + n].copy_from_slice(&h[..n]);
    }
    let read = dir.join("descrip.nii");
    std::fs::write(&read, &bytes).unwrap();
    bytes[344..348].copy_from_slice(b"\x1b]0;");
    let magic = dir.join("magic.nii");
    std::fs::write(&magic, &bytes).unwrap();
    [read, magic]
}

/// The hostile characters XML allows (no C0 control): DEL, a C1 CSI, bidirectional overrides
/// and a right-to-left mark.
const XML_HOSTILE: &str = "\u{7f}\u{9b}\u{202e}\u{2066}\u{200f}";

/// OME-TIFF files, their OME-XML edited in place (the same length): one read with a hostile
/// `Creator`, one whose `PhysicalSizeXUnit` is hostile (an error that quotes it).
fn hostile_ome_tiffs(dir: &Path) -> [PathBuf; 2] {
    let bytes = std::fs::read(data("ome/plain_z.ome.tif")).unwrap();
    // `to`, padded with `pad` to the length of `from`.
    let edit = |from: &str, to: &str, pad: char, name: &str| {
        let to = format!("{to}{}", pad.to_string().repeat(from.len() - to.len()));
        let at = bytes
            .windows(from.len())
            .position(|w| w == from.as_bytes())
            .unwrap();
        let mut out = bytes.clone();
        out[at..at + from.len()].copy_from_slice(to.as_bytes());
        let path = dir.join(name);
        std::fs::write(&path, out).unwrap();
        path
    };
    let creator = edit(
        "Creator=\"tifffile.py 2026.3.3\"",
        &format!("Creator=\"{XML_HOSTILE}\""),
        ' ',
        "creator.ome.tif",
    );
    let unit = edit(
        "PhysicalSizeXUnit=\"mm\" PhysicalSizeY=\"0.5\" PhysicalSizeYUnit=\"mm\"",
        &format!("PhysicalSizeXUnit=\"m{XML_HOSTILE}\" PhysicalSizeY=\"0.5\""),
        ' ',
        "unit.ome.tif",
    );
    [creator, unit]
}

/// What the rule shows of `HOSTILE` in text.
fn escaped() -> String {
    names::text(HOSTILE)
}

#[test]
fn store_metadata_is_escaped_in_info_analyze_render_and_slice() {
    let dir = tempfile::tempdir().unwrap();
    let store = hostile_store(dir.path());
    let f = store.to_str().unwrap();
    let (ok, text, stderr) = clean(&["info", f]);
    assert!(ok, "{stderr}");
    for shown in [
        format!("z{}", escaped()),
        format!("parsec{}", escaped()),
        format!("s1{}", escaped()),
        format!("cells{}", escaped()),
    ] {
        assert!(text.contains(&shown), "{shown} in {text}");
    }
    assert!(stderr.contains("no known length unit"), "{stderr}");
    // JSON: valid, the text itself read back.
    let (ok, json, _) = clean(&["info", f, "--json"]);
    assert!(ok);
    let v: Value = serde_json::from_str(&json).unwrap();
    let z = &v["ome_zarr"];
    assert_eq!(z["axes"][0]["name"], format!("z{HOSTILE}").as_str());
    assert_eq!(z["axes"][0]["unit"], format!("parsec{HOSTILE}").as_str());
    assert_eq!(z["levels"][1]["path"], format!("s1{HOSTILE}").as_str());
    assert_eq!(z["labels"][0], format!("cells{HOSTILE}").as_str());
    let notes = v["notes"].as_array().unwrap();
    assert!(
        notes.iter().any(|n| n.as_str().unwrap().contains(HOSTILE)),
        "{notes:?}"
    );
    assert!(json.contains("\\u202e") && json.contains("\\u009b") && json.contains("\\u007f"));
    let analyze = ["analyze", f, "--phases", "0", "--slabs", "2"];
    let (ok, _, stderr) = clean(&analyze);
    assert!(ok, "{stderr}");
    let (ok, json, _) = clean(&[&analyze[..], &["--json"]].concat());
    assert!(ok);
    let v: Value = serde_json::from_str(&json).unwrap();
    assert!(v.is_object());
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let png = out.join("view.png");
    let (ok, _, stderr) = clean(&["render", f, "-o", png.to_str().unwrap(), "--size", "64x48"]);
    assert!(ok, "{stderr}");
    let png = out.join("slice.png");
    let (ok, _, stderr) = clean(&["slice", f, "-o", png.to_str().unwrap(), "--size", "64x48"]);
    assert!(ok, "{stderr}");
    // Label images: one not there, and one listed but not there, each an error that names it.
    let (ok, _, stderr) = clean(&["info", f, "--label-image", "nuclei"]);
    assert!(
        !ok && stderr.contains(&format!("cells{}", escaped())),
        "{stderr}"
    );
    let hostile = format!("cells{HOSTILE}");
    let (ok, _, stderr) = clean(&["info", f, "--label-image", &hostile, "--json"]);
    assert!(!ok && stderr.lines().count() == 1, "{stderr}");
}

#[test]
fn nrrd_nifti_and_ome_tiff_metadata_never_reach_a_terminal_raw() {
    let dir = tempfile::tempdir().unwrap();
    let [content, encoding, detached] = hostile_nrrds(dir.path());
    let [descrip, magic] = hostile_niftis(dir.path());
    let [creator, unit] = hostile_ome_tiffs(dir.path());
    for good in [&content, &descrip, &creator] {
        let f = good.to_str().unwrap();
        for args in [
            vec!["info", f],
            vec!["info", f, "--json"],
            vec!["analyze", f, "--phases", "0", "--slabs", "2"],
            vec!["analyze", f, "--phases", "0", "--slabs", "2", "--json"],
        ] {
            let (ok, stdout, stderr) = clean(&args);
            assert!(ok, "{args:?}: {stderr}");
            if args.contains(&"--json") {
                serde_json::from_str::<Value>(&stdout).unwrap();
            }
        }
    }
    for bad in [&encoding, &detached, &magic, &unit] {
        let f = bad.to_str().unwrap();
        for args in [vec!["info", f], vec!["analyze", f, "--json"]] {
            let (ok, stdout, stderr) = clean(&args);
            assert!(!ok && stdout.is_empty(), "{args:?}");
            assert_eq!(stderr.lines().count(), 1, "one line: {stderr}");
        }
    }
    let (_, _, stderr) = clean(&["info", encoding.to_str().unwrap()]);
    assert!(
        stderr.contains("\\u{1b}]0;pwned\\u{7}\\u{202e}"),
        "the encoding quoted, escaped: {stderr}"
    );
    let (_, _, stderr) = clean(&["info", unit.to_str().unwrap()]);
    assert!(
        stderr.contains("m\\u{7f}\\u{9b}\\u{202e}\\u{2066}\\u{200f}"),
        "the unit quoted, escaped: {stderr}"
    );
    let (_, _, stderr) = clean(&["info", detached.to_str().unwrap()]);
    assert!(
        stderr.contains("gone\\u{1b}[2J"),
        "the data file named, escaped: {stderr}"
    );
}

#[test]
fn triage_rows_in_every_format_carry_nothing_raw() {
    let dir = tempfile::tempdir().unwrap();
    hostile_store(dir.path());
    hostile_nrrds(dir.path());
    hostile_niftis(dir.path());
    hostile_ome_tiffs(dir.path());
    let root = dir.path().to_str().unwrap();
    let triage = |extra: &[&str]| {
        let args = [&["triage", root, "--phases", "0", "--slabs", "2"], extra].concat();
        let (_, stdout, _) = clean(&args);
        stdout
    };
    let table = triage(&[]);
    assert_eq!(table.lines().count(), 9, "a header and eight rows: {table}");
    let csv = triage(&["--csv"]);
    assert_eq!(csv.lines().count(), 9, "{csv}");
    let rows: Vec<Value> = triage(&["--json"])
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(rows.len(), 8);
    let problems: Vec<String> = rows.iter().map(Value::to_string).collect();
    assert!(
        problems.iter().any(|p| p.contains("parsec")),
        "the store's note on its unit: {problems:?}"
    );
    // The folder listed by `info`, as text and JSON.
    let (ok, _, _) = clean(&["info", root]);
    assert!(ok);
    let (ok, json, _) = clean(&["info", root, "--json"]);
    assert!(ok);
    serde_json::from_str::<Value>(&json).unwrap();
}
