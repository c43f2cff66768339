//! The analysis of a volume whose view search was counted in parts (issue #44,
//! [`ViewRounds`](crate::view::ViewRounds)): the rest of [`analyze`](super::analyze) from the
//! view search's result, so that the parts' sum gives the analysis one process gives.

use std::sync::Arc;

use super::{Analysis, AnalysisParams, Plan, analyzed_with, axis_of, notes};
use crate::error::{Error, Result};
use crate::geometry::Axis;
use crate::partition::Partition;
use crate::progress::Monitor;
use crate::view::ViewSearch;
use crate::volume::Volume;

/// [`analyze`](super::analyze) of `volume` by `params`, its view search's result `views`
/// given (counted in parts and finished by [`ViewRounds::finish`](crate::view::ViewRounds::finish);
/// `None` when no view search runs): the same [`Analysis`], the background, the partition and
/// (when asked for) the gain ranking found here on the whole volume.
pub fn analyze_with_views(
    volume: &Volume,
    params: &AnalysisParams,
    views: Option<ViewSearch>,
    monitor: &Monitor,
) -> Result<Analysis> {
    analyze_planned_with(&Plan::at(Arc::new(volume.clone())), params, views, monitor)
}

/// [`analyze_with_views`] on `plan`: its partition (in memory or strip by strip) along the axis
/// of `views`, a view search of level 0 found already.
pub(crate) fn analyze_planned_with(
    plan: &Plan,
    params: &AnalysisParams,
    views: Option<ViewSearch>,
    monitor: &Monitor,
) -> Result<Analysis> {
    check_views(params, views.as_ref())?;
    analyzed_with(plan, params, views, monitor)
}

/// An error unless `views` is there exactly when `params` run the view search.
fn check_views(params: &AnalysisParams, views: Option<&ViewSearch>) -> Result<()> {
    match (views, params.runs_search()) {
        (None, true) => Err(Error::invalid(
            "views",
            "none",
            "the view search's result: these parameters search the views",
        )),
        (Some(_), false) => Err(Error::invalid(
            "views",
            "a view search",
            "none: an axis is given and no view search was asked for",
        )),
        _ => Ok(()),
    }
}

/// The axis the partition of an analysis in parts runs along (a unit physical direction): the
/// one `params` name, else the best of `views`. The ranking by gain and `explain`, which read
/// the voxels where they are, are refused: they do not run in parts.
pub fn partition_axis(
    grid: &Volume,
    params: &AnalysisParams,
    views: Option<&ViewSearch>,
) -> Result<[f64; 3]> {
    if params.ranks_by_gain() {
        return Err(Error::invalid(
            "axis_by",
            "gain",
            "the entropy rate's ranking alone in parts (the gain ranking reads the voxels where \
             they are)",
        ));
    }
    if params.explain.is_some() {
        return Err(Error::invalid(
            "explain",
            "steps",
            "none in parts (its numbers read the voxels where they are)",
        ));
    }
    check_views(params, views)?;
    let chosen = params.axis.resolve(grid.transform(), grid.spacing())?;
    Ok(axis_of(chosen.map(Axis::direction), views))
}

/// The analysis of a volume whose view search and partition were both counted in parts:
/// `grid` the whole volume's grid and statistics (it need hold no voxel: a volume of an empty
/// box, [`Volume::of_box`], will do), `views` the view search's result, `partition` the one a
/// [`StackSplit`](crate::partition::StackSplit) finished along [`partition_axis`]. The same
/// [`Analysis`] as [`analyze`](super::analyze) of the whole volume, at full resolution.
pub fn analyze_with_partition(
    grid: &Volume,
    params: &AnalysisParams,
    views: Option<ViewSearch>,
    partition: Partition,
) -> Result<Analysis> {
    let axis = partition_axis(grid, params, views.as_ref())?;
    let along: f64 = (0..3).map(|m| axis[m] * partition.axis[m]).sum();
    if along.abs() < 1.0 - 1e-9 {
        return Err(Error::invalid(
            "partition",
            "a partition along another axis",
            "the partition along the axis the views and parameters choose",
        ));
    }
    let notes = notes(grid, grid, &params.view, &partition);
    let chosen = params.axis.resolve(grid.transform(), grid.spacing())?;
    Ok(Analysis {
        views,
        gain: None,
        axis_by: chosen.is_none().then_some(params.axis_by),
        partition,
        notes,
        explain: None,
    })
}

#[cfg(test)]
mod tests {
    use std::ops::Range;

    use super::*;
    use crate::analysis::analyze;
    use crate::measure::PartialCounts;
    use crate::partition::Stop;
    use crate::partition::parts_testing::in_parts;
    use crate::testing::Lcg;
    use crate::view::{ViewRound, ViewRounds};
    use crate::volume::background::Background;
    use crate::volume::{SlabGrid, VoxelBox, phantom};

    /// Cell planes `0..cells` cut at random into slabs of 1 to 6 planes.
    fn random_slabs(cells: usize, lcg: &mut Lcg) -> Vec<Range<usize>> {
        let mut slabs = Vec::new();
        let mut z = 0;
        while z < cells {
            let end = (z + 1 + (lcg.next_u64() >> 33) as usize % 6).min(cells);
            slabs.push(z..end);
            z = end;
        }
        slabs
    }

    /// The view search of `v` by `params`, every slab counted from its own voxel planes alone
    /// and the parts added in a shuffled order.
    fn search_in_parts(v: &Volume, params: &AnalysisParams, lcg: &mut Lcg) -> ViewSearch {
        let rounds = ViewRounds::new(v, &params.view).unwrap();
        let slabs = random_slabs(v.dims()[2] - 1, lcg);
        let [nx, ny, nz] = v.dims();
        let count = |round: &ViewRound, lcg: &mut Lcg| -> Vec<PartialCounts> {
            let mut parts: Vec<Vec<PartialCounts>> = slabs
                .iter()
                .map(|planes| {
                    let held = rounds.voxel_planes(planes, nz);
                    let slab = crate::volume::with_voxels!(v.data(), |d| {
                        Volume::of_slab(
                            &SlabGrid::of(v),
                            held.start,
                            &d[held.start * nx * ny..held.end * nx * ny],
                        )
                    })
                    .unwrap();
                    rounds.count_slab(&slab, round, planes.clone()).unwrap()
                })
                .collect();
            for i in (1..parts.len()).rev() {
                parts.swap(i, (lcg.next_u64() >> 33) as usize % (i + 1));
            }
            let mut sum = rounds.zero(v, round).unwrap();
            for part in parts {
                sum.iter_mut().zip(part).for_each(|(s, p)| s.add(p));
            }
            sum
        };
        let paper = count(&ViewRound::Paper, lcg);
        let shifted = match rounds.shifted_after(v, &ViewRound::Paper, &paper).unwrap() {
            Some(next) => count(&next, lcg),
            None => Vec::new(),
        };
        let sphere = rounds.finish(v, &paper, &shifted).unwrap();
        rounds
            .refine(v, sphere, |round| Ok(count(round, lcg)))
            .unwrap()
    }

    /// What an analysis reports, as JSON text.
    fn report(a: &Analysis) -> String {
        let json = serde_json::to_string(&(&a.views, &a.axis_by, &a.partition, &a.notes));
        format!("{} {:?}", json.unwrap(), a.gain)
    }

    #[test]
    fn an_analysis_from_parts_is_the_analysis_bit_for_bit() {
        let mut lcg = Lcg::new(4404);
        let none = Monitor::none();
        let body = phantom::body([26, 22, 30], 7).unwrap();
        let layers = phantom::layers([24, 20, 28], [0.3, 0.2, 1.0], 3).unwrap();
        for v in [body, layers] {
            let mut refined = AnalysisParams::default();
            refined.view.refine = true;
            for params in [AnalysisParams::paper(), AnalysisParams::default(), refined] {
                let expect = report(&analyze(&v, &params, &none).unwrap());
                let views = search_in_parts(&v, &params, &mut lcg);
                let got = analyze_with_views(&v, &params, Some(views), &none).unwrap();
                assert_eq!(report(&got), expect, "{:?}", params.background);
            }
        }
    }

    #[test]
    fn an_analysis_with_its_partition_in_parts_too_is_the_analysis_bit_for_bit() {
        let mut lcg = Lcg::new(4405);
        let none = Monitor::none();
        let body = phantom::body([26, 22, 30], 7).unwrap();
        let layers = phantom::layers([24, 20, 28], [0.3, 0.2, 1.0], 3).unwrap();
        for v in [body, layers] {
            // The grid alone: no voxel held.
            let empty = VoxelBox {
                origin: [0; 3],
                size: [0; 3],
            };
            let grid = Volume::of_box::<u8>(&SlabGrid::of(&v), empty, &[]).unwrap();
            let along_x = AnalysisParams {
                axis: crate::geometry::AxisChoice::Along(crate::geometry::Axis::X),
                stop: Stop::Slabs(3),
                ..AnalysisParams::default()
            };
            for params in [AnalysisParams::paper(), AnalysisParams::default(), along_x] {
                let expect = report(&analyze(&v, &params, &none).unwrap());
                let views = params
                    .runs_search()
                    .then(|| search_in_parts(&v, &params, &mut lcg));
                let axis = partition_axis(&grid, &params, views.as_ref()).unwrap();
                // The background as the whole volume's (found in parts elsewhere).
                let background = Background::find(&v, params.background, &none).unwrap();
                let p = params.partition();
                let partition = in_parts(&v, axis, &p, &background, &mut lcg);
                let got = analyze_with_partition(&grid, &params, views, partition).unwrap();
                assert_eq!(report(&got), expect, "{:?}", params.axis);
            }
        }
        // What does not run in parts is refused.
        let v = phantom::body([12, 12, 12], 2).unwrap();
        let gain = AnalysisParams {
            gain: true,
            ..AnalysisParams::default()
        };
        let views = crate::view::search(&v, &gain.view, &none).unwrap();
        let e = partition_axis(&v, &gain, Some(&views)).unwrap_err();
        assert!(e.to_string().contains("gain"), "{e}");
    }

    #[test]
    fn views_must_match_whether_the_search_runs() {
        let v = phantom::body([12, 12, 12], 2).unwrap();
        let none = Monitor::none();
        let e = analyze_with_views(&v, &AnalysisParams::paper(), None, &none).unwrap_err();
        assert!(e.to_string().contains("views"), "{e}");
        let given = AnalysisParams {
            axis: crate::geometry::AxisChoice::Along(crate::geometry::Axis::Z),
            ..AnalysisParams::paper()
        };
        let views = crate::view::search(&v, &given.view, &none).unwrap();
        let e = analyze_with_views(&v, &given, Some(views), &none).unwrap_err();
        assert!(e.to_string().contains("no view search"), "{e}");
        let expect = report(&analyze(&v, &given, &none).unwrap());
        assert_eq!(
            report(&analyze_with_views(&v, &given, None, &none).unwrap()),
            expect
        );
    }
}
