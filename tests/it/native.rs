//! Voxels in their own type: a volume held as u8, i8, u16 or i16 gives every result (view search,
//! the three partitions, histograms, renders, slices) bit for bit as the same voxels held as
//! f32; readers hold unscaled small integers as they are stored, reading uncompressed ones in
//! place from a map of the file.

use slabscope::Volume;
use slabscope::analysis::{AnalysisParams, analyze};
use slabscope::formats::{LoadOptions, load, write_volume};
use slabscope::partition::Method;
use slabscope::progress::Monitor;
use slabscope::render::{Layout, RenderParams, Renderer};
use slabscope::report::{AnalysisReport, to_json};
use slabscope::volume::{Voxel, VoxelType, Voxels, phantom};

/// `volume`'s voxels, held as `T` (every value must be one of `T`'s).
fn held_as<T: Voxel + TryFrom<i32>>(volume: &Volume) -> Volume {
    let values: Vec<T> = volume
        .voxels()
        .iter()
        .map(|&v| {
            assert_eq!(v.fract(), 0.0);
            T::try_from(v as i32).ok().expect("a value of the type")
        })
        .collect();
    Volume::from_voxels(
        volume.dims(),
        volume.spacing(),
        T::TYPE,
        Voxels::owned(values),
    )
    .unwrap()
    .with_transform(*volume.transform())
}

/// Everything an analysis reports, as JSON, for the three methods.
fn reports(volume: &Volume) -> Vec<String> {
    [Method::TopDown, Method::BottomUp, Method::Optimal]
        .into_iter()
        .map(|method| {
            let params = AnalysisParams {
                method,
                ..AnalysisParams::default()
            };
            let analysis = analyze(volume, &params, &Monitor::none()).unwrap();
            let report = AnalysisReport::new("v", volume, &params.view, &analysis).unwrap();
            to_json(&report).unwrap()
        })
        .collect()
}

/// The exploded view's pixels, and a histogram.
fn pictures(volume: &Volume) -> (Vec<u8>, Vec<u64>) {
    let renderer = Renderer::new(volume).unwrap();
    let params = RenderParams {
        width: 96,
        height: 80,
        ..RenderParams::default()
    };
    let layout = Layout::whole([0.0, 0.0, 1.0]);
    let image = renderer.render(&layout, &params, &Monitor::none()).unwrap();
    (image.pixmap.data().to_vec(), volume.histogram(32).unwrap())
}

fn agree(f32_held: &Volume, native: &Volume) {
    assert_eq!(f32_held.data().held(), VoxelType::F32);
    assert_eq!(native.stats(), f32_held.stats());
    assert_eq!(
        reports(native),
        reports(f32_held),
        "{}",
        native.data().held()
    );
    assert_eq!(
        pictures(native),
        pictures(f32_held),
        "{}",
        native.data().held()
    );
}

#[test]
fn every_small_integer_type_gives_the_f32_results() {
    let body = phantom::body([40, 36, 52], 3).unwrap();
    agree(&body, &held_as::<i16>(&body));
    let shifted = Volume::new(
        body.dims(),
        body.spacing(),
        VoxelType::U16,
        body.voxels().iter().map(|v| v + 1024.0).collect(),
    )
    .unwrap();
    agree(&shifted, &held_as::<u16>(&shifted));
    let layers = phantom::layers([30, 30, 30], [0.3, 0.2, 1.0], 5).unwrap();
    agree(&layers, &held_as::<u8>(&layers));
    let signed = Volume::new(
        body.dims(),
        body.spacing(),
        VoxelType::I8,
        body.voxels().iter().map(|v| (v / 16.0).round()).collect(),
    )
    .unwrap();
    agree(&signed, &held_as::<i8>(&signed));
}

#[test]
fn readers_hold_small_integers_as_stored_and_map_uncompressed_ones() {
    let dir = tempfile::tempdir().unwrap();
    let body = phantom::body([24, 20, 30], 1).unwrap();
    for (name, mapped) in [("b.nii", true), ("b.nii.gz", false), ("b.nrrd", false)] {
        let path = dir.path().join(name);
        write_volume(&path, &body, false).unwrap();
        let loaded = load(&path, &LoadOptions::default()).unwrap().volume;
        assert_eq!(loaded.data().held(), VoxelType::I16, "{name}");
        assert_eq!(loaded.data().is_mapped(), mapped, "{name}");
        assert_eq!(loaded.data().to_f32_vec(), body.voxels(), "{name}");
        let f32_held = Volume::new(
            loaded.dims(),
            loaded.spacing(),
            loaded.voxel_type(),
            loaded.data().to_f32_vec(),
        )
        .unwrap()
        .with_transform(*loaded.transform());
        assert_eq!(reports(&loaded)[0], reports(&f32_held)[0], "{name}");
    }
}
/// A file cut short while slabscope reads it in place: one line naming it, exit status 1 (not
/// a death by SIGBUS). `SLABSCOPE_TEST_DELAY_MS` makes the CLI wait after loading, so the file
/// can be truncated between the load and the analysis.
#[test]
fn a_mapped_file_cut_short_is_one_clear_line() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("body.nii");
    let body = slabscope::volume::phantom::body([32, 32, 40], 1).unwrap();
    slabscope::formats::write_volume(&path, &body, false).unwrap();
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_slabscope"))
        .args(["analyze", path.to_str().unwrap()])
        .env("SLABSCOPE_TEST_DELAY_MS", "1500")
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(700));
    std::fs::OpenOptions::new()
        .write(true)
        .open(&path)
        .unwrap()
        .set_len(0)
        .unwrap();
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains(path.to_str().unwrap()) && stderr.contains("cut short"),
        "{stderr}"
    );
    assert!(out.stdout.is_empty());
}
