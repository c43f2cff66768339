//! Summaries and answers as bytes, to travel between a cluster's tasks and its client:
//! little-endian words (a magic word and a version first), then each face's runs of labels as
//! LEB128 varints, padded with zeros to a whole word.
//!
//! A summary: `SLABBS`, a zero and the version; the volume's dims, the chunk's origin and size
//! (three words each); the face labels' count n; the six faces' byte lengths (0 for a face on
//! the volume's border); ⌈n / 64⌉ words of border bits; the faces' runs. An answer: `SLABBA`, a
//! zero and the version; dims, origin and size; n; ⌈n / 64⌉ words of background bits. A mask:
//! `SLABBM`, a zero and the version; dims, origin and size; its count; a bit a voxel of the
//! chunk, x fastest, in whole words.

use super::{Chunk, ChunkAnswer, ChunkMask, ChunkSummary, face_area};
use crate::error::{Error, Result};
use crate::measure::{Bytes, put_varint};

/// The first word of [`ChunkSummary::to_bytes`].
const SUMMARY: [u8; 8] = *b"SLABBS\x00\x01";

/// The first word of [`ChunkAnswer::to_bytes`].
const ANSWER: [u8; 8] = *b"SLABBA\x00\x01";

/// The first word of [`ChunkMask::to_bytes`].
const MASK: [u8; 8] = *b"SLABBM\x00\x01";

/// Values as runs `(value, length)`, two varints each.
pub(super) fn runs(values: impl Iterator<Item = u32>) -> Vec<u8> {
    let mut out = Vec::new();
    let mut run: Option<(u32, u64)> = None;
    for v in values {
        run = match run {
            Some((w, n)) if w == v => Some((w, n + 1)),
            Some((w, n)) => {
                put_varint(&mut out, u64::from(w));
                put_varint(&mut out, n);
                Some((v, 1))
            }
            None => Some((v, 1)),
        };
    }
    if let Some((w, n)) = run {
        put_varint(&mut out, u64::from(w));
        put_varint(&mut out, n);
    }
    out
}

/// The runs [`runs`] wrote, read back: `(value, length)`; `None` at the end or at a number
/// that does not read (longer than 64 bits, or cut short).
pub(super) struct Runs<'a> {
    bytes: Bytes<'a>,
}

impl<'a> Runs<'a> {
    pub(super) fn new(bytes: &'a [u8]) -> Self {
        Self {
            bytes: Bytes::new(bytes, "runs cut short"),
        }
    }

    /// Whether every byte was read.
    pub(super) fn done(&self) -> bool {
        self.bytes.is_done()
    }
}

impl Iterator for Runs<'_> {
    type Item = (u64, u64);

    fn next(&mut self) -> Option<(u64, u64)> {
        if self.done() {
            return None;
        }
        Some((self.bytes.varint().ok()?, self.bytes.varint().ok()?))
    }
}

fn bad(what: &str, problem: impl std::fmt::Display) -> Error {
    Error::Degenerate(format!("{what} that does not read back: {problem}"))
}

/// Words read one at a time, refusing to read past the end.
struct Words<'a> {
    bytes: &'a [u8],
    what: &'static str,
}

impl Words<'_> {
    fn next(&mut self) -> Result<u64> {
        let Some((word, rest)) = self.bytes.split_first_chunk::<8>() else {
            return Err(bad(self.what, "cut short"));
        };
        self.bytes = rest;
        Ok(u64::from_le_bytes(*word))
    }

    fn usize(&mut self) -> Result<usize> {
        let w = self.next()?;
        usize::try_from(w).map_err(|_| bad(self.what, format_args!("a size of {w}")))
    }

    fn three(&mut self) -> Result<[usize; 3]> {
        Ok([self.usize()?, self.usize()?, self.usize()?])
    }

    /// The magic word `magic`, naming another version as such, then the chunk.
    fn start(&mut self, magic: [u8; 8]) -> Result<Chunk> {
        if !self.bytes.len().is_multiple_of(8) {
            return Err(bad(self.what, "not a whole number of words"));
        }
        let m = self.next()?.to_le_bytes();
        if m[..7] == magic[..7] && m[7] != magic[7] {
            return Err(Error::Degenerate(format!(
                "{} of version {} where this slabscope reads version {}: make the parts with \
                 one version of slabscope",
                self.what, m[7], magic[7]
            )));
        }
        if m != magic {
            return Err(bad(self.what, "not one of slabscope's"));
        }
        let (dims, origin, size) = (self.three()?, self.three()?, self.three()?);
        Chunk::new(dims, origin, size).map_err(|e| bad(self.what, e))
    }

    /// `n` bits in whole words, none set past the `n`th.
    fn bits(&mut self, n: usize) -> Result<Vec<u64>> {
        let words = n.div_ceil(64);
        if words > self.bytes.len() / 8 {
            return Err(bad(self.what, "cut short"));
        }
        let bits = (0..words)
            .map(|_| self.next())
            .collect::<Result<Vec<_>>>()?;
        if !n.is_multiple_of(64) && bits.last().is_some_and(|w| w >> (n % 64) != 0) {
            return Err(bad(self.what, "a bit set past the last label"));
        }
        Ok(bits)
    }
}

fn words(out: &mut Vec<u8>, words: impl IntoIterator<Item = u64>) {
    for w in words {
        out.extend_from_slice(&w.to_le_bytes());
    }
}

fn head(out: &mut Vec<u8>, magic: [u8; 8], chunk: &Chunk) {
    words(out, [u64::from_le_bytes(magic)]);
    let [d, o, s] = [chunk.dims, chunk.origin, chunk.size];
    words(out, d.into_iter().chain(o).chain(s).map(|x| x as u64));
}

impl ChunkSummary {
    /// The summary as bytes, which [`from_bytes`](Self::from_bytes) reads back.
    #[must_use]
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::new();
        head(&mut out, SUMMARY, &self.chunk);
        words(&mut out, [u64::from(self.ids)]);
        words(&mut out, self.faces.iter().map(|f| f.len() as u64));
        words(&mut out, self.border.iter().copied());
        for f in &self.faces {
            out.extend_from_slice(f);
        }
        out.resize(out.len().next_multiple_of(8), 0);
        out
    }

    /// A summary [`to_bytes`](Self::to_bytes) wrote; an error for any other bytes (cut short,
    /// of another version, faces whose runs do not cover them or name labels it does not have).
    pub fn from_bytes(bytes: &[u8]) -> Result<Self> {
        let what = "a background chunk summary";
        let mut w = Words { bytes, what };
        let chunk = w.start(SUMMARY)?;
        let ids = w.next()?;
        let lens = [0; 6].map(|_| w.usize());
        let mut faces_len = 0usize;
        for (f, len) in lens.iter().enumerate() {
            let len = *len.as_ref().map_err(|_| bad(what, "cut short"))?;
            if (len > 0) != chunk.inner(f) {
                return Err(bad(what, format_args!("face {f} given where it lies")));
            }
            faces_len = faces_len.saturating_add(len);
        }
        // Every face label is on a face, in a run of two bytes at least.
        let ids = u32::try_from(ids)
            .ok()
            .filter(|&n| n as usize <= faces_len / 2)
            .ok_or_else(|| bad(what, format_args!("{ids} face labels on its faces")))?;
        let border = w.bits(ids as usize)?;
        let rest = w.bytes;
        if faces_len > rest.len() || rest.len() - faces_len >= 8 {
            return Err(bad(what, "its faces are not the length written"));
        }
        if rest[faces_len..].iter().any(|&b| b != 0) {
            return Err(bad(what, "bytes after its faces"));
        }
        let mut seen = vec![0u64; (ids as usize).div_ceil(64)];
        let mut at = 0;
        let mut faces: [Vec<u8>; 6] = Default::default();
        for (f, len) in lens.into_iter().enumerate() {
            let len = len?;
            let face = &rest[at..at + len];
            at += len;
            check_face(face, face_area(chunk.size, f), ids, &mut seen)
                .map_err(|p| bad(what, format_args!("face {f}: {p}")))?;
            faces[f] = face.to_vec();
        }
        if seen.iter().map(|w| w.count_ones()).sum::<u32>() != ids {
            return Err(bad(what, "a face label on none of its faces"));
        }
        Ok(Self {
            chunk,
            ids,
            border,
            faces,
        })
    }
}

/// Whether the runs `face` cover `area` voxels exactly with labels up to `ids`, marking in
/// `seen` the face labels met; a face on the volume's border (no bytes) passes.
fn check_face(face: &[u8], area: usize, ids: u32, seen: &mut [u64]) -> Result<(), String> {
    if face.is_empty() {
        return Ok(());
    }
    let mut runs = Runs::new(face);
    let mut covered = 0u64;
    for (v, n) in runs.by_ref() {
        if v > u64::from(ids) {
            return Err(format!("a label {v} of {ids}"));
        }
        if n == 0 {
            return Err("a run of no voxel".into());
        }
        covered = covered.saturating_add(n);
        if covered > area as u64 {
            return Err(format!("runs past its {area} voxels"));
        }
        if v > 0 {
            seen[(v as usize - 1) / 64] |= 1 << ((v - 1) % 64);
        }
    }
    if !runs.done() {
        return Err("a number that does not read".into());
    }
    if covered != area as u64 {
        return Err(format!("runs of {covered} of its {area} voxels"));
    }
    Ok(())
}

impl ChunkAnswer {
    /// The answer as bytes, which [`from_bytes`](Self::from_bytes) reads back.
    #[must_use]
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::new();
        head(&mut out, ANSWER, &self.chunk);
        words(&mut out, [u64::from(self.ids)]);
        words(&mut out, self.background.iter().copied());
        out
    }

    /// An answer [`to_bytes`](Self::to_bytes) wrote; an error for any other bytes.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self> {
        let what = "a background chunk answer";
        let mut w = Words { bytes, what };
        let chunk = w.start(ANSWER)?;
        let ids = w.next()?;
        let ids = u32::try_from(ids).map_err(|_| bad(what, format_args!("{ids} labels")))?;
        let background = w.bits(ids as usize)?;
        if !w.bytes.is_empty() {
            return Err(bad(what, "bytes after its labels"));
        }
        Ok(Self {
            chunk,
            ids,
            background,
        })
    }
}

impl ChunkMask {
    /// The chunk's bits as bytes, which [`from_bytes`](Self::from_bytes) reads back.
    #[must_use]
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::new();
        head(&mut out, MASK, &self.chunk);
        words(&mut out, [self.count as u64]);
        words(&mut out, self.words.iter().copied());
        out
    }

    /// A chunk's bits [`to_bytes`](Self::to_bytes) wrote; an error for any other bytes (their
    /// count not the bits set among them).
    pub fn from_bytes(bytes: &[u8]) -> Result<Self> {
        let what = "a background chunk mask";
        let mut w = Words { bytes, what };
        let chunk = w.start(MASK)?;
        let count = w.next()?;
        let words = w.bits(chunk.len())?;
        if !w.bytes.is_empty() {
            return Err(bad(what, "bytes after its bits"));
        }
        let set: u64 = words.iter().map(|w| u64::from(w.count_ones())).sum();
        if set != count {
            return Err(bad(what, format_args!("a count of {count} for {set} bits")));
        }
        Ok(Self {
            chunk,
            words,
            count: set as usize,
        })
    }
}
