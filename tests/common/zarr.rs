//! Zarr stores written by the tests.

use std::path::{Path, PathBuf};

/// The JSON of a codec by its short name (`bytes`, `gzip`, `zstd`), or the JSON given.
pub fn codec(name: &str) -> String {
    match name {
        "bytes" => r#"{"name": "bytes", "configuration": {"endian": "little"}}"#.into(),
        "gzip" => r#"{"name": "gzip", "configuration": {"level": 5}}"#.into(),
        "zstd" => r#"{"name": "zstd", "configuration": {"level": 3, "checksum": false}}"#.into(),
        other => other.into(),
    }
}

/// A Zarr v3 array `name` in `dir` of 64³ u8 in one chunk of codecs `codecs` (names, or JSON
/// objects), whose chunk `c/0/0/0` holds `chunk`.
pub fn store(dir: &Path, name: &str, codecs: &[&str], chunk: &[u8]) -> PathBuf {
    let store = dir.join(name);
    std::fs::create_dir_all(store.join("c/0/0")).unwrap();
    let codecs: Vec<String> = codecs.iter().map(|c| codec(c)).collect();
    let meta = format!(
        r#"{{"zarr_format": 3, "node_type": "array", "shape": [64, 64, 64],
            "data_type": "uint8", "fill_value": 0,
            "chunk_grid": {{"name": "regular", "configuration": {{"chunk_shape": [64, 64, 64]}}}},
            "chunk_key_encoding": {{"name": "default", "configuration": {{"separator": "/"}}}},
            "codecs": [{}]}}"#,
        codecs.join(", ")
    );
    std::fs::write(store.join("zarr.json"), meta).unwrap();
    std::fs::write(store.join("c/0/0/0"), chunk).unwrap();
    store
}

/// A shard of 2³ inner chunks of 32³ whose first inner chunk is itself a shard of 2³ chunks of
/// 16³, the first of them `bomb` (gzip data), the others empty: a store `name` in `dir`.
pub fn nested_shard(dir: &Path, name: &str, bomb: &[u8]) -> PathBuf {
    let empty = [u8::MAX; 16];
    let mut inner = bomb.to_vec();
    inner.extend(0u64.to_le_bytes());
    inner.extend((bomb.len() as u64).to_le_bytes());
    for _ in 1..8 {
        inner.extend(empty);
    }
    let mut shard = inner.clone();
    shard.extend(0u64.to_le_bytes());
    shard.extend((inner.len() as u64).to_le_bytes());
    for _ in 1..8 {
        shard.extend(empty);
    }
    let index = r#""index_codecs": [{"name": "bytes", "configuration": {"endian": "little"}}]"#;
    let inner = format!(
        r#"{{"name": "sharding_indexed", "configuration": {{"chunk_shape": [16, 16, 16],
            "codecs": [{}, {}], {index}}}}}"#,
        codec("bytes"),
        codec("gzip")
    );
    let outer = format!(
        r#"{{"name": "sharding_indexed", "configuration": {{"chunk_shape": [32, 32, 32],
            "codecs": [{inner}], {index}}}}}"#
    );
    store(dir, name, &[&outer], &shard)
}
