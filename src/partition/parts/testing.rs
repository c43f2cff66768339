//! What the tests of parts share: a partition counted in shuffled strips, each from a volume
//! holding its box alone, added in random groups.

use std::ops::Range;

use super::*;
use crate::testing::Lcg;
use crate::volume::{SlabGrid, Voxel, VoxelType};

/// A 24×20×28 volume of three layers along z (textured) inside a border of air (value
/// `air`), so that the automatic background leaves something out; held as `held`, its values
/// scaled by `scale`. With `scale` not 1, one voxel in five is a millionth of the rest, so that
/// float sums round, and differently in another order of the additions.
pub(crate) fn layered(held: VoxelType, air: f32, scale: f32) -> Volume {
    let dims = [24, 20, 28];
    let data = (0..dims[0] * dims[1] * dims[2])
        .map(|i| {
            let (x, y, z) = (i % 24, i / 24 % 20, i / 480);
            if x < 2 || y < 2 || x > 21 || y > 17 {
                air
            } else {
                let layer = [40.0, 120.0, 80.0][z * 3 / 28];
                let value = (layer + ((x * 7 + y * 3 + z * 5) % 11) as f32 * 2.0) * scale;
                if scale != 1.0 && (x + 2 * y + 3 * z) % 5 == 0 {
                    value * 1e-6
                } else {
                    value
                }
            }
        })
        .collect();
    Volume::new(dims, [1.0, 1.2, 0.9], held, data).unwrap()
}

/// The voxels of box `b` of `v` (dimensions `dims`), x fastest.
fn box_voxels<T: Voxel>(v: &[T], dims: [usize; 3], b: VoxelBox) -> Vec<T> {
    let mut out = Vec::with_capacity(b.len());
    for z in b.origin[2]..b.origin[2] + b.size[2] {
        for y in b.origin[1]..b.origin[1] + b.size[1] {
            let row = (z * dims[1] + y) * dims[0] + b.origin[0];
            out.extend_from_slice(&v[row..row + b.size[0]]);
        }
    }
    out
}

/// The boxes a task counting `rows` holds: the one box of their voxels, or (every other
/// time) a box a layer of planes along z, the layers random.
fn boxes_for(split: &StackSplit, v: &Volume, rows: &Range<usize>, rng: &mut Lcg) -> Vec<VoxelBox> {
    if below(rng, 2) == 0 {
        return vec![
            split
                .voxel_box(v, rows)
                .unwrap()
                .expect("rows with samples"),
        ];
    }
    let mut layers = Vec::new();
    let mut at = 0;
    while at < v.dims()[2] {
        let end = (at + 1 + below(rng, 9)).min(v.dims()[2]);
        layers.push(at..end);
        at = end;
    }
    let boxes: Vec<VoxelBox> = (split.voxel_boxes(v, rows, &layers).unwrap())
        .into_iter()
        .flatten()
        .collect();
    assert!(!boxes.is_empty(), "rows with samples");
    boxes
}

/// The volume a task counting `rows` holds: `v`'s boxes for them ([`boxes_for`]), nothing
/// else (zeros). For an f32 volume every voxel outside them is NaN instead, so that a sample
/// reading one would be missing and change the counts.
fn held_for(split: &StackSplit, v: &Volume, rows: &Range<usize>, rng: &mut Lcg) -> Volume {
    let grid = SlabGrid::of(v);
    let boxes = boxes_for(split, v, rows, rng);
    if v.voxel_type() == VoxelType::F32 {
        let mut poisoned = vec![f32::NAN; v.len()];
        for &b in &boxes {
            let inside = box_voxels(v.voxels(), v.dims(), b);
            let mut k = 0;
            for z in b.origin[2]..b.origin[2] + b.size[2] {
                for y in b.origin[1]..b.origin[1] + b.size[1] {
                    let row = (z * v.dims()[1] + y) * v.dims()[0] + b.origin[0];
                    poisoned[row..row + b.size[0]].copy_from_slice(&inside[k..k + b.size[0]]);
                    k += b.size[0];
                }
            }
        }
        let whole = VoxelBox {
            origin: [0; 3],
            size: v.dims(),
        };
        return Volume::of_box(&grid, whole, &poisoned).unwrap();
    }
    crate::volume::with_voxels!(v.data(), |data| {
        let pieces: Vec<_> = (boxes.iter())
            .map(|&b| (b, box_voxels(data, v.dims(), b)))
            .collect();
        let pieces: Vec<_> = pieces.iter().map(|(b, p)| (*b, &p[..])).collect();
        Volume::of_boxes(&grid, &pieces).unwrap()
    })
}

/// A number below `n` from `rng`.
fn below(rng: &mut Lcg, n: usize) -> usize {
    ((rng.next_u64() >> 33) % n as u64) as usize
}

/// `0..rows` cut into strips of 1 to 7 rows (fewer where the rows are few: four strips at
/// least from four rows on), in a shuffled order.
fn shuffled_strips(rng: &mut Lcg, rows: usize) -> Vec<Range<usize>> {
    let mut strips = Vec::new();
    let mut at = 0;
    let most = (rows / 4).clamp(1, 7);
    while at < rows {
        let end = (at + 1 + below(rng, most)).min(rows);
        strips.push(at..end);
        at = end;
    }
    for i in (1..strips.len()).rev() {
        strips.swap(i, below(rng, i + 1));
    }
    strips
}

/// Adds `parts` in random groups, then the groups in turn.
fn add_grouped<T>(parts: Vec<T>, rng: &mut Lcg, add: impl Fn(&mut T, T)) -> T {
    let mut groups: Vec<T> = Vec::new();
    for part in parts {
        let g = below(rng, groups.len() + 1);
        if g == groups.len() {
            groups.push(part);
        } else {
            add(&mut groups[g], part);
        }
    }
    let mut groups = groups.into_iter();
    let mut sum = groups.next().expect("a part");
    groups.for_each(|g| add(&mut sum, g));
    sum
}

/// The partition of `v` by `p` along `axis` counted in shuffled strips, each from its own box,
/// added in random groups.
pub(crate) fn in_parts(
    v: &Volume,
    axis: [f64; 3],
    p: &PartitionParams,
    background: &Background,
    rng: &mut Lcg,
) -> Partition {
    let background = background.clone();
    let none = Monitor::none();
    let split = StackSplit::new(v, axis, p).unwrap();
    let strips = shuffled_strips(rng, split.rows());
    assert!(strips.len() > 3);
    // Every other time the first pass keeps each strip's runs and the second reads them.
    let keep = below(rng, 2) == 0;
    let (counts, kept): (Vec<SliceCounts>, Vec<StripRuns>) = strips
        .iter()
        .map(|rows| {
            let held = held_for(&split, v, rows, rng);
            let (part, runs) = split
                .count_keeping(&held, &background, rows.clone(), &none)
                .unwrap();
            // Each part travels as bytes, as a task's does.
            let read = SliceCounts::from_bytes(&part.to_bytes()).unwrap();
            assert_eq!(read, part);
            (read, StripRuns::from_bytes(&runs.to_bytes()).unwrap())
        })
        .unzip();
    let counts = add_grouped(counts, rng, |a, b| a.add(b).unwrap());
    let grid = SlabGrid::of(v);
    let empty = Volume::of_box::<u8>(
        &grid,
        VoxelBox {
            origin: [0; 3],
            size: [0; 3],
        },
        &[],
    );
    let empty = empty.unwrap_or_else(|_| v.clone());
    let found = split.slabs(&empty, &background, counts, &none).unwrap();
    let joints = (found.slabs.len() > 1).then(|| {
        let slabs = &found.slabs;
        let joints = if keep {
            let joints = kept.iter().map(|runs| runs.joints(slabs, &none).unwrap());
            joints
                .map(|j| SlabJoints::from_bytes(&j.to_bytes()).unwrap())
                .collect()
        } else {
            (shuffled_strips(rng, split.rows()).iter())
                .map(|rows| {
                    let held = held_for(&split, v, rows, rng);
                    let part =
                        split.count_boundaries(&held, &background, rows.clone(), slabs, &none);
                    SlabJoints::from_bytes(&part.unwrap().to_bytes()).unwrap()
                })
                .collect()
        };
        add_grouped(joints, rng, |a, b| a.add(&b).unwrap())
    });
    split.finish(&found, joints).unwrap()
}
