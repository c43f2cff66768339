//! The common walk of a tile eight rays at a time with AVX2 (x86-64 processors since 2013).
//!
//! A group of eight neighbouring rays walks its inner spans together, in chunks of [`CHUNK`]
//! steps, each in three passes with no branch per lane on the data (per step only branches that
//! skip work in uniform regions, and a rare one for missing samples; loops over the queue of
//! mixed samples):
//!
//! 1. **Read**: positions and cell indices in vector registers, the label of each lane's cell
//!    (its bin, or [`MIXED`]) into the chunk, cells prefetched [`AHEAD`] steps before they are
//!    read. The samples in mixed cells are appended to a queue (packed with a permutation, not
//!    a branch per lane), and their corners prefetched. Reading the labels is one loop and
//!    queueing another: in one loop each step's queueing waited on its label loads, and the
//!    processor could keep only two or three steps in flight (about 8% slower). A step with no
//!    label [`MIXED`] queues nothing and is passed over (a branch, taken in uniform regions,
//!    where the packing took a twentieth of a default analysis's instructions).
//! 2. **Resolve**, a chunk later (so that the corners have arrived): the queued samples are
//!    interpolated and quantized eight at a time, every lane a real sample, from corners
//!    gathered (`Mixer::corner_values`), with the same f32 and f64 operations as
//!    `BinSampler::inner_bin`, and their labels put back in their slots
//!    of the chunk, a missing sample's as [`MIXED`] (which no bin is): eight stores, where
//!    putting each bin or absence in its step's lane by a branch took a tenth of the walk's
//!    instructions. The count pass finds the missing samples among the labels.
//! 3. **Count**: the chunk's symbols are appended to the rays' runs, and complete L-blocks
//!    counted. A lane holds the count of its last block in a register while the block repeats
//!    (in nine steps of ten all eight lanes repeat theirs, inside uniform regions) and adds it
//!    to the table when the block changes: a table increment per sample took a quarter of the
//!    walk's time. A step whose eight labels and lanes are the last step's, when that step left
//!    every lane with a block of one symbol repeated, repeats every block: it only adds one to
//!    each lane's count (one comparison of the labels as a word, where a whole step took about
//!    thirty instructions: 8–10% of a default analysis's).
//!
//! Walking and interpolating in one pass, as this module did before, was 10–15% slower: about
//! one step in three has a sample in a mixed cell, and the branches on it were mispredicted.
//! (AVX2 gathers were tried for the labels' reads and were no faster than plain loads on the
//! processors here; for the corners, one gather a register of a cell's corners replaced eight
//! loads, conversions and stores.) The walk feeds exactly the same symbols to the same sequences as
//! [`super::scalar_walk`]; only the order in which rays take turns differs, and counts are sums.
//!
//! The walk is compiled twice: for AVX2, and for processors with AVX-512 (F and VL), whose 32
//! vector registers hold the count pass's state where AVX2's 16 spilled part of it to the stack
//! at every step (the same instructions on 256-bit registers otherwise, so the same counts).
//! Its helpers are inlined into each (`#[inline(always)]`, which a function with its own target
//! features cannot be), so they are `unsafe fn`s: they may run only where AVX2 is.
//!
//! [`MIXED`]: crate::volume::cells::MIXED
#![allow(unsafe_code)]
// Every helper is an unsafe fn only for the processor it needs: its operations are intrinsics.
#![allow(unsafe_op_in_unsafe_fn)]
// The helpers must be inlined into each compilation of the walk (see above).
#![allow(clippy::inline_always)]
// The intrinsics used are too many to name one by one.
#![allow(clippy::wildcard_imports)]

mod chunk;
mod group;
mod mixer;
mod registers;
#[cfg(test)]
mod tests;

use std::arch::x86_64::*;

use super::BinSampler;
use super::{Walker, mixed_bin};
use crate::measure::DenseCounts;
use crate::volume::Voxel;
use chunk::{CHUNK, Chunk};
use group::{Consts, Group};
use mixer::Mixer;

/// Rays per group: eight 32-bit lanes of a 256-bit register.
const LANES: usize = 8;

/// How many steps before its label is read a cell is prefetched.
const AHEAD: usize = 16;

/// Whether this processor has AVX2, and `sampler`'s cells (a map of at least one) can be
/// indexed by 32-bit lanes.
pub(super) fn available<T: Voxel>(sampler: &BinSampler<T>) -> bool {
    is_x86_feature_detected!("avx2")
        && i32::try_from(sampler.voxels().len()).is_ok()
        && !sampler.cells().is_empty()
}

/// Resolves the queue of `chunk` one entry at a time, through the scalar path: for rays on the
/// grid, and constant volumes. `walkers` are the group's, at the start of their inner spans.
fn resolve_one_by_one<T: Voxel>(
    chunk: &mut Chunk,
    walkers: &[Walker],
    step: [i64; 3],
    sampler: &BinSampler<T>,
) {
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

/// The two chunks of a walk's pipeline, made once for many walks (a thread's row of tiles):
/// made for every tile, zeroing them took 3% of the instructions of a default analysis.
/// Nothing a walk reads of them was left by the walk before: each chunk's steps and queue are
/// written before they are read.
pub(super) struct Chunks(Box<[Chunk; 2]>);

impl Chunks {
    pub(super) fn new() -> Self {
        Self(Box::new([Chunk::new(), Chunk::new()]))
    }
}

/// The widest compilation of the walk this processor runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Width {
    /// AVX2: 16 vector registers.
    Avx2,
    /// AVX-512 F and VL: 32 vector registers.
    Avx512,
}

impl Width {
    /// This processor's (which [`available`] must have found to have AVX2).
    pub(super) fn detected() -> Self {
        if is_x86_feature_detected!("avx512f") && is_x86_feature_detected!("avx512vl") {
            Self::Avx512
        } else {
            Self::Avx2
        }
    }
}

/// The inner spans of `walkers` (in tile order), eight neighbouring rays at a time, leaving
/// each at the end of its span with its run up to date, by the walk compiled for `width`.
///
/// # Safety
///
/// The processor has AVX2 ([`available`]), and AVX-512 F and VL for [`Width::Avx512`].
pub(super) unsafe fn walk<T: Voxel>(
    width: Width,
    walkers: &mut [Walker],
    (step, sampler): ([i64; 3], &BinSampler<T>),
    counts: &mut DenseCounts,
    chunks: &mut Chunks,
) {
    match width {
        Width::Avx2 => walk_avx2(walkers, step, sampler, counts, chunks),
        Width::Avx512 => walk_avx512(walkers, step, sampler, counts, chunks),
    }
}

#[target_feature(enable = "avx2")]
fn walk_avx2<T: Voxel>(
    walkers: &mut [Walker],
    step: [i64; 3],
    sampler: &BinSampler<T>,
    counts: &mut DenseCounts,
    chunks: &mut Chunks,
) {
    // SAFETY: this function runs where AVX2 is.
    unsafe { walk_with(walkers, step, sampler, counts, &mut chunks.0) }
}

#[target_feature(enable = "avx2,avx512f,avx512vl")]
fn walk_avx512<T: Voxel>(
    walkers: &mut [Walker],
    step: [i64; 3],
    sampler: &BinSampler<T>,
    counts: &mut DenseCounts,
    chunks: &mut Chunks,
) {
    // SAFETY: this function runs where AVX2 is.
    unsafe { walk_with(walkers, step, sampler, counts, &mut chunks.0) }
}

/// [`walk`]'s body, inlined into each compilation.
#[inline(always)]
unsafe fn walk_with<T: Voxel>(
    walkers: &mut [Walker],
    step: [i64; 3],
    sampler: &BinSampler<T>,
    counts: &mut DenseCounts,
    chunks: &mut [Chunk; 2],
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
        step: registers::per_axis!(m => _mm256_set1_epi64x(step[m])),
        step_low: registers::per_axis!(m => _mm256_set1_epi32(step[m] as i32)),
        shift: _mm_cvtsi32_si128(bits as i32),
        code_mask: _mm256_set1_epi32(mask as i32),
        full: _mm256_set1_epi32(block as i32),
        spare: _mm256_set1_epi32(mask as i32 + 1),
    };
    let mixer = Mixer::new(sampler);
    for group in walkers.chunks_mut(LANES) {
        let mut g = Group::load(group, block, &consts);
        // On the grid, samples are voxels, not interpolated: the scalar path takes them.
        let vector_mixer = mixer.as_ref().filter(|_| !group.iter().any(|w| w.grid));
        // Not a closure: a closure is compiled with no target features of its own, and its
        // intrinsics would be calls.
        macro_rules! finish {
            ($g:expr, $chunk:expr) => {{
                let (g, chunk): (&mut Group, &mut Chunk) = ($g, $chunk);
                match vector_mixer {
                    Some(mixer) => mixer.resolve(chunk, &g.origin, &consts.step_low),
                    None => resolve_one_by_one(chunk, group, step, sampler),
                }
                g.count(chunk, &consts, table, &mut ends);
            }};
        }
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
                finish!(&mut g, before);
            }
            last = Some(k % 2);
        }
        if let Some(last) = last {
            finish!(&mut g, &mut chunks[last]);
        }
        g.flush_all(table);
        g.store(group, step);
    }
}
