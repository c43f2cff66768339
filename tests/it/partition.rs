//! Slab partitioning (paper §5) on stacks and volumes with known answers.

use proptest::prelude::*;
use slabscope::partition::{
    Histories, MISSING, MergeHistory, OptimalPartitions, PAIRS_KEPT, PartitionParams, Scope, Slab,
    SliceStack, SplitHistory, StackParams, partition, slice_nmi,
};
use slabscope::progress::Monitor;
use slabscope::volume::background::{Background, BackgroundRule};
use slabscope::volume::phantom;
use slabscope::{SamplingParams, Volume, VoxelType};

/// A pseudo-random value in `0..n` for `(a, b)`.
fn hash(a: u64, b: u64, n: u64) -> u64 {
    let mut z = a.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ b.wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 29)).wrapping_mul(0x94d0_49bb_1331_11eb);
    (z ^ (z >> 32)) % n
}

/// A volume of `nz` slices of 12x10 pixels; slice z holds material `material(z)`: its own random
/// texture of three values, so that slices of one material are identical and slices of two
/// materials are nearly independent (NMI measures dependence, not likeness of values).
fn materials(nz: usize, material: impl Fn(usize) -> usize) -> Volume {
    let mut data = Vec::new();
    for z in 0..nz {
        let m = material(z);
        for p in 0..120 {
            data.push((m * 10) as f32 + hash(p, m as u64, 3) as f32);
        }
    }
    Volume::new([12, 10, nz], [1.0; 3], VoxelType::U8, data).unwrap()
}

fn stack(v: &Volume, bins: usize) -> SliceStack {
    let params = StackParams {
        sampling: SamplingParams {
            bins,
            ..SamplingParams::default()
        },
        ..StackParams::default()
    };
    SliceStack::new(v, [0.0, 0.0, 1.0], &params, &Monitor::none()).unwrap()
}

#[test]
fn a_sharp_boundary_between_two_materials() {
    let (n, s) = (24, 9);
    let v = materials(n, |z| usize::from(z >= s));
    let st = stack(&v, 32);
    let h = st.slice_histograms();
    let top = SplitHistory::new(&h, 32);
    assert_eq!(top.steps[0].at, s);
    let bottom = MergeHistory::new(&st, &Monitor::none()).unwrap();
    assert_eq!(bottom.slabs(2), vec![(0, s), (s, n)]);
}

#[test]
fn equal_disjoint_halves_split_for_exactly_one_bit() {
    let v = materials(16, |z| usize::from(z >= 8));
    let st = stack(&v, 32);
    let top = SplitHistory::new(&st.slice_histograms(), 32);
    assert_eq!(top.steps[0].at, 8);
    assert!(
        (top.steps[0].gain - 1.0).abs() < 1e-12,
        "ΔI = {}",
        top.steps[0].gain
    );
}

#[test]
fn k_materials_are_recovered_by_every_method() {
    let bounds = [0, 5, 13, 16, 27, 35];
    let material = |z: usize| bounds.iter().rposition(|&b| z >= b).unwrap();
    let v = materials(40, material);
    let st = stack(&v, 64);
    let h = st.slice_histograms();
    let expect: Vec<Slab> = bounds
        .iter()
        .zip(bounds.iter().skip(1).chain([&40]))
        .map(|(&a, &b)| (a, b))
        .collect();
    let k = expect.len();
    assert_eq!(SplitHistory::new(&h, 64).slabs(k), expect, "top-down");
    assert_eq!(
        MergeHistory::new(&st, &Monitor::none()).unwrap().slabs(k),
        expect,
        "bottom-up"
    );
    assert_eq!(
        OptimalPartitions::new(&h, 64, k)
            .unwrap()
            .get(k)
            .unwrap()
            .slabs,
        expect,
        "optimal"
    );
}

#[test]
fn replaying_a_history_equals_a_fresh_run_stopped_there() {
    let v = phantom::body([24, 20, 60], 4).unwrap();
    let st = stack(&v, 16);
    let h = st.slice_histograms();
    let top = SplitHistory::new(&h, 16);
    let bottom = MergeHistory::new(&st, &Monitor::none()).unwrap();
    for k in [1, 2, 3, 5, 8, 20, 60] {
        assert_eq!(
            top.slabs(k),
            SplitHistory::with_limit(&h, 16, k - 1).slabs(k),
            "top-down K = {k}"
        );
        let fresh = MergeHistory::with_limit(&st, &Monitor::none(), 60 - k).unwrap();
        assert_eq!(bottom.slabs(k), fresh.slabs(k), "bottom-up K = {k}");
    }
    for m in &bottom.steps {
        assert!((0.0..=1.0).contains(&m.nmi));
        assert!(m.pairs.iter().all(|x| (0.0..=1.0).contains(x)));
    }
    assert_eq!(
        bottom.slice_nmi(),
        &slice_nmi(&st, &Monitor::none()).unwrap()[..]
    );
}

/// The cuts between six equal layers of a 40³ box along `normal` (spacing 1), by slice index of
/// a stack along it: slice k lies at distance k from the box corner lowest along the normal.
fn layer_cuts(normal: [f64; 3], slices: usize) -> Vec<usize> {
    let len = normal.iter().map(|c| c * c).sum::<f64>().sqrt();
    let extent: f64 = normal.iter().map(|c| c.abs() / len * 39.0).sum();
    let layer_of = |k: usize| ((k as f64 + 0.5) / extent * 6.0).floor().min(5.0) as usize;
    (1..slices)
        .filter(|&k| layer_of(k) != layer_of(k - 1))
        .collect()
}

fn assert_cuts_near(name: &str, slabs: &[Slab], expect: &[usize]) {
    let cuts: Vec<usize> = slabs.iter().skip(1).map(|s| s.0).collect();
    assert_eq!(cuts.len(), expect.len(), "{name}");
    for (c, e) in cuts.iter().zip(expect) {
        assert!(
            c.abs_diff(*e) <= 1,
            "{name}: cuts {cuts:?}, layers at {expect:?}"
        );
    }
}

#[test]
fn oblique_partition_along_the_layer_normal_recovers_the_layers() {
    let normal = [1.0, 2.0, 2.0];
    let v = phantom::layers([40; 3], normal, 1).unwrap();
    let st = SliceStack::new(&v, normal, &StackParams::default(), &Monitor::none()).unwrap();
    let h = st.slice_histograms();
    let expect = layer_cuts(normal, st.slices());
    assert_eq!(expect.len(), 5);
    assert_cuts_near("top-down", &SplitHistory::new(&h, 32).slabs(6), &expect);
    assert_cuts_near(
        "optimal",
        &OptimalPartitions::new(&h, 32, 6)
            .unwrap()
            .get(6)
            .unwrap()
            .slabs,
        &expect,
    );
}

#[test]
fn oblique_bottom_up_recovers_textured_layers() {
    // Each layer carries its own texture of 4 mm blocks in the plane of the layers, constant
    // along the normal: the structure NMI responds to (the phantom's i.i.d. noise has none).
    let normal = [1.0, 2.0, 2.0];
    let n = [1.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0];
    let (u, w) = (
        [2.0 / 3.0, 1.0 / 3.0, -2.0 / 3.0],
        [2.0 / 3.0, -2.0 / 3.0, 1.0 / 3.0],
    );
    let extent = 39.0 * (n[0] + n[1] + n[2]);
    let mut data = Vec::new();
    for z in 0..40 {
        for y in 0..40 {
            for x in 0..40 {
                let p = [f64::from(x), f64::from(y), f64::from(z)];
                let dot = |a: [f64; 3]| a[0] * p[0] + a[1] * p[1] + a[2] * p[2];
                let layer = ((dot(n) / extent * 6.0).floor() as u64).min(5);
                let block = hash(
                    (dot(u) / 4.0).floor() as i64 as u64,
                    ((dot(w) / 4.0).floor() as i64 as u64).wrapping_add(1000 * layer),
                    4,
                );
                data.push((layer * 40 + block * 8) as f32);
            }
        }
    }
    let v = Volume::new([40; 3], [1.0; 3], VoxelType::U8, data).unwrap();
    let st = SliceStack::new(&v, normal, &StackParams::default(), &Monitor::none()).unwrap();
    let expect = layer_cuts(normal, st.slices());
    let bottom = MergeHistory::new(&st, &Monitor::none()).unwrap();
    assert_cuts_near("bottom-up", &bottom.slabs(6), &expect);
}

/// The information a partition keeps, computed directly: `H(X) - Σ (v_i/v) H(X | slab i)`.
fn information(h: &[u64], bins: usize, slabs: &[Slab]) -> f64 {
    let total: u64 = h.iter().sum();
    let entropy = |c: &[u64]| slabscope::measure::entropy(c.iter().copied());
    let all: Vec<u64> = (0..bins)
        .map(|b| h.chunks(bins).map(|s| s[b]).sum())
        .collect();
    let mut kept = entropy(&all);
    for &(a, z) in slabs {
        let part: Vec<u64> = (0..bins)
            .map(|b| h[a * bins..z * bins].chunks(bins).map(|s| s[b]).sum())
            .collect();
        kept -= part.iter().sum::<u64>() as f64 / total as f64 * entropy(&part);
    }
    kept
}

/// Every partition of `0..n` into `k` contiguous slabs.
fn partitions(n: usize, k: usize) -> Vec<Vec<Slab>> {
    if k == 1 {
        return vec![vec![(0, n)]];
    }
    (k - 1..n)
        .flat_map(|cut| {
            partitions(cut, k - 1).into_iter().map(move |mut p| {
                p.push((cut, n));
                p
            })
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn the_optimum_is_brute_force_and_never_below_greedy(
        h in (3usize..9, 2usize..5).prop_flat_map(|(n, b)| (Just(b), prop::collection::vec(0u64..6, n * b)))
    ) {
        let (bins, h) = h;
        let n = h.len() / bins;
        let opt = OptimalPartitions::new(&h, bins, n).unwrap();
        let greedy = SplitHistory::new(&h, bins);
        for k in 1..=n {
            let best = partitions(n, k).iter().map(|p| information(&h, bins, p)).fold(f64::NEG_INFINITY, f64::max);
            let o = opt.get(k).unwrap();
            prop_assert!((o.information - best).abs() < 1e-9, "K = {}: {} vs brute force {}", k, o.information, best);
            prop_assert!((information(&h, bins, &o.slabs) - o.information).abs() < 1e-9);
            prop_assert!(o.information >= greedy.information(k) - 1e-9);
        }
    }

    #[test]
    fn slab_nmi_follows_the_pairwise_definition(
        slices in (2usize..7, 1usize..30).prop_flat_map(|(n, p)| prop::collection::vec(prop::collection::vec(prop_oneof![0u8..4, Just(MISSING)], p), n))
    ) {
        let st = SliceStack::from_slices(&slices, 4).unwrap();
        let history = MergeHistory::new(&st, &Monitor::none()).unwrap();
        // Check every merge's NMI against the literal joint histogram of the two slabs.
        for m in &history.steps {
            let ((a0, a1), (b0, b1)) = m.merge;
            let mut joint = vec![0u64; 16];
            for s in a0..a1 {
                for t in b0..b1 {
                    for (&x, &y) in slices[s].iter().zip(&slices[t]) {
                        if x != MISSING && y != MISSING {
                            joint[usize::from(x) * 4 + usize::from(y)] += 1;
                        }
                    }
                }
            }
            let expect = slabscope::measure::normalized_mutual_information(&joint, 4, 4);
            prop_assert!((m.nmi - expect).abs() < 1e-12, "{:?}: {} vs {}", m.merge, m.nmi, expect);
        }
    }
}

/// The voxel of `v` at normalized body coordinates (x, y in [-1, 1], z in [0, 1]).
fn voxel_at(v: &Volume, p: [f64; 3]) -> usize {
    let [nx, ny, nz] = v.dims();
    let x = (f64::midpoint(p[0], 1.0) * nx as f64) as usize;
    let y = (f64::midpoint(p[1], 1.0) * ny as f64) as usize;
    let z = (p[2] * nz as f64) as usize;
    x + nx * (y + ny * z)
}

#[test]
fn the_body_phantom_has_air_around_it_and_lungs_inside() {
    let v = phantom::body([64, 64, 104], 1).unwrap();
    let b = Background::find(&v, BackgroundRule::Auto, &slabscope::Monitor::none()).unwrap();
    let t = b.value.unwrap();
    assert!((-1000.0..-800.0).contains(&t), "threshold {t}");
    assert!((0.6..0.98).contains(&b.fraction), "{}", b.fraction);
    let at = |p: [f64; 3]| {
        let i = voxel_at(&v, p);
        b.contains(i, v.voxels()[i])
    };
    assert!(at([-0.95, -0.95, 0.5]), "air in a corner");
    assert!(at([0.0, 0.0, 0.3]), "air between the legs");
    assert!(!at([-0.28, 0.02, 0.71]), "a lung is inside the body");
    assert!(!at([0.0, 0.0, 0.93]), "the brain");
    assert!(!at([0.22, 0.0, 0.3]), "a leg");
}

#[test]
fn a_dark_cavity_inside_a_head_is_not_background() {
    // The modified Shepp-Logan head: 0 around it, and two ellipsoids of 0 inside the brain
    // (1 - 0.8 - 0.2).
    let v = phantom::shepp_logan([65, 65, 65]).unwrap();
    let b = Background::find(&v, BackgroundRule::Auto, &slabscope::Monitor::none()).unwrap();
    let idx = |x: usize, y: usize, z: usize| x + 65 * (y + 65 * z);
    assert!(b.contains(idx(0, 0, 0), 0.0), "the air border");
    // The centre of the left dark ellipsoid (0.22, 0, 0) in [-1, 1] coordinates.
    let cavity = idx((f64::midpoint(0.22, 1.0) * 64.0).round() as usize, 32, 32);
    assert!(v.voxels()[cavity].abs() < 1e-6, "the cavity is dark");
    assert!(!b.contains(cavity, 0.0), "but inside");
    assert!(b.fraction > 0.3 && b.fraction < 0.8, "{}", b.fraction);
}

#[test]
fn with_the_background_left_out_the_end_slabs_hold_the_body() {
    let v = phantom::body([64, 64, 104], 1).unwrap();
    let mean_of_ends = |background| {
        let params = PartitionParams {
            stack: StackParams {
                background,
                ..StackParams::default()
            },
            ..PartitionParams::default()
        };
        let p = partition(&v, [0.0, 0.0, 1.0], &params, &Monitor::none()).unwrap();
        let (first, last) = (&p.info[0], &p.info[p.info.len() - 1]);
        (
            first.mean.unwrap(),
            last.mean.unwrap(),
            first.empty || last.empty,
        )
    };
    let (first, last, empty) = mean_of_ends(BackgroundRule::Auto);
    assert!(
        first > -300.0 && last > -300.0,
        "tissue: {first} and {last} HU"
    );
    assert!(!empty, "the legs and the head are not empty");
    // Counting every voxel, air dominates both ends, as in the paper.
    let (first, last, _) = mean_of_ends(BackgroundRule::None);
    assert!(first < -800.0 && last < -800.0, "{first} and {last} HU");
}

#[test]
fn a_long_axis_keeps_memory_linear_in_its_slices() {
    // 20,000 slices of one voxel: segments of 500 slices, each its own level, with noise.
    let n = 20_000;
    let data = (0..n)
        .map(|i| (hash(i as u64 / 500, 1, 200) + hash(i as u64, 2, 5)) as f32)
        .collect();
    let v = Volume::new([n, 1, 1], [1.0; 3], VoxelType::U8, data).unwrap();
    let h = Histories::new(
        &v,
        [1.0, 0.0, 0.0],
        &StackParams::default(),
        Scope::ALL,
        &Monitor::none(),
    )
    .unwrap();
    // Top-down keeps a gain a step (no curve), to its step limit, and one curve of the stack.
    assert_eq!(h.top().steps.len(), Scope::ALL.top_steps);
    assert_eq!(h.gain_curve().len(), n - 1);
    // Bottom-up keeps the pairs only once few slabs are left.
    let bottom = h.bottom().unwrap();
    assert_eq!(bottom.steps.len(), n - 1);
    let stored: usize = bottom.steps.iter().map(|m| m.pairs.len()).sum();
    assert!(
        stored <= PAIRS_KEPT * PAIRS_KEPT / 2 + PAIRS_KEPT,
        "{stored} pairs kept"
    );
    assert_eq!(h.nmi_curve().len(), n - 1);
    // The optimum does not fit, and says so; the other methods work.
    assert!(h.optimal().is_none());
    assert!(
        h.notes()
            .iter()
            .any(|n| n.contains("optimal partition is skipped"))
    );
    let four = h.slabs(slabscope::Method::TopDown, 3);
    assert_eq!(four.len(), 4);
    let near_an_end = |c: usize| (c + 1) % 500 <= 2;
    assert!(
        four.iter().skip(1).all(|s| near_an_end(s.0)),
        "{four:?}: cuts at segment ends"
    );
    assert_eq!(h.slabs(slabscope::Method::BottomUp, n - 4).len(), 4);
}
