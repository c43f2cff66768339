//! The presets: what each makes of a volume (colour windows and opacity ramps), read from the
//! volume's statistics and the percentiles of its histogram, with the background found there.

use serde::Serialize;

use super::ramp;
use crate::volume::Stats;

/// Named transfer functions.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Preset {
    /// From the histogram: the dominant low intensity (air, background) is transparent.
    Auto,
    /// CT bone in Hounsfield units: opaque above about 300 HU.
    CtBone,
    /// CT soft tissue in Hounsfield units: faint tissue, opaque bone.
    CtSoft,
    /// MRI: windows from percentiles, faint mid intensities, bright structures opaque.
    Mri,
}

impl Preset {
    /// Every preset, for cycling in the TUI.
    pub const ALL: [Preset; 4] = [Self::Auto, Self::CtBone, Self::CtSoft, Self::Mri];

    /// Whether the preset makes sense for a volume of `stats`: the CT presets are in Hounsfield
    /// units and need air (about -1000) in the volume.
    pub fn suits(self, stats: Stats) -> bool {
        match self {
            Self::CtBone | Self::CtSoft => stats.min <= AIR_HU,
            Self::Auto | Self::Mri => true,
        }
    }

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Auto => "auto",
            Self::CtBone => "ct-bone",
            Self::CtSoft => "ct-soft",
            Self::Mri => "mri",
        }
    }
}

/// A volume whose values reach this low is taken to be CT in Hounsfield units.
const AIR_HU: f32 = -500.0;

/// The colour window of CT at most: soft tissue (level 40, width 400 HU).
const CT_WINDOW: (f32, f32) = (-160.0, 240.0);

/// An opacity ramp: from value, to value, opacity reached.
pub(super) type Ramp = (f32, f32, f32);

/// A range of values, low and high end.
pub(super) type Band = (f32, f32);

/// The value at the centre of bin `b` of a histogram of `bins` equal bins over the range of `s`.
fn bin_value(s: Stats, b: usize, bins: usize) -> f32 {
    s.min + (s.max - s.min) * (b as f32 + 0.5) / bins.max(1) as f32
}

/// Values at fractions `q` of the voxels a histogram of `h.len()` equal bins counts.
fn percentiles(s: Stats, h: &[u64], q: &[f64]) -> Vec<f32> {
    let bins = h.len().max(1);
    let total: u64 = h.iter().sum();
    q.iter()
        .map(|&f| {
            let target = (f * total as f64) as u64;
            let mut acc = 0;
            let b = h.iter().position(|&c| {
                acc += c;
                acc > target
            });
            bin_value(s, b.unwrap_or(bins - 1), bins)
        })
        .collect()
}

/// The background, as a range of histogram bins: when the most common value lies in the lower
/// half of the range (air, a scanner's zero), every bin from the lowest up to where its peak has
/// fallen below a tenth of its height; else a narrow spike of at least a fifth of the voxels
/// (the zeros around a masked statistical map), wherever it lies; else none.
fn background(s: Stats, h: &[u64]) -> Option<std::ops::Range<usize>> {
    let (mode, &peak) = h.iter().enumerate().max_by_key(|(_, c)| **c)?;
    let low = |b: usize| h[b] * 10 < peak;
    if bin_value(s, mode, h.len()) < f32::midpoint(s.min, s.max) {
        return Some(0..(mode + 1..h.len()).find(|&b| low(b)).unwrap_or(h.len()));
    }
    let start = (0..mode).rev().find(|&b| low(b)).map_or(0, |b| b + 1);
    let end = (mode + 1..h.len()).find(|&b| low(b)).unwrap_or(h.len());
    let total: u64 = h.iter().sum();
    let share: u64 = h[start..end].iter().sum();
    (end - start <= SPIKE_BINS && share * 5 >= total).then_some(start..end)
}

/// The widest a background away from the lowest values may be, in histogram bins.
const SPIKE_BINS: usize = 3;

/// The opacity ramp from (x0, 0) to (x1, 1), rising either way (a step where they meet).
pub(super) fn rise(v: f32, x0: f32, x1: f32) -> f32 {
    if x0 > x1 {
        ramp(-v, -x0, -x1)
    } else {
        ramp(v, x0, x1)
    }
}

/// What a preset makes of a volume.
pub(super) struct Shape {
    /// The colour window of DVR, cut faces and slices.
    pub(super) window: Band,
    /// The colour window of MIP, which shows the brightest: wider than a soft-tissue window.
    pub(super) mip: Band,
    /// Opacity as a sum of ramps.
    pub(super) ramps: Vec<Ramp>,
    /// The values where cut faces are clear (`None`: up to where the opacity begins).
    pub(super) band: Option<Band>,
}

/// The shape of `preset` for a volume of `s` and histogram `h`.
pub(super) fn shape(preset: Preset, s: Stats, h: &[u64]) -> Shape {
    let p = percentiles(s, h, &[0.005, 0.01, 0.2, 0.6, 0.98, 0.995]);
    let (p05, p1, p20, p60, p98, p995) = (p[0], p[1], p[2], p[3], p[4], p[5]);
    let fixed = |window: Band, ramps: Vec<Ramp>| Shape {
        window,
        mip: window,
        ramps,
        band: None,
    };
    match preset {
        Preset::CtBone => fixed((-200.0, 1500.0), vec![(150.0, 700.0, 0.85)]),
        Preset::CtSoft => fixed(
            (-300.0, 500.0),
            vec![(-300.0, 60.0, 0.08), (300.0, 900.0, 0.7)],
        ),
        Preset::Mri => fixed((p1, p995), vec![(p20, p60, 0.04), (p60, p995, 0.5)]),
        Preset::Auto => {
            let bins = h.len();
            let edge = |b: usize| s.min + (s.max - s.min) * b as f32 / bins as f32;
            let background = background(s, h);
            let mut tissue = h.to_vec();
            if let Some(r) = &background {
                tissue[r.clone()].fill(0);
            }
            if tissue.iter().all(|&c| c == 0) {
                tissue = h.to_vec();
            }
            let q = percentiles(s, &tissue, &[0.01, 0.99]);
            let mip = if q[1] > q[0] {
                (q[0], q[1])
            } else {
                (p1, p995)
            };
            // CT in Hounsfield units: the soft-tissue window radiologists start from.
            let window = if s.min <= AIR_HU && mip.0 < CT_WINDOW.1 && mip.1 > CT_WINDOW.0 {
                (mip.0.max(CT_WINDOW.0), mip.1.min(CT_WINDOW.1))
            } else {
                mip
            };
            let (ramps, band) = match background {
                // Opacity from a quarter of the way between the background and the 98th
                // percentile, as air and tissue are in CT and MRI.
                Some(r) if r.start == 0 => {
                    let top = bin_value(s, r.end.max(1) - 1, bins);
                    let lo = top + 0.25 * (p98 - top);
                    (
                        vec![(lo, p995, 0.6)],
                        Some((f32::NEG_INFINITY, edge(r.end))),
                    )
                }
                // A spike inside the range: clear there, opaque away from it both ways.
                Some(r) => {
                    let (b0, b1) = (edge(r.start), edge(r.end));
                    let below = p05.min(b0) - 1e-3 * (s.max - s.min);
                    let ramps = vec![(b1, p995.max(b1), 0.6), (b0, below, 0.6)];
                    (ramps, Some((b0, b1)))
                }
                None => (
                    vec![(p1, p995, 0.6)],
                    Some((f32::NEG_INFINITY, f32::NEG_INFINITY)),
                ),
            };
            Shape {
                window,
                mip,
                ramps,
                band,
            }
        }
    }
}
