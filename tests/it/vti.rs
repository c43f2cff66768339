//! VTK XML image data written by VTK's own writer (`tests/data/vti/make_vti.py`): ascii, inline
//! base64, appended raw and base64, zlib blocks, both byte orders and header types, point and
//! cell data, a Direction; to the voxel, with spacing, origin and axes, and against the legacy
//! `.vtk` of the same volume. Hostile headers are refused in one line naming the file.

use slabscope::volume::VoxelType;
use slabscope::{Format, LoadOptions, Loaded, load};

use crate::common::data;
use crate::vtk::{assert_ramp_voxels, refused};

fn open(name: &str) -> Loaded {
    load(&data(&format!("vti/{name}")), &LoadOptions::default())
        .unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// The 6x5x4 ramp `x + 10y + 100z` of `make_vti.py` read from `name`, `wrap` applied to each
/// value.
fn assert_ramp(name: &str, ty: VoxelType, wrap: impl Fn(i64) -> i64) -> Loaded {
    let loaded = open(name);
    assert_eq!(loaded.format, Format::Vti, "{name}");
    let v = &loaded.volume;
    assert_eq!(v.dims(), [6, 5, 4], "{name}");
    assert_eq!(v.voxel_type(), ty, "{name}");
    assert_eq!(v.spacing(), [1.5, 2.0, 2.5], "{name}");
    assert!(!v.transform().known, "{name}: VTK's world has no anatomy");
    assert_ramp_voxels(v, name, wrap);
    loaded
}

/// Each voxel axis's step in the world, and the first voxel's place.
fn axes(loaded: &Loaded) -> ([f64; 3], [[f64; 3]; 3]) {
    let t = loaded.volume.transform();
    let first = t.apply([0.0; 3]);
    let step = |m: usize| {
        let mut ijk = [0.0; 3];
        ijk[m] = 1.0;
        let p = t.apply(ijk);
        std::array::from_fn(|r| p[r] - first[r])
    };
    (first, [step(0), step(1), step(2)])
}

#[test]
fn every_encoding_reads_to_the_voxel() {
    let straight = [[1.5, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.5]];
    for (name, ty, wraps) in [
        ("ramp_i16_ascii.vti", VoxelType::I16, None),
        ("ramp_f32_binary.vti", VoxelType::F32, None),
        ("ramp_u8_raw.vti", VoxelType::U8, Some(256)),
        ("ramp_f64_base64.vti", VoxelType::F64, None),
        ("ramp_u16_zlib.vti", VoxelType::U16, None),
        ("ramp_i32_zlib_binary.vti", VoxelType::I32, None),
        ("ramp_i8_be.vti", VoxelType::I8, Some(-256)),
        ("ramp_u32_be_zlib.vti", VoxelType::U32, None),
        // 64-bit integers, held as f32 (these all exactly), and LZ4 blocks.
        ("ramp_i64_raw.vti", VoxelType::F32, None),
        ("ramp_u64_ascii.vti", VoxelType::F32, None),
        ("ramp_f32_lz4.vti", VoxelType::F32, None),
        ("ramp_i64_lz4_binary.vti", VoxelType::F32, None),
    ] {
        let wrap = |v: i64| match wraps {
            Some(256) => v % 256,
            Some(_) => (v as i8).into(),
            None => v,
        };
        let loaded = assert_ramp(name, ty, wrap);
        assert_eq!(axes(&loaded), ([-3.0, 4.0, 10.0], straight), "{name}");
        assert!(
            loaded.notes.iter().all(|n| !n.contains("rounded")),
            "{name}: {:?}",
            loaded.notes
        );
    }
}

#[test]
fn int64_values_beyond_f32_are_rounded_to_the_nearest_and_said() {
    // VTK's own reading of the values, and numpy's nearest f32 of each (make_vti.py).
    let text = std::fs::read_to_string(data("vti/beyond_f32_i64.json")).unwrap();
    let reference: serde_json::Value = serde_json::from_str(&text).unwrap();
    let f32s: Vec<f32> = reference["f32"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap() as f32)
        .collect();
    let values: Vec<i64> = reference["values"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_i64().unwrap())
        .collect();
    assert_eq!(values[0], -(1 << 62) - 1);
    let loaded = open("beyond_f32_i64.vti");
    let v = &loaded.volume;
    assert_eq!(v.voxel_type(), VoxelType::F32);
    assert_eq!(v.data().to_f32_vec(), f32s);
    let rounded = reference["rounded"].as_u64().unwrap();
    assert_eq!(rounded, 120);
    assert!(
        loaded.notes.contains(&format!(
            "120 i64 values beyond what an f32 holds exactly rounded to the nearest f32 (the \
             largest {})",
            values[0]
        )),
        "{:?}",
        loaded.notes
    );
}

#[test]
fn a_direction_turns_the_axes_and_cells_sit_at_their_centres() {
    // x along world y, y along world -x, z along z.
    let turned = [[0.0, 1.5, 0.0], [-2.0, 0.0, 0.0], [0.0, 0.0, 2.5]];
    let points = assert_ramp("rotated_i16_ascii.vti", VoxelType::I16, |v| v);
    assert_eq!(axes(&points), ([-3.0, 4.0, 10.0], turned));
    // The first cell's centre: half a step along each turned axis from the origin.
    let cells = assert_ramp("rotated_f64_cells.vti", VoxelType::F64, |v| v);
    assert_eq!(axes(&cells), ([-4.0, 4.75, 11.25], turned));
    assert!(cells.notes.iter().any(|n| n.contains("cell data")));
}

#[test]
fn pieces_are_assembled_into_the_whole_extent() {
    // VTK's writer streaming 3 pieces (x 0..1, then 1..5 split in y) and 2 (x 0..2, 2..5):
    // pieces of point data share their boundary points.
    for (name, ty, n) in [
        ("ramp_u16_pieces.vti", VoxelType::U16, 3),
        ("ramp_i16_pieces_ascii.vti", VoxelType::I16, 2),
    ] {
        let loaded = assert_ramp(name, ty, |v| v);
        let straight = [[1.5, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.5]];
        assert_eq!(axes(&loaded), ([-3.0, 4.0, 10.0], straight), "{name}");
        let note = format!("{n} pieces assembled into its WholeExtent");
        assert!(loaded.notes.contains(&note), "{name}: {:?}", loaded.notes);
    }
}

#[test]
fn pieces_that_do_not_tile_the_whole_extent_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let ascii = std::fs::read_to_string(data("vti/ramp_i16_pieces_ascii.vti")).unwrap();
    let edit = |from: &str, to: &str| {
        assert!(ascii.contains(from), "{from}");
        ascii.replacen(from, to, 1).into_bytes()
    };
    let whole = "WholeExtent=\"0 5 0 4 0 3\"";
    refused(
        d,
        "gap.vti",
        &edit(whole, "WholeExtent=\"0 6 0 4 0 3\""),
        "its pieces leave voxel (6, 0, 0) of its WholeExtent uncovered",
    );
    refused(
        d,
        "out.vti",
        &edit("Extent=\"2 5 0 4 0 3\"", "Extent=\"2 6 0 4 0 3\""),
        "its piece 1's Extent [2, 6, 0, 4, 0, 3] is not within its WholeExtent",
    );
    // The second piece's first value, at the shared point (2, 0, 0), made 7.
    refused(
        d,
        "disagree.vti",
        &edit("        2 3 4 5 12 13", "        7 3 4 5 12 13"),
        "its piece 1 gives voxel (2, 0, 0) another value than an earlier piece",
    );
    refused(
        d,
        "other.vti",
        &ascii
            .rsplitn(2, "type=\"Int16\"")
            .collect::<Vec<_>>()
            .into_iter()
            .rev()
            .collect::<Vec<_>>()
            .join("type=\"Int32\"")
            .into_bytes(),
        "its piece 1's array \"density\" is not of the first piece's type",
    );
    // Beyond the budget, refused before anything is read.
    refused(
        d,
        "huge.vti",
        &edit(whole, "WholeExtent=\"0 99999 0 99999 0 99999\""),
        "huge.vti",
    );
}

#[test]
fn the_same_volume_as_the_legacy_file() {
    for (vti, vtk) in [
        ("vti/ramp_i16_ascii.vti", "vtk/ramp_i16.vtk"),
        ("vti/ramp_f32_binary.vti", "vtk/ramp_f32.vtk"),
    ] {
        let a = load(&data(vti), &LoadOptions::default()).unwrap();
        let b = load(&data(vtk), &LoadOptions::default()).unwrap();
        assert_eq!(a.volume.dims(), b.volume.dims(), "{vti}");
        assert_eq!(a.volume.spacing(), b.volume.spacing(), "{vti}");
        assert_eq!(a.volume.transform(), b.volume.transform(), "{vti}");
        assert_eq!(a.volume.voxel_type(), b.volume.voxel_type(), "{vti}");
        let n = a.volume.len();
        let (ax, bx): (Vec<f32>, Vec<f32>) = (0..n)
            .map(|i| {
                let ijk = [i % 6, i / 6 % 5, i / 30];
                (a.volume.value(ijk), b.volume.value(ijk))
            })
            .unzip();
        assert_eq!(ax, bx, "{vti}");
    }
}

#[test]
fn scalars_name_the_array_read_among_others() {
    // `flow` (three components) and `mask` come first; `Scalars` names `density`.
    assert_ramp("ramp_u16_zlib.vti", VoxelType::U16, |v| v);
    let text = std::fs::read_to_string(data("vti/ramp_i16_ascii.vti")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    // Without Scalars, the first array of one component is read.
    let path = dir.path().join("unnamed.vti");
    std::fs::write(&path, text.replace(" Scalars=\"density\"", "")).unwrap();
    let loaded = load(&path, &LoadOptions::default()).unwrap();
    assert_eq!(loaded.volume.value([5, 4, 3]), 345.0);
}

#[test]
fn what_is_not_read_is_refused_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let ascii = std::fs::read_to_string(data("vti/ramp_i16_ascii.vti")).unwrap();
    let edit = |from: &str, to: &str| {
        assert!(ascii.contains(from), "{from}");
        ascii.replace(from, to).into_bytes()
    };
    let d = dir.path();
    refused(
        d,
        "mesh.vti",
        b"<VTKFile type=\"PolyData\"><PolyData/></VTKFile>",
        "a VTK XML PolyData file",
    );
    let piece = "<Piece Extent=\"0 5 0 4 0 3\">";
    let two = ascii.replacen("</Piece>", &format!("</Piece>{piece}</Piece>"), 1);
    refused(d, "two.vti", two.as_bytes(), "holds no array \"density\"");
    refused(
        d,
        "wider.vti",
        &edit("type=\"Int16\"", "type=\"Int128\""),
        "of type \"Int128\"",
    );
    refused(
        d,
        "long.vti",
        &ascii
            .replace("type=\"Int16\"", "type=\"Int64\"")
            .replace("345\n", "1e3\n")
            .into_bytes(),
        "ascii data, value 119: \"1e3\" is not an integer of type i64",
    );
    refused(
        d,
        "flow.vti",
        &edit(
            "format=\"ascii\"",
            "NumberOfComponents=\"3\" format=\"ascii\"",
        ),
        "3 components",
    );
    refused(
        d,
        "lzma.vti",
        &edit(
            "header_type=\"UInt32\"",
            "header_type=\"UInt32\" compressor=\"vtkLZMADataCompressor\"",
        ),
        "compressor \"vtkLZMADataCompressor\"",
    );
    refused(d, "short.vti", &edit("345\n", "\n"), "truncated ascii data");
    // The XML parser's message quotes the newline it found: escaped, the error is one line.
    let broken = ascii.replacen("<ImageData", "<ImageData\n\n<", 1);
    refused(d, "newline.vti", broken.as_bytes(), "its XML header");
    refused(d, "cut.vti", &ascii.as_bytes()[..600], "cut.vti");
    // A hostile extent: beyond the budget, refused before anything is allocated.
    refused(
        d,
        "huge.vti",
        &edit(piece, "<Piece Extent=\"0 99999 0 99999 0 99999\">"),
        "huge.vti",
    );
}

/// Where the appended data of `file` starts: after the `_` that follows `<AppendedData`.
fn appended(file: &[u8]) -> usize {
    let tag = file
        .windows(13)
        .position(|w| w == b"<AppendedData")
        .unwrap();
    tag + file[tag..].iter().position(|&b| b == b'_').unwrap() + 1
}

#[test]
fn hostile_binary_headers_are_refused_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let raw = std::fs::read(data("vti/ramp_u16_zlib.vti")).unwrap();
    let data_at = appended(&raw);
    // The block count of the array read (`density`, at offset 775) made a billion.
    let mut many = raw.clone();
    let density = data_at + 775;
    many[density..density + 4].copy_from_slice(&(1u32 << 30).to_le_bytes());
    refused(d, "many.vti", &many, "zlib header says 1073741824 blocks");
    // An offset beyond the file.
    let text = String::from_utf8_lossy(&raw).into_owned();
    let far = text.replacen("offset=\"775\"", "offset=\"9999999\"", 1);
    refused(d, "far.vti", far.as_bytes(), "beyond the file's end");
    // The zlib header of the first block of `density` (after 3 + 4 words) corrupted.
    let mut bad = raw.clone();
    bad[density + 28] = 0xff;
    refused(d, "corrupt.vti", &bad, "corrupt.vti");
    // Inline base64 that is not.
    let b64 = std::fs::read_to_string(data("vti/ramp_f32_binary.vti")).unwrap();
    let at = b64.find("format=\"binary\"").unwrap();
    let start = at + b64[at..].find('>').unwrap() + 12;
    let mut broken = b64.clone();
    broken.replace_range(start..=start, "!");
    refused(d, "b64.vti", broken.as_bytes(), "not base64");
    // A raw array whose size header disagrees with its extent.
    let u8raw = std::fs::read(data("vti/ramp_u8_raw.vti")).unwrap();
    let data_at = appended(&u8raw);
    let mut lie = u8raw.clone();
    lie[data_at..data_at + 8].copy_from_slice(&u64::MAX.to_le_bytes());
    refused(d, "lie.vti", &lie, "not the 120 of its voxels");
    // LZ4 blocks (UInt32 words: the count, the block size, the last block's size, then each
    // block's compressed size): the first block's bytes made garbage, then its size a lie.
    let lz4 = std::fs::read(data("vti/ramp_f32_lz4.vti")).unwrap();
    let at = appended(&lz4);
    let word = |i: usize| u32::from_le_bytes(lz4[at + 4 * i..at + 4 * i + 4].try_into().unwrap());
    assert_eq!((word(0), word(1), word(2)), (8, 64, 32));
    let first = at + 4 * (3 + 8);
    let mut garbage = lz4.clone();
    garbage[first..first + word(3) as usize].fill(0xff);
    refused(d, "lz4garbage.vti", &garbage, "lz4 block 0");
    let mut short = lz4.clone();
    short[at + 12..at + 16].copy_from_slice(&(word(3) - 1).to_le_bytes());
    refused(d, "lz4short.vti", &short, "lz4short.vti");
    let mut many = lz4.clone();
    many[at..at + 4].copy_from_slice(&(1u32 << 30).to_le_bytes());
    refused(
        d,
        "lz4many.vti",
        &many,
        "its lz4 header says 1073741824 blocks",
    );
}

#[test]
fn info_lists_the_arrays_the_one_read_first() {
    let (details, v) = crate::common::info_details(&data("vti/ramp_u16_zlib.vti"), "vti");
    assert_eq!(
        details,
        "arrays      density (UInt16, point data), flow (Float32 x3, point data), mask (UInt8, \
         point data)"
    );
    let arrays = v["vti"]["arrays"].as_array().unwrap();
    let listed: Vec<(&str, &str, u64, &str)> = arrays
        .iter()
        .map(|a| {
            (
                a["name"].as_str().unwrap(),
                a["type"].as_str().unwrap(),
                a["components"].as_u64().unwrap(),
                a["data"].as_str().unwrap(),
            )
        })
        .collect();
    assert_eq!(
        listed,
        [
            ("density", "UInt16", 1, "point"),
            ("flow", "Float32", 3, "point"),
            ("mask", "UInt8", 1, "point"),
        ]
    );
    assert!(v["vtk"].is_null() && v["mrc"].is_null());
    let (details, _) = crate::common::info_details(&data("vti/rotated_f64_cells.vti"), "vti");
    assert_eq!(details, "arrays      density (Float64, cell data)");
}

#[test]
fn appended_raw_values_are_read_in_place() {
    let r = crate::common::run(&[
        "info",
        "--json",
        data("vti/ramp_u8_raw.vti").to_str().unwrap(),
    ]);
    assert!(r.ok, "{}", r.stderr);
    let v: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
    assert_eq!(v["mapped_bytes"], 120, "{v}");
    assert_eq!(v["memory_bytes"], 0, "{v}");
}

#[test]
fn array_names_the_array_read() {
    let path = data("vti/ramp_u16_zlib.vti");
    let named = |name: &str| slabscope::LoadOptions {
        part: slabscope::formats::PartOptions {
            array: Some(name.to_string()),
            ..slabscope::formats::PartOptions::default()
        },
        ..slabscope::LoadOptions::default()
    };
    // `mask`, all zeros, instead of the `density` that `Scalars` names.
    let loaded = slabscope::load(&path, &named("mask")).unwrap();
    assert_eq!(loaded.volume.voxel_type(), slabscope::volume::VoxelType::U8);
    assert_eq!(loaded.volume.dims(), [6, 5, 4]);
    assert!(loaded.volume.data().to_f32_vec().iter().all(|&v| v == 0.0));
    let density = slabscope::load(&path, &named("density")).unwrap();
    assert_eq!(density.volume.value([5, 4, 3]), 345.0);
    let e = slabscope::load(&path, &named("nope"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("holds no array \"nope\": its arrays are \"flow\", \"mask\", \"density\""),
        "{e}"
    );
    // A vector field named is refused as when `Scalars` names it.
    let e = slabscope::load(&path, &named("flow"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("3 components"), "{e}");
    // Of a file of another format, --array is an error.
    let e = slabscope::load(&data("mrc/ramp_i16.mrc"), &named("x"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("this mrc file holds one volume"), "{e}");
}

/// A 64³ u8 `.vti` whose one LZ4 block is the whole array (256 KiB of 7s), appended raw.
fn one_lz4_block(dir: &std::path::Path) -> std::path::PathBuf {
    let block = vec![7u8; 1 << 18];
    let compressed = lz4_flex::block::compress(&block);
    let mut bytes = br#"<?xml version="1.0"?>
<VTKFile type="ImageData" version="1.0" byte_order="LittleEndian" header_type="UInt32" compressor="vtkLZ4DataCompressor">
  <ImageData WholeExtent="0 63 0 63 0 63" Origin="0 0 0" Spacing="1 1 1">
    <Piece Extent="0 63 0 63 0 63">
      <PointData Scalars="s">
        <DataArray type="UInt8" Name="s" format="appended" offset="0"/>
      </PointData>
    </Piece>
  </ImageData>
  <AppendedData encoding="raw">
   _"#
    .to_vec();
    for w in [1, 1 << 18, 0, u32::try_from(compressed.len()).unwrap()] {
        bytes.extend(u32::to_le_bytes(w));
    }
    bytes.extend(&compressed);
    bytes.extend(b"\n  </AppendedData>\n</VTKFile>\n");
    let path = dir.join("one_block.vti");
    std::fs::write(&path, bytes).unwrap();
    path
}

/// An LZ4 block is held whole (LZ4's blocks have no stream): with its compressed bytes, beside
/// the volume, within the budget, or refused before it is decoded, naming the budget.
#[test]
fn an_lz4_block_held_whole_is_weighed_beside_the_volume() {
    let dir = tempfile::tempdir().unwrap();
    let path = one_lz4_block(dir.path());
    let with = |max_memory: u64| LoadOptions {
        max_memory,
        ..LoadOptions::default()
    };
    // The volume alone (256 KiB) fits in 400,000 bytes; with the block beside it, it does not.
    let e = load(&path, &with(400_000)).unwrap_err().to_string();
    assert!(
        e.contains("lz4 blocks, each held whole") && e.contains("one_block.vti"),
        "{e}"
    );
    assert!(!e.contains('\n'), "{e}");
    let loaded = load(&path, &with(600_000)).unwrap();
    assert!(loaded.volume.data().to_f32_vec().iter().all(|&v| v == 7.0));
}
