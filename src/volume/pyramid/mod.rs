//! The multiresolution pyramid (docs/design.md §5): pyramid level k + 1 halves every axis of level
//! k longer than one voxel (or, where a store's own pyramid keeps an axis, the axes it halves),
//! each coarse voxel the mean of the (up to) 2×2×2 finite voxels under it, or for label volumes
//! their most frequent label (ties: the lowest).

use rayon::prelude::*;

mod levels;

pub use levels::{Finest, LevelSource};
pub(super) use levels::{Pyramid, empty};

use super::voxels::Voxel;
use crate::error::{Error, Result};
use crate::geometry::WorldTransform;

/// The fewest voxels along every axis that `auto` keeps.
pub const AUTO_MIN_VOXELS: usize = 128;

/// Which pyramid level to compute on: every voxel, the coarsest level that keeps
/// [`AUTO_MIN_VOXELS`] along every axis, or a level by number.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Resolution {
    /// Level 0: every voxel (the paper's method, and the default).
    #[default]
    Full,
    /// The coarsest level with at least [`AUTO_MIN_VOXELS`] voxels along every axis (level 0
    /// when an axis has fewer at full resolution).
    Auto,
    /// Pyramid level K (a store's K-th dataset when the pyramid is the store's).
    Level(usize),
}

impl std::str::FromStr for Resolution {
    type Err = Error;

    fn from_str(text: &str) -> Result<Self> {
        match text {
            "full" => Ok(Self::Full),
            "auto" => Ok(Self::Auto),
            _ => text.parse().map(Self::Level).map_err(|_| {
                Error::invalid("resolution", text, "auto, full or a pyramid level number")
            }),
        }
    }
}

impl Resolution {
    /// The pyramid level this resolution picks for a volume whose levels have the dimensions
    /// `chain` (its own first, then each coarser level's); a level number past the last is an
    /// error.
    pub fn level(self, chain: &[[usize; 3]]) -> Result<usize> {
        let levels = chain.len().saturating_sub(1);
        match self {
            Self::Full => Ok(0),
            Self::Auto => Ok(chain
                .iter()
                .skip(1)
                .take_while(|d| d.iter().all(|&n| n >= AUTO_MIN_VOXELS))
                .count()),
            Self::Level(k) if k <= levels => Ok(k),
            Self::Level(k) => Err(Error::invalid(
                "resolution",
                k,
                format!(
                    "a pyramid level from 0 to {levels} (each level halves every axis, or the \
                     axes a store's own levels halve)"
                ),
            )),
        }
    }
}

/// The finest of the pyramid levels whose dimensions are `chain` (level 0's first) with at most
/// `voxels` voxels (the last, when no other has so few).
#[must_use]
pub fn level_within(chain: &[[usize; 3]], voxels: usize) -> usize {
    chain
        .iter()
        .position(|d| d.iter().product::<usize>() <= voxels)
        .unwrap_or(chain.len().saturating_sub(1))
}

/// The steps of the pyramid of a level 0 of `dims` that halves every axis longer than one voxel
/// level after level, after the steps `first` (a store's own), until every axis is one voxel.
#[must_use]
pub fn steps_after(dims: [usize; 3], first: &[[usize; 3]]) -> Vec<[usize; 3]> {
    let mut steps = first.to_vec();
    let mut d = first.iter().fold(dims, |d, &s| coarser_dims_by(d, s));
    while d.iter().any(|&n| n > 1) {
        steps.push(step(d));
        d = coarser_dims(d);
    }
    steps
}

/// The dimensions of a level of `dims` and of each level the steps `steps` make from it.
#[must_use]
pub fn chain_dims(dims: [usize; 3], steps: &[[usize; 3]]) -> Vec<[usize; 3]> {
    let mut chain = vec![dims];
    for &s in steps {
        chain.push(coarser_dims_by(chain[chain.len() - 1], s));
    }
    chain
}

/// The dimensions of the level `step` (per axis 1 or 2) makes of a level of `dims`.
#[must_use]
pub fn coarser_dims_by(dims: [usize; 3], step: [usize; 3]) -> [usize; 3] {
    std::array::from_fn(|m| dims[m].div_ceil(step[m]))
}

/// The dimensions of the next pyramid level: every axis longer than one voxel halved, rounding up.
#[must_use]
pub fn coarser_dims(dims: [usize; 3]) -> [usize; 3] {
    dims.map(|n| n.div_ceil(2))
}

/// Per axis, how many fine voxels one voxel of the next level spans: 2, or 1 along an axis of
/// one voxel (which is not halved).
#[must_use]
pub fn step(dims: [usize; 3]) -> [usize; 3] {
    dims.map(|n| if n > 1 { 2 } else { 1 })
}

/// The voxel-to-world transform of a level whose voxels span `factor` voxels of level 0 per
/// axis: level 0's transform composed with that scale and a shift of `(factor - 1) / 2` voxels,
/// so each coarse voxel sits at the centre of the fine voxels it averages (a block cut by the far
/// edge averages fewer, and its centre may lie up to half a coarse voxel off its grid point).
#[must_use]
pub fn level_transform(t: &WorldTransform, factor: [f64; 3]) -> WorldTransform {
    let mut matrix = t.matrix;
    for (row, fine) in matrix.iter_mut().zip(t.matrix) {
        row[3] = fine[3]
            + (0..3)
                .map(|k| fine[k] * (factor[k] - 1.0) / 2.0)
                .sum::<f64>();
        for k in 0..3 {
            row[k] = fine[k] * factor[k];
        }
    }
    WorldTransform {
        matrix,
        known: t.known,
    }
}

/// The next pyramid level of the voxels `fine` (x fastest, dimensions `dims`), every axis
/// longer than one voxel halved: [`downsample_by`] with [`step`].
#[must_use]
pub fn downsample<T: Voxel>(fine: &[T], dims: [usize; 3], labels: bool) -> (Vec<f32>, [usize; 3]) {
    downsample_by(fine, dims, step(dims), labels)
}

/// The level `step` (per axis 1, kept, or 2, halved) makes of the voxels `fine` (x fastest,
/// dimensions `dims`): block means of the finite voxels, or with `labels` their most frequent
/// value (ties: the lowest); NaN where a block has no finite voxel. Returns the voxels and their
/// dimensions.
#[must_use]
pub fn downsample_by<T: Voxel>(
    fine: &[T],
    dims: [usize; 3],
    step: [usize; 3],
    labels: bool,
) -> (Vec<f32>, [usize; 3]) {
    debug_assert_eq!(fine.len(), dims.iter().product::<usize>());
    debug_assert!(step.iter().all(|s| (1..=2).contains(s)));
    let coarse = coarser_dims_by(dims, step);
    let [sx, sy, sz] = step;
    let [nx, ny, nz] = dims;
    let plane = coarse[0] * coarse[1];
    // Integers are never missing, and their sums in f64 are exact in any order.
    let whole = !labels && T::TYPE != super::VoxelType::F32;
    let mut out = vec![0.0f32; plane * coarse[2]];
    out.par_chunks_mut(plane).enumerate().for_each(|(k, out)| {
        let mut block = [0.0f32; 8];
        let mut sums = vec![0i32; if whole { coarse[0] } else { 0 }];
        for (j, out) in out.chunks_exact_mut(coarse[0]).enumerate() {
            // The (up to) four fine rows under this coarse row, z then y.
            let mut rows: [&[T]; 4] = [&[]; 4];
            let mut count = 0;
            for z in k * sz..(k * sz + sz).min(nz) {
                for y in j * sy..(j * sy + sy).min(ny) {
                    rows[count] = &fine[nx * (y + ny * z)..][..nx];
                    count += 1;
                }
            }
            let rows = &rows[..count];
            if whole {
                whole_means(rows, sx, &mut sums, out);
                continue;
            }
            for (i, o) in out.iter_mut().enumerate() {
                let xs = i * sx..(i * sx + sx).min(nx);
                let mut n = 0;
                for &v in rows.iter().flat_map(|r| &r[xs.clone()]) {
                    if !v.is_missing() {
                        block[n] = v.to_f32();
                        n += 1;
                    }
                }
                *o = if labels {
                    mode(&mut block[..n])
                } else {
                    mean(&block[..n])
                };
            }
        }
    });
    (out, coarse)
}

/// The means of integer voxels' blocks under one coarse row: the fine `rows` under it (z then
/// y) summed a row at a time into `sums` (one a coarse voxel, pairs of voxels along x when `sx`
/// is 2, the last alone when the row is odd), then each sum over its block's voxels. Integer
/// sums are the same in any order, and adding whole rows lets the compiler vectorize them (with
/// AVX2 where the processor has it), where summing each block apart did not (docs/performance.md).
fn whole_means<T: Voxel>(rows: &[&[T]], sx: usize, sums: &mut [i32], out: &mut [f32]) {
    super::wide::wide(|| row_sums(rows, sx, sums));
    let nx = rows.first().map_or(0, |r| r.len());
    for (i, (o, &sum)) in out.iter_mut().zip(sums.iter()).enumerate() {
        let voxels = rows.len() * ((i * sx + sx).min(nx) - i * sx);
        *o = (f64::from(sum) / voxels as f64) as f32;
    }
}

/// The sums of [`whole_means`], always inlined so that `wide` compiles them for AVX2 too.
#[allow(clippy::inline_always)] // out of line, they ran the baseline's code (seen in a profile)
#[inline(always)]
fn row_sums<T: Voxel>(rows: &[&[T]], sx: usize, sums: &mut [i32]) {
    let value = |v: &T| v.integer().unwrap_or(0);
    sums.fill(0);
    for row in rows {
        if sx == 1 {
            for (s, v) in sums.iter_mut().zip(row.iter()) {
                *s += value(v);
            }
            continue;
        }
        let pairs = row.chunks_exact(2);
        if let ([.., last], [odd]) = (&mut *sums, pairs.remainder()) {
            *last += value(odd);
        }
        for (s, pair) in sums.iter_mut().zip(pairs) {
            *s += value(&pair[0]) + value(&pair[1]);
        }
    }
}

/// The level the steps `steps` make of the voxels `fine` (x fastest, dimensions `dims`),
/// exactly as one call of [`downsample_by`] a step would give it, but in one streaming pass:
/// each coarse slice is made from the fine slices under it alone, so no intermediate level is
/// ever held whole.
#[must_use]
pub fn downsample_times<T: Voxel>(
    fine: &[T],
    dims: [usize; 3],
    labels: bool,
    steps: &[[usize; 3]],
) -> (Vec<f32>, [usize; 3]) {
    match steps {
        [] => return (fine.iter().map(|v| v.to_f32()).collect(), dims),
        [s] => return downsample_by(fine, dims, *s, labels),
        _ => {}
    }
    let chain = chain_dims(dims, steps);
    let coarse = chain[steps.len()];
    let plane = coarse[0] * coarse[1];
    let fine_plane = dims[0] * dims[1];
    let mut out = vec![0.0f32; plane * coarse[2]];
    out.par_chunks_mut(plane)
        .enumerate()
        .for_each(|(j, slice)| {
            let (a, b) = fine_slices(steps, &chain, j);
            let (mut values, mut d) = downsample_by(
                &fine[a * fine_plane..b * fine_plane],
                [dims[0], dims[1], b - a],
                steps[0],
                labels,
            );
            for &s in &steps[1..] {
                (values, d) = downsample_by(&values, d, s, labels);
            }
            debug_assert_eq!(d, [coarse[0], coarse[1], 1]);
            slice.copy_from_slice(&values);
        });
    (out, coarse)
}

/// The level-0 slices `[a, b)` under slice `j` of the last level of `chain` (the dimensions of
/// level 0 and of each level the steps `steps` make after it).
fn fine_slices(steps: &[[usize; 3]], chain: &[[usize; 3]], j: usize) -> (usize, usize) {
    let (mut a, mut b) = (j, j + 1);
    for (s, d) in steps.iter().zip(chain).rev() {
        (a, b) = (a * s[2], (b * s[2]).min(d[2]));
    }
    (a, b)
}

/// The mean of `values` (summed in f64), NaN when there are none.
fn mean(values: &[f32]) -> f32 {
    if values.is_empty() {
        return f32::NAN;
    }
    (values.iter().map(|&v| f64::from(v)).sum::<f64>() / values.len() as f64) as f32
}

/// The most frequent of `values`, the lowest among equally frequent ones; NaN when there are none.
fn mode(values: &mut [f32]) -> f32 {
    values.sort_unstable_by(f32::total_cmp);
    let mut best = (0, f32::NAN);
    let mut run = 0;
    for (i, &v) in values.iter().enumerate() {
        run = if i > 0 && values[i - 1] == v {
            run + 1
        } else {
            1
        };
        // Strictly more: the first (lowest) value to reach a count keeps it.
        if run > best.0 {
            best = (run, v);
        }
    }
    best.1
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    use crate::volume::{Volume, VoxelType};

    /// The dimensions of every level of the pyramid that halves every axis, from `dims`.
    fn halving(dims: [usize; 3]) -> Vec<[usize; 3]> {
        chain_dims(dims, &steps_after(dims, &[]))
    }

    #[test]
    fn resolutions_pick_levels() {
        let parse = |t: &str| t.parse::<Resolution>().unwrap();
        assert_eq!(parse("full").level(&halving([512; 3])).unwrap(), 0);
        assert_eq!(parse("auto").level(&halving([512; 3])).unwrap(), 2, "128³");
        assert_eq!(parse("auto").level(&halving([256, 256, 415])).unwrap(), 1);
        assert_eq!(parse("auto").level(&halving([181, 217, 181])).unwrap(), 0);
        assert_eq!(parse("auto").level(&halving([512, 512, 45])).unwrap(), 0);
        assert_eq!(parse("3").level(&halving([512; 3])).unwrap(), 3);
        assert!(parse("10").level(&halving([512; 3])).is_err());
        assert!("coarse".parse::<Resolution>().is_err());
    }

    #[test]
    fn streaming_levels_equal_level_after_level() {
        // Odd sizes, an axis that runs out early, missing voxels and labels.
        for (dims, labels) in [([13, 6, 11], false), ([9, 7, 3], false), ([10, 5, 9], true)] {
            let n: usize = dims.iter().product();
            let fine: Vec<f32> = (0..n)
                .map(|i| match (labels, i % 17) {
                    (false, 5) => f32::NAN,
                    (false, _) => (i * 31 % 97) as f32 * 0.37,
                    (true, _) => (i * 7 % 5) as f32,
                })
                .collect();
            // Every axis halved, and a store's steps that keep z, then x, before halving all.
            let halved = steps_after(dims, &[]);
            let kept = steps_after(dims, &[[2, 2, 1], [1, 2, 2], [2, 2, 1]]);
            for steps in [halved, kept] {
                let (mut chained, mut d) = (fine.clone(), dims);
                for times in 1..=5.min(steps.len()) {
                    (chained, d) = downsample_by(&chained, d, steps[times - 1], labels);
                    let (streamed, sd) = downsample_times(&fine, dims, labels, &steps[..times]);
                    assert_eq!(sd, d, "{dims:?} level {times}");
                    let same = streamed
                        .iter()
                        .zip(&chained)
                        .all(|(a, b)| a.to_bits() == b.to_bits());
                    assert!(same, "{dims:?} level {times} {steps:?}");
                }
            }
        }
    }

    #[test]
    fn a_kept_axis_is_not_averaged() {
        // 2×2×2 halved in y and x only: two slices, each the mean of its four voxels.
        let fine: Vec<f32> = (0..8).map(|i| i as f32).collect();
        let (c, dims) = downsample_by(&fine, [2, 2, 2], [2, 2, 1], false);
        assert_eq!((c, dims), (vec![1.5, 5.5], [1, 1, 2]));
        assert_eq!(
            steps_after([8, 8, 3], &[[2, 2, 1]]),
            vec![[2, 2, 1], [2, 2, 2], [2, 2, 2]],
            "then every axis halved: 4×4×3, 2×2×2, 1×1×1"
        );
        let chain = chain_dims([8, 8, 3], &steps_after([8, 8, 3], &[[2, 2, 1]]));
        assert_eq!(chain, vec![[8, 8, 3], [4, 4, 3], [2, 2, 2], [1, 1, 1]]);
        assert_eq!(Resolution::Auto.level(&chain).unwrap(), 0);
        assert_eq!(level_within(&chain, 48), 1, "4×4×3 is 48 voxels");
    }

    #[test]
    fn the_finest_level_within_a_voxel_count() {
        assert_eq!(level_within(&halving([512; 3]), 1 << 21), 2, "128³ is 2²¹");
        assert_eq!(level_within(&halving([1024; 3]), 1 << 21), 3);
        assert_eq!(
            level_within(&halving([256, 256, 415]), 1 << 21),
            2,
            "128×128×208 is more"
        );
        assert_eq!(level_within(&halving([128; 3]), 1 << 21), 0);
        assert_eq!(
            level_within(&halving([5, 1, 1]), 0),
            3,
            "the top: one voxel"
        );
    }

    #[test]
    fn means_of_whole_and_edge_blocks() {
        // 3x2x1: x pairs (0,1) and the edge block (2) alone; z is one voxel and stays.
        let fine = [1u8, 2, 9, 3, 4, 7];
        let (c, dims) = downsample(&fine, [3, 2, 1], false);
        assert_eq!(dims, [2, 1, 1]);
        assert_eq!(c, vec![2.5, 8.0]);
        assert_eq!(step([3, 2, 1]), [2, 2, 1]);
    }

    #[test]
    fn blocks_of_eight_and_missing_voxels() {
        let mut fine: Vec<f32> = (0..8).map(|i| i as f32).collect();
        let (c, _) = downsample(&fine, [2, 2, 2], false);
        assert_eq!(c, vec![3.5]);
        fine[7] = f32::NAN;
        assert_eq!(
            downsample(&fine, [2, 2, 2], false).0,
            vec![3.0],
            "NaN skipped"
        );
        let all_missing = [f32::NAN; 8];
        assert!(downsample(&all_missing, [2, 2, 2], false).0[0].is_nan());
    }

    #[test]
    fn labels_take_the_mode_and_the_lowest_on_ties() {
        let fine = [5u16, 5, 5, 2, 2, 2, 9, 9];
        assert_eq!(
            downsample(&fine, [2, 2, 2], true).0,
            vec![2.0],
            "3 fives, 3 twos: the lowest"
        );
        let fine = [4i16, 4, 4, 1, 1, 7, 7, 7];
        assert_eq!(downsample(&fine, [2, 2, 2], true).0, vec![4.0]);
        let fine = [3i16, 8, 8, 3, 3, 1, 1, 8];
        assert_eq!(downsample(&fine, [2, 2, 2], true).0, vec![3.0]);
    }

    #[test]
    fn exact_block_means_on_a_ramp() {
        let dims = [5, 4, 3];
        let fine: Vec<i16> = (0..60).map(|i| (i * 7 % 23) as i16 - 11).collect();
        let (c, cd) = downsample(&fine, dims, false);
        assert_eq!(cd, [3, 2, 2]);
        for k in 0..2 {
            for j in 0..2 {
                for i in 0..3 {
                    let mut vals = vec![];
                    for z in 2 * k..(2 * k + 2).min(3) {
                        for y in 2 * j..2 * j + 2 {
                            for x in 2 * i..(2 * i + 2).min(5) {
                                vals.push(f64::from(fine[x + 5 * (y + 4 * z)]));
                            }
                        }
                    }
                    let m = (vals.iter().sum::<f64>() / vals.len() as f64) as f32;
                    assert_eq!(c[i + 3 * (j + 2 * k)], m, "({i}, {j}, {k})");
                }
            }
        }
    }

    #[test]
    fn coarse_voxels_sit_at_the_centre_of_their_block() {
        let fine = WorldTransform::ras(
            [[0.0, 0.0, 2.0], [-1.5, 0.0, 0.0], [0.0, 1.0, 0.0]],
            [10.0, 20.0, 30.0],
        );
        let coarse = level_transform(&fine, [2.0, 2.0, 4.0]);
        // Coarse (0,0,0) is the mean of fine (0..2, 0..2, 0..4): its centre is (0.5, 0.5, 1.5).
        let expect = fine.apply([0.5, 0.5, 1.5]);
        let got = coarse.apply([0.0, 0.0, 0.0]);
        let far = fine.apply([2.5, 4.5, 5.5]);
        let got_far = coarse.apply([1.0, 2.0, 1.0]);
        for m in 0..3 {
            assert!((expect[m] - got[m]).abs() < 1e-12);
            assert!((far[m] - got_far[m]).abs() < 1e-12);
        }
        assert!(coarse.known);
    }

    #[test]
    fn pyramid_levels_are_block_means_on_a_coarser_grid() {
        let data: Vec<f32> = (0..60).map(|i| ((i * 7) % 23) as f32).collect();
        let v = Volume::new([5, 4, 3], [1.0, 2.0, 0.5], VoxelType::U8, data.clone())
            .unwrap()
            .with_transform(WorldTransform::ras(
                [[1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 0.5]],
                [3.0, 4.0, 5.0],
            ));
        let c = v.coarser(1);
        assert_eq!(c.dims(), [3, 2, 2]);
        assert_eq!(c.spacing(), [2.0, 4.0, 1.0]);
        assert_eq!(c.voxels(), downsample(&data, [5, 4, 3], false).0);
        let level = c.level();
        assert_eq!((level.index, level.factor), (1, [2, 2, 2]));
        assert_eq!(level.range, [v.stats().min, v.stats().max]);
        assert_eq!(
            c.quantizer(32).unwrap(),
            v.quantizer(32).unwrap(),
            "level 0's range"
        );
        let centre = v.transform().apply([0.5, 0.5, 0.5]);
        assert_eq!(c.transform().apply([0.0; 3]), centre);
        let top = v.coarser(v.coarser_levels());
        assert_eq!(top.dims(), [1, 1, 1]);
        assert_eq!(v.coarser_levels(), 3, "5 → 3 → 2 → 1");
        assert!(Arc::ptr_eq(&v.coarser(2), &v.coarser(2)), "built once");
    }

    #[test]
    fn a_level_built_at_once_is_the_level_built_step_by_step() {
        let data: Vec<f32> = (0..9 * 6 * 5).map(|i| ((i * 13) % 31) as f32).collect();
        let make = || Volume::new([9, 6, 5], [0.5, 1.0, 3.0], VoxelType::I16, data.clone());
        let (direct, stepwise) = (make().unwrap(), make().unwrap());
        let at_once = direct.coarser(3);
        let mut step = Arc::new(stepwise.clone());
        for _ in 0..3 {
            step = step.coarser(1);
        }
        assert_eq!(at_once.dims(), [2, 1, 1]);
        assert_eq!(at_once.voxels(), step.voxels());
        assert_eq!(at_once.spacing(), [4.0, 8.0, 24.0]);
        assert_eq!(at_once.level(), step.level());
        assert_eq!(at_once.level().factor, [8, 8, 8]);
        assert_eq!(at_once.transform(), step.transform());
        // Levels of a level are the volume's: level 1's next is level 2, shared.
        assert!(Arc::ptr_eq(
            &stepwise.coarser(2),
            &stepwise.coarser(1).coarser(1)
        ));
        assert_eq!(direct.coarser(2).voxels(), stepwise.coarser(2).voxels());
        assert_eq!(
            direct.coarser(99).dims(),
            [1, 1, 1],
            "past the top: the top"
        );
    }

    #[test]
    fn label_volumes_take_the_most_frequent_label() {
        // Two labels in halves along z, one voxel of the other in a block: the block keeps its
        // majority, never a mean.
        let mut data: Vec<f32> = (0..8 * 8 * 8)
            .map(|i| if i < 256 { 1.0 } else { 7.0 })
            .collect();
        data[0] = 7.0;
        let v = Volume::new([8, 8, 8], [1.0; 3], VoxelType::U8, data).unwrap();
        assert!(v.labels().is_some());
        let c = v.coarser(1);
        assert!(c.level().labels);
        assert_eq!(c.voxels()[0], 1.0);
        assert!(c.voxels().iter().all(|&x| x == 1.0 || x == 7.0));
        assert_eq!(c.labels(), v.labels(), "level 0's labels");
    }

    #[test]
    fn integer_blocks_average_as_the_float_blocks_do() {
        // Odd dims give edge blocks of 1, 2, 4 and 8 voxels; the integer path sums in integers.
        let dims = [7, 5, 3];
        let ints: Vec<i16> = (0..7 * 5 * 3)
            .map(|i: i32| ((i * 7919) % 2001 - 1000) as i16)
            .collect();
        let floats: Vec<f32> = ints.iter().map(|&v| f32::from(v)).collect();
        // Every axis halved, and each kept in turn (x kept: the rows are summed voxel by voxel).
        for step in [[2, 2, 2], [1, 2, 2], [2, 1, 2], [2, 2, 1], [1, 1, 2]] {
            let (a, da) = downsample_by(&ints, dims, step, false);
            let (b, db) = downsample_by(&floats, dims, step, false);
            assert_eq!(da, db);
            assert_eq!(
                a.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                b.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                "{step:?}"
            );
        }
    }
}
