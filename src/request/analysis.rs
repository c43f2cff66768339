//! The analysis request: the view search and the partition of a volume at the level asked for,
//! within a memory budget, and the report `analyze --json` prints of it.

use std::sync::Arc;

use crate::analysis::{
    Analysis, AnalysisParams, GainRanking, Plan, analyze_planned, analyze_planned_with,
    rank_by_gain,
};
use crate::budget::{Budget, Purpose, blame};
use crate::error::Result;
use crate::params::Given;
use crate::partition::{Histories, Scope, partition_streamed_kept};
use crate::progress::Monitor;
use crate::report::AnalysisReport;
use crate::view::ViewSearch;
use crate::volume::{Resolution, Volume};

/// Which pyramid level an analysis runs on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Level {
    /// The level asked for (`--resolution`, `resolution=`), and whether it was named rather
    /// than left to its default: every voxel asked for by name is counted on every voxel even
    /// beyond the budget ([`Purpose::Analysis`]'s `every_voxel`).
    Asked(Resolution, bool),
    /// The level a picture is drawn from: the finest whose whole analysis fits the budget
    /// ([`Purpose::Picture`]), as `render`, `preview` and the TUI analyse.
    Picture,
}

impl Level {
    /// The pyramid level this asks for, counted from `volume` (0 for a picture's): a level
    /// number past the volume's last is an error about `resolution`. For a level read without
    /// level 0 ([`Volume::unread_finest`]: a remote store's coarser dataset), the level is picked
    /// on level 0's pyramid and counted from the level read; a finer one is an error.
    pub fn wanted(self, volume: &Volume) -> Result<usize> {
        let Self::Asked(resolution, _) = self else {
            return Ok(0);
        };
        let level = resolution.level(&volume.pyramid_dims())?;
        let here = match volume.unread_finest() {
            Some(_) => volume.level().index,
            None => 0,
        };
        level.checked_sub(here).ok_or_else(|| {
            crate::error::Error::invalid(
                "resolution",
                level,
                format!("pyramid level {here} or coarser: that level was read without level 0"),
            )
        })
    }
}

/// An analysis to run: its parameters, its level, its memory budget and the values the user
/// gave. Run it in two steps ([`plan`](Self::plan), then [`Planned::run`]) to look at the plan
/// before the work starts, or in one ([`run`](Self::run)).
#[derive(Clone, Debug, PartialEq)]
pub struct AnalysisRequest {
    /// How to analyse.
    pub params: AnalysisParams,
    /// Which level to analyse.
    pub level: Level,
    /// The memory budget.
    pub budget: Budget,
    /// The values the user gave, when the parameters came from them: an error about a
    /// parameter not given then blames its default ([`Given::blame`]).
    pub given: Option<Given>,
}

impl AnalysisRequest {
    /// An analysis by `params` of every voxel (the default, not named) within `max_memory`
    /// bytes.
    #[must_use]
    pub fn new(params: AnalysisParams, max_memory: u64) -> Self {
        Self {
            params,
            level: Level::Asked(Resolution::Full, false),
            budget: Budget::new(max_memory),
            given: None,
        }
    }

    /// Where the analysis of `volume` runs within the budget.
    pub fn plan(&self, volume: &Volume) -> Result<Planned<'_>> {
        let wanted = self.level.wanted(volume)?;
        let purpose = match self.level {
            Level::Asked(_, named) => Purpose::Analysis {
                wanted,
                every_voxel: wanted == 0 && named && volume.unread_finest().is_none(),
                params: &self.params,
            },
            Level::Picture => Purpose::Picture,
        };
        Ok(Planned {
            request: self,
            plan: self.budget.plan(volume, purpose)?,
        })
    }

    /// This request's work on `level` as it is, in memory: a level the planner chose before,
    /// which the budget is not asked about again. The TUI works so on the volume its load's
    /// [`Level::Picture`] plan gave and on that volume's glance ([`Purpose::Glance`]), which it
    /// shows first.
    #[must_use]
    pub fn on(&self, level: Arc<Volume>) -> Planned<'_> {
        Planned {
            request: self,
            plan: Plan::at(level),
        }
    }

    /// The analysis of `volume`: planned, then run.
    pub fn run(&self, volume: &Volume, monitor: &Monitor) -> Result<Analysed> {
        self.plan(volume)?.run(monitor)
    }
}

/// An analysis planned: the request and where its work runs.
#[derive(Clone, Debug)]
pub struct Planned<'a> {
    request: &'a AnalysisRequest,
    /// Where the view search and the partition run.
    pub plan: Plan,
}

impl Planned<'_> {
    /// The request planned.
    #[must_use]
    pub fn request(&self) -> &AnalysisRequest {
        self.request
    }

    /// What the user should know before a view search that asks for many times the default's
    /// work starts ([`AnalysisParams::heavy_work`] on the level it runs on).
    #[must_use]
    pub fn heavy_work(&self) -> Option<String> {
        let views = self.plan.views.as_ref();
        self.request
            .params
            .heavy_work(views.dims(), views.spacing())
    }

    /// The view search by the request's view parameters on the level planned for it, alone:
    /// the first step of [`run`](Self::run), for a front end that shows the views before the
    /// slabs (the TUI's sphere and list of views).
    pub fn views(&self, monitor: &Monitor) -> Result<ViewSearch> {
        self.plan.search(&self.request.params.view, monitor)
    }

    /// The axes ranked by partition gain on the view search's level, alone.
    pub fn gain(&self, monitor: &Monitor) -> Result<GainRanking> {
        rank_by_gain(&self.plan.views, &self.request.params, monitor)
    }

    /// The histories along `axis` (a unit physical direction) on the level partitioned, every
    /// method's ([`Scope::ALL`]): what an interactive front end steps through, switching method,
    /// slab count or threshold with nothing counted again (the TUI). A plan that counts its
    /// slabs strip by strip keeps what the request's own method reads, with no bottom-up
    /// history, as [`run`](Self::run) does.
    pub fn histories(&self, axis: [f64; 3], monitor: &Monitor) -> Result<Histories> {
        let (params, level) = (&self.request.params, self.plan.partition.as_ref());
        match self.plan.streamed {
            Some(room) => partition_streamed_kept(level, axis, &params.partition(), room, monitor)
                .map(|(_, histories)| histories),
            None => Histories::new(level, axis, &params.stack(), Scope::ALL, monitor),
        }
    }

    /// Runs the view search and the partition. An error about a parameter not given blames its
    /// default, and one the budget's coarser level caused blames the budget
    /// ([`blame`](crate::budget::blame)).
    pub fn run(self, monitor: &Monitor) -> Result<Analysed> {
        self.run_with(None, monitor)
    }

    /// [`run`](Self::run) with the view search's result found already (counted in parts,
    /// [`analyze_with_views`](crate::analysis::analyze_with_views)): the rest of the analysis,
    /// on the plan (its views of every voxel: level 0); `None` runs the search here.
    pub fn run_with(self, views: Option<ViewSearch>, monitor: &Monitor) -> Result<Analysed> {
        let request = self.request;
        let analysed = match views {
            None => analyze_planned(&self.plan, &request.params, monitor),
            Some(views) if self.plan.views.level().index == 0 => {
                analyze_planned_with(&self.plan, &request.params, Some(views), monitor)
            }
            Some(_) => Err(self.coarser_than_the_views()),
        };
        let analysis = analysed.map_err(|e| {
            let e = match &request.given {
                Some(given) => given.blame(e),
                None => e,
            };
            blame(&self.plan, e)
        })?;
        Ok(Analysed {
            params: request.params.clone(),
            plan: self.plan,
            analysis,
        })
    }

    /// The refusal of views counted on every voxel for a plan of a coarser level: blamed on
    /// the budget when the budget chose that level ([`Error::TooCoarse`], whose front ends say
    /// how to raise it).
    fn coarser_than_the_views(&self) -> crate::error::Error {
        let cause = crate::error::Error::Degenerate(format!(
            "the views, counted in parts on every voxel, cannot finish an analysis of pyramid \
             level {}",
            self.plan.views.level().index
        ));
        match &self.plan.note {
            Some(note) => crate::error::Error::TooCoarse {
                note: note.clone(),
                cause: Box::new(cause),
            },
            None => cause,
        }
    }
}

/// An analysis done: what it found, where it ran, and how it was asked.
#[derive(Clone, Debug)]
pub struct Analysed {
    /// The parameters it ran with.
    pub params: AnalysisParams,
    /// Where it ran.
    pub plan: Plan,
    /// What it found.
    pub analysis: Analysis,
}

impl Analysed {
    /// The pyramid level partitioned (the volume itself at full resolution): the slabs are its
    /// slices, and a picture of them is drawn from it.
    #[must_use]
    pub fn level(&self) -> &Arc<Volume> {
        &self.plan.partition
    }

    /// The report of this analysis of `full` (read from `name`), as `analyze --json` prints it:
    /// the volume's own dimensions and geometry, the level partitioned and, when the view
    /// search ran on another, that level.
    pub fn report(&self, name: &str, full: &Volume) -> Result<AnalysisReport> {
        Ok(
            AnalysisReport::new(name, full, &self.params.view, &self.analysis)?
                .computed_on(&self.plan.partition)
                .views_on(&self.plan.views),
        )
    }
}
