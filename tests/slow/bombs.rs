//! Issue #47, the budget on hostile stores, measured: Zarr chunks that decode to a gibibyte
//! (gzip inside gzip, zstd inside gzip, a second zstd frame after a small first one), a shard
//! inside a shard, a pyramid level whose chunks are bombs asked for with `--resolution 1`, and
//! `triage` reading two bombs at once, each refused under `--max-memory 256M` with the peak
//! anonymous memory of the process at most the budget and 64 MiB.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::budget::peak_run;
use crate::common::s;
use crate::common::zarr::{nested_shard, store};

/// What each bomb decodes to: four times the budget.
const BOMB: usize = 1 << 30;

/// The budget the commands run under, and what they may take beyond it.
const BUDGET: u64 = 256 << 20;
const SLACK: u64 = 64 << 20;

/// `BOMB` zeros written into `w` a mebibyte at a time (never held whole).
fn zeros(mut w: impl Write) {
    let block = vec![0u8; 1 << 20];
    for _ in 0..BOMB >> 20 {
        w.write_all(&block).unwrap();
    }
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(bytes).unwrap();
    e.finish().unwrap()
}

fn gzip_of_zeros() -> Vec<u8> {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    zeros(&mut e);
    e.finish().unwrap()
}

fn zstd_of_zeros() -> Vec<u8> {
    let mut e = zstd::stream::Encoder::new(Vec::new(), 1).unwrap();
    zeros(&mut e);
    e.finish().unwrap()
}

/// Runs `slabscope args`: it fails, naming `named` (on stderr, or in triage's rows), within the
/// budget; its standard output.
fn refused_within_budget(args: &[&str], named: &Path) -> String {
    let (out, stdout, peak) = peak_run(args);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!out.status.success(), "{args:?}: {stdout}");
    assert!(
        stderr.contains(s(named)) || stdout.contains(s(named)),
        "{args:?}: {stderr}{stdout}"
    );
    assert!(
        peak <= BUDGET + SLACK,
        "{args:?}: peak anonymous memory {} MiB over the budget of 256 MiB and 64 MiB",
        peak >> 20
    );
    stdout
}

/// The four bombs in `dir`: codec chains of gzip in gzip and gzip over zstd, a second zstd frame
/// after a small one, and a shard inside a shard.
fn bombs(dir: &Path) -> [PathBuf; 4] {
    let gz = gzip_of_zeros();
    let zs = zstd_of_zeros();
    let mut frames = zstd::bulk::compress(&[1u8; 16], 3).unwrap();
    frames.extend(&zs);
    [
        store(dir, "gzgz.zarr", &["bytes", "gzip", "gzip"], &gzip(&gz)),
        store(dir, "zsgz.zarr", &["bytes", "zstd", "gzip"], &gzip(&zs)),
        store(dir, "frames.zarr", &["bytes", "zstd"], &frames),
        nested_shard(dir, "nested.zarr", &gz),
    ]
}

#[test]
fn bombs_are_refused_within_the_budget() {
    let _alone = crate::one_at_a_time();
    if !Path::new("/proc/self/status").exists() {
        eprintln!("skipped: no /proc to read the anonymous memory from");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let stores = bombs(dir.path());
    for store in &stores {
        refused_within_budget(&["analyze", s(store), "--max-memory", "256M"], store);
    }
    // Two bombs at once: each row refused, the two loads within one budget.
    let rows = refused_within_budget(
        &[
            "triage",
            s(&stores[0]),
            s(&stores[1]),
            "--json",
            "--max-memory",
            "256M",
        ],
        &stores[0],
    );
    let rows = crate::common::rows(&rows);
    assert_eq!(rows.len(), 2);
    assert!(rows.iter().all(|r| r["error"].is_string()), "{rows:?}");
}

#[test]
fn a_pyramid_level_of_bombs_asked_for_is_refused_within_the_budget() {
    let _alone = crate::one_at_a_time();
    if !Path::new("/proc/self/status").exists() {
        eprintln!("skipped: no /proc to read the anonymous memory from");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let store = dir.path().join("v04_blosc.ome.zarr");
    crate::common::copy_tree(&crate::common::data("zarr/v04_blosc.ome.zarr"), &store);
    // Level 1's first chunk: a Blosc header that states a gibibyte.
    let mut header = vec![2u8, 1, 1, 2];
    header.extend((BOMB as u32).to_le_bytes());
    header.extend([0u8; 8]);
    std::fs::write(store.join("s1/0/0/0"), header).unwrap();
    refused_within_budget(
        &[
            "analyze",
            s(&store),
            "--resolution",
            "1",
            "--max-memory",
            "256M",
        ],
        &store,
    );
}

/// A folder of hostile stores triaged under a small budget (#47): the bombs above (codec chains,
/// a second frame, a shard inside a shard) and the mutation harness's seeds beside them (tests/data/zarr/hostile), the loads sharing one budget, the peak
/// anonymous memory of the process at most that budget and 64 MiB; each bomb's row an error.
#[test]
fn a_folder_of_hostile_stores_is_triaged_within_a_small_budget() {
    let _alone = crate::one_at_a_time();
    if !Path::new("/proc/self/status").exists() {
        eprintln!("skipped: no /proc to read the anonymous memory from");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let bombs = bombs(dir.path());
    let seeds = crate::common::data("zarr/hostile");
    for name in ["gzip_gzip.zarr", "nested_shard.zarr", "small_chunks.zarr"] {
        crate::common::copy_tree(&seeds.join(name), &dir.path().join(name));
    }
    let small: u64 = 64 << 20;
    let args = ["triage", s(dir.path()), "--json", "--max-memory", "64M"];
    let (_, stdout, peak) = peak_run(&args);
    let rows = crate::common::rows(&stdout);
    assert_eq!(rows.len(), 7, "{stdout}");
    for bomb in &bombs {
        let name = bomb.file_name().unwrap().to_string_lossy();
        let row = rows
            .iter()
            .find(|r| r["path"].as_str().is_some_and(|p| p.ends_with(&*name)));
        assert!(
            row.is_some_and(|r| r["error"].is_string()),
            "{name}: {rows:?}"
        );
    }
    assert!(
        peak <= small + SLACK,
        "peak anonymous memory {} MiB over the budget of 64 MiB and 64 MiB",
        peak >> 20
    );
}

/// The side of the valid stores below, and of their chunks.
const SIDE: usize = 600;
const CHUNK: usize = 100;

/// The chunk at `kz` along z of level `level` (`SIDE` halved `level` times, rounding up) of a
/// store of layers `depth` slices deep along z, with a little texture in x and y: the same
/// for every chunk of a row along y and x (7·100 and 13·100 are multiples of 5), gzipped. A
/// chunk's voxels past the level's edge are zeros.
fn layered_chunk(level: u32, kz: usize, depth: usize) -> Vec<u8> {
    let n = SIDE.div_ceil(1 << level);
    let mut chunk = vec![0u8; CHUNK * CHUNK * CHUNK];
    for (i, v) in chunk.iter_mut().enumerate() {
        let (x, y, z) = (
            i % CHUNK,
            (i / CHUNK) % CHUNK,
            kz * CHUNK + i / (CHUNK * CHUNK),
        );
        if z < n {
            *v = (30 * ((z << level) / depth) + (x * 7 + y * 13) % 5) as u8;
        }
    }
    gzip(&chunk)
}

/// A valid OME-Zarr v0.5 store `name` in `dir`: `SIDE`³ u8 in layers `depth` slices deep along
/// z, three levels (`SIDE`, half, a quarter) in gzip chunks of `CHUNK`³, as a pyramid writer
/// would make it. About 2 MB on disk.
fn layered_store(dir: &Path, name: &str, depth: usize) -> PathBuf {
    let store = dir.join(name);
    let axis = |a: &str| format!(r#"{{"name": "{a}", "type": "space", "unit": "millimeter"}}"#);
    let mut datasets = Vec::new();
    for level in 0..3u32 {
        let (f, n) = (f64::from(1 << level), SIDE.div_ceil(1 << level));
        let shift = (f - 1.0) / 2.0;
        datasets.push(format!(
            r#"{{"path": "s{level}", "coordinateTransformations": [
                {{"type": "scale", "scale": [{f}, {f}, {f}]}},
                {{"type": "translation", "translation": [{shift}, {shift}, {shift}]}}]}}"#
        ));
        let array = store.join(format!("s{level}"));
        std::fs::create_dir_all(&array).unwrap();
        let meta = format!(
            r#"{{"zarr_format": 3, "node_type": "array", "shape": [{n}, {n}, {n}],
                "data_type": "uint8", "fill_value": 0,
                "chunk_grid": {{"name": "regular", "configuration": {{"chunk_shape": [{CHUNK}, {CHUNK}, {CHUNK}]}}}},
                "chunk_key_encoding": {{"name": "default", "configuration": {{"separator": "/"}}}},
                "codecs": [{}, {}], "dimension_names": ["z", "y", "x"]}}"#,
            crate::common::zarr::codec("bytes"),
            crate::common::zarr::codec("gzip")
        );
        std::fs::write(array.join("zarr.json"), meta).unwrap();
        let per = n.div_ceil(CHUNK);
        for kz in 0..per {
            let chunk = layered_chunk(level, kz, depth);
            for ky in 0..per {
                let row = array.join(format!("c/{kz}/{ky}"));
                std::fs::create_dir_all(&row).unwrap();
                for kx in 0..per {
                    std::fs::write(row.join(kx.to_string()), &chunk).unwrap();
                }
            }
        }
    }
    let group = format!(
        r#"{{"zarr_format": 3, "node_type": "group", "attributes": {{"ome": {{"version": "0.5",
            "multiscales": [{{"name": "/", "axes": [{}, {}, {}], "datasets": [{}]}}]}}}}}}"#,
        axis("z"),
        axis("y"),
        axis("x"),
        datasets.join(", ")
    );
    std::fs::write(store.join("zarr.json"), group).unwrap();
    store
}

/// Two valid 600³ stores triaged under `--max-memory 256M` (#47): the two loads share the one
/// budget, each row is a result, and the process stays within the budget and 64 MiB (before the
/// budget weighed an analysis on a coarser level with the volume's own voxels, the same two
/// stores peaked at 478 MiB).
#[test]
fn two_large_valid_stores_are_triaged_within_the_budget() {
    let _alone = crate::one_at_a_time();
    if !Path::new("/proc/self/status").exists() {
        eprintln!("skipped: no /proc to read the anonymous memory from");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let six = layered_store(dir.path(), "six.ome.zarr", SIDE / 6);
    let three = layered_store(dir.path(), "three.ome.zarr", SIDE / 3);
    let args = [
        "triage",
        s(&six),
        s(&three),
        "--json",
        "--max-memory",
        "256M",
    ];
    let (out, stdout, peak) = peak_run(&args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}{stdout}");
    let rows = crate::common::rows(&stdout);
    assert_eq!(rows.len(), 2, "{stdout}");
    for row in &rows {
        assert!(row["error"].is_null(), "{row}");
        assert_eq!(row["dims"], serde_json::json!([600, 600, 600]), "{row}");
        assert!(!row["slabs"].as_array().unwrap().is_empty(), "{row}");
    }
    eprintln!("peak anonymous memory: {} MiB", peak >> 20);
    assert!(
        peak <= BUDGET + SLACK,
        "peak anonymous memory {} MiB over the budget of 256 MiB and 64 MiB",
        peak >> 20
    );
}
