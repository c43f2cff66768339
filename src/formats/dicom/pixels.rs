//! Pixel samples to f32 values: `BitsStored` and the sign respected, MONOCHROME1 inverted,
//! colour turned into luminance, `RescaleSlope` and `RescaleIntercept` applied; and resampling a
//! stack of slices onto an even, orthogonal grid. Values beyond 2^24 (32-bit samples, large
//! rescales) are made in f64 and rounded to f32 once, the whole ones an f32 does not hold
//! exactly counted, as every reader counts the integers it widens (`data::wide`).

use super::format::PixelFormat;
use crate::formats::data::wide::Rounded;

/// Values of at most this magnitude are f32s exactly when whole: 2^24.
const EXACT: f64 = 16_777_216.0;

/// How to turn one frame's samples into values.
#[derive(Clone, Copy, Debug)]
pub(super) struct Decode {
    /// Bytes per sample: 1, 2 or 4.
    pub bytes: usize,
    /// Bits that hold the value.
    pub stored: u32,
    /// Two's complement.
    pub signed: bool,
    /// The smallest and largest stored value.
    pub range: (f64, f64),
    /// Samples are big endian.
    pub big: bool,
    /// Invert (MONOCHROME1): `lo + hi - v` over the stored range.
    pub invert: bool,
    /// Samples per pixel (1, or 3 for colour).
    pub samples: usize,
    /// Colour stored plane by plane.
    pub planar: bool,
    /// Colour is YBR: the first sample is the luminance.
    pub ybr: bool,
    /// `YBR_FULL_422`: pixels in pairs, `Y1 Y2 Cb Cr`.
    pub subsampled: bool,
    /// `v * slope + intercept`.
    pub rescale: (f64, f64),
}

impl Decode {
    /// How to decode samples of `format` stored in `big` endian order, rescaled by `rescale`.
    pub fn new(format: &PixelFormat, big: bool, rescale: (f64, f64)) -> Self {
        Self {
            bytes: usize::from(format.allocated / 8),
            stored: u32::from(format.stored),
            signed: format.signed,
            range: stored_range(format),
            big,
            invert: format.inverted(),
            samples: usize::from(format.samples),
            planar: format.planar,
            ybr: format.photometric.starts_with("YBR"),
            subsampled: format.subsampled(),
            rescale,
        }
    }

    /// The affine map of a stored value to its value: the inversion and the rescale folded.
    fn affine(&self) -> (f64, f64) {
        let (lo, hi) = self.range;
        let (slope, intercept) = self.rescale;
        if self.invert {
            (-slope, (lo + hi) * slope + intercept)
        } else {
            (slope, intercept)
        }
    }

    /// Whether some value of grey samples may lie beyond 2^24 in magnitude (32-bit samples,
    /// or a rescale that reaches that far): such frames are decoded in f64, rounded to f32
    /// once, and the whole values an f32 does not hold exactly counted. Colour is luminance,
    /// a fraction, never counted.
    fn wide(&self) -> bool {
        let (a, b) = self.affine();
        let (lo, hi) = self.range;
        self.samples == 1 && !self.subsampled && (a * lo + b).abs().max((a * hi + b).abs()) > EXACT
    }

    /// How a note names these samples: their type (`u32`, `i16`...), `rescaled` when a rescale
    /// made the values.
    pub fn name(&self) -> String {
        let ty = format!("{}{}", ["u", "i"][usize::from(self.signed)], self.bytes * 8);
        if self.rescale == (1.0, 0.0) {
            ty
        } else {
            format!("rescaled {ty}")
        }
    }

    /// Sample `i` of `src`, as stored.
    fn raw(&self, src: &[u8], i: usize) -> u32 {
        let s = &src[i * self.bytes..(i + 1) * self.bytes];
        match (self.bytes, self.big) {
            (1, _) => u32::from(s[0]),
            (2, false) => u32::from(u16::from_le_bytes([s[0], s[1]])),
            (2, true) => u32::from(u16::from_be_bytes([s[0], s[1]])),
            (_, false) => u32::from_le_bytes([s[0], s[1], s[2], s[3]]),
            (_, true) => u32::from_be_bytes([s[0], s[1], s[2], s[3]]),
        }
    }

    /// The value the stored bits of `raw` hold, sign extended.
    fn stored(&self, raw: u32) -> i64 {
        let shift = 32 - self.stored;
        if self.signed {
            i64::from((raw << shift) as i32 >> shift)
        } else {
            i64::from((raw << shift) >> shift)
        }
    }

    /// Decodes the samples `src` of one frame into the values `out` (one per pixel), counting
    /// the whole values an f32 does not hold exactly (see [`Decode::wide`]) among the pixels
    /// `counted` says (a mosaic's tiles that are slices).
    pub fn frame(&self, src: &[u8], out: &mut [f32], counted: &dyn Fn(usize) -> bool) -> Rounded {
        if !self.wide() {
            self.narrow(src, out);
            return Rounded::default();
        }
        let (a, b) = self.affine();
        let whole = a.fract() == 0.0 && b.fract() == 0.0;
        let mut rounded = Rounded::default();
        for (i, o) in out.iter_mut().enumerate() {
            let v = a * self.stored(self.raw(src, i)) as f64 + b;
            // Whole values below 2^53 are exact in f64: the one rounding is to f32.
            *o = if whole && v.abs() < 9.0e15 && counted(i) {
                rounded.take(v as i128)
            } else {
                v as f32
            };
        }
        rounded
    }

    /// Decodes a frame in f32: colour, or grey values all within 2^24 in magnitude.
    fn narrow(&self, src: &[u8], out: &mut [f32]) {
        let n = out.len();
        let (a, b) = self.affine();
        let (a, b) = (a as f32, b as f32);
        let sample = |raw: u32| self.stored(raw) as f32;
        let raw = |i: usize| self.raw(src, i);
        if self.subsampled {
            for (i, o) in out.iter_mut().enumerate() {
                *o = a * sample(raw(i / 2 * 4 + i % 2)) + b;
            }
            return;
        }
        if self.samples == 3 {
            for (i, o) in out.iter_mut().enumerate() {
                let at = |c: usize| {
                    if self.planar {
                        sample(raw(c * n + i))
                    } else {
                        sample(raw(i * 3 + c))
                    }
                };
                let y = if self.ybr {
                    at(0)
                } else {
                    0.299 * at(0) + 0.587 * at(1) + 0.114 * at(2)
                };
                *o = a * y + b;
            }
            return;
        }
        // The common cases in tight loops: 16 and 8 bits, little endian.
        match (self.bytes, self.big) {
            (2, false) => {
                for (o, s) in out.iter_mut().zip(src.chunks_exact(2)) {
                    *o = a * sample(u32::from(u16::from_le_bytes([s[0], s[1]]))) + b;
                }
            }
            (1, _) => {
                for (o, &s) in out.iter_mut().zip(src) {
                    *o = a * sample(u32::from(s)) + b;
                }
            }
            _ => {
                for (i, o) in out.iter_mut().enumerate() {
                    *o = a * sample(raw(i)) + b;
                }
            }
        }
    }
}

/// The smallest and largest value the stored bits of `format` hold.
fn stored_range(format: &PixelFormat) -> (f64, f64) {
    let bits = i32::from(format.stored);
    if format.signed {
        (-(2f64.powi(bits - 1)), 2f64.powi(bits - 1) - 1.0)
    } else {
        (0.0, 2f64.powi(bits) - 1.0)
    }
}

/// Bilinear sample of the `cols`×`rows` plane at (`u`, `v`) pixels; NaN outside it.
fn bilinear(plane: &[f32], cols: usize, rows: usize, u: f64, v: f64) -> f32 {
    if !(u >= 0.0 && v >= 0.0 && u <= (cols - 1) as f64 && v <= (rows - 1) as f64) {
        return f32::NAN;
    }
    let (i, j) = (u.floor() as usize, v.floor() as usize);
    let (i1, j1) = ((i + 1).min(cols - 1), (j + 1).min(rows - 1));
    let (fu, fv) = ((u - i as f64) as f32, (v - j as f64) as f32);
    let at = |i: usize, j: usize| plane[j * cols + i];
    let top = at(i, j) * (1.0 - fu) + at(i1, j) * fu;
    let bottom = at(i, j1) * (1.0 - fu) + at(i1, j1) * fu;
    top * (1.0 - fv) + bottom * fv
}

/// Slice `out` (at `depth` mm along the normal) of a stack of `planes` at `depths` (ascending)
/// whose in-plane offsets from the first are `shifts` pixels: linear between the two slices
/// around it, each sampled bilinearly where the tilt moved it.
pub(super) fn resample_slice(
    planes: &[Vec<f32>],
    depths: &[f64],
    shifts: &[[f64; 2]],
    plane: [usize; 2],
    depth: f64,
    out: &mut [f32],
) {
    let [cols, rows] = plane;
    let b = depths.partition_point(|&d| d < depth).min(depths.len() - 1);
    let a = b.saturating_sub(1);
    let w = if b == a || depths[b] <= depths[a] {
        1.0
    } else {
        ((depth - depths[a]) / (depths[b] - depths[a])).clamp(0.0, 1.0) as f32
    };
    let still = |s: usize| shifts[s][0].abs() < 1e-6 && shifts[s][1].abs() < 1e-6;
    for j in 0..rows {
        for i in 0..cols {
            let value = |s: usize| {
                if still(s) {
                    planes[s][j * cols + i]
                } else {
                    bilinear(
                        &planes[s],
                        cols,
                        rows,
                        i as f64 - shifts[s][0],
                        j as f64 - shifts[s][1],
                    )
                }
            };
            out[j * cols + i] = if w >= 1.0 {
                value(b)
            } else if w <= 0.0 {
                value(a)
            } else {
                value(a) * (1.0 - w) + value(b) * w
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn format(allocated: u16, stored: u16, signed: bool, photometric: &str) -> PixelFormat {
        PixelFormat {
            rows: 1,
            cols: 2,
            allocated,
            stored,
            signed,
            samples: 1,
            planar: false,
            photometric: photometric.into(),
            frames: 1,
        }
    }

    #[test]
    fn bits_stored_sign_and_rescale() {
        let mut out = [0.0f32; 2];
        // 12 bits stored, signed: 0xFFF is -1; the high nibble is ignored.
        let d = Decode::new(&format(16, 12, true, "MONOCHROME2"), false, (2.0, -10.0));
        d.frame(&[0xFF, 0xFF, 0x01, 0xF0], &mut out, &|_| true);
        assert_eq!(out, [-12.0, -8.0]);
        let d = Decode::new(&format(16, 16, false, "MONOCHROME2"), true, (1.0, 0.0));
        d.frame(&[0x01, 0x00, 0xFF, 0xFF], &mut out, &|_| true);
        assert_eq!(out, [256.0, 65535.0]);
    }

    #[test]
    fn values_beyond_two_to_the_24_are_counted_after_the_rescale() {
        let mut f = format(32, 32, false, "MONOCHROME2");
        f.cols = 4;
        let words: [u32; 4] = [0, 1 << 24, (1 << 24) + 1, u32::MAX];
        let src: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
        let mut out = [0.0f32; 4];
        let d = Decode::new(&f, false, (1.0, 0.0));
        let r = d.frame(&src, &mut out, &|_| true);
        assert_eq!(out, [0.0, 16_777_216.0, 16_777_216.0, 4_294_967_296.0]);
        let largest = i128::from(u32::MAX);
        assert_eq!(r, Rounded { count: 2, largest });
        assert_eq!(d.name(), "u32");
        // Only the pixels counted says (a mosaic's used tiles).
        let r = d.frame(&src, &mut out, &|i| i < 3);
        assert_eq!(
            r,
            Rounded {
                count: 1,
                largest: (1 << 24) + 1
            }
        );
        // An intercept of -1: 2^24 - 1 and 2^24 are f32s, 2^32 - 2 is not.
        let d = Decode::new(&f, false, (1.0, -1.0));
        let r = d.frame(&src, &mut out, &|_| true);
        assert_eq!(out[..3], [-1.0, 16_777_215.0, 16_777_216.0]);
        assert_eq!(
            r,
            Rounded {
                count: 1,
                largest: 4_294_967_294
            }
        );
        assert_eq!(d.name(), "rescaled u32");
        // A fractional slope: the scale's rounding, not counted.
        let d = Decode::new(&f, false, (0.5, 0.0));
        assert_eq!(d.frame(&src, &mut out, &|_| true), Rounded::default());
        assert_eq!(out[2], 8_388_608.5);
        // 16-bit samples a whole slope takes beyond 2^24: 65535 * 257 is odd, not an f32;
        // 65534 * 257 is even, an f32 (a step of 2 between 2^24 and 2^25).
        let f = format(16, 16, false, "MONOCHROME2");
        let src: Vec<u8> = [65535u16, 65534]
            .iter()
            .flat_map(|w| w.to_le_bytes())
            .collect();
        let d = Decode::new(&f, false, (257.0, 0.0));
        let r = d.frame(&src, &mut out[..2], &|_| true);
        assert_eq!(
            r,
            Rounded {
                count: 1,
                largest: 16_842_495
            }
        );
        assert_eq!(out[..2], [16_842_496.0, 16_842_238.0]);
        assert_eq!(d.name(), "rescaled u16");
        // Within 2^24: the f32 path, nothing counted.
        let d = Decode::new(&f, false, (1.0, 0.0));
        assert_eq!(d.frame(&src, &mut out[..2], &|_| true), Rounded::default());
        assert_eq!(out[..2], [65535.0, 65534.0]);
    }

    #[test]
    fn monochrome1_inverts_over_the_stored_range() {
        let mut out = [0.0f32; 2];
        let d = Decode::new(&format(8, 8, false, "MONOCHROME1"), false, (1.0, 0.0));
        d.frame(&[0, 200], &mut out, &|_| true);
        assert_eq!(out, [255.0, 55.0]);
        let d = Decode::new(&format(16, 12, false, "MONOCHROME1"), false, (1.0, -1000.0));
        d.frame(&[0, 0, 0xFF, 0x0F], &mut out, &|_| true);
        assert_eq!(out, [3095.0, -1000.0]);
    }

    #[test]
    fn resampling_interpolates_between_slices_and_follows_tilt() {
        let planes = vec![vec![0.0, 10.0, 20.0], vec![100.0, 110.0, 120.0]];
        let mut out = [0.0f32; 3];
        resample_slice(
            &planes,
            &[0.0, 2.0],
            &[[0.0, 0.0]; 2],
            [3, 1],
            0.5,
            &mut out,
        );
        assert_eq!(out, [25.0, 35.0, 45.0]);
        // The second slice moved by one column: its pixel 0 lies at column 1.
        resample_slice(
            &planes,
            &[0.0, 2.0],
            &[[0.0, 0.0], [1.0, 0.0]],
            [3, 1],
            2.0,
            &mut out,
        );
        assert!(out[0].is_nan());
        assert_eq!(out[1..], [100.0, 110.0]);
    }
}
