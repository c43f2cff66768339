//! Siemens mosaics: the fixtures `tests/data/dicom/mosaic/make.py` writes (pydicom), cut into
//! slices and placed as dcm2niix places them (its NIfTI output frozen in `<series>.json`), over
//! time points, and refused or read by a fallback when the CSA header is gone or wrong. Tile
//! `k` of time point `t` holds `3i + 5j + 11k + 100t + 1`.

use slabscope::{LoadOptions, Loaded, Result, Volume};

use crate::common::{dicom, dicom_data};

fn stored(i: usize, j: usize, k: usize, t: usize) -> f32 {
    (3 * i + 5 * j + 11 * k + 100 * t + 1) as f32
}

fn load(name: &str, volume: usize) -> Result<Loaded> {
    let opts = LoadOptions {
        part: slabscope::formats::PartOptions {
            volume,
            ..slabscope::formats::PartOptions::default()
        },
        ..LoadOptions::default()
    };
    slabscope::load(&dicom_data(&format!("mosaic/{name}")), &opts)
}

/// What dcm2niix made of a series: dims, sform (RAS) and voxels (x fastest).
struct Frozen {
    dims: Vec<usize>,
    sform: [[f64; 4]; 3],
    values: Vec<f32>,
}

fn frozen(name: &str) -> Frozen {
    let text = std::fs::read_to_string(dicom_data(&format!("mosaic/{name}.json"))).unwrap();
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(json["sform_code"], 1);
    let dims = json["dims"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d.as_u64().unwrap() as usize)
        .collect();
    let sform =
        std::array::from_fn(|r| std::array::from_fn(|c| json["sform"][r][c].as_f64().unwrap()));
    let values = json["values"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap() as f32)
        .collect();
    Frozen {
        dims,
        sform,
        values,
    }
}

/// The inverse of the linear part of `m` applied to `world` less its offset.
fn to_index(m: &[[f64; 4]], world: [f64; 3]) -> [f64; 3] {
    let a = |r: usize, c: usize| m[r][c];
    let det = a(0, 0) * (a(1, 1) * a(2, 2) - a(1, 2) * a(2, 1))
        - a(0, 1) * (a(1, 0) * a(2, 2) - a(1, 2) * a(2, 0))
        + a(0, 2) * (a(1, 0) * a(2, 1) - a(1, 1) * a(2, 0));
    let d: [f64; 3] = std::array::from_fn(|r| world[r] - m[r][3]);
    // Cramer's rule.
    std::array::from_fn(|c| {
        let col = |r: usize, k: usize| if k == c { d[r] } else { a(r, k) };
        (col(0, 0) * (col(1, 1) * col(2, 2) - col(1, 2) * col(2, 1))
            - col(0, 1) * (col(1, 0) * col(2, 2) - col(1, 2) * col(2, 0))
            + col(0, 2) * (col(1, 0) * col(2, 1) - col(1, 1) * col(2, 0)))
            / det
    })
}

/// Checks that every voxel of `v` lies on a voxel of dcm2niix's volume `t` and holds its value,
/// and that the two transforms differ only by the flips dcm2niix makes: rows upside down, and
/// (`reversed`) slices in tile order where ours go along the normal.
fn same_as_dcm2niix(v: &Volume, f: &Frozen, t: usize, reversed: bool) {
    let [nx, ny, nz] = v.dims();
    assert_eq!(f.dims[..3], [nx, ny, nz]);
    let ours = v.transform().matrix;
    let plane = nx * ny * nz;
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let world = v.transform().apply([i as f64, j as f64, k as f64]);
                let theirs = to_index(&f.sform, world);
                let kk = if reversed { nz - 1 - k } else { k };
                let want = [i as f64, (ny - 1 - j) as f64, kk as f64];
                for a in 0..3 {
                    assert!(
                        (theirs[a] - want[a]).abs() < 1e-3,
                        "voxel ({i}, {j}, {k}) is at dcm2niix's {theirs:?}, not {want:?}"
                    );
                }
                let at = t * plane + (kk * ny + (ny - 1 - j)) * nx + i;
                assert_eq!(v.value([i, j, k]), f.values[at], "voxel ({i}, {j}, {k})");
            }
        }
    }
    // Ours times the flips is dcm2niix's sform.
    for r in 0..3 {
        let col = |c: usize| ours[r][c];
        let dz = if reversed { -1.0 } else { 1.0 };
        let flipped = [
            col(0),
            -col(1),
            dz * col(2),
            col(3)
                + col(1) * (ny - 1) as f64
                + if reversed {
                    col(2) * (nz - 1) as f64
                } else {
                    0.0
                },
        ];
        for c in 0..4 {
            assert!(
                (flipped[c] - f.sform[r][c]).abs() < 1e-3,
                "row {r}: {flipped:?} != {:?}",
                f.sform[r]
            );
        }
    }
}

#[test]
fn a_mosaic_is_cut_into_its_slices_where_dcm2niix_places_them() {
    let f = frozen("asc");
    assert_eq!(f.dims, [6, 5, 7, 3]);
    let l = load("asc", 0).unwrap();
    let v = &l.volume;
    assert_eq!(v.dims(), [6, 5, 7]);
    let spacing = v.spacing();
    assert_eq!(spacing[..2], [2.0, 2.5]);
    assert!((spacing[2] - 3.3).abs() < 1e-9, "{spacing:?}");
    for k in 0..7 {
        for j in 0..5 {
            for i in 0..6 {
                assert_eq!(v.value([i, j, k]), stored(i, j, k, 0), "({i}, {j}, {k})");
            }
        }
    }
    same_as_dcm2niix(v, &f, 0, false);
    assert!(
        l.notes.iter().any(|n| n
            == "a Siemens mosaic: 7 slices of 6x5 cut from each 18x15 image (slice spacing: \
                SpacingBetweenSlices)"),
        "{:?}",
        l.notes
    );
    assert!(
        l.notes
            .iter()
            .any(|n| n.contains("4D series of 3 volumes of 7 slices"))
    );
}

#[test]
fn each_time_point_is_a_volume() {
    let f = frozen("asc");
    for t in 1..3 {
        let v = load("asc", t).unwrap().volume;
        assert_eq!(v.dims(), [6, 5, 7]);
        assert_eq!(v.value([5, 4, 6]), stored(5, 4, 6, t));
        same_as_dcm2niix(&v, &f, t, false);
    }
    let e = load("asc", 3).unwrap_err().to_string();
    assert!(e.contains('3'), "{e}");
}

#[test]
fn a_slice_normal_against_the_orientation_reverses_the_tiles() {
    // The CSA block here is reserved at (0029,0011), after another creator's block at 10.
    let f = frozen("desc");
    let l = load("desc", 0).unwrap();
    let v = &l.volume;
    assert_eq!(v.dims(), [6, 5, 7]);
    // No SpacingBetweenSlices: SliceThickness.
    assert_eq!(v.spacing(), [2.0, 2.5, 4.0]);
    assert_eq!(v.value([0, 0, 0]), stored(0, 0, 6, 0));
    assert_eq!(v.value([0, 0, 6]), stored(0, 0, 0, 0));
    same_as_dcm2niix(v, &f, 0, true);
    assert!(
        l.notes
            .iter()
            .any(|n| n.contains("(slice spacing: SliceThickness)"))
    );
}

/// The first file of `asc` with `from` replaced by `to` (of the same length) once.
fn patched(from: &[u8], to: &[u8]) -> (tempfile::TempDir, std::path::PathBuf) {
    assert_eq!(from.len(), to.len());
    let mut bytes = std::fs::read(dicom_data("mosaic/asc/t0.dcm")).unwrap();
    let at = bytes.windows(from.len()).position(|w| w == from).unwrap();
    bytes[at..at + to.len()].copy_from_slice(to);
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("patched.dcm");
    std::fs::write(&file, bytes).unwrap();
    (dir, file)
}

fn error_of(from: &[u8], to: &[u8]) -> String {
    let (_dir, file) = patched(from, to);
    let e = slabscope::load(&file, &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("patched.dcm"), "{e}");
    assert_eq!(e.lines().count(), 1, "{e}");
    e
}

#[test]
fn a_bad_csa_header_is_an_error_and_a_missing_one_falls_back() {
    // A hostile tag count (the header holds 4).
    let e = error_of(
        b"SV10\x04\x03\x02\x01\x04\0\0\0",
        b"SV10\x04\x03\x02\x01\x40\x42\x0f\0",
    );
    assert!(e.contains("CSA image header: 1000000 tags claimed"), "{e}");
    // Too many images, and a count the mosaic cannot hold.
    let e = error_of(b"7\0\0\0", b"2000");
    assert!(e.contains("NumberOfImagesInMosaic 2000 (1 to 1024"), "{e}");
    let e = error_of(b"7\0\0\0", b"10\0\0");
    assert!(
        e.contains("10 slices take 4x4 tiles, which do not divide its 18x15"),
        "{e}"
    );
    // No CSA header (its block renamed): NumberOfImagesInMosaic from (0019,100A), the slices
    // along the orientation's normal.
    let (_dir, file) = patched(b"SIEMENS CSA HEADER", b"SIEMENS XYZ HEADER");
    let v = slabscope::load(&file, &LoadOptions::default())
        .unwrap()
        .volume;
    assert_eq!(v.dims(), [6, 5, 7]);
    assert_eq!(v.value([1, 2, 3]), stored(1, 2, 3, 0));
    let with_csa = load("asc", 0).unwrap().volume;
    for r in 0..4 {
        for c in 0..4 {
            let d = v.transform().matrix[r][c] - with_csa.transform().matrix[r][c];
            assert!(d.abs() < 1e-9);
        }
    }
    // Neither: an error.
    let (_dir, file) = patched(b"SIEMENS CSA HEADER", b"SIEMENS XYZ HEADER");
    let mut bytes = std::fs::read(&file).unwrap();
    let at = bytes
        .windows(17)
        .position(|w| w == b"SIEMENS MR HEADER")
        .unwrap();
    bytes[at..at + 7].copy_from_slice(b"OTHERS ");
    std::fs::write(&file, bytes).unwrap();
    let e = slabscope::load(&file, &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("ImageType says MOSAIC, but neither"), "{e}");
}

/// The CSA2 header `csa2` ("SV10") rewritten in the CSA1 layout, as older syngo versions wrote
/// it (and SPM and dcm2niix read it): no signature, and each item's first word its length plus
/// the first tag's item count.
fn as_csa1(csa2: &[u8]) -> Vec<u8> {
    let word = |at: usize| i32::from_le_bytes(csa2[at..at + 4].try_into().unwrap());
    let count = word(8);
    let mut out = csa2[8..16].to_vec();
    let mut at = 16;
    let mut base = None;
    for _ in 0..count {
        let items = word(at + 76);
        let base = *base.get_or_insert(items);
        out.extend_from_slice(&csa2[at..at + 84]);
        at += 84;
        for _ in 0..items {
            let len = word(at + 4);
            for w in [len + base, len, 77, len] {
                out.extend(w.to_le_bytes());
            }
            let padded = (len as usize).div_ceil(4) * 4;
            out.extend_from_slice(&csa2[at + 16..at + 16 + padded]);
            at += 16 + padded;
        }
    }
    assert_eq!(at, csa2.len(), "the whole CSA2 header walked");
    out
}

/// A CSA1 fixture: `desc`'s file with its CSA image header (0029,1110) rewritten in the CSA1
/// layout. Its slice normal, against the orientation's cross product, is in the CSA header only:
/// read from CSA1, the tiles are reversed as dcm2niix reversed them (`desc.json`).
#[test]
fn a_csa1_header_gives_the_slice_normal_as_csa2_does() {
    let bytes = std::fs::read(dicom_data("mosaic/desc/t0.dcm")).unwrap();
    // Explicit VR little endian: (0029,1110) OB, two reserved bytes, a 4-byte length.
    let head = [0x29, 0x00, 0x10, 0x11, b'O', b'B', 0, 0];
    let at = bytes.windows(8).position(|w| w == head).unwrap();
    let len = u32::from_le_bytes(bytes[at + 8..at + 12].try_into().unwrap()) as usize;
    let csa2 = &bytes[at + 12..at + 12 + len];
    assert!(csa2.starts_with(b"SV10"));
    let csa1 = as_csa1(csa2);
    assert!(!csa1.starts_with(b"SV10") && csa1.len().is_multiple_of(2));
    let mut rewritten = bytes[..at + 8].to_vec();
    rewritten.extend(u32::try_from(csa1.len()).unwrap().to_le_bytes());
    rewritten.extend(&csa1);
    rewritten.extend(&bytes[at + 12 + len..]);
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("t0.dcm");
    std::fs::write(&file, rewritten).unwrap();
    let l = slabscope::load(&file, &LoadOptions::default()).unwrap();
    let v = &l.volume;
    assert_eq!(v.dims(), [6, 5, 7]);
    assert_eq!(v.value([0, 0, 0]), stored(0, 0, 6, 0));
    assert_eq!(v.value([0, 0, 6]), stored(0, 0, 0, 0));
    same_as_dcm2niix(v, &frozen("desc"), 0, true);
    assert_eq!(l.notes, load("desc", 0).unwrap().notes);
}

/// The file `bytes` written as `name` in a new folder, loaded as volume `volume`.
fn load_bytes(bytes: &[u8], name: &str, volume: usize) -> (tempfile::TempDir, Result<Loaded>) {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join(name);
    std::fs::write(&file, bytes).unwrap();
    let opts = LoadOptions {
        part: slabscope::formats::PartOptions {
            volume,
            ..slabscope::formats::PartOptions::default()
        },
        ..LoadOptions::default()
    };
    let loaded = slabscope::load(&file, &opts);
    (dir, loaded)
}

/// `a` and `b` are the same volume: dims, spacing, transform and every voxel.
fn same_volume(a: &Volume, b: &Volume) {
    assert_eq!(a.dims(), b.dims());
    assert_eq!(a.spacing(), b.spacing());
    for r in 0..4 {
        for c in 0..4 {
            let d = a.transform().matrix[r][c] - b.transform().matrix[r][c];
            assert!(d.abs() < 1e-9, "{:?} != {:?}", a.transform(), b.transform());
        }
    }
    assert_eq!(a.data().to_f32_vec(), b.data().to_f32_vec());
}

/// A mosaic file of three frames (`asc`'s three files' pixel data in one, `NumberOfFrames` 3):
/// each frame a time point, cut as the single-frame files are, voxel for voxel.
#[test]
fn a_multi_frame_mosaic_is_the_4d_series_its_frames_would_be_as_files() {
    let bytes = dicom::mosaic_frames();
    for t in 0..3 {
        let (_dir, frames) = load_bytes(&bytes, "frames.dcm", t);
        let frames = frames.unwrap();
        let files = load("asc", t).unwrap();
        same_volume(&frames.volume, &files.volume);
        assert_eq!(frames.volume.value([5, 4, 6]), stored(5, 4, 6, t));
        assert!(
            frames
                .notes
                .iter()
                .any(|n| n == "the positions repeat: a 4D series of 3 volumes of 7 slices"),
            "{:?}",
            frames.notes
        );
    }
    let (_dir, e) = load_bytes(&bytes, "frames.dcm", 3);
    let e = e.unwrap_err().to_string();
    assert!(e.contains("frames.dcm") && e.contains('3'), "{e}");
    // Four frames claimed by the pixel data of three: refused before a pixel is read.
    let four = dicom::with(&bytes, (0x28, 0x08), *b"IS", b"4 ");
    let (_dir, e) = load_bytes(&four, "four.dcm", 0);
    let e = e.unwrap_err().to_string();
    assert!(e.contains("four.dcm") && e.lines().count() == 1, "{e}");
}

/// The first time point of `asc` loaded with a CSA series header holding `protocol`.
fn with_protocol(protocol: &str) -> Loaded {
    let bytes = dicom::mosaic_protocol(protocol);
    load_bytes(&bytes, "p.dcm", 0).1.unwrap()
}

const REVERSED: &str = "the CSA series header sets sSliceArray.ucImageNumb (Siemens numbered the \
                        slices in reverse): the tiles are placed by SliceNormalVector all the \
                        same, as dcm2niix places them (it warns and changes nothing)";

/// `sSliceArray.ucImageNumb` in the series header's ASCCONV block: read as dcm2niix reads it
/// (`siemensCsaAscii`), which warns and keeps the tiles where they are; so do we, with a note.
#[test]
fn the_reversed_numbering_flag_is_noted_and_the_tiles_stay_where_dcm2niix_puts_them() {
    let alone = slabscope::load(&dicom_data("mosaic/asc/t0.dcm"), &LoadOptions::default()).unwrap();
    let plain = with_protocol(&dicom::ascconv(""));
    let set = with_protocol(&dicom::ascconv("sSliceArray.ucImageNumb = 0x1\n"));
    let zero = with_protocol(&dicom::ascconv("sSliceArray.ucImageNumb = 0x0\n"));
    for l in [&plain, &set, &zero] {
        same_volume(&l.volume, &alone.volume);
        same_as_dcm2niix(&l.volume, &frozen("asc"), 0, false);
    }
    assert!(set.notes.iter().any(|n| n == REVERSED), "{:?}", set.notes);
    assert_eq!(plain.notes, alone.notes);
    assert_eq!(zero.notes, alone.notes);
    // After the block's end, or in a header with no block: not read.
    let after = format!("{}sSliceArray.ucImageNumb = 0x1\n", dicom::ascconv(""));
    assert_eq!(with_protocol(&after).notes, alone.notes);
    assert_eq!(
        with_protocol("sSliceArray.ucImageNumb = 0x1\n").notes,
        alone.notes
    );
}

#[test]
fn a_huge_or_malformed_series_header_is_bounded() {
    let alone = slabscope::load(&dicom_data("mosaic/asc/t0.dcm"), &LoadOptions::default()).unwrap();
    // Beyond 4 MiB: not searched, and said.
    let mut huge = dicom::ascconv("sSliceArray.ucImageNumb = 0x1\n");
    huge.push_str(&" ".repeat(4 << 20));
    let l = with_protocol(&huge);
    same_volume(&l.volume, &alone.volume);
    assert!(
        l.notes
            .iter()
            .any(|n| n.starts_with("the CSA series header holds 41")
                && n.ends_with("bytes (beyond 4 MiB): not searched for sSliceArray.ucImageNumb")),
        "{:?}",
        l.notes
    );
    assert!(!l.notes.iter().any(|n| n == REVERSED));
    // No end marker, the value cut at the header's end, digits beyond any integer, bytes
    // that are not text: read to where they end, never a panic.
    let open = "### ASCCONV BEGIN ###\nsSliceArray.ucImageNumb = 0x1";
    assert!(with_protocol(open).notes.iter().any(|n| n == REVERSED));
    let long = dicom::ascconv(&format!("sSliceArray.ucImageNumb = {}\n", "7".repeat(64)));
    assert!(with_protocol(&long).notes.iter().any(|n| n == REVERSED));
    let cut = "### ASCCONV BEGIN ###\nsSliceArray.ucImageNumb";
    assert_eq!(with_protocol(cut).notes, alone.notes);
    // A series header that is no CSA header at all: its bytes searched all the same.
    let raw = dicom::ascconv("sSliceArray.ucImageNumb = 0x1\n");
    let bytes = dicom::with(&dicom::asc(0), (0x29, 0x1020), *b"OB", raw.as_bytes());
    let l = load_bytes(&bytes, "raw.dcm", 0).1.unwrap();
    assert!(l.notes.iter().any(|n| n == REVERSED), "{:?}", l.notes);
}
