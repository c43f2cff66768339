//! Reading voxel data for every format through one path: the memory budget is checked before
//! anything is allocated, and short or overlong data is reported with byte counts.

use std::fs::File;
use std::io::{BufRead, BufReader, ErrorKind, Read, Seek, SeekFrom};
use std::path::Path;

use flate2::bufread::{MultiGzDecoder, ZlibDecoder};
use rayon::prelude::*;

pub(crate) mod ascii;
pub(crate) mod budget;
pub(crate) mod wide;

use self::ascii::read_ascii;
use self::budget::voxel_count;
pub(crate) use self::budget::{check_budget, typed_buffer, voxel_buffer};
use self::wide::Rounded;
use super::Source;
use super::scratch::{Room, VoxelOut};
use crate::error::{Error, Result};
use crate::volume::decode_to;
use crate::volume::mapped;
use crate::volume::voxels::{held_type, infinities_missing};
use crate::volume::{Endian, Voxel, VoxelType, Voxels, dims_string};

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
    /// The source holding the data (the header's own, or the data file it names).
    pub file: Source,
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
    /// Whether bytes may follow the values (a writer's closing newline).
    pub trailing: bool,
}

impl DataSpec {
    /// Whether more data than the volume needs is expected (a later volume of a 4D file, or
    /// bytes the format allows after the values).
    fn allow_trailing(&self) -> bool {
        self.trailing || self.volumes.0 + 1 < self.volumes.1
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

/// The volume a reader reads of the `count` a file holds: `opts.part.volume`, checked, and the note
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

/// Voxel types that file bytes decode into: f32 from any type (scaled as the file says), and
/// each integer type of at most 16 bits from itself, unscaled.
trait Decode: Voxel {
    /// Decodes the voxels of `bytes` (exactly `out.len()` of them) into `out`: the integers an
    /// f32 does not hold exactly, counted.
    fn decode(bytes: &[u8], spec: &DataSpec, out: &mut [Self]) -> Rounded;
}

impl Decode for f32 {
    fn decode(bytes: &[u8], spec: &DataSpec, out: &mut [f32]) -> Rounded {
        decode_to(bytes, spec.voxel_type, spec.endian, spec.scale, out);
        // Infinities (in the file, or from scaling) are missing voxels.
        infinities_missing(out);
        // Scaled values are the scale's to round, not the integers'.
        if spec.scale.is_some() {
            return Rounded::default();
        }
        Rounded::of_bytes(bytes, spec.voxel_type, spec.endian)
    }
}

macro_rules! decode_as_stored {
    ($($t:ty),*) => {$(
        impl Decode for $t {
            fn decode(bytes: &[u8], spec: &DataSpec, out: &mut [$t]) -> Rounded {
                debug_assert!(spec.voxel_type == <$t>::TYPE && spec.scale.is_none());
                let to: &mut [u8] = bytemuck::cast_slice_mut(out);
                to.copy_from_slice(bytes);
                if spec.endian != Endian::NATIVE {
                    to.chunks_exact_mut(std::mem::size_of::<$t>()).for_each(<[u8]>::reverse);
                }
                Rounded::default()
            }
        }
    )*};
}

decode_as_stored!(u8, i8, u16, i16);

/// Reads the voxels `spec` describes, after checking the memory budget: integers of at most 16
/// bits that the file does not scale in their own type, everything else as f32, with the
/// 32-bit integers an f32 does not hold exactly counted (the reader notes them).
pub(crate) fn read_voxels(spec: &DataSpec, room: Room) -> Result<(Voxels, Rounded)> {
    read_voxels_in(spec, None, room)
}

/// [`read_voxels`] from `stream`, the voxel bytes (or, for [`Encoding::Ascii`], the text) a
/// reader has decoded itself (a VTK XML array's base64 or zlib blocks) rather than `spec`'s
/// file at `spec.start`; `what` names the stream in messages.
pub(crate) fn read_voxels_from(
    spec: &DataSpec,
    stream: &mut dyn BufRead,
    what: &'static str,
    room: Room,
) -> Result<(Voxels, Rounded)> {
    read_voxels_in(spec, Some((stream, what)), room)
}

/// A stream of voxel bytes a reader decoded, and its name in messages.
type Stream<'a> = Option<(&'a mut dyn BufRead, &'static str)>;

fn read_voxels_in(spec: &DataSpec, stream: Stream, room: Room) -> Result<(Voxels, Rounded)> {
    let held = if spec.encoding == Encoding::Ascii {
        VoxelType::F32
    } else {
        held_type(spec.voxel_type, spec.scale.is_some())
    };
    match held {
        VoxelType::U8 => read_typed::<u8>(spec, stream, room),
        VoxelType::I8 => read_typed::<i8>(spec, stream, room),
        VoxelType::U16 => read_typed::<u16>(spec, stream, room),
        VoxelType::I16 => read_typed::<i16>(spec, stream, room),
        _ => read_typed::<f32>(spec, stream, room),
    }
}

/// [`read_voxels`] into voxels of type `T`. The budget is checked when the voxels are decoded
/// into memory, not where they are mapped: mapped file pages are the kernel's to drop, and what
/// an analysis of them needs is weighed by the analysis (`analysis::level_within_memory`).
fn read_typed<T: Decode>(spec: &DataSpec, stream: Stream, room: Room) -> Result<(Voxels, Rounded)> {
    let max_memory = room.max_memory;
    let expected = voxel_count(spec.file.path(), spec.dims)?
        .and_then(|n| (n as u64).checked_mul(spec.voxel_type.size() as u64))
        .ok_or_else(|| {
            Error::format(
                spec.file.path(),
                format!(
                    "a {} volume has more voxels than this machine can address",
                    dims_string(spec.dims)
                ),
            )
        })?;
    let path = spec.file.path();
    // Decoded voxels beyond the budget go to a scratch file (`scratch.rs`).
    let out = || {
        VoxelOut::new(path, spec.dims, room.scratch, || {
            typed_buffer::<T>(path, spec.dims, max_memory)
        })
    };
    if let Some((stream, what)) = stream {
        return if spec.encoding == Encoding::Ascii {
            // Within the budget: how many values a compressed text holds is not known before.
            let memory = Room {
                scratch: None,
                ..room
            };
            ascii_as::<T>(spec, stream, memory)
        } else {
            read_stream(spec, stream, what, expected, out()?)
        };
    }
    let mut file = spec.file.open()?;
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
        Encoding::Raw => read_raw::<T>(spec, &reader.into_inner(), (pos, len), expected, out),
        Encoding::Gzip => {
            could_hold(spec, len - pos, expected, room)?;
            read_stream(spec, MultiGzDecoder::new(reader), "gzip", expected, out()?)
        }
        Encoding::Zlib => {
            could_hold(spec, len - pos, expected, room)?;
            read_stream(spec, ZlibDecoder::new(reader), "zlib", expected, out()?)
        }
        Encoding::Ascii => {
            text_could_hold(spec, len - pos, room)?;
            ascii_as::<T>(spec, reader, room)
        }
    }
}

/// The most bytes deflate (gzip, zlib) decodes one compressed byte into: 258 bytes a match of
/// at least two bits, and a little more for the stream's own overhead.
const DEFLATE_MOST: u64 = 1032;

/// Fails when `compressed` bytes of deflate cannot hold the `expected` bytes of voxels: checked
/// before room on disk is reserved for them (`room.scratch`), so that a header claiming a huge
/// volume over a small stream reserves nothing. In memory the budget bounds that already.
fn could_hold(spec: &DataSpec, compressed: u64, expected: u64, room: Room) -> Result<()> {
    if room.scratch.is_none() || expected <= compressed.saturating_mul(DEFLATE_MOST) {
        return Ok(());
    }
    Err(Error::format(
        spec.file.path(),
        format!(
            "{compressed} bytes of compressed data cannot hold the {expected} bytes of a {} {} \
             volume",
            dims_string(spec.dims),
            spec.voxel_type
        ),
    ))
}

/// Fails when `text` bytes of ascii data cannot hold the voxels of `spec` (a value and a
/// separator take two bytes at least): checked before room on disk is reserved for them, as
/// [`could_hold`] is.
fn text_could_hold(spec: &DataSpec, text: u64, room: Room) -> Result<()> {
    let values = spec.dims.iter().map(|&d| d as u64).product::<u64>();
    if room.scratch.is_none() || values <= text / 2 + 1 {
        return Ok(());
    }
    Err(Error::format(
        spec.file.path(),
        format!(
            "{text} bytes of ascii data cannot hold the {values} values of a {} volume",
            dims_string(spec.dims)
        ),
    ))
}

/// The ascii values of `reader` (read as f32 only: `read_voxels` holds ascii data as f32), in
/// `room`.
fn ascii_as<T: Decode>(
    spec: &DataSpec,
    reader: impl BufRead,
    room: Room,
) -> Result<(Voxels, Rounded)> {
    let path = spec.file.path();
    if T::TYPE != VoxelType::F32 {
        return Err(Error::format(path, "ascii data is read as f32 only"));
    }
    let mut out = room.f32_voxels(path, spec.dims)?;
    let rounded = read_ascii(spec, reader, out.all())?;
    // Infinities (in the file, or from scaling) are missing voxels.
    infinities_missing(out.all());
    Ok((out.finish()?, rounded))
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

/// Raw voxels: read in place from a map of the file where they are stored as they are held (in
/// this machine's byte order, unscaled, aligned, and for f32 without infinities), else decoded
/// from the map into a `buffer`.
fn read_raw<T: Decode>(
    spec: &DataSpec,
    file: &File,
    (pos, len): (u64, u64),
    expected: u64,
    out: impl FnOnce() -> Result<VoxelOut<T>>,
) -> Result<(Voxels, Rounded)> {
    let path = spec.file.path();
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
    let map = mapped::map(file, path).map_err(|e| Error::io(path, e))?;
    let start = usize::try_from(start).map_err(|_| Error::format(path, "offset beyond memory"))?;
    let count = expected as usize / spec.voxel_type.size();
    let as_held =
        T::TYPE == spec.voxel_type && spec.scale.is_none() && spec.endian == Endian::NATIVE;
    if as_held
        && let Some(voxels) = Voxels::mapped(map.clone(), T::TYPE, start, count)
        && !has_infinity(&voxels)
    {
        // Held as stored: integers of at most 16 bits, or f32.
        return Ok((voxels, Rounded::default()));
    }
    let mut out = out()?;
    let bytes = &map.bytes()[start..start + expected as usize];
    let size = spec.voxel_type.size();
    let rounded = out
        .all()
        .par_chunks_mut(CHUNK)
        .zip(bytes.par_chunks(CHUNK * size))
        .map(|(o, b)| T::decode(b, spec, o))
        .reduce(Rounded::default, Rounded::plus);
    Ok((out.finish()?, rounded))
}

/// Whether f32 voxels hold an infinity, which a reader stores as NaN (so they cannot be read in
/// place).
fn has_infinity(voxels: &Voxels) -> bool {
    match voxels {
        Voxels::F32(s) => s
            .as_slice()
            .par_chunks(CHUNK)
            .any(|c| c.iter().any(|v| v.is_infinite())),
        _ => false,
    }
}

fn read_stream<T: Decode>(
    spec: &DataSpec,
    mut reader: impl Read,
    what: &str,
    expected: u64,
    mut out: VoxelOut<T>,
) -> Result<(Voxels, Rounded)> {
    let path = spec.file.path();
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
    let mut rounded = Rounded::default();
    while out.left() > 0 {
        let want = out.left().min(buf.len() / size);
        let got = fill(&mut reader, &mut buf[..want * size])
            .map_err(|e| corrupt(e, (done * size) as u64))?;
        let whole = got / size;
        rounded.add(T::decode(&buf[..whole * size], spec, out.room(whole)));
        out.commit(whole);
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
    Ok((out.finish()?, rounded))
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

/// The error for channel `channel` of a file that holds `count`.
pub(crate) fn one_channel(path: &Path, count: usize, channel: usize) -> Error {
    Error::format(
        path,
        format!(
            "holds {count} channel{} (numbered from 0), so there is no channel {channel}",
            if count == 1 { "" } else { "s" }
        ),
    )
}
