//! Fuzzing every header parser through `load`: arbitrary bytes, and valid files with random
//! edits, must give a volume or an error naming the file; never a panic or a runaway allocation.
//!
//! `PROPTEST_CASES=20000 cargo test --release --test it fuzz_headers::` runs it for longer.

use std::path::{Path, PathBuf};

use proptest::prelude::*;
use slabscope::{LoadOptions, load};

use crate::common::data;

/// File names that steer detection to each reader.
const NAMES: [&str; 13] = [
    "f.nii",
    "f.nii.gz",
    "f.nrrd",
    "f.nhdr",
    "f.mha",
    "f.mhd",
    "f.mrc",
    "f.vtk",
    "f.dat",
    "f.tif",
    "f_4x4x4_u8.raw",
    "f.bin",
    "f.vti",
];

/// Valid files to mutate, one per format.
const SEEDS: [&str; 21] = [
    "ramp_u8.nii",
    "ramp_i16_scaled.nii.gz",
    "ramp_u16_be.nrrd",
    "ramp_f32_gzip.nrrd",
    "ramp_u8_ascii.nrrd",
    "ramp_i16.mha",
    "ramp_f32_zlib.mha",
    "ramp_u16_stack.tif",
    "ramp_f32_stack.tif",
    "mrc/ramp_zyx.mrc",
    "mrc/ramp_f16.mrc",
    "vtk/ramp_i16.vtk",
    "vtk/ramp_u8_ascii.vtk",
    "vti/ramp_u8_raw.vti",
    "vti/ramp_u16_zlib.vti",
    "vti/ramp_i32_zlib_binary.vti",
    "vti/ramp_f64_base64.vti",
    "vti/ramp_f32_lz4.vti",
    "vti/ramp_i64_lz4_binary.vti",
    "vti/ramp_u16_pieces.vti",
    "vtk/ramp_i64.vtk",
];

fn seed_bytes(name: &str) -> Vec<u8> {
    std::fs::read(data(name)).unwrap()
}

/// Loads `bytes` saved as `name` under a 64 MiB limit and checks the outcome is well-formed.
fn check(dir: &Path, name: &str, bytes: &[u8]) -> Result<(), TestCaseError> {
    // A seed in a folder of fixtures is written under its file name.
    let path: PathBuf = dir.join(Path::new(name).file_name().unwrap());
    std::fs::write(&path, bytes).unwrap();
    let opts = LoadOptions {
        max_memory: 64 << 20,
        ..LoadOptions::default()
    };
    match load(&path, &opts) {
        Ok(loaded) => {
            let v = loaded.volume;
            prop_assert_eq!(v.len(), v.dims().iter().product::<usize>());
            prop_assert!(v.stats().finite > 0);
        }
        Err(e) => {
            let msg = e.to_string();
            let dir = dir.display().to_string();
            prop_assert!(
                msg.starts_with(&dir),
                "error does not name the file: {}",
                msg
            );
            prop_assert!(!msg.contains('\n'), "multi-line error: {}", msg);
        }
    }
    std::fs::remove_file(&path).ok();
    Ok(())
}

/// An edit of a valid file: overwrite a byte, cut the file, or splice in header-like text.
#[derive(Clone, Debug)]
enum Edit {
    Byte(usize, u8),
    Truncate(usize),
    Splice(usize, String),
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Edit::Byte(i, b)),
        any::<usize>().prop_map(Edit::Truncate),
        (
            any::<usize>(),
            prop::sample::select(vec![
                "sizes: 99999 99999 99999\n",
                "dimension: 4\n",
                "-1",
                "\n\n",
                "DimSize = 0 3 3\n",
                "byte skip: 1000000\n",
                "data file: /nonexistent\n",
                "encoding: gzip\n",
                "ElementDataFile = LIST\n",
                "type: double\n",
                "65535",
                "Extent=\"0 1 0 1 0 1\"",
                "<Piece Extent=\"0 5 0 4 0 3\"></Piece>",
            ])
            .prop_map(str::to_string)
        )
            .prop_map(|(i, s)| Edit::Splice(i, s)),
    ]
}

fn apply(mut bytes: Vec<u8>, edits: &[Edit]) -> Vec<u8> {
    for e in edits {
        let n = bytes.len().max(1);
        match e {
            Edit::Byte(i, b) => {
                if !bytes.is_empty() {
                    bytes[i % n] = *b;
                }
            }
            Edit::Truncate(i) => bytes.truncate(i % n),
            Edit::Splice(i, s) => {
                let at = (i % n).min(bytes.len());
                bytes.splice(at..at, s.bytes());
            }
        }
    }
    bytes
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_bytes_never_panic(name in prop::sample::select(NAMES.to_vec()), bytes in prop::collection::vec(any::<u8>(), 0..1500)) {
        let dir = tempfile::tempdir().unwrap();
        check(dir.path(), name, &bytes)?;
    }

    #[test]
    fn edited_valid_files_never_panic(seed in prop::sample::select(SEEDS.to_vec()), edits in prop::collection::vec(edit(), 1..6)) {
        let dir = tempfile::tempdir().unwrap();
        let bytes = apply(seed_bytes(seed), &edits);
        check(dir.path(), seed, &bytes)?;
    }

    #[test]
    fn magic_prefixed_garbage_never_panics(
        magic in prop::sample::select(vec![&b"NRRD0004\n"[..], b"ObjectType = Image\n", b"II*\0", b"MM\0*", b"\x1f\x8b\x08\0", b"<VTKFile type=\"ImageData\">"]),
        rest in prop::collection::vec(any::<u8>(), 0..600),
    ) {
        let dir = tempfile::tempdir().unwrap();
        let mut bytes = magic.to_vec();
        bytes.extend(rest);
        check(dir.path(), "f.vol", &bytes)?;
    }
}
