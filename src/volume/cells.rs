//! The cell map behind quantized trilinear sampling: per cell of the voxel grid (indexed by its
//! lower corner voxel), the bin that all eight corners safely share, or [`MIXED`]. A trilinear
//! sample is a convex combination of its cell's corners, so it lies in their common bin: where
//! the map knows the bin, no interpolation is needed.

use rayon::prelude::*;

use super::{Quantizer, Volume};

/// Voxels per parallel task.
const CHUNK: usize = 1 << 16;

/// Marks a cell whose corners do not all lie safely inside one bin.
pub const MIXED: u8 = u8::MAX;

/// Per cell: the bin its corners share, or [`MIXED`], at the linear index of its lower corner
/// voxel (one byte per voxel). Entries of voxels on the last plane of an axis with more than one
/// voxel are no cell's and must not be read.
///
/// A corner counts as in a bin only with a margin for the rounding of f32 interpolation.
///
/// Returns the map and, per voxel, the bin it safely lies in or [`MIXED`] (near a bin edge, or
/// missing): samples on the voxel grid read that, and compute only the [`MIXED`] ones.
pub fn cell_map(volume: &Volume, q: &Quantizer) -> (Vec<u8>, Vec<u8>) {
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
    let mut bins: Vec<u8> = vec![0; voxels.len()];
    bins.par_chunks_mut(CHUNK)
        .zip(voxels.par_chunks(CHUNK))
        .for_each(|(b, v)| b.iter_mut().zip(v).for_each(|(b, &v)| *b = safe_bin(v)));
    // A cell is uniform when its eight corners share a bin. Entries without a whole cell (on
    // the last plane of an axis) are left MIXED and never read.
    let [nx, ny, nz] = volume.dims();
    let next = |n: usize, stride: usize| if n > 1 { stride } else { 0 };
    let (x, y, z) = (next(nx, 1), next(ny, nx), next(nz, nx * ny));
    let corners = [x, y, y + x, z, z + x, z + y, z + y + x];
    let cells_with_corners = bins.len() - (z + y + x);
    let mut cells = vec![MIXED; bins.len()];
    cells[..cells_with_corners]
        .par_chunks_mut(CHUNK)
        .enumerate()
        .for_each(|(c, out)| {
            let start = c * CHUNK;
            let here = &bins[start..start + out.len()];
            let others = corners.map(|o| &bins[start + o..start + o + out.len()]);
            for (i, (o, &b)) in out.iter_mut().zip(here).enumerate() {
                let same = others.iter().all(|other| other[i] == b);
                *o = if same { b } else { MIXED };
            }
        });
    (cells, bins)
}
