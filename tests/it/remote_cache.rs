//! A remote store's chunks are fetched once: kept in memory for the process, and on disk across
//! processes with `--cache DIR` (a second `info --exact` fetches no chunk).

use std::path::PathBuf;

use slabscope::LoadOptions;
use slabscope::formats::load_preview;

use crate::common::http::{Mode, serve};
use crate::common::{data, run, s};

/// The logged requests for chunks (not metadata files).
fn chunks(log: &[String]) -> Vec<&String> {
    log.iter()
        .filter(|r| {
            let name = r.split(' ').nth(1).unwrap().rsplit('/').next().unwrap();
            !(name.starts_with('.') || name == "zarr.json")
        })
        .collect()
}

#[test]
fn a_chunk_read_twice_by_one_process_is_fetched_once() {
    let server = serve(&data("zarr"), Mode::Normal, "");
    let url = PathBuf::from(server.url("v04_blosc.ome.zarr"));
    let opts = LoadOptions::default();
    // The coarsest dataset (s2, one chunk) as info reads it, then as level 0's pyramid level 2.
    let coarsest = load_preview(&url, &opts, 0).unwrap().unwrap();
    let full = slabscope::load(&url, &opts).unwrap();
    let level = full.volume.asked_level(2).unwrap();
    assert_eq!(
        level.data().to_f32_vec(),
        coarsest.volume.data().to_f32_vec()
    );
    let log = server.requests();
    let s2: Vec<&String> = (chunks(&log).into_iter())
        .filter(|r| r.contains("/s2/"))
        .collect();
    assert_eq!(s2.len(), 1, "{log:#?}");
}

#[test]
fn a_cache_on_disk_makes_the_second_read_fetch_no_chunk() {
    let server = serve(&data("zarr"), Mode::Normal, "");
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let local = data("zarr").join("v04_blosc.ome.zarr");
    let info = |input: &str, cached: bool| {
        let mut args = vec!["info", "--json", "--exact", input];
        if cached {
            args.extend(["--cache", s(&cache)]);
        }
        let ran = run(&args);
        assert!(ran.ok, "{}", ran.stderr);
        let mut json: serde_json::Value = serde_json::from_str(&ran.stdout).unwrap();
        json["file"] = serde_json::Value::Null;
        json
    };
    let url = server.url("v04_blosc.ome.zarr");
    let first = info(&url, true);
    let fetched = chunks(&server.requests()).len();
    assert_eq!(fetched, 27, "level 0's chunks");
    // Each entry named by a SHA-256, nothing else written.
    let names: Vec<String> = std::fs::read_dir(&cache)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names.len(), 27, "{names:?}");
    assert!(names.iter().all(|n| n.len() == 64), "{names:?}");
    let second = info(&url, true);
    let log = server.requests();
    assert_eq!(
        chunks(&log).len(),
        fetched,
        "no chunk fetched again: {log:#?}"
    );
    assert_eq!(first, second);
    assert_eq!(second, info(s(&local), false));
    // A cache that is a file is refused, naming it.
    let file = dir.path().join("file");
    std::fs::write(&file, "x").unwrap();
    let ran = run(&["info", &url, "--cache", s(&file)]);
    assert!(!ran.ok);
    assert_eq!(ran.stderr.lines().count(), 1, "{}", ran.stderr);
    assert!(
        ran.stderr.contains(s(&file)) && ran.stderr.contains("not a folder"),
        "{}",
        ran.stderr
    );
}
