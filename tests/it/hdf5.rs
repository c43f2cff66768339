//! HDF5 files written by h5py (`tests/data/hdf5/make_hdf5.py`): contiguous and chunked datasets,
//! gzip and shuffle, the newest file format, big-endian reals, every voxel read as h5py reads it
//! (`reference.json` freezes h5py's sums, first and last values); the dataset chosen by
//! `--array`, by `DXchange`'s path or as the only one; projections, ambiguity and hostile files
//! refused in one line naming the file.

use std::path::Path;

use slabscope::volume::VoxelType;
use slabscope::{Format, LoadOptions, load};

use crate::common::{data, info_details, run};

fn options(array: Option<&str>, volume: usize) -> LoadOptions {
    LoadOptions {
        part: slabscope::formats::PartOptions {
            array: array.map(str::to_string),
            volume,
            ..slabscope::formats::PartOptions::default()
        },
        ..LoadOptions::default()
    }
}

/// The 6x5x4 ramp `x + 10y + 100z` of `make_hdf5.py`, `wrap` applied to each value.
fn assert_ramp(name: &str, opts: &LoadOptions, ty: VoxelType, wrap: impl Fn(i64) -> i64) {
    let loaded =
        load(&data(&format!("hdf5/{name}")), opts).unwrap_or_else(|e| panic!("{name}: {e}"));
    assert_eq!(loaded.format, Format::Hdf5, "{name}");
    let v = &loaded.volume;
    assert_eq!(v.dims(), [6, 5, 4], "{name}");
    assert_eq!(v.voxel_type(), ty, "{name}");
    for z in 0..4 {
        for y in 0..5 {
            for x in 0..6 {
                let want = wrap((x + 10 * y + 100 * z) as i64) as f32;
                assert_eq!(v.value([x, y, z]), want, "{name}: voxel ({x},{y},{z})");
            }
        }
    }
}

#[test]
fn every_layout_and_filter_reads_to_the_voxel() {
    let none = options(None, 0);
    assert_ramp("ramp_u16_contiguous.h5", &none, VoxelType::U16, |v| v);
    assert_ramp("ramp_f32_gzip_shuffle.h5", &none, VoxelType::F32, |v| v);
    assert_ramp("ramp_i16_gzip_latest.h5", &none, VoxelType::I16, |v| v);
    // f64 is held as f32; these whole numbers are exact.
    assert_ramp("ramp_f64_be.h5", &none, VoxelType::F64, |v| v);
    // DXchange's reconstruction, u8 as h5py cast it (mod 256), chunked one slice a chunk.
    assert_ramp("dxchange_recon.h5", &none, VoxelType::U8, |v| v % 256);
    // A big-endian i64 ramp, chunked with gzip: held as f32, every value exact.
    assert_ramp(
        "wide_ints.h5",
        &options(Some("ramp"), 0),
        VoxelType::F32,
        |v| v,
    );
}

#[test]
fn the_dataset_is_named_by_its_path_with_or_without_the_slash() {
    assert_ramp(
        "two_volumes.h5",
        &options(Some("a"), 0),
        VoxelType::I32,
        |v| v,
    );
    assert_ramp(
        "two_volumes.h5",
        &options(Some("/b/c"), 0),
        VoxelType::U32,
        |v| v + 1,
    );
    let e = load(&data("hdf5/two_volumes.h5"), &options(None, 0))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(
            "holds 2 datasets of three or four dimensions (/a, /b/c): name one with --array"
        ),
        "{e}"
    );
    let e = load(&data("hdf5/two_volumes.h5"), &options(Some("/nope"), 0))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("holds no dataset /nope: its datasets are /a (4x5x6), /b/c (4x5x6)"),
        "{e}"
    );
}

#[test]
fn a_four_dimensional_dataset_is_a_series_of_volumes() {
    for t in 0..2 {
        assert_ramp("ramp_4d_i8.h5", &options(None, t), VoxelType::I8, |v| {
            (v + 1000 * t as i64) % 128
        });
    }
    let e = load(&data("hdf5/ramp_4d_i8.h5"), &options(None, 2))
        .unwrap_err()
        .to_string();
    assert!(e.contains("ramp_4d_i8.h5"), "{e}");
}

#[test]
fn element_size_um_is_the_spacing_and_its_absence_a_note() {
    let loaded = load(&data("hdf5/ramp_u16_contiguous.h5"), &options(None, 0)).unwrap();
    // element_size_um (z, y, x) = 2.5, 2.0, 1.5 µm.
    for (got, want) in loaded
        .volume
        .spacing()
        .into_iter()
        .zip([1.5e-3, 2.0e-3, 2.5e-3])
    {
        assert!((got - want).abs() < 1e-12, "{:?}", loaded.volume.spacing());
    }
    let loaded = load(&data("hdf5/ramp_f32_gzip_shuffle.h5"), &options(None, 0)).unwrap();
    assert_eq!(loaded.volume.spacing(), [1.0; 3]);
    assert!(
        loaded
            .notes
            .iter()
            .any(|n| n.contains("no element_size_um")),
        "{:?}",
        loaded.notes
    );
}

#[test]
fn dxchanges_pixel_size_is_the_voxel_size() {
    let objective = "/measurement/instrument/detection_system/objective";
    for (name, from) in [
        (
            "dxchange_resolution.h5",
            format!("{objective}/resolution (0.65 microns)"),
        ),
        (
            "dxchange_pixel_size.h5",
            format!(
                "/measurement/instrument/detector/pixel_size_x (6.5 um) over \
                 {objective}/magnification (10)"
            ),
        ),
    ] {
        let loaded = load(&data(&format!("hdf5/{name}")), &options(None, 0)).unwrap();
        for got in loaded.volume.spacing() {
            assert!((got - 0.65e-3).abs() < 1e-15, "{name}: {got}");
        }
        let note = format!("voxel size from DXchange's {from}");
        assert!(loaded.notes.contains(&note), "{name}: {:?}", loaded.notes);
    }
}

/// A `NeXus` `NXdata` group's axis datasets give the voxel size: their step (h5py's reading of
/// their first and last values, frozen in `reference.json`) in their `units`, matched to the
/// dimensions by the group's `axes` (read as far as `rust-hdf5` reads it), their lengths and
/// names.
#[test]
fn nexus_axes_give_the_voxel_size() {
    let text = std::fs::read_to_string(data("hdf5/reference.json")).unwrap();
    let reference: serde_json::Value = serde_json::from_str(&text).unwrap();
    let step = |file: &str, axis: &str| {
        let want = &reference[file][format!("/entry/data/{axis}")];
        let n = want["shape"][0].as_f64().unwrap();
        (want["last"].as_f64().unwrap() - want["first"].as_f64().unwrap()) / (n - 1.0)
    };
    for (file, to_mm, note) in [
        (
            "nexus.h5",
            [1e-6, 1e-3, 1e-3],
            "voxel size from the NeXus NXdata axes of /entry/data (z 2.5 um, y 2 um, x 1500 nm)",
        ),
        (
            "nexus_cube.h5",
            [1.0; 3],
            "voxel size from the NeXus NXdata axes of /entry/data (z 3 mm, y 2 mm, x 1 mm)",
        ),
    ] {
        let loaded = load(&data(&format!("hdf5/{file}")), &options(None, 0)).unwrap();
        let want = [
            step(file, "x") * to_mm[0],
            step(file, "y") * to_mm[1],
            step(file, "z") * to_mm[2],
        ];
        assert_eq!(loaded.volume.spacing(), want, "{file}");
        assert!(
            loaded.notes.iter().any(|n| n == note),
            "{file}: {:?}",
            loaded.notes
        );
    }
    // 1.5 µm, 2 µm, 2.5 µm; 1, 2, 3 mm.
    let loaded = load(&data("hdf5/nexus.h5"), &options(None, 0)).unwrap();
    for (got, want) in loaded.volume.spacing().iter().zip([1.5e-3, 2e-3, 2.5e-3]) {
        assert!((got - want).abs() < 1e-15, "{got}");
    }
}

/// What h5py read, frozen in `reference.json`, agrees with every 3-D dataset read here.
#[test]
fn h5pys_reading_agrees() {
    let text = std::fs::read_to_string(data("hdf5/reference.json")).unwrap();
    let reference: serde_json::Value = serde_json::from_str(&text).unwrap();
    let mut checked = 0;
    for (file, datasets) in reference.as_object().unwrap() {
        for (path, want) in datasets.as_object().unwrap() {
            if want["shape"].as_array().unwrap().len() != 3 || file == "projections.h5" {
                continue;
            }
            let loaded = load(&data(&format!("hdf5/{file}")), &options(Some(path), 0))
                .unwrap_or_else(|e| panic!("{file} {path}: {e}"));
            // 32- and 64-bit integers are held as f32: numpy's nearest f32 of each.
            let want = if want["f32"].is_object() {
                let rounded = want["f32"]["rounded"].as_u64().unwrap();
                let said = loaded.notes.iter().any(|n| {
                    n.starts_with(&format!("{rounded} ")) && n.contains(" beyond what an f32 holds")
                });
                assert_eq!(said, rounded > 0, "{file} {path}: {:?}", loaded.notes);
                &want["f32"]
            } else {
                want
            };
            let values = loaded.volume.data().to_f32_vec();
            let sum: f64 = values.iter().map(|&v| f64::from(v)).sum();
            assert_eq!(sum, want["sum"].as_f64().unwrap(), "{file} {path}");
            assert_eq!(
                f64::from(values[0]),
                want["first"].as_f64().unwrap(),
                "{file} {path}"
            );
            let last = f64::from(*values.last().unwrap());
            assert_eq!(last, want["last"].as_f64().unwrap(), "{file} {path}");
            checked += 1;
        }
    }
    // 14 in the .h5 files, the 8 padded Data of the Imaris file.
    assert_eq!(checked, 22);
}

#[test]
fn info_lists_the_datasets_in_text_and_json() {
    let (line, json) = info_details(&data("hdf5/dxchange_recon.h5"), "hdf5");
    assert_eq!(
        line,
        "datasets    /exchange/data (4x5x6 u8), /exchange/mask2d (5x6 u8)"
    );
    let listed = &json["hdf5"]["datasets"];
    assert_eq!(listed[0]["path"], "/exchange/data");
    assert_eq!(listed[0]["shape"], serde_json::json!([4, 5, 6]));
    assert_eq!(listed[0]["type"], "u8");
    let (line, _) = info_details(&data("hdf5/ramp_f64_be.h5"), "hdf5");
    assert_eq!(line, "datasets    /data (4x5x6 f64 big-endian)");
}

/// `info` on `path` fails in one line naming the file and saying `says`.
fn refused(path: &Path, extra: &[&str], says: &str) {
    let mut args = vec!["info", path.to_str().unwrap()];
    args.extend_from_slice(extra);
    let r = run(&args);
    assert!(!r.ok, "{}", path.display());
    let line = r.stderr.trim();
    assert_eq!(line.lines().count(), 1, "{line}");
    assert!(line.contains(&*path.to_string_lossy()), "{line}");
    assert!(line.contains(says), "{line}");
}

#[test]
fn projections_are_refused_unless_named() {
    let path = data("hdf5/projections.h5");
    refused(
        &path,
        &[],
        "holds projections, not a reconstruction (theta, data_white, data_dark beside /exchange/data)",
    );
    let r = run(&["info", path.to_str().unwrap(), "--array", "/exchange/data"]);
    assert!(r.ok, "{}", r.stderr);
    refused(
        &path,
        &["--array", "exchange/theta"],
        "dataset /exchange/theta has 1 dimensions",
    );
}

/// Replaces every occurrence of `from` in `bytes` with `to`; how many there were.
fn patch(bytes: &mut [u8], from: &[u8], to: &[u8]) -> usize {
    let mut n = 0;
    let mut i = 0;
    while i + from.len() <= bytes.len() {
        if &bytes[i..i + from.len()] == from {
            bytes[i..i + from.len()].copy_from_slice(to);
            n += 1;
        }
        i += 1;
    }
    n
}

fn le(values: &[u64], width: usize) -> Vec<u8> {
    values
        .iter()
        .flat_map(|v| v.to_le_bytes()[..width].to_vec())
        .collect()
}

#[test]
fn hostile_files_are_refused_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, bytes: &[u8]| {
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        path
    };
    let contiguous = std::fs::read(data("hdf5/ramp_u16_contiguous.h5")).unwrap();
    let chunked = std::fs::read(data("hdf5/ramp_f32_gzip_shuffle.h5")).unwrap();
    // Cut short, at several places.
    for cut in [8, 100, 900, contiguous.len() - 100] {
        refused(&write("short.h5", &contiguous[..cut]), &[], "short.h5");
    }
    // Dimensions of a trillion voxels each: weighed before anything is allocated.
    let mut huge = contiguous.clone();
    assert_eq!(
        patch(
            &mut huge,
            &le(&[4, 5, 6], 8),
            &le(&[1 << 40, 1 << 40, 6], 8)
        ),
        2
    );
    refused(&write("huge.h5", &huge), &[], "huge.h5");
    // Chunks of 2^31 elements a side, and chunks of zero.
    let mut big = chunked.clone();
    assert_eq!(
        patch(
            &mut big,
            &le(&[3, 2, 4, 4], 4),
            &le(&[1 << 31, 1 << 31, 4, 4], 4)
        ),
        1
    );
    refused(&write("chunks.h5", &big), &[], "chunks.h5");
    let mut zero = chunked.clone();
    assert_eq!(
        patch(&mut zero, &le(&[3, 2, 4, 4], 4), &le(&[0, 2, 4, 4], 4)),
        1
    );
    refused(&write("zero.h5", &zero), &[], "zero.h5");
    // The signature and nothing else.
    refused(&write("sig.h5", b"\x89HDF\r\n\x1a\n"), &[], "sig.h5");
    // A name that says HDF5 on bytes that are not.
    refused(&write("text.h5", b"hello"), &[], "the name says HDF5");
}

#[test]
fn a_budget_too_small_is_refused_before_reading() {
    let path = data("hdf5/ramp_u16_contiguous.h5");
    // 240 bytes stored and 240 held.
    refused(&path, &["--max-memory", "400"], "ramp_u16_contiguous.h5");
    let r = run(&["info", path.to_str().unwrap(), "--max-memory", "480"]);
    assert!(r.ok, "{}", r.stderr);
}

#[test]
fn an_imaris_file_is_read_at_its_finest_level_cut_to_its_size() {
    let path = data("hdf5/imaris.ims");
    for (t, c) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
        let opts = LoadOptions {
            part: slabscope::formats::PartOptions {
                channel: c,
                ..options(None, t).part
            },
            ..options(None, t)
        };
        // 8x8x8 stored, 6x5x4 the image: ramp + 1000t + 2000c.
        let add = 1000 * t as i64 + 2000 * c as i64;
        assert_ramp("imaris.ims", &opts, VoxelType::U16, |v| v + add);
    }
    let loaded = load(&path, &options(None, 0)).unwrap();
    // Extents 9, 10, 10 µm over 6, 5, 4 voxels.
    for (got, want) in loaded
        .volume
        .spacing()
        .into_iter()
        .zip([1.5e-3, 2.0e-3, 2.5e-3])
    {
        assert!((got - want).abs() < 1e-12, "{:?}", loaded.volume.spacing());
    }
    assert!(
        loaded
            .notes
            .iter()
            .any(|n| n.contains("2 channels: loaded channel 0")),
        "{:?}",
        loaded.notes
    );
    refused(
        &path,
        &["--channel", "2"],
        "holds 2 channels (numbered from 0), so there is no channel 2",
    );
    refused(&path, &["--volume", "2"], "imaris.ims");
    // A coarser level, named, is read as stored (padding and all).
    let level1 = "/DataSet/ResolutionLevel 1/TimePoint 0/Channel 0/Data";
    let loaded = load(&path, &options(Some(level1), 0)).unwrap();
    assert_eq!(loaded.volume.dims(), [4, 4, 4]);
    // Another HDF5 file holds one channel.
    refused(
        &data("hdf5/ramp_f64_be.h5"),
        &["--channel", "1"],
        "holds 1 channel",
    );
}

#[test]
fn an_imaris_files_coarser_level_is_the_first_picture() {
    use slabscope::formats::load_preview;
    let path = data("hdf5/imaris.ims");
    // 6x5x4 = 120 voxels at level 0; level 1, 3x3x2, is the pyramid's level 1.
    let preview = load_preview(&path, &options(None, 0), 20).unwrap().unwrap();
    assert_eq!(preview.format, Format::Hdf5);
    assert_eq!(preview.volume.dims(), [3, 3, 2]);
    assert_eq!(preview.volume.level().index, 1);
    assert!(preview.volume.data().to_f32_vec().iter().all(|&v| v == 7.0));
    // Its voxels are twice level 0's along x and z; y's 5 voxels halve to 3.
    for (got, want) in preview
        .volume
        .spacing()
        .into_iter()
        .zip([3.0e-3, 10.0e-3 / 3.0, 5.0e-3])
    {
        assert!((got - want).abs() < 1e-12, "{:?}", preview.volume.spacing());
    }
    // Level 0 small enough: no preview; nor of a file that is not Imaris's.
    assert!(
        load_preview(&path, &options(None, 0), 120)
            .unwrap()
            .is_none()
    );
    let plain = data("hdf5/ramp_f32_gzip_shuffle.h5");
    assert!(
        load_preview(&plain, &options(None, 0), 20)
            .unwrap()
            .is_none()
    );
}
