use super::*;

#[test]
fn noise_is_standard_normal_and_deterministic() {
    let n = 200_000;
    let xs: Vec<f64> = (0..n).map(|i| gaussian(7, i)).collect();
    let mean = xs.iter().sum::<f64>() / n as f64;
    let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
    assert!(mean.abs() < 0.01, "mean {mean}");
    assert!((var - 1.0).abs() < 0.02, "variance {var}");
    assert_eq!(gaussian(7, 12), gaussian(7, 12));
    assert_ne!(gaussian(7, 12), gaussian(8, 12));
}

#[test]
fn layers_follow_the_normal() {
    let dims = [24, 24, 24];
    let v = layers(dims, [0.0, 0.0, 1.0], 1).unwrap();
    assert_eq!(v.voxel_type(), VoxelType::U8);
    // Along z, each 4-slice band is one material.
    for z in 0..24 {
        let mean: f64 = (0..24 * 24)
            .map(|i| f64::from(v.array()[[i % 24, i / 24, z]]))
            .sum::<f64>()
            / 576.0;
        let expect = f64::from(LAYER_VALUES[z / 4]);
        assert!(
            (mean - expect).abs() < 1.0,
            "slice {z}: mean {mean}, material {expect}"
        );
        assert_eq!(layer_of(dims, [0.0, 0.0, 1.0], [3, 5, z]), z / 4);
    }
}

#[test]
fn layers_reject_a_zero_normal() {
    assert!(layers([4, 4, 4], [0.0; 3], 1).is_err());
}

#[test]
fn phantoms_are_deterministic_per_seed() {
    let a = body([20, 20, 34], 3).unwrap();
    let b = body([20, 20, 34], 3).unwrap();
    let c = body([20, 20, 34], 4).unwrap();
    assert_eq!(a.voxels(), b.voxels());
    assert_ne!(a.voxels(), c.voxels());
}

#[test]
fn body_has_air_lungs_and_bone() {
    let v = body([64, 64, 104], 1).unwrap();
    let s = v.stats();
    assert!(
        s.min < -950.0 && s.max > 800.0,
        "range {} .. {}",
        s.min,
        s.max
    );
    // The centre of the left lung, and a corner of air.
    let at = |p: [f64; 3]| {
        let idx = [
            (f64::midpoint(p[0], 1.0) * 64.0) as usize,
            (f64::midpoint(p[1], 1.0) * 64.0) as usize,
            (p[2] * 104.0) as usize,
        ];
        f64::from(v.array()[idx])
    };
    assert!((at([-0.28, 0.02, 0.71]) - hu::LUNG).abs() < 60.0);
    assert!((at([-0.95, -0.95, 0.5]) - hu::AIR).abs() < 60.0);
}

#[test]
fn shepp_logan_has_its_known_values() {
    let v = shepp_logan([65, 65, 65]).unwrap();
    // The centre lies in the skull (1) and the brain (-0.8): 0.2; outside is 0.
    assert!((v.array()[[32, 32, 32]] - 0.2).abs() < 1e-6);
    assert_eq!(v.array()[[0, 0, 0]], 0.0);
    assert!((v.stats().max - 1.0).abs() < 1e-6);
}

/// The recipes of every phantom at an odd size, whose planes are no multiple of any chunk.
fn recipes() -> Vec<Recipe> {
    let dims = [9, 7, 5];
    vec![
        Recipe::layers(dims, [1.0, 2.0, 3.0], 3).unwrap(),
        Recipe::body(dims, 5).unwrap(),
        Recipe::shepp_logan(dims).unwrap(),
    ]
}

#[test]
fn a_phantom_written_a_chunk_at_a_time_is_the_phantom_made_whole() {
    for recipe in recipes() {
        let volume = recipe.volume().unwrap();
        assert_eq!(volume.voxel_type(), recipe.voxel_type());
        assert_eq!(*volume.transform(), recipe.transform());
        let mut whole = Vec::new();
        crate::volume::write_le(volume.data(), volume.voxel_type(), &mut whole).unwrap();
        assert_eq!(whole.len(), 9 * 7 * 5 * recipe.voxel_type().size());
        // One voxel, a prime, a plane, more than the volume: every chunk boundary.
        for chunk in [1, 37, 63, 10_000] {
            let mut streamed = Vec::new();
            recipe.write_le_in(&mut streamed, chunk).unwrap();
            assert!(
                streamed == whole,
                "{:?} in chunks of {chunk}",
                recipe.voxel_type()
            );
        }
        let mut default = Vec::new();
        recipe.write_le(&mut default).unwrap();
        assert!(default == whole);
    }
    // The functions the library has always had make the same volumes.
    let body = body([9, 7, 5], 5).unwrap();
    assert_eq!(body.transform(), &recipes()[1].transform());
    assert_eq!(
        body.stats().mean,
        recipes()[1].volume().unwrap().stats().mean
    );
}

#[test]
fn a_phantom_too_large_to_hold_is_refused_not_aborted() {
    // 2^48 voxels: 1 PiB of f32, more than any address space holds.
    let recipe = Recipe::body([65_536; 3], 1).unwrap();
    let e = recipe.volume().unwrap_err().to_string();
    assert!(
        e.contains("65536x65536x65536") && e.contains("hold in memory"),
        "{e}"
    );
    assert!(Recipe::body([0, 1, 1], 1).is_err());
}
