//! The slices' sums and counts of counted values (for slab means), a row of the stack at a
//! time.

use std::ops::Range;

use rayon::prelude::*;

use super::{Cutter, other_axes};
use crate::error::Result;
use crate::progress::Monitor;
use crate::volume::Voxel;

/// Where a cut hands each row's [`SliceSums`], in row order.
pub(crate) type RowSink<'s> = &'s mut dyn FnMut(&SliceSums);

/// Per slice: the sum and count of the values that count (for slab means). A stack's are its
/// rows' added in row order, each row's counted from zero along the row (in the order of its
/// pixels for each slice): a float sum depends on the order of its additions, so this one order
/// is kept however the rows are cut, one strip after another or in parts apart.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct SliceSums {
    pub(crate) sums: Vec<f64>,
    pub(crate) counts: Vec<u64>,
}

impl SliceSums {
    /// None yet, for `slices` slices.
    pub(crate) fn new(slices: usize) -> Self {
        Self {
            sums: vec![0.0; slices],
            counts: vec![0; slices],
        }
    }

    /// Adds `other`'s, slice by slice.
    pub(crate) fn add_onto(&mut self, other: &Self) {
        self.sums
            .iter_mut()
            .zip(&other.sums)
            .for_each(|(a, b)| *a += b);
        self.counts
            .iter_mut()
            .zip(&other.counts)
            .for_each(|(a, b)| *a += b);
    }
}

impl Cutter<'_> {
    /// Each of `rows`' sums along coordinate axis `m` (row `j` the voxels at `j` along the
    /// slower of the other two axes), handed to `sink` in row order: a pass over the rows'
    /// voxels of its own, a few rows a thread at a time.
    pub(super) fn coordinate_row_sums(
        &self,
        m: usize,
        rows: Range<usize>,
        sink: RowSink,
        monitor: &Monitor,
    ) -> Result<()> {
        let rows: Vec<usize> = rows.collect();
        let group = 4 * rayon::current_num_threads();
        crate::volume::with_voxels!(self.volume.data(), |voxels| {
            for taken in rows.chunks(group) {
                let sums = taken
                    .par_iter()
                    .map(|&j| {
                        let sums = self.coordinate_row(voxels, m, j);
                        monitor.advance(1)?;
                        Ok(sums)
                    })
                    .collect::<Result<Vec<SliceSums>>>()?;
                sums.iter().for_each(&mut *sink);
            }
            Ok(())
        })
    }

    /// Row `j`'s sums along coordinate axis `m`: each slice's counted values added in the
    /// order of the row's pixels, whichever loop is outer (the inner one runs along x).
    fn coordinate_row<T: Voxel>(&self, voxels: &[T], m: usize, j: usize) -> SliceSums {
        let dims = self.volume.dims();
        let stride = [1, dims[0], dims[0] * dims[1]];
        let (a, b) = other_axes(m);
        let (n, row) = (dims[m], j * stride[b]);
        let background = self.background.test();
        let mut sums = SliceSums::new(n);
        let mut add = |s: usize, index: usize| {
            let v = voxels[index].to_f32();
            if v.is_finite() && !background.contains(index, v) {
                sums.sums[s] += f64::from(v);
                sums.counts[s] += 1;
            }
        };
        if m == 0 {
            for i in 0..dims[a] {
                (0..n).for_each(|s| add(s, row + i * stride[a] + s));
            }
        } else {
            for s in 0..n {
                (0..dims[a]).for_each(|i| add(s, row + i + s * stride[m]));
            }
        }
        sums
    }
}
