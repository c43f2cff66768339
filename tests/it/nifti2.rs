//! NIfTI-2 files written by nibabel (`tests/data/nifti2/make.py`) read with the right voxels and
//! the affine nibabel reads back; CIFTI-2 and broken NIfTI-2 headers are clear errors.

use std::path::PathBuf;

use slabscope::volume::VoxelType;
use slabscope::{Format, LoadOptions, Loaded, load};

use crate::common::data;

fn path(name: &str) -> PathBuf {
    data(&format!("nifti2/{name}"))
}

fn open(name: &str, volume: usize) -> Loaded {
    let opts = LoadOptions {
        part: slabscope::formats::PartOptions {
            volume,
            ..slabscope::formats::PartOptions::default()
        },
        ..LoadOptions::default()
    };
    load(&path(name), &opts).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn error(bytes: &[u8], name: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join(name);
    std::fs::write(&file, bytes).unwrap();
    let e = load(&file, &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains(name), "the error names the file: {e}");
    e
}

/// The voxel at `(x, y, z)` of the ramp `(x + 10y + 100z) * scale + offset`.
fn ramp(x: usize, y: usize, z: usize, offset: f64, scale: f64) -> f32 {
    ((x + 10 * y + 100 * z) as f64 * scale + offset) as f32
}

fn assert_ramp(l: &Loaded, offset: f64, scale: f64) {
    let v = &l.volume;
    assert_eq!(v.dims(), [5, 4, 3]);
    for z in 0..3 {
        for y in 0..4 {
            for x in 0..5 {
                assert_eq!(
                    v.value([x, y, z]),
                    ramp(x, y, z, offset, scale),
                    "({x},{y},{z})"
                );
            }
        }
    }
}

/// nibabel's affine of `name` (RAS+, in the file's units) times `unit` mm.
fn nibabel_affine(name: &str, unit: f64) -> [[f64; 4]; 4] {
    let text = std::fs::read_to_string(path("expected.json")).unwrap();
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    let rows = json[name]["affine"].as_array().unwrap();
    std::array::from_fn(|r| {
        std::array::from_fn(|c| {
            let v = rows[r][c].as_f64().unwrap();
            if r < 3 { v * unit } else { v }
        })
    })
}

fn assert_affine(l: &Loaded, name: &str, unit: f64) {
    let got = l.volume.transform().matrix;
    let want = nibabel_affine(name, unit);
    for r in 0..4 {
        for c in 0..4 {
            assert!(
                (got[r][c] - want[r][c]).abs() < 1e-12,
                "{name}: affine {got:?}, nibabel {want:?}"
            );
        }
    }
}

#[test]
fn nifti2_files_read_as_nibabel_reads_them() {
    let l = open("ramp_i16_oblique.nii", 0);
    assert_eq!(l.format, Format::Nifti);
    assert_eq!(l.volume.voxel_type(), VoxelType::I16);
    assert_ramp(&l, -10.0, 2.0);
    assert_eq!(l.volume.spacing(), [0.5, 0.75, 2.0]);
    // The sform, in f64: exact to the bit where NIfTI-1 would have rounded it to f32.
    assert_affine(&l, "ramp_i16_oblique.nii", 1.0);

    // Big-endian, gzipped, the qform alone.
    let l = open("ramp_f32_be.nii.gz", 0);
    assert_ramp(&l, 0.25, 0.5);
    assert_eq!(l.volume.spacing(), [1.5, 1.5, 3.0]);
    assert_affine(&l, "ramp_f32_be.nii.gz", 1.0);

    // A header and image pair.
    let l = open("ramp_u16_pair.hdr", 0);
    assert_eq!(l.volume.voxel_type(), VoxelType::U16);
    assert_ramp(&l, 1000.0, 1.0);
    assert_affine(&l, "ramp_u16_pair.hdr", 1.0);
}

/// A header named by a relative path finds its image beside it (not under its folder twice).
#[test]
fn a_pair_named_by_a_relative_path_reads() {
    let relative = path("ramp_u16_pair.hdr");
    let here = std::env::current_dir().unwrap();
    let relative = relative
        .strip_prefix(&here)
        .expect("the data lie under the test's folder");
    assert!(relative.is_relative() && relative.parent().is_some_and(|p| !p.as_os_str().is_empty()));
    let l = load(relative, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(l.volume.voxel_type(), VoxelType::U16);
    assert_eq!(l.sources[1], relative.with_extension("img"));
}

#[test]
fn nifti2_4d_volumes_and_units() {
    let first = open("ramp_4d_um.nii", 0);
    assert_ramp(&first, 0.0, 1.0);
    assert!(
        first.notes.iter().any(|n| n.contains("loaded volume 0")),
        "{:?}",
        first.notes
    );
    assert_eq!(first.volume.spacing(), [0.001; 3], "micron units become mm");
    assert_affine(&first, "ramp_4d_um.nii", 0.001);
    assert_ramp(&open("ramp_4d_um.nii", 1), 500.0, 1.0);
    let e = load(
        &path("ramp_4d_um.nii"),
        &LoadOptions {
            part: slabscope::formats::PartOptions {
                volume: 2,
                ..slabscope::formats::PartOptions::default()
            },
            ..LoadOptions::default()
        },
    )
    .unwrap_err();
    assert!(e.to_string().contains("2 volumes"), "{e}");
}

#[test]
fn cifti2_is_named_not_read_as_a_volume() {
    let e = load(&path("cifti2_dscalar.nii"), &LoadOptions::default()).unwrap_err();
    let e = e.to_string();
    assert!(e.contains("CIFTI-2") && e.contains("3006"), "{e}");
}

#[test]
fn broken_nifti2_headers_are_clear_errors() {
    let good = std::fs::read(path("ramp_i16_oblique.nii")).unwrap();
    // Cut inside the header.
    let e = error(&good[..300], "short.nii");
    assert!(e.contains("300 of its 540 bytes"), "{e}");
    // Sent as text: the line-ending check's CR LF became LF.
    let mut text = good.clone();
    text.remove(8);
    let e = error(&text, "text.nii");
    assert!(e.contains("line-ending check"), "{e}");
    // 64-bit dimensions whose product overflows.
    let mut huge = good.clone();
    for k in 1..=3 {
        huge[16 + 8 * k..24 + 8 * k].copy_from_slice(&(1i64 << 40).to_le_bytes());
    }
    let e = error(&huge, "huge.nii");
    assert!(e.contains("more voxels than any file can"), "{e}");
    // Large but addressable dimensions: refused by the budget before anything is allocated.
    let mut big = good.clone();
    for k in 1..=3 {
        big[16 + 8 * k..24 + 8 * k].copy_from_slice(&(1i64 << 16).to_le_bytes());
    }
    let e = error(&big, "big.nii");
    assert!(!e.contains("more voxels than any file can"), "{e}");
    // vox_offset inside the 540-byte header.
    let mut inside = good;
    inside[168..176].copy_from_slice(&352i64.to_le_bytes());
    let e = error(&inside, "inside.nii");
    assert!(e.contains("inside the 540-byte header"), "{e}");
}
