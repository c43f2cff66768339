//! Legacy VTK image data written by VTK's own writer (`tests/data/vtk/make_vtk.py`): binary and
//! ASCII, point and cell data, to the voxel, with spacing and origin; other datasets and arrays
//! refused in one line naming the file.

use std::path::Path;

use slabscope::volume::{Volume, VoxelType};
use slabscope::{Format, LoadOptions, Loaded, load};

use crate::common::{data, info_details, run};

fn open(name: &str) -> Loaded {
    load(&data(&format!("vtk/{name}")), &LoadOptions::default())
        .unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// The 6x5x4 ramp `x + 10y + 100z` of `make_vtk.py`, `wrap` applied to each value, placed
/// with its first voxel at `first`.
fn assert_ramp(name: &str, ty: VoxelType, wrap: impl Fn(i64) -> i64, first: [f64; 3]) {
    let loaded = open(name);
    assert_eq!(loaded.format, Format::Vtk, "{name}");
    let v = &loaded.volume;
    assert_eq!(v.dims(), [6, 5, 4], "{name}");
    assert_eq!(v.voxel_type(), ty, "{name}");
    assert_eq!(v.spacing(), [1.5, 2.0, 2.5], "{name}");
    assert_eq!(v.transform().apply([0.0; 3]), first, "{name}");
    assert!(!v.transform().known, "{name}: VTK's world has no anatomy");
    assert_ramp_voxels(v, name, wrap);
}

/// The voxels of `v` (read from `name`) are the 6x5x4 ramp `x + 10y + 100z` of the VTK
/// fixtures, `wrap` applied to each value.
pub(crate) fn assert_ramp_voxels(v: &Volume, name: &str, wrap: impl Fn(i64) -> i64) {
    for z in 0..4 {
        for y in 0..5 {
            for x in 0..6 {
                let want = wrap((x + 10 * y + 100 * z) as i64) as f32;
                assert_eq!(v.value([x, y, z]), want, "{name}: voxel ({x},{y},{z})");
            }
        }
    }
}

/// `info` on `text` saved as `name` in `dir` (under a 64 MiB budget) fails in one line naming
/// the file and saying `says`.
pub(crate) fn refused(dir: &Path, name: &str, text: &[u8], says: &str) {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    let r = run(&["info", "--max-memory", "64M", path.to_str().unwrap()]);
    assert!(!r.ok, "{name}");
    let line = r.stderr.trim();
    assert_eq!(line.lines().count(), 1, "{line}");
    assert!(line.contains(name) && line.contains(says), "{name}: {line}");
}

#[test]
fn point_and_cell_data_read_to_the_voxel() {
    let origin = [-3.0, 4.0, 10.0];
    assert_ramp("ramp_i16.vtk", VoxelType::I16, |v| v, origin);
    assert_ramp("ramp_f32.vtk", VoxelType::F32, |v| v, origin);
    // VTK writes one-byte scalars as colours: fractions of 255 in ASCII.
    assert_ramp("ramp_u8_ascii.vtk", VoxelType::U8, |v| v % 256, origin);
    // Cell data: a voxel a cell, at the cell's centre.
    assert_ramp(
        "ramp_f64_cells.vtk",
        VoxelType::F64,
        |v| v,
        [-2.25, 5.0, 11.25],
    );
    // 64-bit integers (`long`, `unsigned_long`), held as f32: these all exactly.
    assert_ramp("ramp_i64.vtk", VoxelType::F32, |v| v, origin);
    assert_ramp("ramp_u64_ascii.vtk", VoxelType::F32, |v| v, origin);
}

#[test]
fn long_values_beyond_f32_are_rounded_and_said() {
    let dir = tempfile::tempdir().unwrap();
    let head = "# vtk DataFile Version 3.0\nt\nASCII\nDATASET STRUCTURED_POINTS\n\
                DIMENSIONS 2 1 1\nPOINT_DATA 2\nSCALARS s long\nLOOKUP_TABLE default\n";
    let path = dir.path().join("ids.vtk");
    std::fs::write(&path, format!("{head}-9223372036854775808 16777217\n")).unwrap();
    let loaded = load(&path, &LoadOptions::default()).unwrap();
    assert_eq!(
        loaded.volume.data().to_f32_vec(),
        [-9_223_372_036_854_775_808.0, 16_777_216.0]
    );
    assert!(
        loaded.notes.contains(
            &"1 i64 value beyond what an f32 holds exactly rounded to the nearest f32 (the \
              largest 16777217)"
                .to_string()
        ),
        "{:?}",
        loaded.notes
    );
    // Beyond i64, or not whole: refused naming the value.
    for (name, value) in [("over.vtk", "9223372036854775808"), ("half.vtk", "1.5")] {
        refused(
            dir.path(),
            name,
            format!("{head}0 {value}\n").as_bytes(),
            &format!("value 1: \"{value}\" is not an integer of type i64"),
        );
    }
}

#[test]
fn what_is_no_image_is_refused_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let refused = |name: &str, text: &[u8], says: &str| refused(dir.path(), name, text, says);
    let head = "# vtk DataFile Version 3.0\nt\nASCII\n";
    refused(
        "mesh.vtk",
        format!("{head}DATASET POLYDATA\nPOINTS 0 float\n").as_bytes(),
        "a VTK POLYDATA dataset",
    );
    let grid = "DATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\nSPACING 1 1 1\nORIGIN 0 0 0\n";
    refused(
        "flow.vtk",
        format!("{head}{grid}POINT_DATA 8\nVECTORS v float\n").as_bytes(),
        "slabscope reads scalars",
    );
    refused(
        "short.vtk",
        format!("{head}{grid}POINT_DATA 8\nSCALARS s float\nLOOKUP_TABLE default\n1 2 3\n")
            .as_bytes(),
        "short.vtk",
    );
    refused(
        "empty.vtk",
        head.as_bytes(),
        "its header ends before its values start",
    );
    let bytes = std::fs::read(data("vtk/ramp_i16.vtk")).unwrap();
    refused("cut.vtk", &bytes[..bytes.len() - 20], "cut.vtk");
    let bytes = std::fs::read(data("vtk/ramp_i64.vtk")).unwrap();
    refused("cut64.vtk", &bytes[..bytes.len() - 20], "cut64.vtk");
}

#[test]
fn info_lists_the_array_read_in_text_and_json() {
    for (name, line, kind, ty, at) in [
        (
            "ramp_i16.vtk",
            "arrays      density (short scalars, point data)",
            "scalars",
            "short",
            "point",
        ),
        (
            "ramp_f32.vtk",
            "arrays      density (float scalars, point data)",
            "scalars",
            "float",
            "point",
        ),
        (
            "ramp_u8_ascii.vtk",
            "arrays      density (unsigned_char color scalars, point data)",
            "color_scalars",
            "unsigned_char",
            "point",
        ),
        (
            "ramp_f64_cells.vtk",
            "arrays      density (double scalars, cell data)",
            "scalars",
            "double",
            "cell",
        ),
    ] {
        let (details, v) = info_details(&data(&format!("vtk/{name}")), "vtk");
        assert_eq!(details, line, "{name}");
        let arrays = v["vtk"]["arrays"].as_array().unwrap();
        assert_eq!(arrays.len(), 1, "{name}");
        assert_eq!(arrays[0]["name"], "density", "{name}");
        assert_eq!(arrays[0]["kind"], kind, "{name}");
        assert_eq!(arrays[0]["type"], ty, "{name}");
        assert_eq!(arrays[0]["data"], at, "{name}");
        assert!(v["mrc"].is_null() && v["dicom"].is_null(), "{name}");
    }
}

#[test]
fn an_array_name_is_escaped_in_info() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("named.vtk");
    let mut bytes = std::fs::read(data("vtk/ramp_i16.vtk")).unwrap();
    let at = bytes.windows(7).position(|w| w == b"density").unwrap();
    bytes.splice(at..at + 7, b"d\x1b[2Jx".iter().copied());
    std::fs::write(&path, bytes).unwrap();
    let text = run(&["info", path.to_str().unwrap()]);
    assert!(text.ok, "{}", text.stderr);
    assert!(!text.stdout.contains('\x1b'), "{}", text.stdout);
    assert!(text.stdout.contains("arrays      d"), "{}", text.stdout);
}

/// A 3x2x2 file of five arrays as VTK's format describes them: point scalars (the one read),
/// after a `METADATA` block more scalars and vectors, then cell data holding a `FIELD` of two
/// arrays; binary (big-endian) or ASCII.
fn five_arrays(binary: bool) -> Vec<u8> {
    let values = |count: usize, size: usize| -> Vec<u8> {
        if binary {
            let mut v = vec![0u8; count * size];
            v.push(b'\n');
            v
        } else {
            let words: Vec<String> = (0..count).map(|i| i.to_string()).collect();
            format!("{}\n", words.join(" ")).into_bytes()
        }
    };
    let encoding = if binary { "BINARY" } else { "ASCII" };
    let mut f = format!(
        "# vtk DataFile Version 3.0\nfive arrays\n{encoding}\nDATASET STRUCTURED_POINTS\n\
         DIMENSIONS 3 2 2\nSPACING 1 1 1\nORIGIN 0 0 0\nPOINT_DATA 12\n\
         SCALARS density short 1\nLOOKUP_TABLE default\n"
    )
    .into_bytes();
    f.extend(values(12, 2));
    f.extend(b"METADATA\nINFORMATION 0\n\nSCALARS mask unsigned_char\nLOOKUP_TABLE default\n");
    f.extend(values(12, 1));
    f.extend(b"VECTORS flow float\n");
    f.extend(values(36, 4));
    f.extend(b"CELL_DATA 2\nFIELD FieldData 2\npressure 1 2 double\n");
    f.extend(values(2, 8));
    f.extend(b"labels 2 2 int\n");
    f.extend(values(4, 4));
    f
}

#[test]
fn info_lists_every_array_of_the_file() {
    let dir = tempfile::tempdir().unwrap();
    for binary in [true, false] {
        let path = dir.path().join(format!("five_{binary}.vtk"));
        std::fs::write(&path, five_arrays(binary)).unwrap();
        let (details, v) = info_details(&path, "vtk");
        assert_eq!(
            details,
            "arrays      density (short scalars, point data), mask (unsigned_char scalars, point \
             data), flow (float vectors, point data), pressure (double field, cell data), labels \
             (int field, cell data)",
            "binary {binary}"
        );
        let arrays = v["vtk"]["arrays"].as_array().unwrap();
        let listed: Vec<[&str; 4]> = arrays
            .iter()
            .map(|a| ["name", "kind", "type", "data"].map(|k| a[k].as_str().unwrap()))
            .collect();
        assert_eq!(
            listed,
            [
                ["density", "scalars", "short", "point"],
                ["mask", "scalars", "unsigned_char", "point"],
                ["flow", "vectors", "float", "point"],
                ["pressure", "field", "double", "cell"],
                ["labels", "field", "int", "cell"],
            ],
            "binary {binary}"
        );
        // The volume is the first array's.
        let loaded = load(&path, &LoadOptions::default()).unwrap();
        assert_eq!(loaded.volume.dims(), [3, 2, 2]);
    }
}

#[test]
fn a_file_cut_short_after_its_first_array_lists_what_it_holds() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cut.vtk");
    let whole = five_arrays(true);
    let cut = whole.windows(4).position(|w| w == b"CELL").unwrap() - 20;
    std::fs::write(&path, &whole[..cut]).unwrap();
    let (details, _) = info_details(&path, "vtk");
    assert_eq!(
        details,
        "arrays      density (short scalars, point data), mask (unsigned_char scalars, point \
         data), flow (float vectors, point data)"
    );
}
