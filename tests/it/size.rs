//! Files that fit in a head (#22): no source file in `src/` over 600 lines.

use std::path::{Path, PathBuf};

use crate::common::repo;

/// The most lines a file of `src/` may have.
const MOST_LINES: usize = 600;

/// Every `.rs` file under `dir`, sorted.
fn sources(dir: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            files.extend(sources(&path));
        } else if path.extension().is_some_and(|e| e == "rs") {
            files.push(path);
        }
    }
    files.sort();
    files
}

#[test]
fn no_source_file_is_over_600_lines() {
    let root = repo("");
    let long: Vec<String> = sources(&repo("src"))
        .iter()
        .filter_map(|path| {
            let lines = std::fs::read_to_string(path).unwrap().lines().count();
            let name = path.strip_prefix(&root).unwrap().display();
            (lines > MOST_LINES).then(|| format!("{name}: {lines} lines"))
        })
        .collect();
    assert!(
        long.is_empty(),
        "over {MOST_LINES} lines (split along the seams the code has):\n{}",
        long.join("\n")
    );
}
