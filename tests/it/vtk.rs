//! Legacy VTK image data written by VTK's own writer (`tests/data/vtk/make_vtk.py`): binary and
//! ASCII, point and cell data, to the voxel, with spacing and origin; other datasets and arrays
//! refused in one line naming the file.

use slabscope::volume::VoxelType;
use slabscope::{Format, LoadOptions, Loaded, load};

use crate::common::{data, run};

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
}

#[test]
fn what_is_no_image_is_refused_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let refused = |name: &str, text: &[u8], says: &str| {
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        let r = run(&["info", path.to_str().unwrap()]);
        assert!(!r.ok, "{name}");
        let line = r.stderr.trim();
        assert_eq!(line.lines().count(), 1, "{line}");
        assert!(line.contains(name) && line.contains(says), "{line}");
    };
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
        let file = data(&format!("vtk/{name}"));
        let text = run(&["info", file.to_str().unwrap()]);
        assert!(text.ok, "{name}: {}", text.stderr);
        let lines: Vec<&str> = text.stdout.lines().collect();
        assert_eq!(lines[1], "format      vtk", "{name}");
        assert_eq!(lines[2], line, "{name}");
        let json = run(&["info", file.to_str().unwrap(), "--json"]);
        let v: serde_json::Value = serde_json::from_str(&json.stdout).unwrap();
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
