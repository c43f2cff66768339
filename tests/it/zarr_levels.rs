//! Issue #43, every pyramid: a store whose datasets halve y and x only (ome-zarr-py's default
//! `write_image` keeps z) gives a pyramid level a dataset, with the store's voxels and its real
//! spacing, and `--resolution K` names its K-th dataset. The store is written here.

use std::path::{Path, PathBuf};

use slabscope::formats::zarr::ZarrInfo;
use slabscope::volume::Resolution;
use slabscope::{LoadOptions, load};

use crate::common::{run, s};

/// Level `k`'s shape (x, y, z): 16×16×6 halved in y and x each level.
fn dims(k: u32) -> [usize; 3] {
    [16 >> k, 16 >> k, 6]
}

/// The store's voxel (x, y, z) of dataset `k`: not slabscope's block mean of level 0's, so that
/// a level read from the store is told from one computed.
fn voxel(k: u32, [x, y, z]: [usize; 3]) -> u16 {
    (1000 * k as usize + x + 16 * y + 7 * z) as u16
}

/// A Zarr v3 OME-Zarr 0.5 store of three datasets, z/y/x u16 in µm (spacing 0.5 µm in y and x,
/// 2 µm in z), each dataset in one uncompressed chunk, its scale and translation on the grid
/// of a pyramid that keeps z.
fn store(dir: &Path) -> PathBuf {
    let store = dir.join("yx.ome.zarr");
    let mut datasets = Vec::new();
    for k in 0..3u32 {
        let [nx, ny, nz] = dims(k);
        let f = f64::from(1 << k);
        datasets.push(format!(
            r#"{{"path": "s{k}", "coordinateTransformations": [
                {{"type": "scale", "scale": [2.0, {s}, {s}]}},
                {{"type": "translation", "translation": [0.0, {t}, {t}]}}]}}"#,
            s = 0.5 * f,
            t = 0.5 * (f - 1.0) / 2.0,
        ));
        let array = store.join(format!("s{k}"));
        std::fs::create_dir_all(array.join("c/0/0")).unwrap();
        let meta = format!(
            r#"{{"zarr_format": 3, "node_type": "array", "shape": [{nz}, {ny}, {nx}],
                "data_type": "uint16", "fill_value": 0,
                "chunk_grid": {{"name": "regular", "configuration": {{"chunk_shape": [{nz}, {ny}, {nx}]}}}},
                "chunk_key_encoding": {{"name": "default", "configuration": {{"separator": "/"}}}},
                "codecs": [{{"name": "bytes", "configuration": {{"endian": "little"}}}}]}}"#
        );
        std::fs::write(array.join("zarr.json"), meta).unwrap();
        let mut bytes = Vec::new();
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    bytes.extend(voxel(k, [x, y, z]).to_le_bytes());
                }
            }
        }
        std::fs::write(array.join("c/0/0/0"), bytes).unwrap();
    }
    let axes = r#"[{"name": "z", "type": "space", "unit": "micrometer"},
        {"name": "y", "type": "space", "unit": "micrometer"},
        {"name": "x", "type": "space", "unit": "micrometer"}]"#;
    let group = format!(
        r#"{{"zarr_format": 3, "node_type": "group", "attributes": {{"ome": {{"version": "0.5",
            "multiscales": [{{"axes": {axes}, "datasets": [{}]}}]}}}}}}"#,
        datasets.join(", ")
    );
    std::fs::write(store.join("zarr.json"), group).unwrap();
    store
}

#[test]
fn datasets_halved_in_y_and_x_are_levels_with_their_own_spacing() {
    let dir = tempfile::tempdir().unwrap();
    let store = store(dir.path());
    let loaded = load(&store, &LoadOptions::default()).unwrap();
    let info = loaded.details_as::<ZarrInfo>().unwrap();
    let levels: Vec<Option<usize>> = info.levels.iter().map(|l| l.pyramid_level).collect();
    assert_eq!(levels, [Some(0), Some(1), Some(2)]);
    let v = &loaded.volume;
    assert_eq!(
        v.level_dims(),
        [dims(0), dims(1), dims(2), [2, 2, 3], [1, 1, 2], [1, 1, 1]],
        "the store's levels, then every axis halved"
    );
    for k in 1..=2u32 {
        let level = v.coarser(k as usize);
        assert_eq!(level.dims(), dims(k));
        let f = f64::from(1 << k);
        assert_eq!(level.level().factor, [1 << k, 1 << k, 1]);
        assert_eq!(level.spacing(), [0.5e-3 * f, 0.5e-3 * f, 2e-3], "mm");
        // The store's voxels, at the centre of the level-0 voxels they stand for.
        let [nx, ny, nz] = dims(k);
        for p in [[0, 0, 0], [nx - 1, ny - 1, nz - 1], [1, 2, 3]] {
            assert_eq!(level.value(p), f32::from(voxel(k, p)), "level {k} at {p:?}");
        }
        let centre = (f - 1.0) / 2.0;
        let a = v.transform().apply([centre, centre, 0.0]);
        let b = level.transform().apply([0.0; 3]);
        assert!((0..3).all(|m| (a[m] - b[m]).abs() < 1e-15), "{a:?} {b:?}");
    }
    // Past the store's last dataset every axis is halved: level 3 averages level 2's 2×2×2.
    let (two, three) = (v.coarser(2), v.coarser(3));
    assert_eq!(three.level().factor, [8, 8, 2]);
    let mean: f32 = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]
        .iter()
        .flat_map(|&[x, y, _]| [two.value([x, y, 0]), two.value([x, y, 1])])
        .sum::<f32>()
        / 8.0;
    assert_eq!(three.value([0, 0, 0]), mean);
    // Resolutions name the store's datasets.
    let chain = v.level_dims();
    assert_eq!(Resolution::Level(2).level(&chain).unwrap(), 2);
    assert!(Resolution::Level(6).level(&chain).is_err());
}

#[test]
fn resolution_k_analyses_the_store_s_kth_dataset_and_the_preview_reads_it() {
    let dir = tempfile::tempdir().unwrap();
    let store = store(dir.path());
    let ran = run(&["analyze", s(&store), "--resolution", "1", "--json"]);
    assert!(ran.ok, "{}", ran.stderr);
    let json: serde_json::Value = serde_json::from_str(&ran.stdout).unwrap();
    let r = &json["resolution"];
    assert_eq!(r["pyramid_level"], 1, "{r}");
    assert_eq!(r["factor"], serde_json::json!([2, 2, 1]), "{r}");
    assert_eq!(r["dims"], serde_json::json!([8, 8, 6]), "{r}");
    // The first picture within 8×8×6 voxels is dataset s1, read alone.
    let opts = LoadOptions::default();
    let preview = slabscope::formats::load_preview(&store, &opts, 8 * 8 * 6)
        .unwrap()
        .unwrap();
    let p = &preview.volume;
    assert_eq!((p.level().index, p.level().factor), (1, [2, 2, 1]));
    assert_eq!(p.value([3, 4, 5]), f32::from(voxel(1, [3, 4, 5])));
    assert_eq!(
        p.coarser(1).dims(),
        dims(2),
        "its next level: the store's s2"
    );
}
