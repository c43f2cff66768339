//! A group of eight rays in registers: loaded from their walkers, walked a chunk at a time by the
//! read and count passes, and stored back.

use std::arch::x86_64::*;

use super::chunk::{CELL, Chunk};
use super::registers::{
    Narrow, Positions, Wide, bits_of, cells_shuffled, fractions, lanes_of, natural, offset,
    per_axis,
};
use super::{AHEAD, LANES};
use crate::measure::{Run, RunEnds};
use crate::view::rate::{BinSampler, Walker};
use crate::volume::Voxel;
use crate::volume::cells::MIXED;

/// The vector constants of one walk.
pub(super) struct Consts {
    /// Strides of the voxel grid along y and z.
    pub(super) sy: __m256i,
    pub(super) sz: __m256i,
    /// One step.
    pub(super) step: [__m256i; 3],
    /// The low 32 bits of a step (its fractional part), in 32-bit lanes.
    pub(super) step_low: [__m256i; 3],
    /// The packing of block codes: bits per symbol, mask, L; and the spare slot's index.
    pub(super) shift: __m128i,
    pub(super) code_mask: __m256i,
    pub(super) full: __m256i,
    pub(super) spare: __m256i,
}

/// The state of a group of eight rays in registers: positions, the lengths of their inner
/// spans, and their runs (code and length capped at L).
pub(super) struct Group {
    /// The positions AHEAD steps on, and the cells of the AHEAD steps before (step `t`'s at
    /// `t % AHEAD`), in lane order.
    pub(super) p: Positions,
    pub(super) cells: [__m256i; AHEAD],
    /// The fractional parts of the positions where the spans start.
    pub(super) origin: [__m256i; 3],
    pub(super) span: __m256i,
    pub(super) code: __m256i,
    pub(super) len: __m256i,
    /// Per lane: the code of its last complete block, and how many complete blocks in a row
    /// had it, not yet added to the table.
    pub(super) held: __m256i,
    pub(super) times: __m256i,
}

impl Group {
    #[inline(always)]
    pub(super) unsafe fn load(walkers: &[Walker], block: u64, c: &Consts) -> Self {
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
        let mut p = per_axis!(m => [pos[m].get(0), pos[m].get(1)]);
        let origin = fractions(&p);
        let mut cells = [_mm256_setzero_si256(); AHEAD];
        for cell in &mut cells {
            *cell = natural(cells_shuffled(&p, c.sy, c.sz));
            p = offset(&p, &c.step);
        }
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
    #[inline(always)]
    pub(super) unsafe fn store(&self, walkers: &mut [Walker], step: [i64; 3]) {
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
    #[inline(always)]
    pub(super) unsafe fn on(&self, t: usize) -> __m256i {
        _mm256_cmpgt_epi32(self.span, _mm256_set1_epi32(t as i32))
    }

    /// Ends the runs (`code`, `len`) of the lanes set in `lanes` (missing samples).
    #[inline(always)]
    pub(super) unsafe fn end_runs(
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
    #[inline(always)]
    pub(super) unsafe fn read<T: Voxel>(
        &mut self,
        chunk: &mut Chunk,
        c: &Consts,
        sampler: &BinSampler<T>,
    ) {
        let (cells, base) = (sampler.cells(), sampler.cells_base());
        // Lanes outside the window of the map (idle lanes, and only they: their labels are
        // neither queued nor counted) read its last cell instead: no bounds check a lane.
        let last = cells.len() - 1;
        let (base_lanes, last_lanes) = (
            _mm256_set1_epi32(base as i32),
            _mm256_set1_epi32(last as i32),
        );
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
            chunk.cells[t].set(cell);
            let mut inside = Narrow::default();
            inside.set(_mm256_min_epu32(
                _mm256_sub_epi32(cell, base_lanes),
                last_lanes,
            ));
            for (label, &i) in chunk.labels[t].iter_mut().zip(&inside.0) {
                debug_assert!(i as usize <= last);
                // SAFETY: `i` is at most the window's last index (the minimum above).
                *label = unsafe { *cells.get_unchecked(i as usize) };
            }
            self.p = offset(&self.p, &c.step);
        }
        // ...then the queue of the samples in mixed cells, from labels long in cache.
        let mut len = 0;
        for t in 0..chunk.steps {
            // SAFETY: the 8 bytes read are the step's labels.
            let labels = unsafe { _mm_loadl_epi64(chunk.labels[t].as_ptr().cast()) };
            let mixed = _mm_movemask_epi8(_mm_cmpeq_epi8(labels, _mm_set1_epi8(MIXED as i8)));
            if mixed == 0 {
                continue;
            }
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
    #[inline(always)]
    pub(super) unsafe fn count(
        &mut self,
        chunk: &Chunk,
        c: &Consts,
        table: &mut [u64],
        ends: &mut RunEnds,
    ) {
        let one = _mm256_set1_epi32(1);
        // The state in locals, which stay in registers: in `self` it would go through memory
        // at every step, as the table's increments might write it.
        let (mut code, mut len) = (self.code, self.len);
        let (mut held, mut times) = (self.held, self.times);
        // The labels and lanes of the last step when it left every lane it pushed to with a
        // complete block equal to the one before (one symbol repeated): a step with the same
        // labels and lanes repeats each lane's block, so it only counts them. (Most steps do,
        // in uniform regions; `u32::MAX` is no step's lanes.)
        let (mut repeat_labels, mut repeat_lanes) = (0, u32::MAX);
        for t in 0..chunk.steps {
            let mut push = self.on(chunk.start + t);
            let word = i64::from_le_bytes(chunk.labels[t]);
            if word == repeat_labels && bits_of(push) == repeat_lanes {
                times = _mm256_sub_epi32(times, push);
                continue;
            }
            let bytes = _mm_cvtsi64_si128(word);
            // A sample still MIXED after the resolve pass is missing (an idle lane's label
            // may be anything).
            let missing = _mm_movemask_epi8(_mm_cmpeq_epi8(bytes, _mm_set1_epi8(MIXED as i8)))
                as u32
                & bits_of(push);
            if missing != 0 {
                (code, len) = Self::end_runs(missing, (code, len), ends);
                push = _mm256_andnot_si256(lanes_of(missing), push);
            }
            let labels = _mm256_cvtepu8_epi32(bytes);
            // Append the symbols: code = (code << bits | symbol) & mask, length capped at L.
            let pushed = _mm256_and_si256(
                _mm256_or_si256(_mm256_sll_epi32(code, c.shift), labels),
                c.code_mask,
            );
            let grown = _mm256_min_epu32(_mm256_add_epi32(len, one), c.full);
            let repeated = _mm256_cmpeq_epi32(pushed, code);
            code = _mm256_blendv_epi8(code, pushed, push);
            len = _mm256_blendv_epi8(len, grown, push);
            // Count each complete L-block: most repeat their lane's last block, and are
            // counted in registers; at a step where some lane's block differs, those lanes
            // add their counts to the table.
            let complete = _mm256_and_si256(_mm256_cmpeq_epi32(len, c.full), push);
            let same = _mm256_cmpeq_epi32(code, held);
            times = _mm256_sub_epi32(times, _mm256_and_si256(complete, same));
            let change = _mm256_andnot_si256(same, complete);
            if bits_of(change) != 0 {
                Self::flush(change, held, times, table);
                held = _mm256_blendv_epi8(held, code, change);
                times = _mm256_blendv_epi8(times, one, change);
            }
            // Each lane pushed to now holds its block (`held`); when every one of them is
            // complete and its block the one before, the next step repeats them if its
            // labels and lanes are these. (A lane whose sample was missing is not among
            // these lanes, and is among the next step's unless its span ended.)
            let steady = bits_of(_mm256_andnot_si256(
                _mm256_and_si256(complete, repeated),
                push,
            )) == 0;
            (repeat_labels, repeat_lanes) = (word, if steady { bits_of(push) } else { u32::MAX });
        }
        (self.code, self.len) = (code, len);
        (self.held, self.times) = (held, times);
    }

    /// Adds the held counts of the lanes in the mask `lanes` to the table.
    #[inline(always)]
    pub(super) unsafe fn flush(lanes: __m256i, held: __m256i, times: __m256i, table: &mut [u64]) {
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
    #[inline(always)]
    pub(super) unsafe fn flush_all(&mut self, table: &mut [u64]) {
        Self::flush(_mm256_set1_epi32(-1), self.held, self.times, table);
        self.times = _mm256_setzero_si256();
    }
}
