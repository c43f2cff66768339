//! DICOM: the fixtures `tests/data/dicom/make_dicom.py` writes (pydicom, and dcmtk for JPEG
//! lossless), each loaded or refused exactly as specified. Every image holds
//! `stored(i, j, k) = (3i + 5j + 11k) % 1000` (column, row, slice along the normal), so each
//! assembled volume is checked voxel by voxel, and its transform against the positions.

use slabscope::formats::dicom::DicomSeries;
use slabscope::volume::VoxelType;
use slabscope::{LoadOptions, Loaded, Volume};

use crate::common::{data, dicom_data, rows, run, slabscope};

fn stored(i: usize, j: usize, k: usize) -> f32 {
    ((3 * i + 5 * j + 11 * k) % 1000) as f32
}

fn load_with(name: &str, edit: impl FnOnce(&mut LoadOptions)) -> slabscope::Result<Loaded> {
    let mut opts = LoadOptions::default();
    edit(&mut opts);
    slabscope::load(&dicom_data(name), &opts)
}

fn load(name: &str) -> Loaded {
    load_with(name, |_| {}).unwrap()
}

/// Checks every voxel against `expected(i, j, k)` (NaN: missing).
fn check_voxels(v: &Volume, expected: impl Fn(usize, usize, usize) -> f32) {
    let [nx, ny, nz] = v.dims();
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let (got, want) = (v.value([i, j, k]), expected(i, j, k));
                let same = if want.is_nan() {
                    got.is_nan()
                } else {
                    (got - want).abs() <= 1e-3 * want.abs().max(1.0)
                };
                assert!(same, "voxel ({i}, {j}, {k}): {got}, expected {want}");
            }
        }
    }
}

/// The RAS transform of LPS columns `cols` (column, row, slice steps) and LPS `origin`.
fn ras(cols: [[f64; 3]; 3], origin: [f64; 3]) -> [[f64; 4]; 4] {
    let flip = [-1.0, -1.0, 1.0];
    let mut m = [[0.0; 4]; 4];
    for r in 0..3 {
        for c in 0..3 {
            m[r][c] = flip[r] * cols[c][r];
        }
        m[r][3] = flip[r] * origin[r];
    }
    m[3][3] = 1.0;
    m
}

fn close(a: [[f64; 4]; 4], b: [[f64; 4]; 4]) {
    for r in 0..4 {
        for c in 0..4 {
            assert!((a[r][c] - b[r][c]).abs() < 1e-3, "{a:?} != {b:?}");
        }
    }
}

#[test]
fn a_series_with_shuffled_names_is_sorted_along_the_normal() {
    // Instance numbers run backwards and file names are random: positions decide.
    let l = load_with("ct", |o| o.dicom.series = Some("1".into())).unwrap();
    let v = &l.volume;
    assert_eq!(v.dims(), [24, 20, 12]);
    assert_eq!(v.spacing(), [0.8, 0.7, 2.5]);
    // Signed 16-bit samples less 1024 whose values fit in i16: i16.
    assert_eq!(v.voxel_type(), VoxelType::I16);
    check_voxels(v, |i, j, k| stored(i, j, k) - 1024.0);
    let t = ras(
        [[0.8, 0.0, 0.0], [0.0, 0.7, 0.0], [0.0, 0.0, 2.5]],
        [-8.0, -6.0, 40.0],
    );
    close(v.transform().matrix, t);
    assert_eq!(v.transform().axcodes().as_deref(), Some("LPS"));
    let d = l.details_as::<DicomSeries>().unwrap();
    assert_eq!((d.number, d.description.as_str()), (Some(3), "Abdomen 2.5"));
    assert!(d.patient.is_empty(), "patient fields read unasked");
    assert!(
        l.notes.iter().any(|n| n == "left out 1 localizer image"),
        "{:?}",
        l.notes
    );
    // The folder named, and its twelve files.
    assert_eq!(l.sources.len(), 13);
}

#[test]
fn series_are_picked_by_position_or_uid_and_localizers_only_when_asked() {
    let e = load_with("ct", |_| {}).unwrap_err().to_string();
    assert!(e.contains("2 series") && e.contains("Sagittal MPR"), "{e}");
    let sag = load_with("ct", |o| o.dicom.series = Some("2".into())).unwrap();
    let v = &sag.volume;
    assert_eq!(v.dims(), [24, 20, 6]);
    // Columns along +y, rows along -z: the normal (their cross product) is -x, so the slices
    // run from x = 15 to x = 0, 3 mm apart, the file at x = 3k being slice 5 - k.
    let t = ras(
        [[0.0, 0.8, 0.0], [0.0, 0.0, -0.7], [-3.0, 0.0, 0.0]],
        [15.0, -6.0, 60.0],
    );
    close(v.transform().matrix, t);
    check_voxels(v, |i, j, k| stored(i, j, 5 - k) - 1024.0);
    let uid = sag.details_as::<DicomSeries>().unwrap().key.clone();
    let by_uid = load_with("ct", |o| o.dicom.series = Some(uid.clone())).unwrap();
    assert_eq!(by_uid.details_as::<DicomSeries>().unwrap().key, uid);
    let e = load_with("ct", |o| o.dicom.series = Some("7".into()))
        .unwrap_err()
        .to_string();
    assert!(e.contains("no series \"7\""), "{e}");
    let e = load_with("ct", |o| o.dicom.include_localizers = true)
        .unwrap_err()
        .to_string();
    assert!(e.contains("3 series") && e.contains("Topogram"), "{e}");
}

#[test]
fn a_missing_slice_is_named_and_resampling_fills_it() {
    let l = load("gap");
    assert_eq!(l.volume.dims(), [24, 20, 7]);
    let note = l
        .notes
        .iter()
        .find(|n| n.contains("missing slices"))
        .unwrap();
    assert!(
        note.contains("slice04.dcm") && note.contains("slice06.dcm") && note.contains("4.000 mm"),
        "{note}"
    );
    // Resampled: eight slices 2 mm apart, the missing one interpolated (the values are linear in
    // k, so exactly).
    let r = load_with("gap", |o| o.dicom.resample = true).unwrap();
    assert_eq!(r.volume.dims(), [24, 20, 8]);
    check_voxels(&r.volume, |i, j, k| stored(i, j, k) - 1024.0);
    assert!(!r.notes.iter().any(|n| n.contains("missing slices")));
}

#[test]
fn gantry_tilt_is_a_sheared_transform_or_resampled_away() {
    let shift = 3.0 * 15f64.to_radians().tan();
    let l = load("tilt");
    let t = ras(
        [[0.8, 0.0, 0.0], [0.0, 0.7, 0.0], [0.0, shift, 3.0]],
        [0.0, 0.0, 0.0],
    );
    close(l.volume.transform().matrix, t);
    assert!(
        l.notes
            .iter()
            .any(|n| n.starts_with("gantry tilt of 15.00°")),
        "{:?}",
        l.notes
    );
    check_voxels(&l.volume, |i, j, k| stored(i, j, k) - 1024.0);
    // Resampled onto the orthogonal grid: slice k's row j is the tilted slice's row j - shift·k,
    // missing where that falls outside it.
    let r = load_with("tilt", |o| o.dicom.resample = true).unwrap();
    let t = ras(
        [[0.8, 0.0, 0.0], [0.0, 0.7, 0.0], [0.0, 0.0, 3.0]],
        [0.0, 0.0, 0.0],
    );
    close(r.volume.transform().matrix, t);
    check_voxels(&r.volume, |i, j, k| {
        let source = j as f64 - shift * k as f64 / 0.7;
        if source < 0.0 {
            f32::NAN
        } else {
            (3.0 * i as f64 + 5.0 * source + 11.0 * k as f64 - 1024.0) as f32
        }
    });
}

#[test]
fn monochrome1_is_inverted_over_its_stored_bits() {
    let l = load("mono1");
    assert_eq!(l.volume.voxel_type(), VoxelType::U16);
    check_voxels(&l.volume, |i, j, k| 4095.0 - stored(i, j, k));
}

#[test]
fn rescale_is_applied_slice_by_slice() {
    let l = load("rescale");
    assert_eq!(l.volume.voxel_type(), VoxelType::F32);
    check_voxels(&l.volume, |i, j, k| {
        stored(i, j, k) * 0.5 * (k + 1) as f32 - 100.0 * k as f32
    });
}

#[test]
fn an_enhanced_multi_frame_file_reads_its_functional_groups() {
    // Frames stored in reverse; position and rescale per frame, orientation and spacing shared.
    let l = load("enhanced.dcm");
    assert_eq!(l.volume.dims(), [24, 20, 6]);
    assert_eq!(l.volume.spacing(), [0.9, 0.9, 1.2]);
    check_voxels(&l.volume, |i, j, k| 2.0 * stored(i, j, k) + k as f32);
    let t = ras(
        [[0.9, 0.0, 0.0], [0.0, 0.9, 0.0], [0.0, 0.0, 1.2]],
        [0.0, 0.0, 0.0],
    );
    close(l.volume.transform().matrix, t);
}

#[test]
fn repeated_positions_are_a_4d_series() {
    let first = load("fourd");
    assert_eq!(first.volume.dims(), [24, 20, 4]);
    check_voxels(&first.volume, |i, j, k| stored(i, j, k) - 1024.0);
    let second = load_with("fourd", |o| o.part.volume = 1).unwrap();
    check_voxels(&second.volume, |i, j, k| stored(i, j, k) + 500.0 - 1024.0);
    let e = load_with("fourd", |o| o.part.volume = 2)
        .unwrap_err()
        .to_string();
    assert!(e.contains('2'), "{e}");
}

#[test]
fn jpeg_lossless_deflate_and_no_preamble_read_exactly() {
    let l = load("jpegll");
    assert!(
        l.details_as::<DicomSeries>()
            .unwrap()
            .syntax
            .contains("1.2.840.10008.1.2.4.70")
    );
    check_voxels(&l.volume, |i, j, k| stored(i, j, k) - 1024.0);
    for one in ["deflated.dcm", "nopreamble.dcm"] {
        let l = load(one);
        assert_eq!(l.volume.dims(), [24, 20, 1], "{one}");
        check_voxels(&l.volume, |i, j, _| stored(i, j, 0) - 1024.0);
    }
}

#[test]
fn colour_is_read_as_luminance_with_a_note() {
    let l = load("rgb");
    assert!(
        l.notes
            .iter()
            .any(|n| n == "colour images (RGB) read as their luminance")
    );
    check_voxels(&l.volume, |i, j, k| {
        let v = stored(i, j, k) as u32;
        let (r, g, b) = (v % 256, (2 * v) % 256, 255 - v % 256);
        0.299 * r as f32 + 0.587 * g as f32 + 0.114 * b as f32
    });
}

#[test]
fn files_as_writers_really_make_them_are_read() {
    // A data set in implicit VR under a meta group that says explicit; a TIFF header in the
    // preamble (the file is still DICOM); a series of derived images only (a reformat).
    for one in ["mismatch.dcm", "tiffpreamble.dcm"] {
        let l = load(one);
        assert_eq!(l.format, slabscope::Format::Dicom, "{one}");
        check_voxels(&l.volume, |i, j, _| stored(i, j, 0) - 1024.0);
    }
    let l = load("derived");
    assert_eq!(l.volume.dims(), [24, 20, 3]);
    check_voxels(&l.volume, |i, j, k| stored(i, j, k) - 1024.0);
}

#[test]
fn an_unsupported_transfer_syntax_is_named() {
    let e = load_with("jpegls.dcm", |_| {}).unwrap_err().to_string();
    assert!(
        e.contains("jpegls.dcm") && e.contains("JPEG-LS") && e.contains("1.2.840.10008.1.2.4.80"),
        "{e}"
    );
}

#[test]
fn jpeg_2000_lossless_is_exact_and_lossy_is_openjpeg_s_decoding() {
    let l = load("j2k-lossless");
    assert_eq!(l.volume.dims(), [64, 64, 3]);
    check_voxels(&l.volume, |i, j, k| stored(i, j, k) - 1024.0);
    let loss = within_one_of(&load("j2k-lossy").volume, "j2k-lossy/expected.raw", true);
    assert!(loss > 10.0, "the lossy series is lossy: {loss}");
}

/// Checks `volume` against a decoder's own decoding of the same series, `raw` (little-endian
/// stored values, i16 when `signed`, else u16, slice after slice), within 1; returns the largest
/// difference from the values before compression.
fn within_one_of(volume: &Volume, raw: &str, signed: bool) -> f32 {
    let raw = std::fs::read(dicom_data(raw)).unwrap();
    let expected: Vec<f32> = raw
        .chunks_exact(2)
        .map(|b| {
            let v = if signed {
                f32::from(i16::from_le_bytes([b[0], b[1]]))
            } else {
                f32::from(u16::from_le_bytes([b[0], b[1]]))
            };
            v - 1024.0
        })
        .collect();
    assert_eq!(volume.dims(), [64, 64, 3]);
    let mut worst_loss = 0f32;
    for k in 0..3 {
        for j in 0..64 {
            for i in 0..64 {
                let got = volume.value([i, j, k]);
                let want = expected[(k * 64 + j) * 64 + i];
                assert!(
                    (got - want).abs() <= 1.0,
                    "({i}, {j}, {k}): {got}, the reference {want}"
                );
                worst_loss = worst_loss.max((got - (stored(i, j, k) - 1024.0)).abs());
            }
        }
    }
    worst_loss
}

#[test]
fn jpeg_xl_lossless_is_exact_and_lossy_is_libjxl_s_decoding() {
    let l = load("jxl-lossless");
    assert_eq!(l.volume.dims(), [64, 64, 3]);
    check_voxels(&l.volume, |i, j, k| stored(i, j, k) - 1024.0);
    let loss = within_one_of(&load("jxl-lossy").volume, "jxl-lossy/expected.raw", false);
    assert!(loss > 10.0, "the lossy series is lossy: {loss}");
}

/// The error loading `bytes` as `name`.
fn load_error(name: &str, bytes: &[u8]) -> String {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join(name);
    std::fs::write(&file, bytes).unwrap();
    let e = slabscope::load(&file, &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains(name), "{e}");
    e
}

#[test]
fn a_compressed_frame_larger_than_its_image_is_refused() {
    // The first JPEG 2000 slice, its SIZ marker segment claiming 65536x65536 pixels.
    let mut bytes = std::fs::read(dicom_data("j2k-lossless/s0.dcm")).unwrap();
    let soc = bytes
        .windows(4)
        .position(|w| w == [0xFF, 0x4F, 0xFF, 0x51])
        .unwrap();
    for at in [soc + 8, soc + 12] {
        bytes[at..at + 4].copy_from_slice(&65_536u32.to_be_bytes());
    }
    let e = load_error("big.dcm", &bytes);
    assert!(
        e.contains("65536x65536") && e.contains("image of 64x64"),
        "{e}"
    );
    // The first JPEG XL slice, its SizeHeader claiming 64x32768 pixels: not small, a height of
    // 32767 + 1 in 18 bits (selector 2), ratio 0, a width of 63 + 1 in 9 bits (selector 0).
    let mut bytes = std::fs::read(dicom_data("jxl-lossless/s0.dcm")).unwrap();
    let start = bytes.windows(2).position(|w| w == [0xFF, 0x0A]).unwrap() + 2;
    let mut v: u64 = 0;
    let mut at = 0;
    for (value, width) in [(0, 1), (2, 2), (32_767, 18), (0, 3), (0, 2), (63, 9)] {
        v |= value << at;
        at += width;
    }
    bytes[start..start + 5].copy_from_slice(&v.to_le_bytes()[..5]);
    let e = load_error("tall.dcm", &bytes);
    assert!(
        e.contains("64x32768") && e.contains("image of 64x64"),
        "{e}"
    );
}

#[test]
fn a_jpeg_2000_frame_stating_tiles_it_does_not_hold_is_refused() {
    // #47: the first JPEG 2000 slice (one 64x64 tile), its SIZ marker segment claiming tiles of
    // one pixel: 4096 tiles, of which the codestream holds one. It decoded to zeros, exit 0.
    let mut bytes = std::fs::read(dicom_data("j2k-lossless/s0.dcm")).unwrap();
    let soc = bytes
        .windows(4)
        .position(|w| w == [0xFF, 0x4F, 0xFF, 0x51])
        .unwrap();
    for at in [soc + 24, soc + 28] {
        bytes[at..at + 4].copy_from_slice(&1u32.to_be_bytes());
    }
    let e = load_error("tiles.dcm", &bytes);
    assert!(
        e.contains("states 4096 tiles and holds data for 1") && !e.contains('\n'),
        "{e}"
    );
}

const PHI: [&str; 6] = [
    "Zebedee",
    "Quintessa",
    "PID-73125-QX",
    "19370412",
    "Lindenhof",
    "ACC9911037",
];

#[test]
fn patient_fields_appear_nowhere_unless_asked_for() {
    let dir = tempfile::tempdir().unwrap();
    let picture = dir.path().join("r.png");
    let sheet = dir.path().join("sheet.png");
    let (ct, root) = (dicom_data("ct"), dicom_data(""));
    let (ct, root) = (ct.to_str().unwrap(), root.to_str().unwrap());
    let commands: Vec<Vec<&str>> = vec![
        vec!["info", ct],
        vec!["info", ct, "--series", "1"],
        vec!["info", ct, "--series", "1", "--json"],
        vec!["analyze", ct, "--series", "1", "--json", "--phases", "0"],
        vec![
            "render",
            ct,
            "--series",
            "1",
            "-o",
            picture.to_str().unwrap(),
        ],
        vec!["triage", root, "--full"],
        vec!["triage", root, "--json"],
        vec!["triage", root, "--csv"],
        vec!["triage", root, "--list"],
        vec!["triage", ct, "--sheet", sheet.to_str().unwrap()],
    ];
    for args in &commands {
        let text = run(args).text();
        for phi in PHI {
            assert!(!text.contains(phi), "{args:?} shows {phi}:\n{text}");
        }
    }
    let png = std::fs::read(&sheet).unwrap();
    for phi in PHI {
        assert!(!png.windows(phi.len()).any(|w| w == phi.as_bytes()));
    }
    // Asked for, they show.
    let ran = run(&["info", ct, "--series", "1", "--show-phi"]);
    let (status, text) = (ran.code, ran.text());
    assert_eq!(status, 0, "{text}");
    assert!(
        text.contains("Zebedee^Quintessa") && text.contains("PID-73125-QX"),
        "{text}"
    );
}

#[test]
fn triage_gives_a_row_per_series_and_per_broken_file_and_shards_add_up() {
    let dir = mixed_folder();
    let root = dir.path();
    let r = root.to_str().unwrap();
    let out = slabscope()
        .args(["triage", r, "--json", "--phases", "0"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1), "a broken file fails the run");
    let all = rows(&String::from_utf8_lossy(&out.stdout));
    let names: Vec<String> = all
        .iter()
        .map(|row| {
            let path = row["path"].as_str().unwrap();
            let rel = path.strip_prefix(r).unwrap().trim_start_matches('/');
            format!(
                "{rel} {}",
                row["dicom"]["description"].as_str().unwrap_or("-")
            )
        })
        .collect();
    assert_eq!(
        names,
        [
            " Enhanced T1",
            "broken.nii -",
            "ct Abdomen 2.5",
            "ct Sagittal MPR",
            "ct/jpegls.dcm -",
            "gap Gap",
            "gap/cut.dcm -",
            "ramp.nii -",
        ],
        "{all:#?}"
    );
    let error = |i: usize| all[i]["error"].as_str().unwrap_or("").to_string();
    assert!(
        error(1).contains("does not start like a NIfTI file"),
        "{}",
        error(1)
    );
    assert!(error(4).contains("JPEG-LS"), "{}", error(4));
    let cut = error(6);
    assert!(cut.contains("claims 56 bytes where 26 are left"), "{cut}");
    assert_eq!(
        (all[7]["format"].as_str(), error(7).as_str()),
        (Some("nifti"), "")
    );
    let problems = all[5]["problems"].to_string();
    assert!(
        problems.contains("missing slices") && problems.contains("cut.dcm"),
        "{problems}"
    );
    for row in &all {
        if row["error"].is_null() && row["format"] == "dicom" {
            assert!(row["series"].as_str().unwrap().starts_with("1.2.826."));
        }
    }
    // The shards, through a manifest, are the rows of one run. Labels come from the headers,
    // which a manifest does not carry; everything else agrees.
    assert_eq!(sharded_rows(root), all);
}

/// A folder of two DICOM series (one with a JPEG-LS file, one with a file cut short), an
/// enhanced multi-frame file, and another format beside them, valid and broken.
fn mixed_folder() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path();
    for sub in ["ct", "gap"] {
        std::fs::create_dir_all(root.join(sub)).unwrap();
        for f in std::fs::read_dir(dicom_data(sub)).unwrap() {
            let f = f.unwrap().path();
            std::fs::copy(&f, root.join(sub).join(f.file_name().unwrap())).unwrap();
        }
    }
    std::fs::copy(dicom_data("jpegls.dcm"), root.join("ct/jpegls.dcm")).unwrap();
    let slice = std::fs::read(dicom_data("gap/slice00.dcm")).unwrap();
    std::fs::write(root.join("gap/cut.dcm"), &slice[..slice.len() / 3]).unwrap();
    std::fs::copy(dicom_data("enhanced.dcm"), root.join("enhanced.dcm")).unwrap();
    // Another format beside the DICOM, and a broken one.
    std::fs::copy(data("ramp_u8.nii"), root.join("ramp.nii")).unwrap();
    std::fs::write(root.join("broken.nii"), b"not a volume").unwrap();
    dir
}

/// The rows of the three shards of `root`'s triage, through a manifest `--list` wrote.
fn sharded_rows(root: &std::path::Path) -> Vec<serde_json::Value> {
    let list = slabscope()
        .args(["triage", root.to_str().unwrap(), "--list"])
        .output()
        .unwrap();
    let manifest = root.join("manifest.txt");
    std::fs::write(&manifest, &list.stdout).unwrap();
    let mut joined = Vec::new();
    for k in 1..=3 {
        let shard = format!("{k}/3");
        let out = slabscope()
            .args(["triage", "--manifest", manifest.to_str().unwrap()])
            .args(["--shard", &shard, "--json", "--phases", "0"])
            .output()
            .unwrap();
        joined.extend(rows(&String::from_utf8_lossy(&out.stdout)));
    }
    joined
}

#[test]
fn a_pixel_spacing_of_zero_is_assumed_1_mm_with_a_note() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("zero.dcm");
    let mut bytes = std::fs::read(dicom_data("gap/slice00.dcm")).unwrap();
    let at = bytes
        .windows(8)
        .position(|w| w == b"0.7\\0.8 ")
        .expect("the fixture's PixelSpacing");
    bytes[at..at + 8].copy_from_slice(b"0.7\\0.0 ");
    std::fs::write(&file, bytes).unwrap();
    let l = slabscope::load(&file, &LoadOptions::default()).unwrap();
    assert_eq!(&l.volume.spacing()[..2], &[1.0, 1.0]);
    assert!(
        l.notes
            .iter()
            .any(|n| n.contains("pixel spacing 0.7 x 0 mm is not two positive numbers")),
        "{:?}",
        l.notes
    );
}
