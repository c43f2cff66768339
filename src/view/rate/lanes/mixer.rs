//! The resolve pass: samples in mixed cells interpolated and quantized eight at a time, with the
//! same f32 and f64 operations as `BinSampler::inner_bin`.

use std::arch::x86_64::*;

use super::LANES;
use super::chunk::{CELL, Chunk, SLOT};
use super::registers::{Narrow, per_axis};
use crate::geometry::lattice::FIXED_BITS;
use crate::view::rate::BinSampler;
use crate::volume::cells::MIXED;
use crate::volume::{Voxel, VoxelType};

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
    /// [`MIXED`] in every lane.
    pub(super) mixed: __m256i,
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
            mixed: _mm256_set1_epi32(i32::from(MIXED)),
        })
    }
}

impl<T: Voxel> Mixer<'_, T> {
    /// The bins of eight trilinear samples in the cells `cell` whose coordinates have the
    /// fractional parts `low` (in fixed point), and the lanes whose sample is missing (a NaN
    /// corner): the same as `BinSampler::inner_bin`, eight at a time.
    #[inline(always)]
    pub(super) unsafe fn bins(&self, cell: __m256i, low: [__m256i; 3]) -> (__m256i, __m256i) {
        let c = self.corner_values(cell);
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

    /// The eight corners of eight cells as f32 (`Voxel::to_f32`), in the order of `corners`:
    /// gathered, where the voxel type allows it and every voxel read lies in the volume, else
    /// read one by one. Gathered, a cell's two corners along x are one 32-bit read for 16-bit
    /// voxels (and for 8-bit ones, from two bytes before them, so that no read passes the
    /// volume's last voxel): per eight samples four gathers and a few shifts instead of 64
    /// loads, conversions and stores, with the same values.
    #[inline(always)]
    unsafe fn corner_values(&self, cell: __m256i) -> [__m256; 8] {
        let [_, x, y, _, z, _, z_y, _] = self.corners;
        let pairs = [0, y, z, z_y];
        let data = self.voxels.as_ptr().cast::<i32>();
        // No closures: a closure is compiled without the walk's target features.
        macro_rules! gather {
            ($scale:literal, $offset:expr, $back:expr) => {{
                let at = _mm256_add_epi32(cell, _mm256_set1_epi32($offset as i32 - $back));
                // SAFETY: every lane's read lies in the volume (`within`, checked before).
                unsafe { _mm256_i32gather_epi32::<$scale>(data, at) }
            }};
        }
        let mut words = [_mm256_setzero_si256(); 4];
        match T::TYPE {
            VoxelType::F32 if self.within(cell, 0) => {
                let mut out = [_mm256_setzero_ps(); 8];
                for (out, &offset) in out.iter_mut().zip(&self.corners) {
                    *out = _mm256_castsi256_ps(gather!(4, offset, 0));
                }
                out
            }
            VoxelType::I16 | VoxelType::U16 if x == 1 && self.within(cell, 0) => {
                for (w, &offset) in words.iter_mut().zip(&pairs) {
                    *w = gather!(2, offset, 0);
                }
                split(words, 16, T::TYPE == VoxelType::I16)
            }
            VoxelType::I8 | VoxelType::U8 if x == 1 && self.within(cell, 2) => {
                // Bytes 2 and 3 of each word, shifted down to its low half.
                for (w, &offset) in words.iter_mut().zip(&pairs) {
                    *w = _mm256_srli_epi32::<16>(gather!(1, offset, 2));
                }
                split(words, 8, T::TYPE == VoxelType::I8)
            }
            _ => self.corner_values_one_by_one(cell),
        }
    }

    /// Whether every lane of `cell` reads voxels within the volume from `back` voxels before
    /// the cell's lower corner to its upper one.
    #[inline(always)]
    unsafe fn within(&self, cell: __m256i, back: usize) -> bool {
        let Some(last) = self.voxels.len().checked_sub(1 + self.corners[7]) else {
            return false;
        };
        // Both bounds below i32::MAX: `available` keeps the voxels' indices in 32-bit lanes.
        let (lo, hi) = (back as i32 - 1, last as i32);
        let inside = _mm256_andnot_si256(
            _mm256_cmpgt_epi32(cell, _mm256_set1_epi32(hi)),
            _mm256_cmpgt_epi32(cell, _mm256_set1_epi32(lo)),
        );
        _mm256_movemask_epi8(inside) == -1
    }

    /// [`corner_values`](Self::corner_values), a voxel at a time (bounds checked).
    #[inline(always)]
    unsafe fn corner_values_one_by_one(&self, cell: __m256i) -> [__m256; 8] {
        let mut base = Narrow::default();
        base.set(cell);
        let mut corners = [Narrow::default(); 8];
        for (l, &base) in base.0.iter().enumerate() {
            for (corner, &offset) in corners.iter_mut().zip(&self.corners) {
                corner.0[l] = self.voxels[base as usize + offset].to_f32().to_bits();
            }
        }
        let mut out = [_mm256_setzero_ps(); 8];
        for (out, corner) in out.iter_mut().zip(&corners) {
            *out = _mm256_castsi256_ps(corner.get());
        }
        out
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
            // Missing samples get MIXED, which no bin is. Every entry is put, the padding's
            // too: it is the first entry again, its own label.
            let (mut labels, mut slots) = (Narrow::default(), Narrow::default());
            labels.set(_mm256_blendv_epi8(bins, self.mixed, missing));
            slots.set(slot);
            for (&slot, &label) in slots.0.iter().zip(&labels.0) {
                chunk.put(slot, label as u8);
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

/// The corners of [`Mixer::corner_values`] from four words a pair of neighbours along x, the lower in
/// the low `bits` of each 32-bit lane and the upper in the `bits` above them: each as an
/// integer (sign-extended if `signed`), then as f32 (exactly: 16 bits at most).
#[inline(always)]
unsafe fn split(words: [__m256i; 4], bits: i32, signed: bool) -> [__m256; 8] {
    let shift = _mm_cvtsi32_si128(32 - bits);
    let down = _mm_cvtsi32_si128(bits);
    let mut out = [_mm256_setzero_ps(); 8];
    for (pair, w) in out.chunks_exact_mut(2).zip(words) {
        let low = _mm256_sll_epi32(w, shift);
        let high = _mm256_sll_epi32(_mm256_srl_epi32(w, down), shift);
        let [low, high] = if signed {
            [_mm256_sra_epi32(low, shift), _mm256_sra_epi32(high, shift)]
        } else {
            [_mm256_srl_epi32(low, shift), _mm256_srl_epi32(high, shift)]
        };
        pair[0] = _mm256_cvtepi32_ps(low);
        pair[1] = _mm256_cvtepi32_ps(high);
    }
    out
}
