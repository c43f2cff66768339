//! The common walk of a tile eight rays at a time with AVX2 (x86-64 processors since 2013).
//!
//! A group of eight neighbouring rays walks its inner spans together: positions, cell indices
//! and block codes live in vector registers. No position depends on what memory returns, so
//! reads are issued well ahead of use: each cell is prefetched `2·AHEAD` steps before it is
//! needed and its label read `AHEAD` steps before (when the corners of a mixed cell are
//! prefetched in turn). Samples in mixed cells are interpolated and quantized eight at a time
//! with the same f32 and f64 operations as `BinSampler::inner_bin`. (AVX2 gathers were tried
//! for the reads and were no faster than plain loads on the processors here.) It feeds exactly
//! the same symbols to the same sequences as [`super::scalar_walk`]; only the order in which
//! rays take turns differs, and counts are sums.
#![allow(unsafe_code)]
// The intrinsics used are too many to name one by one.
#![allow(clippy::wildcard_imports)]

use std::arch::x86_64::*;

use super::{Walker, mixed_bin};
use crate::measure::{DenseCounts, Run, RunEnds};
use crate::volume::cells::MIXED;
use crate::volume::sampling::{BinSampler, FIXED_BITS};

/// Rays per group: eight 32-bit lanes of a 256-bit register.
const LANES: usize = 8;

/// How many steps ahead of its use a label is read (twice that, its cell is prefetched).
const AHEAD: usize = 8;

/// Whether this processor has AVX2, and `sampler`'s cells can be indexed by 32-bit lanes.
pub(super) fn available(sampler: &BinSampler) -> bool {
    is_x86_feature_detected!("avx2") && i32::try_from(sampler.cells().len()).is_ok()
}

/// Eight 64-bit values in memory, for moving between two registers and scalar code.
#[derive(Clone, Copy, Default)]
#[repr(C, align(32))]
struct Wide([i64; LANES]);

impl Wide {
    /// Values `4·half..4·half + 4` as a register.
    #[inline]
    #[target_feature(enable = "avx2")]
    fn get(&self, half: usize) -> __m256i {
        let v = &self.0[4 * half..4 * half + 4];
        // SAFETY: the 32 bytes read are `v`'s, aligned since `half` is 0 or 1.
        unsafe { _mm256_load_si256(v.as_ptr().cast()) }
    }

    #[inline]
    #[target_feature(enable = "avx2")]
    fn set(&mut self, half: usize, x: __m256i) {
        let v = &mut self.0[4 * half..4 * half + 4];
        // SAFETY: the 32 bytes written are `v`'s, aligned since `half` is 0 or 1.
        unsafe { _mm256_store_si256(v.as_mut_ptr().cast(), x) }
    }
}

/// Eight 32-bit values in memory, for moving between a register and scalar code.
#[derive(Clone, Copy, Default)]
#[repr(C, align(32))]
struct Narrow([u32; LANES]);

impl Narrow {
    #[inline]
    #[target_feature(enable = "avx2")]
    fn get(&self) -> __m256i {
        // SAFETY: the 32 bytes read are the array's, which is aligned.
        unsafe { _mm256_load_si256(self.0.as_ptr().cast()) }
    }

    #[inline]
    #[target_feature(enable = "avx2")]
    fn set(&mut self, x: __m256i) {
        // SAFETY: the 32 bytes written are the array's, which is aligned.
        unsafe { _mm256_store_si256(self.0.as_mut_ptr().cast(), x) }
    }
}

/// Positions of eight lanes: fixed-point coordinates, two registers of four each.
type Positions = [[__m256i; 2]; 3];

/// `p + d` for every lane.
#[inline]
#[target_feature(enable = "avx2")]
fn offset(p: &Positions, d: &[__m256i; 3]) -> Positions {
    std::array::from_fn(|m| {
        [
            _mm256_add_epi64(p[m][0], d[m]),
            _mm256_add_epi64(p[m][1], d[m]),
        ]
    })
}

/// The cell indices `(x >> 32) + (y >> 32)·sy + (z >> 32)·sz` of eight positions in 32-bit
/// lanes, in the lane order 0, 1, 4, 5, 2, 3, 6, 7 (see [`natural`]).
#[inline]
#[target_feature(enable = "avx2")]
fn cells_shuffled(p: &Positions, sy: __m256i, sz: __m256i) -> __m256i {
    const { assert!(FIXED_BITS == 32) };
    // The integer parts are the odd 32-bit halves of the 64-bit lanes.
    let whole = |m: usize| {
        _mm256_castps_si256(_mm256_shuffle_ps::<0b11_01_11_01>(
            _mm256_castsi256_ps(p[m][0]),
            _mm256_castsi256_ps(p[m][1]),
        ))
    };
    _mm256_add_epi32(
        whole(0),
        _mm256_add_epi32(
            _mm256_mullo_epi32(whole(1), sy),
            _mm256_mullo_epi32(whole(2), sz),
        ),
    )
}

/// Lanes in the order 0, 1, 4, 5, 2, 3, 6, 7 back in order (the permutation is its own
/// inverse).
#[inline]
#[target_feature(enable = "avx2")]
fn natural(v: __m256i) -> __m256i {
    _mm256_permutevar8x32_epi32(v, _mm256_setr_epi32(0, 1, 4, 5, 2, 3, 6, 7))
}

/// The labels of the cells at positions `p` of the lanes set in `on` (zero elsewhere),
/// prefetching the corners of mixed cells.
#[inline]
#[target_feature(enable = "avx2")]
fn gather_labels(
    sampler: &BinSampler,
    p: &Positions,
    on: __m256i,
    sy: __m256i,
    sz: __m256i,
) -> __m256i {
    let cell = natural(cells_shuffled(p, sy, sz));
    // Lanes not in `on` (whose positions may lie outside the volume) read cell 0.
    let mut at = Narrow::default();
    at.set(_mm256_and_si256(cell, on));
    let cells = sampler.cells();
    let mut labels = Narrow::default();
    for (label, &i) in labels.0.iter_mut().zip(&at.0) {
        *label = u32::from(cells[i as usize]);
    }
    let labels = labels.get();
    let mixed = _mm256_and_si256(
        _mm256_cmpeq_epi32(labels, _mm256_set1_epi32(i32::from(MIXED))),
        on,
    );
    let mut pending = bits_of(mixed);
    while pending != 0 {
        sampler.prefetch_corners(at.0[pending.trailing_zeros() as usize] as usize);
        pending &= pending - 1;
    }
    labels
}

/// What the vector walk needs to interpolate and quantize samples in mixed cells.
struct Mixer<'a> {
    voxels: &'a [f32],
    /// Offsets of a cell's eight corners from its lower one, in the order of
    /// `Interpolator::interpolate`.
    corners: [usize; 8],
    min: __m256d,
    range: __m256d,
    bins: __m256d,
    last: __m256i,
}

impl<'a> Mixer<'a> {
    /// The mixer of `sampler`, or `None` when its quantizer has a zero range (a constant volume,
    /// whose mixed cells are left to the scalar path).
    #[target_feature(enable = "avx2")]
    fn new(sampler: &BinSampler<'a>) -> Option<Self> {
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

    /// The bins of the trilinear samples at `p` for the lanes in `mixed` (others: anything), and
    /// the lanes among them whose sample is missing (a NaN corner): the same as
    /// `BinSampler::inner_bin`, eight at a time.
    #[inline]
    #[target_feature(enable = "avx2")]
    fn bins(&self, p: &Positions, mixed: __m256i, sy: __m256i, sz: __m256i) -> (__m256i, __m256i) {
        // The corners of the mixed lanes, read one by one (gathers are slower here).
        let mut cell = Narrow::default();
        cell.set(natural(cells_shuffled(p, sy, sz)));
        let mut corners = [Narrow::default(); 8];
        let mut lanes = bits_of(mixed);
        while lanes != 0 {
            let l = lanes.trailing_zeros() as usize;
            lanes &= lanes - 1;
            let base = cell.0[l] as usize;
            for (corner, &offset) in corners.iter_mut().zip(&self.corners) {
                corner.0[l] = self.voxels[base + offset].to_bits();
            }
        }
        let c: [__m256; 8] = std::array::from_fn(|k| _mm256_castsi256_ps(corners[k].get()));
        // Fractions: the low 32 bits of each coordinate, as f64 times 2^-32, rounded to f32.
        let fraction = |m: usize| {
            let low = natural(_mm256_castps_si256(_mm256_shuffle_ps::<0b10_00_10_00>(
                _mm256_castsi256_ps(p[m][0]),
                _mm256_castsi256_ps(p[m][1]),
            )));
            let signed = _mm256_xor_si256(low, _mm256_set1_epi32(i32::MIN));
            let unbias = _mm256_set1_pd(2f64.powi(31));
            let scale = _mm256_set1_pd(2f64.powi(-(FIXED_BITS as i32)));
            let half = |h: __m128i| {
                _mm256_cvtpd_ps(_mm256_mul_pd(
                    _mm256_add_pd(_mm256_cvtepi32_pd(h), unbias),
                    scale,
                ))
            };
            _mm256_set_m128(
                half(_mm256_extracti128_si256::<1>(signed)),
                half(_mm256_castsi256_si128(signed)),
            )
        };
        let f = [fraction(0), fraction(1), fraction(2)];
        let lerp = |a: __m256, b: __m256, t: __m256| {
            _mm256_add_ps(a, _mm256_mul_ps(t, _mm256_sub_ps(b, a)))
        };
        let c00 = lerp(c[0], c[1], f[0]);
        let c10 = lerp(c[2], c[3], f[0]);
        let c01 = lerp(c[4], c[5], f[0]);
        let c11 = lerp(c[6], c[7], f[0]);
        let v = lerp(lerp(c00, c10, f[1]), lerp(c01, c11, f[1]), f[2]);
        let missing = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_UNORD_Q>(v, v));
        // bin = min(B - 1, floor((v - min) * B / range)), in f64 as the quantizer computes it.
        let t = |h: __m128| {
            _mm256_cvttpd_epi32(_mm256_div_pd(
                _mm256_mul_pd(_mm256_sub_pd(_mm256_cvtps_pd(h), self.min), self.bins),
                self.range,
            ))
        };
        let whole = _mm256_set_m128i(
            t(_mm256_extractf128_ps::<1>(v)),
            t(_mm256_castps256_ps128(v)),
        );
        let bins = _mm256_min_epi32(_mm256_max_epi32(whole, _mm256_setzero_si256()), self.last);
        (bins, _mm256_and_si256(missing, mixed))
    }
}

/// The vector constants of one walk.
struct Consts {
    /// Strides of the voxel grid along y and z.
    sy: __m256i,
    sz: __m256i,
    /// One step, and AHEAD steps.
    step: [__m256i; 3],
    near: [__m256i; 3],
    /// The packing of block codes: bits per symbol, mask, L; and the spare slot's index.
    shift: __m128i,
    code_mask: __m256i,
    full: __m256i,
    spare: __m256i,
}

/// The state of a group of eight rays in registers: positions, samples left in their inner
/// spans, and their runs (code and length capped at L).
struct Group {
    p: Positions,
    left: __m256i,
    code: __m256i,
    len: __m256i,
}

impl Group {
    #[target_feature(enable = "avx2")]
    fn load(walkers: &[Walker], block: u64) -> Self {
        let mut pos = [Wide::default(); 3];
        let (mut left, mut code, mut len) =
            (Narrow::default(), Narrow::default(), Narrow::default());
        for (l, w) in walkers.iter().enumerate() {
            for m in 0..3 {
                pos[m].0[l] = w.p[m];
            }
            // `walk` sends spans of 2^31 samples or more to the scalar walk.
            left.0[l] = w.inner as u32;
            let (c, n) = w.run.parts();
            code.0[l] = c as u32;
            len.0[l] = n.min(block) as u32;
        }
        Self {
            p: std::array::from_fn(|m| [pos[m].get(0), pos[m].get(1)]),
            left: left.get(),
            code: code.get(),
            len: len.get(),
        }
    }

    /// Puts the group's runs back in `walkers`, and each walker at the end of its inner span
    /// (`step` further per sample).
    #[target_feature(enable = "avx2")]
    fn store(&self, walkers: &mut [Walker], step: [i64; 3]) {
        let (mut code, mut len) = (Narrow::default(), Narrow::default());
        code.set(self.code);
        len.set(self.len);
        for (l, w) in walkers.iter_mut().enumerate() {
            for m in 0..3 {
                w.p[m] += w.inner * step[m];
            }
            w.run = Run::from_parts(u64::from(code.0[l]), u64::from(len.0[l]));
        }
    }

    /// Ends the runs of the lanes set in `lanes` (missing samples).
    #[target_feature(enable = "avx2")]
    fn end_runs(&mut self, mut lanes: u32, ends: &mut RunEnds) {
        let (mut code, mut len) = (Narrow::default(), Narrow::default());
        code.set(self.code);
        len.set(self.len);
        while lanes != 0 {
            let l = lanes.trailing_zeros() as usize;
            lanes &= lanes - 1;
            let (c, n) = (u64::from(code.0[l]), u64::from(len.0[l]));
            ends.end_run(&mut Run::from_parts(c, n));
            code.0[l] = 0;
            len.0[l] = 0;
        }
        (self.code, self.len) = (code.get(), len.get());
    }

    /// The bins of the samples in mixed cells (lanes set in `mixed`) one at a time, through
    /// the scalar path: for rays on the grid, and constant volumes. Returns the labels with
    /// those bins in, and the lanes whose sample is missing.
    #[target_feature(enable = "avx2")]
    fn mixed_one_by_one(
        &self,
        mut mixed: u32,
        labels: __m256i,
        walkers: &[Walker],
        sampler: &BinSampler,
    ) -> (__m256i, u32) {
        let mut values = Narrow::default();
        values.set(labels);
        let mut at = [Wide::default(); 3];
        for m in 0..3 {
            at[m].set(0, self.p[m][0]);
            at[m].set(1, self.p[m][1]);
        }
        let mut missing = 0;
        while mixed != 0 {
            let l = mixed.trailing_zeros() as usize;
            mixed &= mixed - 1;
            let here = [at[0].0[l], at[1].0[l], at[2].0[l]];
            if let Some(b) = mixed_bin(sampler, here, sampler.inner_cell(here), walkers[l].grid) {
                values.0[l] = u32::from(b);
            } else {
                missing |= 1 << l;
            }
        }
        (values.get(), missing)
    }
}

/// The lanes whose bits are set in `bits`, as a mask.
#[inline]
#[target_feature(enable = "avx2")]
fn lanes_of(bits: u32) -> __m256i {
    let each = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
    _mm256_cmpeq_epi32(_mm256_and_si256(_mm256_set1_epi32(bits as i32), each), each)
}

/// The eight lanes of a mask as bits.
#[inline]
#[target_feature(enable = "avx2")]
fn bits_of(mask: __m256i) -> u32 {
    _mm256_movemask_ps(_mm256_castsi256_ps(mask)) as u32
}

/// The inner spans of `walkers` (in tile order), eight neighbouring rays at a time, leaving
/// each at the end of its span with its run up to date.
#[target_feature(enable = "avx2")]
pub(super) fn walk(
    walkers: &mut [Walker],
    step: [i64; 3],
    sampler: &BinSampler,
    counts: &mut DenseCounts,
) {
    // Samples left are counted in signed 32-bit lanes.
    if walkers.iter().any(|w| w.inner > i64::from(i32::MAX)) {
        super::scalar_walk(walkers, step, sampler, counts);
        return;
    }
    let (bits, mask, block) = counts.packing();
    let (table, mut ends) = counts.split();
    assert_eq!(
        table.len() as u64,
        mask + 2,
        "a dense table holds every code and a spare"
    );
    let [_, sy, sz] = sampler.strides();
    let times = |n: i64| {
        [
            _mm256_set1_epi64x(step[0] * n),
            _mm256_set1_epi64x(step[1] * n),
            _mm256_set1_epi64x(step[2] * n),
        ]
    };
    let consts = Consts {
        sy: _mm256_set1_epi32(sy as i32),
        sz: _mm256_set1_epi32(sz as i32),
        step: times(1),
        near: times(AHEAD as i64),
        shift: _mm_cvtsi32_si128(bits as i32),
        code_mask: _mm256_set1_epi32(mask as i32),
        full: _mm256_set1_epi32(block as i32),
        spare: _mm256_set1_epi32(mask as i32 + 1),
    };
    let mixer = Mixer::new(sampler);
    for group in walkers.chunks_mut(LANES) {
        let mut g = Group::load(group, block);
        // On the grid, samples are voxels, not interpolated: the scalar path takes them.
        let vector_mixer = mixer.as_ref().filter(|_| !group.iter().any(|w| w.grid));
        walk_group(
            &mut g,
            group,
            &consts,
            sampler,
            vector_mixer,
            table,
            &mut ends,
        );
        g.store(group, step);
    }
}

/// The walk of one group through its inner spans.
#[target_feature(enable = "avx2")]
fn walk_group(
    g: &mut Group,
    walkers: &[Walker],
    c: &Consts,
    sampler: &BinSampler,
    mixer: Option<&Mixer>,
    table: &mut [u64],
    ends: &mut RunEnds,
) {
    let one = _mm256_set1_epi32(1);
    let steps = walkers.iter().map(|w| w.inner).max().unwrap_or(0);
    // The labels of the first AHEAD steps, then of AHEAD steps ahead as the group walks.
    let mut ring = [_mm256_setzero_si256(); AHEAD];
    let mut ahead = g.p;
    for (k, slot) in ring.iter_mut().enumerate() {
        let on = _mm256_cmpgt_epi32(g.left, _mm256_set1_epi32(k as i32));
        *slot = gather_labels(sampler, &ahead, on, c.sy, c.sz);
        ahead = offset(&ahead, &c.step);
    }
    for t in 0..steps as usize {
        let on = _mm256_cmpgt_epi32(g.left, _mm256_setzero_si256());
        let later = _mm256_cmpgt_epi32(g.left, _mm256_set1_epi32(AHEAD as i32));
        g.left = _mm256_sub_epi32(g.left, one);
        let ahead = offset(&g.p, &c.near);
        let mut future = Narrow::default();
        future.set(cells_shuffled(&offset(&ahead, &c.near), c.sy, c.sz));
        for &cell in &future.0 {
            sampler.prefetch_cell(cell as usize);
        }
        let slot = &mut ring[t % AHEAD];
        let mut labels = *slot;
        *slot = gather_labels(sampler, &ahead, later, c.sy, c.sz);

        let mixed = _mm256_and_si256(
            _mm256_cmpeq_epi32(labels, _mm256_set1_epi32(i32::from(MIXED))),
            on,
        );
        let mut push = on;
        if bits_of(mixed) != 0 {
            let missing = if let Some(mixer) = mixer {
                let (bins, missing) = mixer.bins(&g.p, mixed, c.sy, c.sz);
                labels = _mm256_blendv_epi8(labels, bins, mixed);
                bits_of(missing)
            } else {
                let (values, missing) =
                    g.mixed_one_by_one(bits_of(mixed), labels, walkers, sampler);
                labels = values;
                missing
            };
            if missing != 0 {
                g.end_runs(missing, ends);
                push = _mm256_andnot_si256(lanes_of(missing), push);
            }
        }
        // Append the symbols: code = (code << bits | symbol) & mask, length capped at L;
        // count each complete L-block, and send the other lanes to the spare slot.
        let pushed = _mm256_and_si256(
            _mm256_or_si256(_mm256_sll_epi32(g.code, c.shift), labels),
            c.code_mask,
        );
        let grown = _mm256_min_epu32(_mm256_add_epi32(g.len, one), c.full);
        g.code = _mm256_blendv_epi8(g.code, pushed, push);
        g.len = _mm256_blendv_epi8(g.len, grown, push);
        let complete = _mm256_and_si256(_mm256_cmpeq_epi32(g.len, c.full), push);
        let mut slots = Narrow::default();
        slots.set(_mm256_blendv_epi8(c.spare, g.code, complete));
        for &slot in &slots.0 {
            // Codes are masked to `mask`, the spare is `mask + 1`.
            table[slot as usize] += 1;
        }
        // Move on; lanes past their spans too (they read nothing more, and `Group::store`
        // puts them where their spans end).
        g.p = offset(&g.p, &c.step);
    }
}
