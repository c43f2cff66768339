//! The whole analysis of one volume, as `analyze`, the TUI's export and triage run it: the most
//! structured view (paper §3.1, §4), then the slabs along it (paper §5).

use crate::error::Result;
use crate::geometry::AxisChoice;
use crate::partition::{Method, Partition, PartitionParams, StackParams, Stop, partition};
use crate::progress::Monitor;
use crate::view::{ViewParams, ViewSearch, search};
use crate::volume::Volume;
use crate::volume::background::BackgroundRule;

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

    /// Whether the view search runs.
    pub fn runs_search(&self) -> bool {
        self.axis == AxisChoice::Best || self.search_views
    }
}

/// The result of an analysis.
#[derive(Clone, Debug)]
pub struct Analysis {
    /// The view search, when it ran.
    pub views: Option<ViewSearch>,
    /// The partition along the chosen axis.
    pub partition: Partition,
    /// What the user should know: spacings coarsened to the sample budget, histories cut short.
    pub notes: Vec<String>,
}

impl Analysis {
    /// The axis partitioned along.
    pub fn axis(&self) -> [f64; 3] {
        self.partition.axis
    }
}

/// Runs the view search (unless an axis is given) and partitions along the axis.
pub fn analyze(volume: &Volume, params: &AnalysisParams, monitor: &Monitor) -> Result<Analysis> {
    let chosen = params.axis.resolve(volume.transform(), volume.spacing())?;
    let views = if params.runs_search() {
        Some(search(volume, &params.view, monitor)?)
    } else {
        None
    };
    let axis = match (chosen, &views) {
        (Some(a), _) => a.direction(),
        (None, Some(v)) => v.best().axis,
        (None, None) => unreachable!("the view search runs when no axis is given"),
    };
    let partition = partition(volume, axis, &params.partition(), monitor)?;
    let notes = notes(volume, &params.view, &partition);
    Ok(Analysis {
        views,
        partition,
        notes,
    })
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

/// The notes of an analysis of `volume` with `view`'s sampling that gave `partition`.
pub fn notes(volume: &Volume, view: &ViewParams, partition: &Partition) -> Vec<String> {
    resolution_note(volume)
        .into_iter()
        .chain(view.sampling.budget_note(volume.dims(), volume.spacing()))
        .chain(partition.notes.iter().cloned())
        .collect()
}
