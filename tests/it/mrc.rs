//! MRC/CCP4 files written by mrcfile, the CCP-EM reference library (`tests/data/mrc/make_mrc.py`):
//! every mode read to the voxel, the voxel size from the cell and sampling in ångström, the
//! extended header skipped, the axes reordered as MAPC, MAPR, MAPS say, and what is no volume
//! refused in one line naming the file.

use slabscope::volume::VoxelType;
use slabscope::{Format, LoadOptions, load};

use crate::common::{data, info_details, run};

/// The 6x5x4 ramp `x + 10y + 100z` of `make_mrc.py`, `wrap` applied to each value.
fn assert_ramp(name: &str, ty: VoxelType, wrap: impl Fn(i64) -> i64) {
    let loaded = load(&data(&format!("mrc/{name}")), &LoadOptions::default())
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    assert_eq!(loaded.format, Format::Mrc, "{name}");
    let v = &loaded.volume;
    assert_eq!(v.dims(), [6, 5, 4], "{name}");
    assert_eq!(v.voxel_type(), ty, "{name}");
    // 1.5, 2.0 and 2.5 Å.
    for (got, want) in v.spacing().into_iter().zip([1.5e-7, 2.0e-7, 2.5e-7]) {
        assert!(
            (got - want).abs() < 1e-15,
            "{name}: spacing {:?}",
            v.spacing()
        );
    }
    for z in 0..4 {
        for y in 0..5 {
            for x in 0..6 {
                let want = wrap((x + 10 * y + 100 * z) as i64) as f32;
                let got = v.value([x, y, z]);
                assert_eq!(got, want, "{name}: voxel ({x},{y},{z})");
            }
        }
    }
}

#[test]
fn every_mode_reads_to_the_voxel() {
    assert_ramp("ramp_i16.mrc", VoxelType::I16, |v| v);
    assert_ramp("ramp_f32.mrc", VoxelType::F32, |v| v);
    assert_ramp("ramp_u16.mrc", VoxelType::U16, |v| v);
    assert_ramp("ramp_i8.mrc", VoxelType::I8, |v| v % 128);
    // Mode 12, f16, widened: these whole numbers are exact in f16.
    assert_ramp("ramp_f16.mrc", VoxelType::F32, |v| v);
}

#[test]
fn the_extended_header_is_skipped_by_its_declared_size() {
    assert_ramp("ramp_ext.mrc", VoxelType::I16, |v| v);
}

#[test]
fn axes_stored_out_of_order_are_put_in_x_y_z_order() {
    // Stored with the columns along Z and the sections along X.
    assert_ramp("ramp_zyx.mrc", VoxelType::I16, |v| v);
    let loaded = load(&data("mrc/ramp_zyx.mrc"), &LoadOptions::default()).unwrap();
    assert!(
        loaded.notes.iter().any(|n| n.contains("reordered")),
        "{:?}",
        loaded.notes
    );
}

#[test]
fn what_is_no_volume_is_refused_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let refused = |path: &std::path::Path, says: &str| {
        let r = run(&["info", path.to_str().unwrap()]);
        assert!(!r.ok, "{}", path.display());
        let line = r.stderr.trim();
        assert_eq!(line.lines().count(), 1, "{line}");
        assert!(line.contains(&*path.to_string_lossy()), "{line}");
        assert!(line.contains(says), "{line}");
    };
    refused(&data("mrc/tilts.st"), "a stack of 4 images");
    let bytes = std::fs::read(data("mrc/ramp_i16.mrc")).unwrap();
    // Complex values (mode 4).
    let mut complex = bytes.clone();
    complex[12..16].copy_from_slice(&4i32.to_le_bytes());
    let path = dir.path().join("fourier.mrc");
    std::fs::write(&path, &complex).unwrap();
    refused(&path, "complex values");
    // Cut short.
    let path = dir.path().join("short.mrc");
    std::fs::write(&path, &bytes[..bytes.len() - 10]).unwrap();
    refused(&path, "short.mrc");
    // An extended header past the end.
    let mut long = bytes.clone();
    long[92..96].copy_from_slice(&1_000_000i32.to_le_bytes());
    let path = dir.path().join("long.mrc");
    std::fs::write(&path, &long).unwrap();
    refused(&path, "long.mrc");
    // Axes named twice.
    let mut twice = bytes.clone();
    twice[64..68].copy_from_slice(&1i32.to_le_bytes());
    twice[68..72].copy_from_slice(&1i32.to_le_bytes());
    let path = dir.path().join("twice.mrc");
    std::fs::write(&path, &twice).unwrap();
    refused(&path, "MAPC, MAPR, MAPS are 1, 1");
    // A header and nothing else, and less than a header.
    let path = dir.path().join("head.mrc");
    std::fs::write(&path, &bytes[..500]).unwrap();
    refused(&path, "shorter than its 1024-byte header");
}

#[test]
fn mrc_files_are_volumes_to_triage() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(data("mrc/ramp_i16.mrc"), dir.path().join("tomogram.rec")).unwrap();
    let r = run(&["triage", dir.path().to_str().unwrap(), "--json"]);
    assert!(r.ok, "{}", r.stderr);
    assert!(r.stdout.contains("\"format\":\"mrc\""), "{}", r.stdout);
}

#[test]
fn info_says_the_mode_in_text_and_json() {
    for (name, line, mode, values) in [
        (
            "ramp_i8.mrc",
            "mode        0 (8-bit signed integers)",
            0,
            "8-bit signed integers",
        ),
        (
            "ramp_i16.mrc",
            "mode        1 (16-bit signed integers)",
            1,
            "16-bit signed integers",
        ),
        (
            "ramp_f32.mrc",
            "mode        2 (32-bit reals)",
            2,
            "32-bit reals",
        ),
        (
            "ramp_u16.mrc",
            "mode        6 (16-bit unsigned integers)",
            6,
            "16-bit unsigned integers",
        ),
        (
            "ramp_f16.mrc",
            "mode        12 (16-bit reals)",
            12,
            "16-bit reals",
        ),
    ] {
        // Right after the format's line.
        let (details, v) = info_details(&data(&format!("mrc/{name}")), "mrc");
        assert_eq!(details, line, "{name}");
        assert_eq!(v["mrc"]["mode"], mode, "{name}");
        assert_eq!(v["mrc"]["values"], values, "{name}");
        // Every other reader's key is there, null.
        for other in ["dicom", "ome_zarr", "vtk", "vti"] {
            assert!(
                v[other].is_null() && v.get(other).is_some(),
                "{name}: {other}"
            );
        }
    }
}
