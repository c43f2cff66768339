//! The command line as a user runs it: the JSON contract (`docs/json.md`), exports, overwrite
//! protection and errors.

use serde_json::Value;

use crate::common::{Ran, layers, run, s};

fn json(args: &[&str]) -> Value {
    let Ran {
        ok, stdout, stderr, ..
    } = run(args);
    assert!(ok, "{args:?}: {stderr}");
    serde_json::from_str(&stdout).unwrap()
}

#[test]
fn analyze_json_follows_the_contract() {
    let dir = tempfile::tempdir().unwrap();
    let file = layers(dir.path(), 24);
    let d = json(&["analyze", file.to_str().unwrap(), "--json"]);
    assert_eq!(d["dims"], serde_json::json!([24, 24, 24]));
    assert_eq!(d["params"]["bins"], 32);
    assert_eq!(d["params"]["block"], 3);
    assert_eq!(d["params"]["level"], 1);
    assert_eq!(d["schema_version"], 2);
    assert_eq!(d["params"]["phases"], 8);
    assert_eq!(d["ranked_by"], "phase_mean");
    let views = d["views"].as_array().unwrap();
    assert_eq!(views.len(), 21);
    let means: Vec<f64> = views
        .iter()
        .map(|v| v["phases"]["mean"].as_f64().unwrap())
        .collect();
    assert!(
        means.windows(2).all(|w| w[0] <= w[1]),
        "views sorted by the score the ranking used, lowest first"
    );
    for v in views {
        let p = &v["phases"];
        assert_eq!(p["n"], 8);
        assert!(p["min"].as_f64() <= p["mean"].as_f64() && p["mean"].as_f64() <= p["max"].as_f64());
        assert!(v["entropy_rate"].is_f64() && p["std"].is_f64());
    }
    assert_eq!(d["best_axis"], views[0]["axis"]);
    let contenders = d["contenders"].as_array().unwrap();
    assert_eq!(
        contenders[0]["axis"], d["best_axis"],
        "the best comes first"
    );
    assert_eq!(d["uncertain"], contenders.len() > 1);
    assert!(
        contenders
            .iter()
            .all(|c| c["mean"].is_f64() && c["se"].is_f64())
    );
    assert_eq!(d["background"]["mode"], "auto");
    assert!(d["background"]["fraction"].is_f64());
    // The paper's method: one lattice, every voxel.
    let paper = json(&[
        "analyze",
        file.to_str().unwrap(),
        "--json",
        "--phases",
        "0",
        "--background",
        "none",
    ]);
    assert_eq!(paper["ranked_by"], "paper_lattice");
    assert!(paper["uncertain"].is_null() && paper["contenders"].is_null());
    assert!(paper["background"].is_null());
    let rates: Vec<f64> = paper["views"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v["entropy_rate"].as_f64().unwrap())
        .collect();
    assert!(rates.windows(2).all(|w| w[0] <= w[1]), "by the paper's h");
    let p = &d["partition"];
    assert_eq!(p["method"], "topdown");
    assert_eq!(p["axis"], d["best_axis"]);
    let slabs = p["slabs"].as_array().unwrap();
    assert_eq!(slabs.len(), 4, "four slabs by default");
    assert_eq!(slabs[0][0], 0);
    assert_eq!(slabs[3][1], p["slices"]);
    for w in slabs.windows(2) {
        assert_eq!(w[0][1], w[1][0], "slabs are contiguous");
    }
    let steps = p["steps"].as_array().unwrap();
    assert_eq!(steps.len(), 3);
    assert!(steps[0]["split"].is_array() && steps[0]["at"].is_u64() && steps[0]["gain"].is_f64());
}

#[test]
fn a_named_axis_skips_the_view_search_unless_asked() {
    let dir = tempfile::tempdir().unwrap();
    let file = layers(dir.path(), 24);
    let f = file.to_str().unwrap();
    let d = json(&[
        "analyze", f, "--axis", "z", "--method", "bottomup", "--slabs", "3", "--json",
    ]);
    assert!(d["best_axis"].is_null());
    assert!(d.get("views").is_none());
    let p = &d["partition"];
    assert_eq!(p["axis"], serde_json::json!([0.0, 0.0, 1.0]));
    let steps = p["steps"].as_array().unwrap();
    assert_eq!(steps.len(), 21, "24 slices merged down to 3");
    let m = &steps[0]["merge"];
    assert_eq!(m[0][1], m[1][0], "a merge joins adjacent slabs");
    assert!(steps[0]["nmi"].as_f64().unwrap() <= 1.0);
    let d = json(&[
        "analyze", f, "--axis", "0,0,-2", "--views", "--method", "optimal", "--json",
    ]);
    assert_eq!(d["views"].as_array().unwrap().len(), 21);
    assert_eq!(
        d["partition"]["axis"],
        serde_json::json!([0.0, 0.0, 1.0]),
        "made canonical"
    );
    assert_eq!(d["partition"]["steps"].as_array().unwrap().len(), 0);
}

#[test]
fn thresholds_stop_the_methods() {
    let dir = tempfile::tempdir().unwrap();
    let file = layers(dir.path(), 24);
    let f = file.to_str().unwrap();
    let d = json(&[
        "analyze",
        f,
        "--axis",
        "1,1,1",
        "--threshold",
        "0.01",
        "--json",
    ]);
    for s in d["partition"]["steps"].as_array().unwrap() {
        assert!(s["gain"].as_f64().unwrap() >= 0.01);
    }
    let Ran { ok, stderr, .. } = run(&["analyze", f, "--slabs", "3", "--threshold", "0.1"]);
    assert!(!ok && stderr.contains("cannot be used with"), "{stderr}");
}

#[test]
fn exports_are_written_and_never_overwritten_unasked() {
    let dir = tempfile::tempdir().unwrap();
    let file = layers(dir.path(), 24);
    let labels = dir.path().join("labels.nrrd");
    let slabs = dir.path().join("slabs.json");
    let curves = dir.path().join("curves.csv");
    let args = [
        "analyze",
        file.to_str().unwrap(),
        "--axis",
        "z",
        "--slabs",
        "3",
        "--export-labels",
        labels.to_str().unwrap(),
        "--export-slabs",
        slabs.to_str().unwrap(),
        "--curves",
        curves.to_str().unwrap(),
    ];
    let Ran { ok, stderr, .. } = run(&args);
    assert!(ok, "{stderr}");
    let info = json(&["info", labels.to_str().unwrap(), "--json"]);
    assert_eq!(info["dims"], serde_json::json!([24, 24, 24]));
    assert_eq!(info["type"], "u8");
    // Slab index + 1: no voxel of these layers is background, so no 0.
    assert_eq!(info["range"], serde_json::json!([1.0, 3.0]));
    let s: Value = serde_json::from_str(&std::fs::read_to_string(&slabs).unwrap()).unwrap();
    assert_eq!(s["slabs"].as_array().unwrap().len(), 3);
    assert_eq!(s["slabs"][0]["fraction"][0], 0.0);
    assert_eq!(s["slabs"][2]["fraction"][1], 1.0);
    let csv = std::fs::read_to_string(&curves).unwrap();
    assert!(csv.starts_with("cut,mm,world_mm,nmi,gain\n"));
    assert_eq!(csv.lines().count(), 24, "a header and 23 cuts");

    let before = std::fs::read(&slabs).unwrap();
    let Ran {
        ok, stdout, stderr, ..
    } = run(&args);
    assert!(!ok && stderr.contains("already exists"), "{stderr}");
    assert!(stdout.is_empty());
    assert_eq!(std::fs::read(&slabs).unwrap(), before);
    let mut forced = args.to_vec();
    forced.push("--force");
    let Ran { ok, stderr, .. } = run(&forced);
    assert!(ok, "{stderr}");
}

/// The labels of an analysis of a coarser level lie over every voxel of the volume, at its
/// shape, and the body's air around it is 0.
#[test]
fn labels_of_a_coarser_level_are_at_the_volumes_shape() {
    let dir = tempfile::tempdir().unwrap();
    let body = dir.path().join("body.nrrd");
    let labels = dir.path().join("labels.nii");
    let (b, l) = (body.to_str().unwrap(), labels.to_str().unwrap());
    let made = run(&["phantom", "body", "-o", b, "--dims", "24x24x40"]);
    assert!(made.ok, "{}", made.stderr);
    let args = [
        "analyze",
        b,
        "--resolution",
        "1",
        "--slabs",
        "3",
        "--export-labels",
        l,
    ];
    let Ran { ok, stderr, .. } = run(&args);
    assert!(ok, "{stderr}");
    let info = json(&["info", l, "--json"]);
    assert_eq!(info["dims"], serde_json::json!([24, 24, 40]));
    assert_eq!(info["range"], serde_json::json!([0.0, 3.0]));
}

/// Under a budget below the background's mask (a bit a voxel, 48 KiB here) beside what the
/// analysis holds, `--export-labels` still writes the labels, the mask held in an unnamed scratch
/// file: byte for byte those written with room to spare, and nothing else left in the folder.
#[test]
fn labels_are_written_under_a_budget_below_the_background_mask() {
    let dir = tempfile::tempdir().unwrap();
    let nii = dir.path().join("body.nii");
    let Ran { ok, stderr, .. } = run(&["phantom", "body", "--dims", "64x64x96", "-o", s(&nii)]);
    assert!(ok, "{stderr}");
    let (tight, roomy) = (dir.path().join("tight.nrrd"), dir.path().join("roomy.nrrd"));
    let export = |out: &std::path::Path, extra: &[&str]| {
        let mut args = vec![
            "analyze",
            s(&nii),
            "--axis",
            "z",
            "--slabs",
            "3",
            "--json",
            "--export-labels",
            s(out),
        ];
        args.extend_from_slice(extra);
        json(&args)
    };
    // 60 KiB: the analysis of level 2 (16×16×24) fits, but not its level, the 48 KiB mask of
    // the 64×64×96 voxels and a 4 KiB plane of labels together.
    let report = export(&tight, &["--max-memory", "60K"]);
    assert_eq!(report["resolution"]["pyramid_level"], 2, "{report}");
    export(&roomy, &["--resolution", "2"]);
    let (a, b) = (
        std::fs::read(&tight).unwrap(),
        std::fs::read(&roomy).unwrap(),
    );
    assert!(a == b, "the same labels");
    let info = json(&["info", s(&tight), "--json"]);
    assert_eq!(info["dims"], serde_json::json!([64, 64, 96]));
    assert_eq!(info["range"], serde_json::json!([0.0, 3.0]));
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 3);
}

/// `--threads` bounds the work without changing an answer; 0 threads is refused by name.
#[test]
fn threads_change_no_answer() {
    let dir = tempfile::tempdir().unwrap();
    let file = layers(dir.path(), 24);
    let f = file.to_str().unwrap();
    let all = json(&["analyze", f, "--slabs", "3", "--json"]);
    let one = json(&["analyze", f, "--slabs", "3", "--json", "--threads", "1"]);
    assert_eq!(all, one);
    let Ran { ok, stderr, .. } = run(&["analyze", f, "--threads", "0"]);
    assert!(!ok && stderr.contains("--threads"), "{stderr}");
}

#[test]
fn phantoms_are_deterministic_and_protected() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.nrrd");
    let b = dir.path().join("b.nrrd");
    for p in [&a, &b] {
        let Ran { ok, stderr, .. } = run(&[
            "phantom",
            "body",
            "-o",
            p.to_str().unwrap(),
            "--dims",
            "20x20x30",
            "--seed",
            "7",
        ]);
        assert!(ok, "{stderr}");
    }
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    let Ran { ok, stderr, .. } = run(&["phantom", "body", "-o", a.to_str().unwrap()]);
    assert!(!ok && stderr.contains("already exists"), "{stderr}");
    let info = json(&["info", a.to_str().unwrap(), "--json"]);
    assert_eq!(info["type"], "i16");
    assert_eq!(info["format"], "nrrd");
    // The extension names the format.
    let nii = dir.path().join("c.nii");
    let Ran { ok, stderr, .. } = run(&["phantom", "body", "--size", "8", "-o", s(&nii)]);
    assert!(ok, "{stderr}");
    assert_eq!(json(&["info", s(&nii), "--json"])["format"], "nifti");
    let Ran { ok, stderr, .. } = run(&[
        "phantom",
        "body",
        "--raw",
        "-o",
        s(&dir.path().join("d.nii.gz")),
    ]);
    assert!(!ok && stderr.contains("--raw is for .nrrd"), "{stderr}");
    // Made and written a chunk at a time: a phantom is never held whole, and one larger than
    // the disk (512 TiB of i16) is refused before a byte is written, in one line naming it.
    for (name, raw) in [("huge.nii", None), ("huge.nrrd", Some("--raw"))] {
        let huge = dir.path().join(name);
        let mut args = vec!["phantom", "body", "--size", "65536", "-o", s(&huge)];
        args.extend(raw);
        let Ran { ok, stderr, .. } = run(&args);
        assert!(!ok, "{stderr}");
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        assert!(
            stderr.contains(s(&huge)) && stderr.contains("of disk"),
            "{stderr}"
        );
    }
    let mut left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    left.sort();
    assert_eq!(
        left,
        ["a.nrrd", "b.nrrd", "c.nii"],
        "nothing else left behind"
    );
}

#[test]
fn analysis_errors_are_clear() {
    let dir = tempfile::tempdir().unwrap();
    let constant = dir.path().join("constant.nrrd");
    std::fs::write(&constant, b"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n\n\x05\x05\x05\x05\x05\x05\x05\x05")
        .unwrap();
    let Ran {
        ok, stdout, stderr, ..
    } = run(&["analyze", constant.to_str().unwrap()]);
    assert!(!ok && stdout.is_empty());
    assert!(
        stderr.contains("constant.nrrd: the volume is constant (every voxel is 5)"),
        "{stderr}"
    );
    let file = layers(dir.path(), 24);
    let f = file.to_str().unwrap();
    for (args, phrase) in [
        (
            vec!["analyze", f, "--axis", "z", "--slabs", "0"],
            "--slabs 0: expected between 1 and the 24 slices",
        ),
        (
            vec!["analyze", f, "--axis", "0,0,0"],
            "is not best, x, y, z, axial, coronal, sagittal or a direction",
        ),
        (
            vec!["analyze", f, "--axis", "axial"],
            "--axis axial: expected x, y, z or a direction, since the file states no orientation",
        ),
        (
            vec!["analyze", f, "--export-labels", "labels.vtk"],
            "labels.vtk: unsupported: volumes are written as .nrrd, .nii or .nii.gz",
        ),
        (
            vec!["render", f, "-o", "view.bmp"],
            "view.bmp: unsupported: pictures are written as .png, .jpg or .jpeg",
        ),
        (vec!["analyze", f, "--bins", "300"], "300 is not in 2..=255"),
        (vec!["analyze", f, "--level", "9"], "9 is not in 0..=4"),
    ] {
        let Ran {
            ok, stdout, stderr, ..
        } = run(&args);
        assert!(!ok && stdout.is_empty(), "{args:?}");
        assert!(stderr.contains(phrase), "{args:?}: {stderr}");
    }
}

#[test]
fn render_writes_a_png_of_the_asked_size() {
    let dir = tempfile::tempdir().unwrap();
    let file = layers(dir.path(), 24);
    let out = dir.path().join("view.png");
    let f = file.to_str().unwrap();
    let o = out.to_str().unwrap();
    let Ran { ok, stderr, .. } = run(&[
        "render", f, "-o", o, "--size", "120x90", "--axis", "z", "--slabs", "3", "--mode", "mip",
    ]);
    assert!(ok, "{stderr}");
    let png = tiny_skia::Pixmap::load_png(&out).unwrap();
    assert_eq!((png.width(), png.height()), (120, 90));
    // A .jpg name gets a JPEG, not PNG bytes under a JPEG name.
    let jpeg = dir.path().join("view.JPG");
    let Ran { ok, stderr, .. } = run(&[
        "render",
        f,
        "-o",
        jpeg.to_str().unwrap(),
        "--size",
        "120x90",
        "--axis",
        "z",
    ]);
    assert!(ok, "{stderr}");
    let bytes = std::fs::read(&jpeg).unwrap();
    assert_eq!(&bytes[..3], &[0xff, 0xd8, 0xff]);
    let decoded = image::load_from_memory_with_format(&bytes, image::ImageFormat::Jpeg).unwrap();
    assert_eq!((decoded.width(), decoded.height()), (120, 90));
    let Ran { ok, stderr, .. } = run(&["render", f, "-o", o, "--size", "120x90", "--axis", "z"]);
    assert!(!ok && stderr.contains("already exists"), "{stderr}");
    let Ran { ok, stderr, .. } = run(&[
        "render",
        f,
        "-o",
        o,
        "--force",
        "--axis",
        "z",
        "--slabs",
        "2",
        "--highlight",
        "5",
    ]);
    assert!(
        !ok && stderr.contains("--highlight 5: there are only 2 slabs"),
        "{stderr}"
    );
    let Ran { ok, stderr, .. } = run(&["render", f, "-o", o, "--force", "--size", "0x5"]);
    assert!(!ok && stderr.contains("is not a size"), "{stderr}");
}

#[test]
fn preview_without_a_terminal_says_to_render_to_a_file() {
    let dir = tempfile::tempdir().unwrap();
    let file = layers(dir.path(), 24);
    let Ran {
        ok, stdout, stderr, ..
    } = run(&[
        "preview",
        file.to_str().unwrap(),
        "--axis",
        "z",
        "--protocol",
        "blocks",
    ]);
    assert!(
        !ok && stdout.is_empty(),
        "no query codes or picture in a file"
    );
    assert!(
        stderr.contains("not a terminal") && stderr.contains("slabscope render FILE -o OUT.png"),
        "{stderr}"
    );
}

#[test]
fn a_reader_that_goes_away_ends_slabscope_quietly() {
    // `slabscope analyze F | head -1`: the pipe is closed before the report is written.
    let dir = tempfile::tempdir().unwrap();
    let path = layers(dir.path(), 24);
    let mut child = crate::common::slabscope()
        .args(["analyze", path.to_str().unwrap()])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{:?}: {stderr}", out.status);
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn slice_writes_one_slice_and_render_faces_a_strip() {
    let dir = tempfile::tempdir().unwrap();
    let file = layers(dir.path(), 24);
    let f = file.to_str().unwrap();
    let out = dir.path().join("slice.png");
    let o = out.to_str().unwrap();
    // The 24-voxel cube, fit into 200x100: 100x100.
    let Ran {
        ok, stdout, stderr, ..
    } = run(&[
        "slice", f, "--axis", "z", "--index", "3", "--size", "200x100", "-o", o,
    ]);
    assert!(ok && stdout.is_empty(), "{stderr}");
    let png = tiny_skia::Pixmap::load_png(&out).unwrap();
    assert_eq!((png.width(), png.height()), (100, 100));
    let Ran { ok, stderr, .. } = run(&[
        "slice", f, "--axis", "z", "--index", "24", "-o", o, "--force",
    ]);
    assert!(!ok, "past the last slice");
    assert!(
        stderr.contains(
            "--index 24: expected a slice from 0 to 23 (there are 24 slices along this axis)"
        ),
        "{stderr}"
    );
    let Ran { ok, stderr, .. } = run(&["slice", f, "--axis", "z", "-o", o]);
    assert!(!ok && stderr.contains("already exists"), "{stderr}");
    // A volume of 3 slices has a middle slice, though not the 4 slabs a partition would ask.
    let thin = dir.path().join("thin.nrrd");
    let Ran { ok, stderr, .. } = run(&[
        "phantom",
        "layers",
        "-o",
        thin.to_str().unwrap(),
        "--dims",
        "16x16x3",
    ]);
    assert!(ok, "{stderr}");
    let Ran { ok, stderr, .. } = run(&["slice", thin.to_str().unwrap(), "-o", o, "--force"]);
    assert!(ok, "{stderr}");
    let strip = dir.path().join("faces.png");
    let Ran { ok, stderr, .. } = run(&[
        "render",
        f,
        "--faces",
        "--axis",
        "z",
        "--slabs",
        "3",
        "--size",
        "400x200",
        "-o",
        strip.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    let png = tiny_skia::Pixmap::load_png(&strip).unwrap();
    // Three columns of tiles fit into 400x200, and two rows of them.
    assert!(png.width() <= 400 && png.width() > 300, "{}", png.width());
    assert!(
        png.height() <= 200 && png.height() > 150,
        "{}",
        png.height()
    );
}

#[test]
fn a_mapped_volume_beyond_the_budget_is_analysed_on_the_finest_level_that_fits() {
    let dir = tempfile::tempdir().unwrap();
    // 64x64x96 i16, uncompressed: mapped. Its analysis at full resolution needs a byte and a
    // quarter a voxel for the slice stack and background (480 KiB) and 576 bytes a slice of the
    // longest stack (133 slices: 75 KiB); level 1 (32x32x48 f32 and its cell map, 67 slices)
    // 290 KiB.
    let nii = dir.path().join("body.nii");
    let Ran { ok, stderr, .. } = run(&["phantom", "body", "--dims", "64x64x96", "-o", s(&nii)]);
    assert!(ok, "{stderr}");
    let analyze = |extra: &[&str]| {
        let mut args = vec!["analyze", s(&nii), "--json", "--axis", "z"];
        args.extend_from_slice(extra);
        json(&args)
    };
    let tight = analyze(&["--max-memory", "300K"]);
    assert_eq!(tight["resolution"]["pyramid_level"], 1, "{tight}");
    let notes = tight["notes"].to_string();
    assert!(
        notes.contains("over the memory limit of 300.0 KiB"),
        "{notes}"
    );
    // The same answer as asking for level 1.
    let level1 = analyze(&["--resolution", "1"]);
    assert_eq!(tight["partition"]["slabs"], level1["partition"]["slabs"]);
    // With room, full resolution.
    assert_eq!(
        analyze(&["--max-memory", "560K"])["resolution"]["pyramid_level"],
        0
    );
    // Loading the mapped file is within any budget; a compressed copy is decoded into memory,
    // and that is refused, unless a scratch folder is given to decode it into.
    assert_eq!(
        json(&["info", s(&nii), "--json", "--max-memory", "1K"])["dims"][2],
        96
    );
    let gz = dir.path().join("body.nii.gz");
    let Ran { ok, .. } = run(&["phantom", "body", "--dims", "64x64x96", "-o", s(&gz)]);
    assert!(ok);
    let Ran { ok, stderr, .. } = run(&["info", s(&gz), "--max-memory", "100K"]);
    assert!(
        !ok && stderr
            .contains("(raise it with --max-memory, or decode it to disk with --scratch DIR)"),
        "{stderr}"
    );
}

/// A compressed volume beyond the budget, given a scratch folder, is decoded into it and then
/// read as the uncompressed file is: the same answers, and nothing left in the folder.
#[test]
fn a_compressed_volume_beyond_the_budget_is_decoded_into_the_scratch_folder() {
    let dir = tempfile::tempdir().unwrap();
    let (nii, gz) = (dir.path().join("body.nii"), dir.path().join("body.nii.gz"));
    for out in [&nii, &gz] {
        let Ran { ok, .. } = run(&["phantom", "body", "--dims", "64x64x96", "-o", s(out)]);
        assert!(ok);
    }
    let scratch = dir.path().join("scratch");
    std::fs::create_dir(&scratch).unwrap();
    let Ran {
        ok, stdout, stderr, ..
    } = run(&[
        "info",
        s(&gz),
        "--max-memory",
        "100K",
        "--scratch",
        s(&scratch),
    ]);
    assert!(ok, "{stderr}");
    assert!(
        stdout.contains(
            "memory      none: 768.0 KiB (786432 bytes) of i16 decoded into a scratch file on disk"
        ),
        "{stdout}"
    );
    assert!(
        stderr.contains("an unnamed scratch file of 768.0 KiB (786432 bytes) on disk"),
        "{stderr}"
    );
    let info = json(&[
        "info",
        s(&gz),
        "--json",
        "--max-memory",
        "100K",
        "--scratch",
        s(&scratch),
    ]);
    assert_eq!(
        (
            &info["scratch_bytes"],
            &info["mapped_bytes"],
            &info["memory_bytes"]
        ),
        (
            &Value::from(786_432),
            &Value::from(786_432),
            &Value::from(0)
        )
    );
    // The scratch file has no name: nothing is left in the folder.
    assert_eq!(std::fs::read_dir(&scratch).unwrap().count(), 0);
    // Decoded to disk, the volume is a mapped one: the same answers as the uncompressed file's,
    // on the level that fits and on every voxel.
    let of = |file: &std::path::Path, extra: &[&str]| {
        let mut args = vec![
            "analyze",
            s(file),
            "--json",
            "--axis",
            "z",
            "--max-memory",
            "300K",
        ];
        args.extend_from_slice(extra);
        let mut report = json(&args);
        report["file"] = serde_json::Value::Null;
        report
    };
    for extra in [&[][..], &["--resolution", "full"][..]] {
        let mapped = of(&nii, extra);
        let decoded = of(&gz, &[&["--scratch", s(&scratch)][..], extra].concat());
        assert_eq!(mapped, decoded);
    }
}

/// A compressed stream too short to hold the volume its header claims is refused before any room
/// is reserved for it in the scratch folder; a folder that is not one is refused as a flag.
#[test]
fn a_scratch_folder_is_not_filled_by_a_header_that_lies() {
    use std::io::Write;
    let dir = tempfile::tempdir().unwrap();
    let nii = dir.path().join("small.nii");
    let Ran { ok, .. } = run(&["phantom", "body", "--dims", "16x16x16", "-o", s(&nii)]);
    assert!(ok);
    let mut bytes = std::fs::read(&nii).unwrap();
    // dim[1..3] (i16 at bytes 42, 44, 46): 20000³ i16, 16 TB.
    for at in [42, 44, 46] {
        bytes[at..at + 2].copy_from_slice(&20000i16.to_le_bytes());
    }
    let gz = dir.path().join("liar.nii.gz");
    let mut encoder = flate2::write::GzEncoder::new(
        std::fs::File::create(&gz).unwrap(),
        flate2::Compression::fast(),
    );
    encoder.write_all(&bytes).unwrap();
    encoder.finish().unwrap();
    let scratch = dir.path().join("scratch");
    std::fs::create_dir(&scratch).unwrap();
    let Ran { ok, stderr, .. } = run(&[
        "info",
        s(&gz),
        "--max-memory",
        "1M",
        "--scratch",
        s(&scratch),
    ]);
    assert!(!ok);
    assert!(
        stderr.contains("bytes of compressed data cannot hold the 16000000000000 bytes of a 20000x20000x20000 i16 volume"),
        "{stderr}"
    );
    let Ran { ok, stderr, .. } = run(&["info", s(&nii), "--scratch", s(&nii)]);
    assert!(!ok);
    assert!(
        stderr.ends_with(&format!(
            "--scratch {}: expected an existing folder\n",
            s(&nii)
        )),
        "{stderr}"
    );
}

/// `--timeout` stops `analyze` and `render` with an error that says so, and a view search far
/// heavier than the default's is announced on stderr before it starts (the default is not).
#[test]
fn a_timeout_stops_the_work_and_a_heavy_request_is_announced() {
    let dir = tempfile::tempdir().unwrap();
    let file = layers(dir.path(), 64);
    let heavy = [
        "--level",
        "4",
        "--phases",
        "64",
        "--refine",
        "--timeout",
        "0.3",
    ];
    let ran = run(&[&["analyze", s(&file)][..], &heavy[..]].concat());
    assert_eq!(ran.code, 1, "{}", ran.stderr);
    assert!(
        ran.stderr
            .contains("times the default's work (icosphere level 4, 64 phases"),
        "{}",
        ran.stderr
    );
    assert!(
        ran.stderr.contains("stopped at the --timeout of 0.3 s"),
        "{}",
        ran.stderr
    );
    assert!(ran.stdout.is_empty());
    let png = dir.path().join("x.png");
    let ran = run(&[&["render", s(&file), "-o", s(&png)][..], &heavy[..]].concat());
    assert!(
        ran.stderr.contains("stopped at the --timeout"),
        "{}",
        ran.stderr
    );
    assert!(!png.exists(), "nothing written when stopped");
    let plain = run(&["analyze", s(&file), "--timeout", "600"]);
    assert!(plain.ok, "{}", plain.stderr);
    assert!(!plain.stderr.contains("default's work"), "{}", plain.stderr);
}

/// A write stages its output as `.NAME.slabscope-PID-XXXXXX.tmp` beside it, and removes the
/// staging files of the same target that a killed run (a process that no longer runs) left;
/// a running process's, and other targets', stay.
#[cfg(target_os = "linux")]
#[test]
fn a_killed_runs_staging_files_are_removed_by_the_next_write() {
    let dir = tempfile::tempdir().unwrap();
    let stale = dir.path().join(".out.nrrd.slabscope-4194305-a1b2c3.tmp");
    let live = dir.path().join(format!(
        ".out.nrrd.slabscope-{}-d4e5f6.tmp",
        std::process::id()
    ));
    let other = dir.path().join(".other.nrrd.slabscope-4194305-g7h8i9.tmp");
    for f in [&stale, &live, &other] {
        std::fs::write(f, b"partial").unwrap();
    }
    let out = dir.path().join("out.nrrd");
    let ran = run(&["phantom", "layers", "--size", "8", "-o", s(&out)]);
    assert!(ran.ok, "{}", ran.stderr);
    assert!(out.exists());
    assert!(!stale.exists(), "the killed run's staging file is gone");
    assert!(live.exists() && other.exists());
    let mut names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names.len(), 3, "nothing else left: {names:?}");
}
