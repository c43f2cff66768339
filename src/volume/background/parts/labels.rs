//! A task's side: the components of its chunk's voxels at or below the threshold, the summary
//! it sends, the answer it gets and the mask bits it makes from them.

use super::{Chunk, face_indices};
use crate::error::{Error, Result};
use crate::volume::Voxel;

/// No face label: a label on none of the chunk's inner faces.
const NONE: u32 = u32::MAX;

fn bit(words: &[u64], i: usize) -> bool {
    words[i / 64] >> (i % 64) & 1 == 1
}

fn set(words: &mut [u64], i: usize) {
    words[i / 64] |= 1 << (i % 64);
}

/// The components (6-neighbours) of a chunk's voxels at or below a threshold. It holds a
/// label (4 bytes) a voxel of the chunk and, while labelling, a stack of at most as many more
/// (far fewer unless the components wind through most of the chunk); nothing of the whole
/// volume's size.
#[derive(Clone, Debug)]
pub struct ChunkLabels {
    chunk: Chunk,
    /// A voxel's label: 0 above the threshold (or missing), else 1 to the number of labels.
    labels: Vec<u32>,
    /// A label's face label (its index among the labels on the chunk's inner faces, in order
    /// of the faces and their voxels), or [`NONE`]; index 0 unused.
    face: Vec<u32>,
    /// The face labels' count.
    faces: u32,
    /// A bit a label: whether it holds a voxel on the volume's border.
    border: Vec<u64>,
}

/// What a task sends the client: its chunk's labels on the chunk's inner faces (the faces
/// another chunk lies beyond), run-length coded, and which of them touch the volume's border.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ChunkSummary {
    pub(super) chunk: Chunk,
    /// The face labels' count.
    pub(super) ids: u32,
    /// A bit a face label: whether it touches the volume's border.
    pub(super) border: Vec<u64>,
    /// Each face's labels (0 for a voxel above the threshold, else its face label + 1) in face
    /// order, as runs `(label, length)` of two LEB128 varints; empty for a face on the
    /// volume's border.
    pub(super) faces: [Vec<u8>; 6],
}

/// The client's answer to a chunk: which of its face labels are background (joined to a
/// component touching the volume's border, in any chunk).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ChunkAnswer {
    pub(super) chunk: Chunk,
    pub(super) ids: u32,
    /// A bit a face label.
    pub(super) background: Vec<u64>,
}

/// A chunk's bits of the background's mask, a bit a voxel of the chunk (x fastest), with their
/// count.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ChunkMask {
    pub(super) chunk: Chunk,
    pub(super) words: Vec<u64>,
    pub(super) count: usize,
}

impl ChunkLabels {
    /// The components of `voxels` (the chunk's, x fastest) at or below `t` (a missing voxel is
    /// not), labelled in the order of their first voxel. Reads no voxel outside the chunk; an
    /// error when `voxels` are not the chunk's or the chunk holds 2^32 voxels or more.
    pub fn find<T: Voxel>(voxels: &[T], chunk: &Chunk, t: f32) -> Result<Self> {
        chunk.check_voxels(voxels.len())?;
        if u32::try_from(voxels.len()).is_err() {
            return Err(Error::invalid(
                "chunk",
                format!("of {:?} voxels", chunk.size),
                "fewer than 2^32 voxels",
            ));
        }
        let (labels, n) = label(voxels, chunk.size, t);
        let mut border = vec![0u64; (n as usize + 1).div_ceil(64)];
        let mut face = vec![NONE; n as usize + 1];
        let mut faces = 0u32;
        for f in 0..6 {
            for i in face_indices(chunk.size, f) {
                let l = labels[i] as usize;
                if l == 0 {
                    continue;
                }
                if !chunk.inner(f) {
                    set(&mut border, l);
                } else if face[l] == NONE {
                    face[l] = faces;
                    faces += 1;
                }
            }
        }
        Ok(Self {
            chunk: *chunk,
            labels,
            face,
            faces,
            border,
        })
    }

    /// The chunk.
    #[must_use]
    pub fn chunk(&self) -> &Chunk {
        &self.chunk
    }

    /// The number of components.
    #[must_use]
    pub fn count(&self) -> usize {
        self.face.len() - 1
    }

    /// The bytes it holds.
    #[must_use]
    pub fn memory_bytes(&self) -> u64 {
        4 * (self.labels.len() + self.face.len()) as u64 + 8 * self.border.len() as u64
    }

    /// The most bytes [`find`](Self::find) can hold for `chunk`, besides its voxels, to weigh
    /// against a budget before labelling: a label a voxel, the stack's as many at most, and a
    /// label's face label and border bit for as many labels as voxels.
    #[must_use]
    pub fn most_bytes(chunk: &Chunk) -> u64 {
        let n = chunk.len() as u64 + 1;
        12 * n + n.div_ceil(64) * 8
    }

    /// The summary the client joins.
    #[must_use]
    pub fn summary(&self) -> ChunkSummary {
        let mut border = vec![0u64; (self.faces as usize).div_ceil(64)];
        for (l, &f) in self.face.iter().enumerate() {
            if f != NONE && bit(&self.border, l) {
                set(&mut border, f as usize);
            }
        }
        let faces = std::array::from_fn(|f| {
            if !self.chunk.inner(f) {
                return Vec::new();
            }
            super::bytes::runs(face_indices(self.chunk.size, f).map(|i| {
                let l = self.labels[i] as usize;
                if l == 0 { 0 } else { self.face[l] + 1 }
            }))
        });
        ChunkSummary {
            chunk: self.chunk,
            ids: self.faces,
            border,
            faces,
        }
    }

    /// The chunk's bits of the background's mask: the voxels of the labels that touch the
    /// volume's border or that `answer` says are background. An error when `answer` is
    /// another chunk's.
    pub fn mask(&self, answer: &ChunkAnswer) -> Result<ChunkMask> {
        if answer.chunk != self.chunk || answer.ids != self.faces {
            return Err(Error::Degenerate(format!(
                "a background answer for the chunk of {:?} at {:?} ({} face labels) given to the \
                 chunk of {:?} at {:?} ({} face labels)",
                answer.chunk.size,
                answer.chunk.origin,
                answer.ids,
                self.chunk.size,
                self.chunk.origin,
                self.faces
            )));
        }
        let background: Vec<bool> = (0..self.face.len())
            .map(|l| {
                l > 0
                    && (bit(&self.border, l)
                        || (self.face[l] != NONE && bit(&answer.background, self.face[l] as usize)))
            })
            .collect();
        let mut words = vec![0u64; self.labels.len().div_ceil(64)];
        let mut count = 0;
        for (i, &l) in self.labels.iter().enumerate() {
            if background[l as usize] {
                set(&mut words, i);
                count += 1;
            }
        }
        Ok(ChunkMask {
            chunk: self.chunk,
            words,
            count,
        })
    }
}

/// The labels of the voxels of a box of `size` at or below `t`: a depth-first fill from each
/// voxel not labelled yet, in linear order; with the number of labels.
fn label<T: Voxel>(voxels: &[T], size: [usize; 3], t: f32) -> (Vec<u32>, u32) {
    let [sx, sy, sz] = size;
    let below = |i: usize| voxels[i].to_f32() <= t;
    let mut labels = vec![0u32; voxels.len()];
    let mut stack: Vec<u32> = Vec::new();
    let mut n = 0;
    for start in 0..voxels.len() {
        if labels[start] != 0 || !below(start) {
            continue;
        }
        n += 1;
        labels[start] = n;
        // The chunk holds fewer than 2^32 voxels (`find` checked).
        stack.push(start as u32);
        while let Some(j) = stack.pop() {
            let j = j as usize;
            let (x, y, z) = (j % sx, (j / sx) % sy, j / (sx * sy));
            let steps = [
                (x > 0).then(|| j - 1),
                (x + 1 < sx).then(|| j + 1),
                (y > 0).then(|| j - sx),
                (y + 1 < sy).then(|| j + sx),
                (z > 0).then(|| j - sx * sy),
                (z + 1 < sz).then(|| j + sx * sy),
            ];
            for k in steps.into_iter().flatten() {
                if labels[k] == 0 && below(k) {
                    labels[k] = n;
                    stack.push(k as u32);
                }
            }
        }
    }
    (labels, n)
}

impl ChunkSummary {
    /// The chunk.
    #[must_use]
    pub fn chunk(&self) -> &Chunk {
        &self.chunk
    }

    /// The bytes it holds.
    #[must_use]
    pub fn memory_bytes(&self) -> u64 {
        (8 * self.border.len() + self.faces.iter().map(Vec::len).sum::<usize>()) as u64
    }
}

impl ChunkAnswer {
    /// The chunk it answers.
    #[must_use]
    pub fn chunk(&self) -> &Chunk {
        &self.chunk
    }
}

impl ChunkMask {
    /// The chunk.
    #[must_use]
    pub fn chunk(&self) -> &Chunk {
        &self.chunk
    }

    /// The chunk's background voxels.
    #[must_use]
    pub fn count(&self) -> usize {
        self.count
    }

    /// Whether the chunk's voxel at its own linear index `i` (x fastest) is background.
    #[must_use]
    pub fn contains(&self, i: usize) -> bool {
        bit(&self.words, i)
    }

    /// Writes the chunk's bits into the whole volume's mask `words` (a bit a voxel, a word per
    /// 64, by linear index x fastest) at the chunk's own voxels, leaving every other bit as it
    /// is. An error when `words` are not a word per 64 of the volume's voxels.
    pub fn write_into(&self, words: &mut [u64]) -> Result<()> {
        let [nx, ny, _] = self.chunk.dims;
        let len = self.chunk.dims.iter().product::<usize>();
        if words.len() != len.div_ceil(64) {
            return Err(Error::invalid(
                "background mask",
                format!("{} words", words.len()),
                format!("{} words, one per 64 of the {len} voxels", len.div_ceil(64)),
            ));
        }
        let [ox, oy, oz] = self.chunk.origin;
        let [sx, sy, sz] = self.chunk.size;
        for z in 0..sz {
            for y in 0..sy {
                let local = (z * sy + y) * sx;
                let whole = ox + nx * (oy + y + ny * (oz + z));
                for x in 0..sx {
                    let g = whole + x;
                    let b = u64::from(bit(&self.words, local + x));
                    words[g / 64] = words[g / 64] & !(1 << (g % 64)) | b << (g % 64);
                }
            }
        }
        Ok(())
    }
}
