//! What both integration-test binaries (`tests/it`, `tests/slow`) share: where the fixtures are,
//! and the real `slabscope` binary run as a user runs it, written once.

#![allow(dead_code)] // each binary uses its own share of the helpers

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;

use serde_json::Value;

pub mod dicom;

/// A path inside the repository (`tests/data`, `src`, ...), wherever the tests run from.
pub fn repo(relative: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)
}

/// A fixture of `tests/data/` (`data("")` is the folder itself).
pub fn data(name: &str) -> PathBuf {
    repo("tests/data").join(name)
}

/// A DICOM fixture of `tests/data/dicom/` (`dicom_data("")` is the folder itself).
pub fn dicom_data(name: &str) -> PathBuf {
    repo("tests/data/dicom").join(name)
}

/// A file of the bad-input corpus `tests/bad/`.
pub fn bad(name: &str) -> PathBuf {
    repo("tests/bad").join(name)
}

/// The path of the `slabscope` binary cargo built for these tests.
pub fn binary() -> &'static str {
    env!("CARGO_BIN_EXE_slabscope")
}

/// A command that runs `slabscope`, to be given its arguments.
pub fn slabscope() -> Command {
    Command::new(binary())
}

/// A path as the `&str` a command line takes (the fixtures' paths are UTF-8).
pub fn s(path: &Path) -> &str {
    path.to_str().unwrap()
}

/// How one run of `slabscope` ended and what it printed.
pub struct Ran {
    /// Whether it exited with status 0.
    pub ok: bool,
    /// Its exit status (-1 when a signal killed it).
    pub code: i32,
    /// Its standard output, lossily decoded.
    pub stdout: String,
    /// Its standard error, lossily decoded.
    pub stderr: String,
}

impl Ran {
    /// Standard output followed by standard error: everything a user would see.
    pub fn text(&self) -> String {
        format!("{}{}", self.stdout, self.stderr)
    }
}

impl From<Output> for Ran {
    fn from(out: Output) -> Self {
        Self {
            ok: out.status.success(),
            code: out.status.code().unwrap_or(-1),
            stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
            stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
        }
    }
}

/// Runs `slabscope` with `args` and waits for it.
pub fn run(args: &[&str]) -> Ran {
    slabscope().args(args).output().unwrap().into()
}

/// The rows of JSON Lines output, one value a line.
pub fn rows(stdout: &str) -> Vec<Value> {
    stdout
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// Writes a `size`³ layers phantom to `dir/layers.nrrd` and returns its path.
pub fn layers(dir: &Path, size: u32) -> PathBuf {
    let path = dir.join("layers.nrrd");
    let size = size.to_string();
    let ran = run(&["phantom", "layers", "--size", &size, "-o", s(&path)]);
    assert!(ran.ok, "{}", ran.stderr);
    path
}

/// Whether `prlimit` is there to cap a run's address space (looked for once).
pub fn prlimit_available() -> bool {
    static FOUND: OnceLock<bool> = OnceLock::new();
    *FOUND.get_or_init(|| Command::new("prlimit").arg("--version").output().is_ok())
}

/// A command that runs `slabscope` killed after `seconds` (exit status 124) and, where `prlimit`
/// exists, with at most `address_space` bytes, so that a runaway allocation fails the run
/// instead of passing unseen. Arguments for `slabscope` are appended to it.
pub fn bounded(seconds: u32, address_space: u64) -> Command {
    let seconds = seconds.to_string();
    let mut cmd = if prlimit_available() {
        let mut c = Command::new("prlimit");
        c.arg(format!("--as={address_space}")).arg("timeout");
        c
    } else {
        Command::new("timeout")
    };
    cmd.arg(seconds).arg(binary());
    cmd
}

/// Copies the folder `from` and everything under it to `to` (made as needed).
pub fn copy_tree(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let target = to.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            copy_tree(&e.path(), &target);
        } else {
            std::fs::copy(e.path(), target).unwrap();
        }
    }
}

/// `info` of `file` as text and as JSON: checks that its second line names `format`, and gives
/// the line after it (the first of the reader's details) and the JSON.
pub fn info_details(file: &Path, format: &str) -> (String, Value) {
    let name = file.display();
    let text = run(&["info", s(file)]);
    assert!(text.ok, "{name}: {}", text.stderr);
    let lines: Vec<&str> = text.stdout.lines().collect();
    assert_eq!(lines[1], format!("format      {format}"), "{name}");
    let json = run(&["info", s(file), "--json"]);
    assert!(json.ok, "{name}: {}", json.stderr);
    (
        lines[2].to_string(),
        serde_json::from_str(&json.stdout).unwrap(),
    )
}
pub mod http;
pub mod zarr;
