//! World coordinates: fixtures written by nibabel, pynrrd and `SimpleITK` (`tests/data/orientation`,
//! with the script that made them) read as those libraries read them; axes named by anatomy;
//! slab positions in world millimetres; label exports that keep the source's geometry.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;
use slabscope::formats::write_volume;
use slabscope::geometry::{AxisChoice, WorldTransform};
use slabscope::partition::{Method, PartitionParams, Stop, partition};
use slabscope::{AnalysisParams, LoadOptions, Monitor, Volume, analyze, label_volume, load};

use crate::common::data;

fn fixtures() -> PathBuf {
    data("orientation")
}

/// Per fixture: the affine its writer's library reads back (null for none) and its codes.
fn expected() -> serde_json::Map<String, Value> {
    let text = std::fs::read_to_string(fixtures().join("expected.json")).unwrap();
    serde_json::from_str::<Value>(&text)
        .unwrap()
        .as_object()
        .unwrap()
        .clone()
}

fn read(path: &Path) -> Volume {
    load(path, &LoadOptions::default()).unwrap().volume
}

fn matrix(v: &Value) -> [[f64; 4]; 4] {
    std::array::from_fn(|r| std::array::from_fn(|c| v[r][c].as_f64().unwrap()))
}

/// Equal to 1e-5, relative to the larger of 1 and the entry.
fn assert_affine(what: &str, got: &[[f64; 4]; 4], want: &[[f64; 4]; 4]) {
    for r in 0..4 {
        for c in 0..4 {
            let tolerance = 1e-5 * want[r][c].abs().max(1.0);
            assert!(
                (got[r][c] - want[r][c]).abs() <= tolerance,
                "{what}: entry ({r}, {c}) is {}, expected {}\n{got:?}",
                got[r][c],
                want[r][c]
            );
        }
    }
}

/// A fixture's transform checked against what its writer reads back.
fn assert_as_written(name: &str, t: &WorldTransform, spacing: [f64; 3], entry: &Value) {
    if entry["affine"].is_null() {
        assert!(!t.known, "{name}");
        assert_eq!(t.axcodes(), None, "{name}");
        assert_affine(name, &t.matrix, &WorldTransform::unknown(spacing).matrix);
    } else {
        assert!(t.known, "{name}");
        assert_affine(name, &t.matrix, &matrix(&entry["affine"]));
        assert_eq!(
            t.axcodes().as_deref(),
            entry["orientation"].as_str(),
            "{name}"
        );
    }
}

#[test]
fn fixtures_read_as_their_writers_read_them() {
    let expected = expected();
    assert_eq!(expected.len(), 9, "every fixture has an expectation");
    for (name, entry) in &expected {
        let v = read(&fixtures().join(name));
        assert_as_written(name, v.transform(), v.spacing(), entry);
        assert_eq!(
            v.transform().is_orthogonal(),
            name != "sheared.nii.gz",
            "{name}"
        );
    }
}

#[test]
fn axes_are_named_by_anatomy() {
    // lsa: x to the left, y to the superior, z to the anterior (1.5 mm), origin y = -60.
    let v = read(&fixtures().join("lsa.nii.gz"));
    let t = v.transform();
    let s = v.spacing();
    let name = |d: [f64; 3]| t.describe(d, s).anatomy.unwrap();
    assert_eq!(name([1.0, 0.0, 0.0]), "R→L, sagittal");
    assert_eq!(name([0.0, 1.0, 0.0]), "I→S, axial");
    assert_eq!(name([0.0, 0.0, 1.0]), "P→A, coronal");
    // 45° between two world axes is no anatomical plane, but still a world direction.
    let oblique = t.describe([0.0, 1.0, 1.0], s);
    assert_eq!(oblique.anatomy, None);
    let n = oblique.world_axis;
    assert!((n[0]).abs() < 1e-12 && (n[1] - n[2]).abs() < 1e-6, "{n:?}");
    for (choice, axis) in [
        ("axial", [0.0, 1.0, 0.0]),
        ("coronal", [0.0, 0.0, 1.0]),
        ("sagittal", [1.0, 0.0, 0.0]),
    ] {
        let c: AxisChoice = choice.parse().unwrap();
        assert_eq!(
            c.resolve(v.transform(), v.spacing())
                .unwrap()
                .unwrap()
                .direction(),
            axis,
            "{choice}"
        );
    }
    let unknown = read(&fixtures().join("no_orientation.nii"));
    let axial: AxisChoice = "axial".parse().unwrap();
    let e = axial
        .resolve(unknown.transform(), unknown.spacing())
        .unwrap_err()
        .to_string();
    assert!(e.contains("the file states no orientation"), "{e}");
    assert_eq!(
        unknown
            .transform()
            .describe([0.0, 0.0, 1.0], unknown.spacing())
            .anatomy,
        None
    );
}

#[test]
fn a_sheared_axis_is_named_by_its_planes_normal() {
    // k steps up 1.2 mm and forward 0.4 mm: the planes k = const are still z = const.
    let v = read(&fixtures().join("sheared.nii.gz"));
    let w = v.transform().describe([0.0, 0.0, 1.0], v.spacing());
    assert_eq!(w.anatomy.as_deref(), Some("I→S, axial"));
    let n = w.world_axis;
    assert!(
        n[0].abs() < 1e-9 && n[1].abs() < 1e-9 && (n[2] - 1.0).abs() < 1e-9,
        "{n:?}"
    );
}

#[test]
fn slab_bounds_are_in_world_millimetres() {
    let v = read(&fixtures().join("lsa.nii.gz"));
    let params = PartitionParams {
        method: Method::TopDown,
        stop: Stop::Slabs(2),
        ..PartitionParams::paper()
    };
    // Along z, 1.5 mm a slice, to the anterior from y = -60 mm.
    let p = partition(&v, [0.0, 0.0, 1.0], &params, &Monitor::none()).unwrap();
    assert_eq!(p.world.anatomy.as_deref(), Some("P→A, coronal"));
    let first = &p.info[0];
    let last = p.info.last().unwrap();
    assert_eq!(first.mm.0, -0.75);
    assert!(
        (first.world_mm.0 - -60.75).abs() < 1e-9,
        "{:?}",
        first.world_mm
    );
    assert!(
        (last.world_mm.1 - (-60.0 + 6.5 * 1.5)).abs() < 1e-9,
        "{:?}",
        last.world_mm
    );
    for s in &p.info {
        let (a, b) = s.mm;
        assert!((s.world_mm.1 - s.world_mm.0 - (b - a)).abs() < 1e-9);
    }
    // Without an orientation the world is the volume's own millimetres.
    let u = read(&fixtures().join("no_orientation.nii"));
    let q = partition(&u, [0.0, 0.0, 1.0], &params, &Monitor::none()).unwrap();
    assert!(q.info.iter().all(|s| s.world_mm == s.mm));
    assert_eq!(q.world.world_axis, [0.0, 0.0, 1.0]);
}

/// The labels of a two-slab partition of `name` written as `ext` in `dir`.
fn export(dir: &Path, name: &str, ext: &str) -> (Volume, PathBuf) {
    let v = read(&fixtures().join(name));
    let params = AnalysisParams {
        axis: AxisChoice::Along(slabscope::Axis::Z),
        stop: Stop::Slabs(2),
        ..AnalysisParams::default()
    };
    let a = analyze(&v, &params, &Monitor::none()).unwrap();
    let labels = label_volume(&v, &v, &a.partition, &Monitor::none()).unwrap();
    let stem = name.split('.').next().unwrap();
    let out = dir.join(format!("{stem}-labels.{ext}"));
    write_volume(&out, &labels, false).unwrap();
    (v, out)
}

const EXPORTS: [&str; 3] = ["nrrd", "nii", "nii.gz"];

#[test]
fn exported_labels_keep_the_source_geometry() {
    let dir = tempfile::tempdir().unwrap();
    for (name, entry) in &expected() {
        for ext in EXPORTS {
            let (source, out) = export(dir.path(), name, ext);
            let back = read(&out);
            let what = format!("{name} as .{ext}");
            assert_eq!(back.dims(), source.dims(), "{what}");
            assert_as_written(&what, back.transform(), source.spacing(), entry);
        }
    }
}

#[test]
fn the_nifti_qform_agrees_with_the_sform() {
    // With the sform's code cleared, a reader falls back on the qform: it must place the
    // labels alike (to the precision of f32), and be absent under shear.
    let dir = tempfile::tempdir().unwrap();
    for (name, entry) in &expected() {
        let (source, out) = export(dir.path(), name, "nii");
        let mut bytes = std::fs::read(&out).unwrap();
        assert_eq!(&bytes[344..348], b"n+1\0");
        let qform_code = i16::from_le_bytes([bytes[252], bytes[253]]);
        let sform_code = i16::from_le_bytes([bytes[254], bytes[255]]);
        let known = entry["affine"].is_array();
        let sheared = name == "sheared.nii.gz";
        assert_eq!(sform_code, i16::from(known), "{name}");
        assert_eq!(qform_code, i16::from(known && !sheared), "{name}");
        bytes[254..256].copy_from_slice(&0i16.to_le_bytes());
        let qform = dir.path().join("qform.nii");
        std::fs::write(&qform, &bytes).unwrap();
        let back = read(&qform);
        if known && !sheared {
            assert_as_written(
                &format!("{name} qform"),
                back.transform(),
                source.spacing(),
                entry,
            );
        } else {
            assert!(!back.transform().known, "{name}");
        }
        std::fs::remove_file(&qform).unwrap();
    }
}

#[test]
fn exports_read_back_in_nibabel_and_simpleitk() {
    let probe = Command::new("python3")
        .args(["-c", "import nibabel, nrrd, SimpleITK, numpy"])
        .output();
    if !probe.is_ok_and(|o| o.status.success()) {
        assert!(
            std::env::var_os("SLABSCOPE_REQUIRE_PYTHON").is_none(),
            "SLABSCOPE_REQUIRE_PYTHON is set, but python3 with nibabel, pynrrd and SimpleITK is not there"
        );
        eprintln!(
            "skipped: needs python3 with nibabel, pynrrd and SimpleITK \
             (pip install numpy nibabel pynrrd SimpleITK; .ci/run installs them)"
        );
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let expected = expected();
    let mut files = Vec::new();
    for (name, entry) in &expected {
        if entry["affine"].is_null() {
            continue;
        }
        for ext in EXPORTS {
            files.push((name.clone(), export(dir.path(), name, ext).1));
        }
    }
    let out = Command::new("python3")
        .arg(fixtures().join("make.py"))
        .arg("read")
        .args(files.iter().map(|f| &f.1))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let seen: Value = serde_json::from_slice(&out.stdout).unwrap();
    for (name, file) in &files {
        let want = matrix(&expected[name]["affine"]);
        let entry = &seen[file.file_name().unwrap().to_str().unwrap()];
        let what = |reader: &str| format!("{} read by {reader}", file.display());
        if let Some(a) = entry.get("nibabel") {
            assert_affine(&what("nibabel"), &matrix(a), &want);
        }
        if let Some(a) = entry.get("pynrrd") {
            assert_affine(&what("pynrrd"), &matrix(a), &want);
        }
        // ITK's NIfTI reader refuses shear ("ITK only supports orthonormal direction
        // cosines"), for the source as for the export; its NRRD reader keeps it.
        match entry.get("sitk") {
            Some(a) => assert_affine(&what("SimpleITK"), &matrix(a), &want),
            None => assert!(
                name == "sheared.nii.gz" && file.extension().is_some_and(|e| e != "nrrd"),
                "{}: {}",
                what("SimpleITK"),
                entry["sitk_error"]
            ),
        }
        if let Some(q) = entry.get("qform").filter(|_| name != "sheared.nii.gz") {
            assert_affine(&what("nibabel's qform"), &matrix(q), &want);
        }
    }
}

/// A 21×17×19 volume of faint tissue (which the camera frames whole) but for one bright voxel at
/// `bright`, with `linear` (unit spacing) as its transform.
fn marked(bright: [usize; 3], linear: [[f64; 3]; 3]) -> Volume {
    let mut data = vec![200.0f32; 21 * 17 * 19];
    data[bright[0] + 21 * (bright[1] + 17 * bright[2])] = 1000.0;
    Volume::new([21, 17, 19], [1.0; 3], slabscope::VoxelType::F32, data)
        .unwrap()
        .with_transform(WorldTransform::ras(linear, [0.0; 3]))
}

/// Where the brightest pixel of a MIP straight from the default camera's front lies, as
/// fractions of the width and height.
fn brightest(v: &Volume, axis: [f64; 3]) -> (f64, f64) {
    use slabscope::render::{CameraParams, Layout, Mode, Preset, RenderParams, Renderer};
    let params = RenderParams {
        width: 120,
        height: 100,
        mode: Mode::Mip,
        preset: Preset::CtBone,
        outlines: false,
        labels: false,
        camera: CameraParams {
            azimuth: 0.0,
            elevation: 0.0,
            ..CameraParams::default()
        },
        ..RenderParams::default()
    };
    let image = Renderer::new(v)
        .unwrap()
        .render(&Layout::whole(axis), &params, &Monitor::none())
        .unwrap();
    let data = image.pixmap.data();
    let i = (0..120 * 100).max_by_key(|&i| data[4 * i]).unwrap();
    ((i % 120) as f64 / 120.0, (i / 120) as f64 / 100.0)
}

#[test]
fn pictures_show_the_patients_right_on_the_left_and_the_head_up() {
    let diag = |a: f64, b: f64, c: f64| [[a, 0.0, 0.0], [0.0, b, 0.0], [0.0, 0.0, c]];
    // The bright voxel lies to the patient's right and towards the head, whichever way the
    // voxels run: RAS, LPS (a rotation of RAS) and LAS (its mirror image).
    for (name, linear, bright) in [
        ("RAS", diag(1.0, 1.0, 1.0), [17, 8, 15]),
        ("LPS", diag(-1.0, -1.0, 1.0), [3, 8, 15]),
        ("LAS", diag(-1.0, 1.0, 1.0), [3, 8, 15]),
        ("LAI", diag(-1.0, 1.0, -1.0), [3, 8, 3]),
    ] {
        let v = marked(bright, linear);
        // Axial slabs from the front: right on the left, superior up.
        let (x, y) = brightest(&v, [0.0, 0.0, 1.0]);
        assert!(x < 0.4 && y < 0.4, "{name} axial: at ({x:.2}, {y:.2})");
        // Coronal slabs from the feet: right on the left, anterior up (the voxel is central
        // front to back, so halfway up).
        let (x, _) = brightest(&v, [0.0, 1.0, 0.0]);
        assert!(x < 0.4, "{name} coronal: at x = {x:.2}");
    }
}

#[test]
fn renders_carry_the_triad_only_when_the_orientation_is_known() {
    use slabscope::render::{Layout, RenderParams, Renderer};
    let red = |v: &Volume| {
        let params = RenderParams {
            width: 160,
            height: 120,
            ..RenderParams::default()
        };
        let image = Renderer::new(v)
            .unwrap()
            .render(&Layout::whole([0.0, 0.0, 1.0]), &params, &Monitor::none())
            .unwrap();
        // The R arrow's colour, in the lower left quarter.
        let data = image.pixmap.data();
        (60..120)
            .flat_map(|y| (0..40).map(move |x| 4 * (y * 160 + x)))
            .filter(|&i| {
                let (r, g, b) = (
                    i32::from(data[i]),
                    i32::from(data[i + 1]),
                    i32::from(data[i + 2]),
                );
                r > g + 40 && r > b + 40
            })
            .count()
    };
    let oriented = marked(
        [3, 8, 15],
        [[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]],
    );
    assert!(red(&oriented) > 5, "the R arrow is drawn");
    let unknown = Volume::new(
        [21, 17, 19],
        [1.0; 3],
        slabscope::VoxelType::F32,
        oriented.voxels().to_vec(),
    )
    .unwrap();
    assert_eq!(red(&unknown), 0, "no made-up orientation");
}
