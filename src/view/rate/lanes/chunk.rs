//! A chunk of a group's walk: the labels of its steps, and the queue of samples in mixed cells
//! waiting to be resolved.

use std::arch::x86_64::*;

use super::LANES;
use super::registers::Narrow;
use crate::volume::cells::MIXED;

/// Steps of a group walked per chunk (see the module documentation).
pub(super) const CHUNK: usize = 32;

/// Entries of a chunk's queue: one per lane and step, and a register's worth past that.
pub(super) const QUEUE: usize = CHUNK * LANES + LANES;

/// The columns of a queue entry.
pub(super) const SLOT: usize = 0;
pub(super) const CELL: usize = 1;

/// For each mask of eight lanes, the indices of its set lanes in order, one per byte (the rest
/// zero): what moves those lanes to the front of a register.
pub(super) const LEFT_PACK: [u64; 256] = {
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
/// [`MIXED`] for samples in mixed cells until they are resolved, and for missing samples after:
/// no bin is [`MIXED`]); and the queue of samples in mixed cells, by slot (step in the chunk
/// · 8 + lane) and cell.
pub(super) struct Chunk {
    pub(super) start: usize,
    pub(super) steps: usize,
    pub(super) labels: [[u8; LANES]; CHUNK],
    pub(super) cells: [Narrow; CHUNK],
    pub(super) queue: [[u32; QUEUE]; 2],
    pub(super) len: usize,
}

impl Chunk {
    pub(super) fn new() -> Self {
        Self {
            start: 0,
            steps: 0,
            labels: [[0; LANES]; CHUNK],
            cells: [Narrow::default(); CHUNK],
            queue: [[0; QUEUE]; 2],
            len: 0,
        }
    }

    /// Writes the lanes set in `lanes` of `columns` to the queue from entry `at`, packed
    /// together, and returns the length after them. (The length is kept by the caller, in a
    /// register: in `self` it would go through memory at every step, as the stores might
    /// write it.)
    #[inline(always)]
    pub(super) unsafe fn enqueue(&mut self, at: usize, lanes: u32, columns: [__m256i; 2]) -> usize {
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
    #[inline(always)]
    pub(super) unsafe fn entries(&self, column: usize, k: usize) -> __m256i {
        let from = &self.queue[column][k..k + LANES];
        // SAFETY: the 32 bytes read are `from`'s; the load needs no alignment.
        unsafe { _mm256_loadu_si256(from.as_ptr().cast()) }
    }

    /// The step and lane of queue entry `k`.
    #[inline]
    pub(super) fn slot(&self, k: usize) -> (usize, usize) {
        let slot = self.queue[SLOT][k] as usize;
        (slot / LANES, slot % LANES)
    }

    /// Puts `label` in slot `slot` (step in the chunk · 8 + lane): a bin, or [`MIXED`] for a
    /// missing sample. Slots are below [`CHUNK`] · 8 = 256, so the slot's low byte is it: no
    /// bounds check.
    #[inline(always)]
    pub(super) fn put(&mut self, slot: u32, label: u8) {
        const { assert!(CHUNK * LANES == 256) };
        self.labels.as_flattened_mut()[usize::from(slot as u8)] = label;
    }

    /// Puts the bin of queue entry `k`, or [`MIXED`] for its absence, in its slot.
    #[inline]
    pub(super) fn resolve(&mut self, k: usize, bin: Option<u8>) {
        self.put(self.queue[SLOT][k], bin.unwrap_or(MIXED));
    }
}
