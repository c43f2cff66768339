//! Every file of the `tests/bad/` corpus (made by `tests/bad/make_corpus.py`) gets a one-line error
//! naming the file and the problem, a non-zero exit and an empty stdout; never a panic, never an
//! allocation sized by an unchecked header.

use std::path::Path;

use crate::common::{Ran, bad, data, slabscope};

/// Runs `slabscope info` on `path` with a 1 GiB memory limit.
fn info(path: &Path, extra: &[&str]) -> Ran {
    let mut cmd = slabscope();
    cmd.arg("info").arg(path).args(extra);
    if !extra.contains(&"--max-memory") {
        cmd.args(["--max-memory", "1G"]);
    }
    cmd.output().unwrap().into()
}

const FAILURES: &[(&str, &str)] = &[
    (
        "truncated.nrrd",
        "truncated voxel data: expected 64 bytes, found 40",
    ),
    ("too_long.nrrd", "header and file size disagree"),
    (
        "absurd_dims.nrrd",
        "truncated voxel data: expected 4000000000000000 bytes, found 16",
    ),
    (
        "overflow_dims.nrrd",
        "has more voxels than this machine can address",
    ),
    ("zero_dim.nrrd", "dimensions 4x0x4 contain a zero"),
    ("int64.nrrd", "unsupported: NRRD type \"int64\""),
    ("bzip2.nrrd", "unsupported: NRRD encoding \"bzip2\""),
    ("no_sizes.nrrd", "header has no \"sizes\" field"),
    (
        "truncated_gzip.nrrd",
        "truncated voxel data: expected 8192 bytes, found",
    ),
    ("corrupt_gzip.nrrd", "corrupt gzip data"),
    ("missing_data_file.nhdr", "its data file"),
    ("vector.nrrd", "3 components per voxel"),
    ("mha_missing_datafile.mha", "no ElementDataFile"),
    (
        "mha_truncated_zlib.mha",
        "truncated voxel data: expected 1024 bytes",
    ),
    (
        "mha_bad_type.mha",
        "unsupported: ElementType MET_FLOAT_MATRIX",
    ),
    (
        "nifti_truncated.nii",
        "truncated voxel data: expected 1024 bytes, found 100",
    ),
    ("nifti_complex.nii", "NIfTI datatype 32 (complex64)"),
    (
        "nifti_absurd.nii",
        "truncated voxel data: expected 140724603846652 bytes, found 64",
    ),
    (
        "nifti_bad_offset.nii",
        "vox_offset 100 lies inside the 348-byte header",
    ),
    (
        "nifti_header_only.nii",
        "the name says NIfTI but the content does not start like a NIfTI file",
    ),
    ("volumeshop_wrong_size.dat", "not a VolumeShop .dat file"),
    ("empty.nrrd", "the file is empty"),
    ("not_a_volume.txt", "not a volume file"),
    ("pixel.png", "not a volume file"),
    ("tiff_garbage.tif", "not a readable TIFF"),
    ("empty_folder", "folder holds no .tif or .tiff slices"),
    ("does_not_exist.nii", "No such file"),
];

#[test]
fn every_bad_file_gets_a_clear_one_line_error() {
    for (name, phrase) in FAILURES {
        let Ran {
            ok, stdout, stderr, ..
        } = info(&bad(name), &[]);
        assert!(!ok, "{name}: expected failure, got success");
        assert!(
            stdout.is_empty(),
            "{name}: stdout should be empty, got {stdout}"
        );
        assert!(
            stderr.contains(phrase),
            "{name}: {stderr:?} lacks {phrase:?}"
        );
        assert!(
            stderr.contains(name),
            "{name}: the error does not name the file: {stderr}"
        );
        assert!(!stderr.contains("panicked"), "{name}: panicked: {stderr}");
        assert_eq!(
            stderr.trim_end().lines().count(),
            1,
            "{name}: not one line: {stderr}"
        );
    }
}

#[test]
fn the_corpus_is_covered() {
    let mut names: Vec<String> = std::fs::read_dir(bad(""))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n != "make_corpus.py")
        .collect();
    names.sort();
    for name in &names {
        let known = FAILURES.iter().any(|(n, _)| n == name)
            || ["nan_voxels.nrrd", "constant.nrrd", "all_nan.nrrd"].contains(&name.as_str());
        assert!(known, "{name} is in tests/bad but no test names it");
    }
}

#[test]
fn nan_voxels_are_counted_and_treated_as_missing() {
    let Ran {
        ok, stdout, stderr, ..
    } = info(&bad("nan_voxels.nrrd"), &["--json"]);
    assert!(ok, "{stderr}");
    assert!(
        stderr.contains("2 NaN or infinite voxels are treated as missing"),
        "{stderr}"
    );
    let json: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(json["missing"], 2);
    assert_eq!(json["range"], serde_json::json!([1.0, 8.0]));
    assert_eq!(json["mean"], (1.0 + 2.0 + 4.0 + 6.0 + 7.0 + 8.0) / 6.0);
}

#[test]
fn an_all_nan_volume_is_described_but_not_analysed() {
    let Ran {
        ok, stdout, stderr, ..
    } = info(&bad("all_nan.nrrd"), &[]);
    assert!(ok, "{stderr}");
    assert!(
        stdout.contains("range       none: every voxel is NaN or infinite"),
        "{stdout}"
    );
    let out = slabscope()
        .args(["analyze", bad("all_nan.nrrd").to_str().unwrap()])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && out.stdout.is_empty());
    assert!(
        stderr.contains("all_nan.nrrd: all 2 voxels are NaN or infinite: the volume holds no data"),
        "{stderr}"
    );
}

#[test]
fn a_constant_volume_loads_with_a_warning() {
    let Ran { ok, stderr, .. } = info(&bad("constant.nrrd"), &[]);
    assert!(ok, "{stderr}");
    assert!(
        stderr.contains("every voxel is 7: the volume is constant"),
        "{stderr}"
    );
}

#[test]
fn the_memory_limit_is_checked_before_allocating() {
    let path = data("pyvista_channels.nrrd");
    let Ran { ok, stderr, .. } = info(&path, &["--max-memory", "1M"]);
    assert!(!ok);
    assert!(
        stderr.contains("a 250x250x100 u8 volume needs 6.0 MiB"),
        "{stderr}"
    );
    assert!(stderr.contains("raise it with --max-memory"), "{stderr}");
}

#[test]
fn raw_files_without_a_description_ask_for_one() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scan.raw");
    std::fs::write(&path, vec![0u8; 2 * 27]).unwrap();
    let Ran { ok, stderr, .. } = info(&path, &[]);
    assert!(!ok);
    assert!(
        stderr.contains("give --dims NXxNYxNZ and --type"),
        "{stderr}"
    );
    let Ran { ok, stderr, .. } = info(&path, &["--dims", "3x3x3"]);
    assert!(!ok);
    assert!(
        stderr.contains("its size suggests 2 bytes per voxel"),
        "{stderr}"
    );
    let Ran { ok, stderr, .. } = info(&path, &["--dims", "3x3x3", "--type", "u16"]);
    assert!(ok, "{stderr}");
    let Ran { ok, stderr, .. } = info(&path, &["--dims", "3x3x3", "--type", "u32"]);
    assert!(!ok);
    assert!(stderr.contains("expected 108 bytes, found 54"), "{stderr}");
}
