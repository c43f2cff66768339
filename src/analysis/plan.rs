//! Where an analysis runs within a memory budget ([`Plan`]): the pyramid level of the view
//! search, the level partitioned, and whether either is counted slab by slab or strip by strip.

use std::sync::Arc;

use super::{AnalysisParams, level_within_memory, memory_needed_with};
use crate::error::Result;
use crate::partition::Method;
use crate::progress::Monitor;
use crate::view::{ViewParams, ViewSearch, search};
use crate::volume::Volume;

/// Where an analysis runs within a memory budget: the pyramid level the view search runs on,
/// the level partitioned, and whether the partition's slice stack is counted strip by strip.
#[derive(Clone, Debug)]
pub struct Plan {
    /// The level the view search runs on.
    pub views: Arc<Volume>,
    /// The level partitioned; its slices are the partition's.
    pub partition: Arc<Volume>,
    /// When the slice stack is counted strip by strip: the working memory it may take, bytes.
    pub streamed: Option<u64>,
    /// When the view search runs on every voxel slab by slab
    /// ([`search_streamed`](crate::view::search_streamed)): the working memory it may take.
    pub views_streamed: Option<u64>,
    /// What the user should know of the plan (nothing when everything runs on the level asked
    /// for, in memory).
    pub note: Option<String>,
}

impl Plan {
    /// Everything on `level`, in memory.
    #[must_use]
    pub fn at(level: Arc<Volume>) -> Self {
        Self {
            views: Arc::clone(&level),
            partition: level,
            streamed: None,
            views_streamed: None,
            note: None,
        }
    }

    /// The view search by `view` on the level planned for it: counted slab by slab on every
    /// voxel when so planned ([`search_streamed`](crate::view::search_streamed)), else in
    /// memory.
    pub fn search(&self, view: &ViewParams, monitor: &Monitor) -> Result<ViewSearch> {
        match self.views_streamed {
            Some(room) => crate::view::search_streamed(&self.views, view, room, monitor),
            None => search(&self.views, view, monitor),
        }
    }

    /// The plan for analysing pyramid level `wanted` of `volume` by `params` within
    /// `max_memory` bytes. Both parts run on the finest level at or coarser than `wanted` that
    /// fits ([`memory_needed`]), except that a full-resolution partition by top-down or optimal
    /// splitting whose stack does not fit is counted strip by strip when the voxels are read in
    /// place (or held) and room is left beside the view search's level for the strips: the
    /// slabs are then those of every voxel, the best axis that of the coarser level (with an
    /// axis given, no view search, no gain ranking and no explanation, the strips have the
    /// whole room).
    pub(crate) fn within(
        volume: &Volume,
        (wanted, every_voxel): (usize, bool),
        max_memory: u64,
        params: &AnalysisParams,
    ) -> Result<Self> {
        let bins = params.view.sampling.bins;
        let (level, note) = level_within_memory(volume, wanted, max_memory, bins)?;
        let human = crate::error::short_bytes;
        let needs = human(memory_needed_with(volume, 0, bins));
        let full = Arc::new(volume.clone());
        let beyond = level != wanted && wanted == 0 && params.method != Method::BottomUp;
        let full_room = max_memory.saturating_sub(volume.memory_bytes());
        if beyond && every_voxel && streams_search(volume, params, full_room) {
            return Ok(Self {
                note: Some(format!(
                    "level 0 needs {needs} for the analysis in memory, over the memory limit of {}: \
                     the view search and the slabs are counted on every voxel, slab by slab",
                    human(max_memory),
                )),
                views: Arc::clone(&full),
                partition: full,
                streamed: Some(full_room),
                views_streamed: Some(full_room),
            });
        }
        // With an axis given and nothing else read on the views' level, no level but the
        // partition's is held: its strips have the whole room.
        let on_views = params.runs_search() || params.ranks_by_gain() || params.explain.is_some();
        let floor = crate::partition::streamed_memory_floor(volume, bins);
        if beyond && !on_views && full_room >= floor {
            return Ok(Self {
                note: Some(format!(
                    "level 0 needs {needs} for the analysis in memory, over the memory limit of \
                     {}: the slabs are counted on every voxel, strip by strip",
                    human(max_memory),
                )),
                views: Arc::clone(&full),
                partition: full,
                streamed: Some(full_room),
                views_streamed: None,
            });
        }
        let views = volume.coarser(level);
        let coarse = if level > 0 { views.memory_bytes() } else { 0 };
        let room = full_room.saturating_sub(coarse);
        if !(beyond && room >= floor) {
            return Ok(Self {
                note,
                ..Self::at(views)
            });
        }
        Ok(Self {
            note: Some(format!(
                "level 0 needs {needs} for the analysis in memory, over the memory limit of {}: the \
                 view search runs on pyramid level {level}, the finest that fits ({}), and the \
                 slabs are counted on every voxel, strip by strip",
                human(max_memory),
                human(memory_needed_with(volume, level, bins)),
            )),
            views,
            partition: full,
            streamed: Some(room),
            views_streamed: None,
        })
    }
}

/// Whether the view search and the partition of every voxel of `volume` can both be counted
/// in `room` bytes (the lesson's axes are then counted slab by slab too). (The gain ranking
/// reads the voxels where they are, with the background's mask, which the partition's floor
/// counts.)
fn streams_search(volume: &Volume, params: &AnalysisParams, room: u64) -> bool {
    params.runs_search()
        && room >= crate::view::streamed_memory_floor(volume, &params.view)
        && room >= crate::partition::streamed_memory_floor(volume, params.view.sampling.bins)
}
