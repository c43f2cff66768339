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
/// label (4 bytes) a voxel of the chunk and, while labelling, 12 bytes a run of voxels at or
/// below the threshold along x (far fewer runs than voxels unless the voxels alternate);
/// nothing of the whole volume's size.
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
    /// against a budget before labelling: a label a voxel, and while labelling 12 bytes a run
    /// of voxels at or below the threshold along x (a run every other voxel of a row at most)
    /// and 4 a row, then a label's face label and border bit for as many labels as runs.
    #[must_use]
    pub fn most_bytes(chunk: &Chunk) -> u64 {
        let [sx, sy, sz] = chunk.size.map(|d| d as u64);
        let runs = sy * sz * sx.div_ceil(2) + 1;
        4 * chunk.len() as u64 + 12 * runs + 4 * (sy * sz + 1) + runs.div_ceil(64) * 8
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

/// The components of `voxels` (x fastest, `size`) at or below `t`, 6-connected, labelled 1, 2,
/// … in the order of their first voxel, and their number. By runs: the voxels at or below `t`
/// of each row along x as runs, in the order of the rows; a run joined (union-find, each root
/// the component's first run) to the runs it overlaps in the row before it along y and along
/// z; the components numbered in the order of their first runs, whose first voxels are theirs.
/// Work and memory a run, not a voxel, besides the labels: 12 bytes a run and 4 a row
/// ([`ChunkLabels::most_bytes`]).
fn label<T: Voxel>(voxels: &[T], size: [usize; 3], t: f32) -> (Vec<u32>, u32) {
    let [sx, sy, sz] = size;
    let rows = sy * sz;
    // Each run's first and end x; the first run of each row (and the end of the last). The
    // chunk holds fewer than 2^32 voxels (`find` checked), so fewer runs.
    let mut runs: Vec<(u32, u32)> = Vec::new();
    let mut first: Vec<u32> = Vec::with_capacity(rows + 1);
    for r in 0..rows {
        first.push(runs.len() as u32);
        let row = &voxels[r * sx..(r + 1) * sx];
        let mut x = 0;
        while x < sx {
            if row[x].to_f32() <= t {
                let start = x;
                while x < sx && row[x].to_f32() <= t {
                    x += 1;
                }
                runs.push((start as u32, x as u32));
            }
            x += 1;
        }
    }
    first.push(runs.len() as u32);
    let of_row = |r: usize| first[r] as usize..first[r + 1] as usize;
    let mut parent: Vec<u32> = (0..runs.len() as u32).collect();
    for r in 0..rows {
        let (y, z) = (r % sy, r / sy);
        for before in [(y > 0).then(|| r - 1), (z > 0).then(|| r - sy)]
            .into_iter()
            .flatten()
        {
            join_overlapping(&runs, &mut parent, of_row(r), of_row(before));
        }
    }
    // Numbered in the order of first runs, in place: a run's parent comes before it (a root
    // is its component's first run, and a path only ever points back), so it is numbered
    // already when the run is reached, with its component's number.
    let mut n = 0;
    for i in 0..parent.len() {
        let p = parent[i] as usize;
        parent[i] = if p == i {
            n += 1;
            n
        } else {
            parent[p]
        };
    }
    let mut labels = vec![0u32; voxels.len()];
    for r in 0..rows {
        for i in of_row(r) {
            let (a, b) = runs[i];
            labels[r * sx + a as usize..r * sx + b as usize].fill(parent[i]);
        }
    }
    (labels, n)
}

/// Joins each run of `here` to the runs of `before` (the row before it, along y or z) it
/// overlaps along x: both in order of x, walked together.
fn join_overlapping(
    runs: &[(u32, u32)],
    parent: &mut [u32],
    here: std::ops::Range<usize>,
    before: std::ops::Range<usize>,
) {
    let (mut i, mut j) = (here.start, before.start);
    while i < here.end && j < before.end {
        let ((a0, a1), (b0, b1)) = (runs[i], runs[j]);
        if a0 < b1 && b0 < a1 {
            union(parent, i as u32, j as u32);
        }
        if a1 <= b1 {
            i += 1;
        } else {
            j += 1;
        }
    }
}

/// The root of `i`'s set, halving the path to it.
fn find(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        let up = parent[parent[i as usize] as usize];
        parent[i as usize] = up;
        i = up;
    }
    i
}

/// Joins the sets of `a` and `b`, the root the smaller: a component's root is its first run.
fn union(parent: &mut [u32], a: u32, b: u32) {
    let (a, b) = (find(parent, a), find(parent, b));
    if a != b {
        parent[a.max(b) as usize] = a.min(b);
    }
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

#[cfg(test)]
mod tests {
    use super::label;

    /// The labels by a depth-first fill from each voxel not labelled yet, in linear order: the
    /// definition the runs' labelling keeps.
    fn filled(v: &[f32], size: [usize; 3], t: f32) -> (Vec<u32>, u32) {
        let [sx, sy, sz] = size;
        let mut labels = vec![0u32; v.len()];
        let mut n = 0;
        for start in 0..v.len() {
            if labels[start] != 0 || v[start] > t || v[start].is_nan() {
                continue;
            }
            n += 1;
            labels[start] = n;
            let mut stack = vec![start];
            while let Some(j) = stack.pop() {
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
                    if labels[k] == 0 && v[k] <= t {
                        labels[k] = n;
                        stack.push(k);
                    }
                }
            }
        }
        (labels, n)
    }

    #[test]
    fn runs_label_as_the_fill_does_numbered_by_first_voxel() {
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let mut next = |n: u64| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state % n
        };
        let mut components = 0;
        for case in 0..300 {
            let size = [
                1 + next(9) as usize,
                1 + next(9) as usize,
                1 + next(9) as usize,
            ];
            let len = size.iter().product();
            // Sparse to dense voxels at or below the threshold, so that components wind, meet
            // late (a U whose arms join in a later row) and stay apart; a voxel missing.
            let dense = next(10);
            let mut v: Vec<f32> = (0..len).map(|_| (next(10) >= dense) as u8 as f32).collect();
            if case % 7 == 0 {
                v[next(len as u64) as usize] = f32::NAN;
            }
            let got = label(&v, size, 0.5);
            assert_eq!(got, filled(&v, size, 0.5), "{size:?} {v:?}");
            components += got.1;
        }
        assert!(components > 1000, "{components}");
        // A U whose arms are runs apart until its last row joins them: one component.
        let size = [5, 3, 1];
        #[rustfmt::skip]
        let v = [
            0.0, 1.0, 1.0, 1.0, 0.0,
            0.0, 1.0, 0.0, 1.0, 0.0,
            0.0, 0.0, 0.0, 0.0, 0.0,
        ];
        let (labels, n) = label(&v, size, 0.5);
        assert_eq!(n, 1);
        assert!(
            labels
                .iter()
                .enumerate()
                .all(|(i, &l)| l == u32::from(v[i] <= 0.5))
        );
    }
}
