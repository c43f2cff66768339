//! Transfer functions: intensity to colour (a window over a colour map) and opacity (piecewise
//! linear), baked into a lookup table with opacity corrected for the sampling step; the colour
//! and opacity of cut faces; and a categorical colour table for label volumes.

mod colormap;
mod labels;
mod preset;

use crate::error::{Error, Result};
use crate::volume::{Stats, Volume};

pub use colormap::Colormap;
pub use labels::{MAX_LABELS, label_values};
pub use preset::Preset;
use preset::{Shape, rise, shape};

/// Entries of the lookup table.
const LUT: usize = 2048;

/// The opacity a user's window reaches at its high end.
const WINDOW_OPACITY: f32 = 0.6;

/// A cut face turns from clear to opaque over this fraction of the colour window, from the
/// value where the volume stops being background.
const FACE_RAMP: f32 = 0.04;

/// What a transfer function is made of: a preset, a colour map and, optionally, a window that
/// replaces the preset's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TransferChoice {
    /// Preset.
    pub preset: Preset,
    /// Colour map.
    pub colormap: Colormap,
    /// Grey ramp and opacity ramp from `lo` to `hi`, instead of the preset's.
    pub window: Option<(f32, f32)>,
}

impl Default for TransferChoice {
    /// The preset from the histogram, in grey, with the preset's window.
    fn default() -> Self {
        Self {
            preset: Preset::Auto,
            colormap: Colormap::Grey,
            window: None,
        }
    }
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

/// The linear ramp from (x0, 0) to (x1, 1).
fn ramp(v: f32, x0: f32, x1: f32) -> f32 {
    if x1 <= x0 {
        return if v >= x1 { 1.0 } else { 0.0 };
    }
    ((v - x0) / (x1 - x0)).clamp(0.0, 1.0)
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
        let look = TransferChoice {
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
        look: TransferChoice,
        step: f64,
        reference: f64,
    ) -> Result<Self> {
        let TransferChoice {
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

#[cfg(test)]
mod tests;
