//! The view search (paper §3.1 and §4) on volumes with known answers.

use std::sync::atomic::{AtomicBool, Ordering};

use slabscope::geometry::{canonical, dot};
use slabscope::progress::Monitor;
use slabscope::view::{ViewParams, ViewSearch, axis_angle, icosphere, score, search};
use slabscope::volume::phantom;
use slabscope::{Error, SamplingParams, Volume, VoxelType};

/// A linear congruential generator: deterministic noise without a dependency.
struct Lcg(u64);

impl Lcg {
    fn below(&mut self, n: u64) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 33) % n
    }
}

fn run(volume: &Volume, params: &ViewParams) -> ViewSearch {
    search(volume, params, &Monitor::none()).unwrap()
}

fn entropy_of(result: &ViewSearch, axis: [f64; 3]) -> f64 {
    let a = canonical(axis);
    result
        .views
        .iter()
        .find(|v| axis_angle(v.axis, a) < 1e-6)
        .unwrap()
        .entropy_rate
}

#[test]
fn a_volume_constant_along_z_has_zero_rate_there_and_z_wins() {
    let (nx, ny, nz) = (24, 20, 16);
    let mut rng = Lcg(5);
    let plane: Vec<f32> = (0..nx * ny).map(|_| rng.below(9) as f32).collect();
    let data: Vec<f32> = (0..nz).flat_map(|_| plane.iter().copied()).collect();
    let v = Volume::new([nx, ny, nz], [1.0; 3], VoxelType::U8, data).unwrap();
    let r = run(&v, &ViewParams::with_bins(8));
    assert_eq!(r.best().axis, [0.0, 0.0, 1.0]);
    assert_eq!(r.best().entropy_rate, 0.0);
    assert!(
        r.views[1].entropy_rate > 0.5,
        "every other axis sees the noise"
    );
}

#[test]
fn iid_noise_has_rate_close_to_its_symbol_entropy_on_every_axis() {
    let mut rng = Lcg(11);
    let data: Vec<f32> = (0..48 * 48 * 48).map(|_| rng.below(8) as f32).collect();
    let v = Volume::new([48; 3], [1.0; 3], VoxelType::U8, data).unwrap();
    let r = run(&v, &ViewParams::with_bins(8));
    for a in &r.views {
        let gap = a.h1 - a.entropy_rate;
        assert!(
            (0.0..0.08).contains(&gap),
            "axis {:?}: h {} vs H(X^1) {}",
            a.axis,
            a.entropy_rate,
            a.h1
        );
    }
    // On the coordinate axes the samples are the voxels themselves: 3 bits each, independent.
    for axis in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]] {
        let h = entropy_of(&r, axis);
        assert!((h - 3.0).abs() < 0.01, "{axis:?}: {h}");
    }
}

#[test]
fn layers_are_best_seen_along_them() {
    let normal = [1.0, 1.0, 1.0];
    let v = phantom::layers([48; 3], normal, 1).unwrap();
    let r = run(&v, &ViewParams::default());
    let n = normal.map(|c| c / 3f64.sqrt());
    let most_parallel = icosphere::axes(1)
        .into_iter()
        .map(|a| dot(a, n).abs())
        .fold(f64::INFINITY, f64::min);
    assert!(
        (dot(r.best().axis, n).abs() - most_parallel).abs() < 1e-9,
        "best {:?} is not among the axes most nearly parallel to the layers",
        r.best().axis
    );
    // Along the normal itself, the sequences cross every layer.
    let along = search(
        &v,
        &ViewParams {
            level: 0,
            ..ViewParams::default()
        },
        &Monitor::none(),
    )
    .unwrap();
    let worst_on_sphere = along.views.last().unwrap().entropy_rate;
    assert!(worst_on_sphere > r.best().entropy_rate + 0.1);
    let sampler = slabscope::view::BinSampler::new(&v, v.quantizer(32).unwrap());
    let lattice =
        slabscope::geometry::lattice::Lattice::at_voxel_spacing(v.dims(), v.spacing(), normal)
            .unwrap();
    let h_normal = slabscope::view::entropy_rate(&sampler, &lattice, 3, &Monitor::none())
        .unwrap()
        .entropy_rate;
    assert!(
        h_normal > r.best().entropy_rate + 0.2,
        "normal {h_normal} vs best {}",
        r.best().entropy_rate
    );
}

#[test]
fn permuting_the_volume_axes_permutes_the_results() {
    let (nx, ny, nz) = (20, 16, 12);
    let mut rng = Lcg(3);
    let blocky = |x: usize, y: usize, z: usize, r: u64| {
        ((x / 4 + 2 * (y / 3) + 3 * (z / 5)) % 7) as f32 * 10.0 + r as f32
    };
    let mut data = vec![0.0; nx * ny * nz];
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                data[x + nx * (y + ny * z)] = blocky(x, y, z, rng.below(3));
            }
        }
    }
    // Cyclic permutation: new (x', y', z') = old (y, z, x).
    let mut permuted = vec![0.0; data.len()];
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                permuted[y + ny * (z + nz * x)] = data[x + nx * (y + ny * z)];
            }
        }
    }
    let a = Volume::new([nx, ny, nz], [1.0; 3], VoxelType::U8, data).unwrap();
    let b = Volume::new([ny, nz, nx], [1.0; 3], VoxelType::U8, permuted).unwrap();
    let params = ViewParams::with_bins(16);
    let (ra, rb) = (run(&a, &params), run(&b, &params));
    for view in &ra.views {
        let d = view.axis;
        let h = entropy_of(&rb, [d[1], d[2], d[0]]);
        assert!(
            (h - view.entropy_rate).abs() < 1e-12,
            "{d:?}: {} vs {h}",
            view.entropy_rate
        );
    }
    let best = ra.best().axis;
    assert!(axis_angle(rb.best().axis, [best[1], best[2], best[0]]) < 1e-9);
}

/// Layers normal to (0, 1, 2) in physical space, sampled with the given voxel counts and spacing.
fn physical_layers(dims: [usize; 3], spacing: [f64; 3]) -> Volume {
    let n = [0.0, 1.0 / 5f64.sqrt(), 2.0 / 5f64.sqrt()];
    let mut data = Vec::with_capacity(dims.iter().product());
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                let p = [
                    x as f64 * spacing[0],
                    y as f64 * spacing[1],
                    z as f64 * spacing[2],
                ];
                let t = dot(p, n);
                data.push(((t / 6.0).floor() as i64).rem_euclid(5) as f32 * 40.0);
            }
        }
    }
    Volume::new(dims, spacing, VoxelType::U8, data).unwrap()
}

#[test]
fn anisotropic_spacing_is_respected() {
    let coarse = physical_layers([40, 40, 40], [1.0; 3]);
    let fine = physical_layers([40, 40, 80], [1.0, 1.0, 0.5]);
    let params = ViewParams::with_bins(8);
    let (a, b) = (run(&coarse, &params), run(&fine, &params));
    assert_eq!(a.best().axis, b.best().axis);
    assert!(dot(a.best().axis, [0.0, 1.0 / 5f64.sqrt(), 2.0 / 5f64.sqrt()]).abs() < 0.3);
    assert_eq!(
        b.params.sampling.ray_spacing,
        Some(0.5),
        "the smallest spacing is the default"
    );
}

#[test]
fn cancellation_stops_the_search_with_an_error() {
    let v = phantom::body([64, 64, 104], 1).unwrap();
    let flag = AtomicBool::new(false);
    let cancel_on_progress = |_: slabscope::Progress| flag.store(true, Ordering::Relaxed);
    let monitor = Monitor::new(Some(&flag), Some(&cancel_on_progress));
    let result = search(&v, &ViewParams::default(), &monitor);
    assert!(matches!(result, Err(Error::Cancelled)), "{result:?}");
}

#[test]
fn phases_report_a_spread_and_refine_reports_a_nearby_axis() {
    let v = phantom::layers([32; 3], [0.0, 1.0, 3.0], 2).unwrap();
    let params = ViewParams {
        phases: 3,
        refine: true,
        ..ViewParams::default()
    };
    let r = run(&v, &params);
    for view in &r.views {
        let s = view.phases.unwrap();
        assert!(s.min <= view.entropy_rate && view.entropy_rate <= s.max);
        assert!(s.min <= s.mean && s.mean <= s.max && s.std >= 0.0);
    }
    let refined = r.refined.as_ref().unwrap();
    assert!(
        score(refined) <= score(&r.views[0]),
        "refined by the ranking's score"
    );
    // The layers are normal to (0, 1, 3); the refined axis lies within 3° of their plane, as
    // the best sphere axis does.
    let n = [0.0, 1.0 / 10f64.sqrt(), 3.0 / 10f64.sqrt()];
    let off_plane = |a: [f64; 3]| dot(a, n).abs().asin().to_degrees();
    assert!(off_plane(r.views[0].axis) < 3.0);
    assert!(off_plane(refined.axis) < 3.0, "{:?}", refined.axis);
}

#[test]
fn bad_parameters_and_constant_volumes_are_refused() {
    let v = Volume::new([4, 4, 4], [1.0; 3], VoxelType::U8, vec![3.0; 64]).unwrap();
    let err = search(&v, &ViewParams::default(), &Monitor::none()).unwrap_err();
    assert!(err.to_string().contains("constant"), "{err}");
    let v = phantom::layers([8; 3], [1.0, 0.0, 0.0], 1).unwrap();
    for params in [
        ViewParams {
            block: 5,
            ..ViewParams::default()
        },
        ViewParams {
            level: 5,
            ..ViewParams::default()
        },
        ViewParams::with_bins(1),
        ViewParams {
            sampling: SamplingParams {
                ray_spacing: Some(0.0),
                ..SamplingParams::default()
            },
            ..ViewParams::default()
        },
    ] {
        assert!(search(&v, &params, &Monitor::none()).is_err(), "{params:?}");
    }
}

/// The i.i.d. noise volume `n`³ of 256 values, u8.
fn noise(n: usize, seed: u64) -> Volume {
    let mut rng = Lcg(seed);
    let data = (0..n * n * n).map(|_| rng.below(256) as f32).collect();
    Volume::new([n; 3], [1.0; 3], VoxelType::U8, data).unwrap()
}

#[test]
fn on_noise_every_axis_scores_the_same_by_default_though_not_on_the_paper_lattice() {
    let v = noise(64, 17);
    let spread = |r: &ViewSearch| {
        let s: Vec<f64> = r.views.iter().map(score).collect();
        s.iter().copied().fold(f64::MIN, f64::max) - s.iter().copied().fold(f64::MAX, f64::min)
    };
    let default = run(&v, &ViewParams::default());
    assert!(
        spread(&default) < 0.05,
        "the 21 phase means differ by {}",
        spread(&default)
    );
    assert_eq!(default.uncertain, Some(true), "noise has no best axis");
    // On the paper's lattice the coordinate axes see unsmoothed voxels and lose by far.
    let paper = run(&v, &ViewParams::paper());
    assert!(spread(&paper) > 0.3, "{}", spread(&paper));
    assert!(paper.uncertain.is_none() && paper.contenders.is_none());
}

#[test]
fn layers_one_voxel_thick_are_seen_along_them_not_through_them() {
    // Each z plane one of four materials with mild noise: every axis in the planes sees one
    // material; every axis through them mixes materials, which interpolation smooths.
    let (n, mut rng) = (40, Lcg(3));
    let materials: Vec<f32> = (0..n).map(|_| (rng.below(4) * 60) as f32).collect();
    let data = (0..n * n * n)
        .map(|i| materials[i / (n * n)] + rng.below(12) as f32)
        .collect();
    let v = Volume::new([n; 3], [1.0; 3], VoxelType::U8, data).unwrap();
    let r = run(&v, &ViewParams::default());
    assert!(
        r.best().axis[2].abs() < 1e-9,
        "an axis through the layers won: {:?}",
        r.best().axis
    );
}

#[test]
fn a_near_tie_is_uncertain_with_both_axes_named_and_a_clear_winner_is_not() {
    // Constant along y in the lower half, along x in the upper one, random across: x and y
    // are equally structured, and nothing else comes near.
    let (n, mut rng) = (32, Lcg(5));
    let r: Vec<f32> = (0..n * n).map(|_| (rng.below(8) * 25) as f32).collect();
    let data = (0..n * n * n)
        .map(|i| {
            let (x, y, z) = (i % n, (i / n) % n, i / (n * n));
            if z < n / 2 {
                r[x + n * z]
            } else {
                r[y + n * z]
            }
        })
        .collect();
    let tie = Volume::new([n; 3], [1.0; 3], VoxelType::U8, data).unwrap();
    let r = run(&tie, &ViewParams::default());
    assert_eq!(r.uncertain, Some(true));
    let named: Vec<[f64; 3]> = r.contenders.unwrap().iter().map(|c| c.axis).collect();
    for axis in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        assert!(
            named.iter().any(|a| axis_angle(*a, axis) < 1e-6),
            "{axis:?} not among {named:?}"
        );
    }
    // Constant along z, random across: z has rate 0 and nothing comes near.
    let plane: Vec<f32> = (0..n * n).map(|_| rng.below(200) as f32).collect();
    let data = (0..n * n * n).map(|i| plane[i % (n * n)]).collect();
    let clear = Volume::new([n; 3], [1.0; 3], VoxelType::U8, data).unwrap();
    let r = run(&clear, &ViewParams::default());
    assert_eq!(r.best().axis, [0.0, 0.0, 1.0]);
    assert_eq!(r.uncertain, Some(false));
    assert_eq!(r.contenders.unwrap().len(), 1, "the best alone");
}
