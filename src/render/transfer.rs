//! Transfer functions: intensity to colour (a window over a colour map) and opacity (piecewise
//! linear), baked into a lookup table with opacity corrected for the sampling step; the colour
//! and opacity of cut faces; and a categorical colour table for label volumes.

use serde::Serialize;

use crate::error::{Error, Result};
use crate::volume::{Stats, Volume};

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

/// Colour maps from 0 to 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Colormap {
    /// Black to white.
    Grey,
    /// Black, red, yellow, white.
    Hot,
    /// Perceptually uniform dark blue to yellow.
    Viridis,
    /// Bone-like: grey with a warm tint.
    Bone,
}

impl Colormap {
    /// Every colour map, for cycling in the TUI.
    pub const ALL: [Colormap; 4] = [Self::Grey, Self::Bone, Self::Hot, Self::Viridis];

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Grey => "grey",
            Self::Hot => "hot",
            Self::Viridis => "viridis",
            Self::Bone => "bone",
        }
    }

    /// The colour at `t` in [0, 1], linear RGB in [0, 1].
    pub fn at(self, t: f32) -> [f32; 3] {
        let t = t.clamp(0.0, 1.0);
        let anchors: &[[f32; 3]] = match self {
            Self::Grey => return [t; 3],
            Self::Hot => &[
                [0.0, 0.0, 0.0],
                [0.9, 0.1, 0.0],
                [1.0, 0.8, 0.1],
                [1.0, 1.0, 1.0],
            ],
            Self::Viridis => &[
                [0.267, 0.005, 0.329],
                [0.229, 0.322, 0.545],
                [0.128, 0.567, 0.551],
                [0.369, 0.789, 0.383],
                [0.993, 0.906, 0.144],
            ],
            Self::Bone => &[
                [0.0, 0.0, 0.0],
                [0.32, 0.32, 0.45],
                [0.65, 0.78, 0.78],
                [1.0, 1.0, 1.0],
            ],
        };
        let x = t * (anchors.len() - 1) as f32;
        let i = (x as usize).min(anchors.len() - 2);
        let f = x - i as f32;
        std::array::from_fn(|c| anchors[i][c] + f * (anchors[i + 1][c] - anchors[i][c]))
    }
}

/// Entries of the lookup table.
const LUT: usize = 2048;

/// The opacity a user's window reaches at its high end.
const WINDOW_OPACITY: f32 = 0.6;

/// A cut face turns from clear to opaque over this fraction of the colour window, from the
/// value where the volume stops being background.
const FACE_RAMP: f32 = 0.04;

/// The most distinct values a volume of integers may have to be drawn as labels (an atlas of
/// 116 regions has 117).
pub const MAX_LABELS: usize = 256;

/// The least share of voxels equal to their neighbour along x for a volume to be drawn as labels:
/// labels come in regions, while a ramp or a quantized image with few levels changes from voxel
/// to voxel.
const LABEL_RUNS: f64 = 0.8;

/// Opacity of a label per reference millimetre: solid after a few voxels.
const LABEL_OPACITY: f32 = 0.5;

/// Distinct colours for labels (Glasbey's first, without black and white), in order.
const PALETTE: [[u8; 3]; 20] = [
    [230, 25, 75],
    [60, 180, 75],
    [255, 225, 25],
    [0, 130, 200],
    [245, 130, 48],
    [145, 30, 180],
    [70, 240, 240],
    [240, 50, 230],
    [210, 245, 60],
    [250, 190, 212],
    [0, 128, 128],
    [220, 190, 255],
    [170, 110, 40],
    [255, 250, 200],
    [128, 0, 0],
    [170, 255, 195],
    [128, 128, 0],
    [255, 215, 180],
    [0, 0, 128],
    [128, 128, 128],
];

/// What a transfer function is made of: a preset, a colour map and, optionally, a window that
/// replaces the preset's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Look {
    /// Preset.
    pub preset: Preset,
    /// Colour map.
    pub colormap: Colormap,
    /// Grey ramp and opacity ramp from `lo` to `hi`, instead of the preset's.
    pub window: Option<(f32, f32)>,
}

/// Bins of the histogram the presets read percentiles from.
pub const HISTOGRAM_BINS: usize = 255;

/// A transfer function baked for one volume range and sampling step.
#[derive(Clone, Debug)]
pub struct Transfer {
    min: f32,
    scale: f32,
    /// Premultiplied RGBA per entry, opacity already corrected for the step.
    table: Vec<[f32; 4]>,
    /// Premultiplied RGBA of a cut face per entry: the colour window, opaque off the background.
    face: Vec<[f32; 4]>,
    /// The colour window, for faces and slices.
    window: (f32, f32),
    /// The colour window of MIP.
    mip: (f32, f32),
    colormap: Colormap,
    /// Opacity per entry, for empty-space tests (a brick's range scans it; ranges are short).
    opacity: Vec<f32>,
    /// The values of a label volume, ascending: the tables then hold one entry per label.
    labels: Option<Vec<f32>>,
}

/// An opacity ramp: from value, to value, opacity reached.
type Ramp = (f32, f32, f32);

/// A range of values, low and high end.
type Band = (f32, f32);

/// The linear ramp from (x0, 0) to (x1, 1).
fn ramp(v: f32, x0: f32, x1: f32) -> f32 {
    if x1 <= x0 {
        return if v >= x1 { 1.0 } else { 0.0 };
    }
    ((v - x0) / (x1 - x0)).clamp(0.0, 1.0)
}

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
fn rise(v: f32, x0: f32, x1: f32) -> f32 {
    if x0 > x1 {
        ramp(-v, -x0, -x1)
    } else {
        ramp(v, x0, x1)
    }
}

/// What a preset makes of a volume.
struct Shape {
    /// The colour window of DVR, cut faces and slices.
    window: Band,
    /// The colour window of MIP, which shows the brightest: wider than a soft-tissue window.
    mip: Band,
    /// Opacity as a sum of ramps.
    ramps: Vec<Ramp>,
    /// The values where cut faces are clear (`None`: up to where the opacity begins).
    band: Option<Band>,
}

/// The shape of `preset` for a volume of `s` and histogram `h`.
fn shape(preset: Preset, s: Stats, h: &[u64]) -> Shape {
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

impl Transfer {
    /// Bakes `preset` with `colormap` for `volume`, for samples `step / reference` apart
    /// (opacity is defined per `reference` millimetres).
    pub fn new(
        volume: &Volume,
        preset: Preset,
        colormap: Colormap,
        step: f64,
        reference: f64,
    ) -> Result<Self> {
        let h = volume.histogram(HISTOGRAM_BINS)?;
        let look = Look {
            preset,
            colormap,
            window: None,
        };
        Self::with_histogram(volume.stats(), &h, look, step, reference)
    }

    /// Like [`new`](Self::new), from the volume's statistics and a histogram of its values; a
    /// window in `look` replaces the preset's.
    ///
    /// `Auto` windows the colours on the voxels that are not background (1st to 99th
    /// percentile), so that CT in Hounsfield units and MRI in any scale look right untuned; its
    /// opacity rises from a quarter of the way between the background and the 98th percentile.
    /// Cut faces are opaque wherever the volume is not background.
    pub fn with_histogram(
        s: Stats,
        h: &[u64],
        look: Look,
        step: f64,
        reference: f64,
    ) -> Result<Self> {
        let Look {
            preset,
            colormap,
            window: custom,
        } = look;
        check_step(step, reference)?;
        // A user's window: grey from its low to its high end, opacity rising across it.
        let Shape {
            window,
            mip,
            ramps,
            band,
        } = match custom {
            Some(w) => Shape {
                window: w,
                mip: w,
                ramps: vec![(w.0, w.1, WINDOW_OPACITY)],
                band: None,
            },
            None => shape(preset, s, h),
        };
        // Faces are clear where the opacity has not begun, unless the preset knows the
        // background; they turn opaque over a small part of the window on either side.
        let (clear_lo, clear_hi) = band.unwrap_or_else(|| {
            let start = ramps
                .iter()
                .map(|r| r.0.min(r.1))
                .fold(f32::INFINITY, f32::min);
            (f32::NEG_INFINITY, start)
        });
        let soft = FACE_RAMP * (window.1 - window.0).abs().max(f32::EPSILON);
        let scale = if s.max > s.min {
            (LUT - 1) as f32 / (s.max - s.min)
        } else {
            0.0
        };
        let exponent = (step / reference) as f32;
        let (mut table, mut face, mut opacity) = (
            Vec::with_capacity(LUT),
            Vec::with_capacity(LUT),
            Vec::with_capacity(LUT),
        );
        for i in 0..LUT {
            let v = if scale > 0.0 {
                s.min + i as f32 / scale
            } else {
                s.min
            };
            let a: f32 = ramps
                .iter()
                .map(|&(x0, x1, o)| o * rise(v, x0, x1))
                .sum::<f32>()
                .min(1.0);
            let a = 1.0 - (1.0 - a).powf(exponent);
            let c = colormap.at(ramp(v, window.0, window.1));
            table.push([c[0] * a, c[1] * a, c[2] * a, a]);
            let f = if v > clear_hi {
                ramp(v, clear_hi, clear_hi + soft)
            } else if v < clear_lo {
                ramp(-v, -clear_lo, -clear_lo + soft)
            } else {
                0.0
            };
            face.push([c[0] * f, c[1] * f, c[2] * f, f]);
            opacity.push(a);
        }
        Ok(Self {
            min: s.min,
            scale,
            table,
            face,
            window,
            mip,
            colormap,
            opacity,
            labels: None,
        })
    }

    /// A categorical transfer function for a label volume of `labels` (value, voxel count): the
    /// most common label (the background) clear, every other a distinct colour of the palette,
    /// in ascending order of value.
    pub fn for_labels(labels: &[(f32, u64)], step: f64, reference: f64) -> Result<Self> {
        check_step(step, reference)?;
        let mut labels = labels.to_vec();
        labels.sort_by(|a, b| a.0.total_cmp(&b.0));
        let background = labels
            .iter()
            .enumerate()
            .max_by_key(|(_, l)| l.1)
            .map_or(0, |(i, _)| i);
        let a = 1.0 - (1.0 - LABEL_OPACITY).powf((step / reference) as f32);
        let (mut table, mut face, mut opacity) = (Vec::new(), Vec::new(), Vec::new());
        let mut colour = PALETTE.iter().cycle();
        for i in 0..labels.len() {
            if i == background {
                table.push([0.0; 4]);
                face.push([0.0; 4]);
                opacity.push(0.0);
                continue;
            }
            let c = colour
                .next()
                .expect("the palette cycles")
                .map(|c| f32::from(c) / 255.0);
            table.push([c[0] * a, c[1] * a, c[2] * a, a]);
            face.push([c[0], c[1], c[2], 1.0]);
            opacity.push(a);
        }
        let values: Vec<f32> = labels.iter().map(|l| l.0).collect();
        let window = (values[0], values[values.len() - 1]);
        Ok(Self {
            min: window.0,
            scale: 0.0,
            table,
            face,
            window,
            mip: window,
            colormap: Colormap::Grey,
            opacity,
            labels: Some(values),
        })
    }

    /// Whether this is a label volume's categorical table (whose samples must be taken from
    /// the nearest voxel: interpolated labels are not labels).
    pub fn is_labels(&self) -> bool {
        self.labels.is_some()
    }

    /// The table index of value `v`.
    #[inline]
    fn index(&self, v: f32) -> usize {
        match &self.labels {
            None => (((v - self.min) * self.scale) as usize).min(LUT - 1),
            Some(l) => l.partition_point(|&x| x < v).min(l.len() - 1),
        }
    }

    /// Premultiplied RGBA of value `v`.
    #[inline]
    pub fn rgba(&self, v: f32) -> [f32; 4] {
        self.table[self.index(v)]
    }

    /// Premultiplied RGBA of a cut face at value `v` (not corrected for the step: a face is a
    /// surface).
    #[inline]
    pub fn face(&self, v: f32) -> [f32; 4] {
        if v.is_nan() {
            return [0.0; 4];
        }
        self.face[self.index(v)]
    }

    /// Whether every value in `[lo, hi]` is fully transparent.
    pub fn transparent(&self, lo: f32, hi: f32) -> bool {
        let range = match &self.labels {
            None => {
                let (a, b) = (self.index(lo), self.index(hi));
                a.min(b)..=a.max(b)
            }
            Some(l) => {
                let (a, b) = (
                    l.partition_point(|&x| x < lo),
                    l.partition_point(|&x| x <= hi),
                );
                if a >= b {
                    return true;
                }
                a..=b - 1
            }
        };
        self.opacity[range].iter().all(|&o| o == 0.0)
    }

    /// The colour window, low and high end.
    pub fn window(&self) -> (f32, f32) {
        self.window
    }

    /// The low end of MIP's window: every value at or below it is background in MIP.
    pub fn floor(&self) -> f32 {
        self.mip.0
    }

    /// The colour of value `v` through the window alone (for slices); a label's colour.
    pub fn grey(&self, v: f32) -> [f32; 3] {
        self.through(v, self.window)
    }

    /// The colour of value `v` in MIP: through MIP's window, which for CT is wider than the
    /// soft tissue's, so that bone stands out; a label's colour.
    pub fn mip_grey(&self, v: f32) -> [f32; 3] {
        self.through(v, self.mip)
    }

    fn through(&self, v: f32, (lo, hi): (f32, f32)) -> [f32; 3] {
        if self.labels.is_some() {
            let f = self.face(v);
            return [f[0], f[1], f[2]];
        }
        self.colormap.at(ramp(v, lo, hi))
    }
}

fn check_step(step: f64, reference: f64) -> Result<()> {
    if step.is_finite() && step > 0.0 && reference > 0.0 {
        Ok(())
    } else {
        Err(Error::invalid("step", step, "a positive number"))
    }
}

/// Distinct values with their counts, and how many voxels equal the one before them.
type Seen = (Vec<(f32, u64)>, u64);

/// The distinct values of `volume` with their voxel counts, when it looks like a label volume:
/// integer voxels with between 2 and [`MAX_LABELS`] distinct values, in regions (most voxels
/// equal to their neighbour).
pub fn label_values(volume: &Volume) -> Option<Vec<(f32, u64)>> {
    use rayon::prelude::*;
    if !volume.voxel_type().is_integer() {
        return None;
    }
    let merge = |(mut a, ra): Seen, (b, rb): Seen| -> Option<Seen> {
        for (v, n) in b {
            match a.iter_mut().find(|e| e.0 == v) {
                Some(e) => e.1 += n,
                None => a.push((v, n)),
            }
        }
        (a.len() <= MAX_LABELS).then_some((a, ra + rb))
    };
    let values = volume
        .voxels()
        .par_chunks(1 << 16)
        .map(|chunk| {
            let mut seen: Vec<(f32, u64)> = Vec::new();
            let (mut last, mut runs) = (0, 0u64);
            for &v in chunk {
                if v.is_nan() {
                    continue;
                }
                if seen.get(last).is_some_and(|e| e.0 == v) {
                    seen[last].1 += 1;
                    runs += 1;
                    continue;
                }
                match seen.iter().position(|e| e.0 == v) {
                    Some(i) => {
                        seen[i].1 += 1;
                        last = i;
                    }
                    None if seen.len() == MAX_LABELS => return None,
                    None => {
                        last = seen.len();
                        seen.push((v, 1));
                    }
                }
            }
            Some((seen, runs))
        })
        .try_reduce(|| (Vec::new(), 0), merge)?;
    let (values, runs) = values;
    let total: u64 = values.iter().map(|v| v.1).sum();
    (values.len() >= 2 && runs as f64 >= LABEL_RUNS * total as f64).then_some(values)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::VoxelType;

    #[test]
    fn colormaps_span_dark_to_bright() {
        for map in Colormap::ALL {
            let (lo, hi) = (map.at(0.0), map.at(1.0));
            assert!(lo.iter().sum::<f32>() < hi.iter().sum::<f32>(), "{map:?}");
        }
        assert_eq!(Colormap::Grey.at(0.25), [0.25; 3]);
    }

    #[test]
    fn ct_bone_is_clear_in_air_and_opaque_in_bone() {
        let data = (0..1000).map(|i| -1000.0 + 3.0 * i as f32).collect();
        let v = Volume::new([10, 10, 10], [1.0; 3], VoxelType::I16, data).unwrap();
        let t = Transfer::new(&v, Preset::CtBone, Colormap::Grey, 1.0, 1.0).unwrap();
        assert_eq!(t.rgba(-1000.0)[3], 0.0);
        assert!(t.rgba(1500.0)[3] > 0.8);
        assert!(t.transparent(-1000.0, 100.0));
        assert!(!t.transparent(-1000.0, 900.0));
        // Half the step: less opacity per sample.
        let half = Transfer::new(&v, Preset::CtBone, Colormap::Grey, 0.5, 1.0).unwrap();
        assert!(half.rgba(1500.0)[3] < t.rgba(1500.0)[3]);
    }

    #[test]
    fn a_window_replaces_the_preset() {
        let data = (0..1000).map(|i| i as f32).collect();
        let v = Volume::new([10, 10, 10], [1.0; 3], VoxelType::F32, data).unwrap();
        let h = v.histogram(HISTOGRAM_BINS).unwrap();
        let look = Look {
            preset: Preset::CtBone,
            colormap: Colormap::Grey,
            window: Some((400.0, 600.0)),
        };
        let t = Transfer::with_histogram(v.stats(), &h, look, 1.0, 1.0).unwrap();
        assert_eq!(t.rgba(399.0)[3], 0.0);
        assert!((t.rgba(999.0)[3] - WINDOW_OPACITY).abs() < 1e-6);
        assert_eq!(t.grey(300.0), [0.0; 3]);
        assert_eq!(t.grey(700.0), [1.0; 3]);
    }

    #[test]
    fn auto_makes_the_dominant_background_clear() {
        // 90% air at 0, the rest a structure at 100.
        let data = (0..1000)
            .map(|i| if i % 10 == 0 { 100.0 } else { 0.0 })
            .collect();
        let v = Volume::new([10, 10, 10], [1.0; 3], VoxelType::U8, data).unwrap();
        let t = Transfer::new(&v, Preset::Auto, Colormap::Grey, 1.0, 1.0).unwrap();
        assert_eq!(t.rgba(0.0)[3], 0.0);
        assert!(t.rgba(100.0)[3] > 0.3);
    }

    #[test]
    fn ct_presets_suit_only_volumes_in_hounsfield_units() {
        let stats = |min: f32| Stats {
            min,
            max: 1000.0,
            mean: 0.0,
            finite: 1,
            missing: 0,
        };
        for p in Preset::ALL {
            assert!(p.suits(stats(-1024.0)), "{p:?}");
        }
        assert!(!Preset::CtBone.suits(stats(0.0)));
        assert!(!Preset::CtSoft.suits(stats(0.0)));
        assert!(Preset::Mri.suits(stats(0.0)) && Preset::Auto.suits(stats(0.0)));
    }

    #[test]
    fn auto_windows_ct_on_soft_tissue_and_clears_faces_in_air() {
        // Half air at -1000, then fat, soft tissue and bone.
        let data: Vec<f32> = (0..4000)
            .map(|i| match i % 8 {
                0..4 => -1000.0 + (i % 13) as f32,
                4 => -100.0,
                5 | 6 => 40.0 + (i % 7) as f32,
                _ => 1200.0,
            })
            .collect();
        let v = Volume::new([20, 20, 10], [1.0; 3], VoxelType::I16, data).unwrap();
        let t = Transfer::new(&v, Preset::Auto, Colormap::Grey, 1.0, 1.0).unwrap();
        let (lo, hi) = t.window();
        assert!(
            (-160.0..-90.0).contains(&lo) && (hi - 240.0).abs() < 1.0,
            "{lo}..{hi}"
        );
        assert_eq!(t.face(-1000.0)[3], 0.0, "air is clear on a cut face");
        assert_eq!(t.face(40.0)[3], 1.0, "tissue is opaque on it");
        assert_eq!(t.face(1200.0), [1.0; 4], "bone is white");
        // MIP shows the brightest: its window reaches bone, so soft tissue is not white there.
        assert!(t.mip_grey(240.0)[0] < 0.5 && t.mip_grey(1200.0)[0] > 0.95);
    }

    #[test]
    fn a_spike_of_zeros_inside_the_range_is_the_background() {
        // A signed map: 70% exactly zero, the rest spread both ways.
        let data: Vec<f32> = (0..10_000)
            .map(|i| {
                if i % 10 < 7 {
                    0.0
                } else {
                    ((i % 97) as f32 - 48.0) / 6.0
                }
            })
            .collect();
        let v = Volume::new([25, 20, 20], [1.0; 3], VoxelType::F32, data).unwrap();
        let t = Transfer::new(&v, Preset::Auto, Colormap::Grey, 1.0, 1.0).unwrap();
        assert_eq!(t.face(0.0)[3], 0.0, "zero is clear");
        assert_eq!(t.rgba(0.0)[3], 0.0);
        assert_eq!(t.face(6.0)[3], 1.0, "high values are opaque");
        assert_eq!(t.face(-6.0)[3], 1.0, "and low ones");
        assert!(t.rgba(8.0)[3] > 0.3 && t.rgba(-8.0)[3] > 0.3);
    }

    #[test]
    fn labels_have_distinct_colours_and_a_clear_background() {
        let labels = [(0.0, 900), (2.0, 50), (5.0, 30), (9.0, 20)];
        let t = Transfer::for_labels(&labels, 1.0, 1.0).unwrap();
        assert!(t.is_labels());
        assert_eq!(t.rgba(0.0)[3], 0.0);
        assert_eq!(t.face(0.0)[3], 0.0);
        let colours: Vec<[f32; 3]> = [2.0, 5.0, 9.0].iter().map(|&v| t.grey(v)).collect();
        assert!(colours[0] != colours[1] && colours[1] != colours[2] && colours[0] != colours[2]);
        assert!(t.transparent(0.0, 0.0) && t.transparent(0.5, 1.5));
        assert!(!t.transparent(0.0, 2.0) && !t.transparent(4.0, 6.0));
        // The background need not be the lowest value.
        let t = Transfer::for_labels(&[(1.0, 5), (3.0, 100)], 1.0, 1.0).unwrap();
        assert_eq!(t.rgba(3.0)[3], 0.0);
        assert!(t.rgba(1.0)[3] > 0.0);
    }
}
