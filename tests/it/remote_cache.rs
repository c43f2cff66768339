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

/// The chunks kept in memory take up to 1/16 of `--max-memory`, so the budget's planner leaves
/// that share for them on a store at a URL: a budget that just holds level 0's analysis of the
/// local store moves the remote one's to pyramid level 1, saying so.
#[test]
fn a_remote_stores_analysis_leaves_the_chunks_share_of_the_budget() {
    let server = serve(&data("zarr"), Mode::Normal, "");
    let name = "v04_blosc.ome.zarr";
    let (url, local) = (server.url(name), data("zarr").join(name));
    let opts = LoadOptions::default();
    let read = |p: &std::path::Path| slabscope::load(p, &opts).unwrap().volume;
    let volume = read(&local);
    assert!(!volume.is_remote());
    assert!(read(&PathBuf::from(&url)).is_remote());
    let needed = slabscope::analysis::memory_needed(&volume, 0);
    let least = (needed..=2 * needed)
        .find(|&m| m - m / 16 >= needed)
        .unwrap();
    let level = |input: &str, max: u64| {
        let max = max.to_string();
        let ran = run(&["analyze", "--json", "--max-memory", &max, input]);
        assert!(ran.ok, "{input}: {}", ran.stderr);
        let json: serde_json::Value = serde_json::from_str(&ran.stdout).unwrap();
        // The view search's level (the slabs are then counted on every voxel, strip by strip).
        let views = json.get("views_resolution").unwrap_or(&json["resolution"]);
        (views["pyramid_level"].as_u64(), json["notes"].to_string())
    };
    assert_eq!(level(s(&local), needed).0, Some(0));
    assert_eq!(level(&url, least).0, Some(0));
    let (moved, notes) = level(&url, least - 1);
    assert_eq!(moved, Some(1), "{notes}");
    assert!(
        notes.contains("kept for the chunks fetched from the store"),
        "{notes}"
    );
}
