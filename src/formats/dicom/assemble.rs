//! Series assembly, as dcm2niix and ITK do it: images grouped by `SeriesInstanceUID` and split
//! where orientation, matrix, pixel spacing or echo differ; localizers and derived images left
//! out unless asked for; each series sorted along the slice normal (positions dotted with the
//! normal of the orientation), the spacing between slices taken from the positions; gaps,
//! uneven spacing, repeated positions (4D) and gantry tilt found and reported.

use std::cmp::Ordering;
use std::collections::BTreeMap;

use super::header::Image;
use crate::geometry::{cross, dot, normalize};

/// Positions closer than this (mm) along the normal are the same slice position.
const SAME_POSITION: f64 = 0.01;

/// Steps differing from the median by more than this fraction of it make the spacing uneven.
const UNEVEN: f64 = 0.01;

/// A step this many times the median is a gap: slices are missing.
const GAP: f64 = 1.5;

/// Tilt below this many degrees is rounding in the positions.
const TILT_DEGREES: f64 = 0.05;

/// One series: images of one `SeriesInstanceUID` that share orientation, matrix, spacing and echo.
#[derive(Clone, Debug)]
pub(super) struct Series {
    /// The `SeriesInstanceUID`, with `#2`, `#3`, ... on the parts of one split in several.
    pub key: String,
    /// `SeriesInstanceUID`.
    pub uid: String,
    /// `SeriesNumber`.
    pub number: Option<i64>,
    /// `SeriesDescription`.
    pub description: String,
    /// Modality.
    pub modality: String,
    /// The images.
    pub images: Vec<Image>,
}

impl Series {
    /// How a list names the series: its number and description, or its key.
    pub fn label(&self) -> String {
        let number = self
            .number
            .map_or_else(String::new, |n| format!("series {n}"));
        match (number.is_empty(), self.description.is_empty()) {
            (false, false) => format!("{number} \"{}\"", self.description),
            (false, true) => number,
            (true, false) => format!("\"{}\"", self.description),
            (true, true) => format!("series {}", self.key),
        }
    }
}

/// Images left out of every series, counted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) struct LeftOut {
    /// Localizer (scout) images.
    pub localizers: usize,
    /// Derived images.
    pub derived: usize,
}

fn rounded(v: f64, step: f64) -> i64 {
    (v / step).round() as i64
}

/// What splits a series: orientation, matrix, pixel spacing, echo.
fn split_key(im: &Image) -> (Vec<i64>, [usize; 2], Vec<i64>, String) {
    (
        im.orientation
            .map(|o| o.iter().map(|&v| rounded(v, 1e-3)).collect())
            .unwrap_or_default(),
        im.plane(),
        im.pixel_spacing
            .map(|s| s.iter().map(|&v| rounded(v, 1e-4)).collect())
            .unwrap_or_default(),
        im.echo.clone().unwrap_or_default(),
    )
}

/// Groups `images` into series, sorted by UID. Unless `include_all`, localizers are left out,
/// and so are derived images in a series that also holds original ones (a screen capture among
/// the slices); a series of derived images only (a reformat, a parameter map) is kept.
pub(super) fn group(images: Vec<Image>, include_all: bool) -> (Vec<Series>, LeftOut) {
    let mut left = LeftOut::default();
    let mut by_uid: BTreeMap<String, Vec<Image>> = BTreeMap::new();
    for im in images {
        if !include_all && im.localizer {
            left.localizers += 1;
        } else {
            by_uid.entry(im.series_uid.clone()).or_default().push(im);
        }
    }
    if !include_all {
        for images in by_uid.values_mut() {
            if images.iter().any(|im| !im.derived) {
                let before = images.len();
                images.retain(|im| !im.derived);
                left.derived += before - images.len();
            }
        }
        by_uid.retain(|_, images| !images.is_empty());
    }
    let mut series = Vec::new();
    for (uid, images) in by_uid {
        let mut parts: BTreeMap<_, Vec<Image>> = BTreeMap::new();
        for im in images {
            parts.entry(split_key(&im)).or_default().push(im);
        }
        // The largest part first: it keeps the plain UID.
        let mut parts: Vec<Vec<Image>> = parts.into_values().collect();
        parts.sort_by_key(|p| std::cmp::Reverse(p.len()));
        for (k, images) in parts.into_iter().enumerate() {
            let first = &images[0];
            series.push(Series {
                key: if k == 0 {
                    uid.clone()
                } else {
                    format!("{uid}#{}", k + 1)
                },
                uid: uid.clone(),
                number: first.series_number,
                description: first.description.clone(),
                modality: first.modality.clone(),
                images,
            });
        }
    }
    // By UID, the order of a triage's rows and of `--series N`; a split series' parts in turn.
    series.sort_by(|a, b| (&a.uid, a.key.len(), &a.key).cmp(&(&b.uid, b.key.len(), &b.key)));
    (series, left)
}

/// A voxel-to-patient (LPS) transform: the linear part (columns: the column, row and slice
/// steps, mm) and the origin (the first voxel's centre).
pub(super) type Lps = ([[f64; 3]; 3], [f64; 3]);

/// A series laid out as a volume: which image is each slice of each volume, and where.
#[derive(Clone, Debug)]
pub(super) struct Layout {
    /// Slices along the normal.
    pub slices: usize,
    /// Volumes (more than one: the positions repeat, a 4D series).
    pub volumes: usize,
    /// `order[v][k]`: the index in the series' images of slice `k` of volume `v`.
    pub order: Vec<Vec<usize>>,
    /// Columns, rows.
    pub plane: [usize; 2],
    /// Spacing between columns, between rows, between slices (mm).
    pub spacing: [f64; 3],
    /// The voxel-to-patient (LPS) transform: linear part (columns: the column, row and slice
    /// steps) and origin; `None` without positions and orientation.
    pub lps: Option<Lps>,
    /// Positions of the slices along the normal, from the first (mm).
    pub depths: Vec<f64>,
    /// Each slice's offset in the plane from the first, in pixels (columns, rows): non-zero
    /// under gantry tilt.
    pub shifts: Vec<[f64; 2]>,
    /// The spacing between slices is uneven or has gaps.
    pub uneven: bool,
    /// The gantry tilt in degrees, when there is one.
    pub tilt: Option<f64>,
    /// What a user should know.
    pub notes: Vec<String>,
    /// What is wrong with the series (gaps, uneven spacing, tilt), each on its own.
    pub problems: Vec<String>,
}

impl Layout {
    /// Whether resampling would change the grid: uneven spacing or tilt.
    pub fn needs_resampling(&self) -> bool {
        self.uneven || self.tilt.is_some()
    }

    /// The orthogonal, evenly spaced grid resampling gives: slices, and the new transform.
    pub fn resampled(&self) -> (usize, Option<Lps>) {
        let step = self.spacing[2];
        let depth = self.depths.last().copied().unwrap_or(0.0);
        let slices = (depth / step).round() as usize + 1;
        let lps = self.lps.map(|(m, origin)| {
            let col = |c: usize| [m[0][c], m[1][c], m[2][c]];
            let n = normalize(cross(col(0), col(1))).unwrap_or([0.0, 0.0, 1.0]);
            let mut m = m;
            for r in 0..3 {
                m[r][2] = n[r] * step;
            }
            (m, origin)
        });
        (slices, lps)
    }
}

/// Orders two images at one position: by temporal index, acquisition, time, instance, file
/// and frame.
fn repeat_order(a: &Image, b: &Image) -> Ordering {
    (
        a.temporal,
        a.acquisition,
        &a.time,
        a.instance,
        a.file,
        a.frame,
    )
        .cmp(&(
            b.temporal,
            b.acquisition,
            &b.time,
            b.instance,
            b.file,
            b.frame,
        ))
}

/// The slice plane's frame: the row and column directions and their normal.
type Frame = ([f64; 3], [f64; 3], [f64; 3]);

/// Orders `images` along the normal of `placed` (by instance number without one) and groups
/// those at one position: `runs[k]` holds the images at slice `k`, each run ordered in time.
fn runs(images: &[Image], placed: Option<Frame>) -> std::result::Result<Vec<Vec<usize>>, String> {
    let depth_of = |i: usize| placed.map_or(0.0, |(_, _, n)| depth(&images[i], n));
    let mut idx: Vec<usize> = (0..images.len()).collect();
    if placed.is_some() {
        idx.sort_by(|&a, &b| {
            depth_of(a)
                .total_cmp(&depth_of(b))
                .then_with(|| repeat_order(&images[a], &images[b]))
        });
    } else {
        idx.sort_by_key(|&i| (images[i].instance, images[i].file, images[i].frame));
    }
    let mut runs: Vec<Vec<usize>> = Vec::new();
    for i in idx {
        match runs.last_mut() {
            Some(run)
                if placed.is_some() && (depth_of(i) - depth_of(run[0])).abs() < SAME_POSITION =>
            {
                run.push(i);
            }
            _ => runs.push(vec![i]),
        }
    }
    let volumes = runs[0].len();
    if runs.iter().any(|r| r.len() != volumes) {
        let (lo, hi) = runs.iter().fold((usize::MAX, 0), |(lo, hi), r| {
            (lo.min(r.len()), hi.max(r.len()))
        });
        return Err(format!(
            "image positions repeat unevenly ({lo} to {hi} images at one position), so the \
             series is neither one volume nor a 4D series"
        ));
    }
    for run in &mut runs {
        run.sort_by(|&a, &b| repeat_order(&images[a], &images[b]));
    }
    Ok(runs)
}

/// An image's position along the normal `n`, mm.
fn depth(im: &Image, n: [f64; 3]) -> f64 {
    dot(im.position.unwrap_or_default(), n)
}

/// The spacing between slices at `depths` (their median step), and what is wrong with them:
/// gaps and uneven steps, between the images `name(k)` names.
fn spacing_between(depths: &[f64], name: &dyn Fn(usize) -> String) -> (Option<f64>, Vec<String>) {
    let steps: Vec<f64> = depths.windows(2).map(|w| w[1] - w[0]).collect();
    let mut sorted = steps.clone();
    sorted.sort_by(f64::total_cmp);
    let Some(&m) = sorted.get(sorted.len() / 2) else {
        return (None, Vec::new());
    };
    let mut problems = Vec::new();
    for (k, &s) in steps.iter().enumerate() {
        if s > GAP * m {
            problems.push(format!(
                "missing slices: a gap of {s:.3} mm between {} and {} where the spacing is \
                 {m:.3} mm",
                name(k),
                name(k + 1)
            ));
        }
    }
    let (lo, hi) = (sorted[0], sorted[sorted.len() - 1]);
    if problems.is_empty() && (hi - lo) > UNEVEN * m + 1e-3 {
        let at = steps
            .iter()
            .position(|&s| (s - m).abs() > UNEVEN * m + 5e-4)
            .unwrap_or(0);
        problems.push(format!(
            "uneven slice spacing: {lo:.3} to {hi:.3} mm (first off the median {m:.3} mm \
             between {} and {})",
            name(at),
            name(at + 1)
        ));
    }
    (Some(m), problems)
}

/// The tilt of a stack whose slices (first at `origin`) sit at `positions`, `step` mm apart
/// along `n`: the step between slices as it is (sheared when tilted), each slice's in-plane
/// offset from the first in pixels of `[dx, dy]`, and the tilt in degrees when there is one.
fn tilt(
    (r, c, n): Frame,
    positions: &[[f64; 3]],
    step: f64,
    [dx, dy]: [f64; 2],
) -> ([f64; 3], Vec<[f64; 2]>, Option<f64>) {
    let straight = n.map(|v| v * step);
    let still = vec![[0.0, 0.0]; positions.len()];
    let (Some(origin), Some(last)) = (positions.first(), positions.last()) else {
        return (straight, still, None);
    };
    if positions.len() < 2 {
        return (straight, still, None);
    }
    let v: [f64; 3] = std::array::from_fn(|k| (last[k] - origin[k]) / (positions.len() - 1) as f64);
    let inplane = [dot(v, r), dot(v, c)];
    let degrees = inplane[0].hypot(inplane[1]).atan2(dot(v, n)).to_degrees();
    if degrees <= TILT_DEGREES {
        return (straight, still, None);
    }
    let along = std::array::from_fn(|k| n[k] * step + r[k] * inplane[0] + c[k] * inplane[1]);
    let shifts = positions
        .iter()
        .map(|p| {
            let q: [f64; 3] = std::array::from_fn(|a| p[a] - origin[a]);
            [dot(q, r) / dx, dot(q, c) / dy]
        })
        .collect();
    (along, shifts, Some(degrees))
}

/// The slice plane's frame the orientation of `im` gives, when it gives one (both directions
/// and their normal non-zero).
fn frame_of(im: &Image) -> Option<Frame> {
    im.orientation.and_then(|o| {
        let r = normalize([o[0], o[1], o[2]])?;
        let c = normalize([o[3], o[4], o[5]])?;
        Some((r, c, normalize(cross(r, c))?))
    })
}

/// The step and depths of `slices` slices without positions or orientation, stacked in
/// instance order `stated` mm apart (1 mm when nothing says), noting both.
fn unplaced(slices: usize, stated: Option<f64>, notes: &mut Vec<String>) -> (f64, Vec<f64>) {
    notes.push(
        "no image positions or orientation: slices ordered by instance number, without \
         anatomical orientation"
            .into(),
    );
    if slices > 1 {
        notes.push(match stated {
            Some(s) => format!("slice spacing {s} mm from SpacingBetweenSlices"),
            None => "no slice positions: 1 mm between slices assumed".into(),
        });
    }
    let step = stated.unwrap_or(1.0);
    let depths = (0..slices).map(|k| k as f64 * step).collect();
    (step, depths)
}

/// The first image's pixel spacing (rows, columns), 1 mm with a note where it is missing or
/// not positive.
fn pixel_spacing(first: &Image, notes: &mut Vec<String>) -> [f64; 2] {
    match first.pixel_spacing {
        Some(s) if s.iter().all(|v| v.is_finite() && *v > 0.0) => s,
        Some([dy, dx]) => {
            notes.push(format!(
                "pixel spacing {dy} x {dx} mm is not two positive numbers: 1 mm assumed"
            ));
            [1.0, 1.0]
        }
        None => {
            notes.push("no pixel spacing: 1 mm assumed".into());
            [1.0, 1.0]
        }
    }
}

/// What a load says of a series cut from Siemens mosaics of `first`'s kind.
fn mosaic_note(first: &Image, t: &super::mosaic::Tile) -> String {
    let [tc, tr] = t.plane;
    let (mc, mr) = (first.format.cols, first.format.rows);
    format!(
        "a Siemens mosaic: {} slices of {tc}x{tr} cut from each {mc}x{mr} image (slice \
         spacing: {})",
        t.of, t.step_from
    )
}

/// Lays `series` out as a volume; `name` names an image in messages (its file). Fails when the
/// positions repeat unevenly (not a 4D series).
pub(super) fn layout(
    series: &Series,
    name: &dyn Fn(&Image) -> String,
) -> std::result::Result<Layout, String> {
    let images = &series.images;
    let first = &images[0];
    let plane = first.plane();
    let mut notes = Vec::new();
    if let Some(t) = &first.tile {
        notes.push(mosaic_note(first, t));
        notes.extend(t.numbering.note());
    }
    let [dy, dx] = pixel_spacing(first, &mut notes);
    let placed = frame_of(first).filter(|_| images.iter().all(|im| im.position.is_some()));
    let runs = runs(images, placed)?;
    let (slices, volumes) = (runs.len(), runs[0].len());
    let order: Vec<Vec<usize>> = (0..volumes)
        .map(|v| runs.iter().map(|r| r[v]).collect())
        .collect();
    let lead: Vec<&Image> = runs.iter().map(|r| &images[r[0]]).collect();
    let stated = first.spacing_between.filter(|s| *s > 0.0);
    let (mut step, mut problems, depths) = if let Some((_, _, n)) = placed {
        let depths: Vec<f64> = lead
            .iter()
            .map(|im| depth(im, n) - depth(lead[0], n))
            .collect();
        let (m, problems) = spacing_between(&depths, &|k| name(lead[k]));
        (m.or(stated).unwrap_or(dx.min(dy)), problems, depths)
    } else {
        let (step, depths) = unplaced(slices, stated, &mut notes);
        (step, Vec::new(), depths)
    };
    if !step.is_finite() || step <= 0.0 {
        step = 1.0;
    }
    let uneven = !problems.is_empty();
    let (mut shifts, mut tilted) = (vec![[0.0, 0.0]; slices], None);
    let lps = placed.map(|(r, c, n)| {
        let positions: Vec<[f64; 3]> = lead
            .iter()
            .map(|im| im.position.unwrap_or_default())
            .collect();
        let (along, moved, degrees) = tilt((r, c, n), &positions, step, [dx, dy]);
        if let Some(degrees) = degrees {
            let stated = first
                .tilt
                .map_or_else(String::new, |t| format!(" (GantryDetectorTilt says {t}°)"));
            problems.push(format!(
                "gantry tilt of {degrees:.2}°{stated}: kept as a sheared transform"
            ));
            (shifts, tilted) = (moved, Some(degrees));
        }
        let m = std::array::from_fn(|row| [r[row] * dx, c[row] * dy, along[row]]);
        (m, positions[0])
    });
    if volumes > 1 {
        notes.push(format!(
            "the positions repeat: a 4D series of {volumes} volumes of {slices} slices"
        ));
    }
    Ok(Layout {
        slices,
        volumes,
        order,
        plane,
        spacing: [dx, dy, step],
        lps,
        depths,
        shifts,
        uneven,
        tilt: tilted,
        notes,
        problems,
    })
}
