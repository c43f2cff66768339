//! Tests of bottom-up merging and of the joint histograms it measures, against their literal
//! definitions.

use super::joints::consecutive_joints;
use super::*;
use crate::measure::mutual_information;
use crate::partition::stack::MISSING;

fn stack_of(slices: &[Vec<u8>], bins: usize) -> SliceStack {
    SliceStack::from_slices(slices, bins).unwrap()
}

/// The literal definition: sum the joint histograms of every pair of slices.
fn literal_joint(slices: &[Vec<u8>], a: Slab, c: Slab, bins: usize) -> Vec<u64> {
    let mut h = vec![0u64; bins * bins];
    for s in a.0..a.1 {
        for t in c.0..c.1 {
            for (&x, &y) in slices[s].iter().zip(&slices[t]) {
                if x != MISSING && y != MISSING {
                    h[usize::from(x) * bins + usize::from(y)] += 1;
                }
            }
        }
    }
    h
}

#[test]
fn slab_joint_histograms_equal_the_pairwise_definition() {
    let mut state = 7u32;
    let mut next = || {
        state = state.wrapping_mul(1_103_515_245).wrapping_add(12345);
        (state >> 16) as u8
    };
    let slices: Vec<Vec<u8>> = (0..9)
        .map(|_| {
            (0..50)
                .map(|_| if next() % 9 == 0 { MISSING } else { next() % 5 })
                .collect()
        })
        .collect();
    let stack = stack_of(&slices, 5);
    let slabs = [(0, 2), (2, 3), (3, 7), (7, 9)];
    let joints = consecutive_joints(Some(&stack), &Columns::new(&stack), &slabs);
    for (i, joint) in joints.iter().enumerate() {
        assert_eq!(
            joint,
            &literal_joint(&slices, slabs[i], slabs[i + 1], 5),
            "pair {i}"
        );
    }
}

/// Blocky values with noise: blocks of `x` voxels along x and `z` planes along z, a voxel in
/// eight raised at random (`seed`).
fn blocky(dims: [usize; 3], (x, z): (usize, usize), seed: u32) -> crate::volume::Volume {
    let mut state = seed;
    let data = (0..dims.iter().product::<usize>())
        .map(|i| {
            state = state.wrapping_mul(1_103_515_245).wrapping_add(12345);
            ((i % dims[0]) / x * 20 + (i / (dims[0] * dims[1])) / z * 30) as f32
                + if state >> 29 == 0 { 15.0 } else { 0.0 }
        })
        .collect();
    crate::volume::Volume::new(dims, [1.0; 3], crate::volume::VoxelType::F32, data).unwrap()
}

#[test]
fn oblique_columns_follow_the_pairwise_definition() {
    // Columns with both long runs and short ones, which start and end at different slices.
    let v = blocky([14, 11, 9], (5, 3), 11);
    let params = super::super::StackParams {
        sampling: crate::geometry::lattice::SamplingParams {
            bins: 8,
            ..Default::default()
        },
        ..Default::default()
    };
    let stack = SliceStack::new(&v, [1.0, 2.0, 3.0], &params, &Monitor::none()).unwrap();
    let n = stack.slices();
    let slabs = [(0, 3), (3, 4), (4, n / 2), (n / 2, n)];
    let joints = consecutive_joints(Some(&stack), &Columns::new(&stack), &slabs);
    let symbol = |p: usize, k: usize| stack.column(p, k, k + 1).1.first().copied();
    for (i, joint) in joints.iter().enumerate() {
        let mut literal = vec![0u64; 64];
        for p in 0..stack.pixels() {
            for s in slabs[i].0..slabs[i].1 {
                for t in slabs[i + 1].0..slabs[i + 1].1 {
                    if let (Some(x), Some(y)) = (symbol(p, s), symbol(p, t))
                        && x != MISSING
                        && y != MISSING
                    {
                        literal[usize::from(x) * 8 + usize::from(y)] += 1;
                    }
                }
            }
        }
        assert_eq!(joint, &literal, "pair {i}");
    }
}

#[test]
fn two_materials_merge_into_their_halves() {
    let slices: Vec<Vec<u8>> = (0..10)
        .map(|s| {
            (0..40)
                .map(|p| {
                    if s < 6 {
                        (p % 3) as u8
                    } else {
                        3 + (p % 2) as u8
                    }
                })
                .collect()
        })
        .collect();
    let h = MergeHistory::new(&stack_of(&slices, 5), &Monitor::none()).unwrap();
    assert_eq!(h.slabs(2), vec![(0, 6), (6, 10)]);
    assert_eq!(h.steps.len(), 9);
    // Identical slices have NMI 1; the last merge joins unrelated halves.
    assert!((h.steps[0].nmi - 1.0).abs() < 1e-12);
    assert!(h.steps.last().unwrap().nmi < 0.5);
    for s in &h.steps {
        assert!((0.0..=1.0).contains(&s.nmi));
    }
}

#[test]
fn nmi_matches_the_measure_on_single_slices() {
    let slices = vec![vec![0u8, 1, 2, 3, 0, 1], vec![0u8, 1, 1, 3, 0, 2]];
    let nmi = slice_nmi(&stack_of(&slices, 4), &Monitor::none()).unwrap();
    let joint = literal_joint(&slices, (0, 1), (1, 2), 4);
    let (mi, h) = mutual_information(&joint, 4, 4);
    assert!((nmi[0] - mi / h).abs() < 1e-12);
}

#[test]
fn long_columns_of_noise_give_the_pairwise_joint_histograms_from_their_checkpoints() {
    // Three pixels, 3000 slices of noise with missing samples: every column has thousands of
    // runs, so slabs of many runs are taken from checkpoints, small ones run by run.
    let mut state = 5u32;
    let mut next = || {
        state = state.wrapping_mul(1_103_515_245).wrapping_add(12345);
        (state >> 16) as u8
    };
    let slices: Vec<Vec<u8>> = (0..3000)
        .map(|_| {
            (0..3)
                .map(|_| {
                    if next() % 11 == 0 {
                        MISSING
                    } else {
                        next() % 5
                    }
                })
                .collect()
        })
        .collect();
    let stack = stack_of(&slices, 5);
    let columns = Columns::new(&stack);
    for slabs in [
        vec![(0, 1), (1, 1700), (1700, 1701), (1701, 3000)],
        vec![(5, 400), (400, 1333), (1333, 1334), (1334, 2999)],
        vec![(0, 1500), (1500, 3000)],
    ] {
        let joints = consecutive_joints(Some(&stack), &columns, &slabs);
        for (i, joint) in joints.iter().enumerate() {
            let expect = literal_joint(&slices, slabs[i], slabs[i + 1], 5);
            assert_eq!(joint, &expect, "{slabs:?}, pair {i}");
        }
    }
}

#[test]
fn the_joint_histograms_of_neighbouring_slices_follow_the_pairwise_definition() {
    // An oblique stack (columns that start and end at different slices) with a few background
    // voxels left out (missing samples); slabs of one slice each, more pairs than the threads'
    // blocks, so that the pairs are split among them.
    let v = blocky([23, 17, 29], (6, 4), 3);
    let params = super::super::StackParams {
        sampling: crate::geometry::lattice::SamplingParams {
            bins: 8,
            ..Default::default()
        },
        background: crate::volume::background::BackgroundRule::Below(0.0),
    };
    let stack = SliceStack::new(&v, [2.0, -1.0, 3.0], &params, &Monitor::none()).unwrap();
    let n = stack.slices();
    assert!(n > 30, "{n} slices");
    let singles: Vec<Slab> = (0..n).map(|s| (s, s + 1)).collect();
    let symbol = |p: usize, k: usize| stack.column(p, k, k + 1).1.first().copied();
    let literal = |s: usize| {
        let mut joint = vec![0u64; 64];
        for p in 0..stack.pixels() {
            if let (Some(x), Some(y)) = (symbol(p, s), symbol(p, s + 1))
                && x != MISSING
                && y != MISSING
            {
                joint[usize::from(x) * 8 + usize::from(y)] += 1;
            }
        }
        joint
    };
    let columns = Columns::new(&stack);
    let missing = (0..stack.pixels())
        .flat_map(|p| (0..n).map(move |s| (p, s)))
        .filter(|&(p, s)| symbol(p, s) == Some(MISSING))
        .count();
    assert!(missing > 0, "no sample left out");
    let joints = consecutive_joints(Some(&stack), &columns, &singles);
    assert_eq!(joints.len(), n - 1);
    for (s, joint) in joints.iter().enumerate() {
        assert_eq!(joint, &literal(s), "slices {s} and {}", s + 1);
    }
    // A few pairs (a merge step's) split the pixels among the threads instead.
    let joints = consecutive_joints(Some(&stack), &columns, &singles[10..13]);
    for (k, joint) in joints.iter().enumerate() {
        assert_eq!(joint, &literal(10 + k), "slices {} and {}", 10 + k, 11 + k);
    }
}
