//! Every format loads files written by other programs (`tests/data/make_fixtures.py`) with the
//! right voxels, dimensions and spacing; the real volumes load as their README describes.

use std::path::{Path, PathBuf};

use slabscope::formats::{NrrdEncoding, RawOptions, write_nrrd};
use slabscope::volume::{Endian, VoxelType};
use slabscope::{Format, LoadOptions, Loaded, Volume, load};

use crate::common::data;

fn open(name: &str) -> Loaded {
    load(&data(name), &LoadOptions::default()).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Checks the 5x4x3 ramp `v = (x + 10y + 100z) * scale + offset` of `make_fixtures.py`.
fn assert_ramp(v: &Volume, offset: f64, scale: f64) {
    assert_eq!(v.dims(), [5, 4, 3]);
    for z in 0..3 {
        for y in 0..4 {
            for x in 0..5 {
                let expect = ((x + 10 * y + 100 * z) as f64 * scale + offset) as f32;
                let got = v.value([x, y, z]);
                assert!(
                    (got - expect).abs() < 1e-4,
                    "voxel ({x},{y},{z}): {got} != {expect}"
                );
            }
        }
    }
}

#[test]
fn nifti_every_voxel_type() {
    let cases = [
        ("u8", VoxelType::U8, 0.0, 1.0),
        ("i8", VoxelType::I8, -100.0, 0.5),
        ("u16", VoxelType::U16, 1000.0, 1.0),
        ("i16", VoxelType::I16, -100.0, 1.0),
        ("u32", VoxelType::U32, 70000.0, 1.0),
        ("i32", VoxelType::I32, -70000.0, 1.0),
        ("f32", VoxelType::F32, 0.25, 0.5),
        ("f64", VoxelType::F64, -0.5, 0.25),
    ];
    for (name, ty, offset, scale) in cases {
        let l = open(&format!("ramp_{name}.nii"));
        assert_eq!(l.format, Format::Nifti);
        assert_eq!(l.volume.voxel_type(), ty, "{name}");
        assert_eq!(l.volume.spacing(), [0.5, 0.75, 2.0], "{name}");
        // i8 is truncated by numpy's astype: (v * 0.5 - 100) as i8 keeps the integer part.
        if ty == VoxelType::I8 {
            let v = &l.volume;
            assert_eq!(v.value([3, 0, 0]), -98.0);
            assert_eq!(v.value([0, 0, 2]), -0.0);
        } else {
            assert_ramp(&l.volume, offset, scale);
        }
    }
}

#[test]
fn nifti_scaling_byte_order_gzip_and_4d() {
    let l = open("ramp_i16_scaled.nii.gz");
    assert_ramp(&l.volume, -10.0, 2.0);
    assert_eq!(l.volume.voxel_type(), VoxelType::I16);

    assert_ramp(&open("ramp_f32_be.nii").volume, 0.25, 0.5);
    assert_ramp(&open("ramp_u8_two_members.nii.gz").volume, 0.0, 1.0);

    let l = open("ramp_4d_um.nii.gz");
    assert_ramp(&l.volume, 0.0, 1.0);
    assert!(
        l.notes.iter().any(|n| n.contains("loaded volume 0")),
        "{:?}",
        l.notes
    );
    assert_eq!(l.volume.spacing(), [0.001; 3], "micron units become mm");
}

#[test]
fn nrrd_raw_gzip_detached_ascii() {
    let l = open("ramp_u16_be.nrrd");
    assert_eq!(l.format, Format::Nrrd);
    assert_ramp(&l.volume, 1000.0, 1.0);
    assert_eq!(l.volume.spacing(), [0.5, 0.75, 2.0]);

    let l = open("ramp_f32_gzip.nrrd");
    assert_ramp(&l.volume, 0.25, 0.5);
    assert_eq!(
        l.volume.spacing(),
        [0.5, 0.75, 2.0],
        "from space directions"
    );

    assert_ramp(&open("ramp_i16_detached.nhdr").volume, -100.0, 1.0);
    assert_ramp(&open("ramp_u8_ascii.nrrd").volume, 0.0, 1.0);
}

#[test]
fn metaimage_attached_compressed_detached() {
    let l = open("ramp_i16.mha");
    assert_eq!(l.format, Format::MetaImage);
    assert_ramp(&l.volume, -100.0, 1.0);
    assert_eq!(l.volume.spacing(), [0.5, 0.75, 2.0]);
    assert_ramp(&open("ramp_f32_zlib.mha").volume, 0.25, 0.5);
    assert_ramp(&open("ramp_u8.mhd").volume, 0.0, 1.0);
}

#[test]
fn tiff_stacks_and_folders() {
    let l = open("ramp_u16_stack.tif");
    assert_eq!(l.format, Format::Tiff);
    assert_ramp(&l.volume, 1000.0, 1.0);
    assert_eq!(
        l.volume.spacing(),
        [0.5, 0.75, 2.0],
        "ImageJ resolution and spacing"
    );
    assert_ramp(&open("ramp_f32_stack.tif").volume, 0.25, 0.5);

    // slice_10 sorts after slice_2.
    let l = open("ramp_slices");
    assert_eq!(l.format, Format::TiffFolder);
    assert_ramp(&l.volume, 0.0, 1.0);
}

#[test]
fn real_volumes_match_their_readme() {
    type Case = (&'static str, [usize; 3], [f64; 3], VoxelType, [f32; 2]);
    let cases: [Case; 4] = [
        (
            "BrainProtonDensity3Slices.mha",
            [181, 217, 3],
            [1.0; 3],
            VoxelType::U8,
            [0.0, 250.0],
        ),
        (
            "nilearn_image_10426.nii.gz",
            [53, 63, 46],
            [3.0; 3],
            VoxelType::F32,
            [-7.9414, 7.9413],
        ),
        (
            "dx_MRI.nhdr",
            [16, 128, 128],
            [2.066_667, 1.773_153, 1.773_153],
            VoxelType::U16,
            [668.0, 57684.0],
        ),
        (
            "pyvista_channels.nrrd",
            [250, 250, 100],
            [1.0; 3],
            VoxelType::U8,
            [0.0, 4.0],
        ),
    ];
    for (name, dims, spacing, ty, range) in cases {
        let v = open(name).volume;
        assert_eq!(v.dims(), dims, "{name}");
        assert_eq!(v.voxel_type(), ty, "{name}");
        for (got, want) in v.spacing().iter().zip(spacing) {
            assert!(
                (got - want).abs() < 1e-5,
                "{name} spacing {:?}",
                v.spacing()
            );
        }
        assert!(
            (v.stats().min - range[0]).abs() < 1e-4,
            "{name} min {}",
            v.stats().min
        );
        assert!(
            (v.stats().max - range[1]).abs() < 1e-4,
            "{name} max {}",
            v.stats().max
        );
    }
}

/// Writes `bytes` to a fresh temporary folder under `name`.
fn temp_file(name: &str, bytes: &[u8]) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    std::fs::write(&path, bytes).unwrap();
    (dir, path)
}

#[test]
fn volumeshop_dat_is_recognised_by_size() {
    let mut bytes = Vec::new();
    for d in [3u16, 2, 2] {
        bytes.extend(d.to_le_bytes());
    }
    for v in 0..12u16 {
        bytes.extend((v * 100).to_le_bytes());
    }
    let (_dir, path) = temp_file("tooth.dat", &bytes);
    let l = load(&path, &LoadOptions::default()).unwrap();
    assert_eq!(l.format, Format::VolumeShop);
    assert_eq!(l.volume.dims(), [3, 2, 2]);
    assert_eq!(l.volume.value([2, 1, 1]), 1100.0);
}

#[test]
fn raw_from_options_and_from_names() {
    let bytes: Vec<u8> = (0..24u16).flat_map(u16::to_be_bytes).collect();
    let mut with_offset = vec![0xAA; 10];
    with_offset.extend(&bytes);
    let (_dir, path) = temp_file("scan.bin", &with_offset);
    let opts = LoadOptions {
        raw: RawOptions {
            dims: Some([4, 3, 2]),
            voxel_type: Some(VoxelType::U16),
            spacing: Some([0.5, 0.5, 1.5]),
            endian: Some(Endian::Big),
            offset: Some(10),
        },
        ..LoadOptions::default()
    };
    let l = load(&path, &opts).unwrap();
    assert_eq!(l.format, Format::Raw);
    assert_eq!(l.volume.spacing(), [0.5, 0.5, 1.5]);
    assert_eq!(l.volume.value([3, 2, 1]), 23.0);

    let bytes: Vec<u8> = (0..24u8).collect();
    for name in ["bonsai_4x3x2_uint8.raw", "head.4x3x2.u8.raw"] {
        let (_dir, path) = temp_file(name, &bytes);
        let l = load(&path, &LoadOptions::default()).unwrap();
        assert_eq!(l.volume.dims(), [4, 3, 2], "{name}");
        assert_eq!(l.volume.value([1, 1, 1]), 17.0, "{name}");
    }
}

#[test]
fn large_raw_file_loads_through_the_map() {
    // 64 MiB of u16: big enough that a parallel, chunked decode is exercised across chunks.
    let n = 256 * 256 * 512;
    let bytes: Vec<u8> = (0..n)
        .flat_map(|i| ((i % 65_521) as u16).to_le_bytes())
        .collect();
    let (_dir, path) = temp_file("big_256x256x512_u16.raw", &bytes);
    let v = load(&path, &LoadOptions::default()).unwrap().volume;
    assert_eq!(v.len(), n);
    assert_eq!(v.data().to_f32_vec()[n - 1], ((n - 1) % 65_521) as f32);
    assert_eq!(v.data().to_f32_vec()[70_000], (70_000 % 65_521) as f32);
}

#[test]
fn nrrd_writer_round_trips_and_never_overwrites() {
    let dir = tempfile::tempdir().unwrap();
    let original = open("ramp_i16.mha").volume;
    for (name, encoding) in [
        ("a.nrrd", NrrdEncoding::Raw),
        ("b.nrrd", NrrdEncoding::Gzip),
    ] {
        let path = dir.path().join(name);
        write_nrrd(&path, &original, encoding, false).unwrap();
        let back = load(&path, &LoadOptions::default()).unwrap().volume;
        assert_eq!(back.data().to_f32_vec(), original.data().to_f32_vec());
        assert_eq!(back.spacing(), original.spacing());
        assert_eq!(back.voxel_type(), VoxelType::I16);
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(&path).unwrap().permissions().mode() & 0o777;
            assert_eq!(
                mode, 0o644,
                "written files are readable, not the temporary file's 0600"
            );
        }
        let err = write_nrrd(&path, &original, encoding, false).unwrap_err();
        assert!(err.to_string().contains("already exists"), "{err}");
        write_nrrd(&path, &original, encoding, true).unwrap();
    }
    let leftovers: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .filter_map(Result::ok)
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left behind");
}

/// Loads volume `n` of `path`.
fn volume_of(path: &Path, n: usize) -> slabscope::Result<Loaded> {
    load(
        path,
        &LoadOptions {
            part: slabscope::formats::PartOptions {
                volume: n,
                ..slabscope::formats::PartOptions::default()
            },
            ..LoadOptions::default()
        },
    )
}

#[test]
fn any_volume_of_a_4d_file_can_be_read() {
    // NIfTI: the fixture's second volume is the first plus 500.
    let nii = data("ramp_4d_um.nii.gz");
    let l = volume_of(&nii, 1).unwrap();
    assert_ramp(&l.volume, 500.0, 1.0);
    assert!(
        l.notes.iter().any(|n| n.contains("loaded volume 1")),
        "{:?}",
        l.notes
    );
    let e = volume_of(&nii, 2).unwrap_err().to_string();
    assert!(
        e.contains("holds 2 volumes (numbered from 0), so there is no volume 2"),
        "{e}"
    );
    // NRRD and MetaImage, 2x2x1 voxels, three volumes of (v + 10·t), in every encoding and
    // placement of the data.
    let values: Vec<u8> = (0..3u8)
        .flat_map(|t| (0..4u8).map(move |v| v + 10 * t))
        .collect();
    let ascii = values
        .iter()
        .map(u8::to_string)
        .collect::<Vec<_>>()
        .join(" ");
    let gzip = {
        use std::io::Write;
        let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        e.write_all(&values).unwrap();
        e.finish().unwrap()
    };
    let nrrd = |encoding: &str, skip: &str, body: &[u8]| {
        let mut f = format!(
            "NRRD0004\ntype: uint8\ndimension: 4\nsizes: 2 2 1 3\nencoding: {encoding}\n{skip}\n"
        )
        .into_bytes();
        f.extend(body);
        f
    };
    let mut padded = vec![7u8; 5];
    padded.extend(&values);
    let files = [
        ("raw.nrrd", nrrd("raw", "", &values)),
        ("ascii.nrrd", nrrd("ascii", "", ascii.as_bytes())),
        ("gzip.nrrd", nrrd("gzip", "", &gzip)),
        ("end.nrrd", nrrd("raw", "byte skip: -1\n", &padded)),
        (
            "four.mha",
            [
                b"ObjectType = Image\nNDims = 4\nDimSize = 2 2 1 3\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n"
                    .as_slice(),
                &values,
            ]
            .concat(),
        ),
    ];
    for (name, bytes) in files {
        let (_dir, path) = temp_file(name, &bytes);
        for t in 0..3 {
            let l = volume_of(&path, t).unwrap_or_else(|e| panic!("{name} {t}: {e}"));
            let got: Vec<f32> = l.volume.data().to_f32_vec();
            let want: Vec<f32> = (0..4).map(|v| (v + 10 * t) as f32).collect();
            assert_eq!(got, want, "{name}, volume {t}");
        }
        assert!(volume_of(&path, 3).is_err(), "{name}");
    }
    // A 3D file, a folder of slices: volume 0 only.
    let e = volume_of(&data("ramp_u8.nii"), 1).unwrap_err().to_string();
    assert!(e.contains("holds 1 volume"), "{e}");
    let e = volume_of(&data("ramp_slices"), 1).unwrap_err().to_string();
    assert!(e.contains("holds 1 volume"), "{e}");
}

/// An OME-TIFF fixture of `tests/data/ome/` (tifffile's; see its `make.py`) read at `channel`
/// and time point `volume`.
fn ome(name: &str, channel: usize, volume: usize) -> slabscope::Result<Loaded> {
    let opts = LoadOptions {
        part: slabscope::formats::PartOptions {
            channel,
            volume,
            ..slabscope::formats::PartOptions::default()
        },
        ..LoadOptions::default()
    };
    load(&data(&format!("ome/{name}")), &opts)
}

#[test]
fn ome_tiff_pages_are_ordered_by_the_ome_xml_and_sized_by_it() {
    let expected: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(data("ome/expected.json")).unwrap()).unwrap();
    // v = x + 10 y + 100 z + 1000 c + 3000 t; spacing 0.5 x 0.25 x 2 µm, in mm.
    for name in ["zct.ome.tif", "ztc_nm.ome.tif"] {
        let e = &expected[name];
        assert_eq!(e["pages"], 12);
        for (c, t) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            let loaded = ome(name, c, t).unwrap();
            let v = &loaded.volume;
            assert_eq!(v.dims(), [5, 4, 3], "{name}");
            let s = v.spacing();
            assert!(
                (s[0] - 5e-4).abs() < 1e-12 && (s[1] - 2.5e-4).abs() < 1e-12,
                "{s:?}"
            );
            assert!((s[2] - 2e-3).abs() < 1e-12, "{s:?}");
            assert_ramp(v, (1000 * c + 3000 * t) as f64, 1.0);
            assert_eq!(
                loaded.notes,
                [format!(
                    "OME-TIFF of 2 channels and 2 time points: read channel {c} at time point {t}"
                )]
            );
        }
    }
    let plain = ome("plain_z.ome.tif", 0, 0).unwrap();
    assert_eq!(plain.volume.spacing(), [0.5, 0.5, 1.5]);
    assert_ramp(&plain.volume, 0.0, 1.0);
    assert!(plain.notes.is_empty(), "{:?}", plain.notes);
}

#[test]
fn an_ome_tiff_channel_or_time_point_it_lacks_is_an_error_naming_what_it_has() {
    let e = ome("zct.ome.tif", 2, 0).unwrap_err().to_string();
    assert!(
        e.ends_with("zct.ome.tif: holds 2 channels (numbered from 0), so there is no channel 2"),
        "{e}"
    );
    let e = ome("zct.ome.tif", 0, 5).unwrap_err().to_string();
    assert!(
        e.ends_with("zct.ome.tif: holds 2 volumes (numbered from 0), so there is no volume 5"),
        "{e}"
    );
}

#[test]
fn a_channel_of_a_file_of_one_channel_is_an_error() {
    let opts = LoadOptions {
        part: slabscope::formats::PartOptions {
            channel: 1,
            ..slabscope::formats::PartOptions::default()
        },
        ..LoadOptions::default()
    };
    for name in ["ramp_u8.nii", "ramp_u16_stack.tif", "ramp_slices"] {
        let e = load(&data(name), &opts).unwrap_err().to_string();
        assert!(
            e.ends_with(&format!(
                "{name}: holds 1 channel (numbered from 0), so there is no channel 1"
            )),
            "{e}"
        );
    }
}

/// DICOM series, TIFF stacks and folders, MRC's f16 and reordered maps beyond the budget, given
/// a scratch folder, are decoded into it and read back mapped: every voxel, the geometry and the
/// type as in memory; without the folder they are refused, the error saying the folder would do.
#[test]
fn decoded_voxels_of_every_reader_beyond_the_budget_go_to_the_scratch_folder() {
    let scratch = tempfile::tempdir().unwrap();
    let in_memory = |series: Option<&str>| {
        let mut opts = LoadOptions::default();
        opts.dicom.series = series.map(str::to_owned);
        opts
    };
    let cases = [
        ("dicom/ct", Some("1")),
        ("dicom/gap", None),
        ("ramp_u16_stack.tif", None),
        ("ramp_slices", None),
        ("mrc/ramp_f16.mrc", None),
        ("mrc/ramp_zyx.mrc", None),
        ("ramp_u8_ascii.nrrd", None),
    ];
    for (name, series) in cases {
        let path = data(name);
        let held = load(&path, &in_memory(series)).unwrap().volume;
        // DICOM and TIFF go there as f32, a reordered MRC map in its own type.
        let size = if name.contains("zyx") { 2 } else { 4 };
        let tight = LoadOptions {
            max_memory: held.len() as u64 * size - 1,
            ..in_memory(series)
        };
        let refused = load(&path, &tight).unwrap_err();
        assert!(
            matches!(refused, slabscope::Error::TooLarge { disk: true, .. }),
            "{name}: {refused}"
        );
        let spilled = LoadOptions {
            scratch: Some(scratch.path().to_path_buf()),
            ..tight
        };
        let v = load(&path, &spilled)
            .unwrap_or_else(|e| panic!("{name}: {e}"))
            .volume;
        assert_eq!(v.scratch_bytes(), held.len() as u64 * size, "{name}");
        assert_eq!(
            (v.dims(), v.spacing(), v.voxel_type()),
            (held.dims(), held.spacing(), held.voxel_type()),
            "{name}"
        );
        assert_eq!(v.transform(), held.transform(), "{name}");
        let [nx, ny, nz] = v.dims();
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    let (a, b) = (v.value([x, y, z]), held.value([x, y, z]));
                    assert!(
                        a.to_bits() == b.to_bits(),
                        "{name} ({x},{y},{z}): {a} != {b}"
                    );
                }
            }
        }
    }
    // The scratch files have no names: nothing is left in the folder.
    assert_eq!(std::fs::read_dir(scratch.path()).unwrap().count(), 0);
    // Ascii data too short for the values its header claims reserves nothing on disk.
    let liar = scratch.path().join("liar.nrrd");
    std::fs::write(
        &liar,
        "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 4000 4000 4000\nencoding: ascii\n\n1 2 3\n",
    )
    .unwrap();
    let opts = LoadOptions {
        max_memory: 1 << 20,
        scratch: Some(scratch.path().to_path_buf()),
        ..LoadOptions::default()
    };
    let e = load(&liar, &opts).unwrap_err().to_string();
    assert!(
        e.ends_with(
            "6 bytes of ascii data cannot hold the 64000000000 values of a 4000x4000x4000 volume"
        ),
        "{e}"
    );
}
