//! The one budget planner: which pyramid level each piece of work runs on. Every front end (the
//! CLI's commands, the TUI, triage, Python) asks it, naming what the level is for ([`Purpose`]);
//! none chooses a level itself.
//!
//! - An **analysis** of the level asked for (`--resolution`) runs there when it fits the memory
//!   budget, else on the finest coarser level that fits, or with its slabs counted strip by strip
//!   on every voxel ([`Plan`]).
//! - A **picture** (render, slice, the TUI) is drawn from the level its analysis runs on at full
//!   resolution within the budget.
//! - A **glance** (the TUI's first answer on a large volume, a store's first picture) runs on the
//!   finest level of at most [`GLANCE_VOXELS`] voxels, at once, before the real answer.
//! - A **pixel**'s level in the ray caster is the finest whose voxels are no larger than the
//!   pixel's footprint (`render::pyramid_level`).
//!
//! A volume fetched from a store at a URL is planned within the budget less the share the
//! answers to its chunk requests kept in memory may take ([`Budget::room`]).

use crate::analysis::{AnalysisParams, Plan};
use crate::error::{Error, Result};
use crate::partition::LabelRoom;
use crate::volume::Volume;

/// The most voxels a glance is computed on: the view search, the histories and the picture of
/// the TUI's first answer on a large volume come from the finest pyramid level this small, and
/// the full resolution follows in the background.
pub const GLANCE_VOXELS: usize = 1 << 21;

/// What a level is chosen for.
#[derive(Clone, Copy, Debug)]
pub enum Purpose<'a> {
    /// The view search and the partition of pyramid level `wanted` by `params`.
    Analysis {
        /// The level asked for (0: every voxel, the paper's method).
        wanted: usize,
        /// Whether every voxel was asked for by name (`--resolution full`): beyond the budget
        /// the view search then counts every voxel too, slab by slab (slower), where by default
        /// it runs on the finest level that fits.
        every_voxel: bool,
        /// The analysis's parameters (the method decides whether slabs can be streamed).
        params: &'a AnalysisParams,
    },
    /// A picture drawn with the analysis it shows: the level a full-resolution analysis runs
    /// on within the budget.
    Picture,
    /// A first answer at once: the finest level of at most [`GLANCE_VOXELS`] voxels.
    Glance,
}

/// A memory budget, in bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Budget {
    /// The most bytes the volume and its analysis may take; a file read in place is not
    /// counted.
    pub max_memory: u64,
}

impl Budget {
    /// A budget of `max_memory` bytes.
    #[must_use]
    pub fn new(max_memory: u64) -> Self {
        Self { max_memory }
    }

    /// The bytes of this budget that `volume`'s source keeps beside it: for a volume fetched
    /// from a store at a URL ([`Volume::is_remote`]), the share the process's cache of the
    /// answers to its chunk requests may take (`formats::remote::cache`: 1/16); else nothing.
    #[must_use]
    pub fn kept_for_source(&self, volume: &Volume) -> u64 {
        kept_for(volume, self.max_memory)
    }

    /// The bytes of this budget left for `volume` and the work on it: the budget less what its
    /// source keeps ([`kept_for_source`](Self::kept_for_source)).
    #[must_use]
    pub fn room(&self, volume: &Volume) -> u64 {
        self.max_memory - self.kept_for_source(volume)
    }

    /// Where `purpose`'s work on `volume` runs within this budget, less what the volume's
    /// source keeps beside it ([`room`](Self::room)); the plan's note says what the user should
    /// know when the budget moved it from the level asked for.
    pub fn plan(&self, volume: &Volume, purpose: Purpose<'_>) -> Result<Plan> {
        let kept = self.kept_for_source(volume);
        let mut plan = plan_in(volume, purpose, self.room(volume)).map_err(|e| match e {
            // The limit the user gave, not the room left beside the kept chunks.
            Error::InvalidParameter {
                parameter: "max_memory",
                expected,
                ..
            } if kept > 0 => Error::invalid(
                "max_memory",
                crate::error::short_bytes(self.max_memory),
                format!(
                    "{expected}, beside the {} kept for the chunks fetched from the store",
                    crate::error::short_bytes(kept)
                ),
            ),
            e => e,
        })?;
        if let (Some(note), 1..) = (&mut plan.note, kept) {
            let human = crate::error::short_bytes;
            *note = format!(
                "{note} (the memory limit of {} less {} kept for the chunks fetched from the \
                 store)",
                human(self.max_memory),
                human(kept)
            );
        }
        Ok(plan)
    }
}

/// [`Budget::plan`] within `room` bytes.
fn plan_in(volume: &Volume, purpose: Purpose<'_>, room: u64) -> Result<Plan> {
    match purpose {
        Purpose::Analysis {
            wanted,
            every_voxel,
            params,
        } => {
            if wanted > 0 {
                // A level the file holds and the user asked for is read or refused, never
                // computed in its place.
                volume.asked_level(wanted)?;
            }
            Plan::within(volume, (wanted, every_voxel), room, params)
        }
        Purpose::Picture => {
            let (level, note) = crate::analysis::within_memory(volume, 0, room)?;
            Ok(Plan {
                note,
                ..Plan::at(level)
            })
        }
        Purpose::Glance => {
            // Never finer than the budget allows either.
            let bins = crate::geometry::lattice::SamplingParams::default().bins;
            let (fits, _) = crate::analysis::level_within_memory(volume, 0, room, bins)?;
            let level = glance_level(volume).max(fits);
            Ok(Plan::at(volume.coarser(level)))
        }
    }
}

impl Budget {
    /// The working memory in which the label volume of `plan`'s partition into `slabs` slabs,
    /// at `volume`'s own shape, is written to a file
    /// ([`stage_labels`](crate::report::stage_labels)) within this budget beside what stays held
    /// once the analysis is done: `volume`'s voxels in memory and the coarser levels the plan
    /// ran on. The labels are never held whole, so their size is never refused, nor is a found
    /// background's mask (a bit a voxel: 1 GiB at 2048³): it is held in memory when it fits
    /// there beside one plane of labels, else in a mapped scratch file
    /// ([`MaskHome::Scratch`](crate::partition::MaskHome::Scratch)), which the kernel's page
    /// cache holds, not the process. What must fit is one plane; the room for chunks of planes
    /// is what is left (at most [`LABEL_CHUNK_BYTES`](crate::partition::LABEL_CHUNK_BYTES)).
    /// `path` is the file the volume came from, for the error.
    pub fn labels(
        &self,
        path: &std::path::Path,
        volume: &Volume,
        plan: &Plan,
        slabs: usize,
    ) -> Result<LabelRoom> {
        let memory = crate::partition::label_stream_memory(volume, slabs);
        let held = self.held_beside_labels(volume, plan);
        let with_mask = held + memory.mask + memory.plane;
        if with_mask <= self.max_memory {
            return Ok(LabelRoom {
                chunk: (self.max_memory - held - memory.mask).min(memory.most),
                mask_in_memory: true,
            });
        }
        let [x, y, z] = volume.dims();
        let what = format!(
            "a plane of the labels of {x}×{y}×{z} voxels beside {}",
            self.beside(volume)
        );
        self.fits(path, held + memory.plane, what)?;
        Ok(LabelRoom {
            chunk: (self.max_memory - held).min(memory.most),
            mask_in_memory: false,
        })
    }

    /// That the label volume of `plan`'s partition into `slabs` slabs, at `volume`'s own shape
    /// ([`label_volume`](crate::partition::label_volume)), fits in this budget held whole with
    /// its background's mask (Python's `Analysis.labels()`, which returns it as an array),
    /// beside what [`labels`](Self::labels) counts.
    pub fn labels_held(
        &self,
        path: &std::path::Path,
        volume: &Volume,
        plan: &Plan,
        slabs: usize,
    ) -> Result<()> {
        let needed = crate::partition::label_memory(volume, slabs);
        let [x, y, z] = volume.dims();
        let what = format!(
            "the label volume of every voxel ({x}×{y}×{z}) beside {}",
            self.beside(volume)
        );
        self.fits(path, self.held_beside_labels(volume, plan) + needed, what)
    }

    /// What stays held of `plan` once its analysis is done, beside the labels of `volume`: the
    /// volume's voxels in memory, the coarser levels the plan ran on, and what its source keeps
    /// ([`kept_for_source`](Self::kept_for_source)).
    fn held_beside_labels(self, volume: &Volume, plan: &Plan) -> u64 {
        let coarser = |level: &Volume| {
            if level.dims() == volume.dims() {
                0
            } else {
                level.memory_bytes()
            }
        };
        let mut held = volume.memory_bytes() + coarser(&plan.partition);
        if plan.views.dims() != plan.partition.dims() {
            held += coarser(&plan.views);
        }
        held + self.kept_for_source(volume)
    }

    /// What the labels of `volume` are weighed beside, as an error says it.
    fn beside(self, volume: &Volume) -> &'static str {
        match self.kept_for_source(volume) {
            0 => "the analysis",
            _ => "the analysis and the chunks kept from the store",
        }
    }

    /// That `needed` bytes, for `what`, fit in this budget.
    fn fits(self, path: &std::path::Path, needed: u64, what: String) -> Result<()> {
        if needed <= self.max_memory {
            return Ok(());
        }
        Err(Error::TooLarge {
            path: path.to_path_buf(),
            what,
            needed,
            limit: self.max_memory,
            machine: false,
            disk: false,
        })
    }
}

/// Of a volume `read` as a coarser pyramid level without its level 0 (a store's dataset,
/// [`Volume::unread_finest`]) : `None` when level 0's analysis fits in `max_memory` bytes held
/// in memory ([`memory_needed_unread`](crate::analysis::memory_needed_unread), from its grid),
/// so that level 0 is to be read; else the finest coarser pyramid level whose analysis fits,
/// that level read as a volume of its own (the last when none does), so that level 0, beyond
/// the budget, is never read. `None` too for a volume read with its level 0.
#[must_use]
pub fn unread_level_within(read: &Volume, max_memory: u64) -> Option<usize> {
    let finest = read.unread_finest()?;
    // Less what the store's source keeps beside it, as the plan leaves it.
    let max_memory = max_memory - kept_for(read, max_memory);
    let held = crate::volume::voxels::held_type(read.voxel_type(), false);
    let chain = read.pyramid_dims();
    let fits = |l: usize| {
        let dims = chain[l];
        // Each axis's spacing grows as its voxels fewer (an estimate where a count is odd).
        let spacing =
            std::array::from_fn(|m| finest.spacing[m] * finest.dims[m] as f64 / dims[m] as f64);
        crate::analysis::memory_needed_unread(dims, spacing, held) <= max_memory
    };
    if fits(0) {
        return None;
    }
    Some(
        (1..chain.len())
            .find(|&l| fits(l))
            .unwrap_or(chain.len() - 1),
    )
}

/// The bytes of a budget of `max_memory` that `volume`'s source keeps beside it
/// ([`Budget::kept_for_source`]).
fn kept_for(volume: &Volume, max_memory: u64) -> u64 {
    #[cfg(feature = "remote")]
    if volume.is_remote() {
        return max_memory / crate::formats::remote::cache::MEMORY_SHARE;
    }
    let _ = (volume, max_memory);
    0
}

/// `e`, raised by the analysis `plan` planned, blamed on the budget when the budget moved the
/// analysis to a coarser level and `e` is about a parameter (a slab count that the level asked
/// for would hold): [`Error::TooCoarse`].
#[must_use]
pub fn blame(plan: &Plan, e: Error) -> Error {
    match (&plan.note, e) {
        (Some(note), e @ (Error::InvalidParameter { .. } | Error::DefaultUnfit { .. })) => {
            Error::TooCoarse {
                note: note.clone(),
                cause: Box::new(e),
            }
        }
        (_, e) => e,
    }
}

/// The pyramid level of a glance at `volume`: 0 when it is small enough to compute at full
/// resolution at once.
#[must_use]
pub fn glance_level(volume: &Volume) -> usize {
    crate::volume::pyramid::level_within(&volume.level_dims(), GLANCE_VOXELS)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::{VoxelType, pyramid};

    #[test]
    fn each_purpose_gets_its_level() {
        let volume = crate::volume::phantom::body([96, 96, 96], 1).unwrap();
        let params = AnalysisParams::default();
        let roomy = Budget::new(u64::MAX);
        let plan = roomy
            .plan(
                &volume,
                Purpose::Analysis {
                    wanted: 1,
                    every_voxel: false,
                    params: &params,
                },
            )
            .unwrap();
        assert_eq!(plan.partition.dims(), [48, 48, 48]);
        assert!(plan.note.is_none());
        let picture = roomy.plan(&volume, Purpose::Picture).unwrap();
        assert_eq!(picture.partition.dims(), [96, 96, 96]);
        // A budget with room for level 1's analysis only moves the picture there, and says so.
        let level1 = crate::analysis::memory_needed(&volume, 1);
        let tight = Budget::new(level1);
        let picture = tight.plan(&volume, Purpose::Picture).unwrap();
        assert_eq!(picture.partition.dims(), [48, 48, 48]);
        assert!(picture.note.is_some_and(|n| n.contains("pyramid level 1")));
        // 96³ is 884,736 voxels: a glance takes it whole; 160³ (4 M) is halved.
        let glance_of = |dims: [usize; 3]| {
            let chain = pyramid::chain_dims(dims, &pyramid::steps_after(dims, &[]));
            pyramid::level_within(&chain, GLANCE_VOXELS)
        };
        assert_eq!(glance_level(&volume), 0);
        assert_eq!(glance_of([96; 3]), 0);
        assert_eq!(glance_of([160; 3]), 1);
        let glance = roomy.plan(&volume, Purpose::Glance).unwrap();
        assert_eq!(glance.partition.dims(), [96, 96, 96]);
        // Nor is a glance finer than the budget allows.
        let glance = tight.plan(&volume, Purpose::Glance).unwrap();
        assert_eq!(glance.partition.dims(), [48, 48, 48]);
    }

    #[test]
    fn with_an_axis_given_the_slabs_of_every_voxel_take_the_whole_room() {
        // At 8 bins the strips' floor (mostly the joint histograms of consecutive slices) is
        // below what the analysis of every voxel holds at once.
        let volume = crate::volume::phantom::body([96, 96, 96], 1).unwrap();
        let mut given = AnalysisParams {
            axis: crate::geometry::AxisChoice::Along(crate::geometry::Axis::Z),
            ..AnalysisParams::default()
        };
        given.view.sampling.bins = 8;
        let floor = crate::partition::streamed_memory_floor(&volume, 8);
        let needed = crate::analysis::memory_needed_with(&volume, 0, 8);
        let budget = Budget::new(volume.memory_bytes() + floor);
        assert!(volume.memory_bytes() + floor < needed);
        let mut searched = AnalysisParams::default();
        searched.view.sampling.bins = 8;
        for (params, every_voxel) in [(&given, true), (&given, false), (&searched, false)] {
            let purpose = Purpose::Analysis {
                wanted: 0,
                every_voxel,
                params,
            };
            let plan = budget.plan(&volume, purpose).unwrap();
            let note = plan.note.unwrap_or_default();
            if params.runs_search() {
                // Beside the view search's level there is no room for the strips: the whole
                // analysis runs on level 1.
                assert_eq!(plan.partition.dims(), [48; 3], "{note}");
                assert!(note.contains("computed on pyramid level 1"), "{note}");
            } else {
                assert_eq!(plan.partition.dims(), [96; 3], "{note}");
                assert_eq!(plan.views.dims(), [96; 3]);
                assert!(plan.streamed.is_some(), "{note}");
                assert!(note.ends_with("the slabs are counted on every voxel, strip by strip"));
            }
        }
    }

    /// A level read without level 0 tells from level 0's grid whether level 0's analysis fits,
    /// and else the finest level whose own does, counted as a volume of that level held alone.
    #[test]
    fn a_level_read_without_level_0_names_the_level_that_fits() {
        let level0 = crate::volume::phantom::body([64, 64, 64], 1).unwrap();
        let finest = crate::volume::pyramid::Finest {
            dims: level0.dims(),
            spacing: level0.spacing(),
            transform: *level0.transform(),
        };
        let read = Volume::clone(&level0.coarser(2)).into_pyramid_level(2, finest, &[]);
        // Level 0 as a store would hold it, its stored type.
        let held = crate::volume::voxels::held_type(read.voxel_type(), false);
        let alone = |n: usize| {
            let f = 64.0 / n as f64;
            let spacing = level0.spacing().map(|s| s * f);
            crate::analysis::memory_needed_unread([n; 3], spacing, held)
        };
        assert_eq!(unread_level_within(&read, alone(64)), None);
        assert_eq!(unread_level_within(&level0, 0), None, "level 0 was read");
        assert_eq!(unread_level_within(&read, alone(64) - 1), Some(1));
        assert_eq!(unread_level_within(&read, alone(32)), Some(1));
        assert_eq!(unread_level_within(&read, alone(32) - 1), Some(2));
        assert_eq!(unread_level_within(&read, alone(16)), Some(2));
        // From the grid, as from a volume of u8 held in memory.
        let bytes = crate::volume::Voxels::owned(vec![7u8; 4096]);
        let small = Volume::from_voxels([16; 3], [1.0; 3], VoxelType::U8, bytes).unwrap();
        assert_eq!(
            crate::analysis::memory_needed_unread([16; 3], [1.0; 3], VoxelType::U8),
            crate::analysis::memory_needed(&small, 0)
        );
        let top = read.pyramid_dims().len() - 1;
        assert_eq!(
            unread_level_within(&read, 1),
            Some(top),
            "the last when none fits"
        );
    }

    /// The least budget whose room beside the chunk cache's share (1/16) holds `needed` bytes.
    #[cfg(feature = "remote")]
    fn least_beside_the_share(needed: u64) -> u64 {
        let share = crate::formats::remote::cache::MEMORY_SHARE;
        (needed..=2 * needed + share)
            .find(|&m| m - m / share >= needed)
            .unwrap()
    }

    /// A volume fetched from a store at a URL is planned within the budget less the share its
    /// chunks kept in memory may take (1/16), so that the two together stay within the budget;
    /// any other volume within the whole budget.
    #[cfg(feature = "remote")]
    #[test]
    fn a_remote_volumes_plan_leaves_the_chunk_caches_share() {
        let local = crate::volume::phantom::body([96, 96, 96], 1).unwrap();
        // (A pyramid of its own: a clone would share local's coarser levels.)
        let remote = crate::volume::phantom::body([96, 96, 96], 1)
            .unwrap()
            .fetched_remotely();
        let params = AnalysisParams::default();
        let analysis = Purpose::Analysis {
            wanted: 0,
            every_voxel: false,
            params: &params,
        };
        let level_of = |volume: &Volume, max: u64, purpose| {
            let plan = Budget::new(max).plan(volume, purpose).unwrap();
            (plan.partition.dims()[0], plan.note)
        };
        let needed = crate::analysis::memory_needed(&local, 0);
        let share = |max: u64| max / crate::formats::remote::cache::MEMORY_SHARE;
        // The least budget whose room beside the share holds level 0's analysis.
        let least = least_beside_the_share(needed);
        assert_eq!(least - share(least), needed);
        assert_eq!(Budget::new(least).kept_for_source(&remote), share(least));
        assert_eq!(Budget::new(least).kept_for_source(&local), 0);
        assert_eq!(Budget::new(least).room(&local), least);
        for purpose in [analysis, Purpose::Picture] {
            assert_eq!(level_of(&local, needed, purpose), (96, None));
            assert_eq!(level_of(&remote, least, purpose), (96, None));
            let (dims, note) = level_of(&remote, least - 1, purpose);
            assert_eq!(dims, 48, "level 1");
            let note = note.unwrap();
            let limit = crate::error::short_bytes(least - 1);
            let kept = crate::error::short_bytes(share(least - 1));
            assert!(
                note.ends_with(&format!(
                    "(the memory limit of {limit} less {kept} kept for the chunks fetched from \
                     the store)"
                )),
                "{note}"
            );
        }
        // Too little for any level: the error names the limit given, and the share beside it.
        let e = Budget::new(4096)
            .plan(&remote, analysis)
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "max_memory 4.0 KiB: expected room for the analysis of a pyramid level with two \
             voxels along every axis (level 0 needs 5.1 MiB), beside the 256 bytes kept for the \
             chunks fetched from the store"
        );
        // The level a store's dataset serves, from level 0's grid: the same room.
        let finest = crate::volume::pyramid::Finest {
            dims: local.dims(),
            spacing: local.spacing(),
            transform: *local.transform(),
        };
        let read = Volume::clone(&local.coarser(2)).into_pyramid_level(2, finest, &[]);
        let alone = crate::analysis::memory_needed_unread(
            [96; 3],
            local.spacing(),
            crate::volume::voxels::held_type(read.voxel_type(), false),
        );
        let fetched = read.clone().fetched_remotely();
        let least = least_beside_the_share(alone);
        assert_eq!(unread_level_within(&read, alone), None);
        assert_eq!(unread_level_within(&fetched, alone), Some(1));
        assert_eq!(unread_level_within(&fetched, least), None);
        assert_eq!(unread_level_within(&fetched, least - 1), Some(1));
        // Labels, too, are weighed beside the share.
        let plan = Budget::new(u64::MAX).plan(&remote, analysis).unwrap();
        let path = std::path::Path::new("body");
        let whole = remote.memory_bytes() + crate::partition::label_memory(&remote, 4);
        let fits = |max: u64| {
            Budget::new(max)
                .labels_held(path, &remote, &plan, 4)
                .is_ok()
        };
        let least = least_beside_the_share(whole);
        assert!(fits(least) && !fits(least - 1));
        let e = Budget::new(whole).labels_held(path, &remote, &plan, 4);
        let e = e.unwrap_err().to_string();
        assert!(e.contains("the chunks kept from the store"), "{e}");
    }

    /// Labels streamed need one plane beside what the analysis holds, whatever their whole size;
    /// the background's mask is in memory when it fits there beside that plane, else in a
    /// scratch file; the room for chunks is what the budget leaves.
    #[test]
    fn labels_stream_within_any_budget_with_room_for_a_plane() {
        let volume = crate::volume::phantom::body([96, 96, 96], 1).unwrap();
        let params = AnalysisParams::default();
        let purpose = Purpose::Analysis {
            wanted: 2,
            every_voxel: false,
            params: &params,
        };
        let plan = Budget::new(u64::MAX).plan(&volume, purpose).unwrap();
        let path = std::path::Path::new("body");
        let held = volume.memory_bytes() + plan.partition.memory_bytes();
        let (mask, plane) = (96u64 * 96 * 96 / 8, 96u64 * 96);
        let room = |max| {
            let r = Budget::new(max).labels(path, &volume, &plan, 4)?;
            Ok::<_, Error>((r.chunk, r.mask_in_memory))
        };
        let least = held + mask + plane;
        assert_eq!(room(least).unwrap(), (plane, true));
        assert_eq!(room(least + 1000).unwrap(), (plane + 1000, true));
        assert_eq!(
            room(u64::MAX).unwrap(),
            (96 * plane, true),
            "every plane at once, no more"
        );
        // Below the mask beside a plane: the mask goes to a scratch file, the chunk has the rest.
        assert_eq!(room(least - 1).unwrap(), (mask + plane - 1, false));
        assert_eq!(room(held + plane).unwrap(), (plane, false));
        let e = room(held + plane - 1).unwrap_err().to_string();
        assert_eq!(
            e,
            format!(
                "body: a plane of the labels of 96×96×96 voxels beside the analysis needs {}, \
                 over the memory limit of {}",
                crate::error::human_bytes(held + plane),
                crate::error::human_bytes(held + plane - 1)
            )
        );
        // Held whole (Python's labels()), they need every voxel's byte.
        let whole = Budget::new(held + mask + 96 * plane);
        assert!(whole.labels_held(path, &volume, &plan, 4).is_ok());
        assert!(
            Budget::new(held + mask + 96 * plane - 1)
                .labels_held(path, &volume, &plan, 4)
                .is_err()
        );
    }
}
