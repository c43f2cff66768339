//! Tests of the transfer functions: colour maps, presets, windows, faces and label tables.

use super::*;
use crate::volume::VoxelType;

#[test]
fn colormaps_span_dark_to_bright() {
    for map in Colormap::ALL {
        let (lo, hi) = (map.at(0.0), map.at(1.0));
        assert!(lo.iter().sum::<f32>() < hi.iter().sum::<f32>(), "{map:?}");
    }
    assert_eq!(Colormap::Grey.at(0.25), [0.25; 3]);
}

#[test]
fn ct_bone_is_clear_in_air_and_opaque_in_bone() {
    let data = (0..1000).map(|i| -1000.0 + 3.0 * i as f32).collect();
    let v = Volume::new([10, 10, 10], [1.0; 3], VoxelType::I16, data).unwrap();
    let t = Transfer::new(&v, Preset::CtBone, Colormap::Grey, 1.0, 1.0).unwrap();
    assert_eq!(t.rgba(-1000.0)[3], 0.0);
    assert!(t.rgba(1500.0)[3] > 0.8);
    assert!(t.transparent(-1000.0, 100.0));
    assert!(!t.transparent(-1000.0, 900.0));
    // Half the step: less opacity per sample.
    let half = Transfer::new(&v, Preset::CtBone, Colormap::Grey, 0.5, 1.0).unwrap();
    assert!(half.rgba(1500.0)[3] < t.rgba(1500.0)[3]);
}

#[test]
fn a_window_replaces_the_preset() {
    let data = (0..1000).map(|i| i as f32).collect();
    let v = Volume::new([10, 10, 10], [1.0; 3], VoxelType::F32, data).unwrap();
    let h = v.histogram(HISTOGRAM_BINS).unwrap();
    let look = TransferChoice {
        preset: Preset::CtBone,
        colormap: Colormap::Grey,
        window: Some((400.0, 600.0)),
    };
    let t = Transfer::with_histogram(v.stats(), &h, look, 1.0, 1.0).unwrap();
    assert_eq!(t.rgba(399.0)[3], 0.0);
    assert!((t.rgba(999.0)[3] - WINDOW_OPACITY).abs() < 1e-6);
    assert_eq!(t.grey(300.0), [0.0; 3]);
    assert_eq!(t.grey(700.0), [1.0; 3]);
}

#[test]
fn auto_makes_the_dominant_background_clear() {
    // 90% air at 0, the rest a structure at 100.
    let data = (0..1000)
        .map(|i| if i % 10 == 0 { 100.0 } else { 0.0 })
        .collect();
    let v = Volume::new([10, 10, 10], [1.0; 3], VoxelType::U8, data).unwrap();
    let t = Transfer::new(&v, Preset::Auto, Colormap::Grey, 1.0, 1.0).unwrap();
    assert_eq!(t.rgba(0.0)[3], 0.0);
    assert!(t.rgba(100.0)[3] > 0.3);
}

#[test]
fn ct_presets_suit_only_volumes_in_hounsfield_units() {
    let stats = |min: f32| Stats {
        min,
        max: 1000.0,
        mean: 0.0,
        finite: 1,
        missing: 0,
    };
    for p in Preset::ALL {
        assert!(p.suits(stats(-1024.0)), "{p:?}");
    }
    assert!(!Preset::CtBone.suits(stats(0.0)));
    assert!(!Preset::CtSoft.suits(stats(0.0)));
    assert!(Preset::Mri.suits(stats(0.0)) && Preset::Auto.suits(stats(0.0)));
}

#[test]
fn auto_windows_ct_on_soft_tissue_and_clears_faces_in_air() {
    // Half air at -1000, then fat, soft tissue and bone.
    let data: Vec<f32> = (0..4000)
        .map(|i| match i % 8 {
            0..4 => -1000.0 + (i % 13) as f32,
            4 => -100.0,
            5 | 6 => 40.0 + (i % 7) as f32,
            _ => 1200.0,
        })
        .collect();
    let v = Volume::new([20, 20, 10], [1.0; 3], VoxelType::I16, data).unwrap();
    let t = Transfer::new(&v, Preset::Auto, Colormap::Grey, 1.0, 1.0).unwrap();
    let (lo, hi) = t.window();
    assert!(
        (-160.0..-90.0).contains(&lo) && (hi - 240.0).abs() < 1.0,
        "{lo}..{hi}"
    );
    assert_eq!(t.face(-1000.0)[3], 0.0, "air is clear on a cut face");
    assert_eq!(t.face(40.0)[3], 1.0, "tissue is opaque on it");
    assert_eq!(t.face(1200.0), [1.0; 4], "bone is white");
    // MIP shows the brightest: its window reaches bone, so soft tissue is not white there.
    assert!(t.mip_grey(240.0)[0] < 0.5 && t.mip_grey(1200.0)[0] > 0.95);
}

#[test]
fn a_spike_of_zeros_inside_the_range_is_the_background() {
    // A signed map: 70% exactly zero, the rest spread both ways.
    let data: Vec<f32> = (0..10_000)
        .map(|i| {
            if i % 10 < 7 {
                0.0
            } else {
                ((i % 97) as f32 - 48.0) / 6.0
            }
        })
        .collect();
    let v = Volume::new([25, 20, 20], [1.0; 3], VoxelType::F32, data).unwrap();
    let t = Transfer::new(&v, Preset::Auto, Colormap::Grey, 1.0, 1.0).unwrap();
    assert_eq!(t.face(0.0)[3], 0.0, "zero is clear");
    assert_eq!(t.rgba(0.0)[3], 0.0);
    assert_eq!(t.face(6.0)[3], 1.0, "high values are opaque");
    assert_eq!(t.face(-6.0)[3], 1.0, "and low ones");
    assert!(t.rgba(8.0)[3] > 0.3 && t.rgba(-8.0)[3] > 0.3);
}

#[test]
fn labels_have_distinct_colours_and_a_clear_background() {
    let labels = [(0.0, 900), (2.0, 50), (5.0, 30), (9.0, 20)];
    let t = Transfer::for_labels(&labels, 1.0, 1.0).unwrap();
    assert!(t.is_labels());
    assert_eq!(t.rgba(0.0)[3], 0.0);
    assert_eq!(t.face(0.0)[3], 0.0);
    let colours: Vec<[f32; 3]> = [2.0, 5.0, 9.0].iter().map(|&v| t.grey(v)).collect();
    assert!(colours[0] != colours[1] && colours[1] != colours[2] && colours[0] != colours[2]);
    assert!(t.transparent(0.0, 0.0) && t.transparent(0.5, 1.5));
    assert!(!t.transparent(0.0, 2.0) && !t.transparent(4.0, 6.0));
    // The background need not be the lowest value.
    let t = Transfer::for_labels(&[(1.0, 5), (3.0, 100)], 1.0, 1.0).unwrap();
    assert_eq!(t.rgba(3.0)[3], 0.0);
    assert!(t.rgba(1.0)[3] > 0.0);
}
