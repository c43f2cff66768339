//! Pixel samples to f32 values: `BitsStored` and the sign respected, MONOCHROME1 inverted,
//! colour turned into luminance, `RescaleSlope` and `RescaleIntercept` applied; and resampling a
//! stack of slices onto an even, orthogonal grid.

use super::format::PixelFormat;

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

    /// Decodes the samples `src` of one frame into the values `out` (one per pixel).
    pub fn frame(&self, src: &[u8], out: &mut [f32]) {
        let n = out.len();
        let (lo, hi) = self.range;
        let (slope, intercept) = self.rescale;
        // Inversion and rescale folded into one affine map of the stored value.
        let (a, b) = if self.invert {
            (-slope, (lo + hi) * slope + intercept)
        } else {
            (slope, intercept)
        };
        let (a, b) = (a as f32, b as f32);
        let shift = 32 - self.stored;
        let signed = self.signed;
        let sample = |raw: u32| -> f32 {
            if signed {
                ((raw << shift) as i32 >> shift) as f32
            } else {
                ((raw << shift) >> shift) as f32
            }
        };
        let raw = |i: usize| -> u32 {
            let s = &src[i * self.bytes..(i + 1) * self.bytes];
            match (self.bytes, self.big) {
                (1, _) => u32::from(s[0]),
                (2, false) => u32::from(u16::from_le_bytes([s[0], s[1]])),
                (2, true) => u32::from(u16::from_be_bytes([s[0], s[1]])),
                (_, false) => u32::from_le_bytes([s[0], s[1], s[2], s[3]]),
                (_, true) => u32::from_be_bytes([s[0], s[1], s[2], s[3]]),
            }
        };
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
        d.frame(&[0xFF, 0xFF, 0x01, 0xF0], &mut out);
        assert_eq!(out, [-12.0, -8.0]);
        let d = Decode::new(&format(16, 16, false, "MONOCHROME2"), true, (1.0, 0.0));
        d.frame(&[0x01, 0x00, 0xFF, 0xFF], &mut out);
        assert_eq!(out, [256.0, 65535.0]);
    }

    #[test]
    fn monochrome1_inverts_over_the_stored_range() {
        let mut out = [0.0f32; 2];
        let d = Decode::new(&format(8, 8, false, "MONOCHROME1"), false, (1.0, 0.0));
        d.frame(&[0, 200], &mut out);
        assert_eq!(out, [255.0, 55.0]);
        let d = Decode::new(&format(16, 12, false, "MONOCHROME1"), false, (1.0, -1000.0));
        d.frame(&[0, 0, 0xFF, 0x0F], &mut out);
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
