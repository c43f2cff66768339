//! The whole analysis of one volume, as `analyze`, the TUI's export and triage run it: the most
//! structured view (paper §3.1, §4), then the slabs along it (paper §5).

mod gain;
mod parts;
mod plan;

use std::sync::Arc;

pub(crate) use parts::analyze_planned_with;
pub use parts::{analyze_with_partition, analyze_with_views, partition_axis};

pub use gain::{
    AGREE_DEGREES, AxisBy, AxisGain, GainRanking, GainSampling, MAX_EVERY, MIN_PIXELS,
    THRESHOLD_SLABS, gain_slabs, rank_by_gain, ranking_every,
};
pub use plan::Plan;

use crate::error::Result;
use crate::explain::{Explain, StepsShown};
use crate::geometry::AxisChoice;
use crate::partition::{
    Histories, Method, Partition, PartitionParams, StackParams, Stop, partition, partition_kept,
    partition_streamed, partition_streamed_kept,
};
use crate::progress::Monitor;
use crate::view::{ViewParams, ViewSearch};
use crate::volume::background::BackgroundRule;
use crate::volume::{Volume, VoxelType};

/// What to analyse and how. The sampling (bins and spacings) is stated once, in `view`, and used
/// by the slicing too.
#[derive(Clone, Debug, PartialEq)]
pub struct AnalysisParams {
    /// The view search's parameters.
    pub view: ViewParams,
    /// The axis to partition along.
    pub axis: AxisChoice,
    /// Run the view search even when `axis` is given.
    pub search_views: bool,
    /// The partition method.
    pub method: Method,
    /// When to stop splitting or merging.
    pub stop: Stop,
    /// The background, left out of every slab histogram.
    pub background: BackgroundRule,
    /// Which ranking picks the axis (when no axis is given).
    pub axis_by: AxisBy,
    /// Rank the axes by partition gain even when the entropy rate picks the axis.
    pub gain: bool,
    /// Keep the numbers behind the axis and these steps ([`crate::explain`]).
    pub explain: Option<StepsShown>,
}

impl Default for AnalysisParams {
    fn default() -> Self {
        Self {
            view: ViewParams::default(),
            axis: AxisChoice::Best,
            search_views: false,
            method: Method::TopDown,
            stop: Stop::Slabs(4),
            background: BackgroundRule::Auto,
            axis_by: AxisBy::Entropy,
            gain: false,
            explain: None,
        }
    }
}

impl AnalysisParams {
    /// The paper's method: the view search on one lattice per axis, every voxel counted.
    pub fn paper() -> Self {
        Self {
            view: ViewParams::paper(),
            background: BackgroundRule::None,
            ..Self::default()
        }
    }

    /// How the slices are cut: the view search's sampling, and the background.
    pub fn stack(&self) -> StackParams {
        StackParams {
            sampling: self.view.sampling,
            background: self.background,
        }
    }

    /// The partition's parameters.
    pub fn partition(&self) -> PartitionParams {
        PartitionParams {
            method: self.method,
            stop: self.stop,
            stack: self.stack(),
        }
    }

    /// Whether the view search runs: the gain ranking's views are its views.
    pub fn runs_search(&self) -> bool {
        self.axis == AxisChoice::Best || self.search_views || self.ranks_by_gain()
    }

    /// The view search's work on a volume of `dims` and `spacing`, as a multiple of the
    /// default parameters' on the same volume: axes on the sphere, samples per axis (the
    /// lattice's spacings), lattices per axis (the shifted phases walk a subset of their rays)
    /// and the refinement's evaluations. A rough count, to warn of a request that will take long
    /// before it starts; 0 when no view search runs.
    pub fn work_ratio(&self, dims: [usize; 3], spacing: [f64; 3]) -> f64 {
        let work = |view: &ViewParams| {
            let axes = crate::view::icosphere::axes(view.level).len() as f64;
            let (x, y, _) = view
                .sampling
                .spacings(dims, spacing)
                .unwrap_or((1.0, 1.0, 1.0));
            let s = crate::geometry::min_spacing(spacing);
            let samples = (s / x).powi(2) * (s / y);
            let phases = 1.0 + view.phases.saturating_sub(1) as f64 / view.phase_subset as f64;
            let refine = if view.refine {
                crate::view::refine_evaluations(view.level) as f64
            } else {
                0.0
            };
            (axes + refine) * samples * phases
        };
        if self.runs_search() {
            work(&self.view) / work(&ViewParams::default())
        } else {
            0.0
        }
    }

    /// The words of a view search that asks for at least [`HEAVY_WORK`] times the default's
    /// work on a volume of `dims` and `spacing`, to say before it starts: `this view search asks
    /// for about 263 times the default's work (icosphere level 4, 64 phases, refinement on)`;
    /// `None` for a lighter one.
    pub fn heavy_work(&self, dims: [usize; 3], spacing: [f64; 3]) -> Option<String> {
        let ratio = self.work_ratio(dims, spacing);
        (ratio >= HEAVY_WORK).then(|| {
            format!(
                "this view search asks for about {ratio:.0} times the default's work (icosphere \
                 level {}, {} phases, refinement {})",
                self.view.level,
                self.view.phases,
                if self.view.refine { "on" } else { "off" },
            )
        })
    }

    /// Whether the axes are ranked by partition gain.
    pub fn ranks_by_gain(&self) -> bool {
        self.gain || self.axis_by == AxisBy::Gain
    }
}

/// A view search asking for this many times the default's work is announced before it starts
/// ([`AnalysisParams::heavy_work`]).
pub const HEAVY_WORK: f64 = 50.0;

/// The result of an analysis.
#[derive(Clone, Debug)]
pub struct Analysis {
    /// The view search, when it ran (each axis with its partition gain when that ranking ran;
    /// [`GainRanking::sorted`] gives them in that ranking's order).
    pub views: Option<ViewSearch>,
    /// The ranking by partition gain, when asked for.
    pub gain: Option<GainRanking>,
    /// Which ranking picked the axis (`None` when the axis was given).
    pub axis_by: Option<AxisBy>,
    /// The partition along the chosen axis.
    pub partition: Partition,
    /// What the user should know: spacings coarsened to the sample budget, histories cut short.
    pub notes: Vec<String>,
    /// The numbers behind the axis and the steps, when asked for.
    pub explain: Option<Explain>,
}

impl Analysis {
    /// The axis partitioned along.
    pub fn axis(&self) -> [f64; 3] {
        self.partition.axis
    }
}

/// Runs the view search (unless an axis is given) and partitions along the axis.
pub fn analyze(volume: &Volume, params: &AnalysisParams, monitor: &Monitor) -> Result<Analysis> {
    analyze_planned(&Plan::at(Arc::new(volume.clone())), params, monitor)
}

/// The axis `params` asks for, a unit physical direction: the one it names, or the best of the
/// view search by entropy rate (no partition is made).
pub fn chosen_axis(
    volume: &Volume,
    params: &AnalysisParams,
    monitor: &Monitor,
) -> Result<[f64; 3]> {
    match params.axis.resolve(volume.transform(), volume.spacing())? {
        Some(axis) => Ok(axis.direction()),
        None => Ok(crate::view::search(volume, &params.view, monitor)?
            .best()
            .axis),
    }
}

/// Runs the view search (unless an axis is given) on `plan`'s view level and partitions its
/// partition level along the axis.
pub fn analyze_planned(
    plan: &Plan,
    params: &AnalysisParams,
    monitor: &Monitor,
) -> Result<Analysis> {
    let views = if params.runs_search() {
        Some(plan.search(&params.view, monitor)?)
    } else {
        None
    };
    analyzed_with(plan, params, views, monitor)
}

/// [`analyze_planned`] with the view search's result `views` (when it runs) found already.
fn analyzed_with(
    plan: &Plan,
    params: &AnalysisParams,
    mut views: Option<ViewSearch>,
    monitor: &Monitor,
) -> Result<Analysis> {
    let volume = plan.partition.as_ref();
    let chosen = params.axis.resolve(volume.transform(), volume.spacing())?;
    let mut gain = if params.ranks_by_gain() {
        Some(rank_by_gain(&plan.views, params, monitor)?)
    } else {
        None
    };
    let by_gain = chosen.is_none() && params.axis_by == AxisBy::Gain;
    if let (Some(g), Some(v)) = (&gain, &mut views) {
        g.annotate(v);
    }
    let axis = match (chosen, &gain) {
        (None, Some(g)) if by_gain => g.refined.axis,
        _ => axis_of(chosen.map(crate::geometry::Axis::direction), views.as_ref()),
    };
    let (partition, explain) = match params.explain {
        None => (partitioned(plan, axis, params, monitor)?, None),
        Some(shown) => {
            let (partition, histories) = partitioned_kept(plan, axis, params, monitor)?;
            let explained = crate::explain::explain(
                (&plan.views, plan.views_streamed),
                views.as_ref(),
                &params.view,
                &histories,
                &partition,
                shown,
                monitor,
            )?;
            (partition, Some(explained))
        }
    };
    if let Some(g) = &mut gain
        && params.method == Method::TopDown
        && params.stop == Stop::Slabs(g.sampling.slabs)
    {
        // The axis partitioned, counted on every voxel: its gain is the partition's.
        g.exact(partition.axis, partition.information, views.as_mut());
    }
    let notes = plan
        .note
        .iter()
        .cloned()
        .chain(notes(&plan.views, volume, &params.view, &partition))
        .collect();
    Ok(Analysis {
        views,
        gain,
        axis_by: chosen.is_none().then_some(params.axis_by),
        partition,
        notes,
        explain,
    })
}

/// The axis to partition along by entropy rate: the one `chosen`, else the best of `views`.
fn axis_of(chosen: Option<[f64; 3]>, views: Option<&ViewSearch>) -> [f64; 3] {
    match (chosen, views) {
        (Some(a), _) => a,
        (None, Some(v)) => v.best().axis,
        (None, None) => unreachable!("the view search runs when no axis is given"),
    }
}

/// The partition of `plan`'s partition level along `axis`: in memory or strip by strip.
fn partitioned(
    plan: &Plan,
    axis: [f64; 3],
    params: &AnalysisParams,
    monitor: &Monitor,
) -> Result<Partition> {
    let volume = plan.partition.as_ref();
    match plan.streamed {
        Some(room) => partition_streamed(volume, axis, &params.partition(), room, monitor),
        None => partition(volume, axis, &params.partition(), monitor),
    }
}

/// [`partitioned`], with the histories it came from.
fn partitioned_kept(
    plan: &Plan,
    axis: [f64; 3],
    params: &AnalysisParams,
    monitor: &Monitor,
) -> Result<(Partition, Histories)> {
    let volume = plan.partition.as_ref();
    match plan.streamed {
        Some(room) => partition_streamed_kept(volume, axis, &params.partition(), room, monitor),
        None => partition_kept(volume, axis, &params.partition(), monitor),
    }
}

/// The anonymous memory an analysis of pyramid level `level` of `volume` takes at its peak, in
/// bytes: the level's voxels where they are held in memory (none for a level 0 read in place
/// from a mapped file; a coarser level holds f32, beside the volume's own voxels held in memory,
/// which stay held while it is analysed), and the larger of the view search's cell map
/// (a byte a voxel for integers of at most 16 bits, whose bins a table gives, two for f32) and
/// the partition's slice stack with the background mask and their columns (a byte, a bit and
/// an eighth more: measured, 1281 MiB at the peak of a 1024³ analysis, 1280 by this count) with
/// its per-slice histograms and curves for the longest stack the level can have
/// ([`slice_bytes`](crate::partition::slice_bytes) a slice at the default 32 bins: next to
/// nothing on a cube, most of it on a long thin volume, 200,000 voxels along and one across).
#[must_use]
pub fn memory_needed(volume: &Volume, level: usize) -> u64 {
    memory_needed_with(
        volume,
        level,
        crate::geometry::lattice::SamplingParams::default().bins,
    )
}

/// [`memory_needed`] for a partition in `bins` bins.
#[must_use]
pub fn memory_needed_with(volume: &Volume, level: usize, bins: usize) -> u64 {
    let level = level.min(volume.coarser_levels());
    let (dims, spacing) = volume.level_grids()[level];
    let n = dims.iter().map(|&d| d as u64).product::<u64>();
    let (held, map) = if level == 0 {
        let integer = volume.data().held() != VoxelType::F32;
        (volume.memory_bytes(), if integer { n } else { 2 * n })
    } else {
        (volume.memory_bytes() + 4 * n, 2 * n)
    };
    held + map.max(stack_bytes(dims, spacing, bins))
}

/// [`memory_needed`] of level 0 of a volume of `dims` and `spacing` whose voxels would be held
/// in memory as `held`, from its grid alone: before it is read (a store's level 0, known from
/// its metadata, [`Volume::unread_finest`]), or of a coarser level that would be read as a
/// volume of its own.
#[must_use]
pub fn memory_needed_unread(dims: [usize; 3], spacing: [f64; 3], held: VoxelType) -> u64 {
    let n = dims.iter().map(|&d| d as u64).product::<u64>();
    let map = if held == VoxelType::F32 { 2 * n } else { n };
    let bins = crate::geometry::lattice::SamplingParams::default().bins;
    n * held.size() as u64 + map.max(stack_bytes(dims, spacing, bins))
}

/// The partition's slice stack with the background mask and their columns, with the per-slice
/// sums of the longest stack of a volume of `dims` and `spacing` ([`memory_needed`]).
fn stack_bytes(dims: [usize; 3], spacing: [f64; 3], bins: usize) -> u64 {
    let n = dims.iter().map(|&d| d as u64).product::<u64>();
    let slices = crate::partition::most_slices(dims, spacing);
    n + n / 4 + slices * crate::partition::slice_bytes(bins)
}

/// The finest pyramid level of `volume` at or coarser than level `wanted` whose analysis fits in
/// `max_memory` bytes ([`memory_needed`]), with a note when the budget moved it from `wanted`.
/// A volume is never refused for its size: only a budget too small for a level of two voxels
/// along every axis is an error.
pub(crate) fn within_memory(
    volume: &Volume,
    wanted: usize,
    max_memory: u64,
) -> Result<(Arc<Volume>, Option<String>)> {
    level_within_memory(
        volume,
        wanted,
        max_memory,
        crate::geometry::lattice::SamplingParams::default().bins,
    )
    .map(|(level, note)| (volume.coarser(level), note))
}

/// The level [`within_memory`] picks for a partition in `bins` bins, and its note.
pub(crate) fn level_within_memory(
    volume: &Volume,
    wanted: usize,
    max_memory: u64,
    bins: usize,
) -> Result<(usize, Option<String>)> {
    let memory_needed = |l| memory_needed_with(volume, l, bins);
    let top = volume.coarser_levels();
    let fits = (wanted.min(top)..=top).find(|&l| memory_needed(l) <= max_memory);
    let human = crate::error::short_bytes;
    match fits {
        Some(l) if l == wanted => Ok((l, None)),
        Some(l) if volume.level_dims()[l].iter().all(|&d| d >= 2) => Ok((
            l,
            Some(format!(
                "level {wanted} needs {} for the analysis, over the memory limit of {}: computed \
                 on pyramid level {l}, the finest that fits ({})",
                human(memory_needed(wanted)),
                human(max_memory),
                human(memory_needed(l)),
            )),
        )),
        _ => Err(crate::error::Error::invalid(
            "max_memory",
            human(max_memory),
            format!(
                "room for the analysis of a pyramid level with two voxels along every axis \
                 (level {wanted} needs {})",
                human(memory_needed(wanted))
            ),
        )),
    }
}

/// What an analysis on a pyramid level says of it; nothing at full resolution.
pub fn resolution_note(level: &Volume) -> Option<String> {
    let l = level.level();
    (l.index > 0).then(|| {
        format!(
            "computed on pyramid level {} ({}, {} voxels of the file a voxel): slab indices are \
             its slices",
            l.index,
            crate::volume::dims_string(level.dims()),
            crate::volume::dims_string(l.factor),
        )
    })
}

/// The notes of an analysis whose view search ran on `views` with `view`'s sampling and whose
/// partition of `volume` gave `partition` (a [`Plan`]'s note says when the two differ).
pub fn notes(
    views: &Volume,
    volume: &Volume,
    view: &ViewParams,
    partition: &Partition,
) -> Vec<String> {
    resolution_note(volume)
        .into_iter()
        .chain(view.sampling.budget_note(views.dims(), views.spacing()))
        .chain(partition.notes.iter().cloned())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_budget_picks_the_finest_level_that_fits() {
        // 16³ held in memory: its voxels, then the larger of 8192 bytes of cell map and the
        // slice stack (5120 bytes) with the per-slice sums of the longest stack (the diagonal,
        // 28 slices of 576 bytes at 32 bins); level 1 is 8³ of f32 (2048 bytes) beside them, its
        // stack (640) and 14 slices of sums.
        let data: Vec<f32> = (0..4096).map(|i| (i % 251) as f32).collect();
        let v = Volume::new([16; 3], [1.0; 3], VoxelType::U8, data).unwrap();
        let full = v.memory_bytes() + 5120 + 28 * 576;
        assert!(v.memory_bytes() >= 4096);
        assert_eq!(memory_needed(&v, 0), full);
        // The volume's own voxels stay held beside a coarser level's.
        assert_eq!(
            memory_needed(&v, 1),
            v.memory_bytes() + 2048 + 640 + 14 * 576
        );
        assert_eq!(level_within_memory(&v, 0, full, 32).unwrap(), (0, None));
        let (level, note) = level_within_memory(&v, 0, full - 1, 32).unwrap();
        assert_eq!(level, 1);
        let note = note.unwrap();
        assert!(
            note.contains("over the memory limit") && note.contains("level 1"),
            "{note}"
        );
        // A level asked for that fits is kept, and no note.
        assert_eq!(level_within_memory(&v, 2, full - 1, 32).unwrap(), (2, None));
        // Integers need no per-voxel map: the slice stack and its background (a byte and a
        // quarter a voxel) and the per-slice sums are the peak.
        let bytes: Vec<u8> = (0..4096).map(|i| (i % 251) as u8).collect();
        let u8s = Volume::from_voxels(
            [16; 3],
            [1.0; 3],
            VoxelType::U8,
            crate::volume::Voxels::owned(bytes),
        )
        .unwrap();
        assert_eq!(memory_needed(&u8s, 0), 4096 + 5120 + 28 * 576);
        // Levels of one voxel along an axis are not analysed.
        assert!(level_within_memory(&v, 0, 10, 32).is_err());
    }

    #[test]
    fn a_long_thin_volume_needs_its_per_slice_sums() {
        // One voxel across, 200,000 along (#47): 200 KB of voxels, but a stack of 200,000 slices
        // whose histograms and prefix sums take 115 MB at 32 bins, 8 times that at 255. The
        // budget weighs them: 64 MB is refused (no coarser level is two voxels across), 200 MB
        // fits.
        for dims in [[1, 1, 200_000], [200_000, 1, 1], [1, 200_000, 1]] {
            let bytes = (0..200_000).map(|i| (i * 7 % 251) as u8).collect();
            let v = Volume::from_voxels(
                dims,
                [1.0; 3],
                VoxelType::U8,
                crate::volume::Voxels::owned(bytes),
            )
            .unwrap();
            let need = memory_needed(&v, 0);
            assert!(need >= 200_000 * 576, "{dims:?}: {need}");
            assert!(memory_needed_with(&v, 0, 255) > 7 * need, "{dims:?}");
            assert!(
                level_within_memory(&v, 0, 64 << 20, 32).is_err(),
                "{dims:?}"
            );
            assert_eq!(
                level_within_memory(&v, 0, 200 << 20, 32).unwrap(),
                (0, None)
            );
        }
    }
}
