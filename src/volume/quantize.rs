//! Quantization of intensities into B equal-width bins, exactly as docs/design.md §2 defines it.

use crate::error::{Error, Result};

/// The largest number of bins: symbols are stored in a byte, and 255 marks a missing sample.
pub const MAX_BINS: usize = 255;

/// Maps intensities to bins: `bin = min(B-1, floor((v - min) * B / (max - min)))` in f64, all
/// values in bin 0 when `max == min`, and missing (NaN) values to no bin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quantizer {
    min: f64,
    range: f64,
    bins: f64,
    last: u8,
}

impl Quantizer {
    /// A quantizer for `bins` bins (2 to 255) over `[min, max]`.
    pub fn new(min: f32, max: f32, bins: usize) -> Result<Self> {
        if !(2..=MAX_BINS).contains(&bins) {
            return Err(Error::invalid(
                "bins",
                bins,
                format!("between 2 and {MAX_BINS}"),
            ));
        }
        if !(min.is_finite() && max.is_finite() && min <= max) {
            return Err(Error::invalid(
                "range",
                format!("[{min}, {max}]"),
                "a finite interval",
            ));
        }
        Ok(Self {
            min: f64::from(min),
            range: f64::from(max) - f64::from(min),
            bins: bins as f64,
            last: (bins - 1) as u8,
        })
    }

    /// `(min, max - min, B)` of the formula, for code that computes it in other forms (which
    /// must give the same bins).
    #[must_use]
    pub fn formula(&self) -> (f64, f64, f64) {
        (self.min, self.range, self.bins)
    }

    /// Number of bins.
    #[must_use]
    pub fn bins(&self) -> usize {
        usize::from(self.last) + 1
    }

    /// The bin of `v`, or `None` when `v` is missing (NaN).
    #[inline]
    #[must_use]
    pub fn bin(&self, v: f32) -> Option<u8> {
        if v.is_nan() {
            return None;
        }
        if self.range == 0.0 {
            return Some(0);
        }
        let t = (f64::from(v) - self.min) * self.bins / self.range;
        // For t >= 0 truncation is floor; a t below 0 (interpolation rounding) is clamped to bin 0
        // either way, since `as` saturates. So this is the formula, without a call to floor.
        Some((t as u32).min(u32::from(self.last)) as u8)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn follows_the_formula_at_edges() {
        let q = Quantizer::new(0.0, 100.0, 32).unwrap();
        assert_eq!(q.bin(0.0), Some(0));
        assert_eq!(q.bin(3.125), Some(1), "exact bin edge goes up");
        assert_eq!(q.bin(3.124), Some(0));
        assert_eq!(q.bin(99.99), Some(31));
        assert_eq!(q.bin(100.0), Some(31), "max is clamped into the last bin");
        assert_eq!(q.bin(-1e-6), Some(0));
        assert_eq!(q.bin(f32::NAN), None);
    }

    #[test]
    fn constant_range_is_bin_zero() {
        let q = Quantizer::new(5.0, 5.0, 32).unwrap();
        assert_eq!(q.bin(5.0), Some(0));
    }

    #[test]
    fn rejects_bad_bins_and_ranges() {
        assert!(Quantizer::new(0.0, 1.0, 1).is_err());
        assert!(Quantizer::new(0.0, 1.0, 256).is_err());
        assert!(Quantizer::new(1.0, 0.0, 8).is_err());
        assert!(Quantizer::new(f32::NAN, 0.0, 8).is_err());
    }

    #[test]
    fn matches_the_f64_formula_on_many_values() {
        let (lo, hi) = (-1024.0f32, 3071.0f32);
        let q = Quantizer::new(lo, hi, 32).unwrap();
        for i in 0..=40950 {
            let v = lo + i as f32 * 0.1;
            let expect = ((f64::from(v) - f64::from(lo)) * 32.0 / (f64::from(hi) - f64::from(lo)))
                .floor()
                .min(31.0);
            assert_eq!(f64::from(q.bin(v).unwrap()), expect.max(0.0));
        }
    }
}
