//! The common walk of a tile eight rays at a time with AVX2 (x86-64 processors since 2013).
//!
//! A group of eight neighbouring rays walks its inner spans together, in chunks of [`CHUNK`]
//! steps, each in three passes with no branch per step or per lane on the data (only loops over
//! the queue of mixed samples, and a rare one for missing samples):
//!
//! 1. **Read**: positions and cell indices in vector registers, the label of each lane's cell
//!    (its bin, or [`MIXED`]) into the chunk, cells prefetched [`AHEAD`] steps before they are
//!    read. The samples in mixed cells are appended to a queue (packed with a permutation, not
//!    a branch per lane), and their corners prefetched. Reading the labels is one loop and
//!    queueing another: in one loop each step's queueing waited on its label loads, and the
//!    processor could keep only two or three steps in flight (about 8% slower).
//! 2. **Resolve**, a chunk later (so that the corners have arrived): the queued samples are
//!    interpolated and quantized eight at a time, every lane a real sample, with the same f32
//!    and f64 operations as `BinSampler::inner_bin`.
//! 3. **Count**: the chunk's symbols are appended to the rays' runs, and complete L-blocks
//!    counted. A lane holds the count of its last block in a register while the block repeats
//!    (in nine steps of ten all eight lanes repeat theirs, inside uniform regions) and adds it
//!    to the table when the block changes: a table increment per sample took a quarter of the
//!    walk's time.
//!
//! Walking and interpolating in one pass, as this module did before, was 10–15% slower: about
//! one step in three has a sample in a mixed cell, and the branches on it were mispredicted.
//! (AVX2 gathers were tried for the reads and were no faster than plain loads on the processors
//! here.) The walk feeds exactly the same symbols to the same sequences as
//! [`super::scalar_walk`]; only the order in which rays take turns differs, and counts are sums.
#![allow(unsafe_code)]
// The intrinsics used are too many to name one by one.
#![allow(clippy::wildcard_imports)]

use std::arch::x86_64::*;

use super::BinSampler;
use super::{Walker, mixed_bin};
use crate::geometry::lattice::FIXED_BITS;
use crate::measure::{DenseCounts, Run, RunEnds};
use crate::volume::cells::MIXED;

/// Rays per group: eight 32-bit lanes of a 256-bit register.
const LANES: usize = 8;

/// How many steps before its label is read a cell is prefetched.
const AHEAD: usize = 16;

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
}

/// The fractional parts (the low 32 bits) of the coordinates of eight positions, in 32-bit
/// lanes in order.
#[inline]
#[target_feature(enable = "avx2")]
fn fractions(p: &Positions) -> [__m256i; 3] {
    std::array::from_fn(|m| {
        natural(_mm256_castps_si256(_mm256_shuffle_ps::<0b10_00_10_00>(
            _mm256_castsi256_ps(p[m][0]),
            _mm256_castsi256_ps(p[m][1]),
        )))
    })
}

/// Steps of a group walked per chunk (see the module documentation).
const CHUNK: usize = 32;

/// Entries of a chunk's queue: one per lane and step, and a register's worth past that.
const QUEUE: usize = CHUNK * LANES + LANES;

/// The columns of a queue entry.
const SLOT: usize = 0;
const CELL: usize = 1;

/// For each mask of eight lanes, the indices of its set lanes in order, one per byte (the rest
/// zero): what moves those lanes to the front of a register.
const LEFT_PACK: [u64; 256] = {
    let mut table = [0; 256];
    let mut mask = 0;
    while mask < 256 {
        let (mut lane, mut packed, mut at) = (0, 0u64, 0);
        while lane < LANES {
            if mask >> lane & 1 == 1 {
                packed |= (lane as u64) << (8 * at);
                at += 1;
            }
            lane += 1;
        }
        table[mask] = packed;
        mask += 1;
    }
    table
};

/// Up to [`CHUNK`] steps of a group from step `start`: per step the lanes' labels (bins, with
/// [`MIXED`] for samples in mixed cells until they are resolved) and the lanes whose sample is
/// missing; and the queue of samples in mixed cells, by slot (step in the chunk · 8 + lane) and
/// cell.
struct Chunk {
    start: usize,
    steps: usize,
    labels: [[u8; LANES]; CHUNK],
    cells: [Narrow; CHUNK],
    missing: [u8; CHUNK],
    queue: [[u32; QUEUE]; 2],
    len: usize,
}

impl Chunk {
    fn new() -> Self {
        Self {
            start: 0,
            steps: 0,
            labels: [[0; LANES]; CHUNK],
            cells: [Narrow::default(); CHUNK],
            missing: [0; CHUNK],
            queue: [[0; QUEUE]; 2],
            len: 0,
        }
    }

    /// Writes the lanes set in `lanes` of `columns` to the queue from entry `at`, packed
    /// together, and returns the length after them. (The length is kept by the caller, in a
    /// register: in `self` it would go through memory at every step, as the stores might
    /// write it.)
    #[inline]
    #[target_feature(enable = "avx2")]
    fn enqueue(&mut self, at: usize, lanes: u32, columns: [__m256i; 2]) -> usize {
        let order = _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(LEFT_PACK[lanes as usize] as i64));
        for (queue, column) in self.queue.iter_mut().zip(columns) {
            let to = &mut queue[at..at + LANES];
            // SAFETY: the 32 bytes written are `to`'s; the store needs no alignment.
            unsafe {
                _mm256_storeu_si256(
                    to.as_mut_ptr().cast(),
                    _mm256_permutevar8x32_epi32(column, order),
                );
            }
        }
        at + lanes.count_ones() as usize
    }

    /// Entries `k..k + 8` of the queue column `column`.
    #[inline]
    #[target_feature(enable = "avx2")]
    fn entries(&self, column: usize, k: usize) -> __m256i {
        let from = &self.queue[column][k..k + LANES];
        // SAFETY: the 32 bytes read are `from`'s; the load needs no alignment.
        unsafe { _mm256_loadu_si256(from.as_ptr().cast()) }
    }

    /// The step and lane of queue entry `k`.
    #[inline]
    fn slot(&self, k: usize) -> (usize, usize) {
        let slot = self.queue[SLOT][k] as usize;
        (slot / LANES, slot % LANES)
    }

    /// Puts the bin of queue entry `k`, or its absence, in its slot.
    #[inline]
    fn resolve(&mut self, k: usize, bin: Option<u8>) {
        let (t, l) = self.slot(k);
        match bin {
            Some(b) => self.labels[t][l] = b,
            None => self.missing[t] |= 1 << l,
        }
    }
}

impl Mixer<'_> {
    /// The bins of eight trilinear samples in the cells `cell` whose coordinates have the
    /// fractional parts `low` (in fixed point), and the lanes whose sample is missing (a NaN
    /// corner): the same as `BinSampler::inner_bin`, eight at a time.
    #[inline]
    #[target_feature(enable = "avx2")]
    fn bins(&self, cell: __m256i, low: [__m256i; 3]) -> (__m256i, __m256i) {
        let mut base = Narrow::default();
        base.set(cell);
        let mut corners = [Narrow::default(); 8];
        for (l, &base) in base.0.iter().enumerate() {
            for (corner, &offset) in corners.iter_mut().zip(&self.corners) {
                corner.0[l] = self.voxels[base as usize + offset].to_bits();
            }
        }
        let c: [__m256; 8] = std::array::from_fn(|k| _mm256_castsi256_ps(corners[k].get()));
        // Fractions: as f64 times 2^-32, rounded to f32.
        let fraction = |low: __m256i| {
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
        let f = low.map(fraction);
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
        (bins, missing)
    }

    /// Resolves the queue of `chunk` eight entries at a time.
    #[target_feature(enable = "avx2")]
    fn resolve(&self, chunk: &mut Chunk, origin: &[__m256i; 3], step: &[__m256i; 3]) {
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
            let low = std::array::from_fn(|m| {
                _mm256_add_epi32(
                    _mm256_permutevar8x32_epi32(origin[m], lane),
                    _mm256_mullo_epi32(t, step[m]),
                )
            });
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

/// The vector constants of one walk.
struct Consts {
    /// Strides of the voxel grid along y and z.
    sy: __m256i,
    sz: __m256i,
    /// One step.
    step: [__m256i; 3],
    /// The low 32 bits of a step (its fractional part), in 32-bit lanes.
    step_low: [__m256i; 3],
    /// The packing of block codes: bits per symbol, mask, L; and the spare slot's index.
    shift: __m128i,
    code_mask: __m256i,
    full: __m256i,
    spare: __m256i,
}

/// The state of a group of eight rays in registers: positions, the lengths of their inner
/// spans, and their runs (code and length capped at L).
struct Group {
    /// The positions AHEAD steps on, and the cells of the AHEAD steps before (step `t`'s at
    /// `t % AHEAD`), in lane order.
    p: Positions,
    cells: [__m256i; AHEAD],
    /// The fractional parts of the positions where the spans start.
    origin: [__m256i; 3],
    span: __m256i,
    code: __m256i,
    len: __m256i,
    /// Per lane: the code of its last complete block, and how many complete blocks in a row
    /// had it, not yet added to the table.
    held: __m256i,
    times: __m256i,
}

impl Group {
    #[target_feature(enable = "avx2")]
    fn load(walkers: &[Walker], block: u64, c: &Consts) -> Self {
        let mut pos = [Wide::default(); 3];
        let (mut span, mut code, mut len) =
            (Narrow::default(), Narrow::default(), Narrow::default());
        for (l, w) in walkers.iter().enumerate() {
            for m in 0..3 {
                pos[m].0[l] = w.p[m];
            }
            // `walk` sends spans of 2^31 samples or more to the scalar walk.
            span.0[l] = w.inner as u32;
            let (c, n) = w.run.parts();
            code.0[l] = c as u32;
            len.0[l] = n.min(block) as u32;
        }
        let mut p = std::array::from_fn(|m| [pos[m].get(0), pos[m].get(1)]);
        let origin = fractions(&p);
        let cells = std::array::from_fn(|_| {
            let cell = natural(cells_shuffled(&p, c.sy, c.sz));
            p = offset(&p, &c.step);
            cell
        });
        Self {
            p,
            cells,
            origin,
            span: span.get(),
            code: code.get(),
            len: len.get(),
            held: c.spare,
            times: _mm256_setzero_si256(),
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

    /// The lanes still in their inner spans at step `t`.
    #[inline]
    #[target_feature(enable = "avx2")]
    fn on(&self, t: usize) -> __m256i {
        _mm256_cmpgt_epi32(self.span, _mm256_set1_epi32(t as i32))
    }

    /// Ends the runs (`code`, `len`) of the lanes set in `lanes` (missing samples).
    #[target_feature(enable = "avx2")]
    fn end_runs(
        mut lanes: u32,
        (code, len): (__m256i, __m256i),
        ends: &mut RunEnds,
    ) -> (__m256i, __m256i) {
        let (mut codes, mut lens) = (Narrow::default(), Narrow::default());
        codes.set(code);
        lens.set(len);
        while lanes != 0 {
            let l = lanes.trailing_zeros() as usize;
            lanes &= lanes - 1;
            let (c, n) = (u64::from(codes.0[l]), u64::from(lens.0[l]));
            ends.end_run(&mut Run::from_parts(c, n));
            codes.0[l] = 0;
            lens.0[l] = 0;
        }
        (codes.get(), lens.get())
    }

    /// Walks `chunk.steps` steps from step `chunk.start`: reads the labels of the cells, and
    /// queues the samples in mixed cells (prefetching the cells AHEAD steps on).
    #[target_feature(enable = "avx2")]
    fn read(&mut self, chunk: &mut Chunk, c: &Consts, sampler: &BinSampler) {
        let cells = sampler.cells();
        chunk.missing = [0; CHUNK];
        // First the labels: no step waits for another's, so many are read at once...
        for t in 0..chunk.steps {
            let step = chunk.start + t;
            let on = self.on(step);
            let ring = &mut self.cells[step % AHEAD];
            // Lanes past their spans (whose positions may lie outside the volume) read cell 0.
            let cell = _mm256_and_si256(*ring, on);
            *ring = natural(cells_shuffled(&self.p, c.sy, c.sz));
            let mut future = Narrow::default();
            future.set(*ring);
            for &cell in &future.0 {
                sampler.prefetch_cell(cell as usize);
            }
            let at = &mut chunk.cells[t];
            at.set(cell);
            for (label, &i) in chunk.labels[t].iter_mut().zip(&at.0) {
                *label = cells[i as usize];
            }
            self.p = offset(&self.p, &c.step);
        }
        // ...then the queue of the samples in mixed cells, from labels long in cache.
        let mut len = 0;
        for t in 0..chunk.steps {
            // SAFETY: the 8 bytes read are the step's labels.
            let labels = unsafe { _mm_loadl_epi64(chunk.labels[t].as_ptr().cast()) };
            let mixed = _mm_movemask_epi8(_mm_cmpeq_epi8(labels, _mm_set1_epi8(MIXED as i8)));
            let slots = _mm256_add_epi32(
                _mm256_set1_epi32((t * LANES) as i32),
                _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7),
            );
            let lanes = mixed as u32 & bits_of(self.on(chunk.start + t));
            len = chunk.enqueue(len, lanes, [slots, chunk.cells[t].get()]);
        }
        chunk.len = len;
        for &cell in &chunk.queue[CELL][..len] {
            sampler.prefetch_corners(cell as usize);
        }
    }

    /// Appends the chunk's samples to the runs, counting each complete L-block.
    #[target_feature(enable = "avx2")]
    fn count(&mut self, chunk: &Chunk, c: &Consts, table: &mut [u64], ends: &mut RunEnds) {
        let one = _mm256_set1_epi32(1);
        // The state in locals, which stay in registers: in `self` it would go through memory
        // at every step, as the table's increments might write it.
        let (mut code, mut len) = (self.code, self.len);
        let (mut held, mut times) = (self.held, self.times);
        for t in 0..chunk.steps {
            let mut push = self.on(chunk.start + t);
            let missing = chunk.missing[t];
            if missing != 0 {
                (code, len) = Self::end_runs(u32::from(missing), (code, len), ends);
                push = _mm256_andnot_si256(lanes_of(u32::from(missing)), push);
            }
            let labels =
                _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(i64::from_le_bytes(chunk.labels[t])));
            // Append the symbols: code = (code << bits | symbol) & mask, length capped at L.
            let pushed = _mm256_and_si256(
                _mm256_or_si256(_mm256_sll_epi32(code, c.shift), labels),
                c.code_mask,
            );
            let grown = _mm256_min_epu32(_mm256_add_epi32(len, one), c.full);
            code = _mm256_blendv_epi8(code, pushed, push);
            len = _mm256_blendv_epi8(len, grown, push);
            // Count each complete L-block: most (nine steps in ten have all eight lanes so)
            // repeat their lane's last block, and are counted in registers; at a step where
            // some lane's block differs, those lanes add their counts to the table.
            let complete = _mm256_and_si256(_mm256_cmpeq_epi32(len, c.full), push);
            let same = _mm256_cmpeq_epi32(code, held);
            times = _mm256_sub_epi32(times, _mm256_and_si256(complete, same));
            let change = _mm256_andnot_si256(same, complete);
            if bits_of(change) != 0 {
                Self::flush(change, held, times, table);
                held = _mm256_blendv_epi8(held, code, change);
                times = _mm256_blendv_epi8(times, one, change);
            }
        }
        (self.code, self.len) = (code, len);
        (self.held, self.times) = (held, times);
    }

    /// Adds the held counts of the lanes in the mask `lanes` to the table.
    #[inline]
    #[target_feature(enable = "avx2")]
    fn flush(lanes: __m256i, held: __m256i, times: __m256i, table: &mut [u64]) {
        let (mut codes, mut counts) = (Narrow::default(), Narrow::default());
        // The other lanes add nothing, to their own codes.
        codes.set(held);
        counts.set(_mm256_and_si256(times, lanes));
        for (&code, &count) in codes.0.iter().zip(&counts.0) {
            // Held codes are masked to `mask`, or the spare `mask + 1`.
            table[code as usize] += u64::from(count);
        }
    }

    /// Adds all held counts to the table.
    #[target_feature(enable = "avx2")]
    fn flush_all(&mut self, table: &mut [u64]) {
        Self::flush(_mm256_set1_epi32(-1), self.held, self.times, table);
        self.times = _mm256_setzero_si256();
    }
}

/// Resolves the queue of `chunk` one entry at a time, through the scalar path: for rays on the
/// grid, and constant volumes. `walkers` are the group's, at the start of their inner spans.
fn resolve_one_by_one(chunk: &mut Chunk, walkers: &[Walker], step: [i64; 3], sampler: &BinSampler) {
    for k in 0..chunk.len {
        let (t, l) = chunk.slot(k);
        let w = &walkers[l];
        let at = (chunk.start + t) as i64;
        let here = std::array::from_fn(|m| w.p[m] + at * step[m]);
        chunk.resolve(
            k,
            mixed_bin(sampler, here, sampler.inner_cell(here), w.grid),
        );
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
    let consts = Consts {
        sy: _mm256_set1_epi32(sy as i32),
        sz: _mm256_set1_epi32(sz as i32),
        step: step.map(|s| _mm256_set1_epi64x(s)),
        step_low: step.map(|s| _mm256_set1_epi32(s as i32)),
        shift: _mm_cvtsi32_si128(bits as i32),
        code_mask: _mm256_set1_epi32(mask as i32),
        full: _mm256_set1_epi32(block as i32),
        spare: _mm256_set1_epi32(mask as i32 + 1),
    };
    let mixer = Mixer::new(sampler);
    let mut chunks = Box::new([Chunk::new(), Chunk::new()]);
    for group in walkers.chunks_mut(LANES) {
        let mut g = Group::load(group, block, &consts);
        // On the grid, samples are voxels, not interpolated: the scalar path takes them.
        let vector_mixer = mixer.as_ref().filter(|_| !group.iter().any(|w| w.grid));
        let mut finish = |g: &mut Group, chunk: &mut Chunk| {
            match vector_mixer {
                Some(mixer) => mixer.resolve(chunk, &g.origin, &consts.step_low),
                None => resolve_one_by_one(chunk, group, step, sampler),
            }
            g.count(chunk, &consts, table, &mut ends);
        };
        // A pipeline of two chunks: the labels of one are read (and the corners of its mixed
        // cells prefetched) before the mixed samples of the one before are resolved and its
        // samples counted.
        let steps = group.iter().map(|w| w.inner).max().unwrap_or(0) as usize;
        let mut last = None;
        for (k, start) in (0..steps).step_by(CHUNK).enumerate() {
            let [a, b] = &mut *chunks;
            let (now, before) = if k % 2 == 0 { (a, b) } else { (b, a) };
            now.start = start;
            now.steps = CHUNK.min(steps - start);
            g.read(now, &consts, sampler);
            if k > 0 {
                finish(&mut g, before);
            }
            last = Some(k % 2);
        }
        if let Some(last) = last {
            finish(&mut g, &mut chunks[last]);
        }
        g.flush_all(table);
        g.store(group, step);
    }
}
