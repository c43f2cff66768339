//! The axis by partition gain (docs/design.md §6): on layered volumes the entropy rate's axis
//! lies inside the layers and the gain's across them; everywhere the gain's axis keeps at least
//! as much, and the axis partitioned reports the partition's own information.

use serde_json::Value;
use slabscope::analysis::{AxisBy, rank_by_gain};
use slabscope::geometry::{AxisChoice, normalize};
use slabscope::progress::Monitor;
use slabscope::view::{axis_angle, icosphere};
use slabscope::volume::phantom;
use slabscope::{AnalysisParams, Axis, Stop, Volume, analyze, load};

use crate::common::{data, run, s};

fn params(axis_by: AxisBy, slabs: usize) -> AnalysisParams {
    AnalysisParams {
        axis_by,
        stop: Stop::Slabs(slabs),
        ..AnalysisParams::default()
    }
}

/// The information kept by `slabs` top-down slabs along `axis`, counted on every voxel.
fn information_along(volume: &Volume, axis: [f64; 3], slabs: usize) -> f64 {
    let p = AnalysisParams {
        axis: AxisChoice::Along(Axis::new(axis).unwrap()),
        ..params(AxisBy::Entropy, slabs)
    };
    analyze(volume, &p, &Monitor::none())
        .unwrap()
        .partition
        .information
}

/// Layers normal to z, to the cube diagonal and to a direction between the sphere's axes: the
/// gain picks the normal within 5° and its six slabs keep 90% of what six along the normal keep.
#[test]
fn on_layers_the_gain_picks_the_layer_normal() {
    let sphere = icosphere::axes(1);
    for normal in [[0.0, 0.0, 1.0], [1.0, 1.0, 1.0], [0.3, 0.5, 0.81]] {
        let n = normalize(normal).unwrap();
        let nearest = sphere
            .iter()
            .map(|&a| axis_angle(a, n))
            .fold(f64::INFINITY, f64::min);
        let volume = phantom::layers([64, 64, 64], normal, 7).unwrap();
        let a = analyze(&volume, &params(AxisBy::Gain, 6), &Monitor::none()).unwrap();
        let picked = a.axis();
        assert!(
            axis_angle(picked, n) < 5.0,
            "{normal:?} ({nearest:.1}° from the sphere): picked {picked:?}"
        );
        let along_normal = information_along(&volume, n, 6);
        assert!(
            a.partition.information >= 0.9 * along_normal,
            "{normal:?}: {} of {along_normal}",
            a.partition.information
        );
        // The entropy rate's axis lies inside the layers: its slabs keep far less.
        let entropy_axis = a.views.as_ref().unwrap().best().axis;
        assert!(
            axis_angle(entropy_axis, n) > 45.0,
            "{normal:?}: {entropy_axis:?}"
        );
        assert!(information_along(&volume, entropy_axis, 6) < 0.5 * along_normal);
    }
    // The diagonal and the oblique normal are far from every sphere axis: refinement found them.
    let diagonal = normalize([1.0, 1.0, 1.0]).unwrap();
    assert!(sphere.iter().all(|&a| axis_angle(a, diagonal) > 20.0));
}

/// On the body phantom and two real MRI volumes both rankings are reported and the gain's axis
/// keeps at least as much as the entropy rate's.
#[test]
fn the_gains_axis_keeps_at_least_as_much_as_the_entropy_rates() {
    let mri = |name: &str| {
        load(&data(name), &slabscope::LoadOptions::default())
            .unwrap()
            .volume
    };
    let volumes = [
        ("body", phantom::body([64, 64, 96], 3).unwrap()),
        ("dx_MRI", mri("dx_MRI.nhdr")),
        ("nilearn", mri("nilearn_image_10426.nii.gz")),
    ];
    for (name, volume) in &volumes {
        let a = analyze(volume, &params(AxisBy::Gain, 4), &Monitor::none()).unwrap();
        let views = a.views.as_ref().unwrap();
        assert!(views.views.iter().all(|v| v.partition_gain.is_some()));
        let by_entropy = information_along(volume, views.best().axis, 4);
        assert!(
            a.partition.information >= by_entropy - 1e-9,
            "{name}: gain's axis {:?} keeps {}, entropy rate's {:?} {by_entropy}",
            a.axis(),
            a.partition.information,
            views.best().axis
        );
    }
}

/// The ranking's sampling, phases and contenders; the refined axis is at least as good as the
/// best sphere axis on the mean.
#[test]
fn the_ranking_states_its_sampling_and_uncertainty() {
    let volume = phantom::layers([40, 40, 40], [1.0, 1.0, 1.0], 2).unwrap();
    let g = rank_by_gain(&volume, &params(AxisBy::Gain, 4), &Monitor::none()).unwrap();
    assert_eq!(g.sampling.slabs, 4);
    assert_eq!(g.sampling.every, 1, "a small volume is counted whole");
    assert_eq!(g.views.len(), 21);
    for w in g.views.windows(2) {
        assert!(w[0].gain_phases.mean >= w[1].gain_phases.mean);
    }
    for v in &g.views {
        let aligned = slabscope::geometry::coordinate_axis(v.axis).is_some();
        assert_eq!(v.gain_phases.n, if aligned { 1 } else { 4 }, "{:?}", v.axis);
    }
    assert!(g.refined.gain_phases.mean >= g.views[0].gain_phases.mean);
    assert_eq!(g.contenders[0].axis, g.refined.axis);
    assert_eq!(g.uncertain(), g.contenders.len() > 1);
    // The threshold rule measures the gain at four slabs.
    let threshold = AnalysisParams {
        stop: Stop::Threshold(0.1),
        ..params(AxisBy::Gain, 4)
    };
    let t = rank_by_gain(&volume, &threshold, &Monitor::none()).unwrap();
    assert_eq!(t.sampling.slabs, 4);
}

fn json(args: &[&str]) -> Value {
    let out = run(args);
    assert!(out.ok, "{}", out.stderr);
    serde_json::from_str(&out.stdout).unwrap()
}

fn axis_of(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_f64().unwrap())
        .collect()
}

/// The CLI: without a flag nothing of the gain is computed; `--gain` reports it without changing
/// the axis; `--axis-by gain` sorts the views by it and partitions along its best; at full
/// resolution an axis's gain is the information of `analyze --axis` along it.
#[test]
fn the_cli_reports_the_gain_ranking() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("layers.nrrd");
    let made = run(&[
        "phantom",
        "layers",
        "--size",
        "40",
        "--normal",
        "0,0,1",
        "-o",
        s(&file),
    ]);
    assert!(made.ok, "{}", made.stderr);
    let plain = json(&["analyze", s(&file), "--json"]);
    for key in [
        "axis_by",
        "gain_sampling",
        "gain_uncertain",
        "gain_contenders",
        "gain_refined",
    ] {
        assert!(plain.get(key).is_none(), "{key} without a flag");
    }
    assert!(plain["views"][0].get("partition_gain").is_none());

    let also = json(&["analyze", s(&file), "--json", "--gain"]);
    assert_eq!(also["axis_by"], "entropy");
    assert_eq!(also["best_axis"], plain["best_axis"]);
    assert_eq!(also["partition"]["slabs"], plain["partition"]["slabs"]);
    assert_eq!(also["views"][0]["axis"], plain["views"][0]["axis"]);

    let by = json(&["analyze", s(&file), "--json", "--axis-by", "gain"]);
    assert_eq!(by["axis_by"], "gain");
    assert_eq!(by["gain_sampling"]["slabs"], 4);
    assert_eq!(axis_of(&by["best_axis"]), vec![0.0, 0.0, 1.0]);
    assert_eq!(by["partition"]["axis"], by["best_axis"]);
    let views = by["views"].as_array().unwrap();
    let means: Vec<f64> = views
        .iter()
        .map(|v| v["gain_phases"]["mean"].as_f64().unwrap())
        .collect();
    assert!(means.windows(2).all(|w| w[0] >= w[1]), "{means:?}");
    // The chosen axis's gain is its partition's information; every coordinate axis's (counted
    // on every voxel of this small volume) is that of a partition along it.
    let chosen = &views[0];
    assert_eq!(chosen["axis"], by["best_axis"]);
    assert_eq!(chosen["partition_gain"], by["partition"]["information"]);
    for (name, axis) in [("x", [1.0, 0.0, 0.0]), ("y", [0.0, 1.0, 0.0])] {
        let along = json(&["analyze", s(&file), "--json", "--axis", name]);
        let entry = views
            .iter()
            .find(|v| axis_of(&v["axis"]) == axis.to_vec())
            .unwrap();
        let gain = entry["partition_gain"].as_f64().unwrap();
        let information = along["partition"]["information"].as_f64().unwrap();
        assert!(
            (gain - information).abs() < 1e-9,
            "{name}: {gain} vs {information}"
        );
    }
}
