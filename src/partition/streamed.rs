//! The partition of a volume whose slice stack does not fit in memory, at full resolution: the
//! stack is cut a strip of rows at a time and each strip's slice histograms and consecutive joint
//! histograms are added up, so that no more than one strip is held. Histograms and joint
//! histograms are sums over the pixels, so the sums are the whole stack's, exactly: the slabs,
//! gains and NMI are those of [`partition`](super::partition) of the same volume, bit for bit.
//!
//! Two passes over the volume: the first counts the slice histograms (from which the top-down
//! history and the optimum follow) and the NMI between consecutive slices; the second, once the
//! slabs are known, the joint histograms of consecutive slabs for the NMI at their boundaries.
//! The strips take half the room left beside the sums, and the first pass keeps each strip's
//! runs in the other half as far as they fit: the second reads those instead of the volume (one
//! pass over it when they all fit, as a smooth volume's do).
//! Bottom-up merging reads the stack once per merge and is not streamed.

use std::ops::Range;

use super::histories::Histories;
use super::parts::{SlabJoints, SlabsFound, SliceCounts, StackSplit};
use super::stack::Cutter;
use super::{Partition, PartitionParams};
use crate::error::{Error, Result, short_bytes};
use crate::progress::Monitor;
use crate::volume::Volume;

/// Bytes a strip takes per pixel beyond its symbols: its column entry, twice while an oblique
/// strip's rows are joined, and the run-length encoding's per-column arrays.
const PIXEL_BYTES: u64 = 96;

/// Bytes a strip takes per symbol: the symbol, and at most one run (a first slice and a symbol)
/// in the run-length encoding.
const SYMBOL_BYTES: u64 = 6;

/// The least memory a streamed partition of `volume` with `bins` bins asks for beyond what its
/// voxels hold, in bytes, along any axis: its background mask and sums, and a strip of one row, for
/// a row and a column of slices as long as the volume's diagonal in steps of its finest spacing
/// (the lattice's default). A budget below it is better spent on a coarser pyramid level.
#[must_use]
pub fn streamed_memory_floor(volume: &Volume, bins: usize) -> u64 {
    let diagonal = most_slices(volume.dims(), volume.spacing());
    let mask = volume.len() as u64 / 8;
    mask + sums_bytes(diagonal, bins as u64) + diagonal * (diagonal * SYMBOL_BYTES + PIXEL_BYTES)
}

/// The most slices a stack of a volume of `dims` voxels spaced `spacing` mm can have along any
/// axis: its diagonal in steps of its finest spacing (the lattice's default sample spacing; a
/// coordinate axis has one slice a voxel, never more).
#[must_use]
pub fn most_slices(dims: [usize; 3], spacing: [f64; 3]) -> u64 {
    let step = crate::geometry::min_spacing(spacing);
    let extent2: f64 = (0..3)
        .map(|i| (dims[i] as f64 * spacing[i] / step).powi(2))
        .sum();
    extent2.sqrt().ceil() as u64
}

/// The bytes a partition holds per slice beside its stack's columns, with `bins` bins: the
/// slice's histogram and its row of prefix sums (`bins` counts each), and its entries in the
/// per-slice curves and sums (position, sample sums and counts, NMI, gain). On a long thin
/// volume (one voxel across, 200,000 along) they, not the voxels, are most of the memory.
#[must_use]
pub fn slice_bytes(bins: usize) -> u64 {
    (2 * bins as u64 + 8) * 8
}

/// Partitions `volume` along `axis` within `max_memory` bytes of working memory (beyond the
/// voxels the volume holds), cutting its stack in strips: the same partition as
/// [`partition`](super::partition), for the top-down and optimal methods.
pub fn partition_streamed(
    volume: &Volume,
    axis: [f64; 3],
    params: &PartitionParams,
    max_memory: u64,
    monitor: &Monitor,
) -> Result<Partition> {
    partition_streamed_kept(volume, axis, params, max_memory, monitor).map(|(p, _)| p)
}

/// [`partition_streamed`], with the histories it was taken from (whose stack keeps no
/// columns: its splits and optimum can be explained, not merges).
pub fn partition_streamed_kept(
    volume: &Volume,
    axis: [f64; 3],
    params: &PartitionParams,
    max_memory: u64,
    monitor: &Monitor,
) -> Result<(Partition, Histories)> {
    let split = StackSplit::new(volume, axis, params)?;
    let cutter = Cutter::new(volume, axis, &params.stack, monitor)?;
    // Strips within half the room beside the sums where a row fits in it, the other half for the
    // runs the first pass keeps of them, which the second reads instead of cutting them again.
    let fixed = fixed_bytes(&cutter);
    let half = fixed + max_memory.saturating_sub(fixed) / 2;
    let strips = strips(&cutter, half).or_else(|_| strips(&cutter, max_memory))?;
    let widest = strips.iter().map(ExactSizeIterator::len).max().unwrap_or(0);
    let room = max_memory.saturating_sub(fixed + stack_bytes(&cutter, widest));
    let work = |strips: &mut dyn Iterator<Item = &Range<usize>>, counting| {
        strips.map(|r| cutter.work(r, counting)).sum()
    };

    monitor.start(
        "slicing in strips (pass 1 of 2)",
        work(&mut strips.iter(), true),
    );
    let mut counts = SliceCounts::new(&cutter);
    let (mut kept, mut kept_bytes) = (Vec::with_capacity(strips.len()), 0);
    for rows in &strips {
        let columns = counts.add_rows(&cutter, rows.clone(), monitor)?;
        let bytes = columns.held_bytes() as u64;
        let keep = kept_bytes + bytes <= room;
        kept_bytes += if keep { bytes } else { 0 };
        kept.push(keep.then_some(columns));
    }
    let found = SlabsFound::of(counts.into_histories(&cutter, params, monitor)?, params)?;

    let again = strips.iter().zip(&kept).filter(|(_, k)| k.is_none());
    let again: Vec<&Range<usize>> = again.map(|(r, _)| r).collect();
    let joints = if found.slabs.len() > 1 {
        monitor.start(
            "slicing in strips (pass 2 of 2)",
            work(&mut again.iter().copied(), false),
        );
        let mut joints = SlabJoints::new(&found.slabs, cutter.bins(), cutter.rows());
        for (rows, columns) in strips.iter().zip(kept) {
            match columns {
                Some(columns) => joints.add_runs(rows, &columns, monitor)?,
                None => joints.add_rows(&cutter, rows.clone(), monitor)?,
            }
        }
        Some(joints)
    } else {
        None
    };
    let mut partition = split.finish(&found, joints)?;
    partition.notes.insert(
        0,
        format!(
            "the slice stack ({}) is over the memory limit: it was counted in {}, {}",
            short_bytes(stack_bytes(&cutter, cutter.rows())),
            match strips.len() {
                1 => format!("one strip of {widest} rows"),
                n => format!("{n} strips of at most {widest} rows"),
            },
            passes(strips.len(), again.len(), found.slabs.len() > 1),
        ),
    );
    Ok((partition, found.histories))
}

/// How many passes over the volume a streamed partition of `strips` strips took, `again` of
/// them cut again by the `second` pass (the others' runs kept from the first).
fn passes(strips: usize, again: usize, second: bool) -> String {
    match (second, again) {
        (false, _) => "in one pass over the volume".into(),
        (true, 0) => "in one pass over the volume (the second read each strip's runs, kept from \
                      the first)"
            .into(),
        (true, a) if a == strips => "in two passes over the volume".into(),
        (true, a) => format!(
            "in two passes over the volume (the second over {a} of the strips, the others' runs \
             kept from the first)"
        ),
    }
}

/// The bytes a strip of `rows` rows of `cutter`'s stack takes at its peak.
fn stack_bytes(cutter: &Cutter, rows: usize) -> u64 {
    let per_row =
        cutter.row_pixels() as u64 * (cutter.slices() as u64 * SYMBOL_BYTES + PIXEL_BYTES);
    rows as u64 * per_row
}

/// The bytes a streamed partition holds beside its strips: the background mask and the sums.
fn fixed_bytes(cutter: &Cutter) -> u64 {
    cutter.background_bytes() + sums_bytes(cutter.slices() as u64, cutter.bins() as u64)
}

/// The bytes of the sums a streamed partition of `slices` slices and `bins` bins adds strips
/// into: the histograms and positions, the joint histograms of consecutive slices and the
/// per-task sums they are counted in.
fn sums_bytes(slices: u64, bins: u64) -> u64 {
    let threads = rayon::current_num_threads() as u64;
    let joints = slices.saturating_sub(1) * bins * bins * 8;
    slices * (bins + 1) * 8
        + joints
        + (threads + 2) * joints.min(super::bottom_up::PASS_BYTES as u64)
}

/// The strips of rows `cutter`'s stack is cut in so that one, with the sums it is added to, fits
/// in `max_memory` bytes.
fn strips(cutter: &Cutter, max_memory: u64) -> Result<Vec<Range<usize>>> {
    let fixed = fixed_bytes(cutter);
    let rows = cutter.rows();
    let fit = max_memory.saturating_sub(fixed) / stack_bytes(cutter, 1).max(1);
    if fit == 0 {
        return Err(Error::invalid(
            "max_memory",
            short_bytes(max_memory),
            format!(
                "room for a strip of one row of the slice stack ({} beyond the {} its sums take)",
                short_bytes(stack_bytes(cutter, 1)),
                short_bytes(fixed),
            ),
        ));
    }
    let per = (fit as usize).min(rows.max(1));
    Ok((0..rows)
        .step_by(per)
        .map(|r| r..(r + per).min(rows))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::partition::{Method, SliceStack, Stop, partition};
    use crate::volume::VoxelType;
    use crate::volume::background::BackgroundRule;

    /// A 24×20×28 volume of three layers along z (one bright, textured, one dark) inside a
    /// border of air, so that the automatic background leaves something out.
    fn layered() -> Volume {
        let dims = [24, 20, 28];
        let data = (0..dims[0] * dims[1] * dims[2])
            .map(|i| {
                let (x, y, z) = (i % 24, i / 24 % 20, i / 480);
                if x < 2 || y < 2 || x > 21 || y > 17 {
                    0.0
                } else {
                    let layer = [40.0, 120.0, 80.0][z * 3 / 28];
                    layer + ((x * 7 + y * 3 + z * 5) % 11) as f32 * 2.0
                }
            })
            .collect();
        Volume::new(dims, [1.0, 1.2, 0.9], VoxelType::U8, data).unwrap()
    }

    fn params(method: Method, background: BackgroundRule) -> PartitionParams {
        let mut p = PartitionParams {
            method,
            stop: Stop::Slabs(3),
            ..PartitionParams::default()
        };
        p.stack.background = background;
        p
    }

    /// Strips of one or two rows: the budget of the sums and one strip of `rows` rows.
    fn budget(volume: &Volume, axis: [f64; 3], p: &PartitionParams, rows: usize) -> u64 {
        let cutter = Cutter::new(volume, axis, &p.stack, &Monitor::none()).unwrap();
        let one = strips(&cutter, u64::MAX).unwrap();
        assert_eq!(one.len(), 1, "an unbounded budget cuts one strip");
        assert!(strips(&cutter, fixed_bytes(&cutter)).is_err());
        fixed_bytes(&cutter) + stack_bytes(&cutter, rows)
    }

    #[test]
    fn a_stack_counted_in_strips_gives_the_whole_stacks_partition() {
        let v = layered();
        for axis in [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.3, 0.5, 0.8]] {
            for background in [BackgroundRule::Auto, BackgroundRule::None] {
                for method in [Method::TopDown, Method::Optimal] {
                    let p = params(method, background);
                    let whole_stack =
                        SliceStack::new(&v, axis, &p.stack, &Monitor::none()).unwrap();
                    let expected = partition(&v, axis, &p, &Monitor::none()).unwrap();
                    let json = |p: &Partition| {
                        let mut p = p.clone();
                        p.notes.clear();
                        serde_json::to_string(&p).unwrap()
                    };
                    // Room for strips of one row alone (the second pass cutting each again),
                    // for strips of one row and some of their runs (which the second pass reads
                    // instead), and for the whole stack twice (one strip, its runs kept).
                    let cutter = Cutter::new(&v, axis, &p.stack, &Monitor::none()).unwrap();
                    let all = 2 * cutter.rows();
                    for (rows, strips_of, passes) in [
                        (
                            1,
                            "strips of at most 1 rows",
                            "in two passes over the volume",
                        ),
                        (2, "strips of at most 1 rows", "(the second over "),
                        (
                            all,
                            "one strip of ",
                            "in one pass over the volume (the second read",
                        ),
                    ] {
                        let budget = budget(&v, axis, &p, rows);
                        let got =
                            partition_streamed(&v, axis, &p, budget, &Monitor::none()).unwrap();
                        let note = &got.notes[0];
                        assert!(note.contains(strips_of) && note.contains(passes), "{note}");
                        assert!(rows == 1 || !note.ends_with("volume"), "{note}");
                        assert_eq!(got.slices, whole_stack.slices());
                        assert_eq!(
                            json(&got),
                            json(&expected),
                            "{axis:?} {background:?} {method:?} {rows}"
                        );
                        assert_eq!(got.background, expected.background);
                    }
                }
            }
        }
    }

    #[test]
    fn bottom_up_and_a_budget_without_room_for_a_row_are_errors() {
        let v = layered();
        let axis = [0.0, 0.0, 1.0];
        let p = params(Method::BottomUp, BackgroundRule::None);
        let e = partition_streamed(&v, axis, &p, u64::MAX, &Monitor::none()).unwrap_err();
        assert!(e.to_string().contains("bottom-up"), "{e}");
        let p = params(Method::TopDown, BackgroundRule::None);
        let e = partition_streamed(&v, axis, &p, 1000, &Monitor::none()).unwrap_err();
        assert!(e.to_string().contains("one row"), "{e}");
    }
}
