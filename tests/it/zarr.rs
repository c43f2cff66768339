//! OME-Zarr stores written by zarr-python and ome-zarr-py (`tests/data/zarr/make.py`) read with
//! the voxels zarr-python reads back, the spacing and origin of their transforms in mm, their
//! time points, channels and label images; broken and hostile stores are clear errors.

use std::path::{Path, PathBuf};

use slabscope::formats::ZarrOptions;
use slabscope::formats::zarr::ZarrInfo;
use slabscope::volume::VoxelType;
use slabscope::{Format, LoadOptions, Loaded, load};

use crate::common::data;

fn path(name: &str) -> PathBuf {
    data(&format!("zarr/{name}"))
}

fn open_with(path: &Path, opts: &LoadOptions) -> Loaded {
    load(path, opts).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn open(name: &str) -> Loaded {
    open_with(&path(name), &LoadOptions::default())
}

/// `make.py`'s voxel at index `idx` (t/c/z/y/x, any trailing subset) before its type's offset.
fn formula(idx: &[usize]) -> usize {
    let weights = [211, 101, 29, 13, 7];
    idx.iter()
        .zip(&weights[5 - idx.len()..])
        .map(|(i, w)| i * w)
        .sum()
}

/// What zarr-python read back of array `key` of store `name`.
fn expected(name: &str, key: &str) -> serde_json::Value {
    let text = std::fs::read_to_string(path("expected.json")).unwrap();
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    json[name][key].clone()
}

/// The sum and the weighted sum (weights `i % 101` over the C-order index) zarr-python gives.
fn sums(values: impl Iterator<Item = f64>) -> (f64, f64) {
    values.enumerate().fold((0.0, 0.0), |(s, w), (i, v)| {
        (s + v, w + v * (i % 101) as f64)
    })
}

/// The voxels of `v` in zarr's C order (z slowest, x fastest: the volume's own order).
fn voxels(v: &slabscope::Volume) -> Vec<f64> {
    let [nx, ny, nz] = v.dims();
    let mut out = Vec::with_capacity(nx * ny * nz);
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                out.push(f64::from(v.value([x, y, z])));
            }
        }
    }
    out
}

#[test]
fn ngff_04_blosc_reads_every_voxel_in_micrometres() {
    let l = open("v04_blosc.ome.zarr");
    assert_eq!(l.format, Format::OmeZarr);
    let v = &l.volume;
    assert_eq!(v.dims(), [14, 12, 10]);
    assert_eq!(v.voxel_type(), VoxelType::U16);
    for (z, y, x) in [(0, 0, 0), (9, 11, 13), (4, 5, 6), (3, 10, 12)] {
        assert_eq!(
            v.value([x, y, z]),
            (formula(&[z, y, x]) % 997) as f32,
            "({x},{y},{z})"
        );
    }
    let e = expected("v04_blosc.ome.zarr", "s0");
    let (sum, weighted) = sums(voxels(&l.volume).into_iter());
    assert_eq!(sum, e["sum"].as_f64().unwrap());
    assert_eq!(weighted, e["weighted"].as_f64().unwrap());
    // Scale [2, 0.5, 0.25] µm over z, y, x; translation [10, 20, 30] µm.
    let s = v.spacing();
    for (got, want) in s.iter().zip([0.25e-3, 0.5e-3, 2e-3]) {
        assert!((got - want).abs() < 1e-15, "{s:?}");
    }
    let m = v.transform().matrix;
    for (k, want) in [30e-3, 20e-3, 10e-3].into_iter().enumerate() {
        assert!((m[k][3] - want).abs() < 1e-15, "{m:?}");
    }
    assert!(!v.transform().known, "no anatomical orientation");
    let info = l.details_as::<ZarrInfo>().unwrap();
    assert_eq!(
        (info.version.as_deref(), info.zarr_format),
        (Some("0.4"), 2)
    );
    assert_eq!(info.levels.len(), 3);
    assert_eq!(info.levels[1].shape, vec![5, 6, 7]);
    assert_eq!(info.chunks, vec![4, 5, 6]);
    assert_eq!(info.codecs, vec!["blosc/lz4"]);
}

#[test]
fn the_store_s_coarser_datasets_are_the_pyramid_s_levels() {
    let l = open("v04_blosc.ome.zarr");
    let levels = pyramid_levels(&l);
    assert_eq!(levels, [Some(0), Some(1), Some(2)]);
    for (k, key) in [(1, "s1"), (2, "s2")] {
        let level = l.volume.coarser(k);
        assert_eq!(level.level().index, k);
        // The store's voxels (make.py rounds its block means to u16), not slabscope's means.
        let read = voxels(&level);
        let e = expected("v04_blosc.ome.zarr", key);
        let (sum, weighted) = sums(read.into_iter());
        assert_eq!(sum, e["sum"].as_f64().unwrap(), "{key}");
        assert_eq!(weighted, e["weighted"].as_f64().unwrap(), "{key}");
        assert!(read_is_whole(&level), "{key}: integers as stored");
    }
    // A label image whose levels keep z is off the grid: its levels are computed.
    let opts = LoadOptions {
        zarr: ZarrOptions {
            label_image: Some("cells".into()),
            ..ZarrOptions::default()
        },
        ..LoadOptions::default()
    };
    let cells = open_with(&path("v05_sharded.ome.zarr"), &opts);
    let off = pyramid_levels(&cells);
    assert_eq!(off, [Some(0), None, None, None, None]);
    assert_eq!(cells.volume.coarser(1).dims(), [6, 5, 5]);
}

#[test]
fn a_coarse_dataset_is_read_alone_as_its_pyramid_level() {
    let store = path("v04_blosc.ome.zarr");
    let opts = LoadOptions::default();
    let full = open_with(&store, &opts).volume;
    let preview = |max| slabscope::formats::load_preview(&store, &opts, max).unwrap();
    let s1 = full.coarser(1);
    for (max, k) in [(s1.len(), 1), (s1.len() - 1, 2)] {
        let p = preview(max).unwrap_or_else(|| panic!("a preview within {max} voxels"));
        let (read, level) = (&p.volume, full.coarser(k));
        assert_eq!(p.format, Format::OmeZarr);
        assert_eq!(read.level().index, k, "within {max} voxels");
        assert_eq!(read.level().factor, level.level().factor);
        assert_eq!(read.dims(), level.dims());
        assert_eq!(read.transform(), level.transform(), "the pyramid's grid");
        assert_eq!(voxels(read), voxels(&level), "the store's voxels");
        // Level 0 is not read: the preview is quantized with its own range.
        let stats = read.stats();
        assert_eq!(read.level().range, [stats.min, stats.max]);
        assert!(read.level().range[0] >= full.level().range[0]);
        // Its own coarser levels are the pyramid's next ones.
        assert_eq!(read.coarser(1).dims(), full.coarser(k + 1).dims());
    }
    // Level 0 small enough, or no dataset as coarse as asked: nothing to preview.
    assert!(preview(full.len()).is_none());
    assert!(preview(full.coarser(2).len() - 1).is_none());
    // Not a store: nothing to preview.
    let nifti = data("ramp_u8.nii");
    assert!(
        slabscope::formats::load_preview(&nifti, &opts, 1)
            .unwrap()
            .is_none()
    );
}

/// The pyramid level each of the store's datasets is read as.
fn pyramid_levels(l: &Loaded) -> Vec<Option<usize>> {
    let info = l.details_as::<ZarrInfo>().unwrap();
    info.levels.iter().map(|l| l.pyramid_level).collect()
}

/// Whether every voxel of `v` is a whole number.
fn read_is_whole(v: &slabscope::Volume) -> bool {
    (0..v.len()).all(|i| v.data().get(i).fract() == 0.0)
}

#[test]
fn ngff_05_time_points_and_channels_in_nanometres() {
    let name = "v05_tczyx.ome.zarr";
    let first = open(name);
    assert!(
        first
            .notes
            .iter()
            .any(|n| n.contains("3 channels and 2 time points")),
        "{:?}",
        first.notes
    );
    let s = first.volume.spacing();
    for (got, want) in s.iter().zip([0.25, 0.25, 0.5]) {
        assert!((got - want).abs() < 1e-12, "{s:?}");
    }
    // Every time point and channel, in zarr's order, make up the whole array.
    let mut all = Vec::new();
    for t in 0..2 {
        for c in 0..3 {
            let opts = LoadOptions {
                part: slabscope::formats::PartOptions {
                    volume: t,
                    channel: c,
                    ..slabscope::formats::PartOptions::default()
                },
                ..LoadOptions::default()
            };
            let l = open_with(&path(name), &opts);
            assert_eq!(l.volume.dims(), [8, 7, 6]);
            assert_eq!(l.volume.voxel_type(), VoxelType::I16);
            let (z, y, x) = (5, 6, 7);
            let want = (formula(&[t, c, z, y, x]) % 997) as f32 - 300.0;
            assert_eq!(l.volume.value([x, y, z]), want, "t {t} c {c}");
            all.extend(voxels(&l.volume));
        }
    }
    let e = expected(name, "s0");
    let (sum, weighted) = sums(all.into_iter());
    assert_eq!(sum, e["sum"].as_f64().unwrap());
    assert_eq!(weighted, e["weighted"].as_f64().unwrap());
    let err = |volume, channel| {
        let opts = LoadOptions {
            part: slabscope::formats::PartOptions {
                volume,
                channel,
                ..slabscope::formats::PartOptions::default()
            },
            ..LoadOptions::default()
        };
        load(&path(name), &opts).unwrap_err().to_string()
    };
    assert!(err(2, 0).contains("holds 2 volumes (numbered from 0), so there is no volume 2"));
    assert!(err(0, 3).contains("holds 3 channels (numbered from 0), so there is no channel 3"));
}

#[test]
fn sharded_gzip_with_an_unwritten_chunk_and_a_label_image() {
    let name = "v05_sharded.ome.zarr";
    let l = open(name);
    let v = &l.volume;
    assert_eq!(v.dims(), [11, 10, 9]);
    assert_eq!(v.voxel_type(), VoxelType::F32);
    // The corner chunk is the fill value, and was never written.
    assert_eq!(v.value([1, 2, 3]), 0.0);
    let want = (formula(&[8, 9, 10]) % 997) as f32 * 0.25 - 50.0;
    assert_eq!(v.value([10, 9, 8]), want);
    let (sum, weighted) = sums(voxels(&l.volume).into_iter());
    let e = expected(name, "s0");
    assert_eq!(sum, e["sum"].as_f64().unwrap());
    assert_eq!(weighted, e["weighted"].as_f64().unwrap());
    let info = l.details_as::<ZarrInfo>().unwrap();
    assert_eq!(info.inner_chunks, Some(vec![4, 4, 4]));
    assert_eq!(info.chunks, vec![8, 8, 8]);
    assert_eq!(info.labels, vec!["cells"]);
    assert_eq!(info.codecs, vec!["sharding(bytes, gzip)"]);

    let opts = LoadOptions {
        zarr: ZarrOptions {
            label_image: Some("cells".into()),
            ..ZarrOptions::default()
        },
        ..LoadOptions::default()
    };
    let cells = open_with(&path(name), &opts);
    assert_eq!(cells.volume.voxel_type(), VoxelType::U8);
    assert_eq!(
        cells.details_as::<ZarrInfo>().unwrap().image,
        "labels/cells"
    );
    assert_eq!(
        cells.volume.value([10, 9, 8]),
        (formula(&[8, 9, 10]) / 40 % 5) as f32
    );
    assert!(cells.volume.labels().is_some(), "read as a label volume");
    let (sum, _) = sums(voxels(&cells.volume).into_iter());
    assert_eq!(
        sum,
        expected(name, "labels/cells/s0")["sum"].as_f64().unwrap()
    );

    let wrong = LoadOptions {
        zarr: ZarrOptions {
            label_image: Some("nuclei".into()),
            ..ZarrOptions::default()
        },
        ..LoadOptions::default()
    };
    let e = load(&path(name), &wrong).unwrap_err().to_string();
    assert!(
        e.contains("no label image \"nuclei\" (its label images: cells)"),
        "{e}"
    );
}

#[test]
fn a_plane_without_units_is_one_slice_with_a_note() {
    let l = open("v04_yx.ome.zarr");
    assert_eq!(l.volume.dims(), [9, 12, 1]);
    assert_eq!(l.volume.spacing(), [0.5, 0.5, 1.0]);
    assert!(l.notes.iter().any(|n| n.contains("no known length unit")));
    assert_eq!(l.volume.value([8, 11, 0]), (formula(&[11, 8]) % 997) as f32);
}

/// A copy of fixture store `name` in a temporary folder, to break.
fn copy(name: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let store = dir.path().join(name);
    crate::common::copy_tree(&path(name), &store);
    (dir, store)
}

fn error_of(store: &Path) -> String {
    let e = load(store, &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(&store.display().to_string()),
        "the error names the store: {e}"
    );
    assert!(!e.contains('\n'), "one line: {e}");
    e
}

#[test]
fn broken_stores_are_one_line_errors() {
    let (_keep, store) = copy("v04_blosc.ome.zarr");
    let zarray = store.join("s0/.zarray");
    let meta = std::fs::read_to_string(&zarray).unwrap();

    std::fs::write(store.join("s0/0/0/0"), b"not blosc at all").unwrap();
    assert!(error_of(&store).contains("s0"), "a corrupt chunk");

    let huge = meta.replace(
        "\"chunks\": [\n    4,\n    5,\n    6\n  ]",
        "\"chunks\": [100000, 100000, 100000]",
    );
    assert_ne!(huge, meta);
    std::fs::write(&zarray, &huge).unwrap();
    let e = error_of(&store);
    assert!(
        e.contains("one chunk of 100000x100000x100000 u16 voxels"),
        "{e}"
    );

    std::fs::write(&zarray, "{\"shape\": [").unwrap();
    assert!(error_of(&store).contains(".zarray: not JSON"));

    std::fs::remove_file(&zarray).unwrap();
    assert!(error_of(&store).contains("no array metadata"));

    std::fs::write(store.join(".zattrs"), "{\"multiscales\": []}").unwrap();
    assert!(error_of(&store).contains("`multiscales` is empty"));
}

#[test]
fn chunks_that_would_decode_past_their_size_are_refused_before_decoding() {
    use std::io::Write;
    // gzip: 1 MiB of zeros in a chunk of 5x4 u8.
    let (_keep, store) = copy("v04_yx.ome.zarr");
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
    e.write_all(&vec![0u8; 1 << 20]).unwrap();
    std::fs::write(store.join("s0/1/1"), e.finish().unwrap()).unwrap();
    let err = error_of(&store);
    assert!(
        err.contains("chunk s0/1/1 decodes to more than the 20 bytes of its chunk"),
        "{err}"
    );
    // zstd: a frame that says 1 GiB, in a chunk of 60 i16.
    let (_keep, store) = copy("v05_tczyx.ome.zarr");
    let frame = zstd::bulk::compress(&vec![0u8; 1 << 20], 19).unwrap();
    std::fs::write(store.join("s0/c/0/0/0/0/0"), frame).unwrap();
    let err = error_of(&store);
    assert!(
        err.contains("says it decodes to more than the 120 bytes"),
        "{err}"
    );
    assert!(
        !err.contains("1048576"),
        "no error quotes a file's bytes: {err}"
    );
}

#[cfg(unix)]
#[test]
fn a_fifo_named_like_a_chunk_cannot_block_the_read() {
    let (_keep, store) = copy("v04_blosc.ome.zarr");
    let chunk = store.join("s0/1/1/1");
    std::fs::remove_file(&chunk).unwrap();
    let made = std::process::Command::new("mkfifo").arg(&chunk).status();
    if !made.is_ok_and(|s| s.success()) {
        eprintln!("skipped: mkfifo is not available");
        return;
    }
    let e = error_of(&store);
    assert!(e.contains("FIFO"), "{e}");
}

#[test]
fn a_plain_zarr_array_reads_with_unit_spacing() {
    let dir = tempfile::tempdir().unwrap();
    let store = dir.path().join("grid.zarr");
    std::fs::create_dir_all(store.join("0/0")).unwrap();
    std::fs::write(
        store.join(".zarray"),
        r#"{"zarr_format": 2, "shape": [2, 3, 4], "chunks": [2, 3, 4], "dtype": "<i2",
            "compressor": null, "fill_value": 0, "order": "C", "filters": null,
            "dimension_separator": "/"}"#,
    )
    .unwrap();
    let bytes: Vec<u8> = (0..24i16).flat_map(|v| (v * 3 - 7).to_le_bytes()).collect();
    std::fs::write(store.join("0/0/0"), bytes).unwrap();
    let l = open_with(&store, &LoadOptions::default());
    assert_eq!(l.volume.dims(), [4, 3, 2]);
    assert_eq!(l.volume.value([3, 2, 1]), (23 * 3 - 7) as f32);
    assert_eq!(l.details_as::<ZarrInfo>().unwrap().version, None);
    assert_eq!(l.format_version, None);
}

#[test]
fn triage_takes_a_store_as_one_volume() {
    let dir = tempfile::tempdir().unwrap();
    let (_keep, store) = copy("v05_sharded.ome.zarr");
    let inside = dir.path().join("scans");
    std::fs::create_dir(&inside).unwrap();
    std::fs::rename(&store, inside.join("s.ome.zarr")).unwrap();
    let found = slabscope::triage::discover(std::slice::from_ref(&inside), &LoadOptions::default())
        .unwrap();
    let paths: Vec<&Path> = found.iter().map(|e| e.path.as_path()).collect();
    assert_eq!(paths, [inside.join("s.ome.zarr").as_path()]);
}

/// Fails unless loading `store` (with `opts`) is refused as a symbolic link out of the store,
/// naming the store and `entry`; the error.
#[cfg(unix)]
fn refused_out(store: &Path, opts: &LoadOptions, entry: &str) -> String {
    let e = load(store, opts).unwrap_err().to_string();
    assert!(
        e.contains(&store.display().to_string()),
        "names the store: {e}"
    );
    assert!(e.contains(entry), "names {entry}: {e}");
    assert!(
        e.contains("a symbolic link that leads out of the store"),
        "{e}"
    );
    assert!(!e.contains('\n'), "one line: {e}");
    e
}

#[cfg(unix)]
#[test]
fn symbolic_links_out_of_the_store_are_refused_and_links_inside_it_read() {
    use std::os::unix::fs::symlink;
    let opts = LoadOptions::default();
    let want = voxels(&open("v04_blosc.ome.zarr").volume);
    // A chunk linked to a file elsewhere, whose bytes 4..8 a Blosc header would read as a size.
    let (keep, store) = copy("v04_blosc.ome.zarr");
    let secret = keep.path().join("secret");
    std::fs::write(&secret, b"\x02\x01\x01\x01ABCDEFGHIJKL").unwrap();
    let chunk = store.join("s0/0/0/0");
    std::fs::remove_file(&chunk).unwrap();
    symlink(&secret, &chunk).unwrap();
    let e = refused_out(&store, &opts, "s0/0/0/0");
    let quoted = u32::from_le_bytes(*b"ABCD").to_string();
    assert!(
        !e.contains(&quoted) && !e.contains("ABCD"),
        "no byte of it: {e}"
    );
    // Linked inside the store, by a relative or an absolute link: read as ever.
    std::fs::remove_file(&chunk).unwrap();
    std::fs::create_dir(store.join("moved")).unwrap();
    std::fs::copy(path("v04_blosc.ome.zarr/s0/0/0/0"), store.join("moved/c")).unwrap();
    symlink("../../../moved/c", &chunk).unwrap();
    assert_eq!(voxels(&open_with(&store, &opts).volume), want);
    std::fs::remove_file(&chunk).unwrap();
    symlink(store.join("moved/c"), &chunk).unwrap();
    assert_eq!(voxels(&open_with(&store, &opts).volume), want);
    // A folder of chunks linked out of the store.
    let elsewhere = keep.path().join("elsewhere");
    std::fs::rename(store.join("s0/1"), &elsewhere).unwrap();
    symlink(&elsewhere, store.join("s0/1")).unwrap();
    refused_out(&store, &opts, "s0/1/");
    // The store itself named through a link: its tree is where the link leads.
    let (keep, store) = copy("v04_blosc.ome.zarr");
    let alias = keep.path().join("alias.zarr");
    symlink(&store, &alias).unwrap();
    assert_eq!(voxels(&open_with(&alias, &opts).volume), want);
}

#[cfg(unix)]
#[test]
fn metadata_and_label_images_out_of_the_store_are_refused() {
    use std::os::unix::fs::symlink;
    let opts = LoadOptions::default();
    // The group's attributes, and a dataset's array metadata, linked to another store's.
    let (_keep, other) = copy("v04_blosc.ome.zarr");
    let (_keep2, store) = copy("v04_blosc.ome.zarr");
    std::fs::remove_file(store.join(".zattrs")).unwrap();
    symlink(other.join(".zattrs"), store.join(".zattrs")).unwrap();
    refused_out(&store, &opts, ".zattrs");
    let (_keep3, store) = copy("v04_blosc.ome.zarr");
    std::fs::remove_file(store.join("s0/.zarray")).unwrap();
    symlink(other.join("s0/.zarray"), store.join("s0/.zarray")).unwrap();
    refused_out(&store, &opts, "dataset \"s0\": .zarray");
    // A label image, and the whole labels group, that lead to another store.
    let cells = LoadOptions {
        zarr: ZarrOptions {
            label_image: Some("cells".into()),
            ..ZarrOptions::default()
        },
        ..LoadOptions::default()
    };
    let (_keep4, other) = copy("v05_sharded.ome.zarr");
    let (_keep5, store) = copy("v05_sharded.ome.zarr");
    std::fs::remove_dir_all(store.join("labels/cells")).unwrap();
    symlink(other.join("labels/cells"), store.join("labels/cells")).unwrap();
    refused_out(&store, &cells, "labels/cells");
    // The same through the command line: one line on stderr, nothing on stdout.
    let ran = crate::common::run(&["info", store.to_str().unwrap(), "--label-image", "cells"]);
    assert!(!ran.ok && ran.stdout.is_empty(), "{}", ran.stdout);
    assert_eq!(ran.stderr.lines().count(), 1, "{}", ran.stderr);
    assert!(
        ran.stderr.contains("leads out of the store"),
        "{}",
        ran.stderr
    );
    let (_keep6, store) = copy("v05_sharded.ome.zarr");
    std::fs::remove_dir_all(store.join("labels")).unwrap();
    symlink(other.join("labels"), store.join("labels")).unwrap();
    refused_out(&store, &cells, "labels/zarr.json");
    // A label image linked inside the store reads.
    let (_keep7, store) = copy("v05_sharded.ome.zarr");
    std::fs::rename(store.join("labels/cells"), store.join("cells_moved")).unwrap();
    symlink("../cells_moved", store.join("labels/cells")).unwrap();
    assert!(open_with(&store, &cells).volume.labels().is_some());
}

/// A level 0 with an axis of no voxels is refused at once, naming the store: it once sent the
/// matching of the coarser datasets to the pyramid's levels round forever (found by the
/// mutation harness).
#[test]
fn an_axis_of_no_voxels_is_refused_at_once() {
    let (_dir, store) = copy("v05_tczyx.ome.zarr");
    let meta = store.join("s0/zarr.json");
    let text = std::fs::read_to_string(&meta).unwrap();
    let broken = text.replacen("    6,\n", "    0,\n", 1);
    assert_ne!(broken, text, "the z extent was edited");
    std::fs::write(&meta, broken).unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    let path = store.clone();
    std::thread::spawn(move || {
        let _ = tx.send(load(&path, &LoadOptions::default()).map(|_| ()));
    });
    let e = rx
        .recv_timeout(std::time::Duration::from_secs(20))
        .expect("the load returned")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("v05_tczyx.ome.zarr") && e.contains("contain a zero"),
        "{e}"
    );
}

/// Beyond the budget, a store's chunks are decoded into a file of the scratch folder given and
/// read from there: the same voxels as in memory.
#[test]
fn a_store_beyond_the_budget_is_decoded_into_the_scratch_folder() {
    let scratch = tempfile::tempdir().unwrap();
    // 14x12x10 u16 (3360 bytes) in chunks of 240 bytes, which a quarter of the budget holds.
    let (name, budget) = ("v04_blosc.ome.zarr", 1200);
    let in_memory = open(name);
    let tight = LoadOptions {
        max_memory: budget,
        ..LoadOptions::default()
    };
    let refused = load(&path(name), &tight).unwrap_err();
    assert!(
        matches!(refused, slabscope::Error::TooLarge { disk: true, .. }),
        "{refused}"
    );
    let decoded = open_with(
        &path(name),
        &LoadOptions {
            scratch: Some(scratch.path().to_path_buf()),
            ..tight
        },
    );
    assert!(decoded.volume.scratch_bytes() > 0, "{name}");
    assert_eq!(
        decoded.volume.scratch_bytes(),
        in_memory.volume.memory_bytes()
    );
    assert_eq!(
        decoded.volume.data().to_f32_vec(),
        in_memory.volume.data().to_f32_vec(),
        "{name}"
    );
    assert!(decoded.notes.iter().any(|n| n.contains("scratch file")));
    assert_eq!(std::fs::read_dir(scratch.path()).unwrap().count(), 0);
}
