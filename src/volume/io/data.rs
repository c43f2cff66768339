//! Reading voxel data for every format through one path: the memory budget is checked before
//! anything is allocated, and short or overlong data is reported with byte counts.

use std::fs::File;
use std::io::{BufRead, BufReader, ErrorKind, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use flate2::bufread::{MultiGzDecoder, ZlibDecoder};
use rayon::prelude::*;

use super::limits::physical_memory;
use crate::error::{Error, Result};
use crate::volume::voxel::decode_to;
use crate::volume::{Endian, VoxelType, dims_string};

/// How the voxel bytes are stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Encoding {
    /// Plain bytes (memory-mapped).
    Raw,
    /// A gzip stream, possibly of several members.
    Gzip,
    /// A zlib stream (MetaImage's `CompressedData`).
    Zlib,
    /// Whitespace-separated numbers (NRRD's `ascii`).
    Ascii,
}

/// Where the voxel data starts after the start offset and skipped lines.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Skip {
    /// Skip this many (decoded) bytes.
    Bytes(u64),
    /// The data is the last bytes of the file (NRRD `byte skip: -1`, MetaImage `HeaderSize = -1`).
    FromEnd,
}

/// Everything needed to read a volume's voxels from a file.
#[derive(Clone, Debug)]
pub(crate) struct DataSpec {
    /// The file holding the data.
    pub file: PathBuf,
    /// Byte offset in the file where the data section starts (e.g. the end of an attached header).
    pub start: u64,
    /// Lines to skip from `start` before the data (NRRD `line skip`).
    pub skip_lines: u64,
    /// Bytes to skip after the lines, counted in decoded bytes for compressed data.
    pub skip: Skip,
    /// Storage encoding.
    pub encoding: Encoding,
    /// Dimensions of the volume to read.
    pub dims: [usize; 3],
    /// Voxel type in the file.
    pub voxel_type: VoxelType,
    /// Byte order in the file.
    pub endian: Endian,
    /// `value * slope + intercept`, when the format scales values.
    pub scale: Option<(f64, f64)>,
    /// Which volume of how many the file holds one after the other (a 4D file): `(0, 1)` for a
    /// 3D file.
    pub volumes: (usize, usize),
}

impl DataSpec {
    /// Whether more data than the volume needs is expected (a later volume of a 4D file).
    fn allow_trailing(&self) -> bool {
        self.volumes.0 + 1 < self.volumes.1
    }

    /// The bytes (decoded) before the volume read: the skip, and the volumes before it (more
    /// than any file holds, when that overflows); `None` when the data is the file's end.
    fn skip_bytes(&self, volume_bytes: u64) -> Option<u64> {
        match self.skip {
            Skip::Bytes(n) => {
                Some(n.saturating_add((self.volumes.0 as u64).saturating_mul(volume_bytes)))
            }
            Skip::FromEnd => None,
        }
    }
}

/// The volume a reader reads of the `count` a file holds: `opts.volume`, checked, and the note
/// that says which was read.
pub(crate) fn pick_volume(
    path: &Path,
    count: usize,
    volume: usize,
    notes: &mut Vec<String>,
) -> Result<(usize, usize)> {
    if volume >= count {
        return Err(one_volume(path, count, volume));
    }
    if count > 1 {
        notes.push(format!(
            "4D file with {count} volumes: loaded volume {volume}{}",
            if volume == 0 { " (the first)" } else { "" }
        ));
    }
    Ok((volume, count))
}

/// Checks `dims` against the memory limit for an f32 volume and returns the voxel count.
pub(crate) fn check_budget(path: &Path, dims: [usize; 3], max_memory: u64) -> Result<usize> {
    if dims.contains(&0) {
        return Err(Error::format(
            path,
            format!("dimensions {} contain a zero", dims_string(dims)),
        ));
    }
    let count = dims.iter().try_fold(1usize, |a, &d| a.checked_mul(d));
    let bytes = count.and_then(|n| (n as u64).checked_mul(4));
    // A limit above this machine's memory is this machine's memory.
    let (limit, machine) = match physical_memory() {
        Some(m) if m < max_memory => (m, true),
        _ => (max_memory, false),
    };
    match (count, bytes) {
        (Some(n), Some(b)) if b <= limit => Ok(n),
        _ => Err(Error::TooLarge {
            path: path.to_path_buf(),
            what: format!(
                "a {} f32 volume{}",
                dims_string(dims),
                if machine {
                    " (more than this machine has)"
                } else {
                    ""
                }
            ),
            needed: bytes.unwrap_or(u64::MAX),
            limit,
        }),
    }
}

/// A zeroed voxel buffer of `dims`, after checking the budget; an allocation the machine cannot
/// make is an error, not an abort.
pub(crate) fn voxel_buffer(path: &Path, dims: [usize; 3], max_memory: u64) -> Result<Vec<f32>> {
    let n = check_budget(path, dims, max_memory)?;
    // Asked of the system first, so that a refusal is an error; then made zeroed, whose pages
    // the system provides only as they are written.
    let mut probe: Vec<f32> = Vec::new();
    probe.try_reserve_exact(n).map_err(|_| Error::TooLarge {
        path: path.to_path_buf(),
        what: format!("a {} f32 volume (the system refused it)", dims_string(dims)),
        needed: n as u64 * 4,
        limit: max_memory,
    })?;
    drop(probe);
    Ok(vec![0.0; n])
}

/// Reads the voxels `spec` describes, after checking the memory budget.
pub(crate) fn read_voxels(spec: &DataSpec, max_memory: u64) -> Result<Vec<f32>> {
    let count = check_budget(&spec.file, spec.dims, max_memory)?;
    let out = voxel_buffer(&spec.file, spec.dims, max_memory)?;
    let expected = count as u64 * spec.voxel_type.size() as u64;
    let path = spec.file.as_path();
    let mut file = File::open(path).map_err(|e| Error::io(path, e))?;
    let len = file.metadata().map_err(|e| Error::io(path, e))?.len();
    if spec.start > len {
        return Err(Error::format(
            path,
            format!(
                "data would start at byte {} but the file holds {len}",
                spec.start
            ),
        ));
    }
    file.seek(SeekFrom::Start(spec.start))
        .map_err(|e| Error::io(path, e))?;
    let mut reader = BufReader::new(file);
    let mut pos = spec.start;
    for line in 0..spec.skip_lines {
        // Streamed: a "line" without an end is not held in memory.
        let (n, ended) = skip_line(&mut reader).map_err(|e| Error::io(path, e))?;
        if !ended {
            return Err(Error::format(
                path,
                format!(
                    "file ends after {line} of {} lines to skip",
                    spec.skip_lines
                ),
            ));
        }
        pos += n;
    }
    match spec.encoding {
        Encoding::Raw => read_raw(spec, &reader.into_inner(), (pos, len), expected, out),
        Encoding::Gzip => read_stream(spec, MultiGzDecoder::new(reader), "gzip", expected, out),
        Encoding::Zlib => read_stream(spec, ZlibDecoder::new(reader), "zlib", expected, out),
        Encoding::Ascii => read_ascii(spec, reader, out),
    }
}

/// The buffered bytes of `reader`, filled again when empty (empty at the end), with reads that
/// a signal interrupted retried.
fn buffered(reader: &mut impl BufRead) -> std::io::Result<&[u8]> {
    loop {
        match reader.fill_buf() {
            Ok(_) => break,
            Err(e) if e.kind() == ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    // Returns what is buffered now, without reading.
    reader.fill_buf()
}

/// Skips one line of `reader`: the bytes skipped, and whether a newline ended them (else the
/// file did).
fn skip_line(reader: &mut impl BufRead) -> std::io::Result<(u64, bool)> {
    let mut skipped = 0u64;
    loop {
        let buf = buffered(reader)?;
        if buf.is_empty() {
            return Ok((skipped, false));
        }
        if let Some(i) = buf.iter().position(|&b| b == b'\n') {
            reader.consume(i + 1);
            return Ok((skipped + i as u64 + 1, true));
        }
        let n = buf.len();
        reader.consume(n);
        skipped += n as u64;
    }
}

/// Voxels decoded per parallel task.
const CHUNK: usize = 1 << 16;

fn read_raw(
    spec: &DataSpec,
    file: &File,
    (pos, len): (u64, u64),
    expected: u64,
    mut out: Vec<f32>,
) -> Result<Vec<f32>> {
    let path = spec.file.as_path();
    // Without a skip, the data (every volume of it) is the end of the file.
    let start = if let Some(n) = spec.skip_bytes(expected) {
        pos.saturating_add(n)
    } else {
        let behind = (spec.volumes.1 - spec.volumes.0) as u64;
        len.saturating_sub(expected.saturating_mul(behind)).max(pos)
    };
    let found = len.saturating_sub(start);
    if found < expected {
        return Err(Error::Truncated {
            path: path.to_path_buf(),
            expected,
            found,
        });
    }
    if found > expected && !spec.allow_trailing() {
        return Err(Error::format(
            path,
            format!(
                "header and file size disagree: a {} {} volume is {expected} bytes of data, \
                 but the file holds {found} bytes after offset {start}",
                dims_string(spec.dims),
                spec.voxel_type
            ),
        ));
    }
    let map = map_file(file).map_err(|e| Error::io(path, e))?;
    let start = usize::try_from(start).map_err(|_| Error::format(path, "offset beyond memory"))?;
    let bytes = &map[start..start + expected as usize];
    let size = spec.voxel_type.size();
    out.par_chunks_mut(CHUNK)
        .zip(bytes.par_chunks(CHUNK * size))
        .for_each(|(o, b)| decode_to(b, spec.voxel_type, spec.endian, spec.scale, o));
    Ok(out)
}

/// Maps a file read-only.
#[allow(unsafe_code)]
fn map_file(file: &File) -> std::io::Result<memmap2::Mmap> {
    // SAFETY: the map is read-only and lives only while this load decodes it. If another process
    // truncates the file meanwhile, reads may fault (SIGBUS); that is the documented price of
    // mapping, accepted because it avoids holding a second copy of a large raw volume.
    unsafe { memmap2::Mmap::map(file) }
}

fn read_stream(
    spec: &DataSpec,
    mut reader: impl Read,
    what: &str,
    expected: u64,
    mut out: Vec<f32>,
) -> Result<Vec<f32>> {
    let count = out.len();
    let path = spec.file.as_path();
    let corrupt = |e: std::io::Error, at: u64| {
        Error::format(
            path,
            format!("corrupt {what} data after {at} decoded bytes: {e}"),
        )
    };
    let Some(skip) = spec.skip_bytes(expected) else {
        return Err(Error::unsupported(
            path,
            format!("data at the end of the file (skip -1) with {what} compression"),
        ));
    };
    let skipped = std::io::copy(&mut (&mut reader).take(skip), &mut std::io::sink())
        .map_err(|e| corrupt(e, 0))?;
    if skipped < skip {
        return Err(Error::format(
            path,
            format!("{what} data ends after {skipped} bytes, before the {skip} bytes to skip"),
        ));
    }
    let size = spec.voxel_type.size();
    let mut buf = vec![0u8; (1 << 20) / size * size];
    let mut done = 0usize;
    while done < count {
        let want = (count - done).min(buf.len() / size);
        let got = fill(&mut reader, &mut buf[..want * size])
            .map_err(|e| corrupt(e, (done * size) as u64))?;
        let whole = got / size;
        decode_to(
            &buf[..whole * size],
            spec.voxel_type,
            spec.endian,
            spec.scale,
            &mut out[done..done + whole],
        );
        if got < want * size {
            return Err(Error::Truncated {
                path: path.to_path_buf(),
                expected,
                found: (done * size + got) as u64,
            });
        }
        done += whole;
    }
    if !spec.allow_trailing() {
        let mut one = [0u8; 1];
        if fill(&mut reader, &mut one).map_err(|e| corrupt(e, expected))? > 0 {
            return Err(Error::format(
                path,
                format!(
                    "header and data disagree: the {what} data holds more than the {expected} bytes \
                     of a {} {} volume",
                    dims_string(spec.dims),
                    spec.voxel_type
                ),
            ));
        }
    }
    Ok(out)
}

/// Reads until `buf` is full or the stream ends; returns the bytes read. A stream that ends inside
/// a compressed block is an end, not an error, so that the caller reports the count.
fn fill(reader: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match reader.read(&mut buf[got..]) {
            Ok(0) => break,
            Ok(n) => got += n,
            Err(e) if e.kind() == ErrorKind::Interrupted => {}
            Err(e) if e.kind() == ErrorKind::UnexpectedEof => break,
            Err(e) => return Err(e),
        }
    }
    Ok(got)
}

/// The longest token of ascii data: longer ones are not numbers slabscope reads.
const MAX_TOKEN: usize = 64;

/// Characters of a bad token an error quotes.
const QUOTED: usize = 40;

/// `token` quoted for a one-line message: at most [`QUOTED`] characters, escaped.
fn quote(token: &[u8]) -> String {
    let text = String::from_utf8_lossy(&token[..token.len().min(QUOTED)]);
    let more = if token.len() > QUOTED { "…" } else { "" };
    format!("{text:?}{more}")
}

/// The next whitespace- or comma-separated token of `reader` in `token`: `false` at the end. A
/// token longer than [`MAX_TOKEN`] stops the reading, so that no garbage is held in memory.
fn next_token(reader: &mut impl BufRead, token: &mut Vec<u8>) -> std::io::Result<bool> {
    token.clear();
    loop {
        let buf = buffered(reader)?;
        if buf.is_empty() {
            return Ok(!token.is_empty());
        }
        let separator = |b: &u8| b.is_ascii_whitespace() || *b == b',';
        let mut used = 0;
        for b in buf {
            used += 1;
            if separator(b) {
                if !token.is_empty() {
                    reader.consume(used);
                    return Ok(true);
                }
            } else {
                token.push(*b);
                if token.len() > MAX_TOKEN {
                    reader.consume(used);
                    return Ok(true);
                }
            }
        }
        reader.consume(used);
    }
}

fn read_ascii(spec: &DataSpec, mut reader: impl BufRead, mut out: Vec<f32>) -> Result<Vec<f32>> {
    let count = out.len();
    out.clear();
    let path = spec.file.as_path();
    let io = |e: std::io::Error| Error::format(path, format!("ascii data: {e}"));
    let skip = match spec.skip {
        Skip::Bytes(n) => n,
        Skip::FromEnd => return Err(Error::unsupported(path, "byte skip -1 with ascii data")),
    };
    std::io::copy(&mut (&mut reader).take(skip), &mut std::io::sink()).map_err(io)?;
    let ty = spec.voxel_type;
    let integer = !matches!(ty, VoxelType::F32 | VoxelType::F64);
    let (lo, hi) = ty.range();
    let mut token = Vec::with_capacity(MAX_TOKEN + 1);
    // The volumes before the one read.
    let before = spec.volumes.0 * count;
    for read in 0..before {
        if !next_token(&mut reader, &mut token).map_err(io)? {
            return Err(Error::format(
                path,
                format!(
                    "truncated ascii data: {read} values before volume {} of {before}",
                    spec.volumes.0
                ),
            ));
        }
    }
    while next_token(&mut reader, &mut token).map_err(io)? {
        if out.len() == count {
            if spec.allow_trailing() {
                break;
            }
            return Err(Error::format(
                path,
                format!("ascii data holds more than the {count} values the header describes"),
            ));
        }
        let bad = |why: &str| {
            Error::format(
                path,
                format!("ascii data, value {}: {} {why}", out.len(), quote(&token)),
            )
        };
        let v: f64 = std::str::from_utf8(&token)
            .ok()
            .filter(|_| token.len() <= MAX_TOKEN)
            .and_then(|t| t.parse().ok())
            .ok_or_else(|| bad("is not a number"))?;
        if integer && !(v.fract() == 0.0 && (lo..=hi).contains(&v)) {
            return Err(bad(&format!("is not a {ty} value ({lo} to {hi})")));
        }
        out.push(match spec.scale {
            Some((m, b)) => (v * m + b) as f32,
            None => v as f32,
        });
    }
    if out.len() < count {
        return Err(Error::format(
            path,
            format!(
                "truncated ascii data: expected {count} values, found {}",
                out.len()
            ),
        ));
    }
    Ok(out)
}

/// The error for volume `volume` of a file that holds `count`.
pub(crate) fn one_volume(path: &Path, count: usize, volume: usize) -> Error {
    Error::format(
        path,
        format!(
            "holds {count} volume{} (numbered from 0), so there is no volume {volume}",
            if count == 1 { "" } else { "s" }
        ),
    )
}
