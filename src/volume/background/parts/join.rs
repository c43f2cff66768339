//! The client's side: the chunks' summaries joined into the components of the whole volume, and
//! each chunk's answer.
//!
//! What it holds: a union-find of the face labels of every chunk added (4 bytes a label, and a
//! bit whether its component touches the volume's border), a few words a chunk, and the faces
//! (their runs of labels as bytes, as they travel) of the chunks whose neighbour beyond them
//! has not come yet: a face is joined and dropped as soon as both its sides are in. Nothing a
//! voxel: at 2048³ in chunks of 64³ (32,768 chunks), a volume whose chunks' faces hold a few
//! runs each holds a few MiB, where a label a face voxel would be 3 GiB.

use std::collections::{BTreeSet, HashMap, HashSet};

use super::bytes::Runs;
use super::{Chunk, ChunkAnswer, ChunkSummary, across};
use crate::error::{Error, Result};

/// A chunk added: its first face label's index in the union-find, and its count.
#[derive(Clone, Copy, Debug)]
struct Joined {
    chunk: Chunk,
    offset: u32,
    ids: u32,
}

/// A face waiting for the chunk beyond it.
#[derive(Debug)]
struct Waiting {
    chunk: usize,
    high: bool,
    runs: Vec<u8>,
}

/// The join of the chunks' summaries, on the client: [`add`](Self::add) each chunk's, in any
/// order, then [`finish`](Self::finish) for every chunk's answer.
#[derive(Debug)]
pub struct BackgroundJoin {
    dims: [usize; 3],
    chunks: Vec<Joined>,
    origins: HashSet<[usize; 3]>,
    /// The union-find's parents, a face label of any chunk each.
    parent: Vec<u32>,
    /// A bit a face label: whether its component touches the border (kept at the roots).
    border: Vec<u64>,
    /// The faces waiting, by their axis and corner ([`Chunk::face_corner`]).
    waiting: HashMap<(usize, [usize; 3]), Waiting>,
}

fn broken(problem: impl std::fmt::Display) -> Error {
    Error::Degenerate(format!(
        "the background's chunks do not make the volume: {problem}"
    ))
}

impl BackgroundJoin {
    /// A join for a volume of dimensions `dims`.
    #[must_use]
    pub fn new(dims: [usize; 3]) -> Self {
        Self {
            dims,
            chunks: Vec::new(),
            origins: HashSet::new(),
            parent: Vec::new(),
            border: Vec::new(),
            waiting: HashMap::new(),
        }
    }

    /// The bytes it holds: the union-find, the chunks and the faces waiting.
    #[must_use]
    pub fn memory_bytes(&self) -> u64 {
        let waiting: usize = self.waiting.values().map(|w| w.runs.len() + 64).sum();
        (4 * self.parent.len() + 8 * self.border.len() + 96 * self.chunks.len() + waiting) as u64
    }

    /// Adds a chunk's summary, joining its faces to those of the chunks beyond them already
    /// added. An error when it is another volume's, a chunk added already, or its faces do not
    /// meet its neighbours' whole (the chunks are not a grid).
    pub fn add(&mut self, summary: ChunkSummary) -> Result<()> {
        let c = summary.chunk;
        if c.dims != self.dims {
            return Err(broken(format_args!(
                "a chunk of a volume of {:?} joined to one of {:?}",
                c.dims, self.dims
            )));
        }
        if !self.origins.insert(c.origin) {
            return Err(broken(format_args!("two chunks at {:?}", c.origin)));
        }
        let offset = u32::try_from(self.parent.len()).ok();
        let end = offset.and_then(|o| o.checked_add(summary.ids));
        let (Some(offset), Some(end)) = (offset, end.filter(|&e| e < u32::MAX)) else {
            return Err(broken("more than 2^32 face labels"));
        };
        self.parent.extend(offset..end);
        self.border.resize((end as usize).div_ceil(64), 0);
        for id in 0..summary.ids as usize {
            if summary.border[id / 64] >> (id % 64) & 1 == 1 {
                let g = offset as usize + id;
                self.border[g / 64] |= 1 << (g % 64);
            }
        }
        let index = self.chunks.len();
        self.chunks.push(Joined {
            chunk: c,
            offset,
            ids: summary.ids,
        });
        for (f, runs) in summary.faces.into_iter().enumerate() {
            if !runs.is_empty() {
                self.meet(index, f, runs)?;
            }
        }
        Ok(())
    }

    /// Face `f` of chunk `index`, its runs `runs`: joined to the face beyond it if that one
    /// waits, else waiting for it.
    fn meet(&mut self, index: usize, f: usize, runs: Vec<u8>) -> Result<()> {
        let c = self.chunks[index].chunk;
        let key = (f / 2, c.face_corner(f));
        let high = f % 2 == 1;
        let Some(other) = self.waiting.remove(&key) else {
            self.waiting.insert(
                key,
                Waiting {
                    chunk: index,
                    high,
                    runs,
                },
            );
            return Ok(());
        };
        let o = self.chunks[other.chunk];
        let (u, v) = across(f);
        if other.high == high || o.chunk.size[u] != c.size[u] || o.chunk.size[v] != c.size[v] {
            return Err(broken(format_args!(
                "the chunk of {:?} at {:?} meets the one of {:?} at {:?} on part of a face",
                c.size, c.origin, o.chunk.size, o.chunk.origin
            )));
        }
        self.join_faces((self.chunks[index].offset, &runs), (o.offset, &other.runs))
    }

    /// Joins the labels that meet across a face: the runs of its two sides, each with its
    /// chunk's first face label.
    fn join_faces(&mut self, (a_at, a): (u32, &[u8]), (b_at, b): (u32, &[u8])) -> Result<()> {
        let (mut ra, mut rb) = (Runs::new(a), Runs::new(b));
        let ((mut va, mut na), (mut vb, mut nb)) = ((0, 0), (0, 0));
        loop {
            if na == 0 {
                let Some(r) = ra.next() else { break };
                (va, na) = r;
            }
            if nb == 0 {
                (vb, nb) = rb.next().ok_or_else(|| broken("faces of unequal runs"))?;
            }
            let step = na.min(nb);
            if va > 0 && vb > 0 {
                // Labels below the chunk's count, which `add` checked fit.
                self.union(a_at + va as u32 - 1, b_at + vb as u32 - 1);
            }
            na -= step;
            nb -= step;
        }
        if nb != 0 || rb.next().is_some() {
            return Err(broken("faces of unequal runs"));
        }
        Ok(())
    }

    fn root(&mut self, mut x: u32) -> u32 {
        while self.parent[x as usize] != x {
            let up = self.parent[self.parent[x as usize] as usize];
            self.parent[x as usize] = up;
            x = up;
        }
        x
    }

    fn touches(&self, x: u32) -> bool {
        self.border[x as usize / 64] >> (x % 64) & 1 == 1
    }

    fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.root(a), self.root(b));
        if ra == rb {
            return;
        }
        let (low, high) = (ra.min(rb), ra.max(rb));
        self.parent[high as usize] = low;
        if self.touches(high) {
            self.border[low as usize / 64] |= 1 << (low % 64);
        }
    }

    /// Every chunk's answer, in the order they were added. An error when a chunk is missing,
    /// or the chunks are not a grid of the whole volume (each a cell between consecutive cuts
    /// along each axis, every cell one chunk).
    pub fn finish(mut self) -> Result<Vec<ChunkAnswer>> {
        if let Some(w) = self.waiting.values().next() {
            let c = self.chunks[w.chunk].chunk;
            return Err(broken(format_args!(
                "no chunk beyond a face of the chunk of {:?} at {:?}",
                c.size, c.origin
            )));
        }
        self.check_grid()?;
        let mut answers = Vec::with_capacity(self.chunks.len());
        for j in std::mem::take(&mut self.chunks) {
            let mut background = vec![0u64; (j.ids as usize).div_ceil(64)];
            for id in 0..j.ids {
                let r = self.root(j.offset + id);
                if self.touches(r) {
                    background[id as usize / 64] |= 1 << (id % 64);
                }
            }
            answers.push(ChunkAnswer {
                chunk: j.chunk,
                ids: j.ids,
                background,
            });
        }
        Ok(answers)
    }

    /// An error unless the chunks are the cells of a grid of the volume, every cell once.
    fn check_grid(&self) -> Result<()> {
        let mut cells = 1usize;
        for a in 0..3 {
            let cuts: BTreeSet<usize> = self
                .chunks
                .iter()
                .map(|j| j.chunk.origin[a])
                .chain([0, self.dims[a]])
                .collect();
            for j in &self.chunks {
                let (o, s) = (j.chunk.origin[a], j.chunk.size[a]);
                if cuts.range(o + 1..).next() != Some(&(o + s)) {
                    return Err(broken(format_args!(
                        "the chunk of {:?} at {:?} crosses another's start",
                        j.chunk.size, j.chunk.origin
                    )));
                }
            }
            cells = cells.saturating_mul(cuts.len() - 1);
        }
        if cells != self.chunks.len() {
            return Err(broken(format_args!(
                "{} chunks where their grid has {cells} cells: a chunk is missing",
                self.chunks.len()
            )));
        }
        Ok(())
    }
}
