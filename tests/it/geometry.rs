//! Nonsense geometry (#47), in fixtures made here for each reader (DICOM edited from a slice of
//! the repository's own): a voxel spacing outside 1e-9 mm to 1e9 mm is refused with one line
//! naming the file; an origin that is not finite or beyond ±1e12 mm is replaced with 0 and a
//! note; ångström voxels (1e-7 mm) stay valid.

use std::path::{Path, PathBuf};

use slabscope::{LoadOptions, load};

use crate::common::{Ran, run, s};

/// `slabscope info PATH EXTRA...`.
fn info(path: &Path, extra: &[&str]) -> Ran {
    let mut args = vec!["info", s(path)];
    args.extend_from_slice(extra);
    run(&args)
}

/// Asserts `ran` refused `path` for its spacing, in one line naming the file.
fn refused(ran: &Ran, path: &Path) {
    let e = ran.stderr.trim_end();
    assert!(!ran.ok, "{}", ran.stdout);
    assert!(e.contains(s(path)) && e.contains("voxel spacing"), "{e}");
    assert!(e.contains("expected 1e-9 mm to 1e9 mm"), "{e}");
    assert_eq!(e.lines().count(), 1, "{e}");
    assert!(ran.stdout.is_empty(), "{}", ran.stdout);
}

/// Asserts `ran` read the volume placed at 0 with a note saying so.
fn placed_at_zero(ran: &Ran) {
    assert!(ran.ok, "{}", ran.stderr);
    let report: serde_json::Value = serde_json::from_str(&ran.stdout).unwrap();
    let notes = report["notes"].to_string();
    assert!(notes.contains("placed at 0"), "{notes}");
    for row in report["affine"].as_array().unwrap().iter().take(3) {
        assert_eq!(row[3], 0.0, "{report}");
    }
}

fn nrrd(dir: &Path, name: &str, fields: &str) -> PathBuf {
    let path = dir.join(name);
    let mut bytes =
        format!("NRRD0004\ntype: uint8\ndimension: 3\nsizes: 2 2 2\n{fields}encoding: raw\n\n")
            .into_bytes();
    bytes.extend(0..8u8);
    std::fs::write(&path, bytes).unwrap();
    path
}

fn mha(dir: &Path, name: &str, fields: &str) -> PathBuf {
    let path = dir.join(name);
    let mut bytes = format!(
        "ObjectType = Image\nNDims = 3\nDimSize = 2 2 2\n{fields}ElementType = MET_UCHAR\n\
         ElementDataFile = LOCAL\n"
    )
    .into_bytes();
    bytes.extend(0..8u8);
    std::fs::write(&path, bytes).unwrap();
    path
}

/// A NIfTI-1 file of 2³ u8 with `pixdim` and an sform of that scale at `origin`.
fn nifti(dir: &Path, name: &str, pixdim: f32, origin: [f32; 3]) -> PathBuf {
    let mut h = vec![0u8; 352];
    let put_i16 =
        |h: &mut Vec<u8>, at: usize, v: i16| h[at..at + 2].copy_from_slice(&v.to_le_bytes());
    let put_f32 =
        |h: &mut Vec<u8>, at: usize, v: f32| h[at..at + 4].copy_from_slice(&v.to_le_bytes());
    h[0..4].copy_from_slice(&348i32.to_le_bytes());
    for (k, d) in [3i16, 2, 2, 2, 1, 1, 1, 1].into_iter().enumerate() {
        put_i16(&mut h, 40 + 2 * k, d);
    }
    put_i16(&mut h, 70, 2); // datatype: u8
    put_i16(&mut h, 72, 8); // bitpix
    for k in 0..4 {
        put_f32(&mut h, 76 + 4 * k, if k == 0 { 1.0 } else { pixdim });
    }
    put_f32(&mut h, 108, 352.0); // vox_offset
    put_f32(&mut h, 112, 1.0); // scl_slope
    h[123] = 2; // xyzt_units: mm
    put_i16(&mut h, 254, 1); // sform_code
    for r in 0..3 {
        for c in 0..4 {
            let v = if c == 3 {
                origin[r]
            } else if c == r {
                pixdim
            } else {
                0.0
            };
            put_f32(&mut h, 280 + 16 * r + 4 * c, v);
        }
    }
    h[344..348].copy_from_slice(b"n+1\0");
    h.extend(0..8u8);
    let path = dir.join(name);
    std::fs::write(&path, h).unwrap();
    path
}

#[test]
fn nrrd_and_metaimage_spacings_outside_the_bounds_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for path in [
        nrrd(d, "tiny.nrrd", "spacings: 1e-300 1e-300 1e-300\n"),
        nrrd(d, "huge.nrrd", "spacings: 2e9 2e9 2e9\n"),
        mha(d, "tiny.mha", "ElementSpacing = 1e-300 1e-300 1e-300\n"),
        mha(d, "huge.mha", "ElementSpacing = 5e9 5e9 5e9\n"),
    ] {
        refused(&info(&path, &["--json"]), &path);
        refused(&run(&["analyze", s(&path), "--json"]), &path);
    }
    // Electron microscopy's ångström voxels are read.
    for path in [
        nrrd(d, "em.nrrd", "spacings: 1e-7 1e-7 1e-7\n"),
        mha(d, "em.mha", "ElementSpacing = 1e-7 1e-7 1e-7\n"),
    ] {
        let ran = info(&path, &["--json"]);
        assert!(ran.ok, "{}", ran.stderr);
    }
}

#[test]
fn origins_beyond_the_bounds_are_replaced_with_a_note() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let lps = "space: left-posterior-superior\nspace directions: (1,0,0) (0,1,0) (0,0,1)\n";
    let far = nrrd(d, "far.nrrd", &format!("{lps}space origin: (0,5e12,0)\n"));
    placed_at_zero(&info(&far, &["--json"]));
    let far = mha(d, "far.mha", "ElementSpacing = 1 1 1\nOffset = 0 0 -3e15\n");
    placed_at_zero(&info(&far, &["--json"]));
    // Within the bounds the origin is kept.
    let near = mha(
        d,
        "near.mha",
        "ElementSpacing = 1 1 1\nOffset = 0 0 -3e11\n",
    );
    let ran = info(&near, &["--json"]);
    let report: serde_json::Value = serde_json::from_str(&ran.stdout).unwrap();
    assert_eq!(report["affine"][2][3], -3e11, "{report}");
}

#[test]
fn nifti_spacing_and_origin_are_held_to_the_bounds() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let tiny = nifti(d, "tiny.nii", 1e-20, [0.0; 3]);
    refused(&info(&tiny, &["--json"]), &tiny);
    let far = nifti(d, "far.nii", 1.0, [2e13, 0.0, 0.0]);
    placed_at_zero(&info(&far, &["--json"]));
    let em = nifti(d, "em.nii", 1e-7, [0.0; 3]);
    let v = load(&em, &LoadOptions::default()).unwrap().volume;
    assert_eq!(v.spacing().map(|x| (x * 1e9).round()), [100.0; 3]);
}

#[test]
fn raw_spacing_given_on_the_command_line_is_held_to_the_bounds() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cube.raw");
    std::fs::write(&path, (0..8u8).collect::<Vec<_>>()).unwrap();
    let raw = |spacing: &str| {
        info(
            &path,
            &[
                "--dims",
                "2x2x2",
                "--type",
                "u8",
                "--spacing",
                spacing,
                "--json",
            ],
        )
    };
    refused(&raw("1e-300,1e-300,1e-300"), &path);
    refused(&raw("1e10,1e10,1e10"), &path);
    assert!(raw("1e-7,1e-7,1e-7").ok);
}

/// A copy of the repository's `v04_yx` store in a temporary folder, its multiscales rewritten by
/// `edit`.
fn zarr_with(edit: impl Fn(&mut serde_json::Value)) -> (tempfile::TempDir, PathBuf) {
    let from = crate::common::data("zarr/v04_yx.ome.zarr");
    let dir = tempfile::tempdir().unwrap();
    let store = dir.path().join("store.ome.zarr");
    for sub in ["", "s0"] {
        std::fs::create_dir_all(store.join(sub)).unwrap();
        for e in std::fs::read_dir(from.join(sub)).unwrap() {
            let e = e.unwrap();
            if e.file_type().unwrap().is_file() {
                std::fs::copy(e.path(), store.join(sub).join(e.file_name())).unwrap();
            }
        }
    }
    let attrs = store.join(".zattrs");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&attrs).unwrap()).unwrap();
    edit(&mut v["multiscales"][0]);
    std::fs::write(&attrs, v.to_string()).unwrap();
    (dir, store)
}

#[test]
fn ome_zarr_scales_and_overflowing_translations_are_held_to_the_bounds() {
    let (_dir, tiny) = zarr_with(|m| {
        m["datasets"][0]["coordinateTransformations"][0]["scale"] =
            serde_json::json!([1e-300, 1e-300]);
    });
    let e = load(&tiny, &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains(s(&tiny)) && e.contains("voxel spacing"), "{e}");
    assert!(!e.contains('\n'), "{e}");
    // A translation in kilometres that overflows to infinity in mm: placed at 0, with a note.
    let (_dir, far) = zarr_with(|m| {
        m["datasets"][0]["coordinateTransformations"] = serde_json::json!([
            {"type": "scale", "scale": [1e-6, 1e-6]},
            {"type": "translation", "translation": [1.7e308, 0.0]}
        ]);
        for axis in m["axes"].as_array_mut().unwrap() {
            axis["unit"] = serde_json::json!("kilometer");
        }
    });
    let loaded = load(&far, &LoadOptions::default()).unwrap();
    assert!(
        loaded.notes.iter().any(|n| n.contains("placed at 0")),
        "{:?}",
        loaded.notes
    );
    let t = loaded.volume.transform();
    assert!(
        t.apply([0.0; 3]).iter().all(|&o| o == 0.0),
        "{:?}",
        t.matrix
    );
    assert!((loaded.volume.spacing()[0] - 1.0).abs() < 1e-9);
}

/// The first slice of the repository's lossless JPEG 2000 series with the DS values of `edits`
/// (tags as little-endian explicit VR `(group, element)` bytes) replaced, each element resized
/// to its new value padded to an even length (the file has no group lengths to mend).
fn dicom_with(dir: &Path, name: &str, edits: &[([u8; 4], &str)]) -> PathBuf {
    let mut bytes = std::fs::read(crate::common::dicom_data("j2k-lossless/s0.dcm")).unwrap();
    for (tag, value) in edits {
        let mut key = tag.to_vec();
        key.extend_from_slice(b"DS");
        let at = bytes.windows(6).position(|w| w == key).unwrap() + 6;
        let len = usize::from(u16::from_le_bytes([bytes[at], bytes[at + 1]]));
        let mut new = value.as_bytes().to_vec();
        if new.len() % 2 == 1 {
            new.push(b' ');
        }
        bytes[at..at + 2].copy_from_slice(&(new.len() as u16).to_le_bytes());
        bytes.splice(at + 2..at + 2 + len, new);
    }
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

#[test]
fn dicom_pixel_spacing_and_position_are_held_to_the_bounds() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // PixelSpacing (0028,0030) and SliceThickness (0018,0050) of 1e-20 mm: refused.
    let tiny = dicom_with(
        d,
        "tiny.dcm",
        &[
            ([0x28, 0, 0x30, 0], "1e-20\\1e-20"),
            ([0x18, 0, 0x50, 0], "1e-20"),
        ],
    );
    let e = load(&tiny, &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains(s(&tiny)) && e.contains("voxel spacing"), "{e}");
    // ImagePositionPatient (0020,0032) 1e300 mm away: placed at 0, with a note.
    let far = dicom_with(d, "far.dcm", &[([0x20, 0, 0x32, 0], "1e300\\0\\0")]);
    placed_at_zero(&info(&far, &["--json"]));
    // Ångström pixels are read.
    let em = dicom_with(
        d,
        "em.dcm",
        &[
            ([0x28, 0, 0x30, 0], "1e-7\\1e-7"),
            ([0x18, 0, 0x50, 0], "1e-7"),
        ],
    );
    assert!(load(&em, &LoadOptions::default()).is_ok());
}

/// The repository's `plain_z.ome.tif` (0.5 × 0.5 × 1.5 mm) with its OME-XML's length units
/// all `unit` (two bytes, as `mm`, so the XML keeps its length).
fn ome_tiff_in(dir: &Path, unit: &str) -> PathBuf {
    let mut bytes = std::fs::read(crate::common::data("ome/plain_z.ome.tif")).unwrap();
    for axis in ["X", "Y", "Z"] {
        let key = format!("PhysicalSize{axis}Unit=\"mm\"");
        let at = bytes
            .windows(key.len())
            .position(|w| w == key.as_bytes())
            .unwrap();
        let end = at + key.len() - 3;
        bytes[end..end + 2].copy_from_slice(unit.as_bytes());
    }
    let path = dir.join(format!("plain_{unit}.ome.tif"));
    std::fs::write(&path, bytes).unwrap();
    path
}

#[test]
fn ome_tiff_physical_sizes_are_held_to_the_bounds() {
    let dir = tempfile::tempdir().unwrap();
    // Picometres: 5e-10 mm along x.
    let pm = ome_tiff_in(dir.path(), "pm");
    let e = load(&pm, &LoadOptions::default()).unwrap_err().to_string();
    assert!(
        e.contains(s(&pm)) && e.contains("voxel spacing 5.000e-10 mm along x"),
        "{e}"
    );
    // Nanometres: 5e-7 mm, read.
    let nm = ome_tiff_in(dir.path(), "nm");
    let v = load(&nm, &LoadOptions::default()).unwrap().volume;
    assert!((v.spacing()[0] - 5e-7).abs() < 1e-15, "{:?}", v.spacing());
}
