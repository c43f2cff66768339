//! 32-bit integers beyond what an f32 holds exactly (2^24 + 1 and up): every reader that widens
//! u32 or i32 voxels to f32 says how many it rounded and the largest, in one note (the one count
//! `data::wide` keeps for 64-bit integers too); values up to 2^24 give none. Each file is written
//! here: NRRD (raw, gzip, ascii), NIfTI, MetaImage, TIFF, VTK XML and legacy, Zarr, DICOM; the
//! HDF5 one is h5py's (`tests/data/hdf5/make_hdf5.py`). DICOM counts its values after the
//! rescale: the values the volume holds.

use std::io::Write;
use std::path::{Path, PathBuf};

use slabscope::{LoadOptions, load};

use crate::common::dicom::dicom32;
use crate::common::{data, run, s};

/// 2^24 + 1: the first integer an f32 does not hold.
const BEYOND: u32 = (1 << 24) + 1;

/// The voxels of every file here: four values, one of them `last`.
fn values(last: u32) -> [u32; 4] {
    [0, 7, 1 << 24, last]
}

fn le(values: &[u32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// The note for one rounded value of type `ty`, the largest `largest`.
fn note(ty: &str, largest: i64) -> String {
    format!(
        "1 {ty} value beyond what an f32 holds exactly rounded to the nearest f32 (the largest \
         {largest})"
    )
}

/// `path` loads with exactly `expected` among its notes about rounding (none when `None`), and
/// the voxels `values(last)` rounded to f32.
fn says(path: &Path, last: u32, expected: Option<&str>) {
    let loaded = load(path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let rounding: Vec<&String> = loaded
        .notes
        .iter()
        .filter(|n| n.contains("beyond what an f32 holds"))
        .collect();
    assert_eq!(
        rounding,
        expected.into_iter().collect::<Vec<_>>(),
        "{}",
        path.display()
    );
    #[allow(clippy::cast_precision_loss)] // the rounding tested
    let want: Vec<f32> = values(last).iter().map(|&v| v as f32).collect();
    assert_eq!(
        loaded.volume.data().to_f32_vec(),
        want,
        "{}",
        path.display()
    );
}

/// Each file `write(dir, name, last)` makes, with the last voxel 2^24 + 1 and then 2^24.
fn both(ty: &str, write: impl Fn(&Path, &str, u32) -> PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    says(
        &write(dir.path(), "beyond", BEYOND),
        BEYOND,
        Some(&note(ty, BEYOND.into())),
    );
    says(&write(dir.path(), "within", 1 << 24), 1 << 24, None);
}

fn nrrd(dir: &Path, name: &str, last: u32, encoding: &str) -> PathBuf {
    let path = dir.join(format!("{name}_{encoding}.nrrd"));
    let mut bytes = format!(
        "NRRD0004\ntype: uint32\ndimension: 3\nsizes: 2 2 1\nencoding: {encoding}\n\
         endian: little\n\n"
    )
    .into_bytes();
    let v = values(last);
    match encoding {
        "raw" => bytes.extend(le(&v)),
        "ascii" => bytes.extend(format!("{} {} {} {}\n", v[0], v[1], v[2], v[3]).bytes()),
        _ => {
            let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
            gz.write_all(&le(&v)).unwrap();
            bytes.extend(gz.finish().unwrap());
        }
    }
    std::fs::write(&path, bytes).unwrap();
    path
}

#[test]
fn nrrd_raw_gzip_and_ascii() {
    for encoding in ["raw", "gzip", "ascii"] {
        both("u32", |d, n, last| nrrd(d, n, last, encoding));
    }
}

/// A NIfTI-1 file of 2x2x1 voxels of `datatype` (768 u32, 8 i32).
fn nifti(dir: &Path, name: &str, last: u32, datatype: i16) -> PathBuf {
    let mut h = vec![0u8; 352];
    let put_i16 = |h: &mut [u8], at: usize, v: i16| h[at..at + 2].copy_from_slice(&v.to_le_bytes());
    let put_f32 = |h: &mut [u8], at: usize, v: f32| h[at..at + 4].copy_from_slice(&v.to_le_bytes());
    h[0..4].copy_from_slice(&348i32.to_le_bytes());
    for (k, d) in [3i16, 2, 2, 1, 1, 1, 1, 1].into_iter().enumerate() {
        put_i16(&mut h, 40 + 2 * k, d);
    }
    put_i16(&mut h, 70, datatype);
    put_i16(&mut h, 72, 32); // bitpix
    for k in 0..4 {
        put_f32(&mut h, 76 + 4 * k, 1.0);
    }
    put_f32(&mut h, 108, 352.0); // vox_offset
    h[123] = 2; // xyzt_units: mm
    h[344..348].copy_from_slice(b"n+1\0");
    h.extend(le(&values(last)));
    let path = dir.join(format!("{name}_{datatype}.nii"));
    std::fs::write(&path, h).unwrap();
    path
}

#[test]
fn nifti_u32_and_i32() {
    both("u32", |d, n, last| nifti(d, n, last, 768));
    both("i32", |d, n, last| nifti(d, n, last, 8));
}

#[test]
fn metaimage() {
    both("u32", |dir, name, last| {
        let path = dir.join(format!("{name}.mha"));
        let mut bytes = b"ObjectType = Image\nNDims = 3\nDimSize = 2 2 1\nElementType = MET_UINT\n\
                          ElementDataFile = LOCAL\n"
            .to_vec();
        bytes.extend(le(&values(last)));
        std::fs::write(&path, bytes).unwrap();
        path
    });
}

#[test]
fn tiff_pages() {
    both("u32", |dir, name, last| {
        let path = dir.join(format!("{name}.tif"));
        let file = std::fs::File::create(&path).unwrap();
        let mut tiff = tiff::encoder::TiffEncoder::new(file).unwrap();
        tiff.write_image::<tiff::encoder::colortype::Gray32>(2, 2, &values(last))
            .unwrap();
        path
    });
}

#[test]
fn vtk_xml_and_legacy() {
    let text = |last: u32| {
        let v = values(last);
        format!("{} {} {} {}", v[0], v[1], v[2], v[3])
    };
    both("u32", |dir, name, last| {
        let path = dir.join(format!("{name}.vti"));
        let xml = format!(
            r#"<?xml version="1.0"?>
<VTKFile type="ImageData" version="1.0" byte_order="LittleEndian" header_type="UInt64">
  <ImageData WholeExtent="0 1 0 1 0 0" Origin="0 0 0" Spacing="1 1 1">
    <Piece Extent="0 1 0 1 0 0">
      <PointData Scalars="s">
        <DataArray type="UInt32" Name="s" format="ascii">{}</DataArray>
      </PointData>
    </Piece>
  </ImageData>
</VTKFile>
"#,
            text(last)
        );
        std::fs::write(&path, xml).unwrap();
        path
    });
    for binary in [false, true] {
        both("u32", |dir, name, last| {
            let path = dir.join(format!("{name}_{binary}.vtk"));
            let mut bytes = format!(
                "# vtk DataFile Version 3.0\nt\n{}\nDATASET STRUCTURED_POINTS\n\
                 DIMENSIONS 2 2 1\nSPACING 1 1 1\nORIGIN 0 0 0\nPOINT_DATA 4\n\
                 SCALARS s unsigned_int\nLOOKUP_TABLE default\n",
                if binary { "BINARY" } else { "ASCII" }
            )
            .into_bytes();
            if binary {
                // Big-endian, as VTK writes binary data.
                bytes.extend(values(last).iter().flat_map(|v| v.to_be_bytes()));
            } else {
                bytes.extend(text(last).bytes());
            }
            bytes.push(b'\n');
            std::fs::write(&path, bytes).unwrap();
            path
        });
    }
}

#[test]
fn zarr_chunks() {
    both("i32", |dir, name, last| {
        let store = dir.join(format!("{name}.zarr"));
        std::fs::create_dir_all(store.join("c/0/0")).unwrap();
        let meta = r#"{"zarr_format": 3, "node_type": "array", "shape": [1, 2, 2],
            "data_type": "int32", "fill_value": 0,
            "chunk_grid": {"name": "regular", "configuration": {"chunk_shape": [1, 2, 2]}},
            "chunk_key_encoding": {"name": "default", "configuration": {"separator": "/"}},
            "codecs": [{"name": "bytes", "configuration": {"endian": "little"}}]}"#;
        std::fs::write(store.join("zarr.json"), meta).unwrap();
        std::fs::write(store.join("c/0/0/0"), le(&values(last))).unwrap();
        store
    });
}

/// h5py's i32 ramp + 2^24 (`make_hdf5.py`): the 60 odd values rounded, the largest 2^24 + 345;
/// said by `info` too (on stderr, where notes go).
#[test]
fn hdf5_and_info() {
    let path = data("hdf5/beyond_i32.h5");
    let loaded = load(&path, &LoadOptions::default()).unwrap();
    let said = "60 i32 values beyond what an f32 holds exactly rounded to the nearest f32 (the \
                largest 16777561)";
    assert!(loaded.notes.iter().any(|n| n == said), "{:?}", loaded.notes);
    let info = run(&["info", s(&path)]);
    assert!(info.ok, "{}", info.stderr);
    assert!(info.stderr.contains(said), "{}", info.stderr);
}

#[test]
fn dicom_u32_and_i32() {
    for (ty, signed) in [("u32", false), ("i32", true)] {
        both(ty, |dir, name, last| {
            let path = dir.join(format!("{name}_{ty}.dcm"));
            std::fs::write(&path, dicom32(&values(last), 1, signed, None)).unwrap();
            path
        });
    }
}

/// DICOM counts the values the volume holds, after the rescale: 2^24 + 1 less 1 is an f32,
/// while 2^24 and 2^24 + 2 plus 1 are not (odd numbers past 2^24); a fractional slope's values
/// are the scale's to round.
#[test]
fn dicom_counts_the_rescaled_values() {
    let dir = tempfile::tempdir().unwrap();
    let load_notes = |name: &str, bytes: Vec<u8>| {
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        let loaded = load(&path, &LoadOptions::default()).unwrap();
        let rounding: Vec<String> = loaded
            .notes
            .into_iter()
            .filter(|n| n.contains("beyond what an f32 holds"))
            .collect();
        (rounding, loaded.volume.data().to_f32_vec())
    };
    let (notes, v) = load_notes(
        "less.dcm",
        dicom32(&values(BEYOND), 1, false, Some(("1", "-1"))),
    );
    assert!(notes.is_empty(), "{notes:?}");
    assert_eq!(v, [-1.0, 6.0, 16_777_215.0, 16_777_216.0]);
    let more = values((1 << 24) + 2);
    let (notes, v) = load_notes("more.dcm", dicom32(&more, 1, false, Some(("1", "1"))));
    let said = "2 rescaled u32 values beyond what an f32 holds exactly rounded to the nearest \
                f32 (the largest 16777219)";
    assert_eq!(notes, [said]);
    assert_eq!(v, [1.0, 8.0, 16_777_216.0, 16_777_220.0]);
    let (notes, _) = load_notes(
        "half.dcm",
        dicom32(&values(BEYOND), 1, false, Some(("0.5", "0"))),
    );
    assert!(notes.is_empty(), "{notes:?}");
}

/// `info` and `analyze` say the note of a DICOM file's rounded values (a stack of six 2x2
/// frames: each frame's 2^24 + 1 counted, 6 in all).
#[test]
fn dicom_rounding_is_said_by_info_and_analyze() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("frames.dcm");
    std::fs::write(&path, dicom32(&values(BEYOND), 6, false, None)).unwrap();
    let said = "6 u32 values beyond what an f32 holds exactly rounded to the nearest f32 (the \
                largest 16777217)";
    let info = run(&["info", s(&path)]);
    assert!(info.ok, "{}", info.stderr);
    assert!(info.stderr.contains(said), "{}", info.stderr);
    // `analyze` says what loading found on stderr, as it says every load's notes.
    let analyze = run(&["analyze", s(&path), "--json"]);
    assert!(analyze.ok, "{}", analyze.stderr);
    let line = format!("slabscope: note: {}: {said}", s(&path));
    assert!(
        analyze.stderr.lines().any(|l| l == line),
        "{}",
        analyze.stderr
    );
}
