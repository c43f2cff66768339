//! The resolve pass: samples in mixed cells interpolated and quantized eight at a time, with the
//! same f32 and f64 operations as `BinSampler::inner_bin`.

use std::arch::x86_64::*;

use super::LANES;
use super::chunk::{CELL, Chunk, SLOT};
use super::registers::{Narrow, bits_of, per_axis};
use crate::geometry::lattice::FIXED_BITS;
use crate::view::rate::BinSampler;
use crate::volume::Voxel;

/// What the vector walk needs to interpolate and quantize samples in mixed cells.
pub(super) struct Mixer<'a, T> {
    pub(super) voxels: &'a [T],
    /// Offsets of a cell's eight corners from its lower one, in the order of
    /// `Interpolator::interpolate`.
    pub(super) corners: [usize; 8],
    pub(super) min: __m256d,
    pub(super) range: __m256d,
    pub(super) bins: __m256d,
    pub(super) last: __m256i,
}

impl<'a, T: Voxel> Mixer<'a, T> {
    /// The mixer of `sampler`, or `None` when its quantizer has a zero range (a constant volume,
    /// whose mixed cells are left to the scalar path).
    #[inline(always)]
    pub(super) unsafe fn new(sampler: &BinSampler<'a, T>) -> Option<Self> {
        let (min, range, bins) = sampler.quantizer().formula();
        let [x, y, z] = sampler.corner_steps();
        (range > 0.0).then(|| Self {
            voxels: sampler.voxels(),
            corners: [0, x, y, y + x, z, z + x, z + y, z + y + x],
            min: _mm256_set1_pd(min),
            range: _mm256_set1_pd(range),
            bins: _mm256_set1_pd(bins),
            last: _mm256_set1_epi32(sampler.bins() as i32 - 1),
        })
    }
}

impl<T: Voxel> Mixer<'_, T> {
    /// The bins of eight trilinear samples in the cells `cell` whose coordinates have the
    /// fractional parts `low` (in fixed point), and the lanes whose sample is missing (a NaN
    /// corner): the same as `BinSampler::inner_bin`, eight at a time.
    #[inline(always)]
    pub(super) unsafe fn bins(&self, cell: __m256i, low: [__m256i; 3]) -> (__m256i, __m256i) {
        let mut base = Narrow::default();
        base.set(cell);
        let mut corners = [Narrow::default(); 8];
        for (l, &base) in base.0.iter().enumerate() {
            for (corner, &offset) in corners.iter_mut().zip(&self.corners) {
                corner.0[l] = self.voxels[base as usize + offset].to_f32().to_bits();
            }
        }
        let mut c = [_mm256_setzero_ps(); 8];
        for (c, corner) in c.iter_mut().zip(&corners) {
            *c = _mm256_castsi256_ps(corner.get());
        }
        let f = per_axis!(m => fraction(low[m]));
        let c00 = lerp(c[0], c[1], f[0]);
        let c10 = lerp(c[2], c[3], f[0]);
        let c01 = lerp(c[4], c[5], f[0]);
        let c11 = lerp(c[6], c[7], f[0]);
        let v = lerp(lerp(c00, c10, f[1]), lerp(c01, c11, f[1]), f[2]);
        let missing = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_UNORD_Q>(v, v));
        let whole = _mm256_set_m128i(
            self.quantized(_mm256_extractf128_ps::<1>(v)),
            self.quantized(_mm256_castps256_ps128(v)),
        );
        let bins = _mm256_min_epi32(_mm256_max_epi32(whole, _mm256_setzero_si256()), self.last);
        (bins, missing)
    }

    /// bin = min(B - 1, floor((v - min) * B / range)) of four values, in f64 as the quantizer
    /// computes it (before the clamp).
    #[inline(always)]
    unsafe fn quantized(&self, h: __m128) -> __m128i {
        _mm256_cvttpd_epi32(_mm256_div_pd(
            _mm256_mul_pd(_mm256_sub_pd(_mm256_cvtps_pd(h), self.min), self.bins),
            self.range,
        ))
    }

    /// Resolves the queue of `chunk` eight entries at a time.
    #[inline(always)]
    pub(super) unsafe fn resolve(
        &self,
        chunk: &mut Chunk,
        origin: &[__m256i; 3],
        step: &[__m256i; 3],
    ) {
        let len = chunk.len;
        if len == 0 {
            return;
        }
        // Pad the queue to whole registers with copies of its first entry (a real cell).
        for queue in &mut chunk.queue {
            let first = queue[0];
            queue[len..len.next_multiple_of(LANES)].fill(first);
        }
        for k in (0..len).step_by(LANES) {
            // The fractional parts of the positions: the low 32 bits of origin + t·step, which
            // wrapping 32-bit arithmetic gives exactly.
            const { assert!(LANES == 8) };
            let slot = chunk.entries(SLOT, k);
            let lane = _mm256_and_si256(slot, _mm256_set1_epi32(LANES as i32 - 1));
            let t = _mm256_add_epi32(
                _mm256_srli_epi32::<3>(slot),
                _mm256_set1_epi32(chunk.start as i32),
            );
            let low = per_axis!(m => _mm256_add_epi32(
                _mm256_permutevar8x32_epi32(origin[m], lane),
                _mm256_mullo_epi32(t, step[m]),
            ));
            let (bins, missing) = self.bins(chunk.entries(CELL, k), low);
            let mut out = Narrow::default();
            out.set(bins);
            let missing = bits_of(missing);
            for (i, &bin) in out.0.iter().enumerate().take(len - k) {
                chunk.resolve(k + i, (missing >> i & 1 == 0).then_some(bin as u8));
            }
        }
    }
}

/// Fixed-point fractions as f64 times 2^-32, rounded to f32.
#[inline(always)]
unsafe fn fraction(low: __m256i) -> __m256 {
    let signed = _mm256_xor_si256(low, _mm256_set1_epi32(i32::MIN));
    _mm256_set_m128(
        half_fraction(_mm256_extracti128_si256::<1>(signed)),
        half_fraction(_mm256_castsi256_si128(signed)),
    )
}

/// [`fraction`] of four lanes, biased by 2^31.
#[inline(always)]
unsafe fn half_fraction(h: __m128i) -> __m128 {
    let unbias = _mm256_set1_pd(2f64.powi(31));
    let scale = _mm256_set1_pd(2f64.powi(-(FIXED_BITS as i32)));
    _mm256_cvtpd_ps(_mm256_mul_pd(
        _mm256_add_pd(_mm256_cvtepi32_pd(h), unbias),
        scale,
    ))
}

/// `a + t·(b − a)`.
#[inline(always)]
unsafe fn lerp(a: __m256, b: __m256, t: __m256) -> __m256 {
    _mm256_add_ps(a, _mm256_mul_ps(t, _mm256_sub_ps(b, a)))
}
