use super::*;
use crate::progress::Monitor;
use crate::testing::Lcg;
use crate::view::rate::tests::{awkward_volume_of as awkward_volume, holed_below};
use crate::volume::{SlabGrid, VoxelType};

/// Cell planes `0..cells` cut at random into slabs.
pub(crate) fn random_slabs(cells: usize, lcg: &mut Lcg) -> Vec<Range<usize>> {
    let mut cuts = vec![0];
    while *cuts.last().unwrap() < cells {
        let last = *cuts.last().unwrap();
        let len = 1 + (lcg.next_u64() >> 33) as usize % 9;
        cuts.push((last + len).min(cells));
    }
    cuts.windows(2).map(|w| w[0]..w[1]).collect()
}

/// The volume holding only the voxel planes a slab of cell planes `planes` reads.
pub(crate) fn slab_of(v: &Volume, rounds: &ViewRounds, planes: &Range<usize>) -> Volume {
    let [nx, ny, nz] = v.dims();
    let held = rounds.voxel_planes(planes, nz);
    crate::volume::with_voxels!(v.data(), |d| {
        Volume::of_slab(
            &SlabGrid::of(v),
            held.start,
            &d[held.start * nx * ny..held.end * nx * ny],
        )
    })
    .unwrap()
}

/// The parts of `round` over `slabs`, counted apart and added in a shuffled order.
fn added(
    rounds: &ViewRounds,
    v: &Volume,
    round: &ViewRound,
    slabs: &[Range<usize>],
    lcg: &mut Lcg,
) -> Vec<PartialCounts> {
    let mut parts: Vec<_> = slabs
        .iter()
        .map(|p| {
            rounds
                .count_slab(&slab_of(v, rounds, p), round, p.clone())
                .unwrap()
        })
        .collect();
    for i in (1..parts.len()).rev() {
        parts.swap(i, (lcg.next_u64() >> 33) as usize % (i + 1));
    }
    let mut sum = rounds.zero(v, round).unwrap();
    for part in parts {
        // Each part travels as bytes, as between a cluster's processes.
        for (s, p) in sum.iter_mut().zip(part) {
            // A slab's pieces come in key order: they are never sorted again.
            assert!(p.fragments().is_sorted_by_key(|f| (f.key, f.start)));
            let bytes = p.to_bytes();
            let back = PartialCounts::from_bytes(&bytes).unwrap();
            assert_eq!(back.to_bytes(), bytes);
            for cut in [0, 7, 8, bytes.len() - 8] {
                assert!(PartialCounts::from_bytes(&bytes[..cut]).is_err());
            }
            s.add(back);
        }
    }
    sum
}

#[test]
fn parts_of_slabs_added_in_any_order_are_the_search_bit_for_bit() {
    let mut lcg = Lcg::new(44);
    for (dims, spacing, voxel_type) in [
        ([30, 26, 41], [1.0, 1.0, 1.0], VoxelType::U8),
        ([28, 20, 33], [0.8, 0.8, 1.7], VoxelType::F32),
        ([24, 31, 19], [1.0, 1.2, 1.0], VoxelType::I16),
    ] {
        let v = awkward_volume(dims, spacing, voxel_type, 4);
        for params in [ViewParams::paper(), ViewParams::default()] {
            let expect = super::super::search(&v, &params, &Monitor::none()).unwrap();
            let expect = serde_json::to_string(&expect).unwrap();
            let slabs = random_slabs(dims[2] - 1, &mut lcg);
            assert!(slabs.len() > 2);
            // Each slab's rounds made from its own volume, as a task makes them.
            let whole = ViewRounds::new(&v, &params).unwrap();
            let rounds = ViewRounds::new(&slab_of(&v, &whole, &slabs[1]), &params).unwrap();
            let paper = added(&rounds, &v, &ViewRound::Paper, &slabs, &mut lcg);
            let shifted = match rounds.shifted_after(&v, &ViewRound::Paper, &paper).unwrap() {
                Some(next) => added(&rounds, &v, &next, &slabs, &mut lcg),
                None => Vec::new(),
            };
            let got = rounds.finish(&v, &paper, &shifted).unwrap();
            assert_eq!(serde_json::to_string(&got).unwrap(), expect, "{dims:?}");
            // A slab left out is an error, not another answer.
            let short = added(&rounds, &v, &ViewRound::Paper, &slabs[1..], &mut lcg);
            let e = rounds.finish(&v, &short, &shifted).unwrap_err();
            assert!(e.to_string().contains("unjoined"), "{e}");
        }
    }
}

/// With few bins a small volume's shifted lattices walk one block of rays in 12, guessed before
/// the paper's samples are counted and counted in the paper round; missing voxels prove the
/// guess wrong for some axes, whose shifted lattices alone a second round counts: the search's
/// result either way.
#[test]
fn the_phases_counted_in_the_paper_round_are_the_search() {
    let mut lcg = Lcg::new(4442);
    let mut params = ViewParams::default();
    params.sampling.bins = 4;
    let v = awkward_volume([32, 32, 32], [1.0, 0.9, 1.3], VoxelType::I16, 5);
    let mut seconds = Vec::new();
    for volume in [&v, &holed_below(&v, 15), &holed_below(&v, 20)] {
        let expect = super::super::search(volume, &params, &Monitor::none()).unwrap();
        let expect = serde_json::to_string(&expect).unwrap();
        let rounds = ViewRounds::new(volume, &params).unwrap();
        assert!(!rounds.foresees_shifted(volume).unwrap());
        let slabs = random_slabs(31, &mut lcg);
        let paper = added(&rounds, volume, &ViewRound::Paper, &slabs, &mut lcg);
        // Each axis's paper lattice and its seven guessed phases.
        assert_eq!(paper.len(), 8 * rounds.axes.len());
        let next = rounds
            .shifted_after(volume, &ViewRound::Paper, &paper)
            .unwrap();
        let shifted = match &next {
            Some(next) => added(&rounds, volume, next, &slabs, &mut lcg),
            None => Vec::new(),
        };
        seconds.push(shifted.len());
        let got = rounds.finish(volume, &paper, &shifted).unwrap();
        assert_eq!(serde_json::to_string(&got).unwrap(), expect);
    }
    // No second round; the seven phases of an axis guessed wrong alone; of every axis.
    let every = 7 * ViewRounds::new(&v, &params).unwrap().axes.len();
    assert_eq!(seconds, [0, 7, every]);
}

#[test]
fn the_refinement_in_parts_is_the_search_bit_for_bit() {
    let mut lcg = Lcg::new(4444);
    let v = awkward_volume([26, 22, 29], [1.0, 0.9, 1.2], VoxelType::U8, 4);
    for params in [ViewParams::paper(), ViewParams::default()] {
        let params = ViewParams {
            refine: true,
            ..params
        };
        let expect = super::super::search(&v, &params, &Monitor::none()).unwrap();
        assert!(expect.refined.is_some());
        let slabs = random_slabs(28, &mut lcg);
        let rounds = ViewRounds::new(&v, &params).unwrap();
        let paper = added(&rounds, &v, &ViewRound::Paper, &slabs, &mut lcg);
        let shifted = match rounds.shifted_after(&v, &ViewRound::Paper, &paper).unwrap() {
            Some(next) => added(&rounds, &v, &next, &slabs, &mut lcg),
            None => Vec::new(),
        };
        let sphere = rounds.finish(&v, &paper, &shifted).unwrap();
        assert!(sphere.refined.is_none());
        let mut kinds = Vec::new();
        let got = rounds
            .refine(&v, sphere, |round| {
                kinds.push(round.kind());
                Ok(added(&rounds, &v, round, &slabs, &mut lcg))
            })
            .unwrap();
        let json = |s: &ViewSearch| serde_json::to_string(s).unwrap();
        assert_eq!(json(&got), json(&expect));
        // Rounds of a step: the paper's lattices, then (with phases) the shifted ones.
        let step: &[u8] = if rounds.has_shifted() { &[2, 3] } else { &[2] };
        assert!(kinds.len() >= 2 * step.len(), "{kinds:?}");
        assert!(kinds.chunks(step.len()).all(|c| c == step), "{kinds:?}");
    }
    // Without refine, the search is as it was and nothing more is counted.
    let rounds = ViewRounds::new(&v, &ViewParams::paper()).unwrap();
    let slabs_of_all = random_slabs(28, &mut lcg);
    let paper = added(&rounds, &v, &ViewRound::Paper, &slabs_of_all, &mut lcg);
    let sphere = rounds.finish(&v, &paper, &[]).unwrap();
    let expect = serde_json::to_string(&sphere).unwrap();
    let got = rounds.refine(&v, sphere, |_| unreachable!()).unwrap();
    assert_eq!(serde_json::to_string(&got).unwrap(), expect);
}

#[test]
fn slabs_off_the_grid_are_refused() {
    let v = awkward_volume([20, 20, 20], [1.0; 3], VoxelType::U8, 4);
    let rounds = ViewRounds::new(&v, &ViewParams::paper()).unwrap();
    for planes in [5..5, 10..20] {
        let e = rounds
            .count_slab(&v, &ViewRound::Paper, planes)
            .unwrap_err();
        assert!(e.to_string().contains("0..19"), "{e}");
    }
}

/// Bytes that no writer made are refused, never read into counts that would overflow or
/// tables whose codes repeat; parts of another binning are refused when they are added up.
#[test]
fn hostile_or_foreign_parts_are_refused() {
    let mut counts = BlockCounts::new(4, 3);
    let mut run = crate::measure::Run::default();
    for s in [0, 1, 2, 3, 0, 1] {
        crate::measure::Counter::push_to(&mut counts, &mut run, s);
    }
    let bytes = PartialCounts::of(counts, 1, Vec::new()).to_bytes();
    let words: Vec<u64> = bytes
        .chunks_exact(8)
        .map(|c| u64::from_le_bytes(c.try_into().unwrap()))
        .collect();
    // MAGIC, bins, block, then the long table: its length and (code, count) pairs.
    assert!(words[3] >= 2, "{words:?}");
    let with = |edit: &dyn Fn(&mut Vec<u64>)| {
        let mut w = words.clone();
        edit(&mut w);
        let b: Vec<u8> = w.iter().flat_map(|x| x.to_le_bytes()).collect();
        PartialCounts::from_bytes(&b).err().unwrap_or_default()
    };
    assert!(with(&|w| w[6] = w[4]).contains("out of order or repeated"));
    assert!(with(&|w| w[5] = u64::MAX).contains("more blocks than any volume holds"));
    let v = awkward_volume([12, 10, 9], [1.0; 3], VoxelType::U8, 4);
    let params = ViewParams {
        phases: 0,
        ..ViewParams::default()
    };
    let rounds = ViewRounds::new(&v, &params).unwrap();
    let paper = rounds.zero(&v, &ViewRound::Paper).unwrap();
    let foreign = vec![PartialCounts::new(8, 3); paper.len()];
    let e = rounds.finish(&v, &foreign, &[]);
    assert!(e.is_err_and(|e| e.to_string().contains("other bins")));
}
