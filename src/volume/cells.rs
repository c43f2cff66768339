//! The cell map behind quantized trilinear sampling: per cell of the voxel grid (indexed by its
//! lower corner voxel), the bin that all eight corners safely share, or [`MIXED`]. A trilinear
//! sample is a convex combination of its cell's corners, so it lies in their common bin: where
//! the map knows the bin, no interpolation is needed.

use rayon::prelude::*;

use super::{Quantizer, Volume};

/// Marks a cell whose corners do not all lie safely inside one bin.
pub const MIXED: u8 = u8::MAX;

/// Per cell: the bin its corners share, or [`MIXED`], at the linear index of its lower corner
/// voxel (one byte per voxel). Entries of voxels on the last plane of an axis with more than one
/// voxel are no cell's and must not be read.
///
/// A corner counts as in a bin only with a margin for the rounding of f32 interpolation.
pub fn cell_map(volume: &Volume, q: &Quantizer) -> Vec<u8> {
    let s = volume.stats();
    // Trilinear interpolation in f32 is within a few ulps of the largest corner magnitude; keep
    // corners 16 ulps (in bin units) away from the bin edges.
    let span = f64::from(s.max) - f64::from(s.min);
    let scale = if span > 0.0 {
        q.bins() as f64 / span
    } else {
        0.0
    };
    let magnitude = f64::from(s.min.abs().max(s.max.abs()));
    let margin = 16.0 * f64::from(f32::EPSILON) * magnitude * scale + 1e-9;
    let last = q.bins() - 1;
    let safe_bin = |v: f32| -> u8 {
        if v.is_nan() {
            return MIXED;
        }
        let t = (f64::from(v) - f64::from(s.min)) * scale;
        let b = (t.max(0.0) as usize).min(last);
        let low_ok = b == 0 || t - b as f64 >= margin;
        let high_ok = b == last || (b + 1) as f64 - t >= margin;
        if low_ok && high_ok { b as u8 } else { MIXED }
    };
    let voxels = volume.voxels();
    let mut cells: Vec<u8> = vec![0; voxels.len()];
    cells
        .par_chunks_mut(1 << 16)
        .zip(voxels.par_chunks(1 << 16))
        .for_each(|(b, v)| b.iter_mut().zip(v).for_each(|(b, &v)| *b = safe_bin(v)));
    // A cell is uniform when its corners agree pairwise along x, then y, then z: three passes
    // of `a[i] = a[i] if a[i] == a[i + offset] else MIXED`. Entries whose partner wraps around a
    // row belong to no cell and are never read.
    let [nx, ny, nz] = volume.dims();
    let mut spare = Vec::new();
    for (n, stride) in [(nx, 1), (ny, nx), (nz, nx * ny)] {
        if n > 1 {
            merge_with_neighbour(&cells, stride, &mut spare);
            std::mem::swap(&mut cells, &mut spare);
        }
    }
    cells
}

/// `out[i] = a[i]` where `a[i] == a[i + offset]`, else `MIXED`; entries without a partner are
/// `MIXED`.
fn merge_with_neighbour(a: &[u8], offset: usize, out: &mut Vec<u8>) {
    const CHUNK: usize = 1 << 16;
    let n = a.len();
    out.clear();
    out.resize(n, MIXED);
    let pairs = n.saturating_sub(offset);
    out[..pairs]
        .par_chunks_mut(CHUNK)
        .zip(
            a[..pairs]
                .par_chunks(CHUNK)
                .zip(a[offset..].par_chunks(CHUNK)),
        )
        .for_each(|(o, (x, y))| {
            for ((o, &x), &y) in o.iter_mut().zip(x).zip(y) {
                *o = if x == y { x } else { MIXED };
            }
        });
}
