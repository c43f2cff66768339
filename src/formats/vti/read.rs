//! The voxels of a `.vti` array: ascii text, inline base64, or appended raw or base64 values,
//! each binary array after a header of its size or, compressed, of its blocks' sizes; 64-bit
//! integers held as f32, the values an f32 does not hold exactly counted in a note.

use std::io::{BufReader, Read};

use super::payload::{Base64, Blocks, Words};
use super::{Array, Layout};
use crate::error::{Error, Result};
use crate::formats::data::ascii::read_wide_ascii;
use crate::formats::data::wide::{Rounded, Wide, read_wide};
use crate::formats::data::{DataSpec, Encoding, read_voxels, read_voxels_from};
use crate::formats::scratch::Room;
use crate::volume::Voxels;
use crate::volume::voxels::held_type;

/// Reads the voxels of `array`, whose volume `spec` describes, from the file's `bytes`; with
/// the 32- and 64-bit integers rounded to f32 counted (none for other types).
pub(super) fn read_array(
    spec: &DataSpec,
    array: &Array,
    layout: Layout,
    bytes: &[u8],
    room: Room,
) -> Result<(Voxels, Rounded)> {
    let path = spec.file.path();
    let shown = crate::error::names::text(&array.name);
    let bad = |what: String| Error::format(path, format!("its array {shown:?}: {what}"));
    // The budget is weighed by the shared voxel reader, as the volume is held, before any block
    // is decompressed or any base64 decoded; the block list alone is weighed here.
    let expected = spec
        .dims
        .iter()
        .try_fold(array.size() as u64, |a, &d| a.checked_mul(d as u64))
        .ok_or_else(|| bad("more voxels than this machine can address".into()))?;
    let (input, base64): (&[u8], bool) = match array.format {
        "ascii" => {
            let spec = DataSpec {
                encoding: Encoding::Ascii,
                trailing: false,
                ..spec.clone()
            };
            let mut text = array.text.as_bytes();
            if let Some(wide) = array.wide {
                return read_wide_ascii(&spec, wide, text, room);
            }
            return read_voxels_from(&spec, &mut text, "ascii", room);
        }
        "binary" => (array.text.as_bytes(), true),
        "appended" => {
            let appended = layout
                .appended
                .ok_or_else(|| bad("appended, but the file has no AppendedData".into()))?;
            let offset = array
                .offset
                .ok_or_else(|| bad("appended, with no offset".into()))?;
            let at = usize::try_from(offset)
                .ok()
                .and_then(|o| appended.start.checked_add(o))
                .filter(|&at| at <= bytes.len())
                .ok_or_else(|| bad(format!("its offset {offset} is beyond the file's end")))?;
            if !appended.base64 && layout.compressor.is_none() && array.wide.is_none() {
                return raw_in_place(spec, &bytes[at..], at, layout.words, expected, room);
            }
            (&bytes[at..], appended.base64)
        }
        other => {
            return Err(bad(format!(
                "format {:?}: expected ascii, binary or appended",
                crate::error::names::text(other)
            )));
        }
    };
    let mut decoded: Box<dyn Read + '_> = if base64 {
        Box::new(Base64::new(input))
    } else {
        Box::new(input)
    };
    if let Some(compressor) = layout.compressor {
        // Each block's compressed size is a word of the file, listed in memory as a u64.
        let max_blocks = (input.len() / layout.words.size) as u64;
        let max_blocks = max_blocks.min(room.max_memory / 8);
        let blocks =
            Blocks::new(decoded, compressor, layout.words, expected, max_blocks).map_err(bad)?;
        blocks_fit(spec, array, blocks.held_whole(), room)?;
        return voxels_of(spec, array.wide, blocks, compressor.name(), room);
    }
    let size = layout
        .words
        .read(&mut decoded)
        .map_err(|e| bad(e.to_string()))?;
    if size != expected {
        return Err(bad(format!(
            "its header says {size} bytes, not the {expected} of its voxels"
        )));
    }
    let what = if base64 { "base64" } else { "raw" };
    voxels_of(spec, array.wide, decoded.take(size), what, room)
}

/// Fails when an LZ4 block held whole (`held` bytes with its compressed bytes) does not fit in
/// `room`'s budget beside the volume `spec` describes, when that is read into memory.
fn blocks_fit(spec: &DataSpec, array: &Array, held: Option<u64>, room: Room) -> Result<()> {
    let Some(held) = held else {
        return Ok(());
    };
    let voxels = spec.dims.iter().map(|&d| d as u64).product::<u64>();
    let volume = if room.scratch.is_some() {
        0
    } else {
        voxels.saturating_mul(held_type(array.ty, false).size() as u64)
    };
    let needed = volume.saturating_add(held);
    if needed <= room.max_memory {
        return Ok(());
    }
    Err(Error::TooLarge {
        path: spec.file.path().to_path_buf(),
        what: format!(
            "its array {:?}'s lz4 blocks, each held whole ({held} bytes with its compressed \
             bytes) beside the volume",
            crate::error::names::text(&array.name)
        ),
        needed,
        limit: room.max_memory,
        machine: false,
        disk: false,
    })
}

/// The voxels of the bytes of `stream` (64-bit integers of the type `wide`, if any), with the
/// values rounded to f32; `what` names the stream in messages.
fn voxels_of(
    spec: &DataSpec,
    wide: Option<Wide>,
    stream: impl Read,
    what: &'static str,
    room: Room,
) -> Result<(Voxels, Rounded)> {
    if let Some(wide) = wide {
        return read_wide(spec, wide, stream, what, room);
    }
    let mut stream = BufReader::new(stream);
    read_voxels_from(spec, &mut stream, what, room)
}

/// Raw appended voxels at `at` in the file (`bytes` from there), after their size: read in place
/// where they can be.
fn raw_in_place(
    spec: &DataSpec,
    bytes: &[u8],
    at: usize,
    words: Words,
    expected: u64,
    room: Room,
) -> Result<(Voxels, Rounded)> {
    let path = spec.file.path();
    let size = words
        .read(&mut &bytes[..])
        .map_err(|e| Error::format(path, e.to_string()))?;
    if size != expected {
        return Err(Error::format(
            path,
            format!(
                "an appended array's header says {size} bytes, not the {expected} of its voxels"
            ),
        ));
    }
    let spec = DataSpec {
        start: (at + words.size) as u64,
        ..spec.clone()
    };
    read_voxels(&spec, room)
}
