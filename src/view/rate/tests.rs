//! Tests of the walks: every walk counts what the scalar walk counts, and axis-aligned rates
//! equal brute-force counts over voxel columns.

use super::*;
use crate::geometry::lattice::FIXED_BITS;
use crate::geometry::min_spacing;
use crate::measure::{PartialCounts, block_entropies};
use crate::testing::Lcg;
use crate::volume::Volume;
use crate::volume::{VoxelType, Voxels};

fn random_volume(dims: [usize; 3], levels: u32, seed: u64) -> Volume {
    let mut lcg = Lcg::new(seed);
    let data = (0..dims.iter().product::<usize>())
        .map(|_| ((lcg.next_u64() >> 33) % u64::from(levels)) as f32)
        .collect();
    Volume::new(dims, [1.0; 3], VoxelType::U8, data).unwrap()
}

#[test]
fn axis_aligned_rate_equals_a_brute_force_count_over_columns() {
    let v = random_volume([7, 6, 9], 5, 3);
    let q = v.quantizer(4).unwrap();
    let bins: Vec<u8> = v.voxels().iter().map(|&x| q.bin(x).unwrap()).collect();
    let [nx, ny, nz] = v.dims();
    let idx = |x: usize, y: usize, z: usize| x + nx * (y + ny * z);
    let columns = |axis: usize| -> Vec<Vec<u8>> {
        match axis {
            0 => (0..ny * nz)
                .map(|r| (0..nx).map(|x| bins[idx(x, r % ny, r / ny)]).collect())
                .collect(),
            1 => (0..nx * nz)
                .map(|r| (0..ny).map(|y| bins[idx(r % nx, y, r / nx)]).collect())
                .collect(),
            _ => (0..nx * ny)
                .map(|r| (0..nz).map(|z| bins[idx(r % nx, r / nx, z)]).collect())
                .collect(),
        }
    };
    for (axis, d) in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
        .into_iter()
        .enumerate()
    {
        for block in 2..=4 {
            let lattice = Lattice::at_voxel_spacing(v.dims(), v.spacing(), d).unwrap();
            let sampler = BinSampler::new(&v, q);
            let got = entropy_rate(&sampler, &lattice, block, &Monitor::none()).unwrap();
            let cols = columns(axis);
            let (h1, hs, hl) = block_entropies(cols.iter().map(Vec::as_slice), 4, block);
            assert!(
                (got.entropy_rate - (hl - hs)).abs() < 1e-12,
                "axis {axis} L {block}"
            );
            assert!((got.h1 - h1).abs() < 1e-12);
            assert_eq!(got.samples, v.len() as u64);
            assert_eq!(got.rays, cols.len() as u64);
        }
    }
}

/// The scalar tile walk of the rays `subset` keeps: what the other walks are held to.
fn one_by_one(subset: RaySubset) -> (Walk, RaySubset) {
    (
        Walk::Tiles {
            vector: Vector::Off,
        },
        subset,
    )
}

/// A noisy volume with blocks, bins at their edges and missing voxels.
fn awkward_volume(dims: [usize; 3], spacing: [f64; 3], seed: u64) -> Volume {
    awkward_volume_of(dims, spacing, VoxelType::F32, seed)
}

/// A noisy volume of blocks for the walks' tests: `(x/3 + y/4 + z/5) mod 7` times ten, noise of
/// up to 2.8 (f32, in steps of 0.7, so that values fall on bin edges) or 4 (integers), and a
/// missing voxel in about 97 where `voxel_type` is f32; held in `voxel_type` itself, so that
/// the walks read it as a volume of that type is read.
pub(in crate::view) fn awkward_volume_of(
    dims: [usize; 3],
    spacing: [f64; 3],
    voxel_type: VoxelType,
    seed: u64,
) -> Volume {
    let float = voxel_type == VoxelType::F32;
    let mut lcg = Lcg::new(seed);
    let data = (0..dims.iter().product::<usize>())
        .map(|i| {
            let r = (lcg.next_u64() >> 33) as u32;
            let (x, y, z) = (
                i % dims[0],
                (i / dims[0]) % dims[1],
                i / (dims[0] * dims[1]),
            );
            let noise = (r % 5) as f32 * if float { 0.7 } else { 1.0 };
            if float && r.is_multiple_of(97) {
                f32::NAN
            } else {
                ((x / 3 + y / 4 + z / 5) % 7) as f32 * 10.0 + noise
            }
        })
        .collect();
    let held = Voxels::narrowed(data, voxel_type);
    Volume::from_voxels(dims, spacing, voxel_type, held).unwrap()
}

/// `volume` as f32 with its voxel planes below `z` missing (NaN): fewer samples than its box
/// holds.
pub(in crate::view) fn holed_below(volume: &Volume, z: usize) -> Volume {
    let [nx, ny, nz] = volume.dims();
    let data = (0..nx * ny * nz)
        .map(|i| match [i % nx, i / nx % ny, i / (nx * ny)] {
            [_, _, k] if k < z => f32::NAN,
            at => volume.value(at),
        })
        .collect();
    Volume::new(volume.dims(), volume.spacing(), VoxelType::F32, data).unwrap()
}

#[test]
fn every_walk_counts_what_the_scalar_walk_counts() {
    // Whatever the processor: without AVX2 the vector runs take the scalar walk.
    let (mut samples, mut columns) = (0, 0);
    for (dims, spacing) in [
        ([23, 19, 31], [1.0, 1.0, 1.0]),
        ([40, 9, 17], [0.7, 1.3, 2.1]),
        ([1, 20, 20], [1.0, 1.0, 1.0]),
    ] {
        let v = awkward_volume(dims, spacing, 11);
        for (bins, block) in [(32, 3), (8, 4), (5, 2), (200, 3)] {
            let sampler = BinSampler::new(&v, v.quantizer(bins).unwrap());
            for axis in [
                [0.0, 0.0, 1.0],
                [1.0, 0.0, 0.0],
                [0.3, -0.5, 0.81],
                [1.0, 1.0, 1.0],
            ] {
                for (phase, along) in [
                    ([0.0; 3], 1.0),
                    ([0.0, 2.0, 0.0], 0.9),
                    ([0.31, 0.77, 0.5], 1.0),
                ] {
                    let s = min_spacing(v.spacing());
                    let lattice =
                        Lattice::new(dims, v.spacing(), axis, s, s * along, phase).unwrap();
                    let none = Monitor::none();
                    let walk = |walk| {
                        let (counts, rays) = counts_with(
                            &sampler,
                            &lattice,
                            block,
                            (&none, 1),
                            (walk, RaySubset::ALL),
                        )?;
                        Ok::<_, crate::error::Error>(AxisEntropy::new(lattice.d, &counts, rays))
                    };
                    let scalar = walk(Walk::Fastest).unwrap();
                    let at = format!("{dims:?} {bins} bins, L {block}, {axis:?} {phase:?}");
                    // The scalar walk, and both compilations of the eight-lane walk where the
                    // processor has them.
                    for vector in [Vector::Off, Vector::Avx2, Vector::Widest] {
                        let counted = walk(Walk::Tiles { vector }).unwrap();
                        assert_eq!(counted, scalar, "{vector:?} {at}");
                    }
                    // Bricks of one cell, ragged ones, and one larger than the volume.
                    for (size, shaped) in [(1, false), (5, false), (8, true), (64, false)] {
                        let bricked = walk(Walk::Bricks { size, shaped }).unwrap();
                        assert_eq!(bricked, scalar, "bricks of {size} ({shaped}): {at}");
                    }
                    columns += usize::from(lattice.columns().is_some());
                    samples += scalar.samples;
                }
            }
        }
    }
    assert!(samples > 1_000_000, "{samples} samples compared");
    assert!(columns >= 12, "{columns} column walks compared");
}

#[test]
fn one_ray_at_a_time_counts_what_the_walks_count() {
    // The lesson's strip of samples is the walk's: every ray's bins, counted, give the tables.
    for (dims, spacing) in [
        ([23, 19, 31], [1.0, 1.0, 1.0]),
        ([40, 9, 17], [0.7, 1.3, 2.1]),
    ] {
        let v = awkward_volume(dims, spacing, 5);
        let sampler = BinSampler::new(&v, v.quantizer(32).unwrap());
        for axis in [[0.0, 0.0, 1.0], [0.3, -0.5, 0.81], [1.0, 1.0, 1.0]] {
            let s = min_spacing(v.spacing());
            let lattice = Lattice::new(dims, v.spacing(), axis, s, s, [0.0; 3]).unwrap();
            let (walked, rays) = block_counts(&sampler, &lattice, 3, &Monitor::none()).unwrap();
            let mut one = BlockCounts::new(32, 3);
            let ((i0, i1), (j0, j1)) = lattice.ray_ranges();
            let mut met = 0;
            for (i, j) in (i0..=i1).flat_map(|i| (j0..=j1).map(move |j| (i, j))) {
                let Some(bins) = ray_bins(&sampler, &lattice, i, j) else {
                    continue;
                };
                met += 1;
                for b in bins {
                    match b {
                        Some(b) => one.push(b),
                        None => one.end_sequence(),
                    }
                }
                one.end_sequence();
            }
            assert_eq!(met, rays, "{dims:?} {axis:?}");
            assert_eq!(one.table(3), walked.table(3), "{dims:?} {axis:?}");
            assert_eq!(one.table(2), walked.table(2), "{dims:?} {axis:?}");
            assert_eq!(one.table(1), walked.table(1), "{dims:?} {axis:?}");
            assert!(walked.blocks() > 1000);
        }
    }
}

#[test]
fn missing_voxels_break_sequences() {
    let mut data = vec![1.0f32; 27];
    data[13] = f32::NAN; // the centre
    data[0] = 0.0;
    let v = Volume::new([3, 3, 3], [1.0; 3], VoxelType::F32, data).unwrap();
    let q = v.quantizer(2).unwrap();
    let lattice = Lattice::at_voxel_spacing(v.dims(), v.spacing(), [0.0, 0.0, 1.0]).unwrap();
    let r = entropy_rate(&BinSampler::new(&v, q), &lattice, 2, &Monitor::none()).unwrap();
    assert_eq!(r.samples, 26);
}

#[test]
fn bricks_counted_apart_in_random_groups_add_up_to_the_whole() {
    let mut lcg = Lcg::new(17);
    let mut next = move |n: usize| (lcg.next_u64() >> 33) as usize % n.max(1);
    let mut open = 0;
    for (dims, spacing, size) in [
        ([23, 19, 31], [1.0, 1.0, 1.0], 6),
        ([40, 9, 17], [0.7, 1.3, 2.1], 4),
        ([1, 20, 20], [1.0, 1.0, 1.0], 3),
        ([9, 2, 12], [1.0, 1.0, 1.0], 2),
    ] {
        let v = awkward_volume(dims, spacing, 23);
        for (bins, block) in [(32, 3), (8, 4), (5, 2)] {
            let sampler = BinSampler::new(&v, v.quantizer(bins).unwrap());
            for (axis, phase) in [
                ([0.0, 0.0, 1.0], [0.0; 3]),
                ([0.3, -0.5, 0.81], [0.0; 3]),
                ([1.0, 1.0, 1.0], [0.31, 0.77, 0.5]),
                ([-0.2, 0.9, 0.1], [0.5, 0.0, 0.25]),
            ] {
                let s = min_spacing(v.spacing());
                let lattice = Lattice::new(dims, v.spacing(), axis, s, s, phase).unwrap();
                let (whole, rays) =
                    block_counts(&sampler, &lattice, block, &Monitor::none()).unwrap();
                let grid = Bricks::new(dims, size);
                // The bricks shuffled and dealt into random groups, each counted apart.
                let mut order: Vec<usize> = (0..grid.len()).collect();
                for i in (1..order.len()).rev() {
                    order.swap(i, next(i + 1));
                }
                let groups = 1 + next(order.len().min(7));
                let mut sets = vec![Vec::new(); groups];
                for b in order {
                    sets[next(groups)].push(b);
                }
                let mut parts: Vec<PartialCounts> = sets
                    .iter()
                    .map(|set| counts_of_bricks(&sampler, &lattice, block, grid, set))
                    .collect();
                let at = format!("{dims:?} bricks of {size}, {bins} bins, L {block}, {axis:?}");
                open += parts.iter().map(|p| p.fragments().len()).sum::<usize>();
                let mut total = PartialCounts::new(bins, block);
                while !parts.is_empty() {
                    total.add(parts.swap_remove(next(parts.len())));
                }
                assert!(total.is_complete(), "{at}");
                assert_eq!(total.rays, rays, "{at}");
                for k in [1, block - 1, block] {
                    assert_eq!(total.counts.table(k), whole.table(k), "{k}-blocks, {at}");
                }
            }
        }
    }
    assert!(open > 10_000, "{open} pieces of rays stitched");
}

/// The cell planes `0..cells` in slabs of `slab` planes, in a shuffled order.
fn shuffled_slabs(cells: usize, slab: usize, lcg: &mut Lcg) -> Vec<std::ops::Range<usize>> {
    let mut slabs: Vec<std::ops::Range<usize>> = (0..cells)
        .step_by(slab)
        .map(|z| z..(z + slab).min(cells))
        .collect();
    for k in (1..slabs.len()).rev() {
        slabs.swap(k, (lcg.next_u64() % (k as u64 + 1)) as usize);
    }
    slabs
}

/// The rays of `lattice` (those `subset` keeps) counted slab by slab in the order of `slabs`,
/// each from a window of the map holding its planes alone, in the bricks `bricks_of` gives it:
/// by one sweep holding the open rays, and by every slab apart with its pieces (in key order)
/// added. Checks that neither leaves a piece open; returns both totals' rates.
fn slab_by_slab(
    v: &Volume,
    q: crate::volume::Quantizer,
    lattice: &Lattice,
    subset: RaySubset,
    slabs: Vec<std::ops::Range<usize>>,
    bricks_of: impl Fn(&std::ops::Range<usize>) -> Bricks,
) -> [AxisEntropy; 2] {
    let (mut sweep, mut apart) = (PartialCounts::new(16, 3), PartialCounts::new(16, 3));
    let mut open = OpenRays::new(lattice);
    for planes in slabs {
        let window = BinSampler::window(v.voxels(), v, q, planes.clone());
        let (bricks, z) = (bricks_of(&planes), planes.start as i64..planes.end as i64);
        let walk = |open: &mut OpenRays| {
            count_slab_into(&window, lattice, 3, bricks, (z.clone(), subset), open)
        };
        sweep.add(walk(&mut open));
        let mut alone = OpenRays::new(lattice);
        let part = walk(&mut alone);
        let pieces = alone.into_fragments();
        assert!(pieces.is_sorted_by_key(|f| (f.key, f.start)));
        apart.add(PartialCounts::of(part.counts, part.rays, pieces));
    }
    assert!(open.is_empty(), "{:?}: rays left open", lattice.d);
    assert!(apart.is_complete(), "{:?}: pieces left apart", lattice.d);
    [sweep, apart].map(|total| AxisEntropy::new(lattice.d, &total.counts, total.rays))
}

#[test]
fn slabs_counted_apart_from_windows_of_the_map_add_up_to_the_whole() {
    // Each slab walked with a sampler holding its planes' cells alone; the slabs added in a
    // shuffled order: every table and the ray count of the tile walk, with and without subsets.
    let mut lcg = Lcg::new(21);
    let mut compared = 0;
    for (dims, spacing) in [
        ([23, 19, 31], [1.0, 1.0, 1.0]),
        ([40, 9, 17], [0.7, 1.3, 2.1]),
        ([12, 11, 1], [1.0, 1.0, 1.0]),
        ([9, 8, 2], [1.0, 1.0, 0.5]),
    ] {
        let v = awkward_volume(dims, spacing, 5);
        let q = v.quantizer(16).unwrap();
        let whole = BinSampler::new(&v, q);
        let cells = dims[2].saturating_sub(1).max(1);
        for axis in [
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 0.0],
            [0.3, -0.5, 0.81],
            [1.0, 1.0, -1.0],
        ] {
            let s = min_spacing(v.spacing());
            let lattice = Lattice::new(dims, v.spacing(), axis, s, s, [0.31, 0.77, 0.5]).unwrap();
            for subset in [
                RaySubset::ALL,
                RaySubset {
                    every: 3,
                    offset: 1,
                },
            ] {
                let none = Monitor::none();
                let (counts, rays) =
                    counts_with(&whole, &lattice, 3, (&none, 1), one_by_one(subset)).unwrap();
                let expect = AxisEntropy::new(lattice.d, &counts, rays);
                for (slab, brick) in [(1, 1), (2, 1), (5, 5), (6, 3), (64, 64)] {
                    let bricks = Bricks::shaped(dims, [4, 7, brick]);
                    let slabs = shuffled_slabs(cells, slab, &mut lcg);
                    let totals = slab_by_slab(&v, q, &lattice, subset, slabs, |_| bricks);
                    for got in totals {
                        assert_eq!(got, expect, "{dims:?} {axis:?} {subset:?} slabs of {slab}");
                    }
                    compared += 1;
                }
            }
        }
    }
    assert_eq!(compared, 4 * 4 * 2 * 5);
}

#[test]
fn slabs_walked_whole_count_what_the_tile_walk_counts() {
    // A slab one brick of whole planes (as the parts and the streamed search make them) is
    // walked as one stretch a ray: slabs of 1 to 7 planes and more than the volume, steps of
    // more than a plane along z (a ray steps over a thin slab), rays along z and lying in
    // planes, missing voxels, subsets; each slab apart, added in a shuffled order, and a sweep.
    let mut lcg = Lcg::new(44);
    let (mut compared, mut rows) = (0, 0);
    for (dims, spacing, sample) in [
        ([17, 13, 29], [1.0, 1.0, 1.0], 1.0),
        ([11, 9, 23], [0.7, 1.3, 0.4], 1.1),
        ([8, 7, 2], [1.0, 1.0, 1.0], 1.0),
    ] {
        let v = awkward_volume(dims, spacing, 7);
        let q = v.quantizer(16).unwrap();
        let whole = BinSampler::new(&v, q);
        let cells = dims[2] - 1;
        // Rays along x and y on the voxel rows (counted as the columns' walk counts them where
        // the spacing is even), and oblique ones.
        let (on_grid, off) = ([0.0; 3], [0.4, 0.1, 0.6]);
        for (axis, rays, phase) in [
            ([1.0, 0.0, 0.0], 1.0, on_grid),
            ([0.0, 1.0, 0.0], 1.0, on_grid),
            ([0.0, 0.0, 1.0], 0.9, off),
            ([0.6, 0.8, 0.0], 0.9, off),
            ([0.3, -0.5, 0.81], 0.9, off),
            ([0.2, 0.1, -0.97], 0.9, off),
        ] {
            let lattice = Lattice::new(dims, spacing, axis, rays, sample, phase).unwrap();
            rows += usize::from(lattice.columns().is_some());
            for subset in [
                RaySubset::ALL,
                RaySubset {
                    every: 2,
                    offset: 1,
                },
            ] {
                let none = Monitor::none();
                let tiles = Walk::Tiles {
                    vector: Vector::Widest,
                };
                let (counts, rays) =
                    counts_with(&whole, &lattice, 3, (&none, 1), (tiles, subset)).unwrap();
                let expect = AxisEntropy::new(lattice.d, &counts, rays);
                for slab in [1, 2, 3, 7, 64] {
                    let slabs = shuffled_slabs(cells, slab, &mut lcg);
                    let whole_planes = |planes: &std::ops::Range<usize>| {
                        Bricks::shaped_from(dims, [dims[0], dims[1], planes.len()], planes.start)
                    };
                    let totals = slab_by_slab(&v, q, &lattice, subset, slabs, whole_planes);
                    for got in totals {
                        assert_eq!(got, expect, "{dims:?} {axis:?} {subset:?} slabs of {slab}");
                    }
                    compared += 1;
                }
            }
        }
    }
    assert_eq!(compared, 3 * 6 * 2 * 5);
    assert_eq!(rows, 4);
}

#[test]
fn a_window_of_the_map_answers_every_sample_as_the_whole_map() {
    let v = awkward_volume([14, 13, 12], [1.0; 3], 8);
    for bins in [4, 32] {
        let q = v.quantizer(bins).unwrap();
        let whole = BinSampler::new(&v, q);
        let window = BinSampler::window(v.voxels(), &v, q, 4..7);
        assert_eq!(window.cells().len(), 14 * 13 * 3);
        assert_eq!(window.cells_base(), 14 * 13 * 4);
        let mut lcg = Lcg::new(bins as u64);
        for _ in 0..20_000 {
            // Anywhere inside the volume, its far faces included.
            let p: [i64; 3] = std::array::from_fn(|m| {
                let last = [13u64, 12, 11][m];
                (lcg.next_u64() % ((last << FIXED_BITS) + 1)) as i64
            });
            assert_eq!(window.bin_fixed(p), whole.bin_fixed(p), "{p:?}");
            let voxel = p.map(|c| c >> FIXED_BITS << FIXED_BITS);
            assert_eq!(window.voxel_bin(voxel), whole.voxel_bin(voxel), "{voxel:?}");
        }
    }
}

#[test]
fn a_subsets_rows_are_the_rays_it_keeps_in_order() {
    let mut rng = Lcg::new(12);
    for _ in 0..4000 {
        let every = 1 + rng.next_u64() % 20;
        let subset = RaySubset {
            every,
            offset: rng.next_u64() % (every + 3),
        };
        let j = (rng.next_u64() % 400) as i64 - 200;
        let a = (rng.next_u64() % 400) as i64 - 200;
        let b = a + (rng.next_u64() % 120) as i64 - 10;
        let kept: Vec<i64> = (a..=b).filter(|&i| subset.keeps(i, j)).collect();
        let row: Vec<i64> = subset.row(j, (a, b)).collect();
        assert_eq!(row, kept, "{subset:?} j {j} {a}..={b}");
    }
}

#[test]
fn phases_walked_together_count_what_each_walks_alone() {
    // An axis's shifted lattices (one step, offsets apart), each keeping one block of rays in
    // `every`, walked tile by tile together and each alone by the scalar tile walk.
    let mut blocks = 0;
    for (dims, spacing, voxel_type) in [
        ([61, 47, 38], [1.0, 1.0, 1.0], VoxelType::F32),
        ([44, 70, 29], [0.8, 1.1, 1.9], VoxelType::I16),
    ] {
        let v = awkward_volume_of(dims, spacing, voxel_type, 5);
        blocks += crate::volume::with_voxels!(v.data(), |d| phases_agree(d, &v));
    }
    assert!(blocks > 100_000, "{blocks} blocks compared");
}

/// Whether the shifted lattices of a few axes walked together over `voxels` (those of `v`)
/// count what each walks alone; returns the blocks compared.
fn phases_agree<T: Voxel>(voxels: &[T], v: &Volume) -> u64 {
    let (dims, mut blocks) = (v.dims(), 0);
    let sampler = BinSampler::over(voxels, v, v.quantizer(32).unwrap());
    let s = min_spacing(v.spacing());
    for axis in [[0.0, 0.0, 1.0], [0.3, -0.5, 0.81], [1.0, 1.0, 1.0]] {
        for every in [12, 3, 1] {
            let phases = [[0.5, 0.5, 0.5], [0.13, 0.71, 0.2], [0.9, 0.05, 0.66]];
            let lattices: Vec<Lattice> = phases
                .iter()
                .map(|&p| Lattice::new(dims, v.spacing(), axis, s, s, p).unwrap())
                .collect();
            let kept: Vec<(&Lattice, RaySubset)> = lattices
                .iter()
                .enumerate()
                .map(|(n, l)| {
                    let offset = n as u64 + 1;
                    (l, RaySubset { every, offset })
                })
                .collect();
            let last = std::sync::Mutex::new(0.0);
            let report = |p: crate::progress::Progress| *last.lock().unwrap() = p.fraction;
            let monitor = Monitor::new(None, Some(&report));
            monitor.start("test", 1000);
            let together = entropy_rates_of(&sampler, &kept, 3, (&monitor, 1000)).unwrap();
            assert_eq!(*last.lock().unwrap(), 1.0, "every unit reported");
            for (&(l, subset), got) in kept.iter().zip(&together) {
                let none = Monitor::none();
                let walk = one_by_one(subset);
                let (counts, rays) = counts_with(&sampler, l, 3, (&none, 1), walk).unwrap();
                let alone = AxisEntropy::new(l.d, &counts, rays);
                assert_eq!(*got, alone, "{dims:?} {axis:?} one in {every}");
                assert!(got.blocks > 0, "{dims:?} {axis:?}: a lattice with blocks");
                blocks += got.blocks;
            }
        }
    }
    blocks
}

#[test]
fn phases_walked_together_slab_by_slab_count_what_each_walks_alone() {
    // An axis's shifted lattices swept slab by slab together (whole planes, and bricks smaller
    // than a slab), each lattice's parts added: its tile walk's counts, nothing left open.
    let mut lcg = Lcg::new(8);
    let v = awkward_volume([61, 47, 38], [1.0, 1.0, 1.0], 5);
    let q = v.quantizer(16).unwrap();
    let whole = BinSampler::new(&v, q);
    let dims = v.dims();
    for axis in [[0.0, 0.0, 1.0], [0.3, -0.5, 0.81]] {
        for every in [12, 3] {
            let phases = [[0.5, 0.5, 0.5], [0.13, 0.71, 0.2], [0.9, 0.05, 0.66]];
            let lattices: Vec<Lattice> = (phases.iter())
                .map(|&p| Lattice::new(dims, v.spacing(), axis, 1.0, 1.0, p).unwrap())
                .collect();
            let kept: Vec<(&Lattice, RaySubset)> = (lattices.iter().enumerate())
                .map(|(n, l)| {
                    (
                        l,
                        RaySubset {
                            every,
                            offset: n as u64 + 1,
                        },
                    )
                })
                .collect();
            for (slab, whole_planes) in [(5, true), (12, false), (40, true)] {
                let mut opens: Vec<OpenRays> = lattices.iter().map(OpenRays::new).collect();
                let mut totals: Vec<PartialCounts> =
                    lattices.iter().map(|_| PartialCounts::new(16, 3)).collect();
                for planes in shuffled_slabs(dims[2] - 1, slab, &mut lcg) {
                    let window = BinSampler::window(v.voxels(), &v, q, planes.clone());
                    let bricks = if whole_planes {
                        Bricks::shaped_from(dims, [dims[0], dims[1], planes.len()], planes.start)
                    } else {
                        Bricks::shaped(dims, [9, 7, slab])
                    };
                    let z = planes.start as i64..planes.end as i64;
                    let mut each: Vec<&mut OpenRays> = opens.iter_mut().collect();
                    let parts = count_slabs_into(&window, &kept, 3, (bricks, z), &mut each);
                    for (total, part) in totals.iter_mut().zip(parts) {
                        total.add(part);
                    }
                }
                for ((&(l, subset), total), open) in kept.iter().zip(&totals).zip(&opens) {
                    let none = Monitor::none();
                    let walk = one_by_one(subset);
                    let (counts, rays) = counts_with(&whole, l, 3, (&none, 1), walk).unwrap();
                    let at = format!("{axis:?} one in {every}, slabs of {slab}");
                    assert_eq!(total.rays, rays, "{at}");
                    let got = AxisEntropy::new(l.d, &total.counts, total.rays);
                    assert_eq!(got, AxisEntropy::new(l.d, &counts, rays), "{at}");
                    assert!(got.blocks > 0 && open.is_empty(), "{at}");
                }
            }
        }
    }
}
