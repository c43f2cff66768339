//! The found background ([`BackgroundRule::Auto`](super::BackgroundRule::Auto)) of a volume held
//! in parts (issue #44: one volume across a cluster's tasks), each task holding one chunk (a box
//! of the whole grid), with exactly [`Background::find`](super::Background::find)'s answer.
//!
//! Three rounds: (1) each task gives the finite values of its chunk on the volume's six faces
//! ([`border_values_in`]), and the client finds the threshold from all of them
//! ([`threshold_of_border`](super::threshold_of_border)); (2) each task labels the components
//! (6-neighbours) of its chunk's voxels at or below it ([`ChunkLabels::find`]) and sends a
//! [`ChunkSummary`]: the labels on the chunk's faces that lie inside the volume, run-length
//! coded, and which of them touch the volume's border; the client joins the summaries
//! ([`BackgroundJoin`]: a union-find of those labels, across the faces where two chunks meet)
//! and answers each chunk which of its labels are background ([`ChunkAnswer`]); (3) each task
//! makes its chunk's bits of the mask from its labels and the answer ([`ChunkMask`]), and the
//! mask assembled from them makes the [`Background`](super::Background::of_parts).
//!
//! A label on none of its chunk's inner faces is decided by the task alone (background when it
//! touches the volume's border), so only labels on inner faces travel and are joined.

use crate::error::{Error, Result};
use crate::volume::Voxel;

mod bytes;
mod join;
mod labels;
#[cfg(test)]
mod tests;

pub use join::BackgroundJoin;
pub use labels::{ChunkAnswer, ChunkLabels, ChunkMask, ChunkSummary};

/// A chunk: a box of a volume's grid, its voxels given x fastest.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Chunk {
    dims: [usize; 3],
    origin: [usize; 3],
    size: [usize; 3],
}

impl Chunk {
    /// The box of `size` voxels from voxel `origin` of a volume of dimensions `dims`; an error
    /// when it is empty or reaches outside the volume.
    pub fn new(dims: [usize; 3], origin: [usize; 3], size: [usize; 3]) -> Result<Self> {
        let inside = (0..3).all(|a| {
            size[a] > 0
                && origin[a]
                    .checked_add(size[a])
                    .is_some_and(|end| end <= dims[a])
        });
        let counted = dims
            .iter()
            .try_fold(1usize, |n, &d| n.checked_mul(d))
            .is_some();
        if !inside || !counted {
            return Err(Error::invalid(
                "chunk",
                format!("of {size:?} voxels at {origin:?}"),
                format!("a box of at least one voxel inside the volume's {dims:?}"),
            ));
        }
        Ok(Self { dims, origin, size })
    }

    /// The whole volume's dimensions.
    #[must_use]
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Its first voxel in the volume.
    #[must_use]
    pub fn origin(&self) -> [usize; 3] {
        self.origin
    }

    /// Its voxels along x, y and z.
    #[must_use]
    pub fn size(&self) -> [usize; 3] {
        self.size
    }

    /// Its number of voxels.
    #[must_use]
    pub fn len(&self) -> usize {
        self.size.iter().product()
    }

    /// Always false: a chunk has at least one voxel.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Whether face `face` (0 and 1 the low and high x faces, 2 and 3 y's, 4 and 5 z's) lies
    /// inside the volume, another chunk beyond it; else it lies on the volume's border.
    fn inner(&self, face: usize) -> bool {
        let a = face / 2;
        if face.is_multiple_of(2) {
            self.origin[a] > 0
        } else {
            self.origin[a] + self.size[a] < self.dims[a]
        }
    }

    /// An error unless `n` voxels are the chunk's.
    fn check_voxels(&self, n: usize) -> Result<()> {
        if n == self.len() {
            Ok(())
        } else {
            Err(Error::invalid(
                "chunk voxels",
                n,
                format!("the {} voxels of a chunk of {:?}", self.len(), self.size),
            ))
        }
    }

    /// The corner that names face `face` where two chunks meet: the origin moved along the
    /// face's axis to its plane (the first voxel beyond a high face).
    fn face_corner(&self, face: usize) -> [usize; 3] {
        let a = face / 2;
        let mut corner = self.origin;
        if face % 2 == 1 {
            corner[a] += self.size[a];
        }
        corner
    }
}

/// The two axes across face `face`'s axis, the first the faster along the face.
fn across(face: usize) -> (usize, usize) {
    match face / 2 {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    }
}

/// The voxels of face `face` of a box of `size`, as the box's linear indices in face order
/// (the lower of the two axes across it fastest).
fn face_indices(size: [usize; 3], face: usize) -> impl Iterator<Item = usize> {
    let a = face / 2;
    let (u, v) = across(face);
    let stride = [1, size[0], size[0] * size[1]];
    let plane = if face % 2 == 1 { size[a] - 1 } else { 0 } * stride[a];
    (0..size[v]).flat_map(move |j| (0..size[u]).map(move |i| plane + i * stride[u] + j * stride[v]))
}

/// The number of voxels on face `face` of a box of `size`.
fn face_area(size: [usize; 3], face: usize) -> usize {
    let (u, v) = across(face);
    size[u] * size[v]
}

/// The finite values of `voxels` (the chunk's, x fastest) that lie on the whole volume's six
/// faces: every chunk's, in any order, are what
/// [`threshold_of_border`](super::threshold_of_border) needs to give
/// [`border_threshold`](super::border_threshold)'s value. Reads no voxel outside the chunk.
pub fn border_values_in<T: Voxel>(voxels: &[T], chunk: &Chunk) -> Result<Vec<f32>> {
    chunk.check_voxels(voxels.len())?;
    let [nx, ny, nz] = chunk.dims;
    let [ox, oy, oz] = chunk.origin;
    let [sx, sy, sz] = chunk.size;
    let mut out = Vec::new();
    for z in 0..sz {
        for y in 0..sy {
            let (gy, gz) = (oy + y, oz + z);
            let row = &voxels[(z * sy + y) * sx..][..sx];
            if gz == 0 || gz + 1 == nz || gy == 0 || gy + 1 == ny {
                out.extend(row.iter().map(|x| x.to_f32()));
            } else {
                // As the whole volume's: its first and last voxel, one voxel twice when nx = 1.
                if ox == 0 {
                    out.push(row[0].to_f32());
                }
                if ox + sx == nx {
                    out.push(row[sx - 1].to_f32());
                }
            }
        }
    }
    out.retain(|x| x.is_finite());
    Ok(out)
}
