//! `analyze --resolution auto` (or a level by number) of a store at a URL reads the coarsest of
//! the store's datasets that serves the level picked, never a chunk of level 0; the analysis
//! equals that dataset's analysed as a volume of its own, whose value range it takes. A local
//! store's the same, without decoding level 0 (#47).

use std::path::{Path, PathBuf};

use slabscope::formats::load_serving;
use slabscope::volume::Resolution;
use slabscope::{LoadOptions, load};

use crate::common::http::{Mode, serve};
use crate::common::{data, run, s};

/// Level 1's voxel at `(x, y, z)`: layers along z, a pattern across them.
fn voxel(x: usize, y: usize, z: usize) -> u8 {
    ((z / 24) * 40 + (x * y + z) % 9) as u8
}

/// The `.zattrs` of an image of 3-D datasets `0`, `1`, ... of scales `scales` (µm).
fn zattrs(scales: &[f64]) -> String {
    let datasets: Vec<String> = (scales.iter().enumerate())
        .map(|(i, s)| {
            let t = (s - 1.0) / 2.0;
            format!(
                r#"{{"path": "{i}", "coordinateTransformations": [{{"type": "scale", "scale": [{s}, {s}, {s}]}},
                    {{"type": "translation", "translation": [{t}, {t}, {t}]}}]}}"#
            )
        })
        .collect();
    format!(
        r#"{{"multiscales": [{{"version": "0.4", "axes": [
            {{"name": "z", "type": "space", "unit": "micrometer"}},
            {{"name": "y", "type": "space", "unit": "micrometer"}},
            {{"name": "x", "type": "space", "unit": "micrometer"}}],
            "datasets": [{}]}}]}}"#,
        datasets.join(", ")
    )
}

/// An uncompressed u8 array of `n`³ voxels in chunks of 64³ at `dir`, its chunks written when
/// `chunks` (else every chunk is missing: the fill value).
fn array(dir: &Path, n: usize, chunks: bool) {
    array_of(dir, n, chunks.then_some(&voxel));
}

/// [`array`] with the voxels `voxel` gives, when given.
fn array_of(dir: &Path, n: usize, voxel: Option<&dyn Fn(usize, usize, usize) -> u8>) {
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(
        dir.join(".zarray"),
        format!(
            r#"{{"zarr_format": 2, "shape": [{n}, {n}, {n}], "chunks": [64, 64, 64],
                "dtype": "|u1", "compressor": null, "fill_value": 0, "order": "C",
                "filters": null}}"#
        ),
    )
    .unwrap();
    let Some(voxel) = voxel else {
        return;
    };
    let c = n / 64;
    for (cz, cy, cx) in
        (0..c).flat_map(|z| (0..c).flat_map(move |y| (0..c).map(move |x| (z, y, x))))
    {
        let mut bytes = Vec::with_capacity(64 * 64 * 64);
        for z in 0..64 {
            for y in 0..64 {
                for x in 0..64 {
                    bytes.push(voxel(cx * 64 + x, cy * 64 + y, cz * 64 + z));
                }
            }
        }
        std::fs::write(dir.join(format!("{cz}.{cy}.{cx}")), bytes).unwrap();
    }
}

/// In `dir`: `pyramid.ome.zarr`, a 256³ level 0 whose chunks are never written (a read of one
/// is a request the server logs) over a 128³ level 1; and `alone.ome.zarr`, that level 1 as an
/// image of its own, on the same grid.
fn stores(dir: &Path) -> (PathBuf, PathBuf) {
    let pyramid = dir.join("pyramid.ome.zarr");
    std::fs::create_dir_all(&pyramid).unwrap();
    std::fs::write(pyramid.join(".zgroup"), r#"{"zarr_format": 2}"#).unwrap();
    std::fs::write(pyramid.join(".zattrs"), zattrs(&[1.0, 2.0])).unwrap();
    array(&pyramid.join("0"), 256, false);
    array(&pyramid.join("1"), 128, true);
    let alone = dir.join("alone.ome.zarr");
    std::fs::create_dir_all(&alone).unwrap();
    std::fs::write(alone.join(".zgroup"), r#"{"zarr_format": 2}"#).unwrap();
    std::fs::write(alone.join(".zattrs"), zattrs(&[2.0])).unwrap();
    crate::common::copy_tree(&pyramid.join("1"), &alone.join("0"));
    (pyramid, alone)
}

/// The icosphere's coarsest level and the paper's lattice alone, for every analysis these tests
/// compare: which dataset is read and that the results agree do not hang on the viewpoints, and
/// the default 42 viewpoints over 8 lattice phases took 6 s an analysis of 128³ in the build
/// `cargo test` makes.
const FEW: [&str; 4] = ["--level", "0", "--phases", "0"];

/// Whether the logged request `r` asks a chunk of level 0 (`/0/` then a chunk key).
fn level_0_chunk(r: &str) -> bool {
    let path = r.split(' ').nth(1).unwrap();
    path.contains("/pyramid.ome.zarr/0/")
        && !path.ends_with("/.zarray")
        && !path.ends_with("/.zattrs")
}

#[test]
fn auto_reads_the_coarsest_dataset_that_serves_and_no_chunk_of_level_0() {
    let dir = tempfile::tempdir().unwrap();
    let (_, alone) = stores(dir.path());
    let server = serve(dir.path(), Mode::Normal, "");
    let url = server.url("pyramid.ome.zarr");
    let json = |args: &[&str]| -> serde_json::Value {
        let ran = run(&[args, &FEW].concat());
        assert!(ran.ok, "{args:?}: {}", ran.stderr);
        serde_json::from_str(&ran.stdout).unwrap()
    };
    let remote = json(&[
        "analyze",
        "--json",
        "--slabs",
        "3",
        "--resolution",
        "auto",
        &url,
    ]);
    let asked = server.requests();
    assert!(!asked.iter().any(|r| level_0_chunk(r)), "{asked:#?}");
    assert!(
        asked
            .iter()
            .any(|r| r.contains("/pyramid.ome.zarr/1/0.0.0")),
        "{asked:#?}"
    );
    // Level 0's grid, the analysis of level 1 ...
    assert_eq!(remote["dims"], serde_json::json!([256, 256, 256]));
    assert_eq!(remote["spacing"], serde_json::json!([0.001, 0.001, 0.001]));
    assert_eq!(remote["resolution"]["pyramid_level"], 1);
    assert_eq!(
        remote["resolution"]["dims"],
        serde_json::json!([128, 128, 128])
    );
    // ... equal to the analysis of level 1 as a volume of its own, its range level 1's.
    let own = json(&["analyze", "--json", "--slabs", "3", s(&alone)]);
    for key in ["range", "views", "best_axis", "partition", "params"] {
        assert_eq!(remote[key], own[key], "{key}");
    }
    // `--resolution 1` names it; `--resolution full` reads level 0 (its chunks missing: 404s).
    let one = json(&[
        "analyze",
        "--json",
        "--slabs",
        "3",
        "--resolution",
        "1",
        &url,
    ]);
    assert_eq!(one["partition"], own["partition"]);
    assert!(!server.requests().iter().any(|r| level_0_chunk(r)));
    let ran = run(&["info", "--exact", &url]);
    assert!(ran.ok, "{}", ran.stderr);
    assert!(server.requests().iter().any(|r| level_0_chunk(r)));
}

#[test]
fn the_level_served_is_the_local_stores_voxel_for_voxel() {
    let server = serve(&data("zarr"), Mode::Normal, "");
    let name = "v04_blosc.ome.zarr";
    let url = PathBuf::from(server.url(name));
    let opts = LoadOptions::default();
    let local = load(&data("zarr").join(name), &opts).unwrap();
    // 14×12×10: auto keeps level 0, which the store's own load reads.
    assert!(
        load_serving(&url, &opts, Resolution::Auto)
            .unwrap()
            .is_none()
    );
    assert!(
        load_serving(&url, &opts, Resolution::Full)
            .unwrap()
            .is_none()
    );
    // A local store's dataset serves as the remote one does.
    let path = data("zarr").join(name);
    let here = load_serving(&path, &opts, Resolution::Level(1)).unwrap();
    let here = here.unwrap().volume;
    assert_eq!(here.level().index, 1);
    assert_eq!(
        here.unread_finest().map(|f| f.dims),
        Some(local.volume.dims())
    );
    for k in 1..=2 {
        let served = load_serving(&url, &opts, Resolution::Level(k))
            .unwrap()
            .unwrap();
        let (a, b) = (&served.volume, local.volume.asked_level(k).unwrap());
        assert_eq!(a.level().index, k);
        assert_eq!(a.unread_finest().map(|f| f.dims), Some(local.volume.dims()));
        assert_eq!((a.dims(), a.spacing()), (b.dims(), b.spacing()));
        assert_eq!(a.transform(), b.transform());
        assert_eq!(a.data().to_f32_vec(), b.data().to_f32_vec(), "level {k}");
        if k == 1 {
            assert_eq!(a.data().to_f32_vec(), here.data().to_f32_vec());
        }
        assert!(
            served.notes.iter().any(|n| n.contains("level 0 not read")),
            "{:?}",
            served.notes
        );
    }
    let past = load_serving(&url, &opts, Resolution::Level(9)).unwrap_err();
    assert!(past.to_string().contains("resolution"), "{past}");
    assert!(
        !server.requests().iter().any(|r| r.contains("/s0/0")),
        "{:?}",
        server.requests()
    );
}

#[test]
fn a_local_stores_coarser_dataset_serves_without_decoding_level_0() {
    let dir = tempfile::tempdir().unwrap();
    let (pyramid, alone) = stores(dir.path());
    // Level 0's chunks: one corrupt (3 bytes where 64³ are due), the others absent.
    std::fs::write(pyramid.join("0").join("0.0.0"), b"bad").unwrap();
    let json = |args: &[&str]| -> serde_json::Value {
        let ran = run(&[args, &FEW].concat());
        assert!(ran.ok, "{args:?}: {}", ran.stderr);
        serde_json::from_str(&ran.stdout).unwrap()
    };
    let own = json(&["analyze", "--json", "--slabs", "3", s(&alone)]);
    for resolution in ["1", "auto"] {
        let args = [
            "analyze",
            "--json",
            "--slabs",
            "3",
            "--resolution",
            resolution,
        ];
        let local = json(&[&args[..], &[s(&pyramid)]].concat());
        assert_eq!(local["dims"], serde_json::json!([256, 256, 256]));
        assert_eq!(local["resolution"]["pyramid_level"], 1);
        for key in ["range", "views", "best_axis", "partition", "params"] {
            assert_eq!(local[key], own[key], "{resolution}: {key}");
        }
    }
    // Level 0 itself is refused, naming the chunk.
    let full = run(&["analyze", "--json", "--resolution", "full", s(&pyramid)]);
    assert!(!full.ok);
    assert!(full.stderr.contains("0.0.0"), "{}", full.stderr);
}

/// Whether pixel `(x, y)` of a 128² plane lies inside the disc of radius 56 at its centre.
fn inside(x: usize, y: usize) -> bool {
    let (dx, dy) = (x as f64 - 63.5, y as f64 - 63.5);
    dx * dx + dy * dy < 56.0 * 56.0
}

/// Level 1 of `full.ome.zarr`: [`voxel`] + 1 inside a cylinder along z, 0 around it.
fn body(x: usize, y: usize, z: usize) -> u8 {
    if inside(x, y) { voxel(x, y, z) + 1 } else { 0 }
}

#[test]
fn labels_of_an_analysis_at_a_served_level_are_level_0s() {
    // Level 0 of 256³ whose every 2³ block is level 1's voxel, so level 1 is its average.
    let dir = tempfile::tempdir().unwrap();
    let full = dir.path().join("full.ome.zarr");
    std::fs::create_dir_all(&full).unwrap();
    std::fs::write(full.join(".zgroup"), r#"{"zarr_format": 2}"#).unwrap();
    std::fs::write(full.join(".zattrs"), zattrs(&[1.0, 2.0])).unwrap();
    array_of(
        &full.join("0"),
        256,
        Some(&|x, y, z| body(x / 2, y / 2, z / 2)),
    );
    array_of(&full.join("1"), 128, Some(&body));
    let server = serve(dir.path(), Mode::Normal, "");
    let url = server.url("full.ome.zarr");
    let out = tempfile::tempdir().unwrap();
    let analysed = |store: &str, labels: &Path| -> serde_json::Value {
        let args = ["analyze", "--json", "--slabs", "3", "--axis", "z"];
        let more = ["--resolution", "auto", "--export-labels", s(labels), store];
        let ran = run(&[&args[..], &more[..]].concat());
        assert!(ran.ok, "{store}: {}", ran.stderr);
        serde_json::from_str(&ran.stdout).unwrap()
    };
    let (there, here) = (out.path().join("remote.nii"), out.path().join("local.nii"));
    let remote = analysed(&url, &there);
    let local = analysed(s(&full), &here);
    assert_eq!(remote["resolution"]["pyramid_level"], 1);
    assert_eq!(remote["partition"], local["partition"]);
    let opts = LoadOptions::default();
    let (a, b) = (load(&there, &opts).unwrap(), load(&here, &opts).unwrap());
    assert_eq!(a.volume.dims(), [256, 256, 256]);
    assert_eq!(
        a.volume.spacing(),
        [f64::from(0.001f32); 3],
        "NIfTI's f32 spacing"
    );
    let labels = a.volume.data().to_f32_vec();
    assert_eq!(labels, b.volume.data().to_f32_vec());
    // A voxel at z lies in level 1's slice z / 2; the background, found on level 0, is the
    // voxels outside the cylinder and only those.
    let slabs = remote["partition"]["slabs"].as_array().unwrap();
    let slab_of = |k: usize| {
        (slabs.iter())
            .position(|r| {
                r[0].as_u64().unwrap() as usize <= k && k < r[1].as_u64().unwrap() as usize
            })
            .unwrap() as f32
            + 1.0
    };
    for (i, &l) in labels.iter().enumerate() {
        let (x, y, z) = (i % 256, i / 256 % 256, i / 65536);
        let expected = if inside(x / 2, y / 2) {
            slab_of(z / 2)
        } else {
            0.0
        };
        assert_eq!(l, expected, "({x}, {y}, {z})");
    }
}
