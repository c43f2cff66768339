//! Moving eight lanes between registers and memory, and the register arithmetic on positions the
//! walk shares: offsets, cell indices, fractional parts, lane masks.

use std::arch::x86_64::*;

use super::LANES;
use crate::geometry::lattice::FIXED_BITS;

/// Eight 64-bit values in memory, for moving between two registers and scalar code.
#[derive(Clone, Copy, Default)]
#[repr(C, align(32))]
pub(super) struct Wide(pub(super) [i64; LANES]);

impl Wide {
    /// Values `4·half..4·half + 4` as a register.
    #[inline(always)]
    pub(super) unsafe fn get(&self, half: usize) -> __m256i {
        let v = &self.0[4 * half..4 * half + 4];
        // SAFETY: the 32 bytes read are `v`'s, aligned since `half` is 0 or 1.
        unsafe { _mm256_load_si256(v.as_ptr().cast()) }
    }
}

/// Eight 32-bit values in memory, for moving between a register and scalar code.
#[derive(Clone, Copy, Default)]
#[repr(C, align(32))]
pub(super) struct Narrow(pub(super) [u32; LANES]);

impl Narrow {
    #[inline(always)]
    pub(super) unsafe fn get(&self) -> __m256i {
        // SAFETY: the 32 bytes read are the array's, which is aligned.
        unsafe { _mm256_load_si256(self.0.as_ptr().cast()) }
    }

    #[inline(always)]
    pub(super) unsafe fn set(&mut self, x: __m256i) {
        // SAFETY: the 32 bytes written are the array's, which is aligned.
        unsafe { _mm256_store_si256(self.0.as_mut_ptr().cast(), x) }
    }
}

/// Positions of eight lanes: fixed-point coordinates, two registers of four each.
pub(super) type Positions = [[__m256i; 2]; 3];

/// `[e(0), e(1), e(2)]` for an expression `e` of `m`, written out: `std::array::from_fn`'s
/// closure would be compiled with no target features, its intrinsics calls.
macro_rules! per_axis {
    ($m:ident => $e:expr) => {
        [
            {
                let $m = 0;
                $e
            },
            {
                let $m = 1;
                $e
            },
            {
                let $m = 2;
                $e
            },
        ]
    };
}
pub(super) use per_axis;

/// `p + d` for every lane.
#[inline(always)]
pub(super) unsafe fn offset(p: &Positions, d: &[__m256i; 3]) -> Positions {
    per_axis!(m => [
        _mm256_add_epi64(p[m][0], d[m]),
        _mm256_add_epi64(p[m][1], d[m]),
    ])
}

/// The cell indices `(x >> 32) + (y >> 32)·sy + (z >> 32)·sz` of eight positions in 32-bit
/// lanes, in the lane order 0, 1, 4, 5, 2, 3, 6, 7 (see [`natural`]).
#[inline(always)]
pub(super) unsafe fn cells_shuffled(p: &Positions, sy: __m256i, sz: __m256i) -> __m256i {
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
#[inline(always)]
pub(super) unsafe fn natural(v: __m256i) -> __m256i {
    _mm256_permutevar8x32_epi32(v, _mm256_setr_epi32(0, 1, 4, 5, 2, 3, 6, 7))
}

/// The fractional parts (the low 32 bits) of the coordinates of eight positions, in 32-bit
/// lanes in order.
#[inline(always)]
pub(super) unsafe fn fractions(p: &Positions) -> [__m256i; 3] {
    per_axis!(m => natural(_mm256_castps_si256(_mm256_shuffle_ps::<0b10_00_10_00>(
        _mm256_castsi256_ps(p[m][0]),
        _mm256_castsi256_ps(p[m][1]),
    ))))
}

/// The lanes whose bits are set in `bits`, as a mask.
#[inline(always)]
pub(super) unsafe fn lanes_of(bits: u32) -> __m256i {
    let each = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
    _mm256_cmpeq_epi32(_mm256_and_si256(_mm256_set1_epi32(bits as i32), each), each)
}

/// The eight lanes of a mask as bits.
#[inline(always)]
pub(super) unsafe fn bits_of(mask: __m256i) -> u32 {
    _mm256_movemask_ps(_mm256_castsi256_ps(mask)) as u32
}
