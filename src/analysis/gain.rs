//! The axis whose slabs keep the most (docs/design.md §6): every axis of the viewpoint sphere
//! ranked by `partition_gain`, the information `I(slab; value)` kept by the top-down partition
//! into K slabs along it, beside the paper's entropy rate. On layered data the entropy rate is
//! lowest inside the layers, so its slabs cut across them; the gain is highest across them.
//!
//! Each axis is scored on a subset of the voxels (every `e`-th along the two grid axes most
//! across it), each counted in the slice of the axis's stack its centre lies in
//! ([`sampled_gain`]), so that ranking costs a fraction of cutting every stack, over four shifts; their mean ranks the axes, their standard error names the contenders (§2's rule, the
//! highest gain best), and a pattern search refines the best sphere axis between the vertices.

use serde::Serialize;

use super::AnalysisParams;
use crate::error::Result;
use crate::geometry::{WorldAxis, azimuth_elevation, canonical, normalize};
use crate::partition::{InPlane, StackParams, Stop, sampled_gain};
use crate::progress::Monitor;
use crate::view::{
    AxisEntropy, Contender, PhaseStats, ViewSearch, icosphere, pattern_search, refine_steps,
};
use crate::volume::Volume;
use crate::volume::background::Background;

/// Which ranking picks the axis.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum AxisBy {
    /// The lowest entropy rate: the paper's most structured view.
    #[default]
    Entropy,
    /// The highest partition gain: the axis whose slabs keep the most.
    Gain,
}

impl AxisBy {
    /// The name used on the command line and in JSON.
    pub fn name(self) -> &'static str {
        match self {
            Self::Entropy => "entropy",
            Self::Gain => "gain",
        }
    }
}

/// Two rankings whose best axes lie within this angle agree, degrees.
pub const AGREE_DEGREES: f64 = 5.0;

/// The slab count the gain is measured at when the partition stops by a threshold.
pub const THRESHOLD_SLABS: usize = 4;

/// A ranking subset keeps at least this many voxels of a slice's typical area per phase.
pub const MIN_PIXELS: f64 = 4096.0;

/// The sparsest subset the ranking takes: one voxel in this many along each of two grid axes.
pub const MAX_EVERY: usize = 4;

/// Which voxels the ranking counted, for the report: `{"slabs": 4, "every": 3, "phases": 4}`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct GainSampling {
    /// The slab count K the gain is measured at.
    pub slabs: usize,
    /// One voxel in this many along the two grid axes most across each axis (1: every voxel).
    pub every: usize,
    /// The shifts of the subset averaged on oblique axes (coordinate axes counted on every
    /// voxel have one).
    pub phases: usize,
}

/// One axis by its gain.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AxisGain {
    /// The canonical axis.
    pub axis: [f64; 3],
    /// The axis in world coordinates.
    #[serde(flatten)]
    pub world: WorldAxis,
    /// As the views give it, degrees.
    pub azimuth: f64,
    /// As the views give it, degrees.
    pub elevation: f64,
    /// `I(slab; value)`, bits, on the unshifted subset.
    pub partition_gain: f64,
    /// The gain over the subset's shifts, whose mean ranks the axes.
    pub gain_phases: PhaseStats,
}

/// Every sphere axis by its gain, best first, with the refined best and the contenders.
#[derive(Clone, Debug)]
pub struct GainRanking {
    /// The sphere's axes, highest mean gain first (ties keep the sphere's order).
    pub views: Vec<AxisGain>,
    /// The best axis found near the best sphere axis.
    pub refined: AxisGain,
    /// The best axis and every axis within two standard errors of it, best first.
    pub contenders: Vec<Contender>,
    /// How the ranking sampled.
    pub sampling: GainSampling,
}

impl GainRanking {
    /// Whether another axis is a contender.
    pub fn uncertain(&self) -> bool {
        self.contenders.len() > 1
    }

    /// The angle between the gain's best axis and `entropy`'s (the entropy rate's best), when
    /// the two rankings disagree: more than [`AGREE_DEGREES`] apart.
    pub fn disagrees_with(&self, entropy: [f64; 3]) -> Option<f64> {
        let apart = crate::view::axis_angle(entropy, self.refined.axis);
        (apart > AGREE_DEGREES).then_some(apart)
    }

    /// Sets the gain of `axis`, wherever the ranking and `views` hold it, to `information`:
    /// the partition's along it, counted on every voxel.
    pub fn exact(&mut self, axis: [f64; 3], information: f64, views: Option<&mut ViewSearch>) {
        let entries = self
            .views
            .iter_mut()
            .chain(std::iter::once(&mut self.refined));
        for g in entries.filter(|g| same(g.axis, axis)) {
            g.partition_gain = information;
        }
        for v in views.into_iter().flat_map(|v| v.views.iter_mut()) {
            if same(v.axis, axis) && v.partition_gain.is_some() {
                v.partition_gain = Some(information);
            }
        }
    }

    /// Writes each sphere axis's gain into `views`' entry for it.
    pub fn annotate(&self, views: &mut ViewSearch) {
        for v in &mut views.views {
            if let Some(g) = self.views.iter().find(|g| g.axis == v.axis) {
                v.partition_gain = Some(g.partition_gain);
                v.gain_phases = Some(g.gain_phases);
            }
        }
    }

    /// `views` in the gain ranking's order, best first (axes it did not rank last).
    pub fn sorted<'v>(&self, views: &'v [AxisEntropy]) -> Vec<&'v AxisEntropy> {
        let place = |axis: [f64; 3]| {
            self.views
                .iter()
                .position(|g| g.axis == axis)
                .unwrap_or(usize::MAX)
        };
        let mut out: Vec<&AxisEntropy> = views.iter().collect();
        out.sort_by_key(|v| place(v.axis));
        out
    }
}

/// The slab count the gain is measured at: the partition's own, or [`THRESHOLD_SLABS`].
pub fn gain_slabs(stop: Stop) -> usize {
    match stop {
        Stop::Slabs(k) => k,
        Stop::Threshold(_) => THRESHOLD_SLABS,
    }
}

/// One voxel in how many the ranking of `volume` keeps along the two grid axes most across each
/// axis: as few as keep [`MIN_PIXELS`] of a slice's typical area (the voxel count to the power
/// 2/3), at most [`MAX_EVERY`], the same for every axis so that their gains compare.
pub fn ranking_every(volume: &Volume) -> usize {
    let area = (volume.len() as f64).powf(2.0 / 3.0);
    ((area / MIN_PIXELS).sqrt().floor() as usize).clamp(1, MAX_EVERY)
}

/// What scores one axis.
struct Scorer<'a> {
    volume: &'a Volume,
    stack: StackParams,
    background: Background,
    sampling: GainSampling,
}

impl Scorer<'_> {
    /// The gain of `axis` on phase `phase` of the subset.
    fn gain(&self, axis: [f64; 3], phase: usize, monitor: &Monitor) -> Result<f64> {
        let in_plane = InPlane {
            every: self.sampling.every,
            phase,
        };
        sampled_gain(
            self.volume,
            axis,
            &self.stack,
            &self.background,
            in_plane,
            self.sampling.slabs,
            monitor,
        )
    }

    /// The phases `axis` is scored on.
    fn phases(&self, axis: [f64; 3]) -> usize {
        InPlane::phases(self.sampling.every, axis).min(self.sampling.phases)
    }

    /// `axis` scored on its unshifted subset only: what the pattern search compares.
    fn quick(&self, axis: [f64; 3]) -> Result<AxisGain> {
        let axis = canonical(normalize(axis).unwrap_or(axis));
        let g = self.gain(axis, 0, &Monitor::none())?;
        Ok(self.entry(axis, &[g]))
    }

    /// `axis` scored on every phase, advancing `monitor` a unit a phase.
    fn full(&self, axis: [f64; 3], monitor: &Monitor) -> Result<AxisGain> {
        let axis = canonical(normalize(axis).unwrap_or(axis));
        let values = (0..self.phases(axis))
            .map(|n| {
                let g = self.gain(axis, n, monitor)?;
                monitor.advance(1)?;
                Ok(g)
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(self.entry(axis, &values))
    }

    fn entry(&self, axis: [f64; 3], values: &[f64]) -> AxisGain {
        let (azimuth, elevation) = azimuth_elevation(axis);
        AxisGain {
            axis,
            world: self
                .volume
                .transform()
                .describe(axis, self.volume.spacing()),
            azimuth,
            elevation,
            partition_gain: values[0],
            gain_phases: PhaseStats::of(values),
        }
    }
}

/// Ranks every axis of the viewpoint sphere (`params.view.level`) of `volume` by the gain of its
/// top-down partition into K slabs ([`gain_slabs`]) with `params`' background and sampling, and
/// refines the best between the sphere's vertices.
pub fn rank_by_gain(
    volume: &Volume,
    params: &AnalysisParams,
    monitor: &Monitor,
) -> Result<GainRanking> {
    crate::partition::Histories::check_not_constant(volume)?;
    let sampling = GainSampling {
        slabs: gain_slabs(params.stop),
        every: ranking_every(volume),
        phases: 4,
    };
    let scorer = Scorer {
        volume,
        stack: params.stack(),
        background: Background::find(volume, params.background, monitor)?,
        sampling,
    };
    let axes = icosphere::axes(params.view.level);
    let start = icosphere::spacing_degrees(params.view.level) / 2.0;
    let refining = refine_steps(start) * 8 + sampling.phases as u64;
    let total = axes.iter().map(|&a| scorer.phases(a) as u64).sum::<u64>() + refining;
    monitor.start("ranking axes by partition gain", total);
    let mut views = axes
        .iter()
        .map(|&axis| scorer.full(axis, monitor))
        .collect::<Result<Vec<_>>>()?;
    views.sort_by(|a, b| b.gain_phases.mean.total_cmp(&a.gain_phases.mean));
    let found = pattern_search(
        &scorer.quick(views[0].axis)?,
        start,
        |g| g.axis,
        |axis| scorer.quick(axis),
        |a, b| a.partition_gain > b.partition_gain,
        || monitor.advance(8),
    )?;
    let refined = if found.axis == views[0].axis {
        views[0].clone()
    } else {
        scorer.full(found.axis, monitor)?
    };
    Ok(GainRanking {
        contenders: contenders(&refined, &views),
        views,
        refined,
        sampling,
    })
}

/// `best` and every axis of `views` whose mean gain lies within two standard errors of the
/// difference below it, `mean_best - mean_b < 2·√(se_b² + se_best²)`, best first.
fn contenders(best: &AxisGain, views: &[AxisGain]) -> Vec<Contender> {
    let of = |a: &AxisGain| Contender {
        axis: a.axis,
        mean: a.gain_phases.mean,
        se: a.gain_phases.se(),
    };
    let b = of(best);
    std::iter::once(b)
        .chain(
            views
                .iter()
                .filter(|a| a.axis != best.axis)
                .map(of)
                .filter(|c| b.mean - c.mean < 2.0 * c.se.hypot(b.se)),
        )
        .collect()
}

/// Whether two canonical unit axes are one (up to the rounding of normalizing one again).
fn same(a: [f64; 3], b: [f64; 3]) -> bool {
    (0..3).all(|m| (a[m] - b[m]).abs() < 1e-12)
}
