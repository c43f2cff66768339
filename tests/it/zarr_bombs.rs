//! Issue #47, decompression past the budget: a chunk whose codec chain (gzip inside gzip, zstd
//! inside gzip), frames (a second zstd frame after a small first one) or nested shards decode
//! past its chunk's bytes is refused before `zarrs` decodes it, under a small budget, in one line
//! that names the store and the chunk and quotes none of its bytes. Every store is written here.

use std::io::Write;
use std::path::{Path, PathBuf};

use slabscope::{LoadOptions, load};

use crate::common::http::{Mode, Server, serve};
use crate::common::zarr::{codec, nested_shard, store};

/// The bytes a bomb decodes to: far past the 256 KiB chunk and the 64 MiB budget's quarter.
const BOMB: usize = 32 << 20;

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
    e.write_all(bytes).unwrap();
    e.finish().unwrap()
}

fn zstd(bytes: &[u8]) -> Vec<u8> {
    zstd::bulk::compress(bytes, 3).unwrap()
}

/// The error of loading `store` under a budget of 64 MiB: one line naming the store.
fn refused(store: &Path) -> String {
    let opts = LoadOptions {
        max_memory: 64 << 20,
        ..LoadOptions::default()
    };
    let e = load(store, &opts).unwrap_err().to_string();
    assert!(
        e.contains(&store.display().to_string()),
        "names the store: {e}"
    );
    assert!(!e.contains('\n'), "one line: {e}");
    assert!(
        !e.contains(&BOMB.to_string()),
        "quotes no byte of the file: {e}"
    );
    e
}

fn assert_decodes_to_more(e: &str) {
    assert!(
        e.contains("chunk c/0/0/0") && e.contains("decodes to more than the 262144 bytes"),
        "{e}"
    );
}

#[test]
fn gzip_inside_gzip_is_weighed_through_both() {
    let dir = tempfile::tempdir().unwrap();
    let chunk = gzip(&gzip(&vec![0u8; BOMB]));
    assert_decodes_to_more(&refused(&store(
        dir.path(),
        "bomb.zarr",
        &["bytes", "gzip", "gzip"],
        &chunk,
    )));
}

#[test]
fn zstd_inside_gzip_is_weighed_through_both() {
    let dir = tempfile::tempdir().unwrap();
    let chunk = gzip(&zstd(&vec![0u8; BOMB]));
    assert_decodes_to_more(&refused(&store(
        dir.path(),
        "bomb.zarr",
        &["bytes", "zstd", "gzip"],
        &chunk,
    )));
}

#[test]
fn a_second_zstd_frame_after_a_small_first_is_weighed() {
    let dir = tempfile::tempdir().unwrap();
    let mut chunk = zstd(&[1u8; 16]);
    chunk.extend(zstd(&vec![0u8; BOMB]));
    assert_decodes_to_more(&refused(&store(
        dir.path(),
        "bomb.zarr",
        &["bytes", "zstd"],
        &chunk,
    )));
}

#[test]
fn a_chain_that_fits_still_reads() {
    let dir = tempfile::tempdir().unwrap();
    let voxels: Vec<u8> = (0..64 * 64 * 64).map(|i| (i % 251) as u8).collect();
    let mut chunk = zstd(&voxels[..1000]);
    chunk.extend(zstd(&voxels[1000..]));
    let chunk = gzip(&chunk);
    let l = load(
        &store(dir.path(), "bomb.zarr", &["bytes", "zstd", "gzip"], &chunk),
        &LoadOptions::default(),
    )
    .unwrap();
    assert_eq!(
        l.volume.value([5, 3, 2]),
        ((2 * 64 + 3) * 64 + 5) as f32 % 251.0
    );
}

#[test]
fn a_shard_inside_a_shard_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let bomb = gzip(&vec![0u8; BOMB]);
    let e = refused(&nested_shard(dir.path(), "bomb.zarr", &bomb));
    assert!(e.contains("a shard inside a shard is not read"), "{e}");
}

#[test]
fn a_codec_on_whole_shards_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let sharding = format!(
        r#"{{"name": "sharding_indexed", "configuration": {{"chunk_shape": [32, 32, 32],
            "codecs": [{}, {}],
            "index_codecs": [{{"name": "bytes", "configuration": {{"endian": "little"}}}}]}}}}"#,
        codec("bytes"),
        codec("gzip")
    );
    let chunk = gzip(&vec![0u8; BOMB]);
    let e = refused(&store(
        dir.path(),
        "bomb.zarr",
        &[&sharding, "gzip"],
        &chunk,
    ));
    assert!(
        e.contains("a codec applied to whole shards is not read"),
        "{e}"
    );
}

/// A copy of the fixture store `name` in `dir`.
fn copy_store(name: &str, dir: &Path) -> PathBuf {
    let store = dir.join(name);
    crate::common::copy_tree(&crate::common::data(&format!("zarr/{name}")), &store);
    store
}

#[test]
fn a_level_asked_for_whose_chunks_cannot_be_read_is_an_error() {
    use crate::common::{run, s};
    let dir = tempfile::tempdir().unwrap();
    let store = copy_store("v04_blosc.ome.zarr", dir.path());
    // Level 1's first chunk: a Blosc header that states a megabyte.
    let mut header = vec![2u8, 1, 1, 2];
    header.extend(1_000_000u32.to_le_bytes());
    header.extend([0u8; 8]);
    std::fs::write(store.join("s1/0/0/0"), header).unwrap();
    let asked = run(&[
        "analyze",
        s(&store),
        "--resolution",
        "1",
        "--max-memory",
        "64M",
    ]);
    assert!(!asked.ok, "computed in its place: {}", asked.stdout);
    let e = asked.stderr.trim();
    assert!(e.contains(s(&store)) && e.contains("s1/0/0/0"), "{e}");
    assert!(
        e.contains("says it decodes to more") && !e.contains("1000000"),
        "{e}"
    );
    assert_eq!(e.lines().count(), 1, "{e}");
    // Level 0 asked for: read, the broken level never needed.
    let full = run(&["analyze", s(&store), "--max-memory", "64M"]);
    assert!(full.ok, "{}", full.stderr);
}

/// A Zarr v3 array of `shape` u8 in chunks of `chunk`, with no chunk written.
fn flood(dir: &Path, name: &str, shape: u64, chunk: u64) -> PathBuf {
    let store = dir.join(name);
    std::fs::create_dir_all(&store).unwrap();
    let meta = format!(
        r#"{{"zarr_format": 3, "node_type": "array", "shape": [{shape}, {shape}, {shape}],
            "data_type": "uint8", "fill_value": 0,
            "chunk_grid": {{"name": "regular", "configuration": {{"chunk_shape": [{chunk}, {chunk}, {chunk}]}}}},
            "chunk_key_encoding": {{"name": "default", "configuration": {{"separator": "/"}}}},
            "codecs": [{}]}}"#,
        codec("bytes")
    );
    std::fs::write(store.join("zarr.json"), meta).unwrap();
    store
}

#[test]
fn a_flood_of_tiny_chunks_is_refused_before_any_is_read() {
    // 512³ in one-voxel chunks: 134 million of them, hours of opening files that do not exist.
    let dir = tempfile::tempdir().unwrap();
    for (name, shape, chunk, reads) in [
        ("ones.zarr", 512, 1, "134217728"),
        ("eights.zarr", 512, 8, "262144"),
    ] {
        let e = refused(&flood(dir.path(), name, shape, chunk));
        assert!(
            e.contains(&format!("{reads} chunks of fewer than 4096 voxels")) && e.contains("65536"),
            "{e}"
        );
    }
    // Chunks of 16³ voxels (4096: not small) are read, all fill, none written.
    let v = load(
        &flood(dir.path(), "sixteens.zarr", 64, 16),
        &LoadOptions::default(),
    )
    .unwrap();
    assert_eq!(v.volume.dims(), [64, 64, 64]);
}

/// A store of 64 absent chunks served over loopback HTTP, each request answered after 50 ms: a
/// load of at least 1.6 s on two threads, however fast the machine, so a timeout of 0.1 s or
/// a cancellation at 10 ms falls inside it. (A store of 64,000 absent chunks on disk, which
/// these tests read before, loaded within a fifth of a second on a fast machine.) The server
/// and the URL it is read from.
fn slow_store(dir: &Path) -> (Server, String) {
    flood(dir, "slow.zarr", 64, 16);
    let server = serve(dir, Mode::Slow(50), "/c/");
    let url = server.url("slow.zarr");
    (server, url)
}

#[test]
fn a_timeout_stops_a_long_load_naming_the_file() {
    use crate::common::run;
    let dir = tempfile::tempdir().unwrap();
    let (_server, url) = slow_store(dir.path());
    let stopped = run(&["analyze", &url, "--timeout", "0.1"]);
    assert!(!stopped.ok);
    // Stopped in the load (the analysis' stop names no loading), on one line naming the store.
    let line = format!("slabscope: error: {url}: loading: stopped at the --timeout of 0.1 s\n");
    assert_eq!(stopped.stderr, line);
    assert!(stopped.stdout.is_empty());
}

#[test]
fn a_load_stops_when_its_cancellation_is_raised() {
    let dir = tempfile::tempdir().unwrap();
    let (_server, url) = slow_store(dir.path());
    let flag = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let opts = LoadOptions {
        cancel: slabscope::Cancel::new(std::sync::Arc::clone(&flag)),
        ..LoadOptions::default()
    };
    let raise = std::thread::spawn(move || {
        std::thread::sleep(std::time::Duration::from_millis(10));
        flag.store(true, std::sync::atomic::Ordering::Relaxed);
    });
    let loaded = load(Path::new(&url), &opts);
    raise.join().unwrap();
    assert!(
        matches!(loaded, Err(slabscope::Error::Cancelled)),
        "{loaded:?}"
    );
}

#[test]
fn triage_stops_a_long_load_at_its_timeout_in_the_row() {
    use crate::common::{rows, run};
    let dir = tempfile::tempdir().unwrap();
    let (_server, url) = slow_store(dir.path());
    let ran = run(&["triage", &url, "--json", "--timeout", "0.1"]);
    assert_eq!(ran.code, 1, "{}", ran.stderr);
    let rows = rows(&ran.stdout);
    assert_eq!(
        rows[0]["error"],
        "loading took longer than the 0.1 s timeout"
    );
    assert!(rows[0]["dims"].is_null(), "not loaded");
}
