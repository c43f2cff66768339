//! Transfer functions: intensity to colour (a window over a colour map) and opacity (piecewise
//! linear), baked into a lookup table with opacity corrected for the sampling step.

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
    /// The colour window, for MIP.
    window: (f32, f32),
    colormap: Colormap,
    /// Opacity per entry, for empty-space tests (a brick's range scans it; ranges are short).
    opacity: Vec<f32>,
}

/// An opacity ramp: from value, to value, opacity reached.
type Ramp = (f32, f32, f32);

/// The linear ramp from (x0, 0) to (x1, 1).
fn ramp(v: f32, x0: f32, x1: f32) -> f32 {
    if x1 <= x0 {
        return if v >= x1 { 1.0 } else { 0.0 };
    }
    ((v - x0) / (x1 - x0)).clamp(0.0, 1.0)
}

/// Values at fractions `q` of the finite voxels, from a histogram of `h.len()` equal bins.
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
            let b = b.unwrap_or(bins - 1);
            s.min + (s.max - s.min) * (b as f32 + 0.5) / bins as f32
        })
        .collect()
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
        if !(step.is_finite() && step > 0.0 && reference > 0.0) {
            return Err(Error::invalid("step", step, "a positive number"));
        }
        let p = percentiles(s, h, &[0.01, 0.05, 0.2, 0.6, 0.98, 0.995]);
        let (p1, p5, p20, p60, p98, p995) = (p[0], p[1], p[2], p[3], p[4], p[5]);
        // Opacity as a sum of ramps: (from, to, opacity).
        let (window, ramps): ((f32, f32), Vec<Ramp>) = match preset {
            Preset::CtBone => ((-200.0, 1500.0), vec![(150.0, 700.0, 0.85)]),
            Preset::CtSoft => (
                (-300.0, 500.0),
                vec![(-300.0, 60.0, 0.08), (300.0, 900.0, 0.7)],
            ),
            Preset::Mri => ((p1, p995), vec![(p20, p60, 0.04), (p60, p995, 0.5)]),
            Preset::Auto => {
                let mode = h
                    .iter()
                    .enumerate()
                    .max_by_key(|(_, c)| **c)
                    .map_or(0, |(i, _)| i);
                let mode_value =
                    s.min + (s.max - s.min) * (mode as f32 + 0.5) / h.len().max(1) as f32;
                let lo = if mode_value < f32::midpoint(s.min, s.max) {
                    mode_value + 0.25 * (p98 - mode_value)
                } else {
                    p5
                };
                ((lo, p995), vec![(lo, p995, 0.6)])
            }
        };
        // A user's window: grey from its low to its high end, opacity rising across it.
        let (window, ramps) = match custom {
            Some((lo, hi)) => ((lo, hi), vec![(lo, hi, WINDOW_OPACITY)]),
            None => (window, ramps),
        };
        let scale = if s.max > s.min {
            (LUT - 1) as f32 / (s.max - s.min)
        } else {
            0.0
        };
        let exponent = (step / reference) as f32;
        let mut table = Vec::with_capacity(LUT);
        let mut opacity = Vec::with_capacity(LUT);
        for i in 0..LUT {
            let v = if scale > 0.0 {
                s.min + i as f32 / scale
            } else {
                s.min
            };
            let a: f32 = ramps
                .iter()
                .map(|&(x0, x1, o)| o * ramp(v, x0, x1))
                .sum::<f32>()
                .min(1.0);
            let a = 1.0 - (1.0 - a).powf(exponent);
            let c = colormap.at(ramp(v, window.0, window.1));
            table.push([c[0] * a, c[1] * a, c[2] * a, a]);
            opacity.push(a);
        }
        Ok(Self {
            min: s.min,
            scale,
            table,
            window,
            colormap,
            opacity,
        })
    }

    /// The table index of value `v`.
    #[inline]
    fn index(&self, v: f32) -> usize {
        (((v - self.min) * self.scale) as usize).min(LUT - 1)
    }

    /// Premultiplied RGBA of value `v`.
    #[inline]
    pub fn rgba(&self, v: f32) -> [f32; 4] {
        self.table[self.index(v)]
    }

    /// Whether every value in `[lo, hi]` is fully transparent.
    pub fn transparent(&self, lo: f32, hi: f32) -> bool {
        let (a, b) = (self.index(lo), self.index(hi));
        self.opacity[a.min(b)..=a.max(b)].iter().all(|&o| o == 0.0)
    }

    /// The low end of the colour window: every value at or below it looks the same in MIP.
    pub fn floor(&self) -> f32 {
        self.window.0
    }

    /// The colour of value `v` through the window alone (for MIP).
    pub fn grey(&self, v: f32) -> [f32; 3] {
        self.colormap.at(ramp(v, self.window.0, self.window.1))
    }
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
}
