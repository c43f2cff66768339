//! The contract `tests/contract/` holds (snapshots taken before #22 moved anything): every
//! subcommand's `--help` byte for byte, every JSON key path of the snapshots still printed (new
//! keys are allowed), and every key name of those outputs documented in `docs/json.md`.
//!
//! A flag added on purpose changes a `--help`: rewrite its snapshot with
//! `slabscope SUBCOMMAND --help > tests/contract/help-SUBCOMMAND.txt` and say so in the commit.

use std::collections::BTreeSet;
use std::path::Path;
use std::sync::OnceLock;

use serde_json::Value;

use crate::common::{data, dicom_data, repo, run, s};

/// The snapshot folder.
fn contract(name: &str) -> std::path::PathBuf {
    repo("tests/contract").join(name)
}

/// The command line whose `--help` the snapshot `help-NAME.txt` holds (`root`: the program's).
fn help_command(name: &str) -> Vec<&str> {
    if name == "root" {
        vec!["--help"]
    } else {
        vec![name, "--help"]
    }
}

/// Where `got` first differs from `want`, as line number and both lines.
fn first_difference(want: &str, got: &str) -> String {
    let (mut want_lines, mut got_lines) = (want.lines(), got.lines());
    for line in 1.. {
        match (want_lines.next(), got_lines.next()) {
            (Some(w), Some(g)) if w == g => {}
            (None, None) => return "the same lines, different line endings".into(),
            (w, g) => {
                let [w, g] = [w, g].map(|l| l.unwrap_or("(no line)"));
                return format!("line {line}: snapshot {w:?}, now {g:?}");
            }
        }
    }
    unreachable!("the loop returns")
}

#[test]
fn every_help_equals_its_snapshot() {
    let mut names: Vec<String> = std::fs::read_dir(contract(""))
        .unwrap()
        .filter_map(|e| {
            let file = e.unwrap().file_name().to_string_lossy().into_owned();
            Some(
                file.strip_prefix("help-")?
                    .strip_suffix(".txt")?
                    .to_string(),
            )
        })
        .collect();
    names.sort();
    assert!(names.len() >= 8, "help snapshots: {names:?}");
    let mut changed = Vec::new();
    for name in &names {
        let want = std::fs::read_to_string(contract(&format!("help-{name}.txt"))).unwrap();
        let ran = run(&help_command(name));
        assert!(ran.ok, "{name}: {}", ran.stderr);
        if ran.stdout != want {
            let args = help_command(name).join(" ");
            changed.push(format!(
                "slabscope {args}: {}",
                first_difference(&want, &ran.stdout)
            ));
        }
    }
    assert!(
        changed.is_empty(),
        "--help differs from tests/contract/help-*.txt:\n{}",
        changed.join("\n")
    );
}

/// Every key path of `value` under `path`, as `tests/contract/keys.py` writes them: `.a.b` for
/// a key of an object, `[]` for the items of a list.
fn walk(value: &Value, path: &str, paths: &mut BTreeSet<String>) {
    match value {
        Value::Object(map) => {
            for (key, item) in map {
                let below = format!("{path}.{key}");
                walk(item, &below, paths);
                paths.insert(below);
            }
        }
        Value::Array(items) => {
            let below = format!("{path}[]");
            for item in items {
                walk(item, &below, paths);
            }
        }
        _ => {}
    }
}

/// The key paths of a JSON document, or of JSON Lines (one document a line), as `keys.py`.
fn key_paths(text: &str) -> BTreeSet<String> {
    let documents: Vec<Value> = serde_json::from_str(text).map_or_else(
        |_| {
            text.lines()
                .filter(|l| !l.trim().is_empty())
                .map(|l| serde_json::from_str(l).unwrap())
                .collect()
        },
        |document| vec![document],
    );
    let mut paths = BTreeSet::new();
    for document in &documents {
        walk(document, "", &mut paths);
    }
    paths
}

/// One JSON output of the contract: the snapshot it answers to (`keys-NAME.txt`), the command
/// line that printed it, and its key paths.
struct Printed {
    snapshot: &'static str,
    command: String,
    keys: BTreeSet<String>,
}

/// The fixtures of the snapshots, made in `dir`: a 48x48x64 body phantom, a folder of it and
/// `ramp_i16.nii`, and a manifest naming it and a file that is not there.
fn fixtures(dir: &Path) -> [String; 3] {
    let body = dir.join("body.nrrd");
    let made = run(&["phantom", "body", "--dims", "48x48x64", "-o", s(&body)]);
    assert!(made.ok, "{}", made.stderr);
    let folder = dir.join("folder");
    std::fs::create_dir(&folder).unwrap();
    std::fs::copy(&body, folder.join("body.nrrd")).unwrap();
    std::fs::copy(data("ramp_i16.nii"), folder.join("ramp_i16.nii")).unwrap();
    let manifest = dir.join("manifest.txt");
    let missing = dir.join("missing.nrrd");
    std::fs::write(&manifest, format!("{}\n{}\n", s(&body), s(&missing))).unwrap();
    [body, folder, manifest].map(|p| s(&p).to_string())
}

/// Runs every command of the contract once (in parallel), whichever test asks first.
fn printed() -> &'static [Printed] {
    static PRINTED: OnceLock<Vec<Printed>> = OnceLock::new();
    PRINTED.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let [body, folder, manifest] = fixtures(dir.path());
        let (derived, ct, dicom) = (dicom_data("derived"), dicom_data("ct"), dicom_data(""));
        let zarr = data("zarr/v05_sharded.ome.zarr");
        let (b, f, m) = (body.as_str(), folder.as_str(), manifest.as_str());
        let commands: [(&str, Vec<&str>); 14] = [
            ("analyze", vec!["analyze", b]),
            (
                "analyze-bottomup",
                vec!["analyze", b, "--method", "bottomup"],
            ),
            ("analyze-optimal", vec!["analyze", b, "--method", "optimal"]),
            ("analyze-explain", vec!["analyze", b, "--explain", "4"]),
            (
                "analyze-explain-bottomup",
                vec!["analyze", b, "--method", "bottomup", "--explain", "4"],
            ),
            (
                "analyze-axis",
                vec![
                    "analyze",
                    b,
                    "--axis",
                    "z",
                    "--phases",
                    "0",
                    "--background",
                    "none",
                ],
            ),
            ("info", vec!["info", b]),
            ("info-dicom", vec!["info", s(&derived), "--show-phi"]),
            ("info-zarr", vec!["info", s(&zarr)]),
            ("info-folder", vec!["info", f]),
            ("info-folder-dicom", vec!["info", s(&ct)]),
            ("triage", vec!["triage", f]),
            ("triage-dicom", vec!["triage", s(&dicom)]),
            ("triage-errors", vec!["triage", "--manifest", m]),
        ];
        std::thread::scope(|scope| {
            let runs: Vec<_> = commands
                .into_iter()
                .map(|(snapshot, mut args)| {
                    args.push("--json");
                    scope.spawn(move || print(snapshot, &args))
                })
                .collect();
            runs.into_iter().map(|r| r.join().unwrap()).collect()
        })
    })
}

/// Runs one command of the contract and reads the key paths of what it printed.
fn print(snapshot: &'static str, args: &[&str]) -> Printed {
    let command = format!("slabscope {}", args.join(" "));
    let ran = run(args);
    // Triage exits 1 when a volume failed, as two of these do on purpose; the rows still print.
    assert!(
        ran.ok || (snapshot.starts_with("triage") && ran.code == 1),
        "{command}: exit {}: {}",
        ran.code,
        ran.stderr
    );
    let keys = key_paths(&ran.stdout);
    assert!(
        !keys.is_empty(),
        "{command} printed no JSON: {}",
        ran.stderr
    );
    Printed {
        snapshot,
        command,
        keys,
    }
}

#[test]
fn every_snapshot_key_is_still_printed() {
    let mut lost = Vec::new();
    let mut checked = 0;
    for out in printed() {
        let file = format!("keys-{}.txt", out.snapshot);
        let text = std::fs::read_to_string(contract(&file)).unwrap();
        let missing: Vec<&str> = text
            .lines()
            .filter(|k| !k.is_empty() && !out.keys.contains(*k))
            .collect();
        if !missing.is_empty() {
            lost.push(format!(
                "{} ({file}) no longer prints {}",
                out.command,
                missing.join(", ")
            ));
        }
        checked += 1;
    }
    let snapshots = std::fs::read_dir(contract(""))
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .unwrap()
                .file_name()
                .to_string_lossy()
                .starts_with("keys-")
        })
        .count();
    assert_eq!(
        checked, snapshots,
        "a keys-*.txt snapshot has no command here"
    );
    assert!(lost.is_empty(), "{}", lost.join("\n"));
}

/// The name of the key a path ends with: `.volumes[].label` is `label`.
fn key_name(path: &str) -> &str {
    path.rsplit('.').next().unwrap_or(path)
}

#[test]
fn every_key_is_documented_in_docs_json_md() {
    let doc_path = repo("docs/json.md");
    let doc = std::fs::read_to_string(&doc_path).unwrap_or_else(|e| {
        panic!(
            "{}: {e} (it documents every JSON key, issue #22)",
            doc_path.display()
        )
    });
    let names: BTreeSet<&str> = printed()
        .iter()
        .flat_map(|out| out.keys.iter().map(|p| key_name(p)))
        .collect();
    let undocumented: Vec<&str> = names
        .into_iter()
        .filter(|name| !doc.contains(&format!("`{name}`")))
        .collect();
    assert!(
        undocumented.is_empty(),
        "docs/json.md names no `{}`",
        undocumented.join("`, `")
    );
}
