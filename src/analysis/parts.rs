//! The analysis of a volume whose view search was counted in parts (issue #44,
//! [`ViewRounds`](crate::view::ViewRounds)): the rest of [`analyze`](super::analyze) from the
//! view search's result, so that the parts' sum gives the analysis one process gives.

use std::sync::Arc;

use super::{Analysis, AnalysisParams, Plan, analyzed_with};
use crate::error::{Error, Result};
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
    match (&views, params.runs_search()) {
        (None, true) => {
            return Err(Error::invalid(
                "views",
                "none",
                "the view search's result: these parameters search the views",
            ));
        }
        (Some(_), false) => {
            return Err(Error::invalid(
                "views",
                "a view search",
                "none: an axis is given and no view search was asked for",
            ));
        }
        _ => {}
    }
    analyzed_with(plan, params, views, monitor)
}

#[cfg(test)]
mod tests {
    use std::ops::Range;

    use super::*;
    use crate::analysis::analyze;
    use crate::measure::PartialCounts;
    use crate::testing::Lcg;
    use crate::view::{ViewRound, ViewRounds};
    use crate::volume::{SlabGrid, phantom};

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
        let shifted = if rounds.has_shifted() {
            let samples = rounds.paper_samples(v, &paper).unwrap();
            count(&ViewRound::Shifted(samples), lcg)
        } else {
            Vec::new()
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
