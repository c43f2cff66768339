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
